// The dashboard's shell: hash routes to pages, and one polling loop for the page on screen.
// Each page module exports mount(root, argument, who, detail) returning { refresh, every }
// (#/NAME/ARGUMENT/DETAIL: #/frame/JOB/N is job.js on a shot's frame N) where refresh()
// fetches and draws and `every` is its polling period in ms. Polling stops while the tab is
// hidden and resumes at once when it is shown again.
import { ApiError, get, post } from './api.js';
import * as farm from './farm.js';
import * as job from './job.js';
import * as jobs from './jobs.js';
import * as signin from './signin.js';
import * as workers from './workers.js';

const pages = { jobs, job, frame: job, workers, farm, signin };
const root = document.getElementById('page');
const problem = document.getElementById('problem');
let current = null;  // { page, timer }

function showProblem(text) {
  problem.textContent = text || '';
  problem.hidden = !text;
}

async function tick(view) {
  if (view !== current) return;
  try {
    await view.page.refresh();
    showProblem('');
  } catch (error) {
    if (error instanceof ApiError && error.status === 401) {
      location.hash = '#/signin';
      return;
    }
    showProblem(error.message);
  }
  if (view === current && view.page.every && !document.hidden) {
    view.timer = setTimeout(() => tick(view), view.page.every);
  }
}

async function who() {
  const whoElement = document.getElementById('who');
  const signout = document.getElementById('signout');
  try {
    const me = await get('session');
    whoElement.textContent = me.auth ? `${me.name} (${me.role})` : 'no sign-in needed';
    signout.hidden = !me.auth;
  } catch {
    whoElement.textContent = '';
    signout.hidden = true;
  }
}

function route() {
  if (current) clearTimeout(current.timer);
  const [name, argument, detail] = location.hash.replace(/^#\/?/, '').split('/');
  const module = pages[name] || jobs;
  for (const link of document.querySelectorAll('nav a')) {
    link.classList.toggle('current', link.dataset.page === (pages[name] ? name : 'jobs'));
  }
  root.replaceChildren();
  showProblem('');
  const decoded = (text) => text && decodeURIComponent(text);
  current = { page: module.mount(root, decoded(argument), who, decoded(detail)), timer: 0 };
  tick(current);
}

document.getElementById('signout').addEventListener('click', async () => {
  await post('session/end');
  await who();
  location.hash = '#/signin';
});
document.addEventListener('visibilitychange', () => {
  if (!document.hidden && current) {
    clearTimeout(current.timer);
    tick(current);
  }
});
window.addEventListener('hashchange', route);
who();
route();
