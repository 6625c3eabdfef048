// The landmark editor's page (`retarget avatar landmarks`, avatar/landmark_editor.h): the avatar
// and the human face side by side, every landmark a dot on both. The server owns the state; this
// page draws it, turns clicks and drags on the avatar into /api/place calls (in the pictures' own
// pixels) and never shows a vertex index except in a dot's tooltip.

const token = new URLSearchParams(location.hash.slice(1)).get('token') || '';
const SVG = 'http://www.w3.org/2000/svg';

let state = null; // the server's state (GET /api/state)
let view = 'front'; // 'front' | 'side'
let selected = null; // a landmark's name
let busy = false; // a change is on its way to the server
const pictures = { avatar: {}, human: {} }; // object URLs of the PNGs, by face and view
// Each picture's zoom: scale k (1..8) and translation (CSS pixels) of its zoomable layer. Clicks
// keep their meaning at any zoom (picturePoint reads the transformed box), only finer.
const zoom = { avatar: { k: 1, tx: 0, ty: 0 }, human: { k: 1, tx: 0, ty: 0 } };

const $ = (id) => document.getElementById(id);

class ApiError extends Error {
  constructor(status, message) {
    super(message);
    this.status = status;
  }
}

// One call to the server with the page's token; the JSON answer, or ApiError with its message.
async function api(method, path, body) {
  const init = { method, headers: { Authorization: `Bearer ${token}` }, cache: 'no-store' };
  if (method === 'POST') {
    init.headers['Content-Type'] = 'application/json';
    init.body = JSON.stringify(body || {});
  }
  let res;
  try {
    res = await fetch(path, init);
  } catch {
    throw new ApiError(0, 'no connection to the server (was `retarget avatar landmarks` stopped?)');
  }
  if (!res.ok) {
    let message = `${res.status} ${res.statusText}`;
    try {
      message = (await res.json()).error || message;
    } catch {
      // not JSON
    }
    throw new ApiError(res.status, message);
  }
  return path.startsWith('/img/') ? res.blob() : res.json();
}

function say(text, kind = 'info') {
  const status = $('status');
  status.textContent = text;
  status.dataset.kind = kind;
}

const pretty = (name) => name.replace(/_/g, ' ');

// ---- drawing -----------------------------------------------------------------------------------

function badge(item) {
  const a = item.avatar;
  if (!a) return { text: 'not set', cls: 'missing', title: 'the avatar has no such landmark yet: click where it belongs' };
  if (a.origin === 'hand-set') return { text: 'hand-set', cls: 'hand', title: 'placed by hand' };
  if (a.origin === 'proposed') {
    const c = a.confidence;
    const cls = c >= 0.7 ? 'sure' : c >= 0.4 ? 'check' : 'doubtful';
    return { text: `${Math.round(c * 100)}%`, cls, title: `proposed with confidence ${c.toFixed(2)}: ${a.how}` };
  }
  return { text: 'rig.yaml', cls: 'file', title: 'as rig.yaml had it' };
}

function drawList() {
  const list = $('list');
  list.replaceChildren();
  const groups = [
    ['On the avatar', state.landmarks.filter((l) => l.avatar && l.human)],
    ['The human face has, the avatar lacks', state.landmarks.filter((l) => !l.avatar && l.human)],
    ['Only on the avatar (no human landmark to pair with)', state.landmarks.filter((l) => l.avatar && !l.human)],
  ];
  for (const [title, items] of groups) {
    if (!items.length) continue;
    const header = document.createElement('li');
    header.className = 'group';
    header.textContent = title;
    list.append(header);
    for (const item of items) {
      const li = document.createElement('li');
      li.className = 'landmark';
      li.dataset.name = item.name;
      li.setAttribute('aria-selected', String(item.name === selected));
      const name = document.createElement('span');
      name.className = 'name';
      name.textContent = pretty(item.name);
      const b = badge(item);
      const tag = document.createElement('span');
      tag.className = `badge ${b.cls}`;
      tag.textContent = b.text;
      tag.title = b.title;
      li.append(name, tag);
      if (item.avatar) {
        const remove = document.createElement('button');
        remove.type = 'button';
        remove.className = 'remove';
        remove.textContent = '×';
        remove.title = `remove ${pretty(item.name)} from the avatar`;
        remove.addEventListener('click', (e) => {
          e.stopPropagation();
          change('/api/remove', { name: item.name });
        });
        li.append(remove);
      }
      li.addEventListener('click', () => select(item.name));
      list.append(li);
    }
  }
}

