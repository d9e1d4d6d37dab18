// The farm's workers: id (as a job's tasks and logs name the worker), name (its --name, by default
// its host's), address, version, tags, state (idle, busy, disabled, draining, drained, offline),
// current job and task, last heard, and the actions an admin may take (disable, enable, drain; the
// server refuses them to others). The table is a list of columns (kColumns).
import { get, post } from './api.js';
import { h, table, time } from './format.js';

// A draining worker still holds its task: shown whatever the state says.
const task = (w) => {
  if (!w.job_id) return '—';
  if (w.job_id === '(other)') return "another owner's job";
  return h('a', { href: `#/job/${encodeURIComponent(w.job_id)}` }, `${w.job_id} task ${w.task}`);
};

// A worker's actions by its state: one entry an action, shown when `when` holds.
const kActions = [
  { name: 'disable', label: 'Disable', when: (w) => ['idle', 'busy', 'offline'].includes(w.state) },
  { name: 'drain', label: 'Drain', when: (w) => ['idle', 'busy'].includes(w.state) },
  { name: 'enable', label: 'Enable', when: (w) => ['disabled', 'draining', 'drained'].includes(w.state) },
];

const kColumns = [
  { title: 'Worker', cell: (w) => w.id },
  { title: 'Name', cell: (w) => w.name },
  { title: 'Address', cell: (w) => w.address || '—' },
  { title: 'Version', cell: (w) => w.version },
  { title: 'Tags', cell: (w) => (w.tags && w.tags.length ? w.tags.join(', ') : '—') },
  { title: 'State', cell: (w) => w.state, class: 'state' },
  { title: 'Current task', cell: task },
  { title: 'Last seen', cell: (w, now) => h('span', { title: time(now - w.since_seen_ms) }, `${(w.since_seen_ms / 1000).toFixed(1)} s ago`) },
  { title: 'Actions', class: 'row-actions', cell: (w, now, act) => kActions.filter((a) => a.when(w))
    .map((a) => h('button', { class: `action ${a.name}`, onclick: () => act(a, w) }, a.label)) },
];

export function mount(root) {
  const body = h('div');
  const problem = h('p', { class: 'error', id: 'workers-problem' });
  root.append(h('h1', {}, 'Workers'), problem, body);

  // By name, as `lightfarm workers disable NAME` does (the id of a worker without one).
  async function act(action, w) {
    problem.textContent = '';
    try {
      await post(`workers/${encodeURIComponent(w.name || w.id)}/${action.name}`);
      await refresh();
    } catch (error) {
      problem.textContent = `${action.label} ${w.name || w.id}: ${error.message}`;
    }
  }

  async function refresh() {
    const { workers } = await get('workers');
    const now = Date.now();
    const rows = workers.map((w) => h('tr', { class: `worker ${w.state}`, 'data-id': w.id, 'data-name': w.name },
      kColumns.map((c) => h('td', { class: c.class }, c.cell(w, now, act)))));
    body.replaceChildren(workers.length === 0 ? h('p', {}, 'No workers.')
      : table(kColumns.map((c) => c.title), rows));
  }

  return { every: 2000, refresh };
}
