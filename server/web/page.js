// The token prompt, messages and the live indicator

import {ApiError, token} from './api.js';
import {$, setText} from './dom.js';

export const auth = {
  asked: false,
  ask(error) {
    this.asked = true;
    const form = $('#auth');
    const message = $('#auth-error');
    if (token.get() && error) {
      setText(
        message,
        error.code === 'wrong_role'
          ? "That token is not the API token (it is the worker token or another role's)."
          : `The coordinator refused that token (${error.code}).`,
      );
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

export function showForgetButton() {
  $('#forget-token').hidden = !token.get();
}

let flashTimer = 0;
export function flash(message) {
  const element = $('#flash');
  setText(element, message);
  element.hidden = false;
  clearTimeout(flashTimer);
  flashTimer = setTimeout(() => {
    element.hidden = true;
  }, 8000);
}

export function reportError(what, error) {
  if (error instanceof ApiError && (error.status === 401 || error.code === 'wrong_role')) return;
  flash(`${what}: ${error.message}`);
}

export function setLive(state) {
  const element = $('#live');
  const text =
    {
      live: 'live',
      connecting: 'connecting',
      reconnecting: 'reconnecting',
      polling: 'polling',
      idle: '',
    }[state] ?? state;
  setText(element, text);
  element.classList.toggle('on', state === 'live');
  element.classList.toggle('off', state === 'reconnecting' || state === 'polling');
  element.title =
    {
      live: 'Live: the coordinator sends every change as it happens',
      polling: 'This coordinator sends no live events: the page reloads every few seconds',
      reconnecting: 'The live connection dropped; trying again',
    }[state] ?? '';
}
