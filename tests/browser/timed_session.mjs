// A timed annotation session in headless Chromium against a running `retarget annotate serve`
// (for the README: its screenshot and the tool's own speed). Not part of the test suite.
//
//   node tests/browser/timed_session.mjs --url http://127.0.0.1:8080/ [--name timer]
//        [--comparisons 60] [--think-ms 0] [--screenshot docs/annotate.png]
//
// Signs in, answers --comparisons comparisons with the keyboard (left/right at random), waiting
// --think-ms after each comparison is fully shown (a person's decision time; 0 = the tool alone),
// and prints the median time from a key press to the next comparison fully shown (images loaded)
// and the comparisons per minute of the whole session.
import { chromium } from 'playwright-core';

function option(name, fallback) {
  const i = process.argv.indexOf(`--${name}`);
  return i > 0 && i + 1 < process.argv.length ? process.argv[i + 1] : fallback;
}

const url = option('url', 'http://127.0.0.1:8080/');
const name = option('name', 'timer');
const count = Number(option('comparisons', '60'));
const thinkMs = Number(option('think-ms', '0'));
const screenshot = option('screenshot', '');
const executablePath = option('chromium', '/usr/bin/chromium');

const browser = await chromium.launch({ executablePath, headless: true, args: ['--no-sandbox'] });
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  await page.goto(url);
  await page.fill('#signin-name', name);
  await page.click('#signin-button');
  const shownAfter = async (previous) => {
    await page.waitForFunction(
      (n) => {
        const c = document.getElementById('comparison');
        const view = document.body.dataset.view;
        return view === 'finished' || (c.dataset.state === 'ready' && Number(c.dataset.shown || 0) > n);
      },
      previous,
      { timeout: 60000 },
    );
    return page.evaluate(() => ({
      shown: Number(document.getElementById('comparison').dataset.shown || 0),
      finished: document.body.dataset.view === 'finished',
    }));
  };
  let state = await shownAfter(0);
  if (screenshot) {
    await page.waitForTimeout(700); // a few turntable frames
    await page.screenshot({ path: screenshot });
    console.log(`screenshot: ${screenshot}`);
  }
  const latencies = [];
  const start = Date.now();
  let answered = 0;
  while (answered < count && !state.finished) {
    if (thinkMs > 0) await page.waitForTimeout(thinkMs);
    const t0 = Date.now();
    await page.keyboard.press(Math.random() < 0.5 ? 'ArrowLeft' : 'ArrowRight');
    state = await shownAfter(state.shown);
    latencies.push(Date.now() - t0);
    answered += 1;
  }
  const minutes = (Date.now() - start) / 60000;
  latencies.sort((a, b) => a - b);
  const median = latencies.length ? latencies[Math.floor(latencies.length / 2)] : NaN;
  console.log(
    `${answered} comparisons, think time ${thinkMs} ms: median key -> next comparison shown ${median} ms ` +
      `(min ${latencies[0]}, max ${latencies[latencies.length - 1]}); ${(answered / minutes).toFixed(1)} comparisons/min`,
  );
  await page.click('#signout').catch(() => {});
} finally {
  await browser.close();
}
