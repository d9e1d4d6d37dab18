// One job: its state and actions, the image merged so far with its tiles shaded by state, its
// tasks (click one for its log) and the EXR header of the image.
import { get, post } from './api.js';
import { duration, h, progress, svg, table, time } from './format.js';

const ended = (state) => ['succeeded', 'failed', 'cancelled'].includes(state);
// Rows of the tasks table: a job may have thousands of tasks; those worth a look come first.
const kMaxTaskRows = 200;
const rank = (t) => (t.state === 'running' ? 0 : t.failures > 0 ? 1 : t.state === 'done' ? 2 : 3);

export function mount(root, id) {
  const path = `jobs/${encodeURIComponent(id)}`;
  const summary = h('div', { id: 'summary' });
  const image = h('img', { id: 'preview', alt: 'the image merged so far' });
  const overlay = svg('svg', { id: 'tiles', preserveAspectRatio: 'none' });
  const tasks = h('div', { id: 'tasks' });
  const log = h('pre', { id: 'log' });
  const logTitle = h('h2', { id: 'log-title' });
  const metadata = h('div', { id: 'metadata' });
  const priority = h('input', { type: 'number', id: 'priority', step: 1 });
  const cancel = h('button', { id: 'cancel', onclick: async () => {
    if (confirm(`Cancel job ${id}?`)) await act(() => post(`${path}/cancel`));
  } }, 'Cancel job');
  const setPriority = h('button', { id: 'set-priority', onclick: () => act(() => post(`${path}/priority`, { priority: Number(priority.value) })) }, 'Set priority');
  const problem = h('p', { class: 'error' });
  root.append(h('h1', {}, `Job ${id}`), summary,
    h('div', { class: 'actions' }, cancel, h('label', { for: 'priority' }, 'Priority'), priority, setPriority, problem),
    h('div', { class: 'preview' }, image, overlay),
    h('h2', {}, 'Tasks'), tasks, logTitle, log, h('h2', {}, 'EXR metadata'), metadata);

  let shown = '';        // the preview's version on screen
  let metadataOf = '';   // the version whose metadata is on screen
  let logTask = null;    // the task whose log is open
  let logAfter = 0;
  let editing = false;   // the priority field is being edited: not overwritten by polls
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
    const [job, { tasks: list }] = await Promise.all([get(path), get(`${path}/tasks`)]);
    summary.replaceChildren(table(['State', 'Owner', 'Method', 'Size', 'Progress', 'Submitted', 'Started', 'Finished', 'ETA'], [
      h('tr', {}, h('td', { class: 'state', id: 'state' }, job.state), h('td', {}, job.owner || '—'), h('td', {}, job.method),
        h('td', {}, `${job.width}×${job.height}, ${job.spp} spp`), h('td', {}, progress(job.tasks_done, job.tasks_total)),
        h('td', {}, time(job.submitted_ms)), h('td', {}, time(job.started_ms)), h('td', {}, time(job.finished_ms)),
        h('td', {}, duration(job.eta_s)))]),
    h('p', { class: 'error' }, job.error));
    cancel.disabled = ended(job.state);
    setPriority.disabled = ended(job.state);
    if (!editing) priority.value = job.priority;

    drawTiles(job, list);
    const rows = [...list].sort((a, b) => rank(a) - rank(b) || a.index - b.index).slice(0, kMaxTaskRows);
    tasks.replaceChildren(table(['Task', 'State', 'Worker', 'Attempts', 'Duration', 'Log lines'], rows.map((t) =>
      h('tr', { class: `task ${t.state}${t.index === logTask ? ' open' : ''}`, 'data-task': t.index, onclick: () => openLog(t.index) },
        h('td', {}, `${t.index} (${t.kind} ${t.x},${t.y} ${t.width}×${t.height})`), h('td', {}, t.state),
        h('td', {}, t.worker || '—'), h('td', { class: 'number' }, String(t.attempts)),
        h('td', {}, t.attempts ? `${(t.duration_ms / 1000).toFixed(1)} s` : '—'), h('td', { class: 'number' }, String(t.log_lines))))),
    list.length > rows.length ? h('p', {}, `${list.length - rows.length} more tasks not listed (running, failed and done ones first).`) : '');

    // The preview is fetched again only when a task was merged since (or the job ended).
    const version = `${job.tasks_done}-${job.state}`;
    if (version !== shown && (job.tasks_done > 0 || job.state === 'succeeded')) {
      shown = version;
      image.src = `/api/${path}/preview.png?v=${encodeURIComponent(version)}`;
    }
    if (shown && metadataOf !== shown && (ended(job.state) || !metadataOf)) {
      metadataOf = shown;
      const { attributes } = await get(`${path}/metadata`);
      metadata.replaceChildren(table(['Attribute', 'Value'], Object.entries(attributes).map(([name, value]) =>
        h('tr', {}, h('td', {}, name), h('td', {}, typeof value === 'object' ? JSON.stringify(value) : String(value))))));
    }
    await refreshLog();
  }

  return { refresh, every: 2000 };
}
