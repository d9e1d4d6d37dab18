// One job: its state and actions, the image merged so far with its tiles shaded by state, its
// tasks (click one for its log) and the EXR header of the image. A shot's page shows instead a
// strip of its frames (lazy-loaded previews, each with its number and state, paged as the API
// lists them); a frame's page (#/frame/JOB/N) shows that frame as a still's page shows the
// still: its tiles, tasks, preview and header, with the strip to go on to another frame.
import { get, post } from './api.js';
import { duration, h, progress, svg, table, time } from './format.js';

const ended = (state) => ['succeeded', 'failed', 'cancelled'].includes(state);
// Rows of the tasks table: a job may have thousands of tasks; those worth a look come first.
const kMaxTaskRows = 200;
const rank = (t) => (t.state === 'running' ? 0 : t.failures > 0 ? 1 : t.state === 'done' ? 2 : 3);

export function mount(root, id, who, frameText) {
  const path = `jobs/${encodeURIComponent(id)}`;
  const frame = frameText === undefined ? null : Number(frameText);
  // What the preview, tiles, tasks and header are of: the job, or its frame.
  const imagePath = frame === null ? path : `${path}/frames/${frame}`;
  const tasksPath = frame === null ? `${path}/tasks` : `${path}/tasks?frame=${frame}`;
  const summary = h('div', { id: 'summary' });
  const frameSummary = h('p', { id: 'frame-summary' });
  const image = h('img', { id: 'preview', alt: 'the image merged so far' });
  const overlay = svg('svg', { id: 'tiles', preserveAspectRatio: 'none' });
  const preview = h('div', { class: 'preview' }, image, overlay);
  const tasks = h('div', { id: 'tasks' });
  const log = h('pre', { id: 'log' });
  const logTitle = h('h2', { id: 'log-title' });
  const metadata = h('div', { id: 'metadata' });
  const metadataTitle = h('h2', {}, 'EXR metadata');
  const priority = h('input', { type: 'number', id: 'priority', step: 1 });
  const cancel = h('button', { id: 'cancel', onclick: async () => {
    if (confirm(`Cancel job ${id}?`)) await act(() => post(`${path}/cancel`));
  } }, 'Cancel job');
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
  root.append(title, summary, frameSummary,
    h('div', { class: 'actions' }, cancel, h('label', { for: 'priority' }, 'Priority'), priority, setPriority, problem),
    shot, preview,
    h('h2', {}, 'Tasks'), tasks, logTitle, log, metadataTitle, metadata);

  let shown = '';        // the preview's version on screen
  let metadataOf = '';   // the version whose metadata is on screen
  let logTask = null;    // the task whose log is open
  let logAfter = 0;
  let editing = false;   // the priority field is being edited: not overwritten by polls
  let framesFrom = null; // the strip's page: its first frame's position; null: the server's choice
  let listed = null;     // the shot's page as last drawn
  const thumbs = new Map();  // frame number -> { element, img, state }
  priority.addEventListener('focus', () => { editing = true; });
  priority.addEventListener('blur', () => { editing = false; });

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
      thumb.element.title = `frame ${f.frame}: ${f.state}, ${f.tasks_done}/${f.tasks_total} tasks`;
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
    // Both asked at once, drawn together: the summary and the tasks agree.
    let [job, { tasks: list }] = await Promise.all([get(jobPath()), get(tasksPath)]);
    if (frame !== null && framesFrom === null && job.shot) {
      // A frame's page lists the strip's page holding the frame.
      const per = job.shot.frames_per_page;
      const position = Math.floor((frame - job.shot.first) / job.shot.step);
      framesFrom = Math.min(Math.max(0, Math.floor(position / per) * per), job.shot.frames_total - 1);
      if (framesFrom !== job.shot.frames_from) job = await get(jobPath());
    }
    summary.replaceChildren(table(['State', 'Owner', 'Method', 'Size', 'Progress', 'Submitted', 'Started', 'Finished', 'ETA'], [
      h('tr', {}, h('td', { class: 'state', id: 'state' }, job.paused && !ended(job.state) ? 'paused' : job.state), h('td', {}, job.owner || '—'), h('td', {}, job.method),
        h('td', {}, `${job.width}×${job.height}, ${job.spp} spp`),
        h('td', {}, progress(job.tasks_done, job.tasks_total), job.shot ? ` ${job.shot.frames_done}/${job.shot.frames_total} frames` : ''),
        h('td', {}, time(job.submitted_ms)), h('td', {}, time(job.started_ms)), h('td', {}, time(job.finished_ms)),
        h('td', {}, duration(job.eta_s)))]),
    h('p', { class: 'error' }, job.error),
    h('p', { class: 'blocklist' }, job.blocklist.map((b) => `blocklisted: ${b.worker} (${b.failures} failures, last: ${b.last_error})`).join('; ')));
    cancel.disabled = ended(job.state);
    setPriority.disabled = ended(job.state);
    if (!editing) priority.value = job.priority;
    if (job.shot) drawStrip(job);
    // A shot's own page has no one image: its frames have theirs.
    const image_shown = !job.shot || frame !== null;
    for (const element of [preview, metadataTitle, metadata]) element.hidden = !image_shown;

    // The frame's or the job's image, its version, and whether it is final.
    let version = null;
    let final = ended(job.state);
    const mine = frame === null ? null : (job.frames || []).find((f) => f.frame === frame);
    if (frame === null) {
      if (job.tasks_done > 0 || job.state === 'succeeded') version = `${job.tasks_done}-${job.state}`;
    } else if (mine) {
      frameSummary.replaceChildren(`Frame ${frame}: `, h('span', { class: 'state', id: 'frame-state' }, mine.state), ' ',
        progress(mine.tasks_done, mine.tasks_total));
      version = mine.preview;
      final = final || mine.state === 'done';
    }

    drawTiles(job, list);
    const rows = [...list].sort((a, b) => rank(a) - rank(b) || a.index - b.index).slice(0, kMaxTaskRows);
    const frames = (t) => (t.frames && t.frames.length ? `frame ${t.frames.join(', ')}, ` : '');
    tasks.replaceChildren(table(['Task', 'State', 'Worker', 'Attempts', 'Duration', 'Log lines'], rows.map((t) =>
      h('tr', { class: `task ${t.state}${t.index === logTask ? ' open' : ''}`, 'data-task': t.index, onclick: () => openLog(t.index) },
        h('td', {}, `${t.index} (${frames(t)}${t.kind} ${t.x},${t.y} ${t.width}×${t.height})`), h('td', {}, t.state),
        h('td', {}, t.worker || '—'), h('td', { class: 'number' }, String(t.attempts)),
        h('td', {}, t.attempts ? `${(t.duration_ms / 1000).toFixed(1)} s` : '—'), h('td', { class: 'number' }, String(t.log_lines))))),
    list.length > rows.length ? h('p', {}, `${list.length - rows.length} more tasks not listed (running, failed and done ones first).`) : '');

    // The preview is fetched again only when a task was merged since (or the job ended).
    if (image_shown && version && version !== shown) {
      shown = version;
      image.src = frame === null ? `/api/${path}/preview.png?v=${encodeURIComponent(version)}` : version;
    }
    if (shown && metadataOf !== shown && (final || !metadataOf)) {
      metadataOf = shown;
      const { attributes } = await get(`${imagePath}/metadata`);
      metadata.replaceChildren(table(['Attribute', 'Value'], Object.entries(attributes).map(([name, value]) =>
        h('tr', {}, h('td', {}, name), h('td', {}, typeof value === 'object' ? JSON.stringify(value) : String(value))))));
    }
    await refreshLog();
  }

  return { refresh, every: 2000 };
}
