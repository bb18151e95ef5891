// Shared by the designer's e2e test and benchmark: open designer.html from file:// in headless
// Debian chromium (playwright-core, no browser download), record console errors and every
// request that is not file:, blob: or data:.
import { pathToFileURL } from 'node:url';
import { resolve } from 'node:path';
import { chromium } from 'playwright-core';

const CHROMIUM = process.env.KAPPE_CHROMIUM || '/usr/bin/chromium';

export async function openDesigner(page_path) {
  const browser = await chromium.launch({
    executablePath: CHROMIUM,
    args: ['--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader'],
  });
  const page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  const errors = [];
  const network = [];
  page.on('console', (m) => {
    if (m.type() === 'error') errors.push(m.text());
  });
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('request', (r) => {
    if (!/^(file|blob|data):/.test(r.url())) network.push(r.url());
  });
  await page.goto(pathToFileURL(resolve(page_path)).href);
  await page.waitForFunction(() => window.KAPPE_DESIGNER_READY === true, null, { timeout: 60000 });
  return { browser, page, errors, network };
}

// Wait until every state's buckling factor is in; the state.
// The full verdict includes the mesh-error pass (the 2×2 split on a sample of the states,
// solved in the Web Workers batch by batch once every state is in): minutes on a loaded machine.
export async function complete(page, timeout = 600000) {
  await page.waitForFunction(
    () => {
      const s = window.kappeDesigner.state();
      return s.states_total > 0 && s.states_done === s.states_total && s.ok !== null;
    },
    null,
    { timeout, polling: 20 },
  );
  return page.evaluate(() => window.kappeDesigner.state());
}
