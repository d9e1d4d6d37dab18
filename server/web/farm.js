// The farm: queue depth, jobs and workers now, and throughput per minute over the last hour.
import { get } from './api.js';
import { h, svg } from './format.js';

// Bars of per-minute counts, oldest on the left, the current (partial) minute on the right.
function chart(counts, label) {
  const width = 600, height = 120, bar = width / counts.length;
  const top = Math.max(1, ...counts);
  const picture = svg('svg', { viewBox: `0 0 ${width} ${height + 16}`, class: 'chart', role: 'img', 'aria-label': label });
  counts.forEach((count, i) => {
    const tall = (height * count) / top;
    const rect = svg('rect', { x: i * bar + 1, y: height - tall, width: bar - 2, height: tall });
    rect.append(svg('title'));
    rect.firstChild.textContent = `${count} (${counts.length - 1 - i} min ago)`;
    picture.append(rect);
  });
  const axis = svg('text', { x: 0, y: height + 14 });
  axis.textContent = `max ${top}/min · 60 min ago`;
  const now = svg('text', { x: width, y: height + 14, 'text-anchor': 'end' });
  now.textContent = 'now';
  picture.append(axis, now);
  return picture;
}

const sum = (counts) => counts.reduce((a, b) => a + b, 0);

export function mount(root) {
  const body = h('div');
  root.append(h('h1', {}, 'Farm'), body);
  return {
    every: 5000,
    refresh: async () => {
      const f = await get('farm');
      const figure = (name, value, id) => h('div', { class: 'figure', id }, h('span', { class: 'value' }, String(value)), h('span', {}, name));
      body.replaceChildren(
        h('div', { class: 'figures' },
          figure('tasks queued', f.queue_depth, 'queue-depth'),
          figure('tasks running', f.tasks_running),
          figure('jobs queued', f.jobs_queued),
          figure('jobs running', f.jobs_running),
          figure('workers live', f.workers_live),
          figure('workers busy', f.workers_busy)),
        h('h2', {}, `Tasks per minute (${sum(f.tasks_per_minute)} in the last hour)`),
        chart(f.tasks_per_minute, 'tasks per minute'),
        h('h2', {}, `Samples per minute (${sum(f.samples_per_minute).toExponential(2)} in the last hour)`),
        chart(f.samples_per_minute, 'samples per minute'));
    },
  };
}
