#!/usr/bin/env node
// three.js plays the animations retarget writes (infer/gltf_animation.h): a page in headless
// Chromium loads gltf_animation_fixture's .glb and .gltf with three's GLTFLoader, plays the
// animation with an AnimationMixer, sets the mixer to keyframes and to times between them, and
// the mesh's morphTargetInfluences must equal the fixture's weights (linearly interpolated
// between frames) within 1e-4; the morph targets must carry the controllers' names.
//
//   node tests/browser/gltf_three_browser_test.mjs --fixture build/tests/gltf_animation_fixture \
//     --tmp /tmp [--chromium /usr/bin/chromium]
//
// The page and its files are answered by Playwright's request routing (no server, no network):
// three from tests/browser/node_modules, the animation from the fixture's folder.
//
// Exit status: 0 pass, 1 fail (the message says what differs), 77 skipped (no chromium binary,
// or playwright-core or three not installed: `npm ci --no-audit --no-fund` in tests/browser).

import { existsSync } from 'node:fs';
import fs from 'node:fs/promises';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { parseArgs } from 'node:util';

import { SKIP, check, findChromium, runMain } from './harness.mjs';
import { runCommand } from './annotation_server_process.mjs';

const ORIGIN = 'http://gltf.retarget.test';
const TOLERANCE = 1e-4;
const FPS = 24;


// The page: three and its GLTFLoader through an import map; window.play(url, times) loads the
// file, plays its first animation once (clamped at the end) and reports the influences at each
// time, in increasing order.
const PAGE = `<!doctype html>
<html><head><meta charset="utf-8"><title>retarget glTF animation</title>
<script type="importmap">
{"imports": {"three": "/three/build/three.module.js", "three/addons/": "/three/examples/jsm/"}}
</script>
<script type="module">
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';

window.play = async (url, times) => {
  const gltf = await new GLTFLoader().loadAsync(url);
  const meshes = [];
  gltf.scene.traverse((o) => { if (o.isMesh) meshes.push(o); });
  if (meshes.length !== 1) throw new Error(meshes.length + ' meshes in the scene, expected 1');
  const mesh = meshes[0];
  if (!mesh.morphTargetInfluences) throw new Error('the mesh has no morph targets');
  const names = [];
  for (const [name, index] of Object.entries(mesh.morphTargetDictionary)) names[index] = name;
  const clip = gltf.animations[0];
  if (!clip) throw new Error('the file has no animation');
  const mixer = new THREE.AnimationMixer(gltf.scene);
  const action = mixer.clipAction(clip);
  action.setLoop(THREE.LoopOnce, 1);
  action.clampWhenFinished = true;
  action.play();
  const influences = [];
  for (const t of times) {
    mixer.setTime(t);
    influences.push(Array.from(mesh.morphTargetInfluences));
  }
  return {
    names,
    influences,
    animations: gltf.animations.length,
    duration: clip.duration,
    tracks: clip.tracks.map((track) => ({ name: track.name, times: Array.from(track.times), values: track.values.length })),
    vertices: mesh.geometry.attributes.position.count,
    normals: !!mesh.geometry.attributes.normal,
  };
};
window.ready = true;
</script></head><body>glTF animation test</body></html>`;

const TYPES = { '.js': 'text/javascript', '.glb': 'model/gltf-binary', '.gltf': 'model/gltf+json' };

// Expected weights at time t: the frames' weights, linear between frames, clamped at the ends.
function weightsAt(expected, t) {
  const { times, weights } = expected;
  if (t <= times[0]) return weights[0];
  const last = times.length - 1;
  if (t >= times[last]) return weights[last];
  let k = 0;
  while (times[k + 1] < t) k++;
  const a = (t - times[k]) / (times[k + 1] - times[k]);
  return weights[k].map((w, c) => w + a * (weights[k + 1][c] - w));
}