// The dots of one face over its picture, in the picture's pixels (the SVG's viewBox); sizes are
// given in screen pixels and converted, so that dots and labels keep their size at any zoom.
function drawDots(face) {
  const svg = $(`${face}-overlay`);
  const [width, height] = state.size;
  svg.setAttribute('viewBox', `0 0 ${width} ${height}`);
  svg.replaceChildren();
  const rect = svg.getBoundingClientRect();
  const u = rect.width > 0 ? width / rect.width : 1; // picture pixels per screen pixel
  const px = (n) => String(n * u);
  const items = state.landmarks.filter((l) => l[face]);
  // The selected one last, so that it is drawn on top.
  items.sort((a, b) => (a.name === selected) - (b.name === selected));
  const labels = []; // {label, x, y, onLeft, isSelected}
  for (const item of items) {
    const [x, y, seen] = item[face].pixels[view];
    const isSelected = item.name === selected;
    // The human's landmarks the avatar lacks are shown faint, unless selected.
    const faint = face === 'human' && !item.avatar && !isSelected;
    const g = document.createElementNS(SVG, 'g');
    g.classList.add('dot');
    if (isSelected) g.classList.add('selected');
    if (!seen) g.classList.add('behind');
    if (faint) g.classList.add('faint');
    g.dataset.name = item.name;
    g.setAttribute('transform', `translate(${x} ${y})`);
    if (isSelected) {
      const ring = document.createElementNS(SVG, 'circle');
      ring.setAttribute('r', px(13));
      ring.setAttribute('stroke-width', px(3));
      ring.setAttribute('class', 'ring');
      g.append(ring);
    }
    const dot = document.createElementNS(SVG, 'circle');
    dot.setAttribute('r', px(faint ? 3 : 5.5));
    dot.setAttribute('stroke-width', px(faint ? 0.8 : 1.5));
    if (!seen) dot.setAttribute('stroke-dasharray', `${px(2)} ${px(2)}`);
    dot.setAttribute('class', `spot ${face === 'avatar' ? badge(item).cls : 'human'}`);
    g.append(dot);
    if (!faint || isSelected) {
      const label = document.createElementNS(SVG, 'text');
      const onLeft = view === 'front' && x < width / 2;
      label.setAttribute('x', px(onLeft ? -9 : 9));
      label.setAttribute('y', px(4));
      label.setAttribute('font-size', px(isSelected ? 14 : 12));
      label.setAttribute('stroke-width', px(3));
      label.setAttribute('text-anchor', onLeft ? 'end' : 'start');
      label.textContent = pretty(item.name);
      g.append(label);
      labels.push({ label, x, y, onLeft, isSelected });
    }
    const title = document.createElementNS(SVG, 'title');
    title.textContent = face === 'avatar'
      ? `${pretty(item.name)}: vertex ${item.avatar.vertex}${seen ? '' : ' (behind, seen from the other side)'}`
      : `${pretty(item.name)} on the human face${seen ? '' : ' (behind)'}`;
    g.append(title);
    svg.append(g);
  }
  placeLabels(labels, u);
}

