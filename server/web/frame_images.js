// The done frames' images of one job. Each is fetched once (through fetch(), since an
// <img src> could not send the token, and shown from a blob: URL, which the page's CSP
// allows) and decoded ahead, so that the strip's thumbnail and the flipbook are the same
// image and the flipbook never waits on the network mid-loop. A few at a time: a long
// animation must not flood the coordinator, and frames asked for `soon` (in view, or next
// in the flipbook) go first.

import {ApiError, checked, fetchWithToken, jobPath} from './api.js';
import {FRAME_IMAGE_ATTEMPTS, FRAME_IMAGE_FETCHES, FRAME_IMAGE_RETRY_MS} from './constants.js';

export class FrameImages {
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
    entry = {frame, state: 'queued', url: '', img: null, failedAt: 0, attempts: 0};
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
      const response = await fetchWithToken(
        jobPath(this.jobId, `/frames/${entry.frame}/image?format=png`),
        {cache: 'no-store'},
      );
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
        if (this.closed || this.entries.get(entry.frame) !== entry || entry.state !== 'failed')
          return;
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
