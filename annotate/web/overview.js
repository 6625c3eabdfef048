// The project owner's page of `retarget annotate serve`: progress per group and per annotator
// (refreshed every 2 s), each annotator's decisions, resetting a sign-in, and the triplet CSVs.
//
// The owner token arrives once in the address (/overview#token=...); it is moved into this tab's
// sessionStorage and removed from the address bar so it is not left in history or screenshots.

import { api as apiWithToken, request as requestWithToken } from './api.js';

const $ = (id) => document.getElementById(id);

const TOKEN_KEY = 'retarget.owner.token';
const REFRESH_MS = 2000;

let token = takeToken();
let refreshTimer = 0;
let selected = ''; // the annotator whose decisions are shown
let latest = null; // the last /api/overview response

function takeToken() {
  const params = new URLSearchParams(location.hash.slice(1));
  const fromUrl = params.get('token');
  if (fromUrl) {
    sessionStorage.setItem(TOKEN_KEY, fromUrl);
    history.replaceState(null, '', location.pathname + location.search);
  }
  return sessionStorage.getItem(TOKEN_KEY) || '';
}

// ---------------------------------------------------------------------------------------------
// HTTP

const request = (method, path, body) => requestWithToken(method, path, { token, body });
const api = (method, path, body) => apiWithToken(method, path, { token, body });

// ---------------------------------------------------------------------------------------------
// Status line (shared look with the annotator's page)

let statusTimer = 0;

function showStatus(text, kind = 'info', ms = 0) {
  const el = $('status');
  el.textContent = text;
  el.className = `show ${kind}`;
  clearTimeout(statusTimer);
  if (ms) statusTimer = setTimeout(clearStatus, ms);
}

function clearStatus() {
  clearTimeout(statusTimer);
  $('status').className = '';
  $('status').textContent = '';
}

// ---------------------------------------------------------------------------------------------
// Rendering

// Builds an element: el('td', {className: 'num'}, 'text', child, ...).
function el(tag, props = {}, ...children) {
  const node = Object.assign(document.createElement(tag), props);
  for (const c of children) node.append(c instanceof Node ? c : String(c ?? ''));
  return node;
}

function bar(done, total) {
  const fraction = total > 0 ? done / total : 0;
  const fill = el('span');
  fill.style.width = `${(100 * fraction).toFixed(1)}%`;
  return el('div', { className: `bar${total > 0 && done >= total ? ' done' : ''}` }, fill);
}

function ago(unixSeconds) {
  if (!unixSeconds) return 'never';
  const s = Math.max(0, Math.round(Date.now() / 1000 - unixSeconds));
  if (s < 5) return 'now';
  if (s < 90) return `${s} s ago`;
  if (s < 5400) return `${Math.round(s / 60)} min ago`;
  if (s < 172800) return `${Math.round(s / 3600)} h ago`;
  return new Date(unixSeconds * 1000).toLocaleString();
}

function render(o) {
  latest = o;
  const groupsDone = o.groups.filter((g) => g.total > 0 && g.done >= g.total).length;
  const summary = $('overview-summary');
  summary.textContent = o.finished
    ? `All ${o.groups.length} groups done`
    : `${o.done} of ${o.total} comparisons decided`;
  summary.dataset.finished = String(Boolean(o.finished));
  summary.dataset.groupsDone = String(groupsDone);
  $('overview-detail').textContent =
    `${groupsDone} of ${o.groups.length} groups have a champion; ${o.done}/${o.total} comparisons decided; ` +
    `${o.annotators.length} annotator${o.annotators.length === 1 ? '' : 's'}`;

  const groups = $('groups-table').tBodies[0];
  groups.replaceChildren(...o.groups.map((g) => {
    const finished = g.total > 0 && g.done >= g.total;
    return el('tr', {},
      el('td', {}, g.id),
      el('td', {}, g.label),
      el('td', {}, bar(g.done, g.total)),
      el('td', { className: 'num' }, `${g.done}/${g.total}`),
      el('td', { className: 'num' }, g.tie_breaks),
      el('td', { className: 'num' }, finished && g.champion != null
        ? el('span', { className: 'badge ok' }, `#${g.champion}`) : '-'));
  }));
  for (const row of groups.rows) row.dataset.group = row.cells[0].textContent;

  const people = $('annotators-table').tBodies[0];
  people.replaceChildren(...o.annotators.map((a) => {
    const reset = el('button', { type: 'button', className: 'danger', textContent: 'reset sign-in',
      title: `End ${a.name}'s sign-in and hand back what they hold` });
    reset.addEventListener('click', (e) => {
      e.stopPropagation();
      void resetSignin(a.name);
    });
    const row = el('tr', { className: `clickable${a.name === selected ? ' selected' : ''}` },
      el('td', {}, a.name),
      el('td', { className: 'num' }, a.decided),
      el('td', { className: 'num' }, a.draws),
      el('td', { className: 'num' }, a.holding ? el('span', { className: 'badge live' }, a.holding) : '0'),
      el('td', {}, ago(a.last_seen)),
      el('td', { className: 'num' }, reset));
    row.dataset.name = a.name;
    row.addEventListener('click', () => void showDecisions(a.name));
    return row;
  }));
  if (!o.annotators.length) {
    people.append(el('tr', {}, el('td', { colSpan: 6, className: 'muted' }, 'Nobody has signed in yet.')));
  }
  $('refreshed').textContent = `updated ${new Date().toLocaleTimeString()}`;
}

