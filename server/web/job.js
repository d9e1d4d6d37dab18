// One job: its state and actions, the image merged so far with its tiles shaded by state (a
// click toggles fit and 1:1, a drag pans at 1:1; the exposure and the channel shown are the
// server's tone mapping of the linear image), downloads, its tasks filtered by state and paged
// (click one for its log) and the EXR header of the image. A shot's page shows instead a
// strip of its frames (lazy-loaded previews, each with its number and state, paged as the API
// lists them); a frame's page (#/frame/JOB/N) shows that frame as a still's page shows the
// still: its tiles, tasks, preview and header, with the strip to go on to another frame.
import { get, post } from './api.js';
import { duration, h, progress, seconds, svg, table, time } from './format.js';

const ended = (state) => ['succeeded', 'failed', 'cancelled'].includes(state);
// Rows of a page of the tasks table; the tile overlay reads up to the API's bound of tasks.
const kTaskRows = 50, kOverlayTasks = 10000;
const kTaskStates = ['waiting', 'queued', 'running', 'done', 'dropped'];

export function mount(root, id, who, frameText) {
  const path = `jobs/${encodeURIComponent(id)}`;
  const frame = frameText === undefined ? null : Number(frameText);
  // What the preview, tiles, tasks and header are of: the job, or its frame.
  const imagePath = frame === null ? path : `${path}/frames/${frame}`;
  const tasksPath = (params) => {
    const q = new URLSearchParams(params);
    if (frame !== null) q.set('frame', frame);
    return `${path}/tasks?${q}`;
  };
  const summary = h('div', { id: 'summary' });
  const frameSummary = h('p', { id: 'frame-summary' });
  const image = h('img', { id: 'preview', alt: 'the image merged so far' });
  const overlay = svg('svg', { id: 'tiles', preserveAspectRatio: 'none' });
  const preview = h('div', { class: 'preview', id: 'preview-box', title: 'click: fit or 1:1; drag: pan at 1:1' },
    h('div', { class: 'preview-inner' }, image, overlay));
  const exposure = h('input', { type: 'range', id: 'exposure', min: -8, max: 8, step: 0.5, value: 0 });
  const exposureLabel = h('output', { id: 'exposure-value', for: 'exposure' }, '+0 EV');
  const channel = h('select', { id: 'channel' }, h('option', { value: 'beauty' }, 'beauty'));
  const downloadExr = h('a', { id: 'download-exr', download: '', hidden: true }, 'Download EXR');
  const downloadPng = h('a', { id: 'download-png', download: '', hidden: true }, 'Download PNG (as shown)');
  const viewer = h('div', { class: 'viewer' },
    h('div', { class: 'actions' }, h('label', { for: 'exposure' }, 'Exposure'), exposure, exposureLabel,
      h('label', { for: 'channel' }, 'Channel'), channel, downloadPng, downloadExr), preview);
  const taskState = h('select', { id: 'task-state' });
  const taskPageLabel = h('span', { id: 'tasks-page' });
  const taskEarlier = h('button', { id: 'tasks-earlier', onclick: () => turnTasks(-1) }, '◀');
  const taskLater = h('button', { id: 'tasks-later', onclick: () => turnTasks(1) }, '▶');
  const tasks = h('div', { id: 'tasks' });
  // Dependencies (issue 30): drawn only for a job whose JSON names them (`depends_on`: each
  // job's id and state), linked to their pages.
  const dependsOn = h('p', { id: 'depends-on', hidden: true });
  const log = h('pre', { id: 'log' });
  const logTitle = h('h2', { id: 'log-title' });
  const metadata = h('div', { id: 'metadata' });
  const metadataTitle = h('h2', {}, 'EXR metadata');
  const priority = h('input', { type: 'number', id: 'priority', step: 1 });
  const cancel = h('button', { id: 'cancel', onclick: async () => {
    if (confirm(`Cancel job ${id}?`)) await act(() => post(`${path}/cancel`));
  } }, 'Cancel job');
  const remove = h('button', { id: 'delete', onclick: async () => {
    if (confirm(`Delete job ${id} and its files?`)) {
      await act(async () => { await post(`${path}/delete`); location.hash = '#/jobs'; });
    }
  } }, 'Delete job');
  const setPriority = h('button', { id: 'set-priority', onclick: () => act(() => post(`${path}/priority`, { priority: Number(priority.value) })) }, 'Set priority');
  const problem = h('p', { class: 'error' });
  const strip = h('div', { id: 'frames', class: 'strip' });
  const pageLabel = h('span', { id: 'frames-page' });
  const earlier = h('button', { id: 'frames-earlier', onclick: () => turn(-1) }, '◀ Earlier');
  const later = h('button', { id: 'frames-later', onclick: () => turn(1) }, 'Later ▶');
  const shot = h('section', { id: 'shot', hidden: true },
    h('h2', {}, 'Frames'), h('div', { class: 'pager' }, earlier, pageLabel, later), strip);
  const title = frame === null ? h('h1', {}, `Job ${id}`)
    : h('h1', {}, h('a', { href: `#/job/${encodeURIComponent(id)}` }, `Job ${id}`), `, frame ${frame}`);
  root.append(title, summary, frameSummary, dependsOn,
    h('div', { class: 'actions' }, cancel, remove, h('label', { for: 'priority' }, 'Priority'), priority, setPriority, problem),
    shot, viewer,
    h('h2', {}, 'Tasks'), h('div', { class: 'pager' }, h('label', { for: 'task-state' }, 'State'), taskState,
      taskEarlier, taskPageLabel, taskLater), tasks, logTitle, log, metadataTitle, metadata);

  let shown = '';        // the preview's version on screen
  let metadataOf = '';   // the version whose metadata is on screen
  let logTask = null;    // the task whose log is open
  let logAfter = 0;
  let editing = false;   // the priority field is being edited: not overwritten by polls
  let framesFrom = null; // the strip's page: its first frame's position; null: the server's choice
  let listed = null;     // the shot's page as last drawn
  const thumbs = new Map();  // frame number -> { element, img, state }
  let base = null;       // the preview's URL at exposure 0 of the beauty, as the server caches it
  let taskOffset = 0;    // the tasks table's page: its first row among the tasks in the state
  let taskTotal = 0;
  priority.addEventListener('focus', () => { editing = true; });
  priority.addEventListener('blur', () => { editing = false; });

  // The image as graded: the cached preview at exposure 0 of the beauty, else the server tone
  // maps the linear EXR again (it knows the channels; a browser's canvas would have only the PNG).
  function previewUrl() {
    const ev = Number(exposure.value);
    if (ev === 0 && channel.value === 'beauty') return base;
    return `${base}&${new URLSearchParams({ exposure: ev, channel: channel.value })}`;
  }
  function showPreview() {
    if (!base) return;
    image.src = previewUrl();
    downloadPng.href = `${previewUrl()}&download=1`;
    downloadPng.hidden = false;
  }
  exposure.addEventListener('input', () => {
    exposureLabel.textContent = `${exposure.value > 0 ? '+' : ''}${exposure.value} EV`;
  });
  exposure.addEventListener('change', showPreview);
  channel.addEventListener('change', showPreview);

  // Fit or 1:1 on a click; at 1:1 a drag pans (and is no click).
  let drag = null;
  preview.addEventListener('mousedown', (e) => {
    drag = { x: e.clientX, y: e.clientY, left: preview.scrollLeft, top: preview.scrollTop, moved: false };
    e.preventDefault();
  });
  window.addEventListener('mousemove', (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.moved = drag.moved || Math.abs(dx) + Math.abs(dy) > 3;
    if (preview.classList.contains('actual')) {
      preview.scrollLeft = drag.left - dx;
      preview.scrollTop = drag.top - dy;
    }
  });
  window.addEventListener('mouseup', () => {
    if (drag && !drag.moved) preview.classList.toggle('actual');
    drag = null;
  });

  taskState.append(h('option', { value: '' }, 'all'), ...kTaskStates.map((s) => h('option', { value: s }, s)));
  taskState.addEventListener('change', () => { taskOffset = 0; return act(() => {}); });
  function turnTasks(step) {
    taskOffset = Math.max(0, Math.min(taskOffset + step * kTaskRows, Math.max(0, taskTotal - 1)));
    return act(() => {});
  }

  async function act(action) {
    problem.textContent = '';
    try {
      await action();
      await refresh();
    } catch (error) {
      problem.textContent = error.message;
    }
  }

  function turn(pages) {
    if (!listed) return;
    const per = listed.frames_per_page;
    framesFrom = Math.min(Math.max(0, listed.frames_from + pages * per), listed.frames_total - 1);
    return act(() => {});
  }

  const jobPath = () => (framesFrom === null ? path : `${path}?frames_from=${framesFrom}`);

  // One rectangle per tile not yet finished: running while any of its passes runs, else queued.
  function drawTiles(job, list) {
    const tiles = new Map();
    for (const t of list) {
      if (t.kind !== 'tile' || t.state === 'done' || t.state === 'dropped') continue;
      const key = `${t.x},${t.y}`;
      if (!tiles.has(key) || t.state === 'running') tiles.set(key, t);
    }
    overlay.setAttribute('viewBox', `0 0 ${job.width} ${job.height}`);
    overlay.replaceChildren(...[...tiles.values()].map((t) =>
      svg('rect', { x: t.x, y: t.y, width: t.width, height: t.height, class: t.state === 'running' ? 'running' : 'queued' })));
  }

  function makeThumb(job, f) {
    const img = h('img', { loading: 'lazy', alt: `frame ${f.frame}` });
    const box = h('span', { class: 'thumb-image' }, img);
    // Through the CSSOM: the Content-Security-Policy refuses style attributes.
    box.style.aspectRatio = `${job.width} / ${job.height}`;
    const state = h('span', { class: 'frame-state' });
    const element = h('a', { class: 'thumb', href: `#/frame/${encodeURIComponent(id)}/${f.frame}`, 'data-frame': f.frame },
      box, h('span', { class: 'caption' }, h('span', { class: 'number' }, String(f.frame)), state));
    return { element, img, state };
  }

  // The page of frames listed: thumbnails made again only when the page changed; an image
  // loaded again only when its frame merged more since (its URL names that version).
  function drawStrip(job) {
    listed = job.shot;
    shot.hidden = false;
    if (thumbs.size !== job.frames.length || job.frames.some((f) => !thumbs.has(f.frame))) {
      thumbs.clear();
      strip.replaceChildren(...job.frames.map((f) => {
        const thumb = makeThumb(job, f);
        thumbs.set(f.frame, thumb);
        return thumb.element;
      }));
    }
    for (const f of job.frames) {
      const thumb = thumbs.get(f.frame);
      thumb.element.className = `thumb ${f.state}${f.frame === frame ? ' open' : ''}`;
      thumb.element.title = `frame ${f.frame}: ${f.state}, ${f.tasks_done}/${f.tasks_total} tasks, ${seconds(f.render_s)} render, ${seconds(f.cpu_s)} CPU`;
      thumb.state.textContent = f.state;
      thumb.img.hidden = !f.preview;
      if (f.preview && thumb.img.getAttribute('src') !== f.preview) thumb.img.src = f.preview;
    }
    const { frames_from: from, frames_total: total, frames_done: done } = job.shot;
    pageLabel.textContent = job.frames.length === 0 ? '' : `frames ${job.frames[0].frame}–${job.frames[job.frames.length - 1].frame}`
      + ` (${from + 1}–${from + job.frames.length} of ${total}; ${done} done)`;
    earlier.disabled = from === 0;
    later.disabled = from + job.frames.length >= total;
  }

  function openLog(task) {
    logTask = task;
    logAfter = 0;
    log.replaceChildren();
    logTitle.textContent = `Log of task ${task}`;
    return refreshLog();
  }

  async function refreshLog() {
    if (logTask === null) return;
    const page = await get(`${path}/logs?task=${logTask}&after=${logAfter}&max=500`);
    for (const l of page.lines) {
      log.append(h('div', { class: `line ${l.level}` }, `${new Date(l.time_ms).toLocaleTimeString()} ${l.worker} #${l.attempt} ${l.level}: ${l.text}`));
    }
    logAfter = page.next_seq;
  }

  async function refresh() {
    // All asked at once, drawn together: the summary, the tiles and the tasks agree.
    const page = { offset: taskOffset, limit: kTaskRows };
    if (taskState.value) page.state = taskState.value;
    let [job, { tasks: list }, rows] = await Promise.all([get(jobPath()),
      get(tasksPath({ limit: kOverlayTasks })), get(tasksPath(page))]);
    if (frame !== null && framesFrom === null && job.shot) {
      // A frame's page lists the strip's page holding the frame.
      const per = job.shot.frames_per_page;
      const position = Math.floor((frame - job.shot.first) / job.shot.step);
      framesFrom = Math.min(Math.max(0, Math.floor(position / per) * per), job.shot.frames_total - 1);
      if (framesFrom !== job.shot.frames_from) job = await get(jobPath());
    }
    summary.replaceChildren(table(['State', 'Owner', 'Method', 'Size', 'Progress', 'Submitted', 'Started', 'Finished', 'ETA', 'CPU time'], [
      h('tr', {}, h('td', { class: 'state', id: 'state' }, job.paused && !ended(job.state) ? 'paused' : job.state), h('td', {}, job.owner || '—'), h('td', {}, job.method),
        h('td', {}, `${job.width}×${job.height}, ${job.spp} spp`),
        h('td', {}, progress(job.tasks_done, job.tasks_total), job.shot ? ` ${job.shot.frames_done}/${job.shot.frames_total} frames` : ''),
        h('td', {}, time(job.submitted_ms)), h('td', {}, time(job.started_ms)), h('td', {}, time(job.finished_ms)),
        h('td', {}, duration(job.eta_s)), h('td', { id: 'cpu-time', title: `${seconds(job.render_s)} rendering on workers` }, seconds(job.cpu_s)))]),
    h('p', { class: 'error' }, job.error),
    h('p', { class: 'blocklist' }, job.blocklist.map((b) => `blocklisted: ${b.worker} (${b.failures} failures, last: ${b.last_error})`).join('; ')));
    cancel.disabled = ended(job.state);
    remove.disabled = !ended(job.state);
    if (Array.isArray(job.depends_on)) {
      dependsOn.hidden = false;
      dependsOn.replaceChildren('Depends on: ', ...job.depends_on.map((d, i) => h('span', { class: 'dependency' },
        i > 0 ? ', ' : '', h('a', { href: `#/job/${encodeURIComponent(d.id)}` }, d.id), ` (${d.state})`)));
    }
    setPriority.disabled = ended(job.state);
    if (!editing) priority.value = job.priority;
    if (job.shot) drawStrip(job);
    // A shot's own page has no one image: its frames have theirs.
    const image_shown = !job.shot || frame !== null;
    for (const element of [viewer, metadataTitle, metadata]) element.hidden = !image_shown;

    // The frame's or the job's image, its version, and whether it is final.
    let version = null;
    let final = ended(job.state);
    const mine = frame === null ? null : (job.frames || []).find((f) => f.frame === frame);
    if (frame === null) {
      if (job.tasks_done > 0 || job.state === 'succeeded') version = `${job.tasks_done}-${job.state}`;
    } else if (mine) {
      frameSummary.replaceChildren(`Frame ${frame}: `, h('span', { class: 'state', id: 'frame-state' }, mine.state), ' ',
        progress(mine.tasks_done, mine.tasks_total), h('span', { id: 'frame-times' }, ` ${seconds(mine.render_s)} render, ${seconds(mine.cpu_s)} CPU`));
      version = mine.preview;
      final = final || mine.state === 'done';
    }

    drawTiles(job, list);
    const complete = frame === null ? job.state === 'succeeded' : mine && mine.state === 'done';
    downloadExr.hidden = !complete;
    if (complete) downloadExr.href = `/api/${imagePath}/result.exr`;
    taskTotal = rows.total;
    const counts = Object.entries(rows.counts).map(([s, n]) => `${n} ${s}`).join(', ');
    taskPageLabel.textContent = rows.total === 0 ? `none (${counts || 'no tasks'})`
      : `${rows.offset + 1}–${rows.offset + rows.tasks.length} of ${rows.total} (${counts})`;
    taskEarlier.disabled = rows.offset === 0;
    taskLater.disabled = rows.offset + rows.tasks.length >= rows.total;
    const frames = (t) => (t.frames && t.frames.length ? `frame ${t.frames.join(', ')}, ` : '');
    tasks.replaceChildren(table(['Task', 'State', 'Worker', 'Attempts', 'Duration', 'CPU', 'Log lines'], rows.tasks.map((t) =>
      h('tr', { class: `task ${t.state}${t.index === logTask ? ' open' : ''}`, 'data-task': t.index, onclick: () => openLog(t.index) },
        h('td', {}, `${t.index} (${frames(t)}${t.kind} ${t.x},${t.y} ${t.width}×${t.height})`), h('td', {}, t.state),
        h('td', {}, t.worker || '—'), h('td', { class: 'number' }, String(t.attempts)),
        h('td', {}, t.attempts ? `${(t.duration_ms / 1000).toFixed(1)} s` : '—'),
        h('td', { class: 'number' }, t.state === 'done' ? seconds(t.cpu_s) : '—'), h('td', { class: 'number' }, String(t.log_lines))))));

    // The preview is fetched again only when a task was merged since (or the job ended).
    if (image_shown && version && version !== shown) {
      shown = version;
      base = frame === null ? `/api/${path}/preview.png?v=${encodeURIComponent(version)}` : version;
      showPreview();
    }
    if (shown && metadataOf !== shown && (final || !metadataOf)) {
      metadataOf = shown;
      const { attributes, channels } = await get(`${imagePath}/metadata`);
      const picked = channel.value;
      channel.replaceChildren(...channels.map((c) => h('option', { value: c }, c)));
      channel.value = channels.includes(picked) ? picked : 'beauty';
      metadata.replaceChildren(table(['Attribute', 'Value'], Object.entries(attributes).map(([name, value]) =>
        h('tr', {}, h('td', {}, name), h('td', {}, typeof value === 'object' ? JSON.stringify(value) : String(value))))));
    }
    await refreshLog();
  }

  return { refresh, every: 2000 };
}
