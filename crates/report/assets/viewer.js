// Kappe report viewer: draws the scene island (`#kappe-data`, built by crates/report/src/island.rs
// from the ReportInput of input.rs) with the vendored three.js bundle (`window.THREE`, which also
// carries `OrbitControls`). Hand-written, no build step: it is inlined into report.html as is.
//
// One timeline: every moment t of the print (robot clock, s) shows the path points printed by t
// (the beads up to the nozzle, the partly printed layer included), the robot posed at t and the
// numbers of the analysed print state of the complete layers. Frames and units: world frame of
// method.md (x span, y along the cap, z up), metres, Pa, seconds.
//
// Test hook (end-to-end tests): window.kappeReport = { seek(fraction), state(), layers(),
// robotTime(), totalTime(), nozzle() } and window.KAPPE_READY after the first render.
(function () {
  'use strict';

  const $ = (id) => document.getElementById(id);
  const data = JSON.parse($('kappe-data').textContent);
  const robotAsset = $('kappe-robot') ? JSON.parse($('kappe-robot').textContent) : null;
  const THREE = window.THREE;

  // ---- typed arrays from base64 -------------------------------------------------------------
  function bytes(b64) {
    const s = atob(b64 || '');
    const out = new Uint8Array(s.length);
    for (let i = 0; i < s.length; i++) out[i] = s.charCodeAt(i);
    return out.buffer;
  }
  const f32 = (b) => new Float32Array(bytes(b));
  const i32 = (b) => new Int32Array(bytes(b));
  const i8 = (b) => new Int8Array(bytes(b));

  // ---- formatting -------------------------------------------------------------------------
  const fmt = (v, digits) => (v === null || v === undefined ? '–' : Number(v).toFixed(digits));
  const kPa = (pa) => fmt(pa / 1e3, 2) + ' kPa';
  const mm = (m) => fmt(m * 1e3, 2) + ' mm';
  function num(v) {
    const a = Math.abs(v);
    if (v === 0) return '0';
    if (a >= 1000 || a < 0.01) return v.toPrecision(3).replace(/\.?0+e/, 'e');
    return String(Number(v.toPrecision(3)));
  }
  function clock(s) {
    if (s < 90) return fmt(s, 1) + ' s';
    return fmt(s / 60, 1) + ' min';
  }
  // 1-2-5 ticks over [lo, hi], about n of them.
  function niceTicks(lo, hi, n) {
    if (!(hi > lo)) return [lo];
    const raw = (hi - lo) / n;
    const mag = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= raw) || 10 * mag;
    const out = [];
    for (let v = Math.ceil(lo / step - 1e-9) * step; v <= hi + step * 1e-9; v += step) out.push(Math.abs(v) < step * 1e-9 ? 0 : v);
    return out;
  }

  // ---- the data, decoded -------------------------------------------------------------------
  const L = data.layers.length;
  const nodes = f32(data.nodes);
  const layerNode0 = []; // first node of each layer in `nodes`
  const layerSeg0 = []; // first segment of each layer
  {
    let n = 0;
    let s = 0;
    for (const l of data.layers) {
      layerNode0.push(n);
      layerSeg0.push(s);
      n += l.n;
      s += l.n - 1;
    }
    layerNode0.push(n);
    layerSeg0.push(s);
  }
  const nSeg = layerSeg0[L];
  const layerIndex = new Map(data.layers.map((l, k) => [l.id, k]));
  const path = {
    points: f32(data.path.points),
    axis: f32(data.path.axis),
    layer: i32(data.path.layer),
    time: f32(data.path.time),
  };
  const nPts = path.time.length;
  const T = Math.max(data.total_time, nPts ? path.time[nPts - 1] : 0, 1e-9);
  // Path points of each layer (print order is layer order) and the layer's print interval.
  const layerPt0 = new Array(L).fill(nPts);
  const layerPt1 = new Array(L).fill(0);
  for (let i = 0; i < nPts; i++) {
    const k = layerIndex.get(path.layer[i]);
    if (k === undefined) continue;
    layerPt0[k] = Math.min(layerPt0[k], i);
    layerPt1[k] = Math.max(layerPt1[k], i + 1);
  }
  const layerStart = [];
  const layerEnd = [];
  {
    let last = 0;
    for (let k = 0; k < L; k++) {
      if (layerPt1[k] > layerPt0[k]) {
        layerStart.push(path.time[layerPt0[k]]);
        layerEnd.push(path.time[layerPt1[k] - 1]);
        last = path.time[layerPt1[k] - 1];
      } else {
        // A layer without path points is printed at the end of the one before.
        layerStart.push(last);
        layerEnd.push(last);
      }
    }
  }
  // Time at which each bead node is reached: that of the nearest path point of its layer.
  const nodeTime = new Float32Array(layerNode0[L]);
  for (let k = 0; k < L; k++) {
    for (let j = layerNode0[k]; j < layerNode0[k + 1]; j++) {
      let best = Infinity;
      let t = layerEnd[k];
      for (let i = layerPt0[k]; i < layerPt1[k]; i++) {
        const dx = nodes[3 * j] - path.points[3 * i];
        const dy = nodes[3 * j + 1] - path.points[3 * i + 1];
        const dz = nodes[3 * j + 2] - path.points[3 * i + 2];
        const d = dx * dx + dy * dy + dz * dz;
        if (d < best) {
          best = d;
          t = path.time[i];
        }
      }
      nodeTime[j] = t;
    }
  }
  // A segment is printed once both its nodes are.
  const segTime = new Float32Array(nSeg);
  for (let k = 0; k < L; k++) {
    for (let j = 0; j < data.layers[k].n - 1; j++) {
      const a = layerNode0[k] + j;
      segTime[layerSeg0[k] + j] = Math.max(nodeTime[a], nodeTime[a + 1]);
    }
  }

  const quantities = data.quantities.map((q) => ({
    ...q,
    pool: f32(q.pool),
    offsets: i32(q.offsets),
    scales: f32(q.scales),
  }));
  // Offset of state s's first chunk in a quantity's `offsets` (cumulative printed layers).
  const stateChunk0 = [0];
  for (const st of data.states) stateChunk0.push(stateChunk0[stateChunk0.length - 1] + st.layers_printed);
  const limitOf = (key) => data.constraints.find((c) => c.name.toLowerCase().includes(key));
  const kpaToPa = (c) => (c.unit === 'MPa' ? 1e6 : c.unit === 'kPa' ? 1e3 : 1) * c.limit;
  const modes = data.modes.map((m) => ({ ...m, u: i8(m.u) }));

  // ---- the timeline ----------------------------------------------------------------------------
  const now = { t: T, pts: nPts, complete: L, partial: -1, state: data.states.length - 1 };
  function upperBound(arr, n, v) {
    let lo = 0;
    let hi = n;
    while (lo < hi) {
      const mid = (lo + hi) >> 1;
      if (arr[mid] <= v) lo = mid + 1;
      else hi = mid;
    }
    return lo;
  }
  function locate(t) {
    now.t = t;
    now.pts = upperBound(path.time, nPts, t);
    let k = 0;
    while (k < L && layerEnd[k] <= t && (layerPt1[k] <= now.pts || layerPt1[k] <= layerPt0[k])) k++;
    now.complete = k;
    now.partial = k < L && layerStart[k] <= t && now.pts > layerPt0[k] ? k : -1;
    let s = 0;
    for (let i = 0; i < data.states.length; i++) if (data.states[i].layers_printed <= Math.max(k, 1)) s = i;
    now.state = s;
  }
  const layersShown = () => now.complete + (now.partial >= 0 ? 1 : 0);

  // ---- colour -------------------------------------------------------------------------------
  const DIVERGING = [
    [-1.0, [33, 102, 172]],
    [-0.5, [103, 169, 207]],
    [0.0, [247, 247, 247]],
    [0.5, [239, 138, 98]],
    [1.0, [178, 24, 43]],
  ];
  const COMPRESSION = [
    [0.0, [8, 48, 107]],
    [0.35, [33, 113, 181]],
    [0.7, [107, 174, 214]],
    [1.0, [239, 243, 255]],
  ];
  const SEQUENTIAL = [
    [0.0, [68, 1, 84]],
    [0.25, [59, 82, 139]],
    [0.5, [33, 145, 140]],
    [0.75, [94, 201, 98]],
    [1.0, [253, 231, 37]],
  ];
  const UTILISATION = [
    [0.0, [26, 152, 80]],
    [0.5, [166, 217, 106]],
    [0.8, [254, 224, 139]],
    [1.0, [244, 109, 67]],
    [1.0001, [165, 0, 38]],
    [1.5, [103, 0, 13]],
  ];
  function ramp(stops, u) {
    if (u <= stops[0][0]) return stops[0][1].map((c) => c / 255);
    for (let i = 1; i < stops.length; i++) {
      const [t1, c1] = stops[i];
      if (u <= t1) {
        const [t0, c0] = stops[i - 1];
        const w = (u - t0) / (t1 - t0);
        return [0, 1, 2].map((k) => (c0[k] + w * (c1[k] - c0[k])) / 255);
      }
    }
    return stops[stops.length - 1][1].map((c) => c / 255);
  }

  // Colour schemes, one per menu entry: value(state, segment) in SI, range, ramp.
  const schemes = [];
  for (const q of quantities) {
    const tiny = 1e-6 * Math.max(Math.abs(q.min), Math.abs(q.max));
    let lo = q.min;
    let hi = q.max;
    let stops = SEQUENTIAL;
    let u = (v) => (v - lo) / (hi - lo || 1);
    let labelNote = '';
    if (q.diverging) {
      if (hi <= tiny && lo < 0) {
        // Compression only (tension is round-off): a one-sided ramp, 0 at the light end.
        hi = 0;
        stops = COMPRESSION;
        labelNote = 'all compression (tension none or round-off)';
      } else if (lo >= -tiny && hi > 0) {
        lo = 0;
      } else {
        const m = Math.max(Math.abs(lo), Math.abs(hi)) || 1;
        lo = -m;
        hi = m;
        stops = DIVERGING;
        u = (v) => v / m;
      }
    }
    if (stops !== DIVERGING && !(hi > lo)) hi = lo + 1;
    schemes.push({ key: q.key, label: q.label, unit: q.unit, scale: q.to_unit, q, lo, hi, stops, u, note: q.note || labelNote, sub: labelNote });
  }
  // Utilisation of the layer stress against its limits: σ/σ_min in compression, σ/σ_max in
  // tension (a tension above round-off with σ_max = 0 is drawn beyond the limit).
  {
    const stress = schemes.find((s) => s.key === 'layer_stress');
    const cmin = limitOf('sigma_min');
    const cmax = limitOf('sigma_max');
    if (stress && cmin) {
      const smin = kpaToPa(cmin);
      const smax = cmax ? kpaToPa(cmax) : 0;
      const tiny = 1e-6 * Math.max(Math.abs(stress.q.min), Math.abs(stress.q.max));
      const util = (v) => (v < 0 ? (smin < 0 ? v / smin : 0) : v <= tiny ? 0 : smax > 0 ? v / smax : 1.5);
      const maxU = Math.max(util(stress.q.min), util(stress.q.max));
      const hi = Math.max(1.2, Math.min(maxU, 1.5));
      schemes.push({
        key: 'utilisation',
        label: 'utilisation σ / limit (layer stress)',
        unit: '',
        scale: 1,
        q: stress.q,
        map: util,
        lo: 0,
        hi,
        stops: UTILISATION,
        u: (v) => util(v) / 1.0,
        note: `1 = at the limit (σ_min ${num(cmin.limit)} ${cmin.unit}${cmax ? `, σ_max ${num(cmax.limit)} ${cmax.unit}` : ''}); dark red: beyond it`,
        util: true,
      });
    }
  }
  let scheme = schemes[0];
  const NEUTRAL = [0.72, 0.72, 0.72];

  function colourOf(sch, v) {
    if (sch.util) return ramp(sch.stops, sch.map(v));
    if (sch.stops === DIVERGING) return ramp(DIVERGING, Math.max(-1, Math.min(1, sch.u(v))));
    return ramp(sch.stops, Math.max(0, Math.min(1, sch.u(v))));
  }

  // Value of segment `g` (layer k) in state s under quantity q; NaN when the state lacks it.
  function quantityValue(q, s, k, g) {
    const st = data.states[s];
    if (!q.shared && k >= st.layers_printed) return NaN;
    const e = (q.shared ? 0 : stateChunk0[s]) + k;
    const chunk = q.offsets[e];
    if (chunk === undefined) return NaN;
    const c = q.scales[e];
    return c * (q.per === 'layer' ? q.pool[chunk] : q.pool[chunk + (g - layerSeg0[k])]);
  }

  function drawLegend() {
    const sch = scheme;
    const box = $('legend-scale');
    if (!box || !sch) return;
    const W = 250;
    const stops = sch.util ? UTILISATION.map(([t, c]) => [t / sch.hi, c]) : sch.stops === DIVERGING ? DIVERGING.map(([t, c]) => [(t + 1) / 2, c]) : sch.stops;
    const grad = stops.map(([t, c]) => `<stop offset="${Math.max(0, Math.min(1, t)).toFixed(4)}" stop-color="rgb(${c.join(',')})"/>`).join('');
    const shownLo = sch.lo * sch.scale;
    const shownHi = sch.hi * sch.scale;
    const [a, b] = shownLo <= shownHi ? [shownLo, shownHi] : [shownHi, shownLo];
    const ticks = niceTicks(a, b, 4);
    if (sch.util && !ticks.includes(1)) ticks.push(1);
    const x = (v) => 6 + ((v - a) / (b - a || 1)) * (W - 12);
    const tickSvg = ticks
      .map((v) => `<line x1="${x(v)}" x2="${x(v)}" y1="20" y2="26" stroke="#333"/><text x="${x(v)}" y="38" text-anchor="middle">${num(v)}</text>`)
      .join('');
    box.innerHTML =
      `<svg width="${W}" height="44" viewBox="0 0 ${W} 44" role="img" aria-label="colour scale">` +
      `<defs><linearGradient id="lg">${grad}</linearGradient></defs>` +
      `<rect x="6" y="6" width="${W - 12}" height="14" fill="url(#lg)" stroke="#888"/>${tickSvg}</svg>` +
      `<div class="legend-unit">${sch.label}${sch.unit ? ` [${sch.unit}]` : ''}${sch.sub ? ` · ${sch.sub}` : ''}</div>`;
    $('legend-note').textContent = sch.note && sch.note !== sch.sub ? sch.note : '';
  }

  // ---- 3D scene -------------------------------------------------------------------------------
  let renderer = null;
  let scene;
  let camera;
  let controls;
  const view = {};
  const v3 = (a) => new THREE.Vector3(a[0], a[1], a[2]);
  const nodeV = (j) => new THREE.Vector3(nodes[3 * j], nodes[3 * j + 1], nodes[3 * j + 2]);
  const uTime = { value: T };
  const uModeScale = { value: 0 };

  // Beads: each segment a box of bead_width × bead_height swept along the centre line (4 faces,
  // flat shaded). Shown up to the current moment by a per-vertex print time (discarded in the
  // fragment shader), displaced by a per-vertex mode shape times a uniform scale.
  const VPS = 24; // vertices per segment: 4 faces × 2 triangles × 3
  function buildBeads() {
    const pos = new Float32Array(nSeg * VPS * 3);
    const col = new Float32Array(nSeg * VPS * 3);
    const tim = new Float32Array(nSeg * VPS);
    const mode = new Float32Array(nSeg * VPS * 3);
    const vnode = new Int32Array(nSeg * VPS); // bead node of each vertex (for the mode shape)
    const c = [0, 1, 2, 3, 4, 5, 6, 7].map(() => new THREE.Vector3());
    const sides = [[1, 1], [-1, 1], [-1, -1], [1, -1]];
    let v = 0;
    for (let k = 0; k < L; k++) {
      const l = data.layers[k];
      const n = v3(l.plane_normal).normalize();
      const hw = l.bead_width / 2;
      const hh = l.bead_height / 2;
      const pts = [];
      for (let j = 0; j < l.n; j++) pts.push(nodeV(layerNode0[k] + j));
      const across = pts.map((p, j) => {
        const t = new THREE.Vector3().subVectors(pts[Math.min(pts.length - 1, j + 1)], pts[Math.max(0, j - 1)]).normalize();
        return new THREE.Vector3().crossVectors(n, t).normalize();
      });
      for (let j = 0; j + 1 < pts.length; j++) {
        for (let s = 0; s < 4; s++) {
          c[s].copy(pts[j]).addScaledVector(across[j], sides[s][0] * hw).addScaledVector(n, sides[s][1] * hh);
          c[s + 4].copy(pts[j + 1]).addScaledVector(across[j + 1], sides[s][0] * hw).addScaledVector(n, sides[s][1] * hh);
        }
        const t = segTime[layerSeg0[k] + j];
        for (let s = 0; s < 4; s++) {
          const quad = [s, ((s + 1) % 4) + 4, (s + 1) % 4, s, s + 4, ((s + 1) % 4) + 4];
          for (const q of quad) {
            pos[v * 3] = c[q].x;
            pos[v * 3 + 1] = c[q].y;
            pos[v * 3 + 2] = c[q].z;
            tim[v] = t;
            vnode[v] = layerNode0[k] + j + (q >= 4 ? 1 : 0);
            v++;
          }
        }
      }
    }
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    geo.setAttribute('color', new THREE.BufferAttribute(col, 3));
    geo.setAttribute('aTime', new THREE.BufferAttribute(tim, 1));
    geo.setAttribute('aMode', new THREE.BufferAttribute(mode, 3));
    geo.computeBoundingSphere();
    const mat = new THREE.MeshStandardMaterial({ vertexColors: true, roughness: 0.85, metalness: 0, flatShading: true, side: THREE.DoubleSide });
    mat.onBeforeCompile = (sh) => {
      sh.uniforms.uTime = uTime;
      sh.uniforms.uModeScale = uModeScale;
      sh.vertexShader = 'attribute float aTime;\nattribute vec3 aMode;\nuniform float uModeScale;\nvarying float vPrintT;\n' +
        sh.vertexShader.replace('#include <begin_vertex>', 'vec3 transformed = vec3(position) + aMode * uModeScale;\nvPrintT = aTime;');
      sh.fragmentShader = 'uniform float uTime;\nvarying float vPrintT;\n' +
        sh.fragmentShader.replace('void main() {', 'void main() {\n  if (vPrintT > uTime) discard;');
    };
    // The bounding sphere ignores the mode displacement: never cull the beads.
    const mesh = new THREE.Mesh(geo, mat);
    mesh.frustumCulled = false;
    view.beads = { mesh, geo, col, mode, vnode };
    scene.add(mesh);
  }

  const tmpColor = new THREE.Color();
  function colourBeads() {
    const { col, geo } = view.beads;
    const s = now.state;
    for (let k = 0; k < L; k++) {
      for (let g = layerSeg0[k]; g < layerSeg0[k + 1]; g++) {
        const v = quantityValue(scheme.q, s, k, g);
        const [r, gg, b] = Number.isFinite(v) ? colourOf(scheme, v) : NEUTRAL;
        tmpColor.setRGB(r, gg, b, THREE.SRGBColorSpace);
        const base = g * VPS * 3;
        for (let i = 0; i < VPS; i++) {
          col[base + i * 3] = tmpColor.r;
          col[base + i * 3 + 1] = tmpColor.g;
          col[base + i * 3 + 2] = tmpColor.b;
        }
      }
    }
    geo.attributes.color.needsUpdate = true;
  }

  // ---- mode shape ------------------------------------------------------------------------------
  let capSize = 1;
  let modeShown = null;
  function modeFor(s) {
    let best = null;
    for (const m of modes) if (m.state <= s && (!best || m.state > best.state)) best = m;
    return best;
  }
  function applyMode() {
    const on = $('show-mode').checked;
    const m = on ? modeFor(now.state) : null;
    const badge = $('mode-badge');
    if (on) {
      badge.hidden = false;
      badge.textContent = m
        ? `buckling mode 1 of state ${data.states[m.state].index} (BLF ${fmt(m.blf, 2)})${m.state !== now.state ? ', the last analysed state before this one' : ''}; displacement exaggerated`
        : 'no buckling mode analysed up to this state';
    } else badge.hidden = true;
    if (!renderer) return;
    if (m !== modeShown) {
      const { mode, vnode, geo } = view.beads;
      mode.fill(0);
      if (m) {
        for (let v = 0; v < vnode.length; v++) {
          const j = vnode[v] - m.first;
          if (j >= 0 && j < m.count) {
            mode[v * 3] = m.u[j * 3] / 127;
            mode[v * 3 + 1] = m.u[j * 3 + 1] / 127;
            mode[v * 3 + 2] = m.u[j * 3 + 2] / 127;
          }
        }
      }
      geo.attributes.aMode.needsUpdate = true;
      modeShown = m;
    }
    uModeScale.value = m ? (Number($('mode-scale').value) / 100) * 0.25 * capSize : 0;
  }

  // ---- bed joints and the current layer's path --------------------------------------------------
  function buildBedJoints() {
    const layer = i32(data.bed_joints.layer);
    const a = f32(data.bed_joints.a);
    const b = f32(data.bed_joints.b);
    const stress = f32(data.bed_joints.stress);
    const order = [...layer.keys()].sort((x, y) => layerIndex.get(layer[x]) - layerIndex.get(layer[y]));
    const pos = new Float32Array(order.length * 6);
    const col = new Float32Array(order.length * 6);
    const endByLayer = new Array(L).fill(0);
    const m = Math.max(1e-9, ...Array.from(stress, Math.abs));
    order.forEach((j, i) => {
      pos.set(a.subarray(3 * j, 3 * j + 3), i * 6);
      pos.set(b.subarray(3 * j, 3 * j + 3), i * 6 + 3);
      const [r, g, bb] = ramp(DIVERGING, Math.max(-1, Math.min(1, stress[j] / m)));
      tmpColor.setRGB(r, g, bb, THREE.SRGBColorSpace);
      col.set([tmpColor.r, tmpColor.g, tmpColor.b, tmpColor.r, tmpColor.g, tmpColor.b], i * 6);
      endByLayer[layerIndex.get(layer[j])] = i + 1;
    });
    for (let k = 1; k < L; k++) endByLayer[k] = Math.max(endByLayer[k], endByLayer[k - 1]);
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    geo.setAttribute('color', new THREE.BufferAttribute(col, 3));
    const lines = new THREE.LineSegments(geo, new THREE.LineBasicMaterial({ vertexColors: true }));
    lines.visible = false;
    view.joints = { lines, geo, endByLayer };
    scene.add(lines);
  }

  function buildPath() {
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(path.points, 3));
    const line = new THREE.Line(geo, new THREE.LineBasicMaterial({ color: 0xff7f0e, depthTest: false }));
    line.renderOrder = 2;
    view.path = { line, geo };
    scene.add(line);
  }

  // ---- robot and cell -------------------------------------------------------------------------
  const robot = data.robot
    ? {
        times: f32(data.robot.times),
        joints: f32(data.robot.joints),
        station: i32(data.robot.station),
        base: data.robot.base ? f32(data.robot.base) : new Float32Array(0),
        poses: f32(data.robot.poses),
        radii: data.robot.link_radii,
      }
    : null;
  const cell = data.cell;
  const meshRobot = !!(robot && robotAsset && cell && cell.stations.length > 0);
  const m4 = (rows) => new THREE.Matrix4().set(...rows.flat());
  const stationMat = cell ? cell.stations.map((s) => m4(s.world_from_base)) : [];
  const flangeTcp = cell ? m4(cell.flange_from_tcp) : new THREE.Matrix4();
  const greyMat = () => new THREE.MeshStandardMaterial({ color: 0xb8bec6, roughness: 0.55, metalness: 0.15 });

  function rpyMatrix(rpy, xyz) {
    const m = new THREE.Matrix4().makeRotationFromEuler(new THREE.Euler(rpy[0], rpy[1], rpy[2], 'ZYX'));
    m.setPosition(xyz[0], xyz[1], xyz[2]);
    return m;
  }

  function boxMesh(b, material) {
    const geo = new THREE.BoxGeometry(2 * b.half_extents[0], 2 * b.half_extents[1], 2 * b.half_extents[2]);
    const mesh = new THREE.Mesh(geo, material);
    mesh.position.set(b.center[0], b.center[1], b.center[2]);
    mesh.rotation.z = b.yaw || 0;
    return mesh;
  }

  function capsuleMesh(a, b, r, material) {
    const d = new THREE.Vector3().subVectors(v3(b), v3(a));
    const len = d.length();
    const g = new THREE.Group();
    const cyl = new THREE.Mesh(new THREE.CylinderGeometry(r, r, Math.max(len, 1e-6), 20, 1, true), material);
    cyl.position.copy(v3(a)).addScaledVector(d, 0.5);
    if (len > 1e-9) cyl.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), d.clone().divideScalar(len));
    const s0 = new THREE.Mesh(new THREE.SphereGeometry(r, 16, 10), material);
    const s1 = s0.clone();
    s0.position.copy(v3(a));
    s1.position.copy(v3(b));
    g.add(cyl, s0, s1);
    return g;
  }

  function buildRobot() {
    if (!robot || robot.times.length === 0) return;
    const group = new THREE.Group();
    if (meshRobot) {
      const links = [];
      const mat = greyMat();
      const chain = robotAsset.joints.map((j) => ({ origin: rpyMatrix(j.rpy, j.xyz), revolute: j.revolute, child: j.child }));
      for (const j of chain) {
        const m = robotAsset.meshes[j.child];
        if (!m) {
          links.push(null);
          continue;
        }
        const geo = new THREE.BufferGeometry();
        geo.setAttribute('position', new THREE.BufferAttribute(f32(m.positions), 3));
        geo.setIndex(new THREE.BufferAttribute(new Uint16Array(bytes(m.indices)), 1));
        const flat = geo.toNonIndexed();
        flat.computeVertexNormals();
        const mesh = new THREE.Mesh(flat, mat);
        mesh.matrixAutoUpdate = false;
        group.add(mesh);
        links.push(mesh);
      }
      // The base link's mesh hangs off the first fixed joints; the tool on tool0.
      const tool = new THREE.Group();
      tool.matrixAutoUpdate = false;
      const toolMat = new THREE.MeshStandardMaterial({ color: 0x4a5560, roughness: 0.6 });
      for (const c of cell.tool) tool.add(capsuleMesh(c.a, c.b, c.radius, toolMat));
      // The nozzle itself: a thin cone to the TCP so the tip reads in close-ups.
      const tcp = new THREE.Vector3().setFromMatrixPosition(flangeTcp);
      const cone = new THREE.Mesh(new THREE.ConeGeometry(0.012, 0.05, 16), new THREE.MeshStandardMaterial({ color: 0xff7f0e }));
      cone.position.copy(tcp).addScaledVector(new THREE.Vector3(0, 0, 1), -0.025);
      cone.rotation.x = -Math.PI / 2;
      tool.add(cone);
      group.add(tool);
      const base = new THREE.Group();
      base.matrixAutoUpdate = false;
      const baseMat = new THREE.MeshStandardMaterial({ color: 0x3d6e9e, roughness: 0.7 });
      for (const b of cell.mobile_base) base.add(boxMesh(b, baseMat));
      group.add(base);
      view.robot = { group, chain, links, tool, base, tip: new THREE.Vector3() };
    } else if (robot.poses.length > 0) {
      const mat = greyMat();
      const caps = robot.radii.map((r) => {
        const cyl = new THREE.Mesh(new THREE.CylinderGeometry(r, r, 1, 20, 1, true), mat);
        const s0 = new THREE.Mesh(new THREE.SphereGeometry(r, 20, 12), mat);
        const s1 = s0.clone();
        group.add(cyl, s0, s1);
        return { cyl, s0, s1 };
      });
      view.robot = { group, caps, tip: new THREE.Vector3() };
    }
    if (view.robot) scene.add(group);
  }

  function buildCell() {
    if (!cell) return;
    const group = new THREE.Group();
    const beamMat = new THREE.MeshStandardMaterial({ color: 0x9c7a54, roughness: 0.9 });
    for (const o of cell.obstacles) group.add(boxMesh(o, beamMat));
    // Each station: the mobile base's footprint outline on the floor and a label.
    const floorZ = cell.floor_z ?? 0;
    cell.stations.forEach((st, k) => {
      const m = stationMat[k];
      for (const b of cell.mobile_base) {
        const box = boxMesh(b, null);
        box.updateMatrix();
        const edges = new THREE.LineSegments(
          new THREE.EdgesGeometry(box.geometry),
          new THREE.LineBasicMaterial({ color: 0x3d6e9e, transparent: true, opacity: 0.6 }),
        );
        edges.matrixAutoUpdate = false;
        edges.matrix.copy(m).multiply(box.matrix);
        group.add(edges);
      }
      const p = new THREE.Vector3().setFromMatrixPosition(m);
      const label = textSprite(`station ${k + 1}`, '#1f4e79');
      label.position.set(p.x, p.y, Math.max(floorZ, p.z) + 0.12);
      group.add(label);
    });
    if (cell.floor_z !== null && cell.floor_z !== undefined) {
      const size = Math.max(4, capSize * 6);
      const grid = new THREE.GridHelper(size, Math.round(size / 0.25), 0xb0b0b0, 0xdedede);
      grid.rotation.x = Math.PI / 2;
      grid.position.set(view.centre.x, view.centre.y, cell.floor_z);
      group.add(grid);
    }
    view.cell = group;
    scene.add(group);
  }

  function textSprite(text, colour) {
    const c = document.createElement('canvas');
    const ctx = c.getContext('2d');
    const font = '600 44px system-ui, "DejaVu Sans", sans-serif';
    ctx.font = font;
    c.width = Math.ceil(ctx.measureText(text).width) + 24;
    c.height = 60;
    ctx.font = font;
    ctx.fillStyle = 'rgba(255,255,255,0.85)';
    ctx.fillRect(0, 0, c.width, c.height);
    ctx.fillStyle = colour;
    ctx.textBaseline = 'middle';
    ctx.fillText(text, 12, 32);
    const tex = new THREE.CanvasTexture(c);
    tex.colorSpace = THREE.SRGBColorSpace;
    const sprite = new THREE.Sprite(new THREE.SpriteMaterial({ map: tex, depthTest: false }));
    sprite.renderOrder = 5;
    const h = 0.045;
    sprite.scale.set((h * c.width) / c.height, h, 1);
    return sprite;
  }

  // Robot pose at time t: joints interpolated linearly between the two frames around t; across a
  // station change the base moves along the straight line between the two stations.
  const tmpM = new THREE.Matrix4();
  const baseM = new THREE.Matrix4();
  function robotFrame(t) {
    const n = robot.times.length;
    const i = Math.max(0, Math.min(n - 1, upperBound(robot.times, n, t) - 1));
    const j = Math.min(n - 1, i + 1);
    const t0 = robot.times[i];
    const t1 = robot.times[j];
    const w = t1 > t0 ? Math.max(0, Math.min(1, (t - t0) / (t1 - t0))) : 0;
    return { i, j, w };
  }
  function stationOf(i) {
    return robot.station.length > i ? robot.station[i] : 0;
  }
  function poseRobot(t) {
    if (!view.robot) {
      return;
    }
    const { i, j, w } = robotFrame(t);
    if (meshRobot) {
      const si = stationOf(i);
      const sj = stationOf(j);
      baseM.copy(stationMat[si] || new THREE.Matrix4());
      if (robot.base.length >= 3 * (j + 1)) {
        // A moving base (issue 27): its pose at this moment, x, y and yaw interpolated between
        // the two frames, at the first station's height.
        const b = robot.base;
        const lerp = (k) => b[3 * i + k] + w * (b[3 * j + k] - b[3 * i + k]);
        const z = new THREE.Vector3().setFromMatrixPosition(stationMat[0] || new THREE.Matrix4()).z;
        baseM.makeRotationZ(lerp(2)).setPosition(lerp(0), lerp(1), z);
      } else if (si !== sj && stationMat[sj]) {
        const pa = new THREE.Vector3();
        const pb = new THREE.Vector3();
        const qa = new THREE.Quaternion();
        const qb = new THREE.Quaternion();
        const s = new THREE.Vector3();
        stationMat[si].decompose(pa, qa, s);
        stationMat[sj].decompose(pb, qb, s);
        baseM.compose(pa.lerp(pb, w), qa.slerp(qb, w), new THREE.Vector3(1, 1, 1));
      }
      view.robot.base.matrix.copy(baseM);
      const M = baseM.clone();
      let q = 0;
      view.robot.chain.forEach((jt, k) => {
        M.multiply(jt.origin);
        if (jt.revolute) {
          const a = robot.joints[i * 6 + q];
          const b = robot.joints[j * 6 + q];
          M.multiply(tmpM.makeRotationZ(a + w * (b - a)));
          q++;
        }
        const mesh = view.robot.links[k];
        if (mesh) mesh.matrix.copy(M);
      });
      // M is now tool0 (the flange).
      view.robot.tool.matrix.copy(M);
      view.robot.tip.setFromMatrixPosition(M.clone().multiply(flangeTcp));
    } else {
      const nCap = robot.radii.length;
      view.robot.caps.forEach((c, k) => {
        const at = (f, e) => new THREE.Vector3(...robot.poses.subarray(((f * nCap + k) * 2 + e) * 3, ((f * nCap + k) * 2 + e) * 3 + 3));
        const a = at(i, 0).lerp(at(j, 0), w);
        const b = at(i, 1).lerp(at(j, 1), w);
        const d = new THREE.Vector3().subVectors(b, a);
        const len = d.length();
        c.cyl.visible = len > 1e-9;
        if (len > 1e-9) {
          c.cyl.position.copy(a).addScaledVector(d, 0.5);
          c.cyl.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), d.clone().divideScalar(len));
          c.cyl.scale.set(1, len, 1);
        }
        c.s0.position.copy(a);
        c.s1.position.copy(b);
        if (k === nCap - 1) view.robot.tip.copy(b);
      });
    }
  }

  // Without a robot the nozzle is the path point at the current moment.
  function pathTip(t) {
    if (nPts === 0) return new THREE.Vector3();
    const i = Math.max(0, Math.min(nPts - 1, upperBound(path.time, nPts, t) - 1));
    return new THREE.Vector3(path.points[3 * i], path.points[3 * i + 1], path.points[3 * i + 2]);
  }
  function nozzle() {
    if (view.robot) return view.robot.tip.clone();
    if (meshRobot || robot) {
      // Robot data but no WebGL: pose it anyway for the hook (same chain, no drawing).
    }
    return pathTip(now.t);
  }

  // ---- worst-place markers -----------------------------------------------------------------------
  function buildMarkers() {
    const group = new THREE.Group();
    view.markers = new Map();
    for (const w of data.worst_places) {
      const row = data.constraints.find((c) => c.name === w.constraint);
      const fail = row && !row.pass;
      const colour = fail ? 0xd7191c : 0xe66101;
      const m = new THREE.Group();
      const ring = new THREE.Mesh(new THREE.TorusGeometry(0.025, 0.004, 8, 32), new THREE.MeshBasicMaterial({ color: colour, depthTest: false }));
      ring.renderOrder = 4;
      const dot = new THREE.Mesh(new THREE.SphereGeometry(0.008, 12, 8), new THREE.MeshBasicMaterial({ color: colour, depthTest: false }));
      dot.renderOrder = 4;
      const label = textSprite(w.constraint + (fail ? ' FAIL' : ''), fail ? '#b2182b' : '#a14a00');
      label.position.set(0, 0, 0.05);
      m.add(ring, dot, label);
      m.position.copy(v3(w.position));
      group.add(m);
      view.markers.set(w.constraint, { obj: m, ring, place: w });
    }
    view.markerGroup = group;
    scene.add(group);
  }
  function updateMarkers() {
    if (!view.markers) return;
    for (const { ring } of view.markers.values()) ring.quaternion.copy(camera.quaternion);
    view.markerGroup.visible = $('show-markers').checked;
    // A place in a layer not printed yet would float in the air: shown from its layer on.
    for (const { obj, place } of view.markers.values()) {
      const k = place.layer === null || place.layer === undefined ? -1 : layerIndex.get(place.layer);
      obj.visible = k === undefined || k < layersShown();
    }
  }

  // ---- camera: views, fit, floor, follow, triad, scale bar -----------------------------------
  const floorZ = () => (cell && cell.floor_z !== null && cell.floor_z !== undefined ? cell.floor_z : -Infinity);
  function capBox() {
    const box = new THREE.Box3();
    for (let j = 0; j < layerNode0[L]; j++) box.expandByPoint(nodeV(j));
    return box;
  }
  function fitBox() {
    const box = capBox();
    // The arm, not the mobile base under it: the cap stays large in the frame.
    if (view.robot && view.robot.group.visible) {
      view.robot.group.updateMatrixWorld(true);
      for (const o of view.robot.links || view.robot.caps.flatMap((c) => [c.cyl, c.s0, c.s1])) {
        if (!o) continue;
        const rb = new THREE.Box3().setFromObject(o);
        if (!rb.isEmpty()) box.union(rb);
      }
    }
    return box;
  }
  const VIEWS = {
    iso: new THREE.Vector3(1.3, -1.5, 0.9),
    top: new THREE.Vector3(0, -0.001, 1),
    front: new THREE.Vector3(0, -1, 0.08),
    side: new THREE.Vector3(1, 0, 0.08),
  };
  let lastView = 'iso';
  function setView(name, box) {
    lastView = name;
    const b = box || fitBox();
    const centre = b.getCenter(new THREE.Vector3());
    const sphere = b.getBoundingSphere(new THREE.Sphere());
    const r = Math.max(sphere.radius, 0.05);
    const dist = r / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * (camera.aspect < 1 ? 1 / camera.aspect : 1) * 0.95;
    camera.position.copy(centre).addScaledVector(VIEWS[name].clone().normalize(), dist);
    camera.near = Math.max(dist / 200, 0.001);
    camera.far = dist * 50;
    camera.updateProjectionMatrix();
    controls.target.copy(centre);
    keepAboveFloor();
    controls.update();
  }
  function keepAboveFloor() {
    const fz = floorZ();
    const minZ = (Number.isFinite(fz) ? fz : capBox().min.z - 0.5) + 0.02;
    if (camera.position.z < minZ) camera.position.z = minZ;
    if (controls.target.z < minZ) controls.target.z = minZ;
  }

  let triad = null;
  function buildTriad() {
    const s = new THREE.Scene();
    const cam = new THREE.OrthographicCamera(-1.6, 1.6, 1.6, -1.6, 0.1, 10);
    const group = new THREE.Group();
    [[1, 0, 0, 0xd62728, 'x'], [0, 1, 0, 0x2ca02c, 'y'], [0, 0, 1, 0x1f77b4, 'z']].forEach(([x, y, z, c, name]) => {
      const dir = new THREE.Vector3(x, y, z);
      group.add(new THREE.ArrowHelper(dir, new THREE.Vector3(), 1, c, 0.3, 0.15));
      const l = textSprite(name, '#' + c.toString(16).padStart(6, '0'));
      l.scale.set(0.35, 0.35, 1);
      l.position.copy(dir.multiplyScalar(1.3));
      group.add(l);
    });
    s.add(group);
    triad = { scene: s, cam };
  }

  function updateScaleBar() {
    const el = $('viewer');
    const h = el.clientHeight || 1;
    const d = camera.position.distanceTo(controls.target);
    const mPerPx = (2 * d * Math.tan(THREE.MathUtils.degToRad(camera.fov / 2))) / h;
    const want = 110 * mPerPx;
    const mag = Math.pow(10, Math.floor(Math.log10(want)));
    const len = [1, 2, 5, 10].map((m) => m * mag).filter((v) => v <= want).pop() || mag;
    $('scalebar-bar').style.width = `${Math.round(len / mPerPx)}px`;
    $('scalebar-label').textContent = len >= 1 ? `${num(len)} m` : `${num(len * 1000)} mm`;
  }

  function render() {
    if (!renderer) return;
    updateMarkers();
    const el = $('viewer');
    const w = el.clientWidth;
    const h = el.clientHeight;
    renderer.setViewport(0, 0, w, h);
    renderer.setScissorTest(false);
    renderer.render(scene, camera);
    if (triad) {
      const size = 96;
      triad.cam.position.copy(camera.position).sub(controls.target).setLength(5);
      triad.cam.up.copy(camera.up);
      triad.cam.lookAt(0, 0, 0);
      renderer.autoClear = false;
      renderer.setViewport(w - size - 6, 6, size, size);
      renderer.setScissor(w - size - 6, 6, size, size);
      renderer.setScissorTest(true);
      renderer.clearDepth();
      renderer.render(triad.scene, triad.cam);
      renderer.setScissorTest(false);
      renderer.autoClear = true;
      renderer.setViewport(0, 0, w, h);
    }
    updateScaleBar();
  }

  function resize() {
    const box = $('viewer');
    const w = Math.max(box.clientWidth, 1);
    const h = Math.max(box.clientHeight, 1);
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    render();
  }

  // ---- side panel, plot cursors --------------------------------------------------------------
  function showPanel() {
    const st = data.states[now.state];
    const shown = layersShown();
    $('st-time').textContent = `${clock(now.t)} of ${clock(T)}`;
    $('st-layers').textContent =
      now.partial >= 0
        ? `${now.complete} complete + layer ${data.layers[now.partial].id} being printed (${fmt(
            (100 * (now.pts - layerPt0[now.partial])) / Math.max(1, layerPt1[now.partial] - layerPt0[now.partial]),
            0,
          )} %), of ${L}`
        : `${shown} of ${L}`;
    const si = robot && robot.times.length ? stationOf(robotFrame(now.t).i) : null;
    $('st-station').textContent = si === null ? '–' : `${si + 1}${cell ? ` of ${cell.stations.length}` : ''}`;
    $('st-index').textContent = `${st.index} (${now.state + 1} of ${data.states.length}, ${st.layers_printed} layers)`;
    $('st-progress').textContent = fmt(st.progress * 100, 1) + ' %';
    const top = data.layers[st.layers_printed - 1];
    $('st-top').textContent = top ? String(top.id) : '–';
    $('st-blf').textContent = st.blf === null ? 'not computed' : fmt(st.blf, 2);
    $('st-smin').textContent = kPa(st.sigma_min);
    $('st-smax').textContent = Math.abs(st.sigma_max) < 1e-9 * Math.max(1, Math.abs(st.sigma_min)) ? '0 kPa (round-off)' : kPa(st.sigma_max);
    $('st-overhang').textContent = mm(st.max_overhang);
    const ok = $('st-ok');
    ok.textContent = st.ok ? 'pass' : 'FAIL';
    ok.className = st.ok ? 'pass' : 'fail';
    const topId = shown > 0 ? data.layers[shown - 1].id : null;
    $('time-label').textContent = `${clock(now.t)} / ${clock(T)} · ${shown} of ${L} layers · state ${st.index}`;
    document.querySelectorAll('#plots figure[data-cursor]').forEach((fig) => {
      const kind = fig.dataset.cursor;
      if (kind === 'none') return;
      const x = kind === 'progress' ? st.progress * 100 : kind === 'time' ? now.t : topId;
      const svg = fig.querySelector('svg');
      if (!svg || x === null) return;
      const x0 = Number(fig.dataset.x0);
      const x1 = Number(fig.dataset.x1);
      const px = Number(fig.dataset.px0) + ((x - x0) / (x1 - x0 || 1)) * (Number(fig.dataset.px1) - Number(fig.dataset.px0));
      let line = svg.querySelector('line.cursor');
      if (!line) {
        line = document.createElementNS('http://www.w3.org/2000/svg', 'line');
        line.setAttribute('class', 'cursor');
        svg.appendChild(line);
      }
      line.setAttribute('x1', px);
      line.setAttribute('x2', px);
      line.setAttribute('y1', fig.dataset.py0);
      line.setAttribute('y2', fig.dataset.py1);
    });
  }

  // ---- the moment -----------------------------------------------------------------------------
  let lastColoured = { state: -1, key: null };
  const lastTip = new THREE.Vector3();
  function showMoment(t, fromSlider) {
    locate(Math.max(0, Math.min(T, t)));
    showPanel();
    if (!fromSlider) $('timeline').value = String(Math.round((now.t / T) * 10000));
    if (renderer) {
      uTime.value = now.t + 1e-6;
      if (lastColoured.state !== now.state || lastColoured.key !== scheme.key) {
        colourBeads();
        lastColoured = { state: now.state, key: scheme.key };
      }
      const shown = layersShown();
      view.joints.geo.setDrawRange(0, shown > 0 ? 2 * view.joints.endByLayer[shown - 1] : 0);
      const k = now.partial >= 0 ? now.partial : shown - 1;
      if (k >= 0) {
        const s = layerPt0[k];
        view.path.geo.setDrawRange(s, Math.max(0, Math.min(now.pts, layerPt1[k]) - s));
      }
      applyMode();
      poseRobot(now.t);
      if ($('follow').checked) {
        const tip = nozzle();
        const d = tip.clone().sub(lastTip);
        if (lastTip.lengthSq() > 0) camera.position.add(d);
        controls.target.copy(tip);
        lastTip.copy(tip);
        keepAboveFloor();
        controls.update();
      }
      render();
    } else {
      applyMode();
    }
  }

  // ---- playback ----------------------------------------------------------------------------------
  let playing = false;
  let playWall = 0;
  let playT = 0;
  const PLAY_SECONDS = 40; // wall seconds for the whole print
  function step(wall) {
    if (!playing) return;
    const t = playT + ((wall - playWall) / 1000) * (T / PLAY_SECONDS);
    if (t >= T) {
      showMoment(T);
      setPlaying(false);
      return;
    }
    showMoment(t);
    requestAnimationFrame(step);
  }
  function setPlaying(on) {
    playing = on;
    $('play').textContent = on ? '‖ Pause' : '▶ Play';
    if (on) {
      playT = now.t >= T ? 0 : now.t;
      playWall = performance.now();
      requestAnimationFrame(step);
    }
  }

  // ---- table rows → places -----------------------------------------------------------------------
  function goToPlace(name) {
    const w = data.worst_places.find((p) => p.constraint === name);
    if (!w) return;
    if (w.state !== null && w.state !== undefined) {
      const st = data.states[w.state];
      showMoment(layerEnd[Math.max(0, st.layers_printed - 1)]);
    }
    if (renderer) {
      const p = v3(w.position);
      const offset = camera.position.clone().sub(controls.target);
      offset.setLength(Math.max(0.35, 0.6 * capSize));
      controls.target.copy(p);
      camera.position.copy(p).add(offset);
      keepAboveFloor();
      controls.update();
      for (const [k, m] of view.markers) m.obj.scale.setScalar(k === name ? 1.8 : 1);
      render();
    }
    document.querySelectorAll('#constraints tr[data-constraint]').forEach((tr) => tr.classList.toggle('selected', tr.dataset.constraint === name));
    $('viewer').scrollIntoView({ block: 'nearest' });
  }

  // ---- set-up ---------------------------------------------------------------------------------
  function setupControls() {
    const sel = $('colour-by');
    schemes.forEach((s, i) => {
      const o = document.createElement('option');
      o.value = String(i);
      o.textContent = s.label;
      sel.appendChild(o);
    });
    sel.addEventListener('change', () => {
      scheme = schemes[Number(sel.value)];
      drawLegend();
      showMoment(now.t);
    });
    $('timeline').addEventListener('input', () => {
      if (playing) setPlaying(false);
      showMoment((Number($('timeline').value) / 10000) * T, true);
    });
    $('play').addEventListener('click', () => setPlaying(!playing));
    document.querySelectorAll('#toolbar [data-view]').forEach((b) =>
      b.addEventListener('click', () => {
        setView(b.dataset.view);
        render();
      }),
    );
    $('fit').addEventListener('click', () => {
      setView(lastView);
      render();
    });
    $('follow').addEventListener('change', () => {
      lastTip.set(0, 0, 0);
      showMoment(now.t);
    });
    for (const id of ['show-mode', 'mode-scale', 'show-markers']) $(id).addEventListener('input', () => showMoment(now.t));
    const bind = (id, apply) => {
      const box = $(id);
      apply(box.checked);
      box.addEventListener('change', () => {
        apply(box.checked);
        render();
      });
    };
    if (renderer) {
      bind('show-beads', (on) => (view.beads.mesh.visible = on));
      bind('show-joints', (on) => (view.joints.lines.visible = on));
      bind('show-top', (on) => (view.path.line.visible = on));
      bind('show-robot', (on) => view.robot && (view.robot.group.visible = on));
      bind('show-cell', (on) => view.cell && (view.cell.visible = on));
    }
    document.querySelectorAll('#constraints tr.link').forEach((tr) => {
      tr.addEventListener('click', () => goToPlace(tr.dataset.constraint));
      tr.addEventListener('keydown', (e) => {
        if (e.key === 'Enter' || e.key === ' ') {
          e.preventDefault();
          goToPlace(tr.dataset.constraint);
        }
      });
    });
  }

  function init3d() {
    const canvas = $('kappe-canvas');
    // preserveDrawingBuffer so that screenshots (and the e2e test) read the drawn frame.
    renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    renderer.setClearColor(0xffffff, 1);
    scene = new THREE.Scene();
    camera = new THREE.PerspectiveCamera(40, 1, 0.01, 100);
    camera.up.set(0, 0, 1);
    controls = new THREE.OrbitControls(camera, canvas);
    controls.addEventListener('change', () => {
      keepAboveFloor();
      render();
    });
    const hemi = new THREE.HemisphereLight(0xffffff, 0x8a7f70, 1.6);
    hemi.position.set(0, 0, 1);
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(1.5, -2, 3);
    scene.add(hemi, sun);
    const cb = capBox();
    view.centre = cb.getCenter(new THREE.Vector3());
    capSize = Math.max(cb.getSize(new THREE.Vector3()).length(), 0.05);
    buildBeads();
    buildBedJoints();
    buildPath();
    buildRobot();
    buildCell();
    buildMarkers();
    buildTriad();
    window.addEventListener('resize', resize);
    const box = $('viewer');
    renderer.setSize(Math.max(box.clientWidth, 1), Math.max(box.clientHeight, 1), false);
    camera.aspect = Math.max(box.clientWidth, 1) / Math.max(box.clientHeight, 1);
    camera.updateProjectionMatrix();
  }

  // ---- start ------------------------------------------------------------------------------------
  let webglError = null;
  try {
    init3d();
  } catch (e) {
    // No WebGL (old browser, blocked GPU): keep tables, plots and the state panel working.
    renderer = null;
    webglError = String(e && e.message ? e.message : e);
    $('viewer').classList.add('no-webgl');
    $('viewer-message').textContent = '3D view unavailable: ' + webglError;
  }
  drawLegend();
  setupControls();
  // Open at the end of the print, the whole cap and the robot in view.
  showMoment(T);
  if (renderer) {
    setView('iso');
    resize();
  }
  window.kappeReport = {
    seek(fraction) {
      if (playing) setPlaying(false);
      showMoment(Math.max(0, Math.min(1, Number(fraction))) * T);
      return now.t;
    },
    state: () => now.state,
    layers: () => layersShown(),
    robotTime: () => now.t,
    totalTime: () => T,
    nozzle: () => nozzle().toArray(),
    // For the tests: the bead centre line of the layer at print position k (shown layers − 1
    // is the top one), and the layer interval on the timeline.
    layerPolyline: (k) => Array.from(nodes.subarray(3 * layerNode0[k], 3 * layerNode0[k + 1])),
    layerTimes: () => data.layers.map((_, k) => [layerStart[k], layerEnd[k]]),
    beadWidth: (k) => data.layers[k].bead_width,
    modeShown: () => (modeShown ? modeShown.state : null),
    camera: () => (camera ? camera.position.toArray() : null),
  };
  const gl = renderer ? renderer.getContext() : null;
  window.KAPPE_READY = {
    webgl2: typeof WebGL2RenderingContext !== 'undefined' && gl instanceof WebGL2RenderingContext,
    revision: THREE.REVISION,
    triangles: renderer ? renderer.info.render.triangles : 0,
    states: data.states.length,
    robotMeshes: meshRobot,
    error: webglError,
  };
})();
