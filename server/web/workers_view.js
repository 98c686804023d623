// The workers view: /workers

import {api, jobPage, workerPath} from './api.js';
import {append, fill, h, setText} from './dom.js';
import {liveStream} from './events.js';
import {formatAgo, formatRate, shortId} from './format.js';
import {act, stateBadge} from './job_actions.js';
import {ageingView} from './jobs_view.js';

export function workersView(main) {
  const rows = new Map(); // worker id -> row
  const tbody = h('tbody');
  const emptyRow = h(
    'tr',
    {class: 'empty-row'},
    h('td', {class: 'empty', colSpan: 10, text: 'Loading…'}),
  );
  tbody.append(emptyRow);
  const view = {gone: false};
  let loadSerial = 0;

  append(main, [
    h('div', {class: 'toolbar'}, h('h1', {text: 'Workers'})),
    h(
      'table',
      {class: 'grid workers', id: 'workers'},
      h(
        'thead',
        {},
        h(
          'tr',
          {},
          h('th', {text: 'Name'}),
          h('th', {text: 'Host'}),
          h('th', {text: 'State'}),
          h('th', {text: 'Job'}),
          h('th', {class: 'num', text: 'Tile'}),
          h('th', {class: 'num', text: 'Threads'}),
          h('th', {class: 'num', text: 'Tiles/min'}),
          h('th', {class: 'num', text: 'Rays/s'}),
          h('th', {text: 'Last seen'}),
          h('th', {text: 'Actions'}),
        ),
      ),
      tbody,
    ),
  ]);
  document.title = 'Workers · Tessera';

  const showEmpty = (text) => {
    setText(emptyRow.firstChild, text);
    if (!emptyRow.isConnected) tbody.append(emptyRow);
  };

  const makeRow = (worker) => {
    const row = {worker, key: null};
    row.name = h('td', {class: 'name'});
    row.host = h('td', {class: 'host'});
    row.state = h('td', {class: 'state-cell'});
    row.job = h('td', {class: 'job'});
    row.tile = h('td', {class: 'num'});
    row.threads = h('td', {class: 'num'});
    row.tilesPerMin = h('td', {class: 'num'});
    row.rays = h('td', {class: 'num'});
    row.seen = h('td', {class: 'seen'});
    row.actions = h('td', {class: 'actions'});
    row.tr = h(
      'tr',
      {dataset: {workerId: worker.id}},
      row.name,
      row.host,
      row.state,
      row.job,
      row.tile,
      row.threads,
      row.tilesPerMin,
      row.rays,
      row.seen,
      row.actions,
    );
    updateRow(row, worker);
    return row;
  };

  const button = (label, verb, worker, cls) => {
    const b = h('button', {
      type: 'button',
      text: label,
      class: cls,
      dataset: {action: verb},
      onclick: () =>
        act(b, `${label} ${worker.name}`, async () => {
          const answer = await api('POST', workerPath(worker.id, `/${verb}`));
          if (verb === 'remove') removeRow(worker.id);
          else if (answer && answer.id) upsert(answer);
        }),
    });
    return b;
  };

  const updateRow = (row, worker) => {
    row.worker = worker;
    fill(row.name, h('span', {text: worker.name}), h('span', {class: 'sub mono', text: worker.id}));
    setText(row.host, worker.host ?? '');
    const key = `${worker.state}/${worker.draining}/${worker.current_job}`;
    if (row.key !== key) {
      fill(
        row.state,
        stateBadge(worker.state),
        worker.draining ? [' ', stateBadge('draining')] : [],
      );
      fill(
        row.job,
        worker.current_job
          ? h('a', {
              href: jobPage(worker.current_job),
              'data-nav': true,
              class: 'mono',
              text: shortId(worker.current_job),
              title: worker.current_job,
            })
          : '—',
      );
      const gone = worker.state === 'gone' || worker.state === 'left';
      fill(
        row.actions,
        h(
          'div',
          {class: 'buttons'},
          gone
            ? null
            : worker.draining
              ? button('Undrain', 'undrain', worker)
              : button('Drain', 'drain', worker),
          button('Remove', 'remove', worker, 'danger'),
        ),
      );
      row.key = key;
    }
    setText(row.tile, worker.current_tile ?? '—');
    setText(row.threads, worker.threads ?? '—');
    setText(
      row.tilesPerMin,
      Number.isFinite(worker.tiles_per_min)
        ? (Math.round(worker.tiles_per_min * 10) / 10).toLocaleString('en-US')
        : '—',
    );
    setText(row.rays, Number.isFinite(worker.rays_per_s) ? formatRate(worker.rays_per_s) : '—');
    setText(row.seen, formatAgo(worker.last_seen));
    row.seen.title = worker.last_seen ?? '';
  };

  const removeRow = (id) => {
    const row = rows.get(id);
    if (row) row.tr.remove();
    rows.delete(id);
    if (rows.size === 0) showEmpty('No workers. Start one with: tessera-worker --server URL');
  };

  function upsert(worker) {
    if (!worker || !worker.id) return;
    const row = rows.get(worker.id);
    if (row) return updateRow(row, worker);
    const fresh = makeRow(worker);
    rows.set(worker.id, fresh);
    emptyRow.remove();
    tbody.append(fresh.tr);
    return undefined;
  }

  const load = async () => {
    const serial = ++loadSerial;
    try {
      const {workers} = await api('GET', '/v1/workers');
      if (view.gone || serial !== loadSerial) return;
      const seen = new Set(workers.map((w) => w.id));
      for (const id of [...rows.keys()]) if (!seen.has(id)) removeRow(id);
      let previous = null;
      for (const worker of workers) {
        upsert(worker);
        const tr = rows.get(worker.id).tr;
        const wanted = previous ? previous.nextSibling : tbody.firstChild;
        if (wanted !== tr) tbody.insertBefore(tr, wanted);
        previous = tr;
      }
      if (workers.length === 0)
        showEmpty('No workers. Start one with: tessera-worker --server URL');
    } catch (error) {
      if (view.gone || serial !== loadSerial) return;
      if (error.status === 401 || error.code === 'wrong_role') {
        for (const id of [...rows.keys()]) removeRow(id);
        showEmpty('The workers are shown once the API token is given above.');
      } else {
        showEmpty(`The workers could not be listed: ${error.message}`);
      }
    }
  };

  const stream = liveStream(
    '/v1/events',
    (type, data) => {
      if (type === 'worker') {
        if (data.change === 'removed') removeRow(data.worker?.id);
        else upsert(data.worker);
      } else if (type === 'resync') {
        load();
      }
    },
    {poll: load},
  );
  load();
  return ageingView(view, stream, () => {
    for (const row of rows.values()) setText(row.seen, formatAgo(row.worker.last_seen));
  });
}
