#!/usr/bin/env node
// Browser test of the landmark page (`retarget avatar landmarks`, avatar/web/): on the fox's
// `retarget avatar init` folder beside the synthetic human (both written by the real commands),
// a person selects mouth_left in the list, sees it ringed on both faces, clicks elsewhere on the
// avatar, undoes, clicks again, tries a click beside the head and the side view, drags
// mouth_right's dot, adds the forehead (the human has one, the fox not), removes the chin, zooms
// in and clicks, and saves. rig.yaml's mouth_left (and the others moved) must then be vertices that lie under the
// clicks in the avatar's own geometry (neutral.obj seen along proposals.yaml's frame, independent
// of the server's projection), every line outside the landmarks as it was, and the folder must
// load again (the server restarted on it shows the saved landmark).
//
//   node tests/browser/avatar_landmarks_browser_test.mjs --retarget build/cli/retarget \
//     --tmp /tmp [--chromium /usr/bin/chromium] [--screenshot landmarks.png]
//
// Exit status: 0 pass, 1 fail (the message says which step and what), 77 skipped (no chromium
// binary, or playwright-core not installed: `npm install --no-audit --no-fund` in tests/browser).

import { spawn } from 'node:child_process';
import { existsSync } from 'node:fs';
import fs from 'node:fs/promises';
import path from 'node:path';
import { performance } from 'node:perf_hooks';
import { parseArgs } from 'node:util';

import { SKIP, check, findChromium, runMain } from './harness.mjs';
import { runCommand } from './annotation_server_process.mjs';

const VIEWPORT = { width: 1400, height: 860 };
const STEP_TIMEOUT_MS = 30000;
const PICK_RADIUS_PX = 8; // LandmarkEditorOptions::pick_radius_px

let stepNumber = 0;
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

// `retarget avatar landmarks` as a child process; resolves once it prints the page's address.
const running = new Set();
process.on('exit', () => {
  for (const child of running) child.kill('SIGKILL');
});
for (const signal of ['SIGINT', 'SIGTERM']) process.once(signal, () => process.exit(130));

