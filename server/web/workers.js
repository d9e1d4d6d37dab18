// The farm's workers: id (as a job's tasks and logs name the worker), name (its --name, by default
// its host's), address, version, tags, state (idle, busy, disabled, draining, drained, offline),
// current job and task, last heard. The table is a list of columns (kColumns): a column, such as
// one of actions, is one entry.
import { get } from './api.js';
import { h, table, time } from './format.js';

// A draining worker still holds its task: shown whatever the state says.
const task = (w) => {
  if (!w.job_id) return '—';
  if (w.job_id === '(other)') return "another owner's job";
  return h('a', { href: `#/job/${encodeURIComponent(w.job_id)}` }, `${w.job_id} task ${w.task}`);
};

const kColumns = [
  { title: 'Worker', cell: (w) => w.id },
  { title: 'Name', cell: (w) => w.name },
  { title: 'Address', cell: (w) => w.address || '—' },
  { title: 'Version', cell: (w) => w.version },
  { title: 'Tags', cell: (w) => (w.tags && w.tags.length ? w.tags.join(', ') : '—') },
  { title: 'State', cell: (w) => w.state, class: 'state' },
  { title: 'Current task', cell: task },
  { title: 'Last seen', cell: (w, now) => h('span', { title: time(now - w.since_seen_ms) }, `${(w.since_seen_ms / 1000).toFixed(1)} s ago`) },
];

export function mount(root) {
  const body = h('div');
  root.append(h('h1', {}, 'Workers'), body);
  return {
    every: 2000,
    refresh: async () => {
      const { workers } = await get('workers');
      const now = Date.now();
      const rows = workers.map((w) => h('tr', { class: `worker ${w.state}`, 'data-id': w.id },
        kColumns.map((c) => h('td', { class: c.class }, c.cell(w, now)))));
      body.replaceChildren(workers.length === 0 ? h('p', {}, 'No workers.')
        : table(kColumns.map((c) => c.title), rows));
    },
  };
}
