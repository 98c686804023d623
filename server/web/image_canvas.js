// The job view's image: a canvas the size of the job's image, zoomed and panned inside its
// viewer, with the tiles' pixels drawn in as they come. It owns the zoom and the pan; the
// overlay asks it where an image pixel is on the screen.

import {MAX_ZOOM} from './constants.js';
import {h, setText} from './dom.js';

export class ImageCanvas {
  constructor({onPlaced}) {
    this.onPlaced = onPlaced; // the view moved: what is drawn over it must follow
    this.zoom = 1;
    this.panX = 0;
    this.panY = 0;
    this.fitted = false;
    this.sized = false; // whether the job's size is known: until then there is nothing to fit
    this.drag = null;
    this.image = h('canvas', {class: 'image', id: 'image', width: 1, height: 1});
    this.context = this.image.getContext('2d');
    this.viewer = h('div', {class: 'viewer', id: 'viewer'}, this.image);
    this.zoomLabel = h('span', {class: 'zoom-level', text: '100%'});
    const button = (text, label, onclick) =>
      h('button', {type: 'button', text, title: label, 'aria-label': label, onclick});
    this.controls = h(
      'span',
      {class: 'group'},
      button('−', 'Zoom out', () => this.zoomBy(1 / 2)),
      this.zoomLabel,
      button('+', 'Zoom in', () => this.zoomBy(2)),
      h('button', {type: 'button', text: 'Fit', onclick: () => this.fit()}),
      h('button', {type: 'button', text: '1:1', onclick: () => this.setZoom(1)}),
    );
    this.listen();
  }

  // The job's size: a new size is fitted into the viewer again.
  resize(width, height) {
    this.sized = true;
    if (this.image.width !== width || this.image.height !== height) {
      this.image.width = width;
      this.image.height = height;
      this.fitted = false;
    }
    this.fitOnce();
  }

  fitOnce() {
    if (!this.fitted && this.sized && this.viewer.clientWidth > 0) {
      this.fit();
      this.fitted = true;
    }
  }

  // Screen position of an image rectangle, relative to the viewer: [x, y, width, height].
  toScreen(x, y, width, height) {
    const z = this.zoom;
    return [this.panX + x * z, this.panY + y * z, width * z, height * z];
  }

  // The image pixel under a point of the viewer.
  toImage(cx, cy) {
    return [(cx - this.panX) / this.zoom, (cy - this.panY) / this.zoom];
  }

  // A whole image (an ImageBitmap or a decoded <img>) in place of what was drawn.
  drawWhole(source, frame = null) {
    this.context.clearRect(0, 0, this.image.width, this.image.height);
    this.context.drawImage(source, 0, 0);
    if (frame !== null) this.image.dataset.frame = String(frame);
  }

  // One tile's pixels from its event: base64 of 8-bit RGB, row by row.
  drawPixels({x, y, width, height, pixels}) {
    if (
      !(width > 0 && height > 0) ||
      x + width > this.image.width ||
      y + height > this.image.height
    )
      return;
    let bytes;
    try {
      bytes = atob(pixels);
    } catch {
      return;
    }
    const count = width * height;
    if (bytes.length !== count * 3) return;
    const data = this.context.createImageData(width, height);
    const rgba = data.data;
    for (let i = 0, j = 0, k = 0; i < count; i += 1, j += 3, k += 4) {
      rgba[k] = bytes.charCodeAt(j);
      rgba[k + 1] = bytes.charCodeAt(j + 1);
      rgba[k + 2] = bytes.charCodeAt(j + 2);
      rgba[k + 3] = 255;
    }
    this.context.putImageData(data, x, y);
  }

  place() {
    const {image, zoom} = this;
    image.style.transform = `translate(${this.panX}px, ${this.panY}px) scale(${zoom})`;
    // Whole pixels, sharp, once they are large enough to be seen one by one.
    image.classList.toggle('pixelated', zoom >= 2);
    setText(
      this.zoomLabel,
      `${zoom >= 10 ? Math.round(zoom * 100) : Math.round(zoom * 1000) / 10}%`,
    );
    this.onPlaced();
  }

  minZoom() {
    const {viewer, image} = this;
    const fitZoom = Math.min(viewer.clientWidth / image.width, viewer.clientHeight / image.height);
    return Math.min(1, fitZoom / 2);
  }

  zoomAt(newZoom, cx, cy) {
    newZoom = Math.min(MAX_ZOOM, Math.max(this.minZoom(), newZoom));
    this.panX = cx - ((cx - this.panX) / this.zoom) * newZoom;
    this.panY = cy - ((cy - this.panY) / this.zoom) * newZoom;
    this.zoom = newZoom;
    this.place();
  }

  zoomBy(factor) {
    this.zoomAt(this.zoom * factor, this.viewer.clientWidth / 2, this.viewer.clientHeight / 2);
  }

  setZoom(value) {
    this.zoomAt(value, this.viewer.clientWidth / 2, this.viewer.clientHeight / 2);
  }

  fit() {
    const {viewer, image} = this;
    const width = viewer.clientWidth;
    const height = viewer.clientHeight;
    let z = Math.min(width / image.width, height / image.height);
    if (z >= 2) z = Math.min(MAX_ZOOM, Math.floor(z)); // enlarged: each pixel as many screen pixels
    this.zoom = z;
    this.panX = Math.round((width - image.width * z) / 2);
    this.panY = Math.round((height - image.height * z) / 2);
    this.place();
  }

  // Wheel zooms about the pointer; dragging pans.
  listen() {
    const {viewer} = this;
    viewer.addEventListener(
      'wheel',
      (event) => {
        event.preventDefault();
        const box = viewer.getBoundingClientRect();
        const step = event.deltaMode === 1 ? event.deltaY * 16 : event.deltaY;
        this.zoomAt(
          this.zoom * Math.exp(-step * 0.0015),
          event.clientX - box.left,
          event.clientY - box.top,
        );
      },
      {passive: false},
    );
    viewer.addEventListener('pointerdown', (event) => {
      if (event.button !== 0) return;
      this.drag = {x: event.clientX, y: event.clientY, panX: this.panX, panY: this.panY};
      viewer.setPointerCapture(event.pointerId);
      viewer.classList.add('dragging');
    });
    viewer.addEventListener('pointermove', (event) => {
      if (!this.drag) return;
      this.panX = this.drag.panX + event.clientX - this.drag.x;
      this.panY = this.drag.panY + event.clientY - this.drag.y;
      this.place();
    });
    const endDrag = () => {
      this.drag = null;
      viewer.classList.remove('dragging');
    };
    viewer.addEventListener('pointerup', endDrag);
    viewer.addEventListener('pointercancel', endDrag);
    this.resized = new ResizeObserver(() => {
      this.fitOnce();
      this.onPlaced();
    });
    this.resized.observe(viewer);
  }

  dragging() {
    return this.drag !== null;
  }

  close() {
    this.resized.disconnect();
  }
}
