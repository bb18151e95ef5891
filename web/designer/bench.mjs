// Speed of the designer in headless chromium (issue 25): 10 moves of the rise slider (through the
// test hook); per move the latency of geometry + stresses + constraint table (the synchronous
// part: parse, form-finding, force pass, verdict, 3D redraw) and the time until every state's
// buckling factor is in (both Web Workers). Prints a table and the medians.
//   node web/designer/bench.mjs /abs/designer.html
import { openDesigner, complete } from './common.mjs';

const { browser, page } = await openDesigner(process.argv[2] || process.env.KAPPE_DESIGNER);
await complete(page);
const rows = [];
// KAPPE_BENCH_MOVES (default 10, the median of 10; CI runs 3 to stay inside its hour).
const MOVES = Number(process.env.KAPPE_BENCH_MOVES || 10);
for (let k = 0; k < MOVES; k++) {
  const rise = 0.2 + 0.004 * (k + 1) * (k % 2 ? -1 : 1);
  const wall0 = Date.now();
  await page.evaluate((v) => window.kappeDesigner.set('cap.rise', v), rise);
  const s = await complete(page);
  rows.push({ rise, latency_ms: s.latency_ms, full_s: s.full_ms / 1000, wall_s: (Date.now() - wall0) / 1000, min_blf: s.min_blf, states: s.states_total });
}
await browser.close();
const med = (a) => { const b = [...a].sort((x, y) => x - y); const n = b.length; return n % 2 ? b[(n - 1) / 2] : (b[n / 2 - 1] + b[n / 2]) / 2; };
console.log('move  rise    latency_ms  full_verdict_s  min_blf');
rows.forEach((r, i) => console.log(`${String(i + 1).padStart(4)}  ${r.rise.toFixed(3)}  ${r.latency_ms.toFixed(1).padStart(10)}  ${r.full_s.toFixed(2).padStart(14)}  ${r.min_blf.toFixed(4)}`));
console.log(`median latency ${med(rows.map((r) => r.latency_ms)).toFixed(1)} ms; median time to full verdict ${med(rows.map((r) => r.full_s)).toFixed(2)} s (${rows[0].states} states)`);
