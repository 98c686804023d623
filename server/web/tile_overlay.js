// What the job view draws over its image: the tiles' states (pending dim, rendering outlined
// in its worker's colour, failed red), the heatmap of done tiles' render times with its
// legend, and the tip that names the tile under the pointer. It owns the two toggles; the
// tiles it shows and where they are on the screen it asks of the view and the canvas.

import {heatColour, workerColour} from './colours.js';
import {h, setText} from './dom.js';
import {formatCount} from './format.js';

export class TileOverlay {
  // `canvas`: the ImageCanvas it lies over. `tiles()`: the tiles shown (nulls allowed).
  // `animated()`: whether the tip names the tile's frame.
  constructor(canvas, {tiles, animated}) {
    this.canvas = canvas;
    this.tiles = tiles;
    this.animated = animated;
    this.showTiles = true;
    this.showHeat = false;
    this.pending = 0; // the animation frame a redraw waits for
    this.overlay = h('canvas', {class: 'overlay', 'aria-hidden': 'true'});
    this.tip = h('div', {class: 'tip', hidden: true});
    canvas.viewer.append(this.overlay, this.tip);
    this.legendBar = h('canvas', {width: 160, height: 10});
    this.legendMax = h('span', {});
    this.legend = h(
      'div',
      {class: 'legend', hidden: true},
      'Render time: 0 ms',
      this.legendBar,
      this.legendMax,
    );
    this.toggleTiles = h('button', {
      type: 'button',
      text: 'Tiles',
      id: 'toggle-tiles',
      'aria-pressed': 'true',
      title: "Tile states: pending dim, rendering outlined in its worker's colour, failed red",
    });
    this.toggleHeat = h('button', {
      type: 'button',
      text: 'Heatmap',
      id: 'toggle-heat',
      'aria-pressed': 'false',
      title: 'Each done tile coloured by its render time, relative to the slowest',
    });
    this.toggles = h('span', {class: 'group'}, this.toggleTiles, this.toggleHeat);
    this.toggleTiles.addEventListener('click', () => {
      this.showTiles = !this.showTiles;
      this.toggleTiles.setAttribute('aria-pressed', String(this.showTiles));
      this.drawSoon();
    });
    this.toggleHeat.addEventListener('click', () => {
      this.showHeat = !this.showHeat;
      this.toggleHeat.setAttribute('aria-pressed', String(this.showHeat));
      this.legend.hidden = !this.showHeat;
      this.drawSoon();
    });
    this.drawLegend();
    this.listen();
  }

  drawSoon() {
    if (!this.pending) this.pending = requestAnimationFrame(() => this.draw());
  }

  draw() {
    this.pending = 0;
    const {overlay, canvas} = this;
    const ratio = window.devicePixelRatio || 1;
    const width = canvas.viewer.clientWidth;
    const height = canvas.viewer.clientHeight;
    if (
      overlay.width !== Math.round(width * ratio) ||
      overlay.height !== Math.round(height * ratio)
    ) {
      overlay.width = Math.round(width * ratio);
      overlay.height = Math.round(height * ratio);
      overlay.style.width = `${width}px`;
      overlay.style.height = `${height}px`;
    }
    const o = overlay.getContext('2d');
    o.setTransform(ratio, 0, 0, ratio, 0, 0);
    o.clearRect(0, 0, width, height);
    const rect = (tile) => canvas.toScreen(tile.x, tile.y, tile.width, tile.height);
    const visible = ([x, y, w, hgt]) => x + w >= 0 && y + hgt >= 0 && x <= width && y <= height;
    const shown = this.tiles();
    if (this.showHeat) this.drawHeat(o, shown, rect, visible);
    if (this.showTiles) this.drawStates(o, shown, rect, visible);
  }

  drawHeat(o, shown, rect, visible) {
    let slowest = 0;
    for (const tile of shown)
      if (tile?.state === 'done' && tile.render_ms > slowest) slowest = tile.render_ms;
    setText(this.legendMax, `${formatCount(Math.round(slowest))} ms`);
    if (slowest <= 0) return;
    for (const tile of shown) {
      if (tile?.state !== 'done' || tile.render_ms === null || tile.render_ms === undefined)
        continue;
      const r = rect(tile);
      if (!visible(r)) continue;
      o.fillStyle = heatColour(tile.render_ms / slowest, 0.6);
      o.fillRect(...r);
    }
  }

  drawStates(o, shown, rect, visible) {
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

  drawLegend() {
    const c = this.legendBar.getContext('2d');
    for (let x = 0; x < this.legendBar.width; x += 1) {
      c.fillStyle = heatColour(x / (this.legendBar.width - 1));
      c.fillRect(x, 0, 1, this.legendBar.height);
    }
  }

  // Hovering names the tile; a drag (the canvas's) hides the tip.
  listen() {
    const {viewer} = this.canvas;
    viewer.addEventListener('pointerdown', (event) => {
      if (event.button === 0) this.tip.hidden = true;
    });
    viewer.addEventListener('pointermove', (event) => {
      if (this.canvas.dragging()) return;
      const box = viewer.getBoundingClientRect();
      const cx = event.clientX - box.left;
      const cy = event.clientY - box.top;
      this.showTip(cx, cy, box);
    });
    viewer.addEventListener('pointerleave', () => {
      if (!this.canvas.dragging()) this.tip.hidden = true;
    });
  }

  showTip(cx, cy, box) {
    const {tip} = this;
    const [ix, iy] = this.canvas.toImage(cx, cy);
    const tile = this.tiles().find(
      (t) => t && ix >= t.x && ix < t.x + t.width && iy >= t.y && iy < t.y + t.height,
    );
    if (!tile) {
      tip.hidden = true;
      return;
    }
    const where = `${tile.index} at ${tile.x}, ${tile.y} (${tile.width} × ${tile.height})`;
    const lines = [
      `${this.animated() ? `Frame ${tile.frame}, tile` : 'Tile'} ${where}`,
      tile.state,
    ];
    if (tile.worker_name || tile.worker) lines.push(`worker ${tile.worker_name || tile.worker}`);
    if (tile.render_ms !== null && tile.render_ms !== undefined)
      lines.push(`${formatCount(Math.round(tile.render_ms))} ms`);
    setText(tip, lines.join('\n'));
    tip.hidden = false;
    tip.style.left = `${Math.min(cx + 14, Math.max(0, box.width - tip.offsetWidth - 4))}px`;
    tip.style.top = `${Math.min(cy + 14, Math.max(0, box.height - tip.offsetHeight - 4))}px`;
  }

  close() {
    if (this.pending) cancelAnimationFrame(this.pending);
  }
}
