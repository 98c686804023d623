// The Tessera dashboard: the jobs, one job's image as it renders, and the workers, live.
//
// Everything comes from the coordinator's API (docs/api.md), with the API token the user
// types in when a call answers 401. The token lives in this tab's sessionStorage under
// `tessera.token` and travels only as `Authorization: Bearer`: never in a URL, a cookie or
// a link. Live updates are server-sent events read from fetch() (EventSource cannot send
// that header). Text from the coordinator (names, hosts, errors) goes into the page as text
// nodes only, never as markup.

const TOKEN_KEY = 'tessera.token';
const PAGE_SIZE = 50;
const JOB_STATES = ['queued', 'running', 'paused', 'completed', 'failed', 'canceled'];
const FINISHED = new Set(['completed', 'failed', 'canceled']);
const MAX_ZOOM = 64; // screen pixels per image pixel at the most
const POLL_MS = 3000; // how often a view reloads where the coordinator serves no events
const DEFAULT_FPS = 24; // the flipbook's pace: the job's status does not carry the scene's fps
const FRAMES_REFRESH_MS = 1000; // GET /frames at most this often while frames change ...
const FRAMES_REFRESH_MAX_MS = 10000; // ... and up to this for long animations (1 ms a frame)
const FRAME_IMAGE_FETCHES = 2; // frame images fetched at once for the strip and the flipbook
const FRAME_IMAGE_RETRY_MS = 3000; // before a frame image that could not be fetched is asked for again
const FRAME_IMAGE_ATTEMPTS = 3; // tries at a frame image before it waits to be asked for again
const MAX_STRIP_FRAMES = 100000; // a frame list longer than this waits for GET /frames

// ---------------------------------------------------------------------------------------
// The DOM, without markup

// h('a', {href: '/x', class: 'c', 'data-nav': ''}, 'text', child...): an element. Keys with
// a dash are attributes; `on...` are listeners; the rest are properties. Strings become text
// nodes, so nothing passed here is ever parsed as HTML.
function h(tag, props = {}, ...children) {
  const element = document.createElement(tag);
  for (const [key, value] of Object.entries(props)) {
    if (value === undefined || value === null || value === false) continue;
    if (key === 'class') element.className = value;
    else if (key === 'text') element.textContent = value;
    else if (key === 'dataset') Object.assign(element.dataset, value);
    else if (key.startsWith('on') && typeof value === 'function') element.addEventListener(key.slice(2), value);
    else if (key.includes('-')) element.setAttribute(key, value === true ? '' : String(value));
    else if (key === 'innerHTML' || key === 'outerHTML') throw new Error('no markup from data');
    else element[key] = value;
  }
  append(element, children);
  return element;
}

function append(parent, children) {
  for (const child of children.flat(Infinity)) {
    if (child === null || child === undefined || child === false) continue;
    parent.append(child instanceof Node ? child : document.createTextNode(String(child)));
  }
  return parent;
}

// The element's children replaced by `children` (as h() takes them).
function fill(element, ...children) {
  element.replaceChildren();
  return append(element, children);
}

function setText(element, text) {
  const value = String(text);
  if (element.textContent !== value) element.textContent = value;
}

const $ = (selector) => document.querySelector(selector);

// ---------------------------------------------------------------------------------------
// Numbers and times, as people read them

function formatDuration(seconds) {
  if (seconds === null || seconds === undefined || !Number.isFinite(seconds)) return '—';
  const s = Math.max(0, Math.round(seconds));
  if (s < 60) return `${s} s`;
  if (s < 3600) return s % 60 ? `${Math.floor(s / 60)} min ${s % 60} s` : `${s / 60} min`;
  const minutes = Math.round((s % 3600) / 60);
  return minutes ? `${Math.floor(s / 3600)} h ${minutes} min` : `${Math.floor(s / 3600)} h`;
}

function formatAgo(iso) {
  const then = Date.parse(iso);
  if (!Number.isFinite(then)) return '—';
  const s = (Date.now() - then) / 1000;
  if (s < 5) return 'just now';
  if (s < 60) return `${Math.floor(s)} s ago`;
  if (s < 3600) return `${Math.floor(s / 60)} min ago`;
  if (s < 86400) return `${Math.floor(s / 3600)} h ago`;
  return `${Math.floor(s / 86400)} d ago`;
}

// 12700000 -> "12.7 M"
function formatRate(value) {
  if (!Number.isFinite(value) || value <= 0) return '0';
  const units = ['', ' k', ' M', ' G', ' T'];
  let i = 0;
  while (value >= 999.5 && i < units.length - 1) {
    value /= 1000;
    i += 1;
  }
  return (i === 0 ? String(Math.round(value)) : value.toPrecision(3)) + units[i];
}

function formatCount(value) {
  return Number.isFinite(value) ? value.toLocaleString('en-US') : '—';
}

function shortId(id) {
  return typeof id === 'string' && id.length > 10 ? id.slice(0, 10) : String(id ?? '');
}

// ---------------------------------------------------------------------------------------
// The token and the API

const memoryToken = { value: '' }; // where sessionStorage is not available

