// Kappe designer Web Worker (appended to the wasm-bindgen glue in a Blob URL): the buckling
// analysis of the print states of one run of `fe_runs`, by `kappe_designer::Worker`
// (kappe::analysis::state_fe). Messages in: { module } once, then
// { generation, text, run, max_split } (max_split 1: the first pass; more: states of the
// mesh-error pass). Out: { generation, max_split, state, result } per state, { done } per run.
let worker = null;
self.onmessage = (ev) => {
  const m = ev.data;
  if (m.module) {
    wasm_bindgen.initSync({ module: m.module });
    worker = new wasm_bindgen.Worker();
    return;
  }
  try {
    // One result per state of the run, in order: its index rides along, so the page need not
    // parse the result (a first-pass result carries the state's as-printed increment).
    let k = 0;
    worker.run(m.text, Uint32Array.from(m.run), m.max_split || 1, (result) => self.postMessage({ generation: m.generation, max_split: m.max_split || 1, state: m.run[k++], result }));
    self.postMessage({ done: m.generation });
  } catch (e) {
    self.postMessage({ done: m.generation, error: String(e) });
  }
};
