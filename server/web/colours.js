// Colours the job view paints with.

// A colour per worker, the same every time for the same id; never red, which is failure's.
export function workerColour(id) {
  let hash = 2166136261;
  for (const c of String(id ?? '')) hash = Math.imul(hash ^ c.charCodeAt(0), 16777619) >>> 0;
  return `hsl(${40 + (hash % 270)}, 90%, 60%)`;
}

// t from 0 (fastest) to 1 (slowest): blue, through green and yellow, to red.
export function heatColour(t, alpha = 1) {
  const hue = 240 * (1 - Math.min(1, Math.max(0, t)));
  return `hsla(${hue}, 90%, 50%, ${alpha})`;
}
