// Regenerates crates/report/assets/ur10e-meshes.json, the UR10e drawn in report.html, from the
// ROS ur_description collision meshes (BSD-3-Clause; copies in shared/robot/ur10e/):
//   node web/ur10e-meshes.mjs /work/shared/robot/ur10e crates/report/assets
// `cargo build` never runs this: the asset is committed. No dependencies.
//
// What it writes: the kinematic chain of the URDF (base → tool0: per joint the fixed origin
// xyz + rpy, and whether it turns about its z axis with q_i) and, per link, its collision mesh
// already moved into the link frame (the URDF `<collision><origin>` applied), decimated by
// vertex clustering on a CELL grid (vertices in one cell merge to their mean, degenerate and
// duplicate triangles dropped), as base64 little-endian float32 positions and uint16 indices.
// The meshes are convex hulls of 71–939 vertices; clustering at 6 mm keeps their silhouette
// while the page carries a fraction of the bytes.
import { readFileSync, writeFileSync, copyFileSync } from 'node:fs';
import { join } from 'node:path';

const [src = '/work/shared/robot/ur10e', out = 'crates/report/assets'] = process.argv.slice(2);
const CELL = 0.006; // m

const urdf = readFileSync(join(src, 'urdf/robot_description.urdf'), 'utf8');
const num3 = (s) => s.trim().split(/\s+/).map(Number);

// Rotation matrix (row-major 3×3) of URDF rpy: R = Rz(yaw)·Ry(pitch)·Rx(roll).
function rpyMatrix([r, p, y]) {
  const [cr, sr, cp, sp, cy, sy] = [Math.cos(r), Math.sin(r), Math.cos(p), Math.sin(p), Math.cos(y), Math.sin(y)];
  return [
    [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
    [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
    [-sp, cp * sr, cp * cr],
  ];
}

// Joints from `base` (DH frame 0, the robot base pose of the plan) to tool0 (DH frame 6).
// base = base_link · Rz(π) (fixed joint base_link-base_fixed_joint), so base_link = base · Rz(π).
const joints = [];
const jointRe = /<joint name="([^"]+)" type="([^"]+)">([\s\S]*?)<\/joint>/g;
const byChild = new Map();
for (const m of urdf.matchAll(jointRe)) {
  const body = m[3];
  const parent = /<parent link="([^"]+)"/.exec(body)[1];
  const child = /<child link="([^"]+)"/.exec(body)[1];
  const o = /<origin xyz="([^"]+)" rpy="([^"]+)"/.exec(body);
  byChild.set(child, { name: m[1], type: m[2], parent, child, xyz: num3(o[1]), rpy: num3(o[2]) });
}
// Walk from tool0 up to base_link.
const chain = [];
for (let link = 'tool0'; link !== 'base_link';) {
  const j = byChild.get(link);
  if (!j) throw new Error(`no joint to ${link}`);
  chain.unshift(j);
  link = j.parent;
}
joints.push({ name: 'base-base_link', child: 'base_link', xyz: [0, 0, 0], rpy: [0, 0, Math.PI], revolute: false });
for (const j of chain) joints.push({ name: j.name, child: j.child, xyz: j.xyz, rpy: j.rpy, revolute: j.type === 'revolute' });

// Collision meshes with their origins.
const linkRe = /<link name="([^"]+)">([\s\S]*?)<\/link>/g;
const links = [];
for (const m of urdf.matchAll(linkRe)) {
  const col = /<collision>([\s\S]*?)<\/collision>/.exec(m[2]);
  if (!col) continue;
  const o = /<origin xyz="([^"]+)" rpy="([^"]+)"/.exec(col[1]);
  const file = /filename="package:\/\/ur_description\/(meshes\/[^"]+)"/.exec(col[1])[1];
  links.push({ link: m[1], file, xyz: num3(o[1]), rpy: num3(o[2]) });
}

function readStl(path) {
  const b = readFileSync(path);
  const n = b.readUInt32LE(80);
  const tris = [];
  for (let i = 0; i < n; i++) {
    const o = 84 + i * 50 + 12;
    const t = [];
    for (let k = 0; k < 3; k++) t.push([b.readFloatLE(o + k * 12), b.readFloatLE(o + k * 12 + 4), b.readFloatLE(o + k * 12 + 8)]);
    tris.push(t);
  }
  return tris;
}

function decimate(tris, R, t) {
  const cells = new Map(); // cell key → {sum, n, id}
  const ids = [];
  const key = (p) => p.map((c) => Math.round(c / CELL)).join(',');
  const idx = [];
  for (const tri of tris) {
    const f = tri.map((p) => {
      const q = [0, 1, 2].map((r) => R[r][0] * p[0] + R[r][1] * p[1] + R[r][2] * p[2] + t[r]);
      const k = key(q);
      let c = cells.get(k);
      if (!c) {
        c = { sum: [0, 0, 0], n: 0, id: ids.length };
        cells.set(k, c);
        ids.push(c);
      }
      c.sum = c.sum.map((s, r) => s + q[r]);
      c.n++;
      return c.id;
    });
    if (f[0] !== f[1] && f[1] !== f[2] && f[0] !== f[2]) idx.push(f);
  }
  const seen = new Set();
  const faces = idx.filter((f) => {
    const k = [...f].sort((a, b) => a - b).join(',');
    if (seen.has(k)) return false;
    seen.add(k);
    return true;
  });
  const pos = new Float32Array(ids.length * 3);
  ids.forEach((c, i) => pos.set(c.sum.map((s) => s / c.n), i * 3));
  const ind = new Uint16Array(faces.flat());
  return { pos, ind, before: tris.length, after: faces.length };
}

const b64 = (typed) => Buffer.from(typed.buffer, typed.byteOffset, typed.byteLength).toString('base64');
const meshes = {};
for (const l of links) {
  const tris = readStl(join(src, 'ur_description', l.file));
  const { pos, ind, before, after } = decimate(tris, rpyMatrix(l.rpy), l.xyz);
  meshes[l.link] = { positions: b64(pos), indices: b64(ind) };
  console.log(`${l.link}: ${before} → ${after} triangles, ${pos.length / 3} vertices`);
}
const asset = {
  source: 'ros-industrial ur_description UR10e collision meshes (BSD-3-Clause, see ur10e-LICENSE.txt), via compas_fab 2.0.1',
  cell_m: CELL,
  joints,
  meshes,
};
writeFileSync(join(out, 'ur10e-meshes.json'), JSON.stringify(asset));
console.log(`wrote ${join(out, 'ur10e-meshes.json')}: ${JSON.stringify(asset).length} bytes`);
