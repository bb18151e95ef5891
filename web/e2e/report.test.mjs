// End-to-end test of report.html in headless Chromium (Debian `chromium`, driven by
// playwright-core; no browser download). Run by .ci/run:
//   KAPPE_REPORT=/abs/report.html [KAPPE_SCREENSHOT=out.png] node --test web/e2e/
// Checks: no console errors or page errors; WebGL2 context and three r187; the canvas is
// non-blank (pixel variance); moving the progress slider changes the shown state and the
// drawn scene; the robot animates; tables and plots are present.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { existsSync } from 'node:fs';
import { resolve } from 'node:path';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';

const REPORT = process.env.KAPPE_REPORT;
const CHROMIUM = process.env.KAPPE_CHROMIUM || '/usr/bin/chromium';
// Messages Chromium prints on software GL that are not errors of the page.
const HARMLESS = [/GPU stall due to ReadPixels/i, /Automatic fallback to software WebGL/i];

// Statistics of the WebGL canvas read back through a 2D canvas (preserveDrawingBuffer is on):
// the luminance variance and the share of pixels that differ from the white background.
function canvasStats() {
  const src = document.getElementById('kappe-canvas');
  const c = document.createElement('canvas');
  c.width = src.width;
  c.height = src.height;
  const ctx = c.getContext('2d');
  ctx.drawImage(src, 0, 0);
  const px = ctx.getImageData(0, 0, c.width, c.height).data;
  let n = 0, sum = 0, sum2 = 0, nonWhite = 0;
  for (let i = 0; i < px.length; i += 4) {
    const y = 0.2126 * px[i] + 0.7152 * px[i + 1] + 0.0722 * px[i + 2];
    n++; sum += y; sum2 += y * y;
    if (px[i] < 235 || px[i + 1] < 235 || px[i + 2] < 235) nonWhite++;
  }
  const mean = sum / n;
  return { width: c.width, height: c.height, variance: sum2 / n - mean * mean, nonWhite: nonWhite / n };
}

test('report.html renders offline in headless Chromium and the slider changes the state', async (t) => {
  assert.ok(REPORT, 'set KAPPE_REPORT to the report.html to test');
  assert.ok(existsSync(REPORT), `${REPORT} does not exist`);
  assert.ok(existsSync(CHROMIUM), `${CHROMIUM} not found (apt-get install chromium)`);

  const browser = await chromium.launch({
    executablePath: CHROMIUM,
    args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking',
      '--disable-component-update', '--disable-sync', '--no-first-run'],
  });
  t.after(() => browser.close());
  const page = await browser.newPage({ viewport: { width: 1400, height: 1000 } });
  const problems = [];
  page.on('console', (m) => {
    if (m.type() === 'error' && !HARMLESS.some((r) => r.test(m.text()))) problems.push(`console: ${m.text()}`);
  });
  page.on('pageerror', (e) => problems.push(`pageerror: ${e.message}`));
  // The page must be self-contained: any request other than the file itself is a failure.
  const requests = [];
  page.on('request', (r) => { if (!r.url().startsWith('file:') && !r.url().startsWith('data:')) requests.push(r.url()); });

  await page.goto(pathToFileURL(resolve(REPORT)).href);
  await page.waitForFunction(() => window.KAPPE_READY, null, { timeout: 60_000 });
  const ready = await page.evaluate(() => window.KAPPE_READY);
  assert.equal(ready.error, null, `viewer error: ${ready.error}`);
  assert.equal(ready.webgl2, true, 'no WebGL2 context');
  assert.equal(ready.revision, '187');
  assert.ok(ready.triangles > 0, 'nothing drawn');

  const data = await page.evaluate(() => JSON.parse(document.getElementById('kappe-data').textContent));
  const last = data.states.length - 1;
  assert.ok(last >= 1, 'the report needs at least two states for the slider test');
  assert.equal(await page.evaluate(() => window.KAPPE_STATE), last, 'starts at the final state');

  const full = await page.evaluate(canvasStats);
  // A blank (single-colour) canvas has variance 0; the cap covers a good part of the view.
  assert.ok(full.variance > 50, `canvas looks blank: luminance variance ${full.variance}`);
  assert.ok(full.nonWhite > 0.02, `canvas looks blank: ${full.nonWhite} non-background`);
  const viewLast = await page.evaluate(() => window.KAPPE_VIEW);
  const panelLast = await page.textContent('#st-index');

  // Move the slider to the first state, as a user dragging it would (fires `input`).
  await page.locator('#state-slider').fill('0');
  assert.equal(await page.evaluate(() => window.KAPPE_STATE), 0);
  const view0 = await page.evaluate(() => window.KAPPE_VIEW);
  assert.equal(view0.state, data.states[0].index);
  assert.equal(view0.layersPrinted, data.states[0].layers_printed);
  assert.ok(view0.triangles < viewLast.triangles, `first state draws ${view0.triangles} triangles, final ${viewLast.triangles}`);
  assert.notEqual(await page.textContent('#st-index'), panelLast, 'state panel did not change');
  const first = await page.evaluate(canvasStats);
  assert.ok(first.nonWhite < full.nonWhite, `scene did not shrink: ${first.nonWhite} vs ${full.nonWhite}`);

  // Keyboard: one step right.
  await page.focus('#state-slider');
  await page.keyboard.press('ArrowRight');
  assert.equal(await page.evaluate(() => window.KAPPE_STATE), 1);

  // Robot playback moves the arm.
  if (data.robot) {
    const before = await page.textContent('#robot-label');
    await page.click('#robot-play');
    await page.waitForFunction((b) => document.getElementById('robot-label').textContent !== b, before, { timeout: 10_000 });
    await page.click('#robot-play');
  }

  // Constraint table: one row per constraint, failures highlighted; all plots inline SVG.
  assert.equal(await page.locator('#constraints tbody tr').count(), data.constraints.length);
  assert.equal(await page.locator('#constraints tr.fail').count(), data.constraints.filter((c) => !c.pass).length);
  assert.ok(await page.locator('#plots svg').count() >= 3, 'plots missing');

  // Back to the final state for the screenshot, the robot at the end of its trajectory
  // (printing the last layer).
  await page.locator('#state-slider').fill(String(last));
  if (data.robot) await page.locator('#robot-time').fill(String(data.robot.times.length - 1));
  if (process.env.KAPPE_SCREENSHOT) {
    await page.screenshot({ path: process.env.KAPPE_SCREENSHOT, clip: { x: 0, y: 0, width: 1400, height: 850 } });
  }
  assert.deepEqual(requests, [], 'the page fetched something');
  assert.deepEqual(problems, [], 'console errors / page errors');
});