const token = {
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
const access = { tokenRequired: null };

async function learnAccess() {
  try {
    const response = await fetch('/healthz', { headers: { Accept: 'application/json' }, cache: 'no-store' });
    const body = await response.json();
    access.tokenRequired = body.api_token_required === true;
  } catch {
    access.tokenRequired = false; // an older coordinator: its 401s ask for the token
  }
}

// The refusal a call would get, without making it: the token is wanted and not given.
function tokenMissing() {
  if (!access.tokenRequired || token.get()) return null;
  const error = new ApiError(401, 'token_missing', 'The coordinator wants the API token.');
  auth.ask();
  return error;
}

function withAuth(headers = {}) {
  const secret = token.get();
  return secret ? { ...headers, Authorization: `Bearer ${secret}` } : headers;
}

// fetch() with the token, for what is read whole (images): refused here while it is missing.
function fetchWithToken(path, init = {}) {
  const missing = tokenMissing();
  if (missing) return Promise.reject(missing);
  return fetch(path, { ...init, headers: withAuth(init.headers) });
}

class ApiError extends Error {
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
async function checked(response) {
  if (response.ok) return response;
  const error = await errorOf(response);
  if (response.status === 401 || (response.status === 403 && error.code === 'wrong_role')) {
    auth.ask(error);
  }
  throw error;
}

async function api(method, path, body) {
  const missing = tokenMissing();
  if (missing) throw missing;
  const headers = withAuth({ Accept: 'application/json' });
  const init = { method, headers, cache: 'no-store' };
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

const jobPath = (id, tail = '') => `/v1/jobs/${encodeURIComponent(id)}${tail}`;
const workerPath = (id, tail = '') => `/v1/workers/${encodeURIComponent(id)}${tail}`;
const jobPage = (id) => `/jobs/${encodeURIComponent(id)}`;

// ---------------------------------------------------------------------------------------
// The token prompt, messages and the live indicator

const auth = {
  asked: false,
  ask(error) {
    this.asked = true;
    const form = $('#auth');
    const message = $('#auth-error');
    if (token.get() && error) {
      setText(message, error.code === 'wrong_role'
        ? 'That token is not the API token (it is the worker token or another role\'s).'
        : `The coordinator refused that token (${error.code}).`);
      message.hidden = false;
    } else {
      message.hidden = true;
    }
    if (form.hidden) {
      form.hidden = false;
      $('#token-input').focus();
    }
  },
  hide() {
    this.asked = false;
    $('#auth').hidden = true;
    $('#auth-error').hidden = true;
  },
};

function showForgetButton() {
  $('#forget-token').hidden = !token.get();
}

let flashTimer = 0;
function flash(message) {
  const element = $('#flash');
  setText(element, message);
  element.hidden = false;
  clearTimeout(flashTimer);
  flashTimer = setTimeout(() => {
    element.hidden = true;
  }, 8000);
}

function reportError(what, error) {
  if (error instanceof ApiError && (error.status === 401 || error.code === 'wrong_role')) return;
  flash(`${what}: ${error.message}`);
}

function setLive(state) {
  const element = $('#live');
  const text = { live: 'live', connecting: 'connecting', reconnecting: 'reconnecting', polling: 'polling', idle: '' }[state] ?? state;
  setText(element, text);
  element.classList.toggle('on', state === 'live');
  element.classList.toggle('off', state === 'reconnecting' || state === 'polling');
  element.title = {
    live: 'Live: the coordinator sends every change as it happens',
    polling: 'This coordinator sends no live events: the page reloads every few seconds',
    reconnecting: 'The live connection dropped; trying again',
  }[state] ?? '';
}

// ---------------------------------------------------------------------------------------
// Server-sent events over fetch()

const sleep = (ms, signal) => new Promise((resolve) => {
  const timer = setTimeout(resolve, ms);
  signal?.addEventListener('abort', () => {
    clearTimeout(timer);
    resolve();
  }, { once: true });
});

// Reads `path` as text/event-stream, calling on.event(type, data) with each event's JSON;
// reconnects with Last-Event-ID after an error or an end, 1 s at first and up to 10 s apart.
// on.open() when a connection is up; on.unavailable(status) when the coordinator does not
// serve the route (an older release); a 401 stops it (the token prompt takes over).
class EventStream {
  constructor(path, on) {
    this.path = path;
    this.on = on;
    this.lastId = null;
    this.stopper = new AbortController();
  }

  start() {
    this.run();
    return this;
  }

  stop() {
    this.stopper.abort();
  }

  get stopped() {
    return this.stopper.signal.aborted;
  }

  async run() {
    let delay = 1000;
    while (!this.stopped) {
      const attempt = new AbortController();
      const abort = () => attempt.abort();
      this.stopper.signal.addEventListener('abort', abort, { once: true });
      try {
        if (tokenMissing()) {
          this.on.denied?.();
          return;
        }
        const headers = withAuth({ Accept: 'text/event-stream' });
        if (this.lastId !== null) headers['Last-Event-ID'] = this.lastId;
        const response = await fetch(this.path, { headers, cache: 'no-store', signal: attempt.signal });
        if (response.status === 401 || response.status === 403) {
          await checked(response).catch(() => {});
          this.on.denied?.();
          return;
        }
        if (response.status === 404 || response.status === 405 || response.status === 501) {
          this.on.unavailable?.(response.status);
          return;
        }
        if (!response.ok || !response.body) throw new Error(`HTTP ${response.status}`);
        delay = 1000;
        this.on.open?.();
        await this.read(response.body);
      } catch (error) {
        if (this.stopped) return;
        if (error.name !== 'AbortError') console.debug('event stream', this.path, error);
      } finally {
        this.stopper.signal.removeEventListener('abort', abort);
        attempt.abort();
      }
      if (this.stopped) return;
      this.on.lost?.();
      await sleep(delay, this.stopper.signal);
      delay = Math.min(delay * 2, 10000);
    }
  }

  async read(body) {
    const reader = body.pipeThrough(new TextDecoderStream()).getReader();
    let buffer = '';
    let event = { type: '', data: [], id: null };
    const dispatch = () => {
      if (event.id !== null) this.lastId = event.id;
      if (event.data.length > 0) {
        let data = null;
        try {
          data = JSON.parse(event.data.join('\n'));
        } catch {
          console.debug('event stream: data that is not JSON', event.data);
        }
        if (data !== null) {
          try {
            this.on.event(event.type || 'message', data);
          } catch (error) {
            console.error('event handler', error);
          }
        }
      }
      event = { type: '', data: [], id: null };
    };
    const line = (text) => {
      if (text === '') return dispatch();
      if (text.startsWith(':')) return undefined; // a comment: the keep-alive
      const colon = text.indexOf(':');
      const field = colon < 0 ? text : text.slice(0, colon);
      let value = colon < 0 ? '' : text.slice(colon + 1);
      if (value.startsWith(' ')) value = value.slice(1);
      if (field === 'event') event.type = value;
      else if (field === 'data') event.data.push(value);
      else if (field === 'id' && !value.includes('\0')) event.id = value;
      return undefined;
    };
    for (;;) {
      const { value, done } = await reader.read();
      if (done) return;
      buffer += value;
      for (;;) {
        const end = /\r\n|\r|\n/.exec(buffer);
        if (!end) break;
        // A lone CR at the end may be the first half of a CRLF still on its way.
        if (end[0] === '\r' && end.index === buffer.length - 1) break;
        line(buffer.slice(0, end.index));
        buffer = buffer.slice(end.index + end[0].length);
      }
    }
  }
}

// A view's stream with the usual wiring: the live indicator, and a poll where the
// coordinator serves no events.
function liveStream(path, onEvent, { onOpen, poll } = {}) {
  let pollTimer = 0;
  const stream = new EventStream(path, {
    event: onEvent,
    open() {
      setLive('live');
      onOpen?.();
    },
    lost() {
      setLive('reconnecting');
    },
    denied() {
      setLive('idle');
      onOpen?.();
    },
    unavailable() {
      setLive('polling');
      onOpen?.();
      if (poll) pollTimer = setInterval(poll, POLL_MS);
    },
  });
  setLive('connecting');
  stream.start();
  return {
    stop() {
      stream.stop();
      clearInterval(pollTimer);
    },
  };
}

// ---------------------------------------------------------------------------------------
// Jobs: their actions, shared by the list and the job's own view

function stateBadge(state) {
  return h('span', { class: `state ${state}`, text: state });
}

// Runs an action from a button: the button is disabled meanwhile; errors are flashed.
async function act(button, what, work) {
  button.disabled = true;
  try {
    return await work();
  } catch (error) {
    reportError(what, error);
    return undefined;
  } finally {
    button.disabled = false;
  }
}

// The buttons for what can be done to `job` in its state. `applied(status)` gets the job's
// new status; `deleted()` is called once it is removed.
function jobButtons(job, { applied, deleted }) {
  const buttons = [];
  const post = (label, verb, cls) => {
    const button = h('button', {
      type: 'button', class: cls, text: label, dataset: { action: verb },
      onclick: () => act(button, `${label} ${job.name || job.id}`, async () => applied(await api('POST', jobPath(job.id, `/${verb}`)))),
    });
    buttons.push(button);
  };
  // What cannot be undone takes two clicks: the first arms it for a few seconds.
  const twoClicks = (label, question, verb, then) => {
    let armed = 0;
    const button = h('button', {
      type: 'button', class: 'danger', text: label, dataset: { action: verb },
      onclick: () => {
        if (!armed) {
          setText(button, question);
          armed = setTimeout(() => {
            armed = 0;
            setText(button, label);
          }, 4000);
          return;
        }
        clearTimeout(armed);
        armed = 0;
        act(button, `${label} ${job.name || job.id}`, then);
      },
    });
    buttons.push(button);
  };
  if (job.state === 'running' || job.state === 'queued') post('Pause', 'pause');
  if (job.state === 'paused') post('Resume', 'resume');
  // A canceled job is retried too: it renders what it lacked, under the same id.
  if (job.state === 'failed' || job.state === 'canceled') post('Retry', 'retry');
  if (!FINISHED.has(job.state)) {
    twoClicks('Cancel', 'Really cancel?', 'cancel', async () => applied(await api('POST', jobPath(job.id, '/cancel'))));
  }
  if (FINISHED.has(job.state)) {
    twoClicks('Delete', 'Really delete?', 'delete', async () => {
      await api('DELETE', jobPath(job.id));
      deleted();
    });
  }
  return buttons;
}

// The priority's number input: a change is sent at once (PATCH /v1/jobs/{id}).
function priorityInput(getJob, applied) {
  const input = h('input', {
    type: 'number', min: 0, max: 100, step: 1, class: 'priority', 'aria-label': 'Priority',
    onchange: async () => {
      const job = getJob();
      const value = Number(input.value);
      if (!Number.isInteger(value) || value < 0 || value > 100) {
        flash('A priority is a whole number from 0 to 100.');
        input.value = job.priority;
        return;
      }
      if (value === job.priority) return;
      input.disabled = true;
      try {
        applied(await api('PATCH', jobPath(job.id), { priority: value }));
      } catch (error) {
        reportError(`Priority of ${job.name || job.id}`, error);
        input.value = getJob().priority;
      } finally {
        input.disabled = FINISHED.has(getJob().state);
      }
    },
  });
  return input;
}

function syncPriority(input, job) {
  input.disabled = FINISHED.has(job.state);
  if (document.activeElement !== input) input.value = job.priority;
}

// ---------------------------------------------------------------------------------------
// The jobs view: /

function jobsView(main) {
  const query = new URLSearchParams(location.search);
  let filter = JOB_STATES.includes(query.get('state')) ? query.get('state') : '';
  let offset = Math.max(0, Number.parseInt(query.get('offset'), 10) || 0);
  let lastCount = 0;
  let loadSerial = 0;
  const rows = new Map(); // job id -> row
  const view = { gone: false };

  const select = h('select', { id: 'state-filter', 'aria-label': 'State' },
    h('option', { value: '', text: 'all' }),
    JOB_STATES.map((state) => h('option', { value: state, text: state })));
  select.value = filter;
  const previous = h('button', { type: 'button', text: '‹ Newer', id: 'page-prev' });
  const next = h('button', { type: 'button', text: 'Older ›', id: 'page-next' });
  const pageLabel = h('span', { class: 'page-label' });
  const tbody = h('tbody');
  const emptyRow = h('tr', { class: 'empty-row' }, h('td', { class: 'empty', colSpan: 9, text: 'Loading…' }));
  tbody.append(emptyRow);

  append(main, [
    h('div', { class: 'toolbar' },
      h('h1', { text: 'Jobs' }),
      h('label', {}, 'State', select),
      h('span', { class: 'spacer' }),
      h('div', { class: 'pager' }, previous, pageLabel, next)),
    h('table', { class: 'grid jobs', id: 'jobs' },
      h('thead', {}, h('tr', {},
        h('th', { text: 'Name' }), h('th', { text: 'State' }), h('th', { text: 'Progress' }),
        h('th', { class: 'num', text: 'Tiles' }), h('th', { class: 'num', text: 'ETA' }),
        h('th', { text: 'Priority' }), h('th', { text: 'Submitted' }),
        h('th', { class: 'num', text: 'Rays/s' }), h('th', { text: 'Actions' }))),
      tbody),
  ]);
  document.title = 'Jobs · Tessera';

  const keepAddress = () => {
    const params = new URLSearchParams();
    if (filter) params.set('state', filter);
    if (offset) params.set('offset', offset);
    const search = params.toString();
    history.replaceState(null, '', search ? `/?${search}` : '/');
  };

  const showEmpty = (text) => {
    setText(emptyRow.firstChild, text);
    if (!emptyRow.isConnected) tbody.append(emptyRow);
  };
  const emptyText = () => {
    if (offset) return 'No more jobs.';
    return filter ? `No ${filter} jobs.` : 'No jobs yet. Submit one with: tessera submit SCENE.json';
  };

  const updatePager = () => {
    previous.disabled = offset === 0;
    next.disabled = lastCount < PAGE_SIZE;
    setText(pageLabel, lastCount ? `${offset + 1}–${offset + lastCount}` : '');
  };

  const makeRow = (job) => {
    const row = { job, state: null };
    row.link = h('a', { href: jobPage(job.id), 'data-nav': true, class: 'job-link' });
    row.name = h('span', { class: 'job-name' });
    row.link.append(row.name);
    row.stateCell = h('td', { class: 'state-cell' });
    row.bar = h('progress', { max: 1, value: 0 });
    row.percent = h('span', { class: 'sub' });
    row.tiles = h('td', { class: 'num tiles' });
    row.eta = h('td', { class: 'num eta' });
    row.priority = priorityInput(() => row.job, applied);
    row.submitted = h('td', { class: 'submitted' });
    row.rays = h('td', { class: 'num rays' });
    row.actions = h('td', { class: 'actions' });
    row.tr = h('tr', { dataset: { jobId: job.id } },
      h('td', { class: 'name' }, row.link, h('span', { class: 'sub mono', text: shortId(job.id) })),
      row.stateCell,
      h('td', { class: 'progress' }, row.bar, row.percent),
      row.tiles, row.eta,
      h('td', {}, row.priority),
      row.submitted, row.rays, row.actions);
    updateRow(row, job);
    return row;
  };

  const updateRow = (row, job) => {
    row.job = job;
    setText(row.name, job.name || job.id);
    row.link.title = job.name || job.id;
    if (row.state !== job.state) {
      fill(row.stateCell, stateBadge(job.state));
      fill(row.actions, h('div', { class: 'buttons' }, jobButtons(job, { applied, deleted: () => removeRow(job.id) })));
      row.state = job.state;
    }
    row.bar.value = job.progress ?? 0;
    setText(row.percent, `${Math.floor((job.progress ?? 0) * 100)}%`);
    setText(row.tiles, `${formatCount(job.tiles?.done)} / ${formatCount(job.tiles?.total)}`);
    setText(row.eta, FINISHED.has(job.state) || job.state === 'paused' ? '—' : formatDuration(job.eta_s));
    syncPriority(row.priority, job);
    setText(row.submitted, formatAgo(job.created_at));
    row.submitted.title = job.created_at ?? '';
    setText(row.rays, formatRate(job.stats?.rays_per_s));
  };

  const removeRow = (id) => {
    const row = rows.get(id);
    if (!row) return;
    row.tr.remove();
    rows.delete(id);
    if (rows.size === 0) showEmpty(emptyText());
  };

  // Newest first: by created_at, then by id.
  const newer = (a, b) => (a.created_at === b.created_at ? a.id > b.id : a.created_at > b.created_at);

  // A job's status from an action or an event: its row is updated, added or dropped.
  function applied(job) {
    if (!job || !job.id) return;
    const row = rows.get(job.id);
    const belongs = !filter || job.state === filter;
    if (row) {
      if (belongs) updateRow(row, job);
      else removeRow(job.id);
      return;
    }
    if (!belongs || offset !== 0) return;
    // A job this page has not shown: in its place by age, if that is on this page.
    let before = null;
    for (const tr of tbody.children) {
      const other = rows.get(tr.dataset.jobId);
      if (other && newer(job, other.job)) {
        before = tr;
        break;
      }
    }
    if (!before && rows.size >= PAGE_SIZE) return;
    const fresh = makeRow(job);
    rows.set(job.id, fresh);
    emptyRow.remove();
    tbody.insertBefore(fresh.tr, before);
    if (rows.size > PAGE_SIZE) {
      const last = tbody.lastElementChild;
      if (last?.dataset.jobId) removeRow(last.dataset.jobId);
    }
  }

  const render = (jobs) => {
    const seen = new Set();
    let previousRow = null;
    for (const job of jobs) {
      let row = rows.get(job.id);
      if (row) updateRow(row, job);
      else {
        row = makeRow(job);
        rows.set(job.id, row);
      }
      seen.add(job.id);
      const wanted = previousRow ? previousRow.nextSibling : tbody.firstChild;
      if (wanted !== row.tr) tbody.insertBefore(row.tr, wanted);
      previousRow = row.tr;
    }
    for (const id of [...rows.keys()]) if (!seen.has(id)) removeRow(id);
    if (jobs.length) emptyRow.remove();
    else showEmpty(emptyText());
  };

  const load = async () => {
    const serial = ++loadSerial;
    const params = new URLSearchParams({ limit: PAGE_SIZE });
    if (filter) params.set('state', filter);
    if (offset) params.set('offset', offset);
    try {
      const { jobs } = await api('GET', `/v1/jobs?${params}`);
      if (serial !== loadSerial || view.gone) return;
      lastCount = jobs.length;
      render(jobs);
      updatePager();
    } catch (error) {
      if (serial !== loadSerial || view.gone) return;
      if (error.status === 401 || error.code === 'wrong_role') {
        for (const id of [...rows.keys()]) removeRow(id);
        showEmpty('The jobs are shown once the API token is given above.');
      } else {
        showEmpty(`The jobs could not be listed: ${error.message}`);
      }
    }
  };

  select.addEventListener('change', () => {
    filter = select.value;
    offset = 0;
    keepAddress();
    load();
  });
  previous.addEventListener('click', () => {
    offset = Math.max(0, offset - PAGE_SIZE);
    keepAddress();
    load();
  });
  next.addEventListener('click', () => {
    offset += PAGE_SIZE;
    keepAddress();
    load();
  });
  updatePager();

  const stream = liveStream('/v1/events', (type, data) => {
    if (type === 'job') applied(data);
    else if (type === 'job_removed') removeRow(data.id);
    else if (type === 'resync') load();
  }, { poll: load });
  load();
  return ageingView(view, stream, () => {
    for (const row of rows.values()) setText(row.submitted, formatAgo(row.job.created_at));
  });
}

// A live table's view: its relative times ("3 min ago") redrawn every 5 s by `age`, and,
// when the view goes, its stream stopped and its clock with it.
function ageingView(view, stream, age) {
  const clock = setInterval(age, 5000);
  return {
    unmount() {
      view.gone = true;
      stream.stop();
      clearInterval(clock);
    },
  };
}

// ---------------------------------------------------------------------------------------
// The job view: /jobs/{id}

// A colour per worker, the same every time for the same id; never red, which is failure's.
function workerColour(id) {
  let hash = 2166136261;
  for (const c of String(id ?? '')) hash = Math.imul(hash ^ c.charCodeAt(0), 16777619) >>> 0;
  return `hsl(${40 + (hash % 270)}, 90%, 60%)`;
}

// t from 0 (fastest) to 1 (slowest): blue, through green and yellow, to red.
function heatColour(t, alpha = 1) {
  const hue = 240 * (1 - Math.min(1, Math.max(0, t)));
  return `hsla(${hue}, 90%, 50%, ${alpha})`;
}

// What a download is saved as. One frame of an animation says which, so that the frames of
// a sequence sort and do not overwrite each other; "-partial" while the image is not whole.
function fileName(job, extension, { frame = null, whole = job.state === 'completed' } = {}) {
  const base = String(job.name || job.id).replace(/[^A-Za-z0-9._-]+/g, '_').replace(/^[._]+/, '').slice(0, 80) || job.id;
  const which = frame === null ? '' : `-frame${String(frame).padStart(4, '0')}`;
  return `${base}${which}${whole ? '' : '-partial'}.${extension}`;
}

// A frame list as the API writes it ("1-48", "1-100x2", "1,5,10-20"): its frames in the
// order the farm renders them (increasing, each once), so that the strip can be drawn before
// GET /frames answers; null where it cannot be read, and the strip waits for that answer.
function parseFrameList(text) {
  const frames = new Set();
  for (const part of String(text ?? '').split(',')) {
    const match = /^\s*(\d+)\s*(?:-\s*(\d+)\s*(?:x\s*(\d+)\s*)?)?$/.exec(part);
    if (!match) return null;
    const first = Number(match[1]);
    const last = match[2] === undefined ? first : Number(match[2]);
    const step = match[3] === undefined ? 1 : Number(match[3]);
    if (last < first || step < 1) return null;
    for (let frame = first; frame <= last; frame += step) {
      frames.add(frame);
      if (frames.size > MAX_STRIP_FRAMES) return null;
    }
  }
  return [...frames].sort((a, b) => a - b);
}

// The done frames' images of one job. Each is fetched once (through fetch(), since an
// <img src> could not send the token, and shown from a blob: URL, which the page's CSP
// allows) and decoded ahead, so that the strip's thumbnail and the flipbook are the same
// image and the flipbook never waits on the network mid-loop. A few at a time: a long
// animation must not flood the coordinator, and frames asked for `soon` (in view, or next
// in the flipbook) go first.
class FrameImages {
  constructor(jobId, onReady) {
    this.jobId = jobId;
    this.onReady = onReady;
    this.entries = new Map(); // frame -> {frame, state: queued|loading|ready|failed, url, img, failedAt, attempts}
    this.queue = [];
    this.active = 0;
    this.closed = false;
  }

  entry(frame) {
    return this.entries.get(frame);
  }

  want(frame, soon = false) {
    if (this.closed) return;
    let entry = this.entries.get(frame);
    if (entry && entry.state === 'failed' && Date.now() - entry.failedAt > FRAME_IMAGE_RETRY_MS) {
      this.entries.delete(frame);
      entry = undefined;
    }
    if (entry) {
      if (soon && entry.state === 'queued') {
        this.queue.splice(this.queue.indexOf(entry), 1);
        this.queue.unshift(entry);
      }
      return;
    }
    entry = { frame, state: 'queued', url: '', img: null, failedAt: 0, attempts: 0 };
    this.entries.set(frame, entry);
    if (soon) this.queue.unshift(entry);
    else this.queue.push(entry);
    this.pump();
  }

  pump() {
    while (!this.closed && this.active < FRAME_IMAGE_FETCHES && this.queue.length > 0) {
      const entry = this.queue.shift();
      this.active += 1;
      this.load(entry).finally(() => {
        this.active -= 1;
        this.pump();
      });
    }
  }

  async load(entry) {
    entry.state = 'loading';
    try {
      const response = await fetchWithToken(jobPath(this.jobId, `/frames/${entry.frame}/image?format=png`), { cache: 'no-store' });
      await checked(response);
      const blob = await response.blob();
      if (this.closed) return;
      entry.url = URL.createObjectURL(blob);
      const img = new Image();
      img.src = entry.url;
      await img.decode();
      if (this.closed) return;
      entry.img = img;
      entry.state = 'ready';
      this.onReady(entry);
    } catch (error) {
      entry.state = 'failed';
      entry.failedAt = Date.now();
      if (entry.url) URL.revokeObjectURL(entry.url);
      entry.url = '';
      if (this.closed) return;
      console.debug('frame image', entry.frame, error);
      // Tried again by itself a few times (a 409 where the frame list ran ahead of the image,
      // a coordinator restarting), since nothing else may ask for it again once the job is
      // over; never where the token or the frame itself is wrong.
      const hopeless = error instanceof ApiError && [400, 401, 403, 404].includes(error.status);
      entry.attempts = (entry.attempts ?? 0) + 1;
      if (hopeless || entry.attempts >= FRAME_IMAGE_ATTEMPTS) return;
      setTimeout(() => {
        if (this.closed || this.entries.get(entry.frame) !== entry || entry.state !== 'failed') return;
        entry.state = 'queued';
        this.queue.push(entry);
        this.pump();
      }, FRAME_IMAGE_RETRY_MS * entry.attempts);
    }
  }

  close() {
    this.closed = true;
    this.queue = [];
    for (const entry of this.entries.values()) if (entry.url) URL.revokeObjectURL(entry.url);
    this.entries.clear();
  }
}

function jobView(main, id) {
  let job = null;
  // By index, over every frame: {index, frame, x, y, width, height, state, worker,
  // worker_name, render_ms}.
  let tiles = [];
  let tilesKnown = false;
  // Until the tile list is read, tile events wait here; until the image is drawn, pixels do.
  let tilesLoading = true;
  let imageLoading = true;
  let tileQueue = [];
  let pixelQueue = [];
  let refreshTimer = 0;
  let loadSerial = 0;
  let showTiles = true;
  let showHeat = false;
  let zoom = 1;
  let panX = 0;
  let panY = 0;
  let fitted = false;
  const view = { gone: false };
  // An animation (more than one frame) is shown one frame at a time, `shownFrame`: the one
  // being rendered while `following`, else the one picked in the strip or the flipbook's.
  // Its frames share the image's place, so the tiles of the others are neither painted nor
  // outlined. A still is the one frame 0, and none of this shows.
  let animated = false;
  let shownFrame = 0;
  let following = true;
  let frameOrder = [];
  const framePosition = new Map(); // frame -> its place in frameOrder
  const frameInfo = new Map(); // frame -> its FrameStatus, from GET /frames
  const cells = new Map(); // frame -> {button, thumb, bar, img, state}: its cell in the strip
  const visibleCells = new Set(); // frames whose cell is in or near the strip's view
  let shownCell = null;
  let shownTiles = null; // the tiles of shownFrame; null when they must be picked out again
  let framesKey = null;
  let framesTimer = 0;
  let framesAt = 0;
  let framesBusy = false;
  let framesAgain = false;
  let playing = false;
  let playRequest = 0;
  let lastStep = 0;
  const frameImages = new FrameImages(id, (entry) => frameImageReady(entry));

  // --- the page ---
  const title = h('h1', { class: 'job-title', text: id });
  const badge = h('span', { class: 'state-holder' });
  const status = h('div', { class: 'status-line', id: 'job-status' });
  const actions = h('span', { class: 'group actions' });
  const priority = priorityInput(() => job, (changed) => applyJob(changed));
  priority.disabled = true;
  const zoomLabel = h('span', { class: 'zoom-level', text: '100%' });
  const toggleTiles = h('button', { type: 'button', text: 'Tiles', id: 'toggle-tiles', 'aria-pressed': 'true', title: 'Tile states: pending dim, rendering outlined in its worker\'s colour, failed red' });
  const toggleHeat = h('button', { type: 'button', text: 'Heatmap', id: 'toggle-heat', 'aria-pressed': 'false', title: 'Each done tile coloured by its render time, relative to the slowest' });
  const pngButton = h('button', { type: 'button', text: 'PNG', id: 'download-png', title: 'Download the image (what is rendered so far)' });
  const exrButton = h('button', { type: 'button', text: 'EXR', id: 'download-exr', title: 'Download the linear float image (what is rendered so far)' });
  const image = h('canvas', { class: 'image', id: 'image', width: 1, height: 1 });
  const overlay = h('canvas', { class: 'overlay', 'aria-hidden': 'true' });
  const tip = h('div', { class: 'tip', hidden: true });
  const viewer = h('div', { class: 'viewer', id: 'viewer' }, image, overlay, tip);
  const counts = h('div', { class: 'tile-counts', id: 'tile-counts', dataset: { done: '0' } });
  const legendBar = h('canvas', { width: 160, height: 10 });
  const legendMax = h('span', {});
  const legend = h('div', { class: 'legend', hidden: true }, 'Render time: 0 ms', legendBar, legendMax);
  const context = image.getContext('2d');
  const playButton = h('button', { type: 'button', text: 'Play', id: 'flip-play', 'aria-pressed': 'false', disabled: true, title: 'Play the done frames in order, looping' });
  const fpsInput = h('input', { type: 'number', id: 'flip-fps', class: 'fps', min: 1, max: 240, step: 'any', value: DEFAULT_FPS, 'aria-label': 'Frames per second' });
  const followButton = h('button', { type: 'button', text: 'Follow', id: 'frame-follow', 'aria-pressed': 'true', title: 'Show the frame being rendered, and move on with the render' });
  const shownLabel = h('span', { class: 'frame-shown', id: 'frame-shown' });
  const frameCounts = h('span', { class: 'frame-counts', id: 'frame-counts' });
  const strip = h('div', { class: 'frame-strip', id: 'frame-strip', role: 'group', 'aria-label': 'Frames' });
  const framesPanel = h('section', { class: 'frames', id: 'frames', hidden: true, 'aria-label': 'Frames' },
    h('div', { class: 'job-tools frames-bar' },
      h('span', { class: 'group' }, playButton, h('label', { class: 'fps-label' }, fpsInput, 'fps')),
      h('span', { class: 'group' }, followButton, shownLabel),
      h('span', { class: 'group' }, frameCounts)),
    strip);

  append(main, [
    h('div', { class: 'job-head' },
      h('a', { href: '/', 'data-nav': true, text: '‹ Jobs' }), title,
      h('span', { class: 'mono', text: id }), badge),
    status,
    h('div', { class: 'job-tools' },
      h('span', { class: 'group' },
        h('button', { type: 'button', text: '−', title: 'Zoom out', 'aria-label': 'Zoom out', onclick: () => zoomBy(1 / 2) }),
        zoomLabel,
        h('button', { type: 'button', text: '+', title: 'Zoom in', 'aria-label': 'Zoom in', onclick: () => zoomBy(2) }),
        h('button', { type: 'button', text: 'Fit', onclick: () => fit() }),
        h('button', { type: 'button', text: '1:1', onclick: () => setZoom(1) })),
      h('span', { class: 'group' }, toggleTiles, toggleHeat),
      h('span', { class: 'group' }, 'Download', pngButton, exrButton),
      actions,
      h('label', { class: 'group' }, 'Priority', priority)),
    framesPanel,
    viewer,
    legend,
    counts,
  ]);

  // --- status ---
  function applyJob(next) {
    if (!next || next.id !== id) return;
    const was = job;
    job = next;
    setText(title, job.name || job.id);
    document.title = `${job.name || job.id} · Tessera`;
    if (!was || was.state !== job.state) {
      fill(badge, stateBadge(job.state));
      fill(actions, jobButtons(job, { applied: applyJob, deleted: () => navigate('/') }));
    }
    syncPriority(priority, job);
    const frames = job.frames;
    if (!animated && frames && frames.total > 1) startFrames(frames);
    const parts = [
      ['Tiles', `${formatCount(job.tiles.done)} / ${formatCount(job.tiles.total)} (${Math.floor(job.progress * 100)}%)`],
      animated ? ['Frames', `${formatCount(frames.done)} / ${formatCount(frames.total)}`] : null,
      ['Rendering', formatCount(job.tiles.rendering)],
      ['Elapsed', formatDuration(job.elapsed_s)],
      ['ETA', FINISHED.has(job.state) || job.state === 'paused' ? '—' : formatDuration(job.eta_s)],
      ['Rays/s', formatRate(job.stats?.rays_per_s)],
      ['Size', `${job.width} × ${job.height}`],
      ['Submitted', formatAgo(job.created_at)],
    ].filter(Boolean);
    const health = job.health ?? {};
    const troubles = [];
    if (health.tile_failures) troubles.push(`${health.tile_failures} tile failures`);
    if (health.refused_results) troubles.push(`${health.refused_results} results refused`);
    if (health.repeated_handouts) troubles.push(`${health.repeated_handouts} tiles sent out again`);
    fill(status,
      ...parts.map(([label, value]) => h('span', {}, `${label} `, h('b', { text: value }))),
      troubles.length ? h('span', { class: 'error', text: troubles.join(', ') }) : null,
      animated && frames.failed ? h('span', { class: 'error', text: `Failed frames: ${frames.failed_list}` }) : null,
      health.last_problem ? h('span', { class: 'error', text: health.last_problem }) : null,
      job.error ? h('span', { class: 'error', text: `Error: ${job.error}` }) : null,
    );
    if (image.width !== job.width || image.height !== job.height) {
      image.width = job.width;
      image.height = job.height;
      fitted = false;
    }
    if (!fitted && viewer.clientWidth > 0) {
      fit();
      fitted = true;
    }
    if (animated) {
      showFrameCounts();
      // The job's counts move with every tile; the frame list is asked for again only when
      // a frame is done, failed or begun, since it grows with the frames.
      const key = `${frames.done}/${frames.failed}/${frames.current}/${job.state}`;
      if (framesKey !== null && key !== framesKey) loadFramesSoon();
      framesKey = key;
      if (following) follow();
    }
    if (!tilesKnown) showCounts();
    // The final image once the job ends: every tile, whatever events were missed.
    if (was && !FINISHED.has(was.state) && FINISHED.has(job.state)) {
      if (!playing) loadImage();
      if (tilesKnown) loadTiles();
    }
  }

  // --- frames: the strip, the frame shown and the flipbook ---
  function startFrames(frames) {
    animated = true;
    framesPanel.hidden = false;
    pngButton.title = 'Download the frame shown (what is rendered of it so far)';
    exrButton.title = 'Download the frame shown as linear floats (what is rendered of it so far)';
    const order = parseFrameList(frames.list);
    if (order) buildStrip(order);
    shownFrame = frames.current ?? order?.[0] ?? 0;
    shownTiles = null;
    markShown();
  }

  function buildStrip(order) {
    frameOrder = order;
    framePosition.clear();
    order.forEach((frame, at) => framePosition.set(frame, at));
    cellObserver.disconnect();
    visibleCells.clear();
    cells.clear();
    shownCell = null;
    const aspect = `${Math.max(1, job.width)} / ${Math.max(1, job.height)}`;
    strip.replaceChildren(...order.map((frame) => {
      const thumb = h('span', { class: 'thumb' });
      thumb.style.aspectRatio = aspect;
      const bar = h('span', {});
      const button = h('button', { type: 'button', class: 'frame-cell pending', dataset: { frame: String(frame), state: 'pending' }, title: `Frame ${frame}: pending` },
        thumb, h('span', { class: 'frame-bar' }, bar), h('span', { class: 'frame-no', text: frame }));
      cells.set(frame, { button, thumb, bar, img: null, state: 'pending', title: '' });
      cellObserver.observe(button);
      return button;
    }));
    for (const frame of order) updateCell(frame);
    markShown();
  }

  function updateCell(frame) {
    const cell = cells.get(frame);
    if (!cell) return;
    const info = frameInfo.get(frame);
    const state = info?.state ?? 'pending';
    if (cell.state !== state) {
      cell.button.classList.replace(cell.state, state);
      cell.button.dataset.state = state;
      cell.state = state;
    }
    const counted = info?.tiles;
    cell.bar.style.width = counted && counted.total > 0 ? `${(100 * counted.done) / counted.total}%` : '0%';
    const title = [
      `Frame ${frame}: ${state}`,
      counted ? `${formatCount(counted.done)} of ${formatCount(counted.total)} tiles done` : null,
      info?.error ?? null,
    ].filter(Boolean).join('\n');
    if (cell.title !== title) {
      cell.button.title = title;
      cell.title = title;
    }
    if (state === 'done') {
      const entry = frameImages.entry(frame);
      if (entry?.state === 'ready') showThumbnail(cell, entry);
      else if (visibleCells.has(frame)) frameImages.want(frame, true);
      else if (playing) frameImages.want(frame);
    } else if (cell.img) {
      cell.img.remove();
      cell.img = null;
    }
  }

  function showThumbnail(cell, entry) {
    if (cell.img && cell.img.src === entry.url) return;
    cell.img = h('img', { src: entry.url, alt: '', draggable: false });
    cell.thumb.replaceChildren(cell.img);
  }

  function frameImageReady(entry) {
    if (view.gone) return;
    const cell = cells.get(entry.frame);
    if (cell && cell.state === 'done') showThumbnail(cell, entry);
  }

  // Thumbnails are fetched as their cells scroll into the strip's view (and a little ahead):
  // a strip of thousands of frames fetches only what is looked at.
  const cellObserver = new IntersectionObserver((seen) => {
    for (const sighting of seen) {
      const frame = Number(sighting.target.dataset.frame);
      if (!sighting.isIntersecting) {
        visibleCells.delete(frame);
        continue;
      }
      visibleCells.add(frame);
      if (frameInfo.get(frame)?.state === 'done') frameImages.want(frame, true);
    }
  }, { root: strip, rootMargin: '0px 50%' });

  function markShown() {
    setText(shownLabel, `Frame ${shownFrame}`);
    shownLabel.dataset.frame = String(shownFrame);
    const cell = cells.get(shownFrame) ?? null;
    if (shownCell && shownCell !== cell) shownCell.button.removeAttribute('aria-current');
    if (cell) {
      cell.button.setAttribute('aria-current', 'true');
      reveal(cell.button);
    }
    shownCell = cell;
  }

  // Scrolls the strip alone: scrollIntoView() would scroll the page too, away from the image.
  function reveal(button) {
    const left = button.offsetLeft;
    const right = left + button.offsetWidth;
    if (left < strip.scrollLeft) strip.scrollLeft = Math.max(0, left - 8);
    else if (right > strip.scrollLeft + strip.clientWidth) strip.scrollLeft = right - strip.clientWidth + 8;
  }

  function showFrameCounts() {
    const frames = job.frames;
    fill(frameCounts,
      `${formatCount(frames.done)} of ${formatCount(frames.total)} frames done`,
      frames.failed ? h('span', { class: 'error', text: `, ${formatCount(frames.failed)} failed` }) : null);
    playButton.disabled = !playing && frames.done === 0;
  }

  function applyFrames(list) {
    const order = list.map((info) => info.frame);
    if (order.length !== frameOrder.length || order.some((frame, at) => frame !== frameOrder[at])) buildStrip(order);
    frameInfo.clear();
    for (const info of list) frameInfo.set(info.frame, info);
    for (const frame of frameOrder) updateCell(frame);
    if (!tilesKnown) showCounts();
  }

  function loadFramesSoon() {
    if (framesTimer || view.gone) return;
    // Longer apart for longer animations: the list is one entry a frame.
    const every = Math.min(FRAMES_REFRESH_MAX_MS, Math.max(FRAMES_REFRESH_MS, frameOrder.length));
    framesTimer = setTimeout(() => {
      framesTimer = 0;
      loadFrames();
    }, Math.max(0, framesAt + every - Date.now()));
  }

  async function loadFrames() {
    if (framesBusy) {
      framesAgain = true;
      return;
    }
    framesBusy = true;
    framesAt = Date.now();
    try {
      const list = await api('GET', jobPath(id, '/frames'));
      if (!view.gone) applyFrames(list.frames ?? []);
    } catch (error) {
      if (!view.gone && error.status !== 404) reportError('The frames', error);
    } finally {
      framesBusy = false;
      if (framesAgain && !view.gone) {
        framesAgain = false;
        loadFramesSoon();
      }
    }
  }

  // The frame shown while following: the first not yet done (frames.current), or, once
  // none is left, the last one followed, so that the end of a render leaves it in view.
  function follow() {
    const current = job?.frames?.current;
    if (current !== null && current !== undefined) showFrame(current);
  }

  function showFrame(frame) {
    if (frame === shownFrame) return;
    shownFrame = frame;
    shownTiles = null;
    markShown();
    const entry = frameImages.entry(frame);
    if (entry?.state === 'ready' && frameInfo.get(frame)?.state === 'done') paintFrame(entry);
    else loadImage();
    showCounts();
    drawOverlaySoon();
  }

  // A done frame already fetched is drawn at once: the flipbook keeps its pace with no
  // request per frame.
  function paintFrame(entry) {
    imageSerial += 1;
    context.clearRect(0, 0, image.width, image.height);
    context.drawImage(entry.img, 0, 0);
    image.dataset.frame = String(entry.frame);
    imageLoading = false;
    const queued = pixelQueue;
    pixelQueue = [];
    for (const event of queued) drawPixels(event);
  }

  const doneFrames = () => frameOrder.filter((frame) => frameInfo.get(frame)?.state === 'done');

  function fps() {
    const value = Number(fpsInput.value);
    return Number.isFinite(value) && value > 0 && value <= 1000 ? value : DEFAULT_FPS;
  }

  function setPlaying(on) {
    if (on === playing) return;
    playing = on;
    playButton.setAttribute('aria-pressed', String(on));
    setText(playButton, on ? 'Pause' : 'Play');
    if (on) {
      setFollowing(false);
      // Every done frame fetched ahead, the next ones to be shown first.
      const done = doneFrames();
      const at = done.findIndex((frame) => framePosition.get(frame) > (framePosition.get(shownFrame) ?? -1));
      const start = at < 0 ? 0 : at;
      for (let k = 0; k < done.length; k += 1) frameImages.want(done[(start + k) % done.length]);
      lastStep = performance.now();
      playRequest = requestAnimationFrame(tick);
    } else {
      cancelAnimationFrame(playRequest);
      playRequest = 0;
    }
    if (job) showFrameCounts();
  }

  function setFollowing(on) {
    following = on;
    followButton.setAttribute('aria-pressed', String(on));
    if (on) {
      setPlaying(false);
      follow();
    }
  }

  function tick(now) {
    playRequest = requestAnimationFrame(tick);
    const period = 1000 / fps();
    if (now - lastStep < period) return;
    // After a stall (a hidden tab, a busy machine) it goes on from now, not in a burst.
    lastStep = now - lastStep > 4 * period ? now : lastStep + period;
    stepFlipbook();
  }

  // The next done frame after the one shown, round to the first again. One whose image is
  // still on its way holds the flipbook where it is (passing it would stutter through the
  // first loop); one that could not be fetched is passed over.
  function stepFlipbook() {
    const done = doneFrames();
    if (done.length === 0) return;
    const position = framePosition.get(shownFrame) ?? -1;
    let at = done.findIndex((frame) => framePosition.get(frame) > position);
    if (at < 0) at = 0;
    for (let k = 0; k < done.length; k += 1) {
      const frame = done[(at + k) % done.length];
      const entry = frameImages.entry(frame);
      if (entry?.state === 'ready') {
        showFrame(frame);
        return;
      }
      if (entry?.state === 'failed') {
        frameImages.want(frame);
        continue;
      }
      frameImages.want(frame, true);
      return;
    }
  }

  function pick(frame) {
    setPlaying(false);
    setFollowing(false);
    showFrame(frame);
  }

  playButton.addEventListener('click', () => setPlaying(!playing));
  followButton.addEventListener('click', () => setFollowing(true));
  strip.addEventListener('click', (event) => {
    const button = event.target.closest?.('.frame-cell');
    if (button) pick(Number(button.dataset.frame));
  });
  strip.addEventListener('keydown', (event) => {
    const moves = { ArrowLeft: -1, ArrowRight: 1, Home: -Infinity, End: Infinity };
    if (!(event.key in moves) || frameOrder.length === 0) return;
    event.preventDefault();
    const from = framePosition.get(shownFrame) ?? 0;
    const to = Math.min(frameOrder.length - 1, Math.max(0, from + moves[event.key]));
    pick(frameOrder[to]);
    cells.get(frameOrder[to])?.button.focus();
  });

  // --- tiles ---
  // The tiles the viewer shows: an animation's of the frame shown only.
  function tilesShown() {
    if (!animated) return tiles;
    shownTiles ??= tiles.filter((tile) => tile && tile.frame === shownFrame);
    return shownTiles;
  }

  function showCounts() {
    const by = { pending: 0, rendering: 0, done: 0, failed: 0 };
    const workers = new Map();
    const shown = tilesShown();
    for (const tile of shown) {
      if (!tile) continue;
      by[tile.state] = (by[tile.state] ?? 0) + 1;
      if (tile.state === 'rendering' && tile.worker) workers.set(tile.worker, tile.worker_name || tile.worker);
    }
    const info = animated ? frameInfo.get(shownFrame) : null;
    const prefix = animated ? `Frame ${shownFrame}: ` : '';
    let done = by.done;
    if (!tilesKnown) done = animated ? (info?.tiles.done ?? 0) : (job?.tiles.done ?? 0);
    counts.dataset.done = String(done);
    if (animated) counts.dataset.frame = String(shownFrame);
    if (!tilesKnown) {
      const total = animated ? info?.tiles.total : job?.tiles.total;
      setText(counts, job && total !== undefined ? `${prefix}${formatCount(done)} of ${formatCount(total)} tiles done` : '');
      return;
    }
    const total = animated ? shown.length : tiles.length;
    counts.dataset.total = String(total);
    fill(counts,
      `${prefix}${formatCount(total)} tiles: ${formatCount(by.done)} done, ${formatCount(by.rendering)} rendering, `
        + `${formatCount(by.pending)} pending, ${formatCount(by.failed)} failed`,
      ...[...workers].map(([worker, name]) => {
        const swatch = h('span', { class: 'swatch rendering' });
        swatch.style.borderColor = workerColour(worker);
        return h('span', {}, swatch, name);
      }),
    );
  }

  function applyTileState(event) {
    const old = tiles[event.index];
    // Done is final: an older event seen again (after a reload) must not undo it.
    if (old && old.state === 'done' && event.state !== 'done') return;
    tiles[event.index] = {
      index: event.index, frame: event.frame ?? 0, x: event.x, y: event.y, width: event.width, height: event.height,
      state: event.state, worker: event.worker ?? null, worker_name: event.worker_name ?? null,
      render_ms: event.render_ms ?? null,
    };
    if ((event.frame ?? 0) === shownFrame) shownTiles = null;
  }

  function drawPixels(event) {
    if (animated && event.frame !== shownFrame) return;
    const { x, y, width, height } = event;
    if (!(width > 0 && height > 0) || x + width > image.width || y + height > image.height) return;
    let bytes;
    try {
      bytes = atob(event.pixels);
    } catch {
      return;
    }
    const count = width * height;
    if (bytes.length !== count * 3) return;
    const data = context.createImageData(width, height);
    const rgba = data.data;
    for (let i = 0, j = 0, k = 0; i < count; i += 1, j += 3, k += 4) {
      rgba[k] = bytes.charCodeAt(j);
      rgba[k + 1] = bytes.charCodeAt(j + 1);
      rgba[k + 2] = bytes.charCodeAt(j + 2);
      rgba[k + 3] = 255;
    }
    context.putImageData(data, x, y);
  }

  function onTile(event) {
    if (!Number.isInteger(event.index) || event.index < 0) return;
    if (tilesLoading) tileQueue.push(event);
    else applyTileState(event);
    const ofShown = !animated || event.frame === shownFrame;
    if (animated) {
      // A frame begins with its first tile out: the strip says so before the list is read again.
      const info = frameInfo.get(event.frame);
      if (info && info.state === 'pending' && event.state === 'rendering') {
        frameInfo.set(event.frame, { ...info, state: 'rendering' });
        updateCell(event.frame);
      }
    }
    if (!ofShown) return;
    if (event.pixels) {
      if (imageLoading) pixelQueue.push(event);
      else drawPixels(event);
    } else if (event.state === 'done' && !playing) {
      // Done, but without its pixels: they come with the next image read.
      clearTimeout(refreshTimer);
      refreshTimer = setTimeout(loadImage, 1000);
    }
    showCounts();
    drawOverlaySoon();
  }

  async function loadTiles() {
    tilesLoading = true;
    try {
      // A page at a time: a job of millions of tiles is never one answer.
      const loaded = [];
      let offset = 0;
      while (offset !== null && offset !== undefined) {
        const list = await api('GET', jobPath(id, `/tiles?offset=${offset}`));
        if (view.gone) return;
        for (const tile of list.tiles ?? []) loaded[tile.index] = tile;
        offset = list.next_offset;
      }
      tiles = loaded;
      shownTiles = null;
      tilesKnown = true;
    } catch (error) {
      if (view.gone) return;
      if (error.status !== 404) reportError('The tiles', error);
    } finally {
      tilesLoading = false;
      const queued = tileQueue;
      tileQueue = [];
      if (tilesKnown) for (const event of queued) applyTileState(event);
      if (!view.gone) {
        showCounts();
        drawOverlaySoon();
      }
    }
  }

  // The image so far (an animation's: the frame shown), drawn whole; pixels of tile events
  // that came meanwhile go on top.
  let imageSerial = 0;
  async function loadImage() {
    const serial = ++imageSerial;
    const frame = shownFrame;
    imageLoading = true;
    try {
      const target = animated ? `/frames/${frame}/image?format=png&partial=1` : '/image?format=png&partial=1';
      const response = await fetchWithToken(jobPath(id, target), { cache: 'no-store' });
      await checked(response);
      const bitmap = await createImageBitmap(await response.blob());
      if (view.gone || serial !== imageSerial) {
        bitmap.close();
        return;
      }
      context.clearRect(0, 0, image.width, image.height);
      context.drawImage(bitmap, 0, 0);
      bitmap.close();
      if (animated) image.dataset.frame = String(frame);
    } catch (error) {
      if (!view.gone && error.status !== 409) reportError('The image', error);
    } finally {
      if (serial === imageSerial) {
        imageLoading = false;
        const queued = pixelQueue;
        pixelQueue = [];
        if (!view.gone) for (const event of queued) drawPixels(event);
      }
    }
  }

  async function loadAll() {
    const serial = ++loadSerial;
    tilesLoading = true;
    imageLoading = true;
    try {
      applyJob(await api('GET', jobPath(id)));
    } catch (error) {
      if (view.gone || serial !== loadSerial) return;
      tilesLoading = false;
      imageLoading = false;
      if (error.status === 404) {
        fill(main, h('div', { class: 'empty' }, `There is no job ${id}. `, h('a', { href: '/', 'data-nav': true, text: 'All jobs' })));
      } else if (error.status !== 401 && error.code !== 'wrong_role') {
        reportError('The job', error);
      }
      return;
    }
    if (view.gone || serial !== loadSerial) return;
    await Promise.all([loadTiles(), loadImage(), animated ? loadFrames() : null]);
  }

  // --- zoom, pan and the overlay ---
  function placeImage() {
    image.style.transform = `translate(${panX}px, ${panY}px) scale(${zoom})`;
    // Whole pixels, sharp, once they are large enough to be seen one by one.
    image.classList.toggle('pixelated', zoom >= 2);
    setText(zoomLabel, `${zoom >= 10 ? Math.round(zoom * 100) : Math.round(zoom * 1000) / 10}%`);
    drawOverlaySoon();
  }

  function minZoom() {
    const fitZoom = Math.min(viewer.clientWidth / image.width, viewer.clientHeight / image.height);
    return Math.min(1, fitZoom / 2);
  }

  function zoomAt(newZoom, cx, cy) {
    newZoom = Math.min(MAX_ZOOM, Math.max(minZoom(), newZoom));
    panX = cx - ((cx - panX) / zoom) * newZoom;
    panY = cy - ((cy - panY) / zoom) * newZoom;
    zoom = newZoom;
    placeImage();
  }

  const zoomBy = (factor) => zoomAt(zoom * factor, viewer.clientWidth / 2, viewer.clientHeight / 2);
  const setZoom = (value) => zoomAt(value, viewer.clientWidth / 2, viewer.clientHeight / 2);

  function fit() {
    const width = viewer.clientWidth;
    const height = viewer.clientHeight;
    let z = Math.min(width / image.width, height / image.height);
    if (z >= 2) z = Math.min(MAX_ZOOM, Math.floor(z)); // enlarged: each pixel as many screen pixels
    zoom = z;
    panX = Math.round((width - image.width * z) / 2);
    panY = Math.round((height - image.height * z) / 2);
    placeImage();
  }

  let overlayFrame = 0;
  function drawOverlaySoon() {
    if (!overlayFrame) overlayFrame = requestAnimationFrame(drawOverlay);
  }

  function drawOverlay() {
    overlayFrame = 0;
    if (view.gone) return;
    const ratio = window.devicePixelRatio || 1;
    const width = viewer.clientWidth;
    const height = viewer.clientHeight;
    if (overlay.width !== Math.round(width * ratio) || overlay.height !== Math.round(height * ratio)) {
      overlay.width = Math.round(width * ratio);
      overlay.height = Math.round(height * ratio);
      overlay.style.width = `${width}px`;
      overlay.style.height = `${height}px`;
    }
    const o = overlay.getContext('2d');
    o.setTransform(ratio, 0, 0, ratio, 0, 0);
    o.clearRect(0, 0, width, height);
    const rect = (tile) => [panX + tile.x * zoom, panY + tile.y * zoom, tile.width * zoom, tile.height * zoom];
    const visible = ([x, y, w, hgt]) => x + w >= 0 && y + hgt >= 0 && x <= width && y <= height;
    const shown = tilesShown();
    if (showHeat) {
      let slowest = 0;
      for (const tile of shown) if (tile?.state === 'done' && tile.render_ms > slowest) slowest = tile.render_ms;
      setText(legendMax, `${formatCount(Math.round(slowest))} ms`);
      if (slowest > 0) {
        for (const tile of shown) {
          if (tile?.state !== 'done' || tile.render_ms === null || tile.render_ms === undefined) continue;
          const r = rect(tile);
          if (!visible(r)) continue;
          o.fillStyle = heatColour(tile.render_ms / slowest, 0.6);
          o.fillRect(...r);
        }
      }
    }
    if (showTiles) {
      for (const tile of shown) {
        if (!tile || tile.state === 'done') continue;
        const [x, y, w, hgt] = rect(tile);
        if (!visible([x, y, w, hgt])) continue;
        if (tile.state === 'pending') {
          o.fillStyle = 'rgba(0, 0, 0, 0.45)';
          o.fillRect(x, y, w, hgt);
          o.strokeStyle = 'rgba(255, 255, 255, 0.12)';
          o.lineWidth = 1;
          o.strokeRect(x + 0.5, y + 0.5, Math.max(0, w - 1), Math.max(0, hgt - 1));
        } else if (tile.state === 'failed') {
          o.fillStyle = 'rgba(220, 30, 30, 0.5)';
          o.fillRect(x, y, w, hgt);
          o.strokeStyle = 'rgb(240, 40, 40)';
          o.lineWidth = 2;
          o.strokeRect(x + 1, y + 1, Math.max(0, w - 2), Math.max(0, hgt - 2));
        } else if (tile.state === 'rendering') {
          o.strokeStyle = workerColour(tile.worker);
          o.lineWidth = 2;
          o.strokeRect(x + 1, y + 1, Math.max(0, w - 2), Math.max(0, hgt - 2));
        }
      }
    }
  }

  function drawLegend() {
    const c = legendBar.getContext('2d');
    for (let x = 0; x < legendBar.width; x += 1) {
      c.fillStyle = heatColour(x / (legendBar.width - 1));
      c.fillRect(x, 0, 1, legendBar.height);
    }
  }

  toggleTiles.addEventListener('click', () => {
    showTiles = !showTiles;
    toggleTiles.setAttribute('aria-pressed', String(showTiles));
    drawOverlaySoon();
  });
  toggleHeat.addEventListener('click', () => {
    showHeat = !showHeat;
    toggleHeat.setAttribute('aria-pressed', String(showHeat));
    legend.hidden = !showHeat;
    drawOverlaySoon();
  });
  drawLegend();

  // Downloads go through fetch(), with the token in a header, and are saved from a blob.
  // An animation's: the frame shown.
  const download = (button, format) => act(button, `The ${format.toUpperCase()} image`, async () => {
    const frame = animated ? shownFrame : null;
    const target = frame === null ? `/image?format=${format}&partial=1` : `/frames/${frame}/image?format=${format}&partial=1`;
    const response = await fetchWithToken(jobPath(id, target), { cache: 'no-store' });
    await checked(response);
    const url = URL.createObjectURL(await response.blob());
    const name = frame === null
      ? fileName(job ?? { id, state: '' }, format)
      : fileName(job, format, { frame, whole: frameInfo.get(frame)?.state === 'done' });
    const link = h('a', { href: url, download: name, hidden: true });
    document.body.append(link);
    link.click();
    link.remove();
    setTimeout(() => URL.revokeObjectURL(url), 60000);
  });
  pngButton.addEventListener('click', () => download(pngButton, 'png'));
  exrButton.addEventListener('click', () => download(exrButton, 'exr'));

  // Wheel zooms about the pointer; dragging pans; hovering names the tile.
  viewer.addEventListener('wheel', (event) => {
    event.preventDefault();
    const box = viewer.getBoundingClientRect();
    const step = event.deltaMode === 1 ? event.deltaY * 16 : event.deltaY;
    zoomAt(zoom * Math.exp(-step * 0.0015), event.clientX - box.left, event.clientY - box.top);
  }, { passive: false });
  let drag = null;
  viewer.addEventListener('pointerdown', (event) => {
    if (event.button !== 0) return;
    drag = { x: event.clientX, y: event.clientY, panX, panY };
    viewer.setPointerCapture(event.pointerId);
    viewer.classList.add('dragging');
    tip.hidden = true;
  });
  viewer.addEventListener('pointermove', (event) => {
    if (drag) {
      panX = drag.panX + event.clientX - drag.x;
      panY = drag.panY + event.clientY - drag.y;
      placeImage();
      return;
    }
    const box = viewer.getBoundingClientRect();
    const cx = event.clientX - box.left;
    const cy = event.clientY - box.top;
    const ix = (cx - panX) / zoom;
    const iy = (cy - panY) / zoom;
    const tile = tilesShown().find((t) => t && ix >= t.x && ix < t.x + t.width && iy >= t.y && iy < t.y + t.height);
    if (!tile) {
      tip.hidden = true;
      return;
    }
    const lines = [`${animated ? `Frame ${tile.frame}, tile` : 'Tile'} ${tile.index} at ${tile.x}, ${tile.y} (${tile.width} × ${tile.height})`, tile.state];
    if (tile.worker_name || tile.worker) lines.push(`worker ${tile.worker_name || tile.worker}`);
    if (tile.render_ms !== null && tile.render_ms !== undefined) lines.push(`${formatCount(Math.round(tile.render_ms))} ms`);
    setText(tip, lines.join('\n'));
    tip.hidden = false;
    tip.style.left = `${Math.min(cx + 14, Math.max(0, box.width - tip.offsetWidth - 4))}px`;
    tip.style.top = `${Math.min(cy + 14, Math.max(0, box.height - tip.offsetHeight - 4))}px`;
  });
  const endDrag = () => {
    drag = null;
    viewer.classList.remove('dragging');
  };
  viewer.addEventListener('pointerup', endDrag);
  viewer.addEventListener('pointercancel', endDrag);
  viewer.addEventListener('pointerleave', () => {
    if (!drag) tip.hidden = true;
  });
  const resized = new ResizeObserver(() => {
    if (!fitted && job && viewer.clientWidth > 0) {
      fit();
      fitted = true;
    }
    drawOverlaySoon();
  });
  resized.observe(viewer);

  // First the events, then what is already there: nothing falls between the two.
  let started = false;
  const start = () => {
    if (started) return;
    started = true;
    loadAll();
  };
  const stream = liveStream(jobPath(id, '/events'), (type, data) => {
    if (type === 'tile') onTile(data);
    else if (type === 'job') applyJob(data);
    else if (type === 'job_removed' && data.id === id) fill(main, h('div', { class: 'empty' }, `The job ${id} was removed. `, h('a', { href: '/', 'data-nav': true, text: 'All jobs' })));
    else if (type === 'resync') loadAll();
  }, {
    onOpen: start,
    poll: () => {
      if (!job || !FINISHED.has(job.state)) loadAll();
    },
  });
  // A stream that never opens (a proxy that holds it) must not keep the page empty.
  const startTimer = setTimeout(start, 4000);
  const clock = setInterval(() => {
    if (job) applyJob(job);
  }, 5000);

  return {
    unmount() {
      view.gone = true;
      stream.stop();
      clearTimeout(startTimer);
      clearTimeout(refreshTimer);
      clearInterval(clock);
      resized.disconnect();
      if (overlayFrame) cancelAnimationFrame(overlayFrame);
      cancelAnimationFrame(playRequest);
      clearTimeout(framesTimer);
      cellObserver.disconnect();
      frameImages.close();
    },
  };
}


// ---------------------------------------------------------------------------------------
// The workers view: /workers

function workersView(main) {
  const rows = new Map(); // worker id -> row
  const tbody = h('tbody');
  const emptyRow = h('tr', { class: 'empty-row' }, h('td', { class: 'empty', colSpan: 10, text: 'Loading…' }));
  tbody.append(emptyRow);
  const view = { gone: false };
  let loadSerial = 0;

  append(main, [
    h('div', { class: 'toolbar' }, h('h1', { text: 'Workers' })),
    h('table', { class: 'grid workers', id: 'workers' },
      h('thead', {}, h('tr', {},
        h('th', { text: 'Name' }), h('th', { text: 'Host' }), h('th', { text: 'State' }),
        h('th', { text: 'Job' }), h('th', { class: 'num', text: 'Tile' }),
        h('th', { class: 'num', text: 'Threads' }), h('th', { class: 'num', text: 'Tiles/min' }),
        h('th', { class: 'num', text: 'Rays/s' }), h('th', { text: 'Last seen' }),
        h('th', { text: 'Actions' }))),
      tbody),
  ]);
  document.title = 'Workers · Tessera';

  const showEmpty = (text) => {
    setText(emptyRow.firstChild, text);
    if (!emptyRow.isConnected) tbody.append(emptyRow);
  };

  const makeRow = (worker) => {
    const row = { worker, key: null };
    row.name = h('td', { class: 'name' });
    row.host = h('td', { class: 'host' });
    row.state = h('td', { class: 'state-cell' });
    row.job = h('td', { class: 'job' });
    row.tile = h('td', { class: 'num' });
    row.threads = h('td', { class: 'num' });
    row.tilesPerMin = h('td', { class: 'num' });
    row.rays = h('td', { class: 'num' });
    row.seen = h('td', { class: 'seen' });
    row.actions = h('td', { class: 'actions' });
    row.tr = h('tr', { dataset: { workerId: worker.id } }, row.name, row.host, row.state, row.job,
      row.tile, row.threads, row.tilesPerMin, row.rays, row.seen, row.actions);
    updateRow(row, worker);
    return row;
  };

  const button = (label, verb, worker, cls) => {
    const b = h('button', {
      type: 'button', text: label, class: cls, dataset: { action: verb },
      onclick: () => act(b, `${label} ${worker.name}`, async () => {
        const answer = await api('POST', workerPath(worker.id, `/${verb}`));
        if (verb === 'remove') removeRow(worker.id);
        else if (answer && answer.id) upsert(answer);
      }),
    });
    return b;
  };

  const updateRow = (row, worker) => {
    row.worker = worker;
    fill(row.name, h('span', { text: worker.name }), h('span', { class: 'sub mono', text: worker.id }));
    setText(row.host, worker.host ?? '');
    const key = `${worker.state}/${worker.draining}/${worker.current_job}`;
    if (row.key !== key) {
      fill(row.state, stateBadge(worker.state), worker.draining ? [' ', stateBadge('draining')] : []);
      fill(row.job, worker.current_job
        ? h('a', { href: jobPage(worker.current_job), 'data-nav': true, class: 'mono', text: shortId(worker.current_job), title: worker.current_job })
        : '—');
      const gone = worker.state === 'gone' || worker.state === 'left';
      fill(row.actions, h('div', { class: 'buttons' },
        gone ? null : worker.draining ? button('Undrain', 'undrain', worker) : button('Drain', 'drain', worker),
        button('Remove', 'remove', worker, 'danger')));
      row.key = key;
    }
    setText(row.tile, worker.current_tile ?? '—');
    setText(row.threads, worker.threads ?? '—');
    setText(row.tilesPerMin, Number.isFinite(worker.tiles_per_min) ? (Math.round(worker.tiles_per_min * 10) / 10).toLocaleString('en-US') : '—');
    setText(row.rays, Number.isFinite(worker.rays_per_s) ? formatRate(worker.rays_per_s) : '—');
    setText(row.seen, formatAgo(worker.last_seen));
    row.seen.title = worker.last_seen ?? '';
  };

  const removeRow = (id) => {
    const row = rows.get(id);
    if (row) row.tr.remove();
    rows.delete(id);
    if (rows.size === 0) showEmpty('No workers. Start one with: tessera-worker --server URL');
  };

  function upsert(worker) {
    if (!worker || !worker.id) return;
    const row = rows.get(worker.id);
    if (row) return updateRow(row, worker);
    const fresh = makeRow(worker);
    rows.set(worker.id, fresh);
    emptyRow.remove();
    tbody.append(fresh.tr);
    return undefined;
  }

  const load = async () => {
    const serial = ++loadSerial;
    try {
      const { workers } = await api('GET', '/v1/workers');
      if (view.gone || serial !== loadSerial) return;
      const seen = new Set(workers.map((w) => w.id));
      for (const id of [...rows.keys()]) if (!seen.has(id)) removeRow(id);
      let previous = null;
      for (const worker of workers) {
        upsert(worker);
        const tr = rows.get(worker.id).tr;
        const wanted = previous ? previous.nextSibling : tbody.firstChild;
        if (wanted !== tr) tbody.insertBefore(tr, wanted);
        previous = tr;
      }
      if (workers.length === 0) showEmpty('No workers. Start one with: tessera-worker --server URL');
    } catch (error) {
      if (view.gone || serial !== loadSerial) return;
      if (error.status === 401 || error.code === 'wrong_role') {
        for (const id of [...rows.keys()]) removeRow(id);
        showEmpty('The workers are shown once the API token is given above.');
      } else {
        showEmpty(`The workers could not be listed: ${error.message}`);
      }
    }
  };

  const stream = liveStream('/v1/events', (type, data) => {
    if (type === 'worker') {
      if (data.change === 'removed') removeRow(data.worker?.id);
      else upsert(data.worker);
    } else if (type === 'resync') {
      load();
    }
  }, { poll: load });
  load();
  return ageingView(view, stream, () => {
    for (const row of rows.values()) setText(row.seen, formatAgo(row.worker.last_seen));
  });
}

// ---------------------------------------------------------------------------------------
// Views by address

function notFoundView(main) {
  append(main, h('div', { class: 'empty' }, 'The dashboard has no page here. ', h('a', { href: '/', 'data-nav': true, text: 'The jobs' })));
  document.title = 'Tessera';
  return { unmount() {} };
}

let current = null;

function route() {
  current?.unmount();
  current = null;
  const main = $('#main');
  main.replaceChildren();
  $('#flash').hidden = true;
  const path = location.pathname;
  let view = '';
  let match;
  if (path === '/') {
    view = 'jobs';
    current = jobsView(main);
  } else if ((match = /^\/jobs\/([^/]+)$/.exec(path))) {
    let id = null;
    try {
      id = decodeURIComponent(match[1]);
    } catch {
      /* not an id */
    }
    view = 'jobs';
    current = id ? jobView(main, id) : notFoundView(main);
  } else if (path === '/workers') {
    view = 'workers';
    current = workersView(main);
  } else {
    current = notFoundView(main);
  }
  for (const link of document.querySelectorAll('nav a[data-view]')) {
    if (link.dataset.view === view) link.setAttribute('aria-current', 'page');
    else link.removeAttribute('aria-current');
  }
}

function navigate(address) {
  history.pushState(null, '', address);
  route();
}

document.addEventListener('click', (event) => {
  const link = event.target.closest?.('a[data-nav]');
  if (!link || event.defaultPrevented || event.button !== 0) return;
  if (event.metaKey || event.ctrlKey || event.shiftKey || event.altKey) return;
  const url = new URL(link.href, location.href);
  if (url.origin !== location.origin) return;
  event.preventDefault();
  if (url.pathname + url.search !== location.pathname + location.search) navigate(url.pathname + url.search);
});
window.addEventListener('popstate', route);

$('#token-form').addEventListener('submit', (event) => {
  event.preventDefault();
  const input = $('#token-input');
  const value = input.value.trim();
  if (!value) return;
  token.set(value);
  input.value = '';
  auth.hide();
  showForgetButton();
  route();
});

$('#forget-token').addEventListener('click', () => {
  token.forget();
  showForgetButton();
  auth.hide();
  route();
});

showForgetButton();
learnAccess().then(route);
