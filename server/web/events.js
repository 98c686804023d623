// Server-sent events over fetch()

import {checked, tokenMissing, withAuth} from './api.js';
import {POLL_MS} from './constants.js';
import {setLive} from './page.js';

const sleep = (ms, signal) =>
  new Promise((resolve) => {
    const timer = setTimeout(resolve, ms);
    signal?.addEventListener(
      'abort',
      () => {
        clearTimeout(timer);
        resolve();
      },
      {once: true},
    );
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
      this.stopper.signal.addEventListener('abort', abort, {once: true});
      try {
        if (tokenMissing()) {
          this.on.denied?.();
          return;
        }
        const headers = withAuth({Accept: 'text/event-stream'});
        if (this.lastId !== null) headers['Last-Event-ID'] = this.lastId;
        const response = await fetch(this.path, {
          headers,
          cache: 'no-store',
          signal: attempt.signal,
        });
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
    let event = {type: '', data: [], id: null};
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
      event = {type: '', data: [], id: null};
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
      const {value, done} = await reader.read();
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
export function liveStream(path, onEvent, {onOpen, poll} = {}) {
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
