// Kappe report viewer: draws the scene island (`#kappe-data`, the serialised ReportInput of
// crates/report/src/input.rs) with the vendored three.js bundle (`window.THREE`, which also
// carries `OrbitControls`). Hand-written, no build step: it is inlined into report.html as is.
//
// Frames and units: world frame of method.md (x span, y along the cap, z up), metres, Pa.
// Test hooks: `window.KAPPE_READY = {webgl2, revision, triangles, states}` after the first
// render; `window.KAPPE_STATE` = current slider position (index into data.states) and
// `window.KAPPE_VIEW` = what that state shows (layers printed, triangles drawn).
(function () {
  'use strict';

  const $ = (id) => document.getElementById(id);
  const data = JSON.parse($('kappe-data').textContent);
  const THREE = window.THREE;

  // ---- formatting -------------------------------------------------------------------------
  const fmt = (v, digits) => (v === null || v === undefined ? '–' : Number(v).toFixed(digits));
  const kPa = (pa) => fmt(pa / 1e3, 2) + ' kPa';
  const mm = (m) => fmt(m * 1e3, 2) + ' mm';

  // ---- colour map: diverging blue (compression) – white (0) – red (tension), symmetric ------
  // Symmetric about zero so that any tension shows up red at once, whatever the magnitudes.
  const STOPS = [
    [-1.0, [33, 102, 172]],
    [-0.5, [103, 169, 207]],
    [0.0, [247, 247, 247]],
    [0.5, [239, 138, 98]],
    [1.0, [178, 24, 43]],
  ];
  let stressScale = 0;
  const bump = (s) => {
    stressScale = Math.max(stressScale, Math.abs(s));
  };
  for (const l of data.layers) l.segment_stress.forEach(bump);
  for (const j of data.bed_joints) bump(j.stress);
  for (const st of data.states) if (st.segment_stress) st.segment_stress.forEach(bump);
  if (!(stressScale > 0)) stressScale = 1;

  function stressRgb(s) {
    const t = Math.max(-1, Math.min(1, s / stressScale));
    for (let i = 1; i < STOPS.length; i++) {
      const [t1, c1] = STOPS[i];
      if (t <= t1) {
        const [t0, c0] = STOPS[i - 1];
        const u = (t - t0) / (t1 - t0);
        return [0, 1, 2].map((k) => (c0[k] + u * (c1[k] - c0[k])) / 255);
      }
    }
    return STOPS[STOPS.length - 1][1].map((c) => c / 255);
  }

  function drawLegend() {
    const bar = $('legend-bar');
    if (bar) {
      const css = STOPS.map(([t, c]) => `rgb(${c.join(',')}) ${((t + 1) * 50).toFixed(0)}%`);
      bar.style.background = `linear-gradient(to right, ${css.join(', ')})`;
    }
    const lo = $('legend-min');
    const hi = $('legend-max');
    if (lo) lo.textContent = kPa(-stressScale);
    if (hi) hi.textContent = kPa(stressScale);
  }

  // ---- state panel (works without WebGL too) -----------------------------------------------
  const slider = $('state-slider');
  const layerIndex = new Map(data.layers.map((l, k) => [l.id, k]));

  function showPanel(i) {
    const st = data.states[i];
    const top = data.layers[st.layers_printed - 1];
    $('st-index').textContent = `${st.index} (${i + 1} of ${data.states.length})`;
    $('st-progress').textContent = fmt(st.progress * 100, 1) + ' %';
    $('st-layers').textContent = `${st.layers_printed} of ${data.layers.length}`;
    $('st-top').textContent = top ? String(top.id) : '–';
    $('st-blf').textContent = st.blf === null ? 'not computed' : fmt(st.blf, 2);
    $('st-smin').textContent = kPa(st.sigma_min);
    $('st-smax').textContent = kPa(st.sigma_max);
    $('st-overhang').textContent = mm(st.max_overhang);
    const ok = $('st-ok');
    ok.textContent = st.ok ? 'pass' : 'FAIL';
    ok.className = st.ok ? 'pass' : 'fail';
    $('state-label').textContent = `state ${st.index}, ${fmt(st.progress * 100, 1)} %`;
  }

  // ---- 3D scene -------------------------------------------------------------------------
  let renderer = null;
  let scene;
  let camera;
  let controls;
  const view = {}; // objects the state slider changes

  function v3(a) {
    return new THREE.Vector3(a[0], a[1], a[2]);
  }

  // Beads: each segment is a box of bead_width (in the layer plane, across the path) by
  // bead_height (along the plane normal) swept along the centre line; 4 side faces, flat
  // shaded, one colour per segment so that the stress of each element reads directly.
  const VERTS_PER_SEGMENT = 24; // 4 faces × 2 triangles × 3 vertices (non-indexed)
  function buildBeads() {
    let nseg = 0;
    for (const l of data.layers) nseg += l.nodes.length - 1;
    const pos = new Float32Array(nseg * VERTS_PER_SEGMENT * 3);
    const col = new Float32Array(nseg * VERTS_PER_SEGMENT * 3);
    const layerVertEnd = [];
    const layerSegStart = [];
    let v = 0;
    let seg = 0;
    const corner = (p, w, n, sw, sn, out) => {
      out.copy(p).addScaledVector(w, sw).addScaledVector(n, sn);
    };
    const c = [0, 1, 2, 3, 4, 5, 6, 7].map(() => new THREE.Vector3());
    for (const l of data.layers) {
      layerSegStart.push(seg);
      const n = v3(l.plane_normal).normalize();
      const hw = l.bead_width / 2;
      const hh = l.bead_height / 2;
      const pts = l.nodes.map(v3);
      // Across-path direction per node from the central-difference tangent, so that
      // neighbouring segments share their end sections (no gaps at bends).
      const across = pts.map((p, j) => {
        const a = pts[Math.max(0, j - 1)];
        const b = pts[Math.min(pts.length - 1, j + 1)];
        const t = new THREE.Vector3().subVectors(b, a).normalize();
        return new THREE.Vector3().crossVectors(n, t).normalize();
      });
      for (let j = 0; j + 1 < pts.length; j++) {
        // corners: 0..3 at node j, 4..7 at node j+1: (+w+n), (−w+n), (−w−n), (+w−n)
        const sides = [[1, 1], [-1, 1], [-1, -1], [1, -1]];
        for (let k = 0; k < 4; k++) {
          corner(pts[j], across[j], n, sides[k][0] * hw, sides[k][1] * hh, c[k]);
          corner(pts[j + 1], across[j + 1], n, sides[k][0] * hw, sides[k][1] * hh, c[k + 4]);
        }
        for (let k = 0; k < 4; k++) {
          const a = c[k];
          const b = c[(k + 1) % 4];
          const bb = c[((k + 1) % 4) + 4];
          const aa = c[k + 4];
          for (const q of [a, bb, b, a, aa, bb]) {
            pos[v * 3] = q.x;
            pos[v * 3 + 1] = q.y;
            pos[v * 3 + 2] = q.z;
            v++;
          }
        }
        seg++;
      }
      layerVertEnd.push(v);
    }
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    geo.setAttribute('color', new THREE.BufferAttribute(col, 3));
    geo.computeVertexNormals();
    geo.computeBoundingSphere();
    const mat = new THREE.MeshStandardMaterial({
      vertexColors: true,
      roughness: 0.85,
      metalness: 0.0,
      side: THREE.DoubleSide,
    });
    const mesh = new THREE.Mesh(geo, mat);
    view.beads = { mesh, geo, col, layerVertEnd, layerSegStart };
    scene.add(mesh);
  }

  const tmpColor = new THREE.Color();
  function colourBeads(stateStress) {
    const { col, geo } = view.beads;
    let seg = 0;
    for (const l of data.layers) {
      for (let j = 0; j < l.segment_stress.length; j++) {
        const s =
          stateStress && seg < stateStress.length ? stateStress[seg] : l.segment_stress[j];
        const [r, g, b] = stressRgb(s);
        // Vertex colours are linear in three's colour management; the map is in sRGB.
        tmpColor.setRGB(r, g, b, THREE.SRGBColorSpace);
        const base = seg * VERTS_PER_SEGMENT * 3;
        for (let k = 0; k < VERTS_PER_SEGMENT; k++) {
          col[base + k * 3] = tmpColor.r;
          col[base + k * 3 + 1] = tmpColor.g;
          col[base + k * 3 + 2] = tmpColor.b;
        }
        seg++;
      }
    }
    geo.attributes.color.needsUpdate = true;
  }

  function buildBedJoints() {
    const joints = data.bed_joints
      .map((j) => ({ j, k: layerIndex.get(j.layer) }))
      .sort((a, b) => a.k - b.k);
    const pos = new Float32Array(joints.length * 6);
    const col = new Float32Array(joints.length * 6);
    const endByLayer = new Array(data.layers.length).fill(0);
    joints.forEach(({ j, k }, i) => {
      pos.set(j.a, i * 6);
      pos.set(j.b, i * 6 + 3);
      const [r, g, b] = stressRgb(j.stress);
      tmpColor.setRGB(r, g, b, THREE.SRGBColorSpace);
      col.set([tmpColor.r, tmpColor.g, tmpColor.b, tmpColor.r, tmpColor.g, tmpColor.b], i * 6);
      endByLayer[k] = i + 1;
    });
    for (let k = 1; k < endByLayer.length; k++) {
      endByLayer[k] = Math.max(endByLayer[k], endByLayer[k - 1]);
    }
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    geo.setAttribute('color', new THREE.BufferAttribute(col, 3));
    const lines = new THREE.LineSegments(geo, new THREE.LineBasicMaterial({ vertexColors: true }));
    lines.visible = false;
    view.joints = { lines, geo, endByLayer };
    scene.add(lines);
  }

  // The print path: the whole printed path (grey) and the top layer's path with its tool
  // axes (orange, drawn over the beads because the nozzle tip lies on the bead's top face).
  function buildPath() {
    const path = data.print_path;
    const n = path.points.length;
    const flat = new Float32Array(n * 3);
    path.points.forEach((p, i) => flat.set(p, i * 3));
    const startByLayer = new Array(data.layers.length).fill(n);
    const endByLayer = new Array(data.layers.length).fill(0);
    path.layer.forEach((id, i) => {
      const k = layerIndex.get(id);
      startByLayer[k] = Math.min(startByLayer[k], i);
      endByLayer[k] = Math.max(endByLayer[k], i + 1);
    });
    const geoAll = new THREE.BufferGeometry();
    geoAll.setAttribute('position', new THREE.BufferAttribute(flat, 3));
    const all = new THREE.Line(geoAll, new THREE.LineBasicMaterial({ color: 0x444444 }));
    all.visible = false;
    const geoTop = new THREE.BufferGeometry();
    geoTop.setAttribute('position', new THREE.BufferAttribute(flat, 3));
    const topMat = new THREE.LineBasicMaterial({ color: 0xff7f0e, depthTest: false });
    const top = new THREE.Line(geoTop, topMat);
    top.renderOrder = 2;
    // Tool axes: from the tip back along −axis (where the nozzle body is), 4 cm.
    const axes = new Float32Array(n * 6);
    path.points.forEach((p, i) => {
      const a = path.tool_axis[i];
      axes.set(p, i * 6);
      axes.set([p[0] - 0.04 * a[0], p[1] - 0.04 * a[1], p[2] - 0.04 * a[2]], i * 6 + 3);
    });
    const geoAxes = new THREE.BufferGeometry();
    geoAxes.setAttribute('position', new THREE.BufferAttribute(axes, 3));
    const axesLines = new THREE.LineSegments(
      geoAxes,
      new THREE.LineBasicMaterial({ color: 0x2ca02c, depthTest: false }),
    );
    axesLines.renderOrder = 2;
    view.path = { all, top, axesLines, geoAll, geoTop, geoAxes, startByLayer, endByLayer };
    scene.add(all, top, axesLines);
  }

  // Robot: one cylinder (unit height along +y, scaled) and two spheres per link.
  function buildRobot() {
    const robot = data.robot;
    if (!robot || robot.times.length === 0) return;
    const group = new THREE.Group();
    const mat = new THREE.MeshStandardMaterial({ color: 0x8fa3b8, roughness: 0.5, metalness: 0.2 });
    const links = robot.link_radii.map((r) => {
      const cyl = new THREE.Mesh(new THREE.CylinderGeometry(r, r, 1, 20, 1, true), mat);
      const s0 = new THREE.Mesh(new THREE.SphereGeometry(r, 20, 12), mat);
      const s1 = new THREE.Mesh(new THREE.SphereGeometry(r, 20, 12), mat);
      group.add(cyl, s0, s1);
      return { cyl, s0, s1 };
    });
    view.robot = { group, links, frame: 0 };
    scene.add(group);
  }

  const Y = new THREE.Vector3(0, 1, 0);
  function poseRobot(i) {
    if (!view.robot) return;
    const pose = data.robot.poses[i];
    view.robot.frame = i;
    view.robot.links.forEach((link, j) => {
      const a = v3(pose[j][0]);
      const b = v3(pose[j][1]);
      const d = new THREE.Vector3().subVectors(b, a);
      const len = d.length();
      link.cyl.visible = len > 1e-9;
      if (len > 1e-9) {
        link.cyl.position.copy(a).addScaledVector(d, 0.5);
        link.cyl.quaternion.setFromUnitVectors(Y, d.clone().divideScalar(len));
        link.cyl.scale.set(1, len, 1);
      }
      link.s0.position.copy(a);
      link.s1.position.copy(b);
    });
    const t = data.robot.times[i];
    $('robot-label').textContent = `t = ${fmt(t, 1)} s`;
    $('robot-time').value = String(i);
  }

  function frameCamera() {
    const box = new THREE.Box3();
    for (const l of data.layers) for (const p of l.nodes) box.expandByPoint(v3(p));
    const capBox = box.clone();
    // Frame the robot too (its first pose), so that the view shows where it stands.
    if (data.robot && data.robot.poses.length > 0) {
      for (const [a, b] of data.robot.poses[0]) box.expandByPoint(v3(a)).expandByPoint(v3(b));
    }
    // Look at the cap; stand far enough back to see the robot as well.
    const centre = capBox.getCenter(new THREE.Vector3());
    const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-3);
    camera.near = radius / 100;
    camera.far = radius * 100;
    const dir = new THREE.Vector3(1.3, -1.5, 0.8).normalize();
    camera.position.copy(centre).addScaledVector(dir, radius * 1.9);
    camera.updateProjectionMatrix();
    controls.target.copy(centre);
    controls.update();
    // Base plane grid at z = 0, 5 cm cells, a bit larger than the cap.
    const capCentre = centre;
    const size = Math.ceil((radius * 3) / 0.1) * 0.1;
    const grid = new THREE.GridHelper(size, Math.round(size / 0.05), 0x999999, 0xdddddd);
    grid.rotation.x = Math.PI / 2;
    grid.position.set(capCentre.x, capCentre.y, 0);
    scene.add(grid);
  }

  function render() {
    if (renderer) renderer.render(scene, camera);
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

  function showState(i) {
    showPanel(i);
    const st = data.states[i];
    const k = st.layers_printed - 1;
    if (renderer) {
      view.beads.geo.setDrawRange(0, view.beads.layerVertEnd[k]);
      colourBeads(st.segment_stress);
      view.joints.geo.setDrawRange(0, 2 * view.joints.endByLayer[k]);
      const p = view.path;
      let end = 0;
      for (let m = 0; m <= k; m++) end = Math.max(end, p.endByLayer[m]);
      p.geoAll.setDrawRange(0, end);
      const s = p.startByLayer[k];
      const e = p.endByLayer[k];
      const count = e > s ? e - s : 0;
      p.geoTop.setDrawRange(s, count);
      p.geoAxes.setDrawRange(2 * s, 2 * count);
      render();
    }
    window.KAPPE_STATE = i;
    window.KAPPE_VIEW = {
      state: st.index,
      layersPrinted: st.layers_printed,
      triangles: renderer ? renderer.info.render.triangles : 0,
    };
  }

  // ---- robot playback: the whole trajectory in about 20 s of wall time -------------------
  let playing = false;
  let playStart = 0;
  let playT0 = 0;
  function robotStep(now) {
    if (!playing) return;
    const times = data.robot.times;
    const t0 = times[0];
    const span = Math.max(times[times.length - 1] - t0, 1e-9);
    const speed = span / 20; // trajectory seconds per wall second
    let t = playT0 + ((now - playStart) / 1000) * speed;
    if (t > times[times.length - 1]) {
      t = t0;
      playT0 = t0;
      playStart = now;
    }
    // Binary search for the last step with time <= t.
    let lo = 0;
    let hi = times.length - 1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (times[mid] <= t) lo = mid;
      else hi = mid - 1;
    }
    poseRobot(lo);
    render();
    requestAnimationFrame(robotStep);
  }

  function setupRobotControls() {
    const play = $('robot-play');
    const scrub = $('robot-time');
    if (!view.robot) {
      $('robot-controls').hidden = true;
      return;
    }
    scrub.max = String(data.robot.times.length - 1);
    play.addEventListener('click', () => {
      playing = !playing;
      play.textContent = playing ? '⏸ Pause robot' : '▶ Play robot';
      if (playing) {
        playStart = performance.now();
        playT0 = data.robot.times[view.robot.frame];
        requestAnimationFrame(robotStep);
      }
    });
    scrub.addEventListener('input', () => {
      poseRobot(Number(scrub.value));
      render();
    });
    poseRobot(0);
  }

  function setupToggles() {
    const bind = (id, apply) => {
      const box = $(id);
      if (!box) return;
      apply(box.checked);
      box.addEventListener('change', () => {
        apply(box.checked);
        render();
      });
    };
    bind('show-beads', (on) => (view.beads.mesh.visible = on));
    bind('show-joints', (on) => (view.joints.lines.visible = on));
    bind('show-path', (on) => (view.path.all.visible = on));
    bind('show-top', (on) => {
      view.path.top.visible = on;
      view.path.axesLines.visible = on;
    });
    bind('show-robot', (on) => {
      if (view.robot) view.robot.group.visible = on;
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
    controls.addEventListener('change', render);
    const hemi = new THREE.HemisphereLight(0xffffff, 0x8a7f70, 1.6);
    hemi.position.set(0, 0, 1);
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(1.5, -2, 3);
    scene.add(hemi, sun);
    buildBeads();
    buildBedJoints();
    buildPath();
    buildRobot();
    frameCamera();
    setupToggles();
    setupRobotControls();
    window.addEventListener('resize', resize);
    resize();
  }

  // ---- start ----------------------------------------------------------------------------
  drawLegend();
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
  slider.addEventListener('input', () => showState(Number(slider.value)));
  showState(Number(slider.value));
  const gl = renderer ? renderer.getContext() : null;
  window.KAPPE_READY = {
    webgl2: typeof WebGL2RenderingContext !== 'undefined' && gl instanceof WebGL2RenderingContext,
    revision: THREE.REVISION,
    triangles: renderer ? renderer.info.render.triangles : 0,
    states: data.states.length,
    error: webglError,
  };
})();
