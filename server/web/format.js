// Building elements and formatting values. Server text always goes in as text, never as HTML.
export function h(tag, attributes = {}, ...children) {
  const element = document.createElement(tag);
  for (const [name, value] of Object.entries(attributes)) {
    if (name.startsWith('on')) element.addEventListener(name.slice(2), value);
    else if (value !== false && value !== null && value !== undefined) element.setAttribute(name, value);
  }
  element.append(...children.flat().filter((c) => c !== null && c !== undefined));
  return element;
}

const SVG = 'http://www.w3.org/2000/svg';
export function svg(tag, attributes = {}) {
  const element = document.createElementNS(SVG, tag);
  for (const [name, value] of Object.entries(attributes)) element.setAttribute(name, value);
  return element;
}

export function time(ms) {
  return ms === null || ms === undefined ? '—' : new Date(ms).toLocaleString();
}

export function duration(seconds) {
  if (seconds === null || seconds === undefined) return '—';
  const s = Math.round(seconds);
  if (s < 60) return `${s} s`;
  if (s < 3600) return `${Math.floor(s / 60)} min ${s % 60} s`;
  return `${Math.floor(s / 3600)} h ${Math.floor((s % 3600) / 60)} min`;
}

// A task's or a frame's time on its workers: hundredths of a second below 10 s, tenths below a
// minute.
export function seconds(s) {
  if (s === null || s === undefined) return '—';
  if (s < 10) return `${s.toFixed(2)} s`;
  return s < 60 ? `${s.toFixed(1)} s` : duration(s);
}

export function progress(done, total) {
  const fraction = total > 0 ? done / total : 0;
  const bar = h('span', { class: 'bar' });
  // Through the CSSOM: the Content-Security-Policy refuses style attributes.
  bar.style.width = `${(100 * fraction).toFixed(1)}%`;
  return h('span', { class: 'progress', title: `${done}/${total} tasks` }, bar,
    h('span', { class: 'label' }, `${done}/${total}`));
}

export function table(headings, rows) {
  return h('table', {},
    h('thead', {}, h('tr', {}, headings.map((t) => h('th', {}, t)))),
    h('tbody', {}, rows));
}
