// The job view's flipbook and its follow mode: Play runs the done frames in order at the
// chosen pace, looping; Follow shows the frame being rendered and moves on with the render.
// Either stops the other, and picking a frame stops both. It owns the pace and the two
// modes; the frame shown is the view's, which it asks to show another.

import {DEFAULT_FPS} from './constants.js';
import {h, setText} from './dom.js';

export class Flipbook {
  // `strip`: the FrameStrip, which knows the done frames and their order. `images`: the
  // job's FrameImages. `shown()`: the frame shown. `show(frame)`: show another. `follow()`:
  // show the frame being rendered. `changed()`: playing or not changed.
  constructor({strip, images, shown, show, follow, changed}) {
    Object.assign(this, {strip, images, shown, show, follow, changed});
    this.playing = false;
    this.following = true;
    this.request = 0; // the animation frame the next step waits for
    this.lastStep = 0;
    this.playButton = h('button', {
      type: 'button',
      text: 'Play',
      id: 'flip-play',
      'aria-pressed': 'false',
      disabled: true,
      title: 'Play the done frames in order, looping',
    });
    this.fpsInput = h('input', {
      type: 'number',
      id: 'flip-fps',
      class: 'fps',
      min: 1,
      max: 240,
      step: 'any',
      value: DEFAULT_FPS,
      'aria-label': 'Frames per second',
    });
    this.followButton = h('button', {
      type: 'button',
      text: 'Follow',
      id: 'frame-follow',
      'aria-pressed': 'true',
      title: 'Show the frame being rendered, and move on with the render',
    });
    this.playButton.addEventListener('click', () => this.setPlaying(!this.playing));
    this.followButton.addEventListener('click', () => this.setFollowing(true));
  }

  // Play is offered once a frame is done (or while it plays, to pause it).
  enable(doneFrames) {
    this.playButton.disabled = !this.playing && doneFrames === 0;
  }

  fps() {
    const value = Number(this.fpsInput.value);
    return Number.isFinite(value) && value > 0 && value <= 1000 ? value : DEFAULT_FPS;
  }

  setPlaying(on) {
    if (on === this.playing) return;
    this.playing = on;
    this.playButton.setAttribute('aria-pressed', String(on));
    setText(this.playButton, on ? 'Pause' : 'Play');
    if (on) {
      this.setFollowing(false);
      // Every done frame fetched ahead, the next ones to be shown first.
      const done = this.strip.doneFrames();
      const position = this.strip.position;
      const at = done.findIndex(
        (frame) => position.get(frame) > (position.get(this.shown()) ?? -1),
      );
      const start = at < 0 ? 0 : at;
      for (let k = 0; k < done.length; k += 1) this.images.want(done[(start + k) % done.length]);
      this.lastStep = performance.now();
      this.request = requestAnimationFrame((now) => this.tick(now));
    } else {
      cancelAnimationFrame(this.request);
      this.request = 0;
    }
    this.changed();
  }

  setFollowing(on) {
    this.following = on;
    this.followButton.setAttribute('aria-pressed', String(on));
    if (on) {
      this.setPlaying(false);
      this.follow();
    }
  }

  // A frame picked by hand: neither mode goes on.
  pick(frame) {
    this.setPlaying(false);
    this.setFollowing(false);
    this.show(frame);
  }

  tick(now) {
    this.request = requestAnimationFrame((next) => this.tick(next));
    const period = 1000 / this.fps();
    if (now - this.lastStep < period) return;
    // After a stall (a hidden tab, a busy machine) it goes on from now, not in a burst.
    this.lastStep = now - this.lastStep > 4 * period ? now : this.lastStep + period;
    this.step();
  }

  // The next done frame after the one shown, round to the first again. One whose image is
  // still on its way holds the flipbook where it is (passing it would stutter through the
  // first loop); one that could not be fetched is passed over.
  step() {
    const done = this.strip.doneFrames();
    if (done.length === 0) return;
    const position = this.strip.position.get(this.shown()) ?? -1;
    let at = done.findIndex((frame) => this.strip.position.get(frame) > position);
    if (at < 0) at = 0;
    for (let k = 0; k < done.length; k += 1) {
      const frame = done[(at + k) % done.length];
      const entry = this.images.entry(frame);
      if (entry?.state === 'ready') {
        this.show(frame);
        return;
      }
      if (entry?.state === 'failed') {
        this.images.want(frame);
        continue;
      }
      this.images.want(frame, true);
      return;
    }
  }

  close() {
    cancelAnimationFrame(this.request);
  }
}
