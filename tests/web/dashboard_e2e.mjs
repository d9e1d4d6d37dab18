// The dashboard end to end: a real lightfarm-server with tokens, two lightfarm-workers and the
// lightfarm CLI from the build, and Debian's headless Chromium driven by playwright-core.
// Checks: a wrong token is refused; signed in, a job submitted from the CLI appears and its
// progress rises; the preview loads and changes while tiles land; a task's log opens; a shot's
// page shows its frames' thumbnails and states, and a click opens a frame's page; a job
// cancelled from the page (after its priority was raised there) is so for the CLI too; the jobs
// page filtered by state and by name, paged, and its row actions (cancel, delete, EXR and PNG
// downloads); a job's preview zoomed to 1:1 and graded by the exposure slider and the channel
// picker (a job rendered with AOVs); tasks filtered by state; the farm's charts' axes and units.
// Screenshots of every page go to SCREENSHOTS (the build's web-screenshots/).
//
//   node dashboard_e2e.mjs BIN_DIR SCENES_DIR SCREENSHOTS_DIR
import { spawn, execFileSync } from 'node:child_process';
import { mkdirSync, mkdtempSync, rmSync, writeFileSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { chromium } from 'playwright-core';

const [binDir, scenesDir, shotsDir] = process.argv.slice(2);
if (!shotsDir) {
  console.error('usage: node dashboard_e2e.mjs BIN_DIR SCENES_DIR SCREENSHOTS_DIR');
  process.exit(2);
}
const dir = mkdtempSync(join(tmpdir(), 'lf_dashboard_e2e_'));
const dataDir = join(dir, 'data');
mkdirSync(shotsDir, { recursive: true });
const children = [];
const bin = (name) => join(binDir, name);

function token(name, role) {
  const out = execFileSync(bin('lightfarm-server'), ['token', 'create', '--data-dir', dataDir, '--name', name, '--role', role], { encoding: 'utf8' });
  const file = join(dir, `${name}.token`);
  writeFileSync(file, out.trim().split('\n').pop() + '\n', { mode: 0o600 });
  return file;
}

// Starts a process; resolves with the first stdout line matching `ready` (its match), keeping
// its output for the failure report.
function start(name, args, ready) {
  const child = spawn(bin(name), args, { stdio: ['ignore', 'pipe', 'pipe'] });
  child.log = '';
  children.push(child);
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`${name} did not start:\n${child.log}`)), 20000);
    const take = (chunk) => {
      child.log += chunk;
      const match = ready && child.log.match(ready);
      if (match) { clearTimeout(timer); resolve(match); }
    };
    child.stdout.on('data', take);
    child.stderr.on('data', take);
    child.on('exit', (code) => reject(new Error(`${name} exited with ${code}:\n${child.log}`)));
    if (!ready) { clearTimeout(timer); resolve(null); }
  });
}

function cli(args, tokenFile) {
  return execFileSync(bin('lightfarm'), [...args, '--server', grpcAddress, '--token-file', tokenFile], { encoding: 'utf8', timeout: 60000 }).trim();
}

async function until(what, check, seconds = 30) {
  const end = Date.now() + seconds * 1000;
  for (;;) {
    const value = await check();
    if (value) return value;
    if (Date.now() > end) throw new Error(`timed out waiting for ${what}`);
    await new Promise((r) => setTimeout(r, 100));
  }
}

// A time as format.js's seconds() writes it: hundredths below 10 s, tenths below a minute,
// then minutes (a busy machine's job passed 10 s of CPU before the job page's check: "10.3 s").
const kTime = String.raw`(?:\d+\.\d\d? s|\d+ min \d+ s|\d+ h \d+ min)`;

function check(condition, message) {
  if (!condition) throw new Error(message);
  console.log(`ok: ${message}`);
}