async function startEditor(retarget, rigFolder, faceModel, timeoutMs = 30000) {
  const args = ['avatar', 'landmarks', rigFolder, '--face-model', faceModel, '--port', '0'];
  const child = spawn(retarget, args, { stdio: ['ignore', 'pipe', 'pipe'] });
  running.add(child);
  child.on('exit', () => running.delete(child));
  let output = '';
  const url = await new Promise((resolve, reject) => {
    const fail = (why) => {
      clearTimeout(timer);
      reject(new Error(`retarget avatar landmarks: ${why}\n$ ${retarget} ${args.join(' ')}\n${output}`));
    };
    const timer = setTimeout(() => fail(`no address printed within ${timeoutMs / 1000} s`), timeoutMs);
    child.stdout.on('data', (chunk) => {
      output += chunk;
      const m = /open:\s+(http:\/\/\S+#token=\S+)/.exec(output);
      if (m) {
        clearTimeout(timer);
        resolve(m[1]);
      }
    });
    child.stderr.on('data', (chunk) => (output += chunk));
    child.on('error', (e) => fail(e.message));
    child.on('exit', (code, signal) => fail(`exited (${signal || code}) before serving`));
  });
  return {
    url,
    output: () => output,
    async stop() {
      if (child.exitCode !== null || child.signalCode !== null) return;
      const exited = new Promise((resolve) => child.once('exit', resolve));
      child.kill('SIGTERM');
      const timer = setTimeout(() => child.kill('SIGKILL'), 5000);
      await exited;
      clearTimeout(timer);
    },
  };
}

// ---- the avatar's own geometry, read from the files -------------------------------------------

function rigLandmark(text, name) {
  const m = new RegExp(`^\\s+${name}:\\s*(\\d+)`, 'm').exec(text);
  return m ? Number(m[1]) : null;
}

// rig.yaml's lines outside its landmarks: section.
function outsideLandmarks(text) {
  let inside = false;
  return text.split('\n').filter((line) => {
    if (line && line[0] !== ' ' && line[0] !== '#') inside = line.startsWith('landmarks:');
    return !inside;
  });
}

async function readObjVertices(file) {
  const vertices = [];
  for (const line of (await fs.readFile(file, 'utf8')).split('\n')) {
    const m = /^v\s+(\S+)\s+(\S+)\s+(\S+)/.exec(line);
    if (m) vertices.push([Number(m[1]), Number(m[2]), Number(m[3])]);
  }
  return vertices;
}

async function readFrame(proposalsYaml) {
  const text = await fs.readFile(proposalsYaml, 'utf8');
  const frame = {};
  for (const axis of ['left', 'up', 'forward']) {
    const m = new RegExp(`^\\s+${axis}:\\s*\\[([^\\]]+)\\]`, 'm').exec(text.slice(text.indexOf('\nframe:')));
    check(m, `${proposalsYaml}: no frame.${axis}`);
    frame[axis] = m[1].split(',').map(Number);
  }
  return frame;
}

const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

// ---- the page ---------------------------------------------------------------------------------

// The picture pixels of a landmark's dot on one face (its SVG transform), or null.
async function dotPixel(page, face, name) {
  return page.evaluate(([f, n]) => {
    const g = document.querySelector(`#${f}-overlay g.dot[data-name="${n}"]`);
    if (!g) return null;
    const m = /translate\(([-\d.e]+)[ ,]+([-\d.e]+)\)/.exec(g.getAttribute('transform'));
    return m ? { x: Number(m[1]), y: Number(m[2]), behind: g.classList.contains('behind') } : null;
  }, [face, name]);
}

// Picture pixels -> page (client) coordinates of the avatar's picture.
async function toClient(page, p) {
  return page.evaluate(([x, y]) => {
    const svg = document.getElementById('avatar-overlay');
    const rect = svg.getBoundingClientRect();
    const [w, h] = svg.getAttribute('viewBox').split(' ').slice(2).map(Number);
    return { x: rect.left + (x * rect.width) / w, y: rect.top + (y * rect.height) / h };
  }, [p.x, p.y]);
}

async function statusText(page) {
  return page.evaluate(() => {
    const s = document.getElementById('status');
    return { text: s.textContent, kind: s.dataset.kind || '' };
  });
}

async function waitForStatus(page, pattern) {
  await page.waitForFunction((source) => new RegExp(source).test(document.getElementById('status').textContent),
    pattern.source, { timeout: STEP_TIMEOUT_MS });
  return statusText(page);
}

async function main() {
  const { values: args } = parseArgs({
    options: {
      retarget: { type: 'string' },
      tmp: { type: 'string' },
      chromium: { type: 'string' },
      screenshot: { type: 'string' },
    },
  });
  if (!args.retarget || !args.tmp) {
    console.error('usage: avatar_landmarks_browser_test.mjs --retarget PATH --tmp DIR [--chromium PATH] [--screenshot OUT.png]');
    return 1;
  }
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
  check(existsSync(args.retarget), `--retarget ${args.retarget}: no such file (build the project first)`);

  const scratch = path.resolve(args.tmp, `avatar_landmarks_browser_${process.pid}`);
  const rigFolder = path.join(scratch, 'fox');
  const rigYaml = path.join(rigFolder, 'rig.yaml');
  const faceModel = path.join(scratch, 'synth', 'human', 'face_model.yaml');
  let editor = null;
  let browser = null;
  try {
    let before = '';
    await step('retarget synth, then retarget avatar init on the fox', async () => {
      await fs.rm(scratch, { recursive: true, force: true });
      await fs.mkdir(scratch, { recursive: true });
      await runCommand(args.retarget, ['synth', '--out', path.join(scratch, 'synth'), '--force']);
      await runCommand(args.retarget, ['avatar', 'init', path.join(scratch, 'synth', 'avatars', 'fox'), '--out', rigFolder]);
      before = await fs.readFile(rigYaml, 'utf8');
      check(rigLandmark(before, 'mouth_left') !== null, `${rigYaml} has no mouth_left:\n${before}`);
      return `mouth_left: ${rigLandmark(before, 'mouth_left')}`;
    });

    await step('retarget avatar landmarks serves the page', async () => {
      editor = await startEditor(args.retarget, rigFolder, faceModel);
      return editor.url.replace(/#token=.*/, '#token=...');
    });

    browser = await chromium.launch({ executablePath: chromiumPath, headless: true, args: ['--no-sandbox'] });
    const context = await browser.newContext({ viewport: VIEWPORT });
    context.setDefaultTimeout(STEP_TIMEOUT_MS);
    const page = await context.newPage();
    const pageErrors = [];
    page.on('pageerror', (e) => pageErrors.push(e.message));

    await step('the page shows both faces with their landmarks', async () => {
      await page.goto(editor.url);
      await page.waitForSelector('body[data-state="ready"]');
      for (const face of ['avatar', 'human']) {
        const loaded = await page.evaluate((f) => {
          const img = document.getElementById(`${f}-img`);
          return img.complete && img.naturalWidth > 0;
        }, face);
        check(loaded, `the ${face} picture did not load`);
      }
      const avatarDots = await page.locator('#avatar-overlay g.dot').count();
      const humanDots = await page.locator('#human-overlay g.dot').count();
      check(avatarDots >= 10, `${avatarDots} landmark dots on the avatar`);
      check(humanDots >= avatarDots, `${humanDots} dots on the human, fewer than the avatar's ${avatarDots}`);
      const badge = await page.locator('#list li[data-name="mouth_left"] .badge').textContent();
      check(/%$/.test(badge), `mouth_left's confidence badge reads "${badge}", not a percentage`);
      // No vertex index on the page except in tooltips.
      const text = await page.evaluate(() => {
        const clone = document.body.cloneNode(true);
        clone.querySelectorAll('title').forEach((t) => t.remove());
        return clone.textContent;
      });
      check(!/vertex\s*\d/.test(text), 'a vertex index is shown outside a tooltip');
      return `${avatarDots} dots on the avatar, ${humanDots} on the human`;
    });

    await step('select mouth_left in the list: ringed on both faces', async () => {
      await page.click('#list li[data-name="mouth_left"]');
      check(await page.getAttribute('#list li[data-name="mouth_left"]', 'aria-selected') === 'true',
        'the list row is not selected');
      for (const face of ['avatar', 'human']) {
        const rings = await page.locator(`#${face}-overlay g.dot.selected[data-name="mouth_left"] circle.ring`).count();
        check(rings === 1, `mouth_left is not ringed on the ${face}`);
      }
    });

    // A point on the avatar's snout: 60% of the way from mouth_left's dot to the nose tip's.
    const oldVertex = rigLandmark(before, 'mouth_left');
    const mouth = await dotPixel(page, 'avatar', 'mouth_left');
    const nose = await dotPixel(page, 'avatar', 'nose_tip');
    check(mouth && nose, 'no dots for mouth_left and nose_tip');
    const target = { x: mouth.x + 0.6 * (nose.x - mouth.x), y: mouth.y + 0.6 * (nose.y - mouth.y) };
    check(Math.hypot(target.x - mouth.x, target.y - mouth.y) > 3 * PICK_RADIUS_PX,
      `the nose tip's dot is too close to mouth_left's for the test (${JSON.stringify({ mouth, nose })})`);
    const client = await toClient(page, target);

    async function clickTarget() {
      const hit = await page.evaluate(([x, y]) => {
        const e = document.elementFromPoint(x, y);
        return e ? `${e.tagName}#${e.id}.${e.getAttribute('class') || ''}` : 'nothing';
      }, [client.x, client.y]);
      check(hit.startsWith('svg#avatar-overlay'), `the click point is over ${hit}, not the avatar's picture`);
      await page.mouse.click(client.x, client.y);
      await waitForStatus(page, /Moved mouth_left/);
    }

    await step('click elsewhere on the avatar: mouth_left moves under the click', async () => {
      await clickTarget();
      const moved = await dotPixel(page, 'avatar', 'mouth_left');
      const d = Math.hypot(moved.x - target.x, moved.y - target.y);
      check(d <= PICK_RADIUS_PX + 1, `mouth_left's dot is ${d.toFixed(1)} px from the click`);
      check(await page.locator('#list li[data-name="mouth_left"] .badge').textContent() === 'hand-set',
        'mouth_left is not marked hand-set');
      check(await page.isEnabled('#save'), 'save is not enabled after a change');
      return `dot ${d.toFixed(1)} px from the click`;
    });

    await step('undo puts it back; the click again moves it', async () => {
      await page.click('#undo');
      await waitForStatus(page, /Undid: moved mouth_left/);
      const back = await dotPixel(page, 'avatar', 'mouth_left');
      check(Math.hypot(back.x - mouth.x, back.y - mouth.y) < 0.01, 'undo did not put mouth_left back');
      check(await page.isDisabled('#save'), 'save is enabled with nothing to save');
      await clickTarget();
    });

    await step('a click beside the head is refused with a message; the side view shows the profile', async () => {
      const corner = await toClient(page, { x: 3, y: 3 });
      await page.mouse.click(corner.x, corner.y);
      const s = await waitForStatus(page, /beside the avatar's head/);
      check(s.kind === 'error', `the refusal is not shown as an error: ${JSON.stringify(s)}`);
      const frontSrc = await page.getAttribute('#avatar-img', 'src');
      await page.click('#view-side');
      await page.waitForFunction((src) => document.getElementById('avatar-img').src !== src, frontSrc);
      const right = await dotPixel(page, 'avatar', 'mouth_right');
      check(right && right.behind, 'in the side view (the face\'s left) mouth_right is not drawn as hidden');
      if (args.screenshot) {
        await page.click('#view-front');
        await fs.mkdir(path.dirname(path.resolve(args.screenshot)), { recursive: true });
        await page.screenshot({ path: args.screenshot });
      }
      await page.click('#view-front');
    });

    // Drag mouth_right's dot halfway to the nose tip's, and release it there.
    const right = await dotPixel(page, 'avatar', 'mouth_right');
    const dragTarget = { x: right.x + 0.5 * (nose.x - right.x), y: right.y + 0.5 * (nose.y - right.y) };
    await step('drag mouth_right\'s dot: it lands under the release point', async () => {
      const from = await toClient(page, right);
      const to = await toClient(page, dragTarget);
      await page.mouse.move(from.x, from.y);
      await page.mouse.down();
      for (let i = 1; i <= 8; i++) await page.mouse.move(from.x + ((to.x - from.x) * i) / 8, from.y + ((to.y - from.y) * i) / 8);
      await page.mouse.up();
      await waitForStatus(page, /Moved mouth_right/);
      const moved = await dotPixel(page, 'avatar', 'mouth_right');
      const d = Math.hypot(moved.x - dragTarget.x, moved.y - dragTarget.y);
      check(d <= PICK_RADIUS_PX + 1, `mouth_right's dot is ${d.toFixed(1)} px from where it was dropped`);
      return `dot ${d.toFixed(1)} px from the release point`;
    });

    // The human has a forehead, the fox has none yet: add it above the eyes; remove the chin.
    const eyeL = await dotPixel(page, 'avatar', 'eye_inner_left');
    const eyeR = await dotPixel(page, 'avatar', 'eye_inner_right');
    const spread = Math.hypot(eyeL.x - eyeR.x, eyeL.y - eyeR.y);
    const foreheadTarget = { x: (eyeL.x + eyeR.x) / 2, y: (eyeL.y + eyeR.y) / 2 - 0.8 * spread };
    await step('add the forehead the human has and the fox lacks; remove the chin', async () => {
      check(await page.locator('#avatar-overlay g.dot[data-name="forehead"]').count() === 0, 'the fox has a forehead already');
      await page.click('#list li[data-name="forehead"]');
      check(await page.locator('#human-overlay g.dot.selected[data-name="forehead"] circle.ring').count() === 1,
        'the human\'s forehead is not ringed');
      const at = await toClient(page, foreheadTarget);
      await page.mouse.click(at.x, at.y);
      await waitForStatus(page, /Added forehead/);
      const added = await dotPixel(page, 'avatar', 'forehead');
      check(added, 'no forehead dot on the avatar after adding it');
      check(await page.locator('#list li[data-name="forehead"] .badge').textContent() === 'hand-set', 'forehead not hand-set');
      await page.click('#list li[data-name="chin"] button.remove');
      await waitForStatus(page, /Removed chin/);
      check(await page.locator('#avatar-overlay g.dot[data-name="chin"]').count() === 0, 'the chin is still on the avatar');
      check(await page.locator('#human-overlay g.dot[data-name="chin"]').count() === 1, 'the human lost its chin');
    });

    // Zoomed in 4x about the upper lip, a click still means the picture point under it.
    const lip = await dotPixel(page, 'avatar', 'lip_upper_center');
    const lipTarget = { x: lip.x + 0.5 * (nose.x - lip.x), y: lip.y + 0.5 * (nose.y - lip.y) };
    await step('zoom in with the wheel, click: lip_upper_center lands under the click; 0 resets the zoom', async () => {
      const at = await toClient(page, lip);
      await page.mouse.move(at.x, at.y);
      await page.mouse.wheel(0, -925); // exp(925 x 0.0015) = 4x
      await page.waitForFunction(() => /scale\(4/.test(document.getElementById('avatar-zoomable').style.transform));
      const still = await toClient(page, lip);
      check(Math.hypot(still.x - at.x, still.y - at.y) < 2, 'the zoom moved the point under the cursor');
      await page.click('#list li[data-name="lip_upper_center"]');
      const to = await toClient(page, lipTarget);
      await page.mouse.click(to.x, to.y);
      await waitForStatus(page, /Moved lip_upper_center/);
      const moved = await dotPixel(page, 'avatar', 'lip_upper_center');
      const d = Math.hypot(moved.x - lipTarget.x, moved.y - lipTarget.y);
      check(d <= PICK_RADIUS_PX + 1, `lip_upper_center's dot is ${d.toFixed(1)} px from the click`);
      await page.keyboard.press('0');
      const transform = await page.evaluate(() => document.getElementById('avatar-zoomable').style.transform);
      check(/scale\(1\)/.test(transform), `0 did not reset the zoom: ${transform}`);
      return `dot ${d.toFixed(1)} px from the click`;
    });

    let saved = null;
    await step('save: rig.yaml\'s mouth_left is the vertex under the click, nothing else changed', async () => {
      await page.click('#save');
      const s = await waitForStatus(page, /Saved to/);
      check(s.kind === 'ok', `save: ${JSON.stringify(s)}`);
      const after = await fs.readFile(rigYaml, 'utf8');
      saved = rigLandmark(after, 'mouth_left');
      check(saved !== null && saved !== oldVertex, `mouth_left is ${saved}, was ${oldVertex}`);
      check(JSON.stringify(outsideLandmarks(after)) === JSON.stringify(outsideLandmarks(before)),
        'rig.yaml changed outside its landmarks: section');
      for (const name of ['nose_tip', 'eye_inner_left', 'lip_lower_center'])
        check(rigLandmark(after, name) === rigLandmark(before, name), `${name} changed`);
      check(rigLandmark(after, 'mouth_right') !== rigLandmark(before, 'mouth_right'), 'the dragged mouth_right was not saved');
      check(rigLandmark(after, 'forehead') !== null, 'the added forehead was not saved');
      check(!/^\s+chin:/m.test(after), 'the removed chin is still in rig.yaml');

      // Under the click, in the avatar's own geometry: the front view looks along the face's
      // frame (picture x = the face's left, y = down), at a scale read off two landmarks' dots.
      const V = await readObjVertices(path.join(rigFolder, 'neutral.obj'));
      const frame = await readFrame(path.join(rigFolder, 'proposals.yaml'));
      const plane = (v) => [dot(V[v], frame.left), -dot(V[v], frame.up)];
      const noseVertex = rigLandmark(before, 'nose_tip');
      const [a, b] = [plane(oldVertex), plane(noseVertex)];
      const scale = Math.hypot(nose.x - mouth.x, nose.y - mouth.y) / Math.hypot(b[0] - a[0], b[1] - a[1]);
      // Where vertex v lies on the front picture, from the geometry alone.
      const onPicture = (v) => {
        const n = plane(v);
        return { x: mouth.x + scale * (n[0] - a[0]), y: mouth.y + scale * (n[1] - a[1]) };
      };
      const notes = [];
      for (const [name, vertex, where] of [['mouth_left', saved, target],
        ['mouth_right', rigLandmark(after, 'mouth_right'), dragTarget],
        ['forehead', rigLandmark(after, 'forehead'), foreheadTarget],
        ['lip_upper_center', rigLandmark(after, 'lip_upper_center'), lipTarget]]) {
        const p = onPicture(vertex);
        const d = Math.hypot(p.x - where.x, p.y - where.y);
        check(d <= PICK_RADIUS_PX + 1.5, `${name}: vertex ${vertex} lies ${d.toFixed(1)} px from the click on the avatar`);
        notes.push(`${name} ${d.toFixed(1)} px`);
      }
      check(pageErrors.length === 0, `errors on the page: ${pageErrors.join('; ')}`);
      return `mouth_left ${oldVertex} -> ${saved}; from the clicks: ${notes.join(', ')}`;
    });

    await step('the saved folder loads: the editor restarted on it shows the saved mouth_left', async () => {
      await editor.stop();
      editor = await startEditor(args.retarget, rigFolder, faceModel);
      await page.goto(editor.url);
      await page.waitForSelector('body[data-state="ready"]');
      const title = await page.locator('#avatar-overlay g.dot[data-name="mouth_left"] title').textContent();
      check(title.includes(`vertex ${saved}`), `mouth_left after a restart: "${title}"`);
      const badge = await page.locator('#list li[data-name="mouth_left"] .badge').textContent();
      check(badge === 'hand-set', `mouth_left after a restart is marked "${badge}", not hand-set`);
      const nose = await page.locator('#list li[data-name="nose_tip"] .badge').textContent();
      check(/%$/.test(nose), `nose_tip, unchanged, is marked "${nose}" after a restart, not with its confidence`);
      check(await page.isDisabled('#save'), 'a freshly loaded folder has unsaved changes');
    });
  } finally {
    if (browser) await browser.close();
    if (editor) await editor.stop();
  }
  await fs.rm(scratch, { recursive: true, force: true });
  return 0;
}

runMain(main);
