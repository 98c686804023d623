// The job view: /jobs/{id}: the job's image as it renders, its tiles and frames, live.
//
// The view holds what the API says of the job (its status, its tiles, which frame is shown)
// and keeps its parts, each a module that owns its own state, up to date: the head
// (job_header.js), the image (image_canvas.js), what is drawn over it (tile_overlay.js),
// the frames' strip (frame_strip.js) and the flipbook (flipbook.js).

import {api, checked, fetchWithToken, jobPath} from './api.js';
import {workerColour} from './colours.js';
import {FRAMES_REFRESH_MAX_MS, FRAMES_REFRESH_MS} from './constants.js';
import {FINISHED} from './contract.js';
import {append, fill, h, setText} from './dom.js';
import {liveStream} from './events.js';
import {Flipbook} from './flipbook.js';
import {fileName, formatCount} from './format.js';
import {FrameImages} from './frame_images.js';
import {parseFrameList} from './frame_list.js';
import {FrameStrip} from './frame_strip.js';
import {ImageCanvas} from './image_canvas.js';
import {act} from './job_actions.js';
import {JobHeader} from './job_header.js';
import {navigate} from './navigation.js';
import {reportError} from './page.js';
import {TileOverlay} from './tile_overlay.js';

export function jobView(main, id) {
  let job = null;
  // By index, over every frame: {index, frame, x, y, width, height, state, worker,
  // worker_name, render_ms}.
  let tiles = [];
  let tilesKnown = false;
  // Until the tile list is read, tile events wait here; until the image is drawn, pixels do.
  let tilesLoading = true;
  let imageLoading = true;
  let tileQueue = [];
  let pixelQueue = [];
  let refreshTimer = 0;
  let loadSerial = 0;
  let imageSerial = 0;
  const view = {gone: false};
  // An animation (more than one frame) is shown one frame at a time, `shownFrame`: the one
  // being rendered while following, else the one picked in the strip or the flipbook's.
  // Its frames share the image's place, so the tiles of the others are neither painted nor
  // outlined. A still is the one frame 0, and none of this shows.
  let animated = false;
  let shownFrame = 0;
  let shownTiles = null; // the tiles of shownFrame; null when they must be picked out again
  let framesKey = null;
  let framesTimer = 0;
  let framesAt = 0;
  let framesBusy = false;
  let framesAgain = false;

  // --- the parts ---
  const header = new JobHeader(id, {
    applied: (changed) => applyJob(changed),
    deleted: () => navigate('/'),
  });
  const canvas = new ImageCanvas({onPlaced: () => overlay.drawSoon()});
  const overlay = new TileOverlay(canvas, {tiles: () => tilesShown(), animated: () => animated});
  const frameImages = new FrameImages(id, (entry) => {
    if (!view.gone) strip.imageReady(entry);
  });
  const strip = new FrameStrip({
    images: frameImages,
    onPick: (frame) => flipbook.pick(frame),
    playing: () => flipbook.playing,
  });
  const flipbook = new Flipbook({
    strip,
    images: frameImages,
    shown: () => shownFrame,
    show: (frame) => showFrame(frame),
    follow: () => follow(),
    changed: () => {
      if (job) showFrameCounts();
    },
  });
  const download = (button, format) =>
    act(button, `The ${format.toUpperCase()} image`, () => save(format));
  const pngButton = h('button', {
    type: 'button',
    text: 'PNG',
    id: 'download-png',
    title: 'Download the image (what is rendered so far)',
    onclick: () => download(pngButton, 'png'),
  });
  const exrButton = h('button', {
    type: 'button',
    text: 'EXR',
    id: 'download-exr',
    title: 'Download the linear float image (what is rendered so far)',
    onclick: () => download(exrButton, 'exr'),
  });
  const counts = h('div', {class: 'tile-counts', id: 'tile-counts', dataset: {done: '0'}});
  const framesPanel = h(
    'section',
    {class: 'frames', id: 'frames', hidden: true, 'aria-label': 'Frames'},
    h(
      'div',
      {class: 'job-tools frames-bar'},
      h(
        'span',
        {class: 'group'},
        flipbook.playButton,
        h('label', {class: 'fps-label'}, flipbook.fpsInput, 'fps'),
      ),
      h('span', {class: 'group'}, flipbook.followButton, strip.shownLabel),
      h('span', {class: 'group'}, strip.counts),
    ),
    strip.element,
  );
  append(main, [
    header.head,
    header.status,
    h(
      'div',
      {class: 'job-tools'},
      canvas.controls,
      overlay.toggles,
      h('span', {class: 'group'}, 'Download', pngButton, exrButton),
      header.actions,
      header.priorityGroup,
    ),
    framesPanel,
    canvas.viewer,
    overlay.legend,
    counts,
  ]);

  // --- status ---
  function applyJob(next) {
    if (!next || next.id !== id) return;
    const was = job;
    job = next;
    const frames = job.frames;
    if (!animated && frames && frames.total > 1) startFrames(frames);
    header.show(job, was, animated);
    canvas.resize(job.width, job.height);
    if (animated) {
      showFrameCounts();
      // The job's counts move with every tile; the frame list is asked for again only when
      // a frame is done, failed or begun, since it grows with the frames.
      const key = `${frames.done}/${frames.failed}/${frames.current}/${job.state}`;
      if (framesKey !== null && key !== framesKey) loadFramesSoon();
      framesKey = key;
      if (flipbook.following) follow();
    }
    if (!tilesKnown) showCounts();
    // The final image once the job ends: every tile, whatever events were missed.
    if (was && !FINISHED.has(was.state) && FINISHED.has(job.state)) {
      if (!flipbook.playing) loadImage();
      if (tilesKnown) loadTiles();
    }
  }

  // --- frames ---
  const aspect = () => `${Math.max(1, job.width)} / ${Math.max(1, job.height)}`;

  function startFrames(frames) {
    animated = true;
    framesPanel.hidden = false;
    pngButton.title = 'Download the frame shown (what is rendered of it so far)';
    exrButton.title = 'Download the frame shown as linear floats (what is rendered of it so far)';
    const order = parseFrameList(frames.list);
    if (order) strip.build(order, aspect());
    shownFrame = frames.current ?? order?.[0] ?? 0;
    shownTiles = null;
    strip.mark(shownFrame);
  }

  function showFrameCounts() {
    strip.showCounts(job.frames);
    flipbook.enable(job.frames.done);
  }

  function loadFramesSoon() {
    if (framesTimer || view.gone) return;
    // Longer apart for longer animations: the list is one entry a frame.
    const every = Math.min(FRAMES_REFRESH_MAX_MS, Math.max(FRAMES_REFRESH_MS, strip.order.length));
    framesTimer = setTimeout(
      () => {
        framesTimer = 0;
        loadFrames();
      },
      Math.max(0, framesAt + every - Date.now()),
    );
  }

  async function loadFrames() {
    if (framesBusy) {
      framesAgain = true;
      return;
    }
    framesBusy = true;
    framesAt = Date.now();
    try {
      const list = await api('GET', jobPath(id, '/frames'));
      if (!view.gone) {
        strip.apply(list.frames ?? [], aspect());
        if (!tilesKnown) showCounts();
      }
    } catch (error) {
      if (!view.gone && error.status !== 404) reportError('The frames', error);
    } finally {
      framesBusy = false;
      if (framesAgain && !view.gone) {
        framesAgain = false;
        loadFramesSoon();
      }
    }
  }

  // The frame shown while following: the first not yet done (frames.current), or, once
  // none is left, the last one followed, so that the end of a render leaves it in view.
  function follow() {
    const current = job?.frames?.current;
    if (current !== null && current !== undefined) showFrame(current);
  }

  function showFrame(frame) {
    if (frame === shownFrame) return;
    shownFrame = frame;
    shownTiles = null;
    strip.mark(frame);
    const entry = frameImages.entry(frame);
    if (entry?.state === 'ready' && strip.isDone(frame)) paintFrame(entry);
    else loadImage();
    showCounts();
    overlay.drawSoon();
  }

  // A done frame already fetched is drawn at once: the flipbook keeps its pace with no
  // request per frame.
  function paintFrame(entry) {
    imageSerial += 1;
    canvas.drawWhole(entry.img, entry.frame);
    imageLoading = false;
    const queued = pixelQueue;
    pixelQueue = [];
    for (const event of queued) drawPixels(event);
  }

  // --- tiles ---
  // The tiles the viewer shows: an animation's of the frame shown only.
  function tilesShown() {
    if (!animated) return tiles;
    shownTiles ??= tiles.filter((tile) => tile && tile.frame === shownFrame);
    return shownTiles;
  }

  function showCounts() {
    const by = {pending: 0, rendering: 0, done: 0, failed: 0};
    const workers = new Map();
    const shown = tilesShown();
    for (const tile of shown) {
      if (!tile) continue;
      by[tile.state] = (by[tile.state] ?? 0) + 1;
      if (tile.state === 'rendering' && tile.worker)
        workers.set(tile.worker, tile.worker_name || tile.worker);
    }
    const info = animated ? strip.info.get(shownFrame) : null;
    const prefix = animated ? `Frame ${shownFrame}: ` : '';
    let done = by.done;
    if (!tilesKnown) done = animated ? (info?.tiles.done ?? 0) : (job?.tiles.done ?? 0);
    counts.dataset.done = String(done);
    if (animated) counts.dataset.frame = String(shownFrame);
    if (!tilesKnown) {
      const total = animated ? info?.tiles.total : job?.tiles.total;
      setText(
        counts,
        job && total !== undefined
          ? `${prefix}${formatCount(done)} of ${formatCount(total)} tiles done`
          : '',
      );
      return;
    }
    const total = animated ? shown.length : tiles.length;
    counts.dataset.total = String(total);
    fill(
      counts,
      `${prefix}${formatCount(total)} tiles: ${formatCount(by.done)} done, ${formatCount(by.rendering)} rendering, ` +
        `${formatCount(by.pending)} pending, ${formatCount(by.failed)} failed`,
      ...[...workers].map(([worker, name]) => {
        const swatch = h('span', {class: 'swatch rendering'});
        swatch.style.borderColor = workerColour(worker);
        return h('span', {}, swatch, name);
      }),
    );
  }

  function applyTileState(event) {
    const old = tiles[event.index];
    // Done is final: an older event seen again (after a reload) must not undo it.
    if (old && old.state === 'done' && event.state !== 'done') return;
    tiles[event.index] = {
      index: event.index,
      frame: event.frame ?? 0,
      x: event.x,
      y: event.y,
      width: event.width,
      height: event.height,
      state: event.state,
      worker: event.worker ?? null,
      worker_name: event.worker_name ?? null,
      render_ms: event.render_ms ?? null,
    };
    if ((event.frame ?? 0) === shownFrame) shownTiles = null;
  }

  function drawPixels(event) {
    if (animated && event.frame !== shownFrame) return;
    canvas.drawPixels(event);
  }

  function onTile(event) {
    if (!Number.isInteger(event.index) || event.index < 0) return;
    if (tilesLoading) tileQueue.push(event);
    else applyTileState(event);
    const ofShown = !animated || event.frame === shownFrame;
    if (animated && event.state === 'rendering') strip.begun(event.frame);
    if (!ofShown) return;
    if (event.pixels) {
      if (imageLoading) pixelQueue.push(event);
      else drawPixels(event);
    } else if (event.state === 'done' && !flipbook.playing) {
      // Done, but without its pixels: they come with the next image read.
      clearTimeout(refreshTimer);
      refreshTimer = setTimeout(loadImage, 1000);
    }
    showCounts();
    overlay.drawSoon();
  }

  async function loadTiles() {
    tilesLoading = true;
    try {
      // A page at a time: a job of millions of tiles is never one answer.
      const loaded = [];
      let offset = 0;
      while (offset !== null && offset !== undefined) {
        const list = await api('GET', jobPath(id, `/tiles?offset=${offset}`));
        if (view.gone) return;
        for (const tile of list.tiles ?? []) loaded[tile.index] = tile;
        offset = list.next_offset;
      }
      tiles = loaded;
      shownTiles = null;
      tilesKnown = true;
    } catch (error) {
      if (view.gone) return;
      if (error.status !== 404) reportError('The tiles', error);
    } finally {
      tilesLoading = false;
      const queued = tileQueue;
      tileQueue = [];
      if (tilesKnown) for (const event of queued) applyTileState(event);
      if (!view.gone) {
        showCounts();
        overlay.drawSoon();
      }
    }
  }

  // The image so far (an animation's: the frame shown), drawn whole; pixels of tile events
  // that came meanwhile go on top.
  async function loadImage() {
    const serial = ++imageSerial;
    const frame = shownFrame;
    imageLoading = true;
    try {
      const target = animated
        ? `/frames/${frame}/image?format=png&partial=1`
        : '/image?format=png&partial=1';
      const response = await fetchWithToken(jobPath(id, target), {cache: 'no-store'});
      await checked(response);
      const bitmap = await createImageBitmap(await response.blob());
      if (view.gone || serial !== imageSerial) {
        bitmap.close();
        return;
      }
      canvas.drawWhole(bitmap, animated ? frame : null);
      bitmap.close();
    } catch (error) {
      if (!view.gone && error.status !== 409) reportError('The image', error);
    } finally {
      if (serial === imageSerial) {
        imageLoading = false;
        const queued = pixelQueue;
        pixelQueue = [];
        if (!view.gone) for (const event of queued) drawPixels(event);
      }
    }
  }

  function showGone(what) {
    fill(
      main,
      h('div', {class: 'empty'}, what, h('a', {href: '/', 'data-nav': true, text: 'All jobs'})),
    );
  }

  async function loadAll() {
    const serial = ++loadSerial;
    tilesLoading = true;
    imageLoading = true;
    try {
      applyJob(await api('GET', jobPath(id)));
    } catch (error) {
      if (view.gone || serial !== loadSerial) return;
      tilesLoading = false;
      imageLoading = false;
      if (error.status === 404) showGone(`There is no job ${id}. `);
      else if (error.status !== 401 && error.code !== 'wrong_role') reportError('The job', error);
      return;
    }
    if (view.gone || serial !== loadSerial) return;
    await Promise.all([loadTiles(), loadImage(), animated ? loadFrames() : null]);
  }

  // Downloads go through fetch(), with the token in a header, and are saved from a blob.
  // An animation's: the frame shown.
  async function save(format) {
    const frame = animated ? shownFrame : null;
    const target =
      frame === null
        ? `/image?format=${format}&partial=1`
        : `/frames/${frame}/image?format=${format}&partial=1`;
    const response = await fetchWithToken(jobPath(id, target), {cache: 'no-store'});
    await checked(response);
    const url = URL.createObjectURL(await response.blob());
    const name =
      frame === null
        ? fileName(job ?? {id, state: ''}, format)
        : fileName(job, format, {frame, whole: strip.isDone(frame)});
    const link = h('a', {href: url, download: name, hidden: true});
    document.body.append(link);
    link.click();
    link.remove();
    setTimeout(() => URL.revokeObjectURL(url), 60000);
  }

  // First the events, then what is already there: nothing falls between the two.
  let started = false;
  const start = () => {
    if (started) return;
    started = true;
    loadAll();
  };
  const stream = liveStream(
    jobPath(id, '/events'),
    (type, data) => {
      if (type === 'tile') onTile(data);
      else if (type === 'job') applyJob(data);
      else if (type === 'job_removed' && data.id === id) showGone(`The job ${id} was removed. `);
      else if (type === 'resync') loadAll();
    },
    {
      onOpen: start,
      poll: () => {
        if (!job || !FINISHED.has(job.state)) loadAll();
      },
    },
  );
  // A stream that never opens (a proxy that holds it) must not keep the page empty.
  const startTimer = setTimeout(start, 4000);
  const clock = setInterval(() => {
    if (job) applyJob(job);
  }, 5000);

  return {
    unmount() {
      view.gone = true;
      stream.stop();
      clearTimeout(startTimer);
      clearTimeout(refreshTimer);
      clearTimeout(framesTimer);
      clearInterval(clock);
      canvas.close();
      overlay.close();
      flipbook.close();
      strip.close();
      frameImages.close();
    },
  };
}
