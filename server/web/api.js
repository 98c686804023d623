// The token and the API

import {TOKEN_KEY} from './constants.js';
import {auth} from './page.js';

const memoryToken = {value: ''}; // where sessionStorage is not available

export const token = {
  get() {
    try {
      return sessionStorage.getItem(TOKEN_KEY) || '';
    } catch {
      return memoryToken.value;
    }
  },
  set(value) {
    try {
      sessionStorage.setItem(TOKEN_KEY, value);
    } catch {
      memoryToken.value = value;
    }
  },
  forget() {
    try {
      sessionStorage.removeItem(TOKEN_KEY);
    } catch {
      /* nothing stored */
    }
    memoryToken.value = '';
  },
};

// Whether the coordinator wants the API token, as its /healthz says (null until asked).
// Without the token, nothing that needs it is asked for: the prompt comes up instead of a
// refusal, so the first visit is no 401 in the console.
const access = {tokenRequired: null};

export async function learnAccess() {
  try {
    const response = await fetch('/healthz', {
      headers: {Accept: 'application/json'},
      cache: 'no-store',
    });
    const body = await response.json();
    access.tokenRequired = body.api_token_required === true;
  } catch {
    access.tokenRequired = false; // an older coordinator: its 401s ask for the token
  }
}

// The refusal a call would get, without making it: the token is wanted and not given.
export function tokenMissing() {
  if (!access.tokenRequired || token.get()) return null;
  const error = new ApiError(401, 'token_missing', 'The coordinator wants the API token.');
  auth.ask();
  return error;
}

export function withAuth(headers = {}) {
  const secret = token.get();
  return secret ? {...headers, Authorization: `Bearer ${secret}`} : headers;
}

// fetch() with the token, for what is read whole (images): refused here while it is missing.
export function fetchWithToken(path, init = {}) {
  const missing = tokenMissing();
  if (missing) return Promise.reject(missing);
  return fetch(path, {...init, headers: withAuth(init.headers)});
}

export class ApiError extends Error {
  constructor(status, code, message) {
    super(message);
    this.status = status;
    this.code = code;
  }
}

async function errorOf(response) {
  let code = `http_${response.status}`;
  let message = `${response.status} ${response.statusText}`.trim();
  try {
    const body = await response.json();
    if (body && body.error) {
      code = String(body.error.code ?? code);
      message = String(body.error.message ?? message);
    }
  } catch {
    /* not JSON: keep the status line */
  }
  return new ApiError(response.status, code, message);
}

// The response when it is a success; otherwise the API's error, thrown, after asking for
// the token where the coordinator wants one.
export async function checked(response) {
  if (response.ok) return response;
  const error = await errorOf(response);
  if (response.status === 401 || (response.status === 403 && error.code === 'wrong_role')) {
    auth.ask(error);
  }
  throw error;
}

export async function api(method, path, body) {
  const missing = tokenMissing();
  if (missing) throw missing;
  const headers = withAuth({Accept: 'application/json'});
  const init = {method, headers, cache: 'no-store'};
  // POST, PUT and PATCH must say application/json, with a body or without (docs/api.md).
  if (method !== 'GET' && method !== 'DELETE' && method !== 'HEAD') {
    headers['Content-Type'] = 'application/json';
    if (body !== undefined) init.body = JSON.stringify(body);
  }
  let response;
  try {
    response = await fetch(path, init);
  } catch (error) {
    throw new ApiError(0, 'unreachable', `The coordinator did not answer (${error.message}).`);
  }
  await checked(response);
  if (response.status === 204) return null;
  return response.json();
}

export const jobPath = (id, tail = '') => `/v1/jobs/${encodeURIComponent(id)}${tail}`;
export const workerPath = (id, tail = '') => `/v1/workers/${encodeURIComponent(id)}${tail}`;
export const jobPage = (id) => `/jobs/${encodeURIComponent(id)}`;