async function main() {
  const { values: args } = parseArgs({
    options: { fixture: { type: 'string' }, tmp: { type: 'string' }, chromium: { type: 'string' } },
  });
  if (!args.fixture || !args.tmp) {
    console.error('usage: gltf_three_browser_test.mjs --fixture PATH --tmp DIR [--chromium PATH]');
    return 1;
  }
  // Skips: no browser, no playwright-core, no three.
  const chromiumPath = findChromium(args.chromium);
  if (!chromiumPath) return SKIP;
  let chromium;
  let threeRoot;
  try {
    ({ chromium } = await import('playwright-core'));
    // three's package root, from its main module (node_modules/three/build/three.module.js).
    threeRoot = path.dirname(path.dirname(fileURLToPath(import.meta.resolve('three'))));
    check(existsSync(path.join(threeRoot, 'examples/jsm/loaders/GLTFLoader.js')), 'no GLTFLoader.js');
  } catch (e) {
    console.log('SKIP: playwright-core or three is not installed (run `npm ci --no-audit --no-fund` in ' +
      `tests/browser): ${e.message.split('\n')[0]}`);
    return SKIP;
  }
  check(existsSync(args.fixture), `--fixture ${args.fixture}: no such file (build the project first)`);

  const scratch = path.resolve(args.tmp, `gltf_three_${process.pid}`);
  await fs.rm(scratch, { recursive: true, force: true });
  await runCommand(args.fixture, [scratch, String(FPS)]);
  const expected = JSON.parse(await fs.readFile(path.join(scratch, 'expected.json'), 'utf8'));
  const frames = expected.times.length;
  const duration = expected.times[frames - 1];
  // Every keyframe, a point inside every interval (1/2, then 1/4 and 3/4 alternately), the end.
  const times = [];
  for (let f = 0; f + 1 < frames; f++) {
    times.push(expected.times[f]);
    const a = f % 3 === 0 ? 0.5 : f % 3 === 1 ? 0.25 : 0.75;
    times.push(expected.times[f] + a * (expected.times[f + 1] - expected.times[f]));
  }
  times.push(duration);

  let browser = null;
  const pageErrors = [];
  try {
    browser = await chromium.launch({ executablePath: chromiumPath, headless: true, args: ['--no-sandbox'] });
    const context = await browser.newContext();
    context.setDefaultTimeout(30000);
    await context.route(`${ORIGIN}/**`, async (route) => {
      const { pathname } = new URL(route.request().url());
      if (pathname === '/') return route.fulfill({ body: PAGE, contentType: 'text/html; charset=utf-8' });
      const [root, rest] = pathname.startsWith('/three/') ? [threeRoot, pathname.slice(7)] : [scratch, pathname.slice(1)];
      const file = path.resolve(root, decodeURIComponent(rest));
      if (!file.startsWith(root + path.sep) || !existsSync(file)) return route.fulfill({ status: 404, body: 'not found' });
      return route.fulfill({ body: await fs.readFile(file), contentType: TYPES[path.extname(file)] ?? 'application/octet-stream' });
    });
    const page = await context.newPage();
    page.on('pageerror', (e) => pageErrors.push(e.message));
    page.on('console', (m) => { if (m.type() === 'error') pageErrors.push(`console: ${m.text()}`); });
    await page.goto(`${ORIGIN}/`);
    await page.waitForFunction(() => window.ready === true);

    for (const file of ['anim.glb', 'anim.gltf']) {
      const got = await page.evaluate(([url, t]) => window.play(url, t), [`/${file}`, times]);
      check(got.animations === 1, `${file}: ${got.animations} animations`);
      check(JSON.stringify(got.names) === JSON.stringify(expected.controllers),
        `${file}: morph target names ${JSON.stringify(got.names)}, expected ${JSON.stringify(expected.controllers)}`);
      check(got.vertices === 20 && got.normals, `${file}: ${got.vertices} vertices, normals ${got.normals}`);
      check(got.tracks.length === 1 && got.tracks[0].name.endsWith('.morphTargetInfluences'),
        `${file}: tracks ${JSON.stringify(got.tracks.map((t) => t.name))}`);
      const track = got.tracks[0];
      check(track.times.length === frames && track.times.every((t, f) => Math.abs(t - expected.times[f]) < 1e-6),
        `${file}: key times ${JSON.stringify(track.times)}, expected ${JSON.stringify(expected.times)}`);
      check(Math.abs(got.duration - duration) < 1e-6, `${file}: duration ${got.duration} s, expected ${duration} s`);
      let worst = 0;
      times.forEach((t, i) => {
        const want = weightsAt(expected, t);
        const have = got.influences[i];
        check(have.length === want.length, `${file} at ${t} s: ${have.length} influences, expected ${want.length}`);
        for (let c = 0; c < want.length; c++) {
          const error = Math.abs(have[c] - want[c]);
          worst = Math.max(worst, error);
          check(error <= TOLERANCE,
            `${file} at ${t.toFixed(5)} s: ${expected.controllers[c]} is ${have[c]}, expected ${want[c]} ` +
            `(all: ${JSON.stringify(have)} vs ${JSON.stringify(want)})`);
        }
      });
      console.log(`${file}: ${times.length} times over ${duration.toFixed(3)} s (${frames} frames at ${FPS} fps) x ` +
        `${expected.controllers.length} controllers: influences within ${worst.toExponential(1)} of the weights`);
    }
    check(!pageErrors.length, `errors in the page:\n${pageErrors.join('\n')}`);
    await fs.rm(scratch, { recursive: true, force: true });
    console.log('PASS');
    return 0;
  } finally {
    if (browser) await browser.close().catch(() => {});
  }
}


await runMain(main);
