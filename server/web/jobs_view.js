// The jobs view: /

import {api, jobPage} from './api.js';
import {PAGE_SIZE} from './constants.js';
import {JOB_STATES} from './contract.js';
import {append, fill, h, setText} from './dom.js';
import {liveStream} from './events.js';
import {formatAgo, formatCount, formatEta, formatRate, shortId} from './format.js';
import {jobButtons, priorityInput, stateBadge, syncPriority} from './job_actions.js';

export function jobsView(main) {
  const query = new URLSearchParams(location.search);
  let filter = JOB_STATES.includes(query.get('state')) ? query.get('state') : '';
  let offset = Math.max(0, Number.parseInt(query.get('offset'), 10) || 0);
  let lastCount = 0;
  let loadSerial = 0;
  const rows = new Map(); // job id -> row
  const view = {gone: false};

  const select = h(
    'select',
    {id: 'state-filter', 'aria-label': 'State'},
    h('option', {value: '', text: 'all'}),
    JOB_STATES.map((state) => h('option', {value: state, text: state})),
  );
  select.value = filter;
  const previous = h('button', {type: 'button', text: '‹ Newer', id: 'page-prev'});
  const next = h('button', {type: 'button', text: 'Older ›', id: 'page-next'});
  const pageLabel = h('span', {class: 'page-label'});
  const tbody = h('tbody');
  const emptyRow = h(
    'tr',
    {class: 'empty-row'},
    h('td', {class: 'empty', colSpan: 9, text: 'Loading…'}),
  );
  tbody.append(emptyRow);

  append(main, [
    h(
      'div',
      {class: 'toolbar'},
      h('h1', {text: 'Jobs'}),
      h('label', {}, 'State', select),
      h('span', {class: 'spacer'}),
      h('div', {class: 'pager'}, previous, pageLabel, next),
    ),
    h(
      'table',
      {class: 'grid jobs', id: 'jobs'},
      h(
        'thead',
        {},
        h(
          'tr',
          {},
          h('th', {text: 'Name'}),
          h('th', {text: 'State'}),
          h('th', {text: 'Progress'}),
          h('th', {class: 'num', text: 'Tiles'}),
          h('th', {class: 'num', text: 'ETA'}),
          h('th', {text: 'Priority'}),
          h('th', {text: 'Submitted'}),
          h('th', {class: 'num', text: 'Rays/s'}),
          h('th', {text: 'Actions'}),
        ),
      ),
      tbody,
    ),
  ]);
  document.title = 'Jobs · Tessera';

  const keepAddress = () => {
    const params = new URLSearchParams();
    if (filter) params.set('state', filter);
    if (offset) params.set('offset', offset);
    const search = params.toString();
    history.replaceState(null, '', search ? `/?${search}` : '/');
  };

  const showEmpty = (text) => {
    setText(emptyRow.firstChild, text);
    if (!emptyRow.isConnected) tbody.append(emptyRow);
  };
  const emptyText = () => {
    if (offset) return 'No more jobs.';
    return filter
      ? `No ${filter} jobs.`
      : 'No jobs yet. Submit one with: tessera submit SCENE.json';
  };

  const updatePager = () => {
    previous.disabled = offset === 0;
    next.disabled = lastCount < PAGE_SIZE;
    setText(pageLabel, lastCount ? `${offset + 1}–${offset + lastCount}` : '');
  };

  const makeRow = (job) => {
    const row = {job, state: null};
    row.link = h('a', {href: jobPage(job.id), 'data-nav': true, class: 'job-link'});
    row.name = h('span', {class: 'job-name'});
    row.link.append(row.name);
    row.stateCell = h('td', {class: 'state-cell'});
    row.bar = h('progress', {max: 1, value: 0});
    row.percent = h('span', {class: 'sub'});
    row.tiles = h('td', {class: 'num tiles'});
    row.eta = h('td', {class: 'num eta'});
    row.priority = priorityInput(() => row.job, applied);
    row.submitted = h('td', {class: 'submitted'});
    row.rays = h('td', {class: 'num rays'});
    row.actions = h('td', {class: 'actions'});
    row.tr = h(
      'tr',
      {dataset: {jobId: job.id}},
      h('td', {class: 'name'}, row.link, h('span', {class: 'sub mono', text: shortId(job.id)})),
      row.stateCell,
      h('td', {class: 'progress'}, row.bar, row.percent),
      row.tiles,
      row.eta,
      h('td', {}, row.priority),
      row.submitted,
      row.rays,
      row.actions,
    );
    updateRow(row, job);
    return row;
  };

  const updateRow = (row, job) => {
    row.job = job;
    setText(row.name, job.name || job.id);
    row.link.title = job.name || job.id;
    if (row.state !== job.state) {
      fill(row.stateCell, stateBadge(job.state));
      fill(
        row.actions,
        h('div', {class: 'buttons'}, jobButtons(job, {applied, deleted: () => removeRow(job.id)})),
      );
      row.state = job.state;
    }
    row.bar.value = job.progress ?? 0;
    setText(row.percent, `${Math.floor((job.progress ?? 0) * 100)}%`);
    setText(row.tiles, `${formatCount(job.tiles?.done)} / ${formatCount(job.tiles?.total)}`);
    setText(row.eta, formatEta(job));
    syncPriority(row.priority, job);
    setText(row.submitted, formatAgo(job.created_at));
    row.submitted.title = job.created_at ?? '';
    setText(row.rays, formatRate(job.stats?.rays_per_s));
  };

  const removeRow = (id) => {
    const row = rows.get(id);
    if (!row) return;
    row.tr.remove();
    rows.delete(id);
    if (rows.size === 0) showEmpty(emptyText());
  };

  // Newest first: by created_at, then by id.
  const newer = (a, b) =>
    a.created_at === b.created_at ? a.id > b.id : a.created_at > b.created_at;

  // A job's status from an action or an event: its row is updated, added or dropped.
  function applied(job) {
    if (!job || !job.id) return;
    const row = rows.get(job.id);
    const belongs = !filter || job.state === filter;
    if (row) {
      if (belongs) updateRow(row, job);
      else removeRow(job.id);
      return;
    }
    if (!belongs || offset !== 0) return;
    // A job this page has not shown: in its place by age, if that is on this page.
    let before = null;
    for (const tr of tbody.children) {
      const other = rows.get(tr.dataset.jobId);
      if (other && newer(job, other.job)) {
        before = tr;
        break;
      }
    }
    if (!before && rows.size >= PAGE_SIZE) return;
    const fresh = makeRow(job);
    rows.set(job.id, fresh);
    emptyRow.remove();
    tbody.insertBefore(fresh.tr, before);
    if (rows.size > PAGE_SIZE) {
      const last = tbody.lastElementChild;
      if (last?.dataset.jobId) removeRow(last.dataset.jobId);
    }
  }

  const render = (jobs) => {
    const seen = new Set();
    let previousRow = null;
    for (const job of jobs) {
      let row = rows.get(job.id);
      if (row) updateRow(row, job);
      else {
        row = makeRow(job);
        rows.set(job.id, row);
      }
      seen.add(job.id);
      const wanted = previousRow ? previousRow.nextSibling : tbody.firstChild;
      if (wanted !== row.tr) tbody.insertBefore(row.tr, wanted);
      previousRow = row.tr;
    }
    for (const id of [...rows.keys()]) if (!seen.has(id)) removeRow(id);
    if (jobs.length) emptyRow.remove();
    else showEmpty(emptyText());
  };

  const load = async () => {
    const serial = ++loadSerial;
    const params = new URLSearchParams({limit: PAGE_SIZE});
    if (filter) params.set('state', filter);
    if (offset) params.set('offset', offset);
    try {
      const {jobs} = await api('GET', `/v1/jobs?${params}`);
      if (serial !== loadSerial || view.gone) return;
      lastCount = jobs.length;
      render(jobs);
      updatePager();
    } catch (error) {
      if (serial !== loadSerial || view.gone) return;
      if (error.status === 401 || error.code === 'wrong_role') {
        for (const id of [...rows.keys()]) removeRow(id);
        showEmpty('The jobs are shown once the API token is given above.');
      } else {
        showEmpty(`The jobs could not be listed: ${error.message}`);
      }
    }
  };

  select.addEventListener('change', () => {
    filter = select.value;
    offset = 0;
    keepAddress();
    load();
  });
  previous.addEventListener('click', () => {
    offset = Math.max(0, offset - PAGE_SIZE);
    keepAddress();
    load();
  });
  next.addEventListener('click', () => {
    offset += PAGE_SIZE;
    keepAddress();
    load();
  });
  updatePager();

  const stream = liveStream(
    '/v1/events',
    (type, data) => {
      if (type === 'job') applied(data);
      else if (type === 'job_removed') removeRow(data.id);
      else if (type === 'resync') load();
    },
    {poll: load},
  );
  load();
  return ageingView(view, stream, () => {
    for (const row of rows.values()) setText(row.submitted, formatAgo(row.job.created_at));
  });
}

// A live table's view: its relative times ("3 min ago") redrawn every 5 s by `age`, and,
// when the view goes, its stream stopped and its clock with it.
export function ageingView(view, stream, age) {
  const clock = setInterval(age, 5000);
  return {
    unmount() {
      view.gone = true;
      stream.stop();
      clearInterval(clock);
    },
  };
}