let grpcAddress;
let browser;
try {
  const adminToken = token('admin', 'admin');
  const aliceToken = token('alice', 'submitter');
  const workerToken = token('render-node', 'worker');
  const server = start('lightfarm-server', ['--listen', '127.0.0.1:0', '--http', '127.0.0.1:0', '--data-dir', dataDir, '--lease-seconds', '5'], /http on ([\d.]+:\d+)/);
  const grpcPort = await until('the gRPC port', () => (children[0].log.match(/listening on ([\d.]+:\d+)/) || [])[1]);
  grpcAddress = grpcPort;
  const httpAddress = (await server)[1];
  const base = `http://${httpAddress}`;
  for (const name of ['w1', 'w2']) {
    start('lightfarm-worker', ['--server', grpcAddress, '--token-file', workerToken, '--name', name, '--threads', '1', '--cache-dir', join(dir, `cache-${name}`)]);
  }

  // Enough tasks to watch for some 30 s even on a fast idle machine (a pass of 256 samples on a
  // 16x16 tile takes 0.05 s there): 16 tiles of 64x64 in passes of 2048 samples.
  const scene = join(scenesDir, 'cornell_box.json');
  const submit = (extra) => cli(['submit', scene, '--resolution', '64x64', '--tile', '16', ...extra], aliceToken).split('\n').pop().trim();
  const job = submit(['--spp', '16384', '--passes', '8', '--name', 'watched']);
  console.log(`job ${job} submitted`);

  browser = await chromium.launch({
    executablePath: '/usr/bin/chromium',
    args: ['--headless=new', '--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage', '--disable-background-networking'],
  });
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 } });
  const page = await context.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  page.on('console', (m) => { if (m.type() === 'error' && !/401|403|404|409/.test(m.text())) errors.push(m.text()); });

  // Not signed in: the sign-in page; a wrong token is refused.
  await page.goto(base);
  await page.waitForSelector('form#signin');
  await page.fill('#token', 'lf1_' + '0'.repeat(64));
  await page.click('form#signin button');
  await until('the refusal', async () => (await page.textContent('#signin-error')).length > 0);
  check(page.url().includes('#/signin'), `a wrong token is refused: "${await page.textContent('#signin-error')}"`);
  const api = await context.request.get(`${base}/api/jobs`, { headers: { Authorization: 'Bearer lf1_nope' } });
  check(api.status() === 401, 'the API refuses a wrong bearer token with 401');
  await page.screenshot({ path: join(shotsDir, 'signin.png'), fullPage: true });

  // Signed in as alice: the job appears and its progress rises.
  await page.fill('#token', readFileSync(aliceToken, 'utf8').trim());
  await page.click('form#signin button');
  const row = `tr.job[data-id="${job}"]`;
  await page.waitForSelector(row, { timeout: 15000 });
  check(true, 'the job submitted from the CLI appears on the jobs page');
  const done = async () => Number((await page.textContent(`${row} .progress .label`)).split('/')[0]);
  const first = await until('progress', async () => { const d = await done(); return d > 0 ? d : 0; });
  const later = await until('rising progress', async () => { const d = await done(); return d > first ? d : 0; });
  check(later > first, `progress rises on the jobs page (${first} then ${later} tasks)`);
  await page.screenshot({ path: join(shotsDir, 'jobs.png'), fullPage: true });

  // The job's page: the preview loads and changes while tiles land.
  const previews = [];
  page.on('response', async (r) => {
    if (r.url().includes('/preview.png') && r.status() === 200) previews.push(await r.body());
  });
  await page.click(`${row} a`);
  await page.waitForSelector('#summary table');
  await until('a loaded preview', () => page.evaluate(() => document.getElementById('preview').naturalWidth > 0));
  const firstSrc = await page.getAttribute('#preview', 'src');
  await until('a changed preview', async () => previews.length >= 2 && (await page.getAttribute('#preview', 'src')) !== firstSrc, 40);
  await until('the new preview loaded', () => page.evaluate(() => document.getElementById('preview').complete && document.getElementById('preview').naturalWidth === 64));
  check(!previews[0].equals(previews[previews.length - 1]), `the preview loads and changes (${previews.length} images, ${previews[0].length} then ${previews[previews.length - 1].length} bytes)`);
  const shaded = await page.$$eval('#tiles rect', (r) => r.length);
  check(shaded >= 1 && shaded <= 16, `${shaded} of the 16 tiles shaded as queued or running`);

  // A task's log opens.
  await page.waitForSelector('tr.task.done');
  await page.click('tr.task.done');
  await until('log lines', async () => (await page.$$('#log .line')).length > 0, 20);
  check(true, `a task's log opens: "${(await page.textContent('#log .line')).slice(0, 100)}"`);
  // History (issue 30): the job's CPU time on its workers, and each done task's.
  const cpu = await page.textContent('#cpu-time');
  const taskCpu = await page.$$eval('tr.task.done', (rows) => rows.map((r) => r.children[5].textContent));
  const time = new RegExp(`^${kTime}$`);
  check(time.test(cpu) && taskCpu.length > 0 && taskCpu.every((t) => time.test(t)),
    `the job page shows the CPU time (${cpu}) and each done task's (${taskCpu.slice(0, 3).join(', ')})`);
  await page.screenshot({ path: join(shotsDir, 'job.png'), fullPage: true });

  // Workers and the farm.
  await page.goto(`${base}/#/workers`);
  await until('two workers', async () => (await page.$$('tr.worker')).length === 2);
  check(true, 'the workers page lists both workers');
  await page.screenshot({ path: join(shotsDir, 'workers.png'), fullPage: true });
  await page.goto(`${base}/#/farm`);
  await page.waitForSelector('#queue-depth .value');
  await until('tasks in the chart', () => page.$$eval('svg.chart rect', (r) => r.some((e) => Number(e.getAttribute('height')) > 0)));
  check(true, `the farm page shows the queue depth (${await page.textContent('#queue-depth .value')}) and throughput`);
  const axes = await page.$$eval('svg.chart', (charts) => charts.map((c) => ({
    title: c.querySelector('text.title').textContent,
    units: [...c.querySelectorAll('text.unit')].map((t) => t.textContent),
    ticks: [...c.querySelectorAll('text.tick')].map((t) => t.textContent),
  })));
  check(axes.length === 2 && axes[0].units.join('|') === 'tasks/min|minutes ago' && axes[1].units.join('|') === 'samples/min|minutes ago'
    && axes.every((a) => a.ticks.includes('0') && a.ticks.includes('now') && a.ticks.includes('30')),
  `the charts have titles, axes with units and ticks: ${axes.map((a) => `${a.title} [${a.units.join(', ')}; ${a.ticks.join(' ')}]`).join('; ')}`);
  await page.screenshot({ path: join(shotsDir, 'farm.png'), fullPage: true });

  // A shot (4 frames of the moving ball, tiny): its page shows a strip of 4 frame thumbnails
  // with their states and no one image; a click on a thumbnail opens the frame's page, with the
  // frame's preview, its tasks only and its EXR header.
  const shotScene = join(scenesDir, 'shots', 'moving_ball.json');
  const shotJob = cli(['submit', shotScene, '--frames', '1-4', '--resolution', '32x18', '--spp', '4', '--tile', '16',
    '--priority', '10', '--name', 'shot'], aliceToken).split('\n').pop().trim();
  await page.goto(`${base}/#/job/${shotJob}`);
  await until('4 frame thumbnails', async () => (await page.$$('#frames a.thumb')).length === 4);
  const numbers = await page.$$eval('#frames a.thumb .number', (e) => e.map((n) => n.textContent));
  check(numbers.join(',') === '1,2,3,4', `the shot's page shows a thumbnail a frame, numbered ${numbers.join(', ')}`);
  check(await page.isHidden('#preview'), "the shot's own page shows its frames instead of one image");
  const states = () => page.$$eval('#frames a.thumb .frame-state', (e) => e.map((n) => n.textContent));
  const seen = new Set();
  await until('every frame done', async () => { (await states()).forEach((s) => seen.add(s)); return (await states()).every((s) => s === 'done'); }, 60);
  await until('the thumbnails loaded', () => page.$$eval('#frames a.thumb img', (imgs) => imgs.length === 4 && imgs.every((i) => i.complete && i.naturalWidth === 32)));
  check(true, `each thumbnail shows its frame's state (seen: ${[...seen].join(', ')}) and its 32x18 preview`);
  await page.screenshot({ path: join(shotsDir, 'shot.png'), fullPage: true });
  await page.click('#frames a.thumb[data-frame="3"]');
  await until("the frame's page", () => page.url().endsWith(`#/frame/${shotJob}/3`));
  await page.waitForSelector('#frame-state');
  await until("the frame's preview", () => page.evaluate(() => document.getElementById('preview').naturalWidth === 32));
  check((await page.textContent('h1')).includes('frame 3') && (await page.textContent('#frame-state')) === 'done',
    `a click opens frame 3's page: "${await page.textContent('h1')}", ${await page.textContent('#frame-state')}, its preview loaded`);
  const frameTimes = await page.textContent('#frame-times');
  check(new RegExp(`^ ${kTime} render, ${kTime} CPU$`).test(frameTimes),
    `the frame's page shows its tasks' times on their workers:${frameTimes}`);
  const frameTasks = await page.$$eval('tr.task td:first-child', (e) => e.map((n) => n.textContent));
  check(frameTasks.length === 4 && frameTasks.every((t) => t.includes('frame 3,')), `the frame's page lists its 4 tasks only (${frameTasks[0]}, ...)`);
  await until("the frame's EXR header", () => page.$$eval('#metadata tr', (rows) => rows.some((r) => r.textContent === 'lightfarm.frame3')));
  check(await page.isVisible('#frames a.thumb.open[data-frame="3"]'), "the frame's thumbnail is marked open in the strip");
  await page.screenshot({ path: join(shotsDir, 'frame.png'), fullPage: true });

  // Raise a job's priority and cancel it from its page; the CLI agrees.
  const doomed = submit(['--spp', '65536', '--passes', '64', '--name', 'doomed']);
  const waiter = submit(['--spp', '1', '--name', 'waiter', '--after', doomed]);
  await page.goto(`${base}/#/job/${doomed}`);
  await page.waitForSelector('#state');
  await page.fill('#priority', '5');
  await page.click('#set-priority');
  const raised = await until('the new priority', () => {
    const line = cli(['status', doomed, '--json'], aliceToken);
    return /"priority":\s*5\b/.test(line) && line;
  });
  check(raised, 'a priority set on the page is the one the CLI sees');
  const answer = cli(['priority', doomed, '7'], aliceToken);
  await until('the page to show the CLI\'s priority', async () => (await page.inputValue('#priority')) === '7');
  check(true, `a priority set with the CLI (${answer}) shows on the page`);
  page.once('dialog', (d) => d.accept());
  await page.click('#cancel');
  await until('the cancelled state', async () => (await page.textContent('#state')) === 'cancelled');
  const status = cli(['status', doomed], aliceToken);
  check(/cancelled/i.test(status), `cancelled from the page, and the CLI agrees: ${status.split('\n')[0]}`);
  await page.screenshot({ path: join(shotsDir, 'job-cancelled.png'), fullPage: true });
  // Dependencies (issue 30): the dependent's page links its dependency, in its state.
  await page.goto(`${base}/#/job/${waiter}`);
  await until('the dependency on the page', async () => (await page.textContent('#depends-on')) === `Depends on: ${doomed} (cancelled)`);
  check(await page.isVisible(`#depends-on a[href="#/job/${doomed}"]`) && (await page.textContent('#state')) === 'failed',
    'a dependent of a cancelled job shows it linked, cancelled, and has failed');

  // Alice may not see the admin's jobs: an admin's job answers 404.
  const adminJob = cli(['submit', scene, '--resolution', '16x16', '--spp', '1', '--name', 'admins'], adminToken).split('\n').pop().trim();
  const hidden = await context.request.get(`${base}/api/jobs/${adminJob}`);
  check(hidden.status() === 404, "another owner's job is not found for alice");

  // The jobs page as a tool: 3 tiny stills (one with AOVs) and one long job to act on.
  const tiny = (name, extra = []) => cli(['submit', scene, '--resolution', '32x32', '--spp', '4', '--tile', '16', '--passes', '1', '--priority', '20', '--name', name, ...extra], aliceToken).split('\n').pop().trim();
  const tinies = [tiny('tiny-one'), tiny('tiny-two'), tiny('tiny-aov', ['--aov', 'albedo,normal'])];
  const victim = submit(['--spp', '65536', '--passes', '64', '--name', 'victim']);
  await until('the tiny jobs done', () => tinies.every((t) => /succeeded/.test(cli(['status', t], aliceToken))), 60);
  await page.goto(`${base}/#/jobs`);
  await page.waitForSelector(`tr.job[data-id="${victim}"]`);
  const listed = () => page.$$eval('tr.job', (rows) => rows.map((r) => ({ id: r.dataset.id, name: r.querySelector('td.name').textContent, state: r.querySelector('td.state').textContent })));
  const all = await listed();
  await page.selectOption('#filter-state', 'cancelled');
  await until('only cancelled jobs', async () => { const l = await listed(); return l.length > 0 && l.length < all.length && l.every((j) => j.state === 'cancelled'); });
  check((await listed()).some((j) => j.id === doomed), `filtered by state: ${(await listed()).length} cancelled of ${all.length} jobs`);
  await page.selectOption('#filter-state', '');
  await page.fill('#filter-name', 'TINY');
  await page.press('#filter-name', 'Enter');
  await until('only the tiny jobs', async () => { const l = await listed(); return l.length === 3 && l.every((j) => j.name.startsWith('tiny-')); });
  check(true, `filtered by name: ${(await listed()).map((j) => j.name).join(', ')}`);
  await page.fill('#filter-name', '');
  await page.press('#filter-name', 'Enter');
  await page.selectOption('#page-size', '5');
  await until('a page of 5', async () => (await listed()).length === 5);
  const firstPage = (await listed()).map((j) => j.id);
  await page.click('#jobs-next');
  await until('the second page', async () => (await page.textContent('#jobs-page')) === 'page 2');
  const secondPage = (await listed()).map((j) => j.id);
  check(secondPage.length === all.length - 5 && secondPage.every((id) => !firstPage.includes(id)),
    `paging: page 1 lists ${firstPage.length} jobs, page 2 the other ${secondPage.length}`);
  await page.click('#jobs-previous');
  await until('the first page again', async () => (await listed())[0].id === firstPage[0]);
  await page.screenshot({ path: join(shotsDir, 'jobs-paged.png'), fullPage: true });

  // Row actions: pause and resume the victim, cancel it, requeue it, cancel it again and delete
  // it; the CLI and the API agree.
  const victimRow = `tr.job[data-id="${victim}"]`;
  const victimApi = async () => (await context.request.get(`${base}/api/jobs/${victim}`)).json();
  await page.click(`${victimRow} button.action.pause`);
  await until('the victim paused on the page', async () => (await page.textContent(`${victimRow} td.state`)) === 'paused');
  check((await victimApi()).paused === true && /paused/i.test(cli(['status', victim], aliceToken)), 'pause from the jobs page: the API and the CLI say paused');
  await page.click(`${victimRow} button.action.resume`);
  await until('the victim resumed on the page', async () => ['queued', 'running'].includes(await page.textContent(`${victimRow} td.state`)));
  check((await victimApi()).paused === false, 'resume from the jobs page: the API says not paused');
  const cancelVictim = async () => {
    page.once('dialog', (d) => d.accept());
    await page.click(`${victimRow} button.action.cancel`);
    await until('the victim cancelled on the page', async () => (await page.textContent(`${victimRow} td.state`)) === 'cancelled');
  };
  await cancelVictim();
  check(/cancelled/i.test(cli(['status', victim], aliceToken)), 'cancel from the jobs page: the CLI says cancelled');
  await page.click(`${victimRow} button.action.requeue`);
  await until('the victim queued again', async () => ['queued', 'running'].includes(await page.textContent(`${victimRow} td.state`)));
  check(['QUEUED', 'RUNNING', 'queued', 'running'].includes((await victimApi()).state), `requeue from the jobs page: the cancelled job is ${(await victimApi()).state} again`);
  await cancelVictim();
  page.once('dialog', (d) => d.accept());
  await page.click(`${victimRow} button.action.delete`);
  await until('the victim gone from the page', async () => (await page.$(victimRow)) === null);
  check((await context.request.get(`${base}/api/jobs/${victim}`)).status() === 404, 'delete from the jobs page: the API no longer knows the job');

  // Downloads: the EXR and the PNG of a succeeded job, as attachments.
  const exrLink = await page.getAttribute(`tr.job[data-id="${tinies[0]}"] a.action.exr`, 'href');
  const exr = await context.request.get(`${base}${exrLink}`);
  const exrBytes = await exr.body();
  check(exr.status() === 200 && exrBytes.subarray(0, 4).equals(Buffer.from([0x76, 0x2f, 0x31, 0x01])) && /attachment/.test(exr.headers()['content-disposition']),
    `the EXR link serves an OpenEXR file (${exrBytes.length} bytes, ${exr.headers()['content-disposition']})`);
  const png = await context.request.get(`${base}${await page.getAttribute(`tr.job[data-id="${tinies[0]}"] a.action.png`, 'href')}`);
  check(png.status() === 200 && (await png.body()).subarray(1, 4).toString() === 'PNG' && /attachment/.test(png.headers()['content-disposition']), 'the PNG link serves a PNG attachment');

  // The preview: a click shows it at 1:1, the exposure slider and the channel picker change it.
  await page.goto(`${base}/#/job/${tinies[2]}`);
  const sizes = () => page.evaluate(() => { const i = document.getElementById('preview'); return i.complete ? [i.naturalWidth, i.clientWidth] : [0, 0]; });
  await until('the preview', async () => (await sizes())[0] === 32);
  const fitted = await sizes();
  await page.click('#preview-box');
  await until('1:1', async () => { const [n, c] = await sizes(); return n === 32 && c === 32; });
  check(fitted[1] !== 32, `a click shows the preview at 1:1 (displayed ${fitted[1]} px wide, then 32, its natural width)`);
  const shown = async () => { const src = await page.getAttribute('#preview', 'src'); return (await context.request.get(`${base}${src}`)).body(); };
  const plain = await shown();
  await page.$eval('#exposure', (e) => { e.value = '3'; e.dispatchEvent(new Event('input')); e.dispatchEvent(new Event('change')); });
  await until('the brighter preview', async () => (await page.getAttribute('#preview', 'src')).includes('exposure=3'));
  const brighter = await shown();
  check(!brighter.equals(plain) && (await page.textContent('#exposure-value')) === '+3 EV', `the exposure slider changes the image (${plain.length} then ${brighter.length} bytes at +3 EV)`);
  await until('the channels', async () => (await page.$$eval('#channel option', (o) => o.map((e) => e.value))).includes('normal'));
  const channels = await page.$$eval('#channel option', (o) => o.map((e) => e.value));
  check(['beauty', 'A', 'B', 'albedo', 'normal'].every((c) => channels.includes(c)), `the channel picker lists the job's AOVs: ${channels.join(', ')}`);
  await page.selectOption('#channel', 'normal');
  await until('the normals', async () => (await page.getAttribute('#preview', 'src')).includes('channel=normal'));
  const normals = await shown();
  check(!normals.equals(brighter), 'switching the channel to normal changes the image');
  await page.screenshot({ path: join(shotsDir, 'job-aov.png'), fullPage: true });

  // Tasks filtered by state: the tiny job's 4 tasks are done, none runs.
  await page.selectOption('#task-state', 'done');
  await until('the done tasks', async () => (await page.textContent('#tasks-page')).startsWith('1–4 of 4'));
  check((await page.$$('tr.task.done')).length === 4, `tasks filtered by done: ${await page.textContent('#tasks-page')}`);
  await page.selectOption('#task-state', 'running');
  await until('no running tasks', async () => (await page.$$('tr.task')).length === 0);
  check((await page.textContent('#tasks-page')).startsWith('none'), `tasks filtered by running: ${await page.textContent('#tasks-page')}`);

  // Workers as an admin: alice's page has the buttons but the server refuses her; the admin
  // disables, drains and enables a worker from the workers page, and the CLI agrees.
  await page.goto(`${base}/#/workers`);
  await page.click('tr.worker[data-name="w2"] button.action.disable');
  await until('the refusal', async () => (await page.textContent('#workers-problem')).length > 0);
  check(/may not disable/.test(await page.textContent('#workers-problem')), `a submitter may not disable a worker: "${await page.textContent('#workers-problem')}"`);
  const admin = await browser.newContext({ viewport: { width: 1280, height: 900 } });
  const adminPage = await admin.newPage();
  adminPage.on('pageerror', (e) => errors.push(e.message));
  await adminPage.goto(base);
  await adminPage.waitForSelector('form#signin');
  await adminPage.fill('#token', readFileSync(adminToken, 'utf8').trim());
  await adminPage.click('form#signin button');
  await adminPage.waitForSelector('tr.job', { timeout: 15000 });
  await adminPage.goto(`${base}/#/workers`);
  const w2 = 'tr.worker[data-name="w2"]';
  const w2State = () => adminPage.textContent(`${w2} td.state`);
  await adminPage.waitForSelector(`${w2} button.action.disable`);
  await adminPage.click(`${w2} button.action.disable`);
  await until('w2 disabled', async () => (await w2State()) === 'disabled');
  check(/w2.*disabled/.test(cli(['workers'], adminToken)), 'disable from the workers page: the CLI lists w2 as disabled');
  await adminPage.click(`${w2} button.action.enable`);
  await until('w2 enabled', async () => ['idle', 'busy'].includes(await w2State()));
  await adminPage.click(`${w2} button.action.drain`);
  await until('w2 drained', async () => (await w2State()) === 'drained');
  check(true, 'drain from the workers page: the idle w2 is drained');
  await adminPage.click(`${w2} button.action.enable`);
  await until('w2 enabled again', async () => ['idle', 'busy'].includes(await w2State()));
  check(true, `enable from the workers page: w2 is ${await w2State()}`);
  await adminPage.screenshot({ path: join(shotsDir, 'workers-admin.png'), fullPage: true });

  check(errors.length === 0, `no errors on the pages${errors.length ? ': ' + errors.join('; ') : ''}`);
  console.log('dashboard e2e: all checks passed');
} catch (error) {
  console.error(`FAILED: ${error.stack || error}`);
  for (const child of children) console.error(`---- ${child.spawnargs.slice(0, 2).join(' ')}\n${child.log.slice(-4000)}`);
  process.exitCode = 1;
} finally {
  if (browser) await browser.close();
  for (const child of children) child.kill('SIGTERM');
  await new Promise((r) => setTimeout(r, 300));
  rmSync(dir, { recursive: true, force: true });
}
