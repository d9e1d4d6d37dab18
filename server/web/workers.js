// Workers heard from within a lease: id (as a job's tasks and logs name the worker), name (its
// --name, by default its host's), version, state, current task, last heartbeat.
import { get } from './api.js';
import { h, table } from './format.js';

export function mount(root) {
  const body = h('div');
  root.append(h('h1', {}, 'Workers'), body);
  return {
    every: 2000,
    refresh: async () => {
      const { workers } = await get('workers');
      const task = (w) => {
        if (!w.job_id) return '—';
        if (w.job_id === '(other)') return "another owner's job";
        return h('a', { href: `#/job/${encodeURIComponent(w.job_id)}` }, `${w.job_id} task ${w.task}`);
      };
      const rows = workers.map((w) => h('tr', { class: 'worker' },
        h('td', {}, w.id), h('td', {}, w.name), h('td', {}, w.version),
        h('td', { class: 'state' }, w.state),
        h('td', {}, task(w)), h('td', {}, `${(w.since_seen_ms / 1000).toFixed(1)} s ago`)));
      body.replaceChildren(workers.length === 0 ? h('p', {}, 'No live workers.')
        : table(['Worker', 'Name', 'Version', 'State', 'Task', 'Last heard'], rows));
    },
  };
}
