// An animation's frames in the job view: a strip of cells, one a frame in the order the
// farm renders them, each with its state, its progress and, once done, its thumbnail; the
// frame shown is marked, and named beside the strip. It owns the frames' list as GET
// /frames last gave it. Picking a cell (a click, the arrow keys) is the view's to act on.

import {fill, h, setText} from './dom.js';
import {formatCount} from './format.js';

export class FrameStrip {
  // `images`: the job's FrameImages. `onPick(frame)`: a frame was picked. `playing()`:
  // whether the flipbook runs, which wants every done frame's image, not only those in view.
  constructor({images, onPick, playing}) {
    this.images = images;
    this.onPick = onPick;
    this.playing = playing;
    this.order = []; // the frames, in the order rendered
    this.position = new Map(); // frame -> its place in `order`
    this.info = new Map(); // frame -> its FrameStatus, from GET /frames
    this.cells = new Map(); // frame -> {button, thumb, bar, img, state, title}
    this.inView = new Set(); // frames whose cell is in or near the strip's view
    this.marked = null; // the cell of the frame shown
    this.shown = null; // the frame shown, as last marked
    this.element = h('div', {
      class: 'frame-strip',
      id: 'frame-strip',
      role: 'group',
      'aria-label': 'Frames',
    });
    this.shownLabel = h('span', {class: 'frame-shown', id: 'frame-shown'});
    this.counts = h('span', {class: 'frame-counts', id: 'frame-counts'});
    // Thumbnails are fetched as their cells scroll into the strip's view (and a little
    // ahead): a strip of thousands of frames fetches only what is looked at.
    this.observer = new IntersectionObserver(
      (seen) => {
        for (const sighting of seen) {
          const frame = Number(sighting.target.dataset.frame);
          if (!sighting.isIntersecting) {
            this.inView.delete(frame);
            continue;
          }
          this.inView.add(frame);
          if (this.info.get(frame)?.state === 'done') this.images.want(frame, true);
        }
      },
      {root: this.element, rootMargin: '0px 50%'},
    );
    this.element.addEventListener('click', (event) => {
      const button = event.target.closest?.('.frame-cell');
      if (button) this.onPick(Number(button.dataset.frame));
    });
    this.element.addEventListener('keydown', (event) => this.onKey(event));
  }

  // The cells for `order`, each `aspect` ("width / height") like the image.
  build(order, aspect) {
    this.order = order;
    this.position.clear();
    order.forEach((frame, at) => this.position.set(frame, at));
    this.observer.disconnect();
    this.inView.clear();
    this.cells.clear();
    this.marked = null;
    this.element.replaceChildren(...order.map((frame) => this.makeCell(frame, aspect)));
    for (const frame of order) this.update(frame);
    if (this.shown !== null) this.mark(this.shown);
  }

  makeCell(frame, aspect) {
    const thumb = h('span', {class: 'thumb'});
    thumb.style.aspectRatio = aspect;
    const bar = h('span', {});
    const button = h(
      'button',
      {
        type: 'button',
        class: 'frame-cell pending',
        dataset: {frame: String(frame), state: 'pending'},
        title: `Frame ${frame}: pending`,
      },
      thumb,
      h('span', {class: 'frame-bar'}, bar),
      h('span', {class: 'frame-no', text: frame}),
    );
    this.cells.set(frame, {button, thumb, bar, img: null, state: 'pending', title: ''});
    this.observer.observe(button);
    return button;
  }

  // GET /frames's list: the strip is built again only where the frames themselves changed.
  apply(list, aspect) {
    const order = list.map((info) => info.frame);
    if (order.length !== this.order.length || order.some((f, at) => f !== this.order[at]))
      this.build(order, aspect);
    this.info.clear();
    for (const info of list) this.info.set(info.frame, info);
    for (const frame of this.order) this.update(frame);
  }

  // A frame begins with its first tile out: the strip says so before the list is read again.
  begun(frame) {
    const info = this.info.get(frame);
    if (info && info.state === 'pending') {
      this.info.set(frame, {...info, state: 'rendering'});
      this.update(frame);
    }
  }

  update(frame) {
    const cell = this.cells.get(frame);
    if (!cell) return;
    const info = this.info.get(frame);
    const state = info?.state ?? 'pending';
    if (cell.state !== state) {
      cell.button.classList.replace(cell.state, state);
      cell.button.dataset.state = state;
      cell.state = state;
    }
    const counted = info?.tiles;
    cell.bar.style.width =
      counted && counted.total > 0 ? `${(100 * counted.done) / counted.total}%` : '0%';
    const title = [
      `Frame ${frame}: ${state}`,
      counted ? `${formatCount(counted.done)} of ${formatCount(counted.total)} tiles done` : null,
      info?.error ?? null,
    ]
      .filter(Boolean)
      .join('\n');
    if (cell.title !== title) {
      cell.button.title = title;
      cell.title = title;
    }
    if (state === 'done') {
      const entry = this.images.entry(frame);
      if (entry?.state === 'ready') this.showThumbnail(cell, entry);
      else if (this.inView.has(frame)) this.images.want(frame, true);
      else if (this.playing()) this.images.want(frame);
    } else if (cell.img) {
      cell.img.remove();
      cell.img = null;
    }
  }

  showThumbnail(cell, entry) {
    if (cell.img && cell.img.src === entry.url) return;
    cell.img = h('img', {src: entry.url, alt: '', draggable: false});
    cell.thumb.replaceChildren(cell.img);
  }

  // A frame's image arrived: its thumbnail, if it is still done.
  imageReady(entry) {
    const cell = this.cells.get(entry.frame);
    if (cell && cell.state === 'done') this.showThumbnail(cell, entry);
  }

  isDone(frame) {
    return this.info.get(frame)?.state === 'done';
  }

  doneFrames() {
    return this.order.filter((frame) => this.isDone(frame));
  }

  mark(shown) {
    this.shown = shown;
    setText(this.shownLabel, `Frame ${shown}`);
    this.shownLabel.dataset.frame = String(shown);
    const cell = this.cells.get(shown) ?? null;
    if (this.marked && this.marked !== cell) this.marked.button.removeAttribute('aria-current');
    if (cell) {
      cell.button.setAttribute('aria-current', 'true');
      this.reveal(cell.button);
    }
    this.marked = cell;
  }

  // Scrolls the strip alone: scrollIntoView() would scroll the page too, away from the image.
  reveal(button) {
    const strip = this.element;
    const left = button.offsetLeft;
    const right = left + button.offsetWidth;
    if (left < strip.scrollLeft) strip.scrollLeft = Math.max(0, left - 8);
    else if (right > strip.scrollLeft + strip.clientWidth)
      strip.scrollLeft = right - strip.clientWidth + 8;
  }

  showCounts(frames) {
    fill(
      this.counts,
      `${formatCount(frames.done)} of ${formatCount(frames.total)} frames done`,
      frames.failed
        ? h('span', {class: 'error', text: `, ${formatCount(frames.failed)} failed`})
        : null,
    );
  }

  onKey(event) {
    const moves = {ArrowLeft: -1, ArrowRight: 1, Home: -Infinity, End: Infinity};
    if (!(event.key in moves) || this.order.length === 0) return;
    event.preventDefault();
    const from = this.position.get(this.shown) ?? 0;
    const to = Math.min(this.order.length - 1, Math.max(0, from + moves[event.key]));
    this.onPick(this.order[to]);
    this.cells.get(this.order[to])?.button.focus();
  }

  close() {
    this.observer.disconnect();
  }
}
