// The head of the job view: the job's name and state, its status line (tiles, frames,
// times, rate, troubles) and its actions (pause, resume, retry, cancel, delete, priority).
// It shows the job it is given; the actions' answers go back to the view.

import {fill, h, setText} from './dom.js';
import {formatAgo, formatCount, formatDuration, formatEta, formatRate} from './format.js';
import {jobButtons, priorityInput, stateBadge, syncPriority} from './job_actions.js';

export class JobHeader {
  // `applied(job)`: an action's answer, the job as it is now. `deleted()`: the job is gone.
  constructor(id, {applied, deleted}) {
    this.applied = applied;
    this.deleted = deleted;
    this.job = null;
    this.title = h('h1', {class: 'job-title', text: id});
    this.badge = h('span', {class: 'state-holder'});
    this.head = h(
      'div',
      {class: 'job-head'},
      h('a', {href: '/', 'data-nav': true, text: '‹ Jobs'}),
      this.title,
      h('span', {class: 'mono', text: id}),
      this.badge,
    );
    this.status = h('div', {class: 'status-line', id: 'job-status'});
    this.actions = h('span', {class: 'group actions'});
    this.priority = priorityInput(
      () => this.job,
      (changed) => applied(changed),
    );
    this.priority.disabled = true;
    this.priorityGroup = h('label', {class: 'group'}, 'Priority', this.priority);
  }

  // `was`: the job as last shown (null the first time). `animated`: its frames are counted.
  show(job, was, animated) {
    this.job = job;
    setText(this.title, job.name || job.id);
    document.title = `${job.name || job.id} · Tessera`;
    if (!was || was.state !== job.state) {
      fill(this.badge, stateBadge(job.state));
      fill(this.actions, jobButtons(job, {applied: this.applied, deleted: this.deleted}));
    }
    syncPriority(this.priority, job);
    const frames = job.frames;
    const parts = [
      [
        'Tiles',
        `${formatCount(job.tiles.done)} / ${formatCount(job.tiles.total)} (${Math.floor(job.progress * 100)}%)`,
      ],
      animated ? ['Frames', `${formatCount(frames.done)} / ${formatCount(frames.total)}`] : null,
      ['Rendering', formatCount(job.tiles.rendering)],
      ['Elapsed', formatDuration(job.elapsed_s)],
      ['ETA', formatEta(job)],
      ['Rays/s', formatRate(job.stats?.rays_per_s)],
      ['Size', `${job.width} × ${job.height}`],
      ['Submitted', formatAgo(job.created_at)],
    ].filter(Boolean);
    const health = job.health ?? {};
    const troubles = [];
    if (health.tile_failures) troubles.push(`${health.tile_failures} tile failures`);
    if (health.refused_results) troubles.push(`${health.refused_results} results refused`);
    if (health.repeated_handouts) troubles.push(`${health.repeated_handouts} tiles sent out again`);
    fill(
      this.status,
      ...parts.map(([label, value]) => h('span', {}, `${label} `, h('b', {text: value}))),
      troubles.length ? h('span', {class: 'error', text: troubles.join(', ')}) : null,
      animated && frames.failed
        ? h('span', {class: 'error', text: `Failed frames: ${frames.failed_list}`})
        : null,
      health.last_problem ? h('span', {class: 'error', text: health.last_problem}) : null,
      job.error ? h('span', {class: 'error', text: `Error: ${job.error}`}) : null,
    );
  }
}
