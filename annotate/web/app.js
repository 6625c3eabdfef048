// The annotator's page of `retarget annotate serve`: sign in with a name, then answer one
// comparison after another - which of two avatar expressions (A, B) looks more like the human
// expression in the middle - until every group's tournament has a champion.
//
// The server is the only source of truth: an answer counts once its response arrives (it is
// committed to SQLite before that), so the page never moves on optimistically, and a request
// that fails for want of a connection (the server restarting) is simply retried. The sign-in
// {name, token} lives in localStorage so a reload continues as the same person, and the
// comparison on screen is leased to us, so a reload shows it again.

import { ApiError, api as callServer, request } from './api.js';

const $ = (id) => document.getElementById(id);

const SESSION_KEY = 'retarget.annotate.session';
const POLL_MS = 1500; // waiting for others: how often to ask /api/next again
const FPS = 12; // turntable frames per second
const PREFETCH_CONCURRENCY = 2; // background image fetches at once (the visible ones go first)

// ---------------------------------------------------------------------------------------------
// State

let session = readSession(); // {name, token} or null

const state = {
  view: 'boot',
  shown: null, // the assignment on screen and answerable, or null
  busy: false, // a request that decides what is shown next is in flight
  showSeq: 0, // bumps on every display() so a late image load cannot show a stale comparison
  epoch: 0, // bumps on sign-in/out: loops and responses of an old session are dropped
  runEpoch: 0, // the epoch the request in flight belongs to
  pollTimer: 0,
  renewTimer: 0,
  answerTimes: [], // performance.now() of each answer this page session (for the rate)
  lastProgress: null,
};

function readSession() {
  try {
    const s = JSON.parse(localStorage.getItem(SESSION_KEY) || 'null');
    return s && typeof s.token === 'string' && typeof s.name === 'string' ? s : null;
  } catch {
    return null;
  }
}

function writeSession(s) {
  session = s;
  if (s) localStorage.setItem(SESSION_KEY, JSON.stringify(s));
  else localStorage.removeItem(SESSION_KEY);
}

// ---------------------------------------------------------------------------------------------
// HTTP

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// One JSON call with this person's session token (api.js).
const api = (method, path, body) => callServer(method, path, { token: session && session.token, body });

