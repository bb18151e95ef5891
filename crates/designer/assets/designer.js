// Kappe designer page (issue 25): the design's parameters as sliders and fields, the cap in 3D
// coloured by member stress (the vendored three.js bundle of the report), the per-state table
// and the constraint report. Every number comes from the kappe library compiled to WebAssembly
// (crates/designer): `Session` on this thread (parse, validate, form-finding, stresses,
// overhangs, verdict), `Worker` in two Web Workers (the buckling factor of every state). The
// wasm bytes are inlined (base64, #kappe-wasm) and the workers are made from Blob URLs, so the
// page opens offline from a file.
//
// Test hook: window.kappeDesigner = { set(field, value), state(), designToml(), load(text) };
// window.KAPPE_DESIGNER_READY once the first design is shown.
(async function () {
  'use strict';
  const $ = (id) => document.getElementById(id);
  const THREE = window.THREE;
  const GLUE = $('kappe-glue').textContent;
  const WORKER_SRC = $('kappe-worker').textContent;
  const b64 = $('kappe-wasm').textContent.trim();
  const gz = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
  const bytes = await new Response(new Blob([gz]).stream().pipeThrough(new DecompressionStream('gzip'))).arrayBuffer();
  const module = await WebAssembly.compile(bytes);
  wasm_bindgen.initSync({ module });
  const session = new wasm_bindgen.Session();

  // ---- the parameters ----------------------------------------------------------------------
  // [field, label, min, max, step]; the field names are the design file's.
  const FIELDS = [
    ['cap.span', 'span Cs, m', 0.3, 2.0, 0.01],
    ['cap.rise', 'rise Cr, m', 0.05, 0.6, 0.005],
    ['cap.length', 'length Cl, m', 0.05, 2.0, 0.01],
    ['cap.tilt_deg', 'layer tilt am, °', 5, 60, 0.5],
    ['print.layer_height', 'layer height lh, m', 0.006, 0.015, 0.0005],
    ['print.layer_width', 'layer width lw, m', 0.015, 0.03, 0.0005],
    ['print.print_speed', 'print speed, m/s', 0.01, 0.2, 0.005],
    ['material.specific_weight', 'specific weight γ, N/m³', 10000, 30000, 100],
    ['material.youngs_modulus', 'Young’s modulus E, Pa', 1e6, 50e6, 1e5],
    ['material.poisson_ratio', 'Poisson ratio ν', 0.0, 0.49, 0.01],
    ['constraints.sigma_min', 'σ_min, Pa', -200e3, 0, 1e3],
    ['constraints.sigma_max', 'σ_max, Pa', 0, 50e3, 100],
    ['constraints.blf_min', 'BLF_min', 0.5, 5, 0.05],
    ['schedule.wait', 'wait after each layer, s', 0, 120, 1],
  ];
  const SELECTS = [
    ['material.time.preset', 'time model', ['', 'wolfs2018', 'earth']],
  ];
  const inputs = {};
  const errs = {};

  function row(field, label, control) {
    const div = document.createElement('div');
    div.className = 'field';
    div.dataset.field = field;
    const l = document.createElement('label');
    l.textContent = label;
    div.appendChild(l);
    control.forEach((c) => div.appendChild(c));
    const e = document.createElement('div');
    e.className = 'error';
    e.id = 'error-' + field;
    div.appendChild(e);
    errs[field] = e;
    $('fields').appendChild(div);
  }
  for (const [field, label, min, max, step] of FIELDS) {
    const range = document.createElement('input');
    Object.assign(range, { type: 'range', min, max, step });
    range.setAttribute('aria-label', field);
    range.name = field + ':slider';
    const num = document.createElement('input');
    Object.assign(num, { type: 'text', inputMode: 'decimal' });
    num.name = field;
    num.setAttribute('aria-label', field + ' value');
    range.addEventListener('input', () => {
      num.value = range.value;
      set(field, Number(range.value));
    });
    num.addEventListener('change', () => {
      const v = num.value.trim();
      set(field, v === '' || isNaN(Number(v)) ? v : Number(v));
    });
    inputs[field] = { range, num };
    row(field, label, [range, num]);
  }
  for (const [field, label, options] of SELECTS) {
    const sel = document.createElement('select');
    sel.name = field;
    for (const o of options) {
      const opt = document.createElement('option');
      opt.value = o;
      opt.textContent = o || 'none (constant E)';
      sel.appendChild(opt);
    }
    sel.addEventListener('change', () => set(field, sel.value === '' ? null : sel.value));
    inputs[field] = { select: sel };
    row(field, label, [sel]);
  }

  function showFields() {
    for (const f of Object.keys(inputs)) {
      const v = JSON.parse(session.get(f));
      const i = inputs[f];
      if (i.select) i.select.value = v === null ? '' : String(v);
      else {
        if (v !== null && document.activeElement !== i.num) i.num.value = String(v);
        if (v !== null) i.range.value = String(v);
      }
    }
  }
  function clearErrors() {
    for (const e of Object.values(errs)) e.textContent = '';
    $('error-design').textContent = '';
  }
  function showError(e) {
    const target = errs[e.field] || $('error-design');
    target.textContent = (e.field && !errs[e.field] ? e.field + ': ' : '') + e.message;
  }

  // ---- state ------------------------------------------------------------------------------
  let current = null; // the last good design's load result
  let report = null;
  let lastError = null;
  let t0 = 0;
  const timing = { latency_ms: null, full_ms: null };

  function parseErr(e) {
    try {
      return JSON.parse(String(e));
    } catch (_) {
      return { field: '', message: String(e) };
    }
  }

  function apply(res) {
    current = res;
    report = res.report;
    clearErrors();
    lastError = null;
    showFields();
    drawCap(res.view);
    drawReport();
    timing.latency_ms = performance.now() - t0;
    $('latency').textContent = timing.latency_ms.toFixed(0) + ' ms';
    startWorkers(res);
  }

  function set(field, value) {
    t0 = performance.now();
    try {
      apply(JSON.parse(session.set(field, JSON.stringify(value))));
      return { ok: true };
    } catch (e) {
      lastError = parseErr(e);
      if (!lastError.field) lastError.field = field;
      showError(lastError);
      return { ok: false, error: lastError };
    }
  }

  function load(text, source) {
    t0 = performance.now();
    try {
      apply(JSON.parse(session.load(text)));
      return { ok: true };
    } catch (e) {
      lastError = parseErr(e);
      clearErrors();
      showError(lastError);
      if (source) $('error-design').textContent = source + ': ' + (lastError.field ? lastError.field + ': ' : '') + lastError.message;
      return { ok: false, error: lastError };
    }
  }

  // ---- workers ----------------------------------------------------------------------------
  const NWORKERS = Math.max(1, Math.min(2, navigator.hardwareConcurrency || 2));
  const workerUrl = URL.createObjectURL(new Blob([GLUE, '\n', WORKER_SRC], { type: 'text/javascript' }));
  let pool = [];
  // Jobs: { run: [state indices], max_split, owner } (max_split 1: the first pass; more: the
  // mesh-error pass, whose state goes to the worker that solved its first pass: it keeps that
  // solve's mode and starts from it, as `kappe design` does; a worker with nothing of its own
  // left takes the other's largest job and solves it cold).
  let queue = [];
  // The worker that solved each state's first pass (this design).
  let owner = new Map();
  // Results not yet handed to the session. Each hand-over re-evaluates the whole design (the
  // verdict of every state so far) on this thread, which shares the two cores with the workers:
  // results are handed over together, at most every FLUSH_MS while the workers have queued
  // work, and at once when a worker waits or nothing is queued (the next mesh-error batch
  // depends on them).
  const FLUSH_MS = 400;
  let pending = [];
  let flushTimer = null;
  let lastFlush = 0;
  // The mesh-error solves handed out for the current design ("state:split"): the pass names
  // what it still lacks, so a batch shrinks as its results come in and must not be sent twice.
  let sent = new Set();

  function spawn() {
    const w = new Worker(workerUrl);
    w.postMessage({ module });
    w.busy = false;
    w.onmessage = (ev) => onWorker(w, ev.data);
    w.onerror = (ev) => {
      console.warn('designer worker: ' + ev.message);
    };
    return w;
  }

  function startWorkers(res) {
    // Workers still busy with an older design are stopped (a wasm call cannot be interrupted).
    pool = pool.map((w) => {
      if (w.busy) {
        w.terminate();
        return spawn();
      }
      return w;
    });
    while (pool.length < NWORKERS) pool.push(spawn());
    queue = res.runs.map((r) => ({ run: r.slice(), max_split: 1, owner: null }));
    sent = new Set();
    owner = new Map();
    pending = [];
    clearTimeout(flushTimer);
    flushTimer = null;
    pool.forEach(feed);
    if (res.runs.length === 0) finished();
  }
  function feed(w) {
    if (w.busy || !queue.length || !current) return;
    w.busy = true;
    let k = queue.findIndex((j) => j.owner === w || j.owner === null);
    if (k < 0) k = 0;
    const job = queue.splice(k, 1)[0];
    w.postMessage({ generation: current.generation, text: current.text, run: job.run, max_split: job.max_split });
  }
  // Once every first-pass factor is in, the mesh-error pass (kappe's `converge_fe`, replayed on
  // this thread at every result) asks for the split solves it needs next, batch by batch: each
  // state is one job, largest first, so both workers stay busy (longest processing time first).
  function refine(batch) {
    if (!batch) return;
    const todo = batch.states.filter((i) => !sent.has(i + ':' + batch.max_split));
    todo.sort((a, b) => b - a);
    for (const i of todo) {
      sent.add(i + ':' + batch.max_split);
      queue.push({ run: [i], max_split: batch.max_split, owner: owner.get(i) || null });
    }
    pool.forEach(feed);
  }
  function onWorker(w, msg) {
    if (msg.done !== undefined) {
      w.busy = false;
      if (msg.error) {
        console.warn('designer worker: ' + msg.error);
      }
      feed(w);
      if (pending.length && !w.busy) flush();
      return;
    }
    if (!current || msg.generation !== current.generation) return;
    if (msg.max_split === 1) owner.set(msg.state, w);
    pending.push(msg.result);
    const starving = !queue.length || pool.some((x) => !x.busy);
    const wait = lastFlush + FLUSH_MS - performance.now();
    if (starving || wait <= 0) flush();
    else if (flushTimer === null) flushTimer = setTimeout(flush, wait);
  }
  function flush() {
    clearTimeout(flushTimer);
    flushTimer = null;
    if (!pending.length || !current) return;
    // Each result is a JSON list of one state's FeWire: one list of them all.
    const results = '[' + pending.map((r) => r.slice(1, -1)).filter((r) => r.length).join(',') + ']';
    pending = [];
    lastFlush = performance.now();
    try {
      report = JSON.parse(session.add_fe(current.generation, results));
    } catch (e) {
      showError(parseErr(e));
      return;
    }
    drawReport();
    refine(report.refine);
    if (report.complete) finished();
  }
  function finished() {
    timing.full_ms = performance.now() - t0;
    $('full').textContent = (timing.full_ms / 1000).toFixed(2) + ' s';
  }

  // ---- the report ----------------------------------------------------------------------------
  const fmt = (v, d) => (v === null || v === undefined ? '–' : Number(v).toFixed(d));
  function readable(v, unit) {
    if (v === null || v === undefined) return 'not checked yet';
    if (unit === 'Pa') return fmt(Math.abs(v) < 5 ? 0 : v / 1e3, 2) + ' kPa';
    if (unit === 'm') return fmt(v * 1e3, 1) + ' mm';
    return fmt(v, 3);
  }
  function drawReport() {
    const r = report;
    if (!r) return;
    const v = $('verdict');
    if (r.complete) {
      v.textContent = r.ok ? 'PASS' : 'FAIL';
      v.className = 'verdict ' + (r.ok ? 'pass' : 'fail');
    } else {
      const what = r.refine ? 'mesh error, ' + r.refine.states.length + ' states left in this round' : 'buckling ' + r.states_done + ' / ' + r.states_total;
      v.textContent = (r.ok_so_far ? 'passing so far' : 'FAIL') + ' (' + what + ')';
      v.className = 'verdict ' + (r.ok_so_far ? 'pending' : 'fail');
    }
    $('progress').value = r.states_total ? r.states_done / r.states_total : 1;
    $('min-blf').textContent = fmt(r.min_blf, 3);
    const tb = $('constraints').tBodies[0];
    tb.textContent = '';
    for (const c of r.constraints) {
      const tr = tb.insertRow();
      tr.className = c.pass ? 'pass' : 'fail';
      [c.name, c.pass ? 'PASS' : 'FAIL', readable(c.limit, c.unit), readable(c.worst, c.unit), c.state === null ? '' : String(c.state), c.element]
        .forEach((t) => (tr.insertCell().textContent = t));
    }
    $('failures').textContent = r.failures.join('\n');
    drawPlot(r.states);
  }

  // Per-state plot: compression (kPa) and BLF over the print states (SVG, no library).
  function drawPlot(states) {
    const W = 520, H = 160, P = 28;
    const n = Math.max(1, states.length - 1);
    const comp = states.map((s) => -s.compression_pa / 1e3);
    const cmax = Math.max(1e-9, ...comp);
    const blfs = states.map((s) => s.blf).filter((b) => b !== null);
    const bmax = Math.max(1, ...blfs);
    const x = (i) => P + ((W - 2 * P) * i) / n;
    const y = (v, m) => H - P - ((H - 2 * P) * v) / m;
    let d1 = '', d2 = '';
    states.forEach((s, i) => {
      d1 += (i ? 'L' : 'M') + x(i).toFixed(1) + ' ' + y(comp[i], cmax).toFixed(1);
      if (s.blf !== null) d2 += 'M' + x(i).toFixed(1) + ' ' + y(s.blf, bmax).toFixed(1) + 'h0.1';
    });
    $('plot').innerHTML =
      `<svg viewBox="0 0 ${W} ${H}" width="100%" role="img" aria-label="per state compression and BLF">` +
      `<path d="${d1}" fill="none" stroke="#1f77b4"/><path d="${d2}" stroke="#d62728" stroke-width="4" stroke-linecap="round"/>` +
      `<text x="${P}" y="12" font-size="11" fill="#1f77b4">max compression, up to ${cmax.toFixed(2)} kPa</text>` +
      `<text x="${W - P}" y="12" font-size="11" fill="#d62728" text-anchor="end">BLF, up to ${bmax.toFixed(2)}</text>` +
      `<text x="${W / 2}" y="${H - 6}" font-size="11" text-anchor="middle">print state</text></svg>`;
  }

  // ---- 3D -----------------------------------------------------------------------------------
  const canvas = $('kappe-canvas');
  let renderer = null, scene, camera, controls, lines = null, fitted = false;
  try {
    renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    $('viewer-message').textContent = 'no WebGL: ' + e.message;
  }
  if (renderer) {
    scene = new THREE.Scene();
    scene.background = new THREE.Color(0xffffff);
    camera = new THREE.PerspectiveCamera(40, 1, 0.01, 100);
    camera.up.set(0, 0, 1);
    controls = new THREE.OrbitControls(camera, canvas);
    controls.addEventListener('change', render);
  }
  function render() {
    if (!renderer) return;
    const w = canvas.clientWidth, h = canvas.clientHeight;
    if (canvas.width !== w || canvas.height !== h) {
      renderer.setSize(w, h, false);
      camera.aspect = w / Math.max(1, h);
      camera.updateProjectionMatrix();
    }
    renderer.render(scene, camera);
  }
  window.addEventListener('resize', render);
  // Compression blue, zero grey, tension red.
  function colour(stress, scale) {
    const u = Math.max(-1, Math.min(1, stress / scale));
    return u < 0 ? [0.6 + 0.6 * u, 0.6 + 0.2 * u, 0.6 + 0.3 * -u] : [0.6 + 0.4 * u, 0.6 - 0.5 * u, 0.6 - 0.5 * u];
  }
  // Overhang o against the limit: grey (none) to orange (at the limit), red above it.
  function overhangColour(o, limit) {
    if (o > limit) return [0.9, 0.1, 0.1];
    const u = Math.max(0, Math.min(1, o / Math.max(limit, 1e-12)));
    return [0.6 + 0.4 * u, 0.6, 0.6 - 0.5 * u];
  }
  function drawCap(view) {
    if (!renderer) return;
    if (lines) {
      scene.remove(lines);
      lines.geometry.dispose();
    }
    // Plain loops into the typed arrays: this runs on every change, for ~10^4 members
    // (`members`: node indices of member k at 2k, 2k + 1; `stress`: its stress).
    const m = view.members, st = view.stress, xyz = view.xyz;
    const pos = new Float32Array(st.length * 6);
    const col = new Float32Array(st.length * 6);
    // Colour by member stress, or by the overhang of the members' layers against the limit.
    const byOverhang = $('colour-by').value === 'overhang';
    const oh = view.overhang, ohMax = view.overhang_max;
    let scale = 1e-9;
    for (let k = 0; k < st.length; k++) scale = Math.max(scale, Math.abs(st[k]));
    for (let k = 0; k < st.length; k++) {
      const c = byOverhang ? overhangColour(Math.max(oh[m[2 * k]], oh[m[2 * k + 1]]), ohMax) : colour(st[k], scale);
      for (let s = 0; s < 2; s++) {
        const j = 3 * m[2 * k + s], o = 6 * k + 3 * s;
        pos[o] = xyz[j];
        pos[o + 1] = xyz[j + 1];
        pos[o + 2] = xyz[j + 2];
        col[o] = c[0];
        col[o + 1] = c[1];
        col[o + 2] = c[2];
      }
    }
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    geo.setAttribute('color', new THREE.BufferAttribute(col, 3));
    lines = new THREE.LineSegments(geo, new THREE.LineBasicMaterial({ vertexColors: true }));
    scene.add(lines);
    $('legend').textContent = byOverhang
      ? 'layer overhang: grey none … orange at the limit ' + (ohMax * 1e3).toFixed(1) + ' mm, red above it; largest ' + (Math.max(0, ...oh) * 1e3).toFixed(1) + ' mm'
      : 'member stress: blue compression … red tension, |σ| up to ' + (scale / 1e3).toFixed(2) + ' kPa';
    if (!fitted) {
      geo.computeBoundingSphere();
      const c = geo.boundingSphere.center, r = geo.boundingSphere.radius;
      camera.position.set(c.x + 2.2 * r, c.y - 2.6 * r, c.z + 1.8 * r);
      controls.target.copy(c);
      controls.update();
      fitted = true;
    }
    render();
  }

  $('colour-by').addEventListener('change', () => current && drawCap(current.view));

  // ---- files ----------------------------------------------------------------------------------
  $('download').addEventListener('click', () => {
    const a = document.createElement('a');
    a.href = URL.createObjectURL(new Blob([session.text()], { type: 'application/toml' }));
    a.download = 'design.toml';
    a.click();
    setTimeout(() => URL.revokeObjectURL(a.href), 1000);
  });
  function openFile(file) {
    file.text().then((text) => load(text, file.name));
  }
  $('open').addEventListener('change', (ev) => ev.target.files[0] && openFile(ev.target.files[0]));
  document.addEventListener('dragover', (ev) => ev.preventDefault());
  document.addEventListener('drop', (ev) => {
    ev.preventDefault();
    const f = ev.dataTransfer && ev.dataTransfer.files[0];
    if (f) openFile(f);
  });

  window.kappeDesigner = {
    set: (field, value) => set(field, value),
    load: (text) => load(text, 'design'),
    designToml: () => session.text(),
    state: () => ({
      ok: report ? report.ok : null,
      ok_so_far: report ? report.ok_so_far : null,
      min_blf: report ? report.min_blf : null,
      states_done: report ? report.states_done : 0,
      states_total: report ? report.states_total : 0,
      blf: report ? report.states.map((s) => s.blf) : [],
      error: lastError,
      latency_ms: timing.latency_ms,
      full_ms: report && report.complete ? timing.full_ms : null,
    }),
  };
  load(wasm_bindgen.default_toml(), null);
  window.KAPPE_DESIGNER_READY = true;
})();
