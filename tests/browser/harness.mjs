// What every browser and node test here shares: the exit code CTest reads as "skipped", the
// Chromium binaries looked for, the failure a check raises, and running a test's main() so that
// its own failures print one line and anything else (Playwright, Node) its stack too.
import { existsSync } from 'node:fs';

export const SKIP = 77;
export const CHROMIUM_CANDIDATES = ['/usr/bin/chromium', '/usr/bin/chromium-browser', '/usr/bin/google-chrome'];

export class TestFailure extends Error {}

export function check(condition, message) {
  if (!condition) throw new TestFailure(message);
}

// The Chromium to drive: `given` (--chromium) or the first candidate installed; null after
// printing why the test is skipped.
export function findChromium(given) {
  const chromiumPath = given || CHROMIUM_CANDIDATES.find((p) => existsSync(p));
  if (!chromiumPath || !existsSync(chromiumPath)) {
    console.log(`SKIP: no chromium binary (${given || CHROMIUM_CANDIDATES.join(', ')} not found)`);
    return null;
  }
  return chromiumPath;
}

// Sets the process's exit code from `main` (an async function returning 0, 1 or SKIP).
export async function runMain(main) {
  try {
    process.exitCode = await main();
  } catch (e) {
    const stack = e instanceof TestFailure ? '' : `\n${(e.stack || '').split('\n').filter((l) => /^\s+at /.test(l)).join('\n')}`;
    console.error(`FAIL: ${e.message}${stack}`);
    process.exitCode = 1;
  }
}