// Labels must not cover one another: each (the selected one first) goes beside its dot, on its
// preferred side or the other, moved up or down a line if need be; one that fits nowhere is
// shown only while the pointer is on its dot (class "crowded").
function placeLabels(labels, u) {
  labels.sort((a, b) => b.isSelected - a.isSelected);
  // Nor hide a dot.
  const placed = labels.map((l) => ({ x: l.x - 6 * u, y: l.y - 6 * u, w: 12 * u, h: 12 * u }));
  const line = 14 * u;
  for (const l of labels) {
    const w = l.label.getComputedTextLength();
    const h = Number(l.label.getAttribute('font-size'));
    let spot = null;
    for (const left of [l.onLeft, !l.onLeft]) {
      for (const dy of [0, line, -line, 2 * line, -2 * line]) {
        const box = { x: l.x + (left ? -9 * u - w : 9 * u), y: l.y + 4 * u + dy - 0.8 * h, w, h };
        const clash = placed.some((p) => box.x < p.x + p.w && p.x < box.x + box.w && box.y < p.y + p.h && p.y < box.y + box.h);
        if (!clash) {
          spot = { box, dy, left };
          break;
        }
      }
      if (spot) break;
    }
    if (!spot) {
      l.label.classList.add('crowded');
      continue;
    }
    placed.push(spot.box);
    if (spot.dy !== 0) {
      // A leader from the dot to its moved label.
      const leader = document.createElementNS(SVG, 'line');
      leader.setAttribute('x2', String(spot.left ? -8 * u : 8 * u));
      leader.setAttribute('y2', String(spot.dy));
      leader.setAttribute('stroke-width', String(u));
      leader.setAttribute('class', 'leader');
      l.label.before(leader);
    }
    l.label.setAttribute('x', String(spot.left ? -9 * u : 9 * u));
    l.label.setAttribute('y', String(4 * u + spot.dy));
    l.label.setAttribute('text-anchor', spot.left ? 'end' : 'start');
  }
}

function draw() {
  document.body.dataset.state = 'ready';
  document.body.dataset.view = view;
  $('rig-name').textContent = state.rig;
  $('human-name').textContent = state.human;
  $('avatar-caption').textContent = state.rig;
  $('human-caption').textContent = state.human;
  for (const face of ['avatar', 'human']) {
    const img = $(`${face}-img`);
    if (pictures[face][view] && img.src !== pictures[face][view]) img.src = pictures[face][view];
    drawDots(face);
  }
  for (const v of ['front', 'side']) $(`view-${v}`).setAttribute('aria-pressed', String(v === view));
  drawList();
  $('undo').disabled = !state.can_undo || busy;
  $('save').disabled = !state.unsaved || busy;
  $('unsaved').hidden = !state.unsaved;
  document.body.dataset.unsaved = String(state.unsaved);
}

function select(name) {
  selected = name;
  const item = state.landmarks.find((l) => l.name === name);
  if (item) {
    const where = item.avatar ? 'click where it belongs on the avatar, or drag its dot' : 'click where it belongs on the avatar to add it';
    say(`${pretty(name)} selected: ${where}.`);
  }
  draw();
}

// ---- changes -----------------------------------------------------------------------------------

async function change(path, body) {
  if (busy) return;
  busy = true;
  try {
    state = await api('POST', path, body);
    if (path === '/api/save') say(`Saved to ${state.saved}.`, 'ok');
    else say(state.last_change ? `${state.last_change[0].toUpperCase()}${state.last_change.slice(1)}.` : '');
  } catch (e) {
    say(e.message, 'error');
  } finally {
    busy = false;
    draw();
  }
}

// Client coordinates -> the picture's pixels.
function picturePoint(svg, event) {
  const rect = svg.getBoundingClientRect();
  const [width, height] = state.size;
  return { x: ((event.clientX - rect.left) * width) / rect.width, y: ((event.clientY - rect.top) * height) / rect.height };
}

function wireAvatar() {
  const svg = $('avatar-overlay');
  let drag = null; // {name, start: {x, y}, moved, dot}
  svg.addEventListener('pointerdown', (event) => {
    if (!state || event.button !== 0) return;
    const dot = event.target.closest('g.dot');
    if (!dot) return;
    event.preventDefault();
    if (dot.dataset.name !== selected) select(dot.dataset.name);
    drag = { name: dot.dataset.name, start: picturePoint(svg, event), moved: false };
    svg.setPointerCapture(event.pointerId);
  });
  svg.addEventListener('pointermove', (event) => {
    if (!drag) return;
    const p = picturePoint(svg, event);
    if (Math.hypot(p.x - drag.start.x, p.y - drag.start.y) > 3) drag.moved = true;
    const g = svg.querySelector(`g.dot[data-name="${CSS.escape(drag.name)}"]`);
    if (g && drag.moved) g.setAttribute('transform', `translate(${p.x} ${p.y})`);
  });
  svg.addEventListener('pointerup', (event) => {
    if (!state || event.button !== 0) return;
    const p = picturePoint(svg, event);
    if (drag) {
      const { name, moved } = drag;
      drag = null;
      if (moved) change('/api/place', { name, view, x: p.x, y: p.y });
      return;
    }
    if (!selected) {
      say('Pick a landmark first (in the list, or by its dot), then click on the avatar.', 'error');
      return;
    }
    change('/api/place', { name: selected, view, x: p.x, y: p.y });
  });
}

