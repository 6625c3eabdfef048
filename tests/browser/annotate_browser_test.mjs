#!/usr/bin/env node
// Browser test of the web annotation tool (`retarget annotate serve`, annotate/web/): two people
// in two browsers work through a tiny project at once, with a draw, a reload, an undo and a
// server killed with SIGKILL and restarted on the way; at the end the owner's export must hold
// exactly the triplets that were clicked.
//
//   node tests/browser/annotate_browser_test.mjs --retarget build/cli/retarget \
//     --fixture build/tests/annotation_fixture --tmp /tmp [--chromium /usr/bin/chromium] \
//     [--screenshot annotate.png] [--seed N] [--web annotate/web]
//
// --web DIR answers the five page files from DIR instead of the binary's embedded copies (for
// front-end work without a rebuild); --seed varies the left/right choices.
//
// Exit status: 0 pass, 1 fail (the message says which step and what), 77 skipped (no chromium
// binary, or playwright-core not installed: `npm install --no-audit --no-fund` in tests/browser).

import { existsSync } from 'node:fs';
import fs from 'node:fs/promises';
import path from 'node:path';
import { performance } from 'node:perf_hooks';
import { parseArgs } from 'node:util';

import { SKIP, TestFailure, check, findChromium, runMain } from './harness.mjs';
import { AnnotationServerProcess, runCommand } from './annotation_server_process.mjs';

const VIEWPORT = { width: 1280, height: 800 };
const STEP_TIMEOUT_MS = 30000; // a page reacting to one click; generous, for a loaded CI machine

// ---------------------------------------------------------------------------------------------
// Small utilities

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));