async function showDecisions(name) {
  selected = name;
  for (const row of $('annotators-table').tBodies[0].rows) {
    row.classList.toggle('selected', row.dataset.name === name);
  }
  try {
    const d = await api('GET', `/api/annotator?name=${encodeURIComponent(name)}`);
    if (selected !== name) return;
    $('decisions').hidden = false;
    $('decisions-title').textContent = `${d.name}: ${d.decisions.length} answer${d.decisions.length === 1 ? '' : 's'}`;
    const body = $('decisions-table').tBodies[0];
    body.replaceChildren(...d.decisions.map((x, i) => el('tr', {},
      el('td', { className: 'num' }, i + 1),
      el('td', {}, new Date(x.time * 1000).toLocaleTimeString()),
      el('td', {}, `${x.label} (${x.group})`),
      el('td', { className: 'num' }, x.comparison),
      el('td', { className: 'num' }, x.answer === 'left' ? el('b', {}, `#${x.left}`) : `#${x.left}`),
      el('td', { className: 'num' }, x.answer === 'right' ? el('b', {}, `#${x.right}`) : `#${x.right}`),
      el('td', {}, x.answer + (x.tie_break ? ' (tie-break)' : '')))));
    if (!d.decisions.length) {
      body.append(el('tr', {}, el('td', { colSpan: 7, className: 'muted' }, 'No answers yet.')));
    }
  } catch (e) {
    handleError(e);
  }
}

// ---------------------------------------------------------------------------------------------
// Actions

async function resetSignin(name) {
  if (!confirm(`Reset ${name}'s sign-in? Their comparisons go back to the queue and they will ` +
    'have to sign in again (their answers stay).')) return;
  try {
    const r = await api('POST', '/api/reset', { name });
    showStatus(`${name}: sign-in reset, ${r.released} comparison${r.released === 1 ? '' : 's'} handed back.`, 'ok', 4000);
    await refresh();
  } catch (e) {
    handleError(e);
  }
}

async function download(derived) {
  const button = $(derived ? 'export-all' : 'export-direct');
  button.disabled = true;
  try {
    const res = await request('GET', `/api/export?derived=${derived ? 1 : 0}`);
    const blob = await res.blob();
    const link = el('a', { href: URL.createObjectURL(blob), download: derived ? 'triplets.csv' : 'triplets-direct.csv' });
    document.body.append(link);
    link.click();
    link.remove();
    setTimeout(() => URL.revokeObjectURL(link.href), 10000);
  } catch (e) {
    handleError(e);
  } finally {
    button.disabled = false;
  }
}

function handleError(e) {
  if (e.status === 401 || e.status === 403) {
    forget('That token or password was not accepted.');
  } else if (e.status === 0) {
    showStatus('Connection to the server lost - retrying...', 'warn');
  } else {
    showStatus(e.message, 'error', 5000);
  }
}

async function refresh() {
  clearTimeout(refreshTimer);
  try {
    const o = await api('GET', '/api/overview');
    if ($('status').classList.contains('warn')) clearStatus();
    render(o);
    if (selected) void showDecisions(selected);
  } catch (e) {
    handleError(e);
    if (!token) return;
  }
  refreshTimer = setTimeout(refresh, REFRESH_MS);
}

// ---------------------------------------------------------------------------------------------
// Views

function showOverview() {
  $('owner-signin').hidden = true;
  $('overview').hidden = false;
  $('owner-who').hidden = false;
  void refresh();
}

function forget(message) {
  clearTimeout(refreshTimer);
  token = '';
  sessionStorage.removeItem(TOKEN_KEY);
  $('overview').hidden = true;
  $('owner-who').hidden = true;
  $('owner-signin').hidden = false;
  if (message) showStatus(message, 'error', 5000);
  $('owner-token').focus();
}

function init() {
  $('owner-form').addEventListener('submit', (e) => {
    e.preventDefault();
    token = $('owner-token').value.trim();
    if (!token) return;
    sessionStorage.setItem(TOKEN_KEY, token);
    $('owner-token').value = '';
    clearStatus();
    showOverview();
  });
  $('owner-forget').addEventListener('click', () => forget());
  $('export-all').addEventListener('click', () => void download(true));
  $('export-direct').addEventListener('click', () => void download(false));
  if (token) showOverview();
  else forget();
}

init();
