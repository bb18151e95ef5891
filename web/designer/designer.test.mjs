// End-to-end test of the designer page (issue 25), run by web/designer/run.sh (and so by CI):
//   KAPPE_DESIGNER=/abs/designer.html KAPPE_BIN=/abs/kappe node --test web/designer/designer.test.mjs
// Loads the page from file:// in headless chromium, moves the rise slider (through the test
// hook, and once through the real slider), waits for every state's buckling factor, downloads
// the design.toml text and runs `kappe design` on it: the same verdict and every state's BLF
// within 1e-6 relative (the same library, compiled natively and to wasm32: the solver's
// arithmetic differs only in the order of a few floating-point sums, ~1e-13 relative; 1e-6 is
// the bound). A bad value typed into a field shows an error next to it and keeps the
// last good design. No console errors, no network requests.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { openDesigner, complete } from './common.mjs';

const PAGE = process.env.KAPPE_DESIGNER;
const KAPPE = process.env.KAPPE_BIN;

test('designer: rise slider, verdict and BLFs equal kappe design, errors, offline', async (t) => {
  assert.ok(PAGE && KAPPE, 'set KAPPE_DESIGNER and KAPPE_BIN');
  const { browser, page, errors, network } = await openDesigner(PAGE);
  t.after(() => browser.close());

  const first = await complete(page);
  assert.equal(first.error, null);
  assert.ok(first.states_total > 50, `states_total ${first.states_total}`);

  // The real slider: drag cap.rise, the design changes.
  const slider = page.locator('input[name="cap.rise:slider"]');
  await slider.fill('0.21');
  await page.waitForFunction(() => window.kappeDesigner.designToml().includes('rise = 0.21'));

  // The hook: rise 0.22; every state analysed again.
  const r = await page.evaluate(() => window.kappeDesigner.set('cap.rise', 0.22));
  assert.deepEqual(r, { ok: true });
  const s = await complete(page);
  assert.notEqual(s.min_blf, first.min_blf, 'the rise changes the lowest BLF');
  const toml = await page.evaluate(() => window.kappeDesigner.designToml());
  assert.match(toml, /rise = 0\.22/);

  // The overhangs coloured on the cap: the legend names the limit (overhang_max, lw/2 = 10 mm
  // on the default) and the largest layer overhang; back to the stresses.
  await page.locator('#colour-by').selectOption('overhang');
  const legend = await page.locator('#legend').textContent();
  assert.match(legend, /layer overhang: .* limit 10\.0 mm, .* largest \d+\.\d mm/, legend);
  await page.locator('#colour-by').selectOption('stress');
  assert.match(await page.locator('#legend').textContent(), /member stress/);

  // A bad value typed into a field: an error next to it, the last good design kept.
  const field = page.locator('input[name="cap.rise"]');
  await field.fill('-0.5');
  await field.dispatchEvent('change');
  const shown = await page.locator('[id="error-cap.rise"]').textContent();
  assert.match(shown, /cap\.rise/, `error shown: ${shown}`);
  const after = await page.evaluate(() => window.kappeDesigner.state());
  assert.equal(after.min_blf, s.min_blf);
  assert.equal(await page.evaluate(() => window.kappeDesigner.designToml()), toml);
  const bad = await page.evaluate(() => window.kappeDesigner.set('print.layer_width', 'wide'));
  assert.equal(bad.ok, false);
  assert.equal(bad.error.field, 'print.layer_width');

  // kappe design on the downloaded text: same verdict, every BLF within 1e-6 relative.
  const dir = mkdtempSync(join(tmpdir(), 'kappe-designer-'));
  writeFileSync(join(dir, 'design.toml'), toml);
  try {
    execFileSync(KAPPE, ['design', join(dir, 'design.toml'), '--out', join(dir, 'out'), '--quiet'], {
      stdio: ['ignore', 'ignore', 'inherit'],
    });
  } catch (e) {
    if (e.status !== 1) throw e; // 1: the design fails its checks (still written)
  }
  const summary = JSON.parse(readFileSync(join(dir, 'out', 'summary.json'), 'utf8'));
  assert.equal(s.ok, summary.ok, 'same verdict');
  assert.equal(summary.states.length, s.blf.length);
  let worst = 0;
  summary.states.forEach((st, i) => {
    const a = st.blf, b = s.blf[i];
    assert.equal(a === null, b === null, `state ${i}: BLF ${a} vs ${b}`);
    if (a !== null) worst = Math.max(worst, Math.abs(a - b) / Math.abs(a));
  });
  assert.ok(worst <= 1e-6, `largest relative BLF difference ${worst}`);
  console.log(`designer vs kappe design: ${summary.states.length} states, verdict ${summary.ok}, largest relative BLF difference ${worst.toExponential(2)}`);

  assert.deepEqual(errors, [], 'no console errors');
  assert.deepEqual(network, [], 'no network requests');
});
