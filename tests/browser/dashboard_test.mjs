// The web dashboard in a real browser (Debian's Chromium, driven by playwright-core) against
// a real tessera-server with one local worker:
//   1. a job submitted over the API ...
//   2. ... shows up in the jobs table;
//   3. its page fills in tile by tile (two screenshots of the canvas, apart, differ), and
//      its Tiles and Heatmap toggles show which is on;
//   4. a running job is canceled from its page, and the API says so, then retried from it;
//   5. a job named like markup is shown as text (no element made, no dialog);
//   6. no request leaves the coordinator's origin;
//   7. a coordinator with tokens: the page asks for the API token, shows nothing until it
//      has it and asks nothing that would be refused (no 401), keeps it in sessionStorage
//      only (never in a URL or a cookie);
//   8. an animation's page: its frame strip has a cell per frame, which turn done and show
//      thumbnails; a frame clicked is shown; the flipbook plays the frames; the tile counts
//      are of the frame shown. A still's page shows none of it.
// Screenshots go to OUT_DIR (dashboard-jobs.png, dashboard-job.png, dashboard-workers.png,
// dashboard-frames.png).
//
// Usage: node dashboard_test.mjs TESSERA_SERVER TESSERA_CLI OUT_DIR
// Exits 77 (skipped) where playwright-core (tests/tools, npm ci) or /usr/bin/chromium is
// missing.
import {spawn, execFile} from 'node:child_process';
import {createRequire} from 'node:module';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import {fileURLToPath} from 'node:url';
import {promisify} from 'node:util';

const CHROMIUM = '/usr/bin/chromium';
const here = path.dirname(fileURLToPath(import.meta.url));
const sourceDir = path.resolve(here, '..', '..');

const [serverBin, cliBin, outDir] = process.argv.slice(2);
if (!serverBin || !cliBin || !outDir) {
  console.error('usage: node dashboard_test.mjs TESSERA_SERVER TESSERA_CLI OUT_DIR');
  process.exit(2);
}

function skip(why) {
  console.log(`skipped: ${why}`);
  process.exit(77);
}

let chromium;
try {
  const require = createRequire(path.join(sourceDir, 'tests', 'tools', 'package.json'));
  ({chromium} = require('playwright-core'));
} catch (error) {
  skip(
    `playwright-core is not installed in tests/tools (deploy/install-deps.sh runs npm ci there): ${error.message.split('\n')[0]}`,
  );
}
if (typeof fetch !== 'function')
  skip(`node ${process.version} has no fetch(): it needs node 18 or later`);
if (!fs.existsSync(CHROMIUM))
  skip(`${CHROMIUM} is not installed (deploy/install-deps.sh installs the chromium package)`);

// --- helpers ---

const started = Date.now();
const elapsed = () => `${((Date.now() - started) / 1000).toFixed(1)} s`;
const log = (message) => console.log(`[${elapsed()}] ${message}`);
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

class Failure extends Error {}
function check(condition, message) {
  if (!condition) throw new Failure(message);
}

// Polls `probe` until it returns something truthy; fails saying `what` after `timeoutMs`.
async function until(what, probe, timeoutMs = 30000, everyMs = 100) {
  const end = Date.now() + timeoutMs;
  for (;;) {
    const value = await probe();
    if (value) return value;
    if (Date.now() > end)
      throw new Failure(`timed out after ${timeoutMs / 1000} s waiting for ${what}`);
    await sleep(everyMs);
  }
}

const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'tessera-dashboard-'));
fs.mkdirSync(outDir, {recursive: true});
const servers = [];