function wireHuman() {
  $('human-overlay').addEventListener('click', (event) => {
    const dot = event.target.closest('g.dot');
    if (dot) select(dot.dataset.name);
  });
}

function applyZoom(face) {
  const z = zoom[face];
  $(`${face}-zoomable`).style.transform = `translate(${z.tx}px, ${z.ty}px) scale(${z.k})`;
  if (state) drawDots(face);
}

function resetZoom() {
  for (const face of ['avatar', 'human']) {
    Object.assign(zoom[face], { k: 1, tx: 0, ty: 0 });
    applyZoom(face);
  }
}

// The mouse wheel zooms a picture about the point under the cursor, 1x..8x, never showing
// beyond the picture's edges.
function wireZoom(face) {
  const frame = $(`${face}-frame`);
  frame.addEventListener('wheel', (event) => {
    event.preventDefault();
    const r = frame.getBoundingClientRect();
    const cx = event.clientX - r.left;
    const cy = event.clientY - r.top;
    const z = zoom[face];
    const k = Math.min(8, Math.max(1, z.k * Math.exp(-event.deltaY * 0.0015)));
    z.tx = Math.min(0, Math.max(r.width * (1 - k), cx - ((cx - z.tx) * k) / z.k));
    z.ty = Math.min(0, Math.max(r.height * (1 - k), cy - ((cy - z.ty) * k) / z.k));
    z.k = k;
    applyZoom(face);
  }, { passive: false });
}

function setView(v) {
  view = v;
  resetZoom();
  draw();
}

async function loadPictures() {
  await Promise.all(['avatar', 'human'].flatMap((face) => ['front', 'side'].map(async (v) => {
    const blob = await api('GET', `/img/${face}/${v}.png`);
    pictures[face][v] = URL.createObjectURL(blob);
  })));
}

async function main() {
  if (!token) {
    say('This address has no token: open the one `retarget avatar landmarks` printed (it ends in #token=...).', 'error');
    document.body.dataset.state = 'error';
    return;
  }
  $('view-front').addEventListener('click', () => setView('front'));
  $('view-side').addEventListener('click', () => setView('side'));
  $('undo').addEventListener('click', () => change('/api/undo'));
  $('save').addEventListener('click', () => change('/api/save'));
  wireAvatar();
  wireHuman();
  wireZoom('avatar');
  wireZoom('human');
  window.addEventListener('resize', () => state && draw());
  document.addEventListener('keydown', (event) => {
    if ((event.ctrlKey || event.metaKey) && event.key === 's') {
      event.preventDefault();
      if (state && state.unsaved) change('/api/save');
    } else if ((event.ctrlKey || event.metaKey) && event.key === 'z') {
      event.preventDefault();
      if (state && state.can_undo) change('/api/undo');
    } else if (event.key === 'u' && state && state.can_undo) {
      change('/api/undo');
    } else if (event.key === '0') {
      resetZoom();
    } else if (event.key === 'Escape') {
      selected = null;
      draw();
    }
  });
  window.addEventListener('beforeunload', (event) => {
    if (state && state.unsaved) event.preventDefault();
  });
  try {
    [state] = await Promise.all([api('GET', '/api/state'), loadPictures()]);
    draw();
    say('Pick a landmark in the list or by its dot.');
  } catch (e) {
    document.body.dataset.state = 'error';
    say(e.message, 'error');
  }
}

main();
