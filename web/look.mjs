// A quick look at a report (console, timings, hook values, screenshots at 25/50/100 %):
//   node web/look.mjs REPORT.html OUT.png
import { chromium } from 'playwright-core';
import { resolve } from 'node:path';
import { pathToFileURL } from 'node:url';
const [report, shot] = process.argv.slice(2);
const browser = await chromium.launch({ executablePath: '/usr/bin/chromium', args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'] });
const page = await browser.newPage({ viewport: { width: 1400, height: 1000 } });
page.on('console', (m) => console.log('console', m.type(), m.text()));
page.on('pageerror', (e) => console.log('pageerror', e.message));
const t0 = Date.now();
await page.goto(pathToFileURL(resolve(report)).href);
await page.waitForFunction(() => window.KAPPE_READY, null, { timeout: 60000 });
console.log('ready ms', Date.now() - t0, await page.evaluate(() => JSON.stringify(window.KAPPE_READY)));
for (const f of [0.25, 0.5, 1]) {
  const r = await page.evaluate((f) => { const k = window.kappeReport; k.seek(f); return { t: k.robotTime(), T: k.totalTime(), s: k.state(), l: k.layers(), n: k.nozzle() }; }, f);
  console.log(f, JSON.stringify(r));
  if (shot) await page.screenshot({ path: shot.replace('.png', `-${f * 100}.png`), clip: { x: 0, y: 0, width: 1400, height: 900 } });
}
await browser.close();
