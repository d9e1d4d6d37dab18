// Jobs, newest first, filtered by state, owner and name (the server filters and pages them:
// GET /api/jobs), each with its id, name, owner, state, progress (a shot's frames too),
// priority, submission time, ETA and the actions its state allows (kActions).
import { get, post } from './api.js';
import { duration, h, progress, table, time } from './format.js';

const kPageSizes = [5, 25, 100];
const kStates = ['queued', 'running', 'succeeded', 'failed', 'cancelled'];
const ended = (state) => ['succeeded', 'failed', 'cancelled'].includes(state);
const jobPath = (j) => `jobs/${encodeURIComponent(j.id)}`;

// A row's actions: one entry an action, shown when `when` holds for the job. An action with
// `run` is a button (after `confirm`, if given; the list is fetched again after it), one with
// `href` a download link.
const kActions = [
  { name: 'cancel', label: 'Cancel', when: (j) => !ended(j.state), confirm: (j) => `Cancel job ${j.id}?`,
    run: (j) => post(`${jobPath(j)}/cancel`) },
  { name: 'priority', label: 'Priority…', when: (j) => !ended(j.state), run: (j) => {
    const value = prompt(`Priority of job ${j.id} (higher runs first)`, j.priority);
    return value === null ? null : post(`${jobPath(j)}/priority`, { priority: Number(value) });
  } },
  { name: 'pause', label: 'Pause', when: (j) => !ended(j.state) && !j.paused, run: (j) => post(`${jobPath(j)}/pause`) },
  { name: 'resume', label: 'Resume', when: (j) => !ended(j.state) && j.paused, run: (j) => post(`${jobPath(j)}/resume`) },
  // A failed or cancelled job renders on from the tasks it had done.
  { name: 'requeue', label: 'Requeue', when: (j) => j.state === 'failed' || j.state === 'cancelled',
    run: (j) => post(`${jobPath(j)}/requeue`) },
  { name: 'delete', label: 'Delete', when: (j) => ended(j.state),
    confirm: (j) => `Delete job ${j.id} and its files?`, run: (j) => post(`${jobPath(j)}/delete`) },
  // A still's image; a shot's frames are downloaded from their own pages.
  { name: 'exr', label: 'EXR', when: (j) => j.state === 'succeeded' && !j.shot, href: (j) => `/api/${jobPath(j)}/result.exr` },
  { name: 'png', label: 'PNG', when: (j) => j.state === 'succeeded' && !j.shot, href: (j) => `/api/${jobPath(j)}/preview.png?download=1` },
];

export function mount(root) {
  const body = h('div');
  const problem = h('p', { class: 'error', id: 'jobs-problem' });
  const state = h('select', { id: 'filter-state' }, h('option', { value: '' }, 'any state'),
    kStates.map((s) => h('option', { value: s }, s)));
  const owner = h('input', { id: 'filter-owner', type: 'search', placeholder: 'owner' });
  const name = h('input', { id: 'filter-name', type: 'search', placeholder: 'name or id contains' });
  const size = h('select', { id: 'page-size' }, kPageSizes.map((n) => h('option', { value: n, selected: n === 25 }, `${n} a page`)));
  const filters = h('form', { class: 'filters', id: 'job-filters', onsubmit: (e) => { e.preventDefault(); restart(); } },
    h('label', { for: 'filter-state' }, 'State'), state, h('label', { for: 'filter-owner' }, 'Owner'), owner,
    h('label', { for: 'filter-name' }, 'Name'), name, h('button', { type: 'submit' }, 'Filter'), size);
  const previous = h('button', { id: 'jobs-previous', onclick: () => turn(-1) }, '◀ Newer');
  const next = h('button', { id: 'jobs-next', onclick: () => turn(1) }, 'Older ▶');
  const pageLabel = h('span', { id: 'jobs-page' });
  root.append(h('h1', {}, 'Jobs'), filters, problem, body, h('div', { class: 'pager' }, previous, pageLabel, next));

  // The `before` of each page from the first (0: the newest); the last is on screen.
  let pages = [0];
  let nextBefore = null;
  for (const input of [state, owner, name, size]) input.addEventListener('change', restart);

  function query() {
    const q = new URLSearchParams({ limit: size.value, before: pages[pages.length - 1] });
    for (const [key, input] of [['state', state], ['owner', owner], ['name', name]]) {
      if (input.value.trim()) q.set(key, input.value.trim());
    }
    return `jobs?${q}`;
  }

  function restart() {
    pages = [0];
    return refresh().catch((error) => { problem.textContent = error.message; });
  }

  function turn(step) {
    if (step > 0 && nextBefore !== null) pages.push(nextBefore);
    if (step < 0 && pages.length > 1) pages.pop();
    return refresh().catch((error) => { problem.textContent = error.message; });
  }

  async function act(action, job) {
    problem.textContent = '';
    if (action.confirm && !confirm(action.confirm(job))) return;
    try {
      await action.run(job);
      await refresh();
    } catch (error) {
      problem.textContent = `${action.label} ${job.id}: ${error.message}`;
    }
  }

  function actions(job) {
    return kActions.filter((a) => a.when(job)).map((a) => (a.href
      ? h('a', { class: `action ${a.name}`, href: a.href(job), download: '' }, a.label)
      : h('button', { class: `action ${a.name}`, onclick: () => act(a, job) }, a.label)));
  }

  async function refresh() {
    const { jobs, next_before: after } = await get(query());
    nextBefore = after;
    const link = (j, text) => h('a', { href: `#/job/${encodeURIComponent(j.id)}` }, text);
    const rows = jobs.map((j) => h('tr', { class: `job ${j.state}`, 'data-id': j.id },
      h('td', { class: 'id' }, link(j, j.id)),
      h('td', { class: 'name' }, link(j, j.name || '—')),
      h('td', { class: 'owner' }, j.owner || '—'),
      h('td', { class: 'state' }, j.paused && !ended(j.state) ? 'paused' : j.state),
      h('td', {}, progress(j.tasks_done, j.tasks_total),
        j.shot ? h('span', { class: 'frames' }, ` ${j.shot.frames_done}/${j.shot.frames_total} frames`) : ''),
      h('td', { class: 'number priority' }, String(j.priority)),
      h('td', {}, time(j.submitted_ms)),
      h('td', {}, duration(j.eta_s)),
      h('td', { class: 'row-actions' }, actions(j))));
    body.replaceChildren(jobs.length === 0 ? h('p', {}, pages.length > 1 ? 'No more jobs.' : 'No jobs match.')
      : table(['ID', 'Name', 'Owner', 'State', 'Progress', 'Priority', 'Submitted', 'ETA', 'Actions'], rows));
    pageLabel.textContent = `page ${pages.length}`;
    previous.disabled = pages.length === 1;
    next.disabled = nextBefore === null;
  }

  return { every: 2000, refresh };
}
