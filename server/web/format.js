// Numbers and times, as people read them

import {FINISHED} from './contract.js';

export function formatDuration(seconds) {
  if (seconds === null || seconds === undefined || !Number.isFinite(seconds)) return '—';
  const s = Math.max(0, Math.round(seconds));
  if (s < 60) return `${s} s`;
  if (s < 3600) return s % 60 ? `${Math.floor(s / 60)} min ${s % 60} s` : `${s / 60} min`;
  const minutes = Math.round((s % 3600) / 60);
  return minutes ? `${Math.floor(s / 3600)} h ${minutes} min` : `${Math.floor(s / 3600)} h`;
}

// A job's time left: none once it ended or while it is paused.
export function formatEta(job) {
  return FINISHED.has(job.state) || job.state === 'paused' ? '—' : formatDuration(job.eta_s);
}

export function formatAgo(iso) {
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
export function formatRate(value) {
  if (!Number.isFinite(value) || value <= 0) return '0';
  const units = ['', ' k', ' M', ' G', ' T'];
  let i = 0;
  while (value >= 999.5 && i < units.length - 1) {
    value /= 1000;
    i += 1;
  }
  return (i === 0 ? String(Math.round(value)) : value.toPrecision(3)) + units[i];
}

export function formatCount(value) {
  return Number.isFinite(value) ? value.toLocaleString('en-US') : '—';
}

export function shortId(id) {
  return typeof id === 'string' && id.length > 10 ? id.slice(0, 10) : String(id ?? '');
}

// What a download is saved as. One frame of an animation says which, so that the frames of
// a sequence sort and do not overwrite each other; "-partial" while the image is not whole.
export function fileName(job, extension, {frame = null, whole = job.state === 'completed'} = {}) {
  const base =
    String(job.name || job.id)
      .replace(/[^A-Za-z0-9._-]+/g, '_')
      .replace(/^[._]+/, '')
      .slice(0, 80) || job.id;
  const which = frame === null ? '' : `-frame${String(frame).padStart(4, '0')}`;
  return `${base}${which}${whole ? '' : '-partial'}.${extension}`;
}