// A seeded generator (mulberry32), so a failing run can be repeated click for click.
function seededRandom(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

function median(values) {
  const v = [...values].sort((x, y) => x - y);
  if (!v.length) return NaN;
  const mid = Math.floor(v.length / 2);
  return v.length % 2 ? v[mid] : (v[mid - 1] + v[mid]) / 2;
}

let stepNumber = 0;

// Runs one named step, printing its outcome; a failure names the step.
async function step(title, fn) {
  const n = ++stepNumber;
  const t0 = performance.now();
  console.log(`[${n}] ${title}`);
  try {
    const note = await fn();
    console.log(`    [${n}] ok (${Math.round(performance.now() - t0)} ms)${note ? `: ${note}` : ''}`);
  } catch (e) {
    console.log(`    [${n}] FAILED`);
    e.message = `step ${n} (${title}): ${e.message}`;
    throw e;
  }
}

// ---------------------------------------------------------------------------------------------
// Browser contexts

let webDir = ''; // --web DIR: the pages come from DIR instead of the server's embedded copies

// A fresh browser context (its own localStorage: one person). With --web, the five page files
// are answered from the source folder, so front-end changes can be tried without a rebuild.
async function newContext(browser, options = {}) {
  const context = await browser.newContext({ viewport: VIEWPORT, ...options });
  context.setDefaultTimeout(STEP_TIMEOUT_MS); // every action and wait of the page
  if (webDir) {
    const files = { '/': 'index.html', '/overview': 'overview.html', '/static/app.js': 'app.js',
      '/static/overview.js': 'overview.js', '/static/style.css': 'style.css' };
    const types = { html: 'text/html', js: 'text/javascript', css: 'text/css' };
    await context.route((url) => url.pathname in files, async (route) => {
      const file = files[new URL(route.request().url()).pathname];
      const body = await fs.readFile(path.join(webDir, file));
      await route.fulfill({ body, contentType: `${types[file.split('.').pop()]}; charset=utf-8` });
    });
  }
  return context;
}

// ---------------------------------------------------------------------------------------------
// One person in one browser context

const clicks = []; // every answer given: {who, comparison, group, left, right, answer, undone, note}
const latencies = []; // ms from a click to the next comparison fully shown
const pageErrors = []; // uncaught exceptions in any page

// What a page shows, read from the DOM (ids and data attributes are the page's test contract).
function readPage() {
  const c = document.getElementById('comparison');
  const num = (v) => (v === undefined || v === '' ? null : Number(v));
  const view = document.body.dataset.view;
  return {
    view,
    state: c.dataset.state,
    shown: Number(c.dataset.shown || 0),
    comparison: num(c.dataset.comparison),
    left: num(c.dataset.left),
    right: num(c.dataset.right),
    group: num(c.dataset.group),
    done: num(document.getElementById('progress-done').textContent),
    remaining: num(document.getElementById('progress-left').textContent),
    rate: document.getElementById('progress-rate').textContent,
    status: document.getElementById('status').textContent,
    ready: view === 'work' && c.dataset.state === 'ready',
    waiting: view === 'work' && c.dataset.state === 'waiting',
    finished: view === 'finished',
  };
}

function describe(s) {
  if (s.ready) return `showing comparison ${s.comparison} (${s.left} vs ${s.right}, group ${s.group})`;
  return `view ${s.view}, state ${s.state}${s.status ? `, status "${s.status}"` : ''}`;
}

class Annotator {
  // via: 'keys' (arrow keys and 1/2/D/U, alternating) or 'buttons'.
  constructor(name, context, page, via) {
    Object.assign(this, { name, context, page, via, presses: 0 });
    page.on('pageerror', (e) => pageErrors.push(`${name}: ${e.message}`));
  }

  static async open(browser, name, via, baseUrl) {
    const context = await newContext(browser);
    const page = await context.newPage();
    await page.goto(`${baseUrl}/`);
    return new Annotator(name, context, page, via);
  }

  snap() {
    return this.page.evaluate(readPage);
  }

  // Signs in through the form; resolves once the first comparison (or waiting) is on screen.
  async signIn(name = this.name) {
    await this.page.fill('#signin-name', name);
    await this.page.click('#signin-button');
  }

  async press(action) {
    const n = this.presses++;
    if (this.via === 'buttons') {
      const id = { left: '#btn-left', right: '#btn-right', draw: '#btn-draw', undo: '#btn-undo' }[action];
      await this.page.click(id);
      return;
    }
    const keys = { left: ['ArrowLeft', '1'], right: ['ArrowRight', '2'], draw: ['ArrowDown', 'd'], undo: ['u', 'Backspace'] };
    await this.page.keyboard.press(keys[action][n % 2]);
  }

  // Waits until the page moved on from `before` (a ready comparison): another comparison shown
  // (data-shown counts displays), waiting, finished, or thrown back to the sign-in form.
  async waitForChange(before, timeout = STEP_TIMEOUT_MS) {
    try {
      await this.page.waitForFunction((prev) => {
        const c = document.getElementById('comparison');
        const view = document.body.dataset.view;
        return view === 'finished' || view === 'signin' || c.dataset.state === 'waiting' ||
          (c.dataset.state === 'ready' && c.dataset.shown !== prev);
      }, String(before.shown), { timeout, polling: 'raf' });
    } catch (e) {
      throw new TestFailure(`${this.name}'s page did not move on within ${timeout} ms from ${describe(before)}; ` +
        `now ${describe(await this.snap())}`);
    }
    const after = await this.snap();
    check(after.view !== 'signin', `${this.name} was sent back to the sign-in form: "${after.status}"`);
    return after;
  }

  // Waits for a comparison to be shown (after `shown` displays so far) or the finish.
  async waitForShown(shown, timeout = STEP_TIMEOUT_MS) {
    try {
      await this.page.waitForFunction((prev) => {
        const c = document.getElementById('comparison');
        return document.body.dataset.view === 'finished' ||
          (document.body.dataset.view === 'work' && c.dataset.state === 'ready' && Number(c.dataset.shown) > prev);
      }, shown, { timeout, polling: 'raf' });
    } catch {
      throw new TestFailure(`${this.name} was shown no comparison within ${timeout} ms; now ${describe(await this.snap())}`);
    }
    return this.snap();
  }

  // Answers what is shown (left | right | draw) and waits for the page to move on. Records the
  // click, and the time until the next comparison was fully shown.
  async act(answer, timeout = STEP_TIMEOUT_MS) {
    const before = await this.snap();
    check(before.ready, `${this.name} has nothing to answer: ${describe(before)}`);
    const t0 = performance.now();
    await this.press(answer);
    const after = await this.waitForChange(before, timeout);
    const ms = performance.now() - t0;
    check(!/no longer yours/.test(after.status),
      `${this.name}'s answer to comparison ${before.comparison} was refused: "${after.status}"`);
    const click = { who: this.name, comparison: before.comparison, group: before.group, left: before.left,
      right: before.right, answer, undone: false, note: '' };
    clicks.push(click);
    if (after.ready) latencies.push(ms);
    return { before, after, click, ms };
  }
}

// ---------------------------------------------------------------------------------------------
// The run

async function main() {
  const { values: args } = parseArgs({
    options: {
      retarget: { type: 'string' },
      fixture: { type: 'string' },
      tmp: { type: 'string' },
      chromium: { type: 'string' },
      screenshot: { type: 'string' },
      seed: { type: 'string', default: '7' }, // the clicks' left/right choices
      web: { type: 'string' }, // serve the pages from this folder (annotate/web) instead
    },
  });
  webDir = args.web ? path.resolve(args.web) : '';
  if (!args.retarget || !args.fixture || !args.tmp) {
    console.error('usage: annotate_browser_test.mjs --retarget PATH --fixture PATH --tmp DIR ' +
      '[--chromium PATH] [--screenshot OUT.png] [--seed N] [--web DIR]');
    return 1;
  }

  // Skips: no browser, or no playwright-core.
  const chromiumPath = findChromium(args.chromium);
  if (!chromiumPath) return SKIP;
  let chromium;
  try {
    ({ chromium } = await import('playwright-core'));
  } catch (e) {
    console.log('SKIP: playwright-core is not installed (run `npm install --no-audit --no-fund` in ' +
      `tests/browser): ${e.message.split('\n')[0]}`);
    return SKIP;
  }
  for (const [flag, file] of [['--retarget', args.retarget], ['--fixture', args.fixture]]) {
    check(existsSync(file), `${flag} ${file}: no such file (build the project first)`);
  }

  const started = performance.now();
  const random = seededRandom(Number(args.seed));
  const side = () => (random() < 0.5 ? 'left' : 'right');
  const scratch = path.resolve(args.tmp, `annotate_browser_${process.pid}`);
  let project = '';
  let server = null;
  let browser = null;

  try {
    await step('fixture project and server start', async () => {
      await fs.rm(scratch, { recursive: true, force: true });
      await fs.mkdir(scratch, { recursive: true });
      // The fixture writes its inputs and the project under the folder and prints the project's path.
      const folder = path.join(scratch, 'fixture');
      const printed = (await runCommand(args.fixture, [folder])).trim().split('\n').pop() || '';
      project = [printed, path.join(folder, 'project'), folder]
        .find((p) => p && existsSync(path.join(p, 'project.yaml')));
      check(project, `${args.fixture} ${folder} made no annotation project (no project.yaml; it printed "${printed}")`);
      server = await new AnnotationServerProcess({ retarget: args.retarget, project }).start();
      return server.baseUrl;
    });
    browser = await chromium.launch({ executablePath: chromiumPath, headless: true, args: ['--no-sandbox'] });

    // 7. The README's picture: a comparison on screen, turntables running.
    if (args.screenshot) {
      await step(`screenshot of the annotation page -> ${args.screenshot}`, async () => {
        const demo = await Annotator.open(browser, 'demo', 'buttons', server.baseUrl);
        await demo.signIn();
        const s = await demo.waitForShown(0);
        check(s.ready, `demo was shown no comparison: ${describe(s)}`);
        // The turntable runs: the anchor canvas takes several pictures within half a second (12
        // frames/s; distinct samples, since ping-pong comes back to a frame it showed).
        const pictures = await demo.page.evaluate(async () => {
          const seen = new Set();
          for (let i = 0; i < 8; i++) {
            seen.add(document.getElementById('canvas-anchor').toDataURL());
            await new Promise((resolve) => setTimeout(resolve, 60));
          }
          return seen.size;
        });
        check(pictures >= 3, `the turntable does not animate: ${pictures} distinct anchor pictures in 0.5 s`);
        await fs.mkdir(path.dirname(path.resolve(args.screenshot)), { recursive: true });
        await demo.page.screenshot({ path: args.screenshot });
        // Sign out hands the comparison back and returns to the form.
        await demo.page.click('#signout');
        await demo.page.waitForSelector('#signin-name', { state: 'visible', timeout: STEP_TIMEOUT_MS });
        await demo.context.close();
      });
    }

    // 1. Two people sign in through the form (a name already signed in is refused).
    const ana = await Annotator.open(browser, 'ana', 'keys', server.baseUrl);
    const ben = await Annotator.open(browser, 'ben', 'buttons', server.baseUrl);
    await step('ana and ben sign in; a second sign-in as "ana" is refused', async () => {
      await ana.signIn();
      const a = await ana.waitForShown(0);
      check(a.ready, `ana: ${describe(a)}`);
      await ben.signIn('ana');
      await ben.page.waitForFunction(() => /signed in/.test(document.getElementById('status').textContent),
        null, { timeout: STEP_TIMEOUT_MS });
      check((await ben.snap()).view === 'signin', 'the refused sign-in left the form');
      await ben.signIn('ben');
      const b = await ben.waitForShown(0);
      check(b.ready, `ben: ${describe(b)}`);
      check(a.comparison !== b.comparison, `ana and ben were both given comparison ${a.comparison}`);
      return `ana: ${a.comparison}, ben: ${b.comparison}; ${a.remaining} comparisons to go`;
    });

    const done = { reload: false, kill: false, undo: false, draw: null };
    const answered = () => clicks.filter((c) => !c.undone && c.answer !== 'draw').length;

    // 2. A draw goes to the other person, who decides it; the drawer never sees it meanwhile.
    async function drawScenario(drawer, other) {
      await step(`${drawer.name} draws; the comparison goes to ${other.name}`, async () => {
        const x = (await drawer.snap()).comparison;
        const { after } = await drawer.act('draw');
        check(!(after.ready && after.comparison === x), `${drawer.name} was shown ${x} again right after drawing it`);
        let o = await other.snap();
        if (o.ready) {
          const r = await other.act(side());
          o = r.after.ready ? r.after : await other.waitForShown(r.after.shown);
        } else {
          o = await other.waitForShown(o.shown); // waiting: its poll (every 1.5 s) picks it up
        }
        check(o.ready && o.comparison === x,
          `after ${drawer.name} drew comparison ${x}, ${other.name} was next shown ${describe(o)}`);
        const d = await drawer.snap();
        check(!(d.ready && d.comparison === x), `${drawer.name} is shown ${x} again before ${other.name} decided it`);
        const r = await other.act(side());
        r.click.note = `decides ${drawer.name}'s draw`;
        done.draw = { comparison: x, drawer: drawer.name, decider: other.name, answer: r.click.answer };
        return `comparison ${x}: ${drawer.name} drew, ${other.name} chose ${r.click.answer}`;
      });
    }

    // 3. A reload keeps the sign-in, the progress and the comparison on screen (its lease).
    async function reloadScenario() {
      await step('reload ana\'s page mid-way', async () => {
        const before = await ana.snap();
        await ana.page.reload();
        const after = await ana.waitForShown(0);
        check(after.view === 'work', `after the reload ana is at ${describe(after)}`);
        check(after.comparison === before.comparison,
          `ana was shown comparison ${before.comparison} before the reload and ${after.comparison} after`);
        check(after.done === before.done, `#progress-done was ${before.done} before the reload, ${after.done} after`);
        done.reload = true;
        return `comparison ${after.comparison} again, ${after.done} done`;
      });
    }

    // 4. SIGKILL the server; ben clicks while it is down; restart on the same port; both go on.
    async function killScenario() {
      await step('SIGKILL the server, click while it is down, restart on the same port', async () => {
        const port = server.port;
        await server.kill();
        const before = await ben.snap();
        const t0 = performance.now();
        await ben.press('left');
        await ben.page.waitForFunction(() => /connection/i.test(document.getElementById('status').textContent),
          null, { timeout: STEP_TIMEOUT_MS });
        check(await ben.page.isDisabled('#btn-right'), 'the buttons stay enabled while an answer is in flight');
        server = await new AnnotationServerProcess({ retarget: args.retarget, project, port }).start();
        check(server.port === port, `restarted on port ${server.port}, not ${port}`);
        const after = await ben.waitForChange(before, 30000);
        clicks.push({ who: 'ben', comparison: before.comparison, group: before.group, left: before.left,
          right: before.right, answer: 'left', undone: false, note: 'clicked while the server was down' });
        const a = await ana.act(side()); // ana's page was idle through it all
        done.kill = true;
        return `ben's answer went through ${Math.round(performance.now() - t0)} ms after the click ` +
          `(${describe(after)}); ana went on to ${describe(a.after)}`;
      });
    }

    // 5. Undo by key: the previous comparison comes back and is answered the other way.
    async function undoScenario(last) {
      await step('ana undoes her last answer (key U) and answers it the other way', async () => {
        const before = last.after;
        await ana.page.keyboard.press('u');
        const s = await ana.waitForChange(before);
        check(s.ready && s.comparison === last.click.comparison && s.left === last.click.left &&
          s.right === last.click.right,
          `after undo ana should see comparison ${last.click.comparison} again, but: ${describe(s)}`);
        check(s.done === before.done - 1, `#progress-done went from ${before.done} to ${s.done} on undo`);
        last.click.undone = true;
        const corrected = last.click.answer === 'left' ? 'right' : 'left';
        const r = await ana.act(corrected);
        r.click.note = 'corrected after undo';
        done.undo = true;
        return `comparison ${last.click.comparison}: ${last.click.answer} -> ${corrected}`;
      });
    }

    await step('ana (keys) and ben (buttons) work concurrently until every group is finished', async () => {
      let turn = 0;
      for (let iteration = 0; ; iteration++) {
        check(iteration < 400, 'the run did not finish within 400 steps');
        const [a, b] = await Promise.all([ana.snap(), ben.snap()]);
        if (a.finished && b.finished) break;
        check(!(a.ready && b.ready && a.comparison === b.comparison),
          `ana and ben are both shown comparison ${a.comparison}`);
        const remaining = Math.min(a.remaining ?? Infinity, b.remaining ?? Infinity);

        // The draw, when it is sure to go to the other person next: nothing else is open for them.
        if (!done.draw) {
          if (a.ready && (b.waiting || (b.ready && remaining === 2))) {
            await drawScenario(ana, ben);
            continue;
          }
          if (remaining === 1 && b.ready && a.waiting) {
            await drawScenario(ben, ana); // ben holds the last one: roles swap
            continue;
          }
        }
        if (!done.reload && answered() >= 3 && a.ready) {
          await reloadScenario();
          continue;
        }
        if (!done.kill && done.reload && answered() >= 5 && a.ready && b.ready) {
          await killScenario();
          continue;
        }

        // An ordinary turn: alternate; with three left, ben first (so ana keeps one for the draw).
        let actor = null;
        if (a.ready && b.ready) actor = remaining === 3 ? ben : turn++ % 2 ? ben : ana;
        else if (a.ready) actor = ana;
        else if (b.ready) actor = ben;
        if (!actor) {
          await sleep(100); // loading, or both waiting for a poll
          continue;
        }
        const result = await actor.act(side());
        if (actor === ana && !done.undo && answered() >= 2 && result.after.ready) await undoScenario(result);
      }
      for (const [what, ok] of Object.entries(done)) check(ok, `the ${what} scenario never ran`);
      return `${clicks.length} clicks (${clicks.filter((c) => c.who === 'ana').length} ana, ` +
        `${clicks.filter((c) => c.who === 'ben').length} ben)`;
    });

    await step('both pages show the finish; the rate is shown; the draw was not re-shown', async () => {
      for (const who of [ana, ben]) {
        const s = await who.snap();
        check(s.finished && /thank you/i.test(await who.page.textContent('#finished')),
          `${who.name}: ${describe(s)}`);
        check(s.remaining === 0, `${who.name}'s #progress-left is ${s.remaining}`);
      }
      const rate = (await ben.snap()).rate;
      check(/^\d+$/.test(rate), `ben's #progress-rate is "${rate}" after many answers`);
      const drawer = done.draw.drawer;
      const reshown = clicks.filter((c) => c.comparison === done.draw.comparison);
      check(reshown.length === 2 && reshown[0].who === drawer && reshown[1].who !== drawer,
        `comparison ${done.draw.comparison} was answered as ${JSON.stringify(reshown)}`);
      return `ben: ${rate} comparisons per minute`;
    });

    // 6. The export holds exactly the clicked decisions.
    await step('the export equals the clicks; it needs the owner token', async () => {
      const url = `${server.baseUrl}/api/export?derived=0`;
      const res = await fetch(url, { headers: { Authorization: `Bearer ${server.ownerToken}` } });
      const csv = await res.text();
      check(res.ok, `GET /api/export?derived=0: ${res.status} ${csv}`);
      const [header, ...lines] = csv.trim().split('\n');
      check(header === 'group,anchor,positive,negative,derived,tie_break', `CSV header: ${header}`);
      const exported = lines.map((line) => {
        const f = line.split(',');
        return { key: `${f[0]}:${f[f.length - 4]}>${f[f.length - 3]}`, derived: f[f.length - 2], tieBreak: f[f.length - 1] };
      });
      check(exported.every((t) => t.derived === '0' && t.tieBreak === '0'),
        `derived or tie-break rows in the direct export:\n${csv}`);
      const expected = clicks.filter((c) => !c.undone && c.answer !== 'draw').map((c) => {
        const [positive, negative] = c.answer === 'left' ? [c.left, c.right] : [c.right, c.left];
        return `${c.group}:${positive}>${negative}`;
      });
      const got = new Set(exported.map((t) => t.key));
      const want = new Set(expected);
      const missing = [...want].filter((k) => !got.has(k));
      const extra = [...got].filter((k) => !want.has(k));
      check(!missing.length && !extra.length && exported.length === expected.length,
        `export and clicks differ: missing ${JSON.stringify(missing)}, unexpected ${JSON.stringify(extra)} ` +
        `(${exported.length} rows, ${expected.length} decided clicks)\nclicks: ${JSON.stringify(clicks)}`);
      const total = (await ana.snap()).done + (await ben.snap()).done;
      check(total === expected.length, `the pages count ${total} decisions, the clicks ${expected.length}`);

      const anonymous = await fetch(url);
      check(anonymous.status === 401, `GET /api/export without a token gave ${anonymous.status}, not 401`);
      const wrong = await fetch(url, { headers: { Authorization: 'Bearer not-the-owner-token' } });
      check(wrong.status === 401 || wrong.status === 403, `a wrong owner token gave ${wrong.status}`);
      const withDerived = await fetch(`${server.baseUrl}/api/export?derived=1`,
        { headers: { Authorization: `Bearer ${server.ownerToken}` } });
      const all = (await withDerived.text()).trim().split('\n').slice(1);
      check(all.length >= lines.length, `derived=1 has ${all.length} rows, fewer than derived=0's ${lines.length}`);
      return `${lines.length} direct triplets, ${all.length} with derived ones; no token: 401`;
    });

    await step('the overview page shows every group done; downloads work', async () => {
      const context = await newContext(browser, { acceptDownloads: true });
      const page = await context.newPage();
      page.on('pageerror', (e) => pageErrors.push(`overview: ${e.message}`));
      await page.goto(`${server.baseUrl}/overview#token=${server.ownerToken}`);
      await page.waitForSelector('#overview-summary[data-finished="true"]', { timeout: STEP_TIMEOUT_MS });
      const summary = await page.textContent('#overview-summary');
      check(/all 4 groups done/i.test(summary), `#overview-summary: "${summary}"`);
      check(await page.evaluate(() => location.hash === ''), 'the owner token stays in the address bar');
      const groups = await page.$$eval('#groups-table tbody tr', (rows) => rows.map((r) => r.cells[3].textContent));
      check(groups.length === 4 && groups.every((g) => /^(\d+)\/\1$/.test(g)), `group rows: ${groups}`);
      // ben's decisions, by clicking his row.
      await page.click('#annotators-table tbody tr[data-name="ben"]');
      await page.waitForSelector('#decisions:not([hidden]) #decisions-table tbody tr', { timeout: STEP_TIMEOUT_MS });
      const rows = await page.$$eval('#decisions-table tbody tr', (r) => r.length);
      const bens = clicks.filter((c) => c.who === 'ben').length;
      check(rows === bens, `ben's decisions table has ${rows} rows, ben clicked ${bens} times`);
      // The direct export through the button (fetched with the token, saved from a blob link).
      const [download] = await Promise.all([page.waitForEvent('download'), page.click('#export-direct')]);
      const saved = await fs.readFile(await download.path(), 'utf8');
      check(saved.startsWith('group,anchor,positive,negative'), `downloaded file: ${saved.slice(0, 80)}`);
      await context.close();
      return `"${summary}", ${download.suggestedFilename()} saved`;
    });

    await step('the owner resets ben\'s sign-in; his page asks him to sign in again', async () => {
      const context = await newContext(browser);
      const page = await context.newPage();
      page.on('pageerror', (e) => pageErrors.push(`overview: ${e.message}`));
      await page.goto(`${server.baseUrl}/overview#token=${server.ownerToken}`);
      page.once('dialog', (dialog) => dialog.accept()); // the "are you sure" confirm
      await page.click('#annotators-table tbody tr[data-name="ben"] button');
      await page.waitForFunction(() => /sign-in reset/.test(document.getElementById('status').textContent),
        null, { timeout: STEP_TIMEOUT_MS });
      await context.close();
      await ben.page.reload();
      await ben.page.waitForSelector('#signin-name', { state: 'visible', timeout: STEP_TIMEOUT_MS });
      const s = await ben.snap();
      check(/sign in again/.test(s.status), `after the reset ben's page says "${s.status}"`);
      check(await ben.page.inputValue('#signin-name') === 'ben', 'the sign-in form forgot ben\'s name');
      await ben.page.click('#signin-button'); // the name is free again
      await ben.page.waitForSelector('#finished:not([hidden])', { timeout: STEP_TIMEOUT_MS });
    });

    await step('ana signs out', async () => {
      await ana.page.click('#signout');
      await ana.page.waitForSelector('#signin-name', { state: 'visible', timeout: STEP_TIMEOUT_MS });
      const stored = await ana.page.evaluate(() => localStorage.length);
      check(stored === 0, 'the session is still in localStorage after signing out');
    });

    check(!pageErrors.length, `uncaught errors in the pages:\n${pageErrors.join('\n')}`);
    const undone = clicks.filter((c) => c.undone).length;
    console.log(`clicks: ${clicks.length} (${undone} undone, ${clicks.filter((c) => c.answer === 'draw').length} draw)`);
    console.log(`median click -> next comparison fully shown: ${median(latencies).toFixed(0)} ms ` +
      `over ${latencies.length} clicks (max ${Math.max(...latencies).toFixed(0)} ms)`);
    console.log(`PASS in ${((performance.now() - started) / 1000).toFixed(1)} s`);
    await fs.rm(scratch, { recursive: true, force: true });
    return 0;
  } catch (e) {
    if (existsSync(scratch)) e.message += `\n(the project is kept for a look: ${scratch})`;
    throw e;
  } finally {
    if (browser) await browser.close().catch(() => {});
    if (server) await server.stop('SIGTERM');
  }
}

await runMain(main);