// A tessera-server on a free loopback port, with one single-threaded local worker.
async function startServer(name, extra = []) {
  const dir = path.join(tmp, name);
  fs.mkdirSync(dir);
  const portFile = path.join(dir, 'port');
  const logFile = path.join(dir, 'server.log');
  const out = fs.openSync(logFile, 'w');
  const child = spawn(
    serverBin,
    [
      '--listen',
      '127.0.0.1:0',
      '--port-file',
      portFile,
      '--data-dir',
      path.join(dir, 'data'),
      '--local-workers',
      '1',
      '--worker-threads',
      '1',
      ...extra,
    ],
    {stdio: ['ignore', out, out]},
  );
  fs.closeSync(out);
  let exited = null;
  child.on('exit', (code, signal) => {
    exited = signal ?? code;
  });
  const server = {name, child, logFile, stopped: false};
  servers.push(server);
  const port = await until(
    `${name}'s port file`,
    () => {
      if (exited !== null)
        throw new Failure(
          `tessera-server (${name}) exited (${exited}):\n${fs.readFileSync(logFile, 'utf8')}`,
        );
      try {
        const text = fs.readFileSync(portFile, 'utf8').trim();
        return /^\d+$/.test(text) ? Number(text) : null;
      } catch {
        return null;
      }
    },
    30000,
    50,
  );
  server.origin = `http://127.0.0.1:${port}`;
  log(`${name}: tessera-server at ${server.origin}`);
  return server;
}

async function stopServer(server) {
  if (server.stopped) return;
  server.stopped = true;
  if (server.child.exitCode !== null || server.child.signalCode !== null) return;
  const gone = new Promise((resolve) => server.child.once('exit', resolve));
  server.child.kill('SIGTERM');
  const timer = setTimeout(() => server.child.kill('SIGKILL'), 10000);
  await gone;
  clearTimeout(timer);
}

// The coordinator's API from here (not the page): JSON in, JSON out.
async function api(server, method, target, body, token) {
  const headers = {Accept: 'application/json'};
  if (body !== undefined || method === 'POST') headers['Content-Type'] = 'application/json';
  if (token) headers.Authorization = `Bearer ${token}`;
  const response = await fetch(server.origin + target, {
    method,
    headers,
    body: body === undefined ? undefined : JSON.stringify(body),
  });
  const text = await response.text();
  if (!response.ok) throw new Failure(`${method} ${target}: ${response.status} ${text}`);
  return text ? JSON.parse(text) : null;
}

// examples/showcase.json at `width` x `height`, `samples` per pixel, in 16-pixel tiles.
function showcase(width, height, samples) {
  const scene = JSON.parse(
    fs.readFileSync(path.join(sourceDir, 'examples', 'showcase.json'), 'utf8'),
  );
  scene.image = {width, height};
  scene.render.samples_per_pixel = samples;
  scene.render.tile_size = 16;
  return scene;
}

// examples/showcase.json as an animation of `frames` frames at `width` x `height` in 8-pixel
// tiles, its camera moving to the side, so that each frame differs.
function animation(width, height, frames, samples) {
  const scene = showcase(width, height, samples);
  scene.render.tile_size = 8;
  scene.animation = {frames: [1, frames], fps: 24};
  scene.camera.eye = {
    keys: [
      [1, [0, 0, 5]],
      [frames, [1, 0, 5]],
    ],
  };
  return scene;
}

async function submit(server, name, scene, {priority, token} = {}) {
  const body = {name, scene};
  if (priority !== undefined) body.priority = priority;
  return api(server, 'POST', '/v1/jobs', body, token);
}

const doneTiles = (page) =>
  page.evaluate(() => Number(document.querySelector('#tile-counts')?.dataset.done ?? -1));

// Polls `predicate(arg)` in the page (page.waitForFunction would evaluate a string there,
// which the page's Content-Security-Policy rightly refuses).
const pageUntil = (page, what, predicate, arg, timeoutMs = 30000) =>
  until(what, () => page.evaluate(predicate, arg), timeoutMs, 100);
const doneAtLeast = (page, count, timeoutMs) =>
  until(
    `${count} tiles done in the page`,
    async () => (await doneTiles(page)) >= count,
    timeoutMs,
    50,
  );

// --- the test ---

// 320x240 at 256 samples takes one thread about 8 s alone, 11 s beside the browser (on a
// 2-core machine); the tile steps need some seconds (at least 5) to see it render.
const SAMPLES = 256;
// 32x24 at 1024 samples: about a second a frame here, long enough to see the page follow it.
const ANIMATION_SAMPLES = 1024;
const XSS_NAME = '<img src=x onerror=alert(1)>';
const API_TOKEN = 'dashboard-api-token-0123456789abcdef';
const WORKER_TOKEN = 'dashboard-worker-token-fedcba9876543210';

