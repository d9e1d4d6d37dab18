// The farm: queue depth, jobs and workers now, and throughput per minute over the last hour as
// bar charts with a y axis in the unit counted a minute and an x axis in minutes ago.
import { get } from './api.js';
import { h, svg } from './format.js';

// 1234567 as "1.23M": tick labels stay short.
function short(value) {
  for (const [size, suffix] of [[1e9, 'G'], [1e6, 'M'], [1e3, 'k']]) {
    if (value >= size) return `${Number((value / size).toPrecision(3))}${suffix}`;
  }
  return String(Number(value.toPrecision(3)));
}

// The smallest 1, 2 or 5 times a power of ten at least `value`: the axis' top.
function niceTop(value) {
  const power = 10 ** Math.floor(Math.log10(value));
  return [1, 2, 5, 10].map((m) => m * power).find((t) => t >= value);
}

const text = (attributes, content) => {
  const element = svg('text', attributes);
  element.textContent = content;
  return element;
};

// Bars of per-minute counts, oldest on the left, the current (partial) minute on the right.
function chart(counts, title, unit) {
  const left = 56, top = 22, width = 560, height = 120, bottom = 34;
  const bar = width / counts.length;
  const max = niceTop(Math.max(1, ...counts));
  const y = (value) => top + height - (height * value) / max;
  const picture = svg('svg', { viewBox: `0 0 ${left + width + 8} ${top + height + bottom}`, class: 'chart', role: 'img', 'aria-label': `${title}, ${unit}` });
  picture.append(text({ x: left, y: 14, class: 'title' }, title));
  // The y axis: ticks at 0, half and the top, in `unit`.
  for (const value of [0, max / 2, max]) {
    picture.append(svg('line', { x1: left - 4, x2: left + width, y1: y(value), y2: y(value), class: value ? 'grid' : 'axis' }),
      text({ x: left - 6, y: y(value) + 4, 'text-anchor': 'end', class: 'tick' }, short(value)));
  }
  picture.append(text({ x: 12, y: top + height / 2, transform: `rotate(-90 12 ${top + height / 2})`, 'text-anchor': 'middle', class: 'unit' }, unit));
  counts.forEach((count, i) => {
    const rect = svg('rect', { x: left + i * bar + 1, y: y(count), width: bar - 2, height: top + height - y(count) });
    rect.append(svg('title'));
    rect.firstChild.textContent = `${count} ${unit} (${counts.length - 1 - i} min ago)`;
    picture.append(rect);
  });
  // The x axis: minutes ago, every quarter of the hour.
  for (let ago = 0; ago < counts.length; ago += 15) {
    const x = left + (counts.length - 1 - ago) * bar + bar / 2;
    picture.append(svg('line', { x1: x, x2: x, y1: top + height, y2: top + height + 4, class: 'axis' }),
      text({ x, y: top + height + 15, 'text-anchor': 'middle', class: 'tick' }, ago === 0 ? 'now' : `${ago}`));
  }
  picture.append(text({ x: left + width / 2, y: top + height + 30, 'text-anchor': 'middle', class: 'unit' }, 'minutes ago'));
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
        h('h2', {}, `Tasks done (${sum(f.tasks_per_minute)} in the last hour)`),
        chart(f.tasks_per_minute, 'Tasks done per minute, last hour', 'tasks/min'),
        h('h2', {}, `Samples rendered (${short(sum(f.samples_per_minute))} in the last hour)`),
        chart(f.samples_per_minute, 'Samples rendered per minute, last hour', 'samples/min'));
    },
  };
}
