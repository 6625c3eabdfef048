#!/usr/bin/env node
// The Khronos glTF validator (npm gltf-validator, the reference implementation of the glTF 2.0
// specification's rules) on the animations retarget writes (infer/gltf_animation.h): the .glb
// and .gltf of gltf_animation_fixture and, with --retarget, the .glb that
// `retarget gltf-animation` makes from the fixture's rig folder and weights.csv.
//
//   node tests/browser/gltf_validator_test.mjs --fixture build/tests/gltf_animation_fixture \
//     --tmp /tmp [--retarget build/cli/retarget] [--keep]
//
// Exit status: 0 pass (warnings, infos and hints are printed), 1 fail (any error, or an asset
// that is not what was written), 77 skipped (gltf-validator not installed: `npm ci` in
// tests/browser, as scripts/setup.sh does).

import { existsSync } from 'node:fs';
import fs from 'node:fs/promises';
import path from 'node:path';
import { parseArgs } from 'node:util';

import { SKIP, check, runMain } from './harness.mjs';
import { runCommand } from './annotation_server_process.mjs';

const SEVERITY = ['error', 'warning', 'info', 'hint'];


// Validates one file; prints every issue; returns the report.
async function validate(validator, file) {
  const bytes = new Uint8Array(await fs.readFile(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0, // all of them
    // Our files are self-contained: any external resource is a failure.
    externalResourceFunction: (uri) => Promise.reject(new Error(`unexpected external resource ${uri}`)),
  });
  const { numErrors, numWarnings, numInfos, numHints, messages } = report.issues;
  console.log(`${file}: ${numErrors} errors, ${numWarnings} warnings, ${numInfos} infos, ${numHints} hints`);
  for (const m of messages) console.log(`  ${SEVERITY[m.severity] ?? m.severity} ${m.code} at ${m.pointer ?? '-'}: ${m.message}`);
  return report;
}

async function main() {
  const { values: args } = parseArgs({
    options: {
      fixture: { type: 'string' },
      retarget: { type: 'string' },
      tmp: { type: 'string' },
      keep: { type: 'boolean', default: false },
    },
  });
  if (!args.fixture || !args.tmp) {
    console.error('usage: gltf_validator_test.mjs --fixture PATH --tmp DIR [--retarget PATH] [--keep]');
    return 1;
  }
  let validator;
  try {
    validator = (await import('gltf-validator')).default;
  } catch (e) {
    console.log('SKIP: gltf-validator is not installed (run `npm ci --no-audit --no-fund` in tests/browser): ' +
      `${e.message.split('\n')[0]}`);
    return SKIP;
  }
  check(existsSync(args.fixture), `--fixture ${args.fixture}: no such file (build the project first)`);

  const scratch = path.resolve(args.tmp, `gltf_validator_${process.pid}`);
  await fs.rm(scratch, { recursive: true, force: true });
  await runCommand(args.fixture, [scratch, '24']);
  const expected = JSON.parse(await fs.readFile(path.join(scratch, 'expected.json'), 'utf8'));
  const files = [path.join(scratch, 'anim.glb'), path.join(scratch, 'anim.gltf')];
  if (args.retarget) {
    check(existsSync(args.retarget), `--retarget ${args.retarget}: no such file (build the project first)`);
    const out = path.join(scratch, 'cli.glb');
    const printed = await runCommand(args.retarget, ['gltf-animation', '--rig', path.join(scratch, 'rig'),
      '--weights', path.join(scratch, 'weights.csv'), '--fps', '24', '--out', out]);
    console.log(`retarget gltf-animation: ${printed.trim()}`);
    files.push(out);
    // A table whose columns are not the rig's controllers is refused, naming the first that differs.
    const csv = await fs.readFile(path.join(scratch, 'weights.csv'), 'utf8');
    const renamed = path.join(scratch, 'renamed.csv');
    await fs.writeFile(renamed, csv.replace(`,${expected.controllers[1]},`, ',smileLeft,'));
    const refused = await runCommand(args.retarget, ['gltf-animation', '--rig', path.join(scratch, 'rig'),
      '--weights', renamed, '--out', path.join(scratch, 'refused.glb')]).then(() => '', (e) => e.message);
    const want = `column 3 is "smileLeft" but the rig's controller 2 is "${expected.controllers[1]}"`;
    check(refused.includes(want), `retarget gltf-animation with renamed.csv: expected an error with '${want}', got: ${refused || 'success'}`);
    check(!existsSync(path.join(scratch, 'refused.glb')), 'a refused table still wrote refused.glb');
    console.log('retarget gltf-animation refuses a table with other columns: ok');
  }

  const frames = expected.weights.length;
  const controllers = expected.controllers.length;
  let warnings = 0;
  for (const file of files) {
    const report = await validate(validator, file);
    warnings += report.issues.numWarnings;
    check(report.issues.numErrors === 0, `${file}: ${report.issues.numErrors} validation errors (listed above)`);
    // What the validator saw is what was written: one animation of the morph weights.
    const info = report.info ?? {};
    check(info.version === '2.0', `${file}: version ${info.version}`);
    check(info.animationCount === 1, `${file}: ${info.animationCount} animations, expected 1`);
    check(info.hasMorphTargets === true, `${file}: the validator found no morph targets`);
    check(info.totalTriangleCount === 24 && info.totalVertexCount === 20,
      `${file}: ${info.totalTriangleCount} triangles and ${info.totalVertexCount} vertices, expected 24 and 20`);
    console.log(`  ok: ${frames} frames x ${controllers} controllers, ${info.totalVertexCount} vertices, ` +
      `${info.totalTriangleCount} triangles, generator "${info.generator}"`);
  }
  if (!args.keep) await fs.rm(scratch, { recursive: true, force: true });
  console.log(`PASS: ${files.length} files valid glTF 2.0 (${warnings} warnings)`);
  return 0;
}

await runMain(main);