const requests = []; // every URL the browser asked for
const dialogs = [];
const pageErrors = [];
let context = null;
let status = 0;

// Records the page's dialogs (dismissed) and its faults: an exception, or a console error
// such as a Content-Security-Policy refusal (an answer's 401 or 404 is not one).
function watch(page) {
  page.on('dialog', async (dialog) => {
    dialogs.push(`${dialog.type()}: ${dialog.message()}`);
    await dialog.dismiss().catch(() => {});
  });
  page.on('pageerror', (error) => pageErrors.push(`page error: ${error.message}`));
  page.on('console', (message) => {
    if (message.type() === 'error' && !/Failed to load resource/.test(message.text()))
      pageErrors.push(`console: ${message.text()}`);
  });
  return page;
}

async function main() {
  const open = await startServer('open');
  const origin = open.origin;

  context = await chromium.launchPersistentContext(path.join(tmp, 'profile'), {
    executablePath: CHROMIUM,
    headless: true,
    args: [
      '--headless',
      '--no-sandbox',
      '--disable-gpu',
      '--disable-quic',
      '--no-first-run',
      '--disable-background-networking',
      '--disable-component-update',
      '--disable-sync',
    ],
    viewport: {width: 1000, height: 700},
    acceptDownloads: true,
  });
  context.on('request', (request) => requests.push(request.url()));
  const page = watch(context.pages()[0] ?? (await context.newPage()));

  // 1. A job over the API.
  const job = await submit(open, 'showcase 320x240', showcase(320, 240, SAMPLES));
  log(`1. submitted ${job.id} over the API`);

  // 2. Its row in the jobs table.
  await page.goto(`${origin}/`);
  const row = page.locator(`#jobs tbody tr[data-job-id="${job.id}"]`);
  await row.waitFor({timeout: 15000});
  check(
    (await row.locator('.job-name').textContent()) === 'showcase 320x240',
    'the row names the job',
  );
  log("2. the job's row is in the jobs table");

  // 3. Its page fills in tile by tile.
  await row.locator('a.job-link').click();
  await page.waitForURL(`${origin}/jobs/${job.id}`);
  const canvas = page.locator('#image');
  await canvas.waitFor();
  await doneAtLeast(page, 1, 30000);
  check(await page.locator('#frames').isHidden(), "a still's page shows the frame strip");
  const first = await doneTiles(page);
  const firstShot = await canvas.screenshot();
  const status1 = await api(open, 'GET', `/v1/jobs/${job.id}`);
  check(
    status1.state !== 'completed',
    `the job rendered too fast to be watched (${status1.elapsed_s} s): raise SAMPLES`,
  );
  await doneAtLeast(page, Math.min(first + 40, 300), 60000);
  const second = await doneTiles(page);
  const secondShot = await canvas.screenshot();
  check(!firstShot.equals(secondShot), 'the canvas did not change while tiles were done');
  log(`3. the canvas filled in: ${first} then ${second} tiles done, and the screenshots differ`);
  // The page as the README shows it: half rendered, the tiles being rendered outlined.
  await doneAtLeast(page, 150, 60000);
  await page.screenshot({path: path.join(outDir, 'dashboard-job.png')});
  // The PNG download: fetched with the page's credentials, saved from a blob.
  const [download] = await Promise.all([
    page.waitForEvent('download'),
    page.click('#download-png'),
  ]);
  const saved = path.join(tmp, 'download.png');
  await download.saveAs(saved);
  check(
    fs
      .readFileSync(saved)
      .subarray(0, 8)
      .equals(Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a])),
    'the PNG download is a PNG',
  );
  log(`   the PNG download is a PNG (${download.suggestedFilename()})`);
  // The overlay's toggles show which is on: pressed, and coloured unlike the one that is off.
  const looks = () =>
    page.evaluate(() =>
      Object.fromEntries(
        ['#toggle-tiles', '#toggle-heat'].map((selector) => {
          const button = document.querySelector(selector);
          return [
            selector.slice(8),
            {
              pressed: button.getAttribute('aria-pressed'),
              background: getComputedStyle(button).backgroundColor,
            },
          ];
        }),
      ),
    );
  const before = await looks();
  check(
    before.tiles.pressed === 'true' && before.heat.pressed === 'false',
    `the toggles start ${JSON.stringify(before)}`,
  );
  check(
    before.tiles.background !== before.heat.background,
    'Tiles (on) and Heatmap (off) look alike',
  );
  await page.click('#toggle-heat');
  await page.click('#toggle-tiles');
  const after = await looks();
  check(
    after.tiles.pressed === 'false' && after.heat.pressed === 'true',
    `the toggles are ${JSON.stringify(after)} once clicked`,
  );
  check(
    after.heat.background === before.tiles.background &&
      after.tiles.background === before.heat.background,
    'a toggle clicked does not look as the other did',
  );
  check(await page.locator('.legend').isVisible(), 'the heatmap shows no legend');
  await page.click('#toggle-heat');
  await page.click('#toggle-tiles');
  log('   Tiles and Heatmap show which is on');
  const final = await until(
    'the first job to complete',
    async () => {
      const s = await api(open, 'GET', `/v1/jobs/${job.id}?wait_s=10`);
      return s.state === 'completed' ? s : null;
    },
    120000,
    0,
  );
  log(`   the job took ${final.elapsed_s} s to render`);
  await doneAtLeast(page, 300, 15000);

  // 4. Cancel a running job from its page.
  const big = await submit(open, 'to be canceled', showcase(640, 480, SAMPLES), {priority: 90});
  await page.goto(`${origin}/jobs/${big.id}`);
  await page.locator('.job-head .state.running').waitFor({timeout: 30000});
  // Two clicks, as for Delete: the first only asks.
  await page.locator('button[data-action="cancel"]').click();
  await page
    .locator('button[data-action="cancel"]', {hasText: 'Really cancel?'})
    .waitFor({timeout: 5000});
  const asked = await api(open, 'GET', `/v1/jobs/${big.id}`);
  check(asked.state !== 'canceled', 'one click on Cancel canceled the job');
  await page.locator('button[data-action="cancel"]').click();
  await page.locator('.job-head .state.canceled').waitFor({timeout: 15000});
  const canceled = await api(open, 'GET', `/v1/jobs/${big.id}`);
  check(canceled.state === 'canceled', `the API says ${canceled.state}, not canceled`);
  log('4. a running job was canceled from its page');
  // Canceled by mistake: Retry brings it back, under its id, with its tiles done.
  await page.locator('button[data-action="retry"]').click();
  await page
    .locator('.job-head .state.running, .job-head .state.queued')
    .first()
    .waitFor({timeout: 15000});
  const retried = await api(open, 'GET', `/v1/jobs/${big.id}`);
  check(
    retried.state === 'running' || retried.state === 'queued',
    `the API says ${retried.state} after Retry`,
  );
  check(
    retried.tiles.done >= canceled.tiles.done,
    `the retried job lost tiles: ${retried.tiles.done} of ${canceled.tiles.done}`,
  );
  await api(open, 'POST', `/v1/jobs/${big.id}/cancel`); // it would take the worker from what follows
  log(`   and retried from its page, keeping its ${canceled.tiles.done} tiles done`);

  // 5. A name made of markup is text.
  const cliEnv = {...process.env, TESSERA_SERVER: origin};
  delete cliEnv.TESSERA_API_TOKEN;
  const {stdout} = await promisify(execFile)(
    cliBin,
    ['submit', path.join(tmp, 'xss.json'), '--name', XSS_NAME],
    {
      env: cliEnv,
    },
  ).catch((error) => {
    throw new Failure(`tessera submit: ${error.message}`);
  });
  const xssId = /submitted (j-[0-9a-f]+)/.exec(stdout)?.[1];
  check(xssId, `tessera submit printed no id: ${stdout}`);
  await page.goto(`${origin}/`);
  const xssRow = page.locator(`#jobs tbody tr[data-job-id="${xssId}"]`);
  await xssRow.waitFor({timeout: 15000});
  check(
    (await xssRow.locator('.job-name').textContent()) === XSS_NAME,
    "the job's name is shown as it is",
  );
  check((await page.locator('#jobs img').count()) === 0, 'the jobs table holds an img element');
  await page.goto(`${origin}/jobs/${xssId}`);
  await pageUntil(
    page,
    "the job view's title",
    (name) => document.querySelector('.job-title')?.textContent === name,
    XSS_NAME,
    15000,
  );
  check((await page.locator('main img').count()) === 0, 'the job view holds an img element');
  await sleep(500); // an onerror would have fired by now
  check(dialogs.length === 0, `a dialog opened: ${dialogs.join('; ')}`);
  log('5. a name of markup is shown as text, and no dialog opened');

  // 8. An animation: its frame strip and its flipbook. It is paused as soon as it is
  // submitted, and resumed once its page is up, so that the page sees it render.
  const FRAMES = 4;
  const TILES_PER_FRAME = 12; // 32 x 24 in 8-pixel tiles
  const anim = await submit(open, 'animation', animation(32, 24, FRAMES, ANIMATION_SAMPLES));
  await api(open, 'POST', `/v1/jobs/${anim.id}/pause`);
  await page.goto(`${origin}/jobs/${anim.id}`);
  await page.locator('#frames').waitFor({state: 'visible', timeout: 15000});
  await pageUntil(
    page,
    `${FRAMES} cells in the frame strip`,
    (n) => document.querySelectorAll('#frame-strip .frame-cell').length === n,
    FRAMES,
    15000,
  );
  const cellFrames = await page
    .locator('#frame-strip .frame-cell')
    .evaluateAll((cells) => cells.map((cell) => cell.dataset.frame));
  check(
    cellFrames.join(',') === '1,2,3,4',
    `the strip's cells are of frames ${cellFrames.join(',')}, not 1 to 4`,
  );
  // While it renders, the page follows the frame being rendered and counts its tiles only.
  await api(open, 'POST', `/v1/jobs/${anim.id}/resume`);
  const followed = new Set();
  const wrongCounts = [];
  let sawRendering = false;
  await until(
    `the ${FRAMES} frames done in the strip`,
    async () => {
      const seen = await page.evaluate(() => ({
        shown: document.querySelector('#frame-shown')?.dataset.frame,
        counted: document.querySelector('#tile-counts')?.dataset.frame,
        total: document.querySelector('#tile-counts')?.dataset.total,
        rendering: document.querySelectorAll('#frame-strip .frame-cell.rendering').length,
        done: document.querySelectorAll('#frame-strip .frame-cell.done').length,
      }));
      if (seen.done < FRAMES) followed.add(seen.shown);
      if (
        seen.total !== undefined &&
        (seen.total !== String(TILES_PER_FRAME) || seen.counted !== seen.shown)
      )
        wrongCounts.push(`${seen.total} tiles of frame ${seen.counted}, frame ${seen.shown} shown`);
      sawRendering ||= seen.rendering > 0;
      return seen.done === FRAMES;
    },
    90000,
    20,
  );
  check(
    wrongCounts.length === 0,
    `the tile counts were not those of the frame shown: ${wrongCounts.slice(0, 3).join('; ')}`,
  );
  check(
    followed.size >= 2,
    `the page did not follow the render from frame to frame (it showed ${[...followed].join(', ')})`,
  );
  log(
    `8. an animation's page followed its render through frames ${[...followed].sort().join(', ')}${sawRendering ? ', a cell rendering in the strip' : ''}`,
  );
  await pageUntil(
    page,
    'a thumbnail to load',
    () =>
      [...document.querySelectorAll('#frame-strip .frame-cell img')].some(
        (img) => img.complete && img.naturalWidth > 0,
      ),
    null,
    15000,
  );
  const animStatus = await api(open, 'GET', `/v1/jobs/${anim.id}`);
  check(
    animStatus.frames?.total === FRAMES && animStatus.tiles.total === FRAMES * TILES_PER_FRAME,
    `the job has ${animStatus.frames?.total} frames and ${animStatus.tiles.total} tiles`,
  );
  log(`   its strip shows its ${FRAMES} frames, done, with thumbnails`);
  // A frame clicked is shown, its own tiles only; the camera moved, so frames 1 and 4 differ.
  const showsFrame = (frame) =>
    pageUntil(
      page,
      `frame ${frame} on the canvas`,
      (f) =>
        document.querySelector('#image')?.dataset.frame === f &&
        document.querySelector('#frame-shown')?.dataset.frame === f,
      String(frame),
      15000,
    );
  await page.click('#frame-strip .frame-cell[data-frame="1"]');
  await showsFrame(1);
  await pageUntil(
    page,
    'the tile counts of frame 1',
    (n) =>
      document.querySelector('#tile-counts')?.dataset.frame === '1' &&
      document.querySelector('#tile-counts')?.dataset.total === n,
    String(TILES_PER_FRAME),
    15000,
  );
  const frame1Shot = await canvas.screenshot();
  await page.click('#frame-strip .frame-cell[data-frame="4"]');
  await showsFrame(4);
  const frame4Shot = await canvas.screenshot();
  check(!frame1Shot.equals(frame4Shot), 'frames 1 and 4 look the same on the canvas');
  check(
    (await page.locator('#tile-counts').getAttribute('data-total')) === String(TILES_PER_FRAME),
    'the tile counts are not of one frame',
  );
  log('   a frame clicked in the strip is shown, with its own tiles only');
  // The flipbook plays every frame in turn, and stops where it is paused.
  await page.fill('#flip-fps', '12');
  await page.click('#flip-play');
  const shownFrames = new Set();
  await until(
    'the flipbook to show every frame',
    async () => {
      shownFrames.add(
        await page.evaluate(() => document.querySelector('#frame-shown')?.dataset.frame),
      );
      return shownFrames.size >= FRAMES;
    },
    15000,
    10,
  );
  await page.screenshot({path: path.join(outDir, 'dashboard-frames.png')});
  await page.click('#flip-play');
  check(
    (await page.locator('#flip-play').getAttribute('aria-pressed')) === 'false',
    'the flipbook does not say it is paused',
  );
  const pausedAt = await page.locator('#frame-shown').getAttribute('data-frame');
  await sleep(400);
  check(
    (await page.locator('#frame-shown').getAttribute('data-frame')) === pausedAt,
    'the flipbook went on after its pause',
  );
  log(
    `   the flipbook played frames ${[...shownFrames].sort().join(', ')} and paused on ${pausedAt}`,
  );

  // The jobs and the workers, for the record.
  await page.goto(`${origin}/`);
  await page
    .locator(`#jobs tbody tr[data-job-id="${big.id}"] .state.canceled`)
    .waitFor({timeout: 15000});
  await page.screenshot({path: path.join(outDir, 'dashboard-jobs.png')});
  await page.click('nav a[data-view="workers"]');
  await page.waitForURL(`${origin}/workers`);
  await page.locator('#workers tbody tr[data-worker-id]').first().waitFor({timeout: 15000});
  check(
    (
      await page.locator('#workers tbody tr[data-worker-id] td.name').first().textContent()
    ).includes('local-1'),
    'the local worker is listed',
  );
  await page.screenshot({path: path.join(outDir, 'dashboard-workers.png')});
  log('   the workers view lists the local worker');

  await stopServer(open);

  // 7. A coordinator with tokens.
  const locked = await startServer('tokens', [
    '--api-token',
    API_TOKEN,
    '--worker-token',
    WORKER_TOKEN,
  ]);
  const secretJob = await submit(locked, 'behind a token', showcase(64, 48, 1), {token: API_TOKEN});
  const tokenPage = watch(await context.newPage());
  // Until a token is given, nothing is asked that would be refused: no 401 in the console.
  let tokenGiven = false;
  const refusedEarly = [];
  tokenPage.on('response', (response) => {
    if (!tokenGiven && response.status() === 401) refusedEarly.push(response.url());
  });
  await page.close();
  await tokenPage.goto(`${locked.origin}/`);
  await tokenPage.locator('#token-form').waitFor({state: 'visible', timeout: 15000});
  await pageUntil(
    tokenPage,
    'the jobs table to ask for the token',
    () => /API token/.test(document.querySelector('#jobs .empty-row')?.textContent ?? ''),
    null,
    15000,
  );
  check(
    (await tokenPage.locator('#jobs tbody tr[data-job-id]').count()) === 0,
    'jobs are shown without the token',
  );
  // A wrong token is refused, saying so.
  check(
    refusedEarly.length === 0,
    `asked without the token, and refused: ${refusedEarly.join(', ')}`,
  );
  tokenGiven = true;
  await tokenPage.fill('#token-input', 'not-the-token');
  await tokenPage.press('#token-input', 'Enter');
  await tokenPage.locator('#auth-error').waitFor({state: 'visible', timeout: 15000});
  check(
    (await tokenPage.locator('#jobs tbody tr[data-job-id]').count()) === 0,
    'jobs are shown with a wrong token',
  );
  await tokenPage.fill('#token-input', API_TOKEN);
  await tokenPage.click('#token-form button[type="submit"]');
  await tokenPage
    .locator(`#jobs tbody tr[data-job-id="${secretJob.id}"]`)
    .waitFor({timeout: 15000});
  check(
    await tokenPage.locator('#token-form').isHidden(),
    'the token form stays up once the token is given',
  );
  const stored = await tokenPage.evaluate(() => ({
    session: sessionStorage.getItem('tessera.token'),
    local: localStorage.length,
    cookie: document.cookie,
  }));
  check(stored.session === API_TOKEN, 'sessionStorage does not hold the token');
  check(stored.local === 0, 'localStorage holds something');
  check(stored.cookie === '', `document.cookie is ${JSON.stringify(stored.cookie)}`);
  check((await context.cookies()).length === 0, 'the browser holds cookies');
  // "Forget token" forgets it, and asks nothing more without it.
  tokenGiven = false;
  await tokenPage.click('#forget-token');
  await tokenPage.locator('#token-form').waitFor({state: 'visible', timeout: 15000});
  check(
    (await tokenPage.evaluate(() => sessionStorage.getItem('tessera.token'))) === null,
    'the token is still stored after "Forget token"',
  );
  await pageUntil(
    tokenPage,
    'the jobs table to ask for the token again',
    () => /API token/.test(document.querySelector('#jobs .empty-row')?.textContent ?? ''),
    null,
    15000,
  );
  check(
    refusedEarly.length === 0,
    `asked without the token once forgotten, and refused: ${refusedEarly.join(', ')}`,
  );
  log(
    '7. with tokens: the page asks for the API token, shows the jobs once given, keeps it in sessionStorage only',
  );

  // 6. Every request stayed at the coordinators' origins, and no URL carried a token.
  const origins = [origin, locked.origin];
  const outside = requests.filter(
    (url) => !origins.some((o) => url.startsWith(`${o}/`) || url.startsWith(`blob:${o}/`)),
  );
  check(outside.length === 0, `requests left the coordinator's origin: ${outside.join(', ')}`);
  const leaked = requests.filter((url) => url.includes(API_TOKEN) || url.includes(WORKER_TOKEN));
  check(leaked.length === 0, `a request URL holds a token: ${leaked.join(', ')}`);
  log(
    `6. all ${requests.length} requests stayed at the coordinator's origin; none carried a token`,
  );

  check(dialogs.length === 0, `a dialog opened: ${dialogs.join('; ')}`);
  check(pageErrors.length === 0, `the page reported errors:\n  ${pageErrors.join('\n  ')}`);
  await stopServer(locked);
}

fs.writeFileSync(path.join(tmp, 'xss.json'), JSON.stringify(showcase(32, 32, 1)));
const cleanUp = async () => {
  await context?.close().catch(() => {});
  await Promise.all(servers.map((server) => stopServer(server).catch(() => {})));
  fs.rmSync(tmp, {recursive: true, force: true});
};
for (const signal of ['SIGINT', 'SIGTERM']) {
  process.once(signal, async () => {
    await cleanUp();
    process.exit(1);
  });
}
try {
  await main();
  log('PASS');
} catch (error) {
  status = 1;
  console.error(`FAIL: ${error instanceof Failure ? error.message : error.stack}`);
  for (const server of servers) {
    try {
      const lines = fs.readFileSync(server.logFile, 'utf8').trimEnd().split('\n');
      console.error(`--- ${server.name}'s log, last lines:\n${lines.slice(-30).join('\n')}`);
    } catch {
      /* no log */
    }
  }
} finally {
  await cleanUp();
}
process.exit(status);
