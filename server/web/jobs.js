// Jobs, newest first: state, owner, method, progress (a shot's frames too), priority, times
// and ETA.
import { get } from './api.js';
import { duration, h, progress, table, time } from './format.js';

export function mount(root) {
  const body = h('div');
  root.append(h('h1', {}, 'Jobs'), body);
  return {
    every: 2000,
    refresh: async () => {
      const { jobs } = await get('jobs?limit=100');
      const rows = jobs.map((j) => h('tr', { class: `job ${j.state}`, 'data-id': j.id },
        h('td', {}, h('a', { href: `#/job/${encodeURIComponent(j.id)}` }, j.name || j.id)),
        h('td', { class: 'state' }, j.state),
        h('td', {}, j.owner || '—'),
        h('td', {}, j.method),
        h('td', {}, progress(j.tasks_done, j.tasks_total),
          j.shot ? h('span', { class: 'frames' }, ` ${j.shot.frames_done}/${j.shot.frames_total} frames`) : ''),
        h('td', { class: 'number' }, String(j.priority)),
        h('td', {}, time(j.submitted_ms)),
        h('td', {}, time(j.started_ms)),
        h('td', {}, time(j.finished_ms)),
        h('td', {}, duration(j.eta_s))));
      body.replaceChildren(jobs.length === 0 ? h('p', {}, 'No jobs yet.')
        : table(['Job', 'State', 'Owner', 'Method', 'Progress', 'Priority', 'Submitted', 'Started', 'Finished', 'ETA'], rows));
    },
  };
}
