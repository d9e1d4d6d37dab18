// Workers heard from within a lease: id (as a job's tasks and logs name the worker), name (its
// --name, by default its host's), address, version, state, current job and task, last heartbeat.
// The table is a list of columns (kColumns): a column, such as one of actions, is one entry.
import { get } from './api.js';
import { h, table, time } from './format.js';

const task = (w) => {
  if (w.state !== 'busy') return '—';
  if (w.job_id === '(other)') return "another owner's job";
  return h('a', { href: `#/job/${encodeURIComponent(w.job_id)}` }, `${w.job_id} task ${w.task}`);
};

// Listed workers are live (heard within a lease): busy with a task or idle.
const kColumns = [
  { title: 'Worker', cell: (w) => w.id },
  { title: 'Name', cell: (w) => w.name },
  { title: 'Address', cell: (w) => w.address || '—' },
  { title: 'Version', cell: (w) => w.version },
  { title: 'State', cell: (w) => `live, ${w.state}`, class: 'state' },
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
      body.replaceChildren(workers.length === 0 ? h('p', {}, 'No live workers.')
        : table(kColumns.map((c) => c.title), rows));
    },
  };
}