// Runs fn until it gets a response: a lost connection (the server being restarted) is retried
// with a short back-off instead of bothering the person. Other errors propagate.
async function withRetry(fn) {
  const epoch = state.epoch;
  for (let attempt = 0; ; attempt++) {
    try {
      const result = await fn(attempt);
      if (attempt > 0) clearStatus('connection');
      return result;
    } catch (e) {
      if (!(e instanceof ApiError) || e.status !== 0) throw e;
      if (epoch !== state.epoch) throw new ApiError(-1, 'signed out');
      showStatus('Connection to the server lost - retrying...', 'warn', { key: 'connection' });
      await sleep(Math.min(500 * (attempt + 1), 3000));
      if (epoch !== state.epoch) throw new ApiError(-1, 'signed out');
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Status line

let statusTimer = 0;
let statusKey = '';

// kind: info | warn | error | ok. A message with `ms` clears itself; `key` lets clearStatus(key)
// remove just that message (and not a newer one).
function showStatus(text, kind = 'info', { ms = 0, key = '' } = {}) {
  const el = $('status');
  el.textContent = text;
  el.className = `show ${kind}`;
  statusKey = key;
  clearTimeout(statusTimer);
  if (ms) statusTimer = setTimeout(() => clearStatus(), ms);
}

function clearStatus(key) {
  if (key !== undefined && key !== statusKey) return;
  clearTimeout(statusTimer);
  $('status').className = '';
  $('status').textContent = '';
  statusKey = '';
}

// ---------------------------------------------------------------------------------------------
// Views

function setView(view) {
  state.view = view;
  document.body.dataset.view = view;
  $('signin').hidden = view !== 'signin';
  $('work').hidden = view !== 'work';
  $('finished').hidden = view !== 'finished';
  $('stats').hidden = view === 'signin' || view === 'boot';
  $('who').hidden = !session || view === 'signin';
  $('who-name').textContent = session ? session.name : '';
  // Keys go to the page, not to a sign-in field that has just been hidden.
  const focused = document.activeElement;
  if (view !== 'signin' && focused instanceof HTMLElement && focused.closest('#signin')) focused.blur();
}

function showSignin(message, kind = 'warn') {
  stopTimers();
  state.shown = null;
  setView('signin');
  if (session && !$('signin-name').value) $('signin-name').value = session.name;
  $('signin-button').disabled = false;
  if (message) showStatus(message, kind);
  else clearStatus();
  $('signin-name').focus();
}

function stopTimers() {
  clearTimeout(state.pollTimer);
  clearTimeout(state.renewTimer);
  state.pollTimer = state.renewTimer = 0;
}

function setButtons(enabled) {
  for (const id of ['btn-left', 'btn-right', 'btn-draw']) $(id).disabled = !enabled;
  $('btn-undo').disabled = state.busy || state.view !== 'work';
}

function updateProgress(p) {
  if (!p) return;
  state.lastProgress = p;
  $('progress-done').textContent = String(p.done);
  $('progress-done').title = `${p.done} decided, ${p.draws} passed on`;
  $('progress-left').textContent = String(p.left);
  $('progress-left').title = `${p.total - p.left} of ${p.total} comparisons decided`;
  $('progress-groups').textContent = `${p.groups_done}/${p.groups}`;
}

// Comparisons per minute over this page session, from the answers' timestamps.
function updateRate() {
  const t = state.answerTimes;
  const el = $('progress-rate');
  if (t.length < 2) {
    el.textContent = '-';
    return;
  }
  const minutes = (t[t.length - 1] - t[0]) / 60000;
  el.textContent = minutes > 0 ? String(Math.round((t.length - 1) / minutes)) : '-';
}

// ---------------------------------------------------------------------------------------------
// Images: turntable sprites fetched once per page load with the Authorization header.

const sprites = new Map(); // url -> Promise<Sprite>

// Sprite = {img, frames, frameWidth, frameHeight}: F square frames side by side, yaw -40..+40 deg.
function loadSprite(url) {
  let p = sprites.get(url);
  if (!p) {
    p = fetchSprite(url);
    sprites.set(url, p);
    p.catch(() => sprites.delete(url)); // let a later attempt fetch it again
  }
  return p;
}

async function fetchSprite(url) {
  const res = await request('GET', url, { token: session && session.token, cache: 'default' });
  const header = parseInt(res.headers.get('X-Turntable-Frames') || '', 10);
  const blob = await res.blob();
  const img = new Image();
  img.src = URL.createObjectURL(blob);
  await img.decode();
  const h = img.naturalHeight;
  const frames = header > 0 ? header : Math.max(1, Math.round(img.naturalWidth / h));
  return { img, frames, frameWidth: img.naturalWidth / frames, frameHeight: h };
}

const prefetchQueue = [];
let prefetchActive = 0;

// Fetches the group's other candidates in the background, a couple at a time.
function prefetch(urls) {
  for (const url of urls || []) {
    if (!sprites.has(url) && !prefetchQueue.includes(url)) prefetchQueue.push(url);
  }
  while (prefetchActive < PREFETCH_CONCURRENCY && prefetchQueue.length) {
    const url = prefetchQueue.shift();
    if (sprites.has(url)) continue;
    prefetchActive++;
    loadSprite(url)
      .catch(() => {})
      .finally(() => {
        prefetchActive--;
        prefetch([]);
      });
  }
}

// ---------------------------------------------------------------------------------------------
// The turntable: one timer animates all three canvases in lock-step, ping-pong through the frames.

const turntable = {
  canvases: { left: null, anchor: null, right: null },
  sprites: null, // {left, anchor, right} of the comparison on screen
  paused: false,
  start: 0, // performance.now() at tick 0
  pausedTick: 0,
  drawnTick: -1,
};

function currentTick(now) {
  return turntable.paused ? turntable.pausedTick : Math.floor(((now - turntable.start) * FPS) / 1000);
}

function drawTurntable(tick) {
  const s = turntable.sprites;
  if (!s) return;
  // Phase along the sprite with the most frames; the others follow it proportionally.
  const most = Math.max(s.left.frames, s.anchor.frames, s.right.frames);
  let pos = 0;
  if (most > 1) {
    const period = 2 * (most - 1);
    const k = ((tick % period) + period) % period;
    pos = k <= most - 1 ? k : period - k;
  }
  for (const side of ['left', 'anchor', 'right']) {
    const sprite = s[side];
    const canvas = turntable.canvases[side];
    const frame = most > 1 ? Math.round((pos * (sprite.frames - 1)) / (most - 1)) : 0;
    const ctx = canvas.getContext('2d');
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    ctx.drawImage(sprite.img, frame * sprite.frameWidth, 0, sprite.frameWidth, sprite.frameHeight,
      0, 0, canvas.width, canvas.height);
  }
  turntable.drawnTick = tick;
}

function animate(now) {
  requestAnimationFrame(animate);
  const tick = currentTick(now);
  if (tick !== turntable.drawnTick) drawTurntable(tick);
}

// Puts new sprites on the canvases, starting from the frontal frame (yaw 0) turning right.
function setTurntable(s) {
  for (const side of ['left', 'anchor', 'right']) {
    const canvas = turntable.canvases[side];
    const w = Math.round(s[side].frameWidth);
    const h = s[side].frameHeight;
    if (canvas.width !== w || canvas.height !== h) {
      canvas.width = w;
      canvas.height = h;
    }
  }
  turntable.sprites = s;
  const most = Math.max(s.left.frames, s.anchor.frames, s.right.frames);
  const startTick = Math.floor((most - 1) / 2);
  if (turntable.paused) turntable.pausedTick = startTick;
  turntable.start = performance.now() - (startTick * 1000) / FPS;
  drawTurntable(startTick);
}

function togglePause() {
  const now = performance.now();
  if (turntable.paused) {
    turntable.start = now - (turntable.pausedTick * 1000) / FPS;
    turntable.paused = false;
  } else {
    turntable.pausedTick = currentTick(now);
    turntable.paused = true;
  }
  $('pause-text').textContent = turntable.paused ? 'resume turntable' : 'pause turntable';
  $('comparison').classList.toggle('paused', turntable.paused);
}

// ---------------------------------------------------------------------------------------------
// The flow

// Acts on a response carrying {assignment, progress, waiting, finished}; resolves once what it
// asks for is on screen.
async function apply(resp) {
  if (state.runEpoch !== state.epoch) return; // signed out while the request was in flight
  updateProgress(resp.progress);
  clearTimeout(state.pollTimer);
  if (resp.assignment) {
    await display(resp.assignment);
  } else if (resp.finished) {
    showFinished();
  } else {
    showWaiting(resp.waiting || 0);
  }
}

// Shows an assignment once its three images are loaded; the previous one stays dimmed
// (and unanswerable) behind a "loading" overlay until then.
async function display(a) {
  if (state.runEpoch !== state.epoch) return;
  const seq = ++state.showSeq;
  const epoch = state.epoch;
  state.shown = null;
  clearTimeout(state.renewTimer);
  setView('work');
  setButtons(false);
  const box = $('comparison');
  box.dataset.state = 'loading';
  $('overlay-text').textContent = 'loading';

  const urls = [a.images.left, a.images.anchor, a.images.right];
  const loaded = await withRetry(() => Promise.all(urls.map(loadSprite)));
  if (seq !== state.showSeq || epoch !== state.epoch) return; // something newer took over
  setTurntable({ left: loaded[0], anchor: loaded[1], right: loaded[2] });

  state.shown = a;
  box.dataset.comparison = String(a.comparison);
  box.dataset.left = String(a.left);
  box.dataset.right = String(a.right);
  box.dataset.group = String(a.group);
  box.dataset.state = 'ready';
  box.dataset.shown = String(Number(box.dataset.shown || 0) + 1);
  $('task-prompt').hidden = false;
  $('task-label').textContent = a.label;
  $('task-round').textContent = `round ${a.round}`;
  setButtons(!state.busy);
  if (state.view === 'work' && statusKey === 'waiting') clearStatus();

  prefetch(a.prefetch);
  scheduleRenewal(a);
}

function clearShown(stateName, overlayText) {
  state.shown = null;
  state.showSeq++;
  clearTimeout(state.renewTimer);
  const box = $('comparison');
  box.dataset.state = stateName;
  for (const k of ['comparison', 'left', 'right', 'group']) delete box.dataset[k];
  $('overlay-text').textContent = overlayText;
  setButtons(false);
}

function showWaiting(waiting) {
  setView('work');
  clearShown('waiting', 'waiting for others');
  $('task-prompt').hidden = true;
  $('task-label').textContent = 'waiting for others';
  $('task-round').textContent = '';
  const what = waiting === 1 ? '1 comparison is' : `${waiting} comparisons are`;
  showStatus(`Nothing for you right now: ${what} with other annotators. Waiting for others...`, 'info',
    { key: 'waiting' });
  schedulePoll(state.epoch);
}

function schedulePoll(epoch) {
  clearTimeout(state.pollTimer);
  state.pollTimer = setTimeout(() => {
    if (epoch !== state.epoch || state.shown) return;
    if (state.busy) schedulePoll(epoch); // e.g. an undo in flight: look again later
    else void run(next);
  }, POLL_MS);
}

function showFinished() {
  clearShown('finished', 'finished');
  stopTimers();
  setView('finished');
  const p = state.lastProgress;
  $('finished-summary').textContent = p
    ? `You decided ${p.done} comparison${p.done === 1 ? '' : 's'}; all ${p.groups} groups are done.`
    : '';
  showStatus('Finished - every group is done. Thank you!', 'ok', { key: 'finished' });
}

// Leases run out (lease_seconds); asking /api/next again renews the one we hold, as long as
// the person is at the page (a key, click or pointer move within the lease): a tab left open
// must not keep a comparison from everyone else. If the lease was lost meanwhile, whatever the
// server gives instead is shown (or the next answer gets a 409 and moves on).
let lastActivity = performance.now();
for (const type of ['keydown', 'pointerdown', 'pointermove']) {
  document.addEventListener(type, () => (lastActivity = performance.now()), { passive: true, capture: true });
}

function scheduleRenewal(a) {
  const seconds = Number(a.lease_seconds) || 120;
  state.renewTimer = setTimeout(async () => {
    if (state.busy || state.shown !== a) return;
    if (performance.now() - lastActivity > seconds * 1000) {
      scheduleRenewal(a); // away: let the lease run out, look again later
      return;
    }
    state.busy = true;
    state.runEpoch = state.epoch;
    try {
      const resp = await api('POST', '/api/next');
      if (resp.assignment && resp.assignment.comparison === a.comparison && state.shown === a) {
        updateProgress(resp.progress);
        scheduleRenewal(a);
      } else {
        await apply(resp);
      }
    } catch (e) {
      if (e.status === 401) return endSession();
      if (state.shown === a) scheduleRenewal(a); // try again later
    } finally {
      state.busy = false;
      setButtons(!!state.shown);
    }
  }, seconds * 500);
}

// Runs one step of the flow with the busy flag held, so no second request can start meanwhile.
async function run(step, ...args) {
  if (state.busy) return;
  state.busy = true;
  state.runEpoch = state.epoch;
  setButtons(false);
  try {
    await step(...args);
  } catch (e) {
    handleError(e);
  } finally {
    state.busy = false;
    setButtons(!!state.shown);
  }
}

async function next() {
  await apply(await withRetry(() => api('POST', '/api/next')));
}

async function answer(which) {
  const a = state.shown;
  if (!a) return;
  flash(which);
  state.shown = null; // no second answer to the same comparison
  let resp;
  try {
    resp = await withRetry(() => api('POST', '/api/answer', { comparison: a.comparison, answer: which }));
  } catch (e) {
    if (e.status === 409 || e.status === 404) {
      // Decided by someone else, or our lease ran out and it was taken: move on.
      showStatus(`That comparison is no longer yours (${e.message}) - here is another.`, 'warn', { ms: 3500 });
      await next();
      return;
    }
    state.shown = a;
    throw e;
  }
  state.answerTimes.push(performance.now());
  updateRate();
  if (resp.result && resp.result.status === 'requeued') {
    showStatus('Passed on to someone else.', 'info', { ms: 1800 });
  } else if (resp.result && resp.result.status === 'tie_break') {
    showStatus('A repeated draw - settled by the geometric tie-break.', 'info', { ms: 2500 });
  }
  await apply(resp);
}

async function undo() {
  let resp;
  try {
    resp = await withRetry(() => api('POST', '/api/undo'));
  } catch (e) {
    if (e.status === 409 || e.status === 404) {
      showStatus(`Cannot undo: ${e.message}`, 'warn', { ms: 3000 });
      return;
    }
    throw e;
  }
  state.answerTimes.pop();
  updateRate();
  updateProgress(resp.progress);
  showStatus('Undone - answer it again.', 'info', { ms: 2000 });
  await display(resp.assignment);
}

function handleError(e) {
  if (e.status === -1) return; // the session this belonged to is gone
  if (e.status === 401) return endSession();
  showStatus(e.message, 'error');
}

function endSession() {
  state.epoch++;
  if (session) $('signin-name').value = session.name;
  writeSession(null);
  showSignin('Your sign-in has ended (the project owner may have reset it). Please sign in again.');
}

// Brief feedback on the side chosen.
function flash(which) {
  const el = $(which === 'left' ? 'btn-left' : which === 'right' ? 'btn-right' : 'btn-draw');
  el.classList.add('chosen');
  setTimeout(() => el.classList.remove('chosen'), 180);
}

// ---------------------------------------------------------------------------------------------
// Sign-in and sign-out

const NAME_RE = /^[A-Za-z0-9 _.-]{1,40}$/;

async function signin(event) {
  event.preventDefault();
  const name = $('signin-name').value.trim();
  if (!NAME_RE.test(name)) {
    showStatus('Please use 1-40 letters, digits, spaces or _ . -', 'error');
    return;
  }
  $('signin-button').disabled = true;
  try {
    const s = await api('POST', '/api/signin', { name });
    state.epoch++;
    writeSession({ name: s.name, token: s.token });
    state.answerTimes = [];
    updateRate();
    clearStatus();
    await start();
  } catch (e) {
    $('signin-button').disabled = false;
    if (e.status === 409) {
      showStatus(`"${name}" is already signed in somewhere else. Continue there, pick another name, ` +
        'or ask the project owner to reset that sign-in.', 'error');
    } else if (e.status === 0) {
      showStatus('Cannot reach the server - is it running?', 'error');
    } else {
      showStatus(e.message, 'error');
    }
  }
}

async function signout() {
  const held = state.shown;
  state.epoch++;
  stopTimers();
  state.shown = null;
  try {
    if (held) await api('POST', '/api/release', { comparison: held.comparison });
  } catch {
    // the sign-out releases it anyway
  }
  try {
    await api('POST', '/api/signout');
  } catch {
    // gone already
  }
  const name = session ? session.name : '';
  writeSession(null);
  state.busy = false;
  $('signin-name').value = name;
  showSignin('Signed out.', 'info');
}

// Signed in: who am I, then the first comparison.
async function start() {
  setView('work');
  clearShown('loading', 'loading');
  await run(async () => {
    const me = await withRetry(() => api('GET', '/api/me'));
    updateProgress(me.progress);
    await next();
  });
}

// ---------------------------------------------------------------------------------------------
// Keys and buttons

const KEYS = {
  ArrowLeft: 'left', 1: 'left',
  ArrowRight: 'right', 2: 'right',
  ArrowDown: 'draw', d: 'draw', D: 'draw',
  Backspace: 'undo', u: 'undo', U: 'undo',
  ' ': 'pause',
};

function onKey(e) {
  if (state.view !== 'work' || e.ctrlKey || e.metaKey || e.altKey) return;
  if (e.target instanceof HTMLInputElement || e.target instanceof HTMLTextAreaElement) return;
  const action = KEYS[e.key];
  if (!action) return;
  e.preventDefault();
  if (e.repeat) return; // a held key must not answer a run of comparisons
  if (action === 'pause') togglePause();
  else if (action === 'undo') void run(undo);
  else if (state.shown) void run(answer, action);
}

function init() {
  turntable.canvases = { left: $('canvas-left'), anchor: $('canvas-anchor'), right: $('canvas-right') };
  $('signin-form').addEventListener('submit', signin);
  $('signout').addEventListener('click', () => void signout());
  // Buttons let go of the focus after a click, so Enter or space cannot repeat an answer.
  const onClick = (id, action) => $(id).addEventListener('click', (e) => {
    e.currentTarget.blur();
    void run(action === 'undo' ? undo : answer, action);
  });
  onClick('btn-left', 'left');
  onClick('btn-right', 'right');
  onClick('btn-draw', 'draw');
  onClick('btn-undo', 'undo');
  $('btn-pause').addEventListener('click', togglePause);
  $('panel-left').addEventListener('click', () => state.shown && void run(answer, 'left'));
  $('panel-right').addEventListener('click', () => state.shown && void run(answer, 'right'));
  document.addEventListener('keydown', onKey);
  requestAnimationFrame(animate);

  if (session) void start();
  else showSignin();
}

init();
