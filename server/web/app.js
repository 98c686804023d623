// The Tessera dashboard: the jobs, one job's image as it renders, and the workers, live.
//
// Everything comes from the coordinator's API (docs/api.md), with the API token the user
// types in when a call answers 401. The token lives in this tab's sessionStorage under
// `tessera.token` and travels only as `Authorization: Bearer`: never in a URL, a cookie or
// a link. Live updates are server-sent events read from fetch() (EventSource cannot send
// that header). Text from the coordinator (names, hosts, errors) goes into the page as text
// nodes only, never as markup.
//
// This module is the router: the view for each address, and the page's start. The views and
// their parts are modules of their own beside it.

import {learnAccess, token} from './api.js';
import {$, append, h} from './dom.js';
import {jobView} from './job_view.js';
import {jobsView} from './jobs_view.js';
import {navigate, setRouter} from './navigation.js';
import {auth, showForgetButton} from './page.js';
import {workersView} from './workers_view.js';

function notFoundView(main) {
  append(
    main,
    h(
      'div',
      {class: 'empty'},
      'The dashboard has no page here. ',
      h('a', {href: '/', 'data-nav': true, text: 'The jobs'}),
    ),
  );
  document.title = 'Tessera';
  return {unmount() {}};
}

export let current = null;

export function route() {
  current?.unmount();
  current = null;
  const main = $('#main');
  main.replaceChildren();
  $('#flash').hidden = true;
  const path = location.pathname;
  let view = '';
  let match;
  if (path === '/') {
    view = 'jobs';
    current = jobsView(main);
  } else if ((match = /^\/jobs\/([^/]+)$/.exec(path))) {
    let id = null;
    try {
      id = decodeURIComponent(match[1]);
    } catch {
      /* not an id */
    }
    view = 'jobs';
    current = id ? jobView(main, id) : notFoundView(main);
  } else if (path === '/workers') {
    view = 'workers';
    current = workersView(main);
  } else {
    current = notFoundView(main);
  }
  for (const link of document.querySelectorAll('nav a[data-view]')) {
    if (link.dataset.view === view) link.setAttribute('aria-current', 'page');
    else link.removeAttribute('aria-current');
  }
}

document.addEventListener('click', (event) => {
  const link = event.target.closest?.('a[data-nav]');
  if (!link || event.defaultPrevented || event.button !== 0) return;
  if (event.metaKey || event.ctrlKey || event.shiftKey || event.altKey) return;
  const url = new URL(link.href, location.href);
  if (url.origin !== location.origin) return;
  event.preventDefault();
  if (url.pathname + url.search !== location.pathname + location.search)
    navigate(url.pathname + url.search);
});
setRouter(route);
window.addEventListener('popstate', route);

$('#token-form').addEventListener('submit', (event) => {
  event.preventDefault();
  const input = $('#token-input');
  const value = input.value.trim();
  if (!value) return;
  token.set(value);
  input.value = '';
  auth.hide();
  showForgetButton();
  route();
});

$('#forget-token').addEventListener('click', () => {
  token.forget();
  showForgetButton();
  auth.hide();
  route();
});

showForgetButton();
learnAccess().then(route);
