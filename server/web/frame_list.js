// A frame list as the API writes it ("1-48", "1-100x2", "1,5,10-20"): its frames in the
// order the farm renders them (increasing, each once), so that the strip can be drawn before
// GET /frames answers; null where it cannot be read, and the strip waits for that answer.

import {MAX_STRIP_FRAMES} from './constants.js';

export function parseFrameList(text) {
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
