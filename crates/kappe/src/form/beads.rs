//! The printed volume as beads: every layer swept as a box section lw × lh along its centre line,
//! exported as Wavefront OBJ and binary glTF (GLB), openable in Rhino and Blender.
//!
//! Both formats are written by hand: OBJ is a few lines of text, and a GLB with one mesh is a JSON
//! header and two buffers; the `gltf` crate reads the result back in the tests.

use std::fmt::Write as _;

use crate::form::frame::{LayerFrame, V3};
use crate::form::section::Sections;

/// An indexed triangle mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions, m.
    pub positions: Vec<[f32; 3]>,
    /// Triangles, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

/// Sweep a box section (width lw across the shell, height lh along n) along every layer.
pub fn bead_mesh(
    sections: &Sections,
    frame: &LayerFrame,
    layer_width: f64,
    layer_height: f64,
) -> TriMesh {
    let mut mesh = TriMesh::default();
    let n = frame.n;
    for layer in &sections.layers {
        let pts: Vec<V3> = layer.nodes.iter().map(|p| p.xyz).collect();
        if pts.len() < 2 {
            continue;
        }
        let base = mesh.positions.len() as u32;
        for (i, p) in pts.iter().enumerate() {
            let prev = pts[i.saturating_sub(1)];
            let next = pts[(i + 1).min(pts.len() - 1)];
            let t = (next - prev).normalize();
            let w = t.cross(&n).normalize() * (0.5 * layer_width);
            let h = n * (0.5 * layer_height);
            for c in [-w - h, w - h, w + h, -w + h] {
                let q = p + c;
                mesh.positions.push([q.x as f32, q.y as f32, q.z as f32]);
            }
        }
        let ring = |i: usize, k: usize| base + (4 * i + (k % 4)) as u32;
        for i in 0..pts.len() - 1 {
            for k in 0..4 {
                let (a, b, c, d) = (
                    ring(i, k),
                    ring(i, k + 1),
                    ring(i + 1, k + 1),
                    ring(i + 1, k),
                );
                mesh.triangles.push([a, b, c]);
                mesh.triangles.push([a, c, d]);
            }
        }
        let last = pts.len() - 1;
        mesh.triangles.push([ring(0, 0), ring(0, 2), ring(0, 1)]);
        mesh.triangles.push([ring(0, 0), ring(0, 3), ring(0, 2)]);
        mesh.triangles
            .push([ring(last, 0), ring(last, 1), ring(last, 2)]);
        mesh.triangles
            .push([ring(last, 0), ring(last, 2), ring(last, 3)]);
    }
    mesh
}

impl TriMesh {
    /// Wavefront OBJ text (1-based indices).
    pub fn to_obj(&self, name: &str) -> String {
        let mut s = String::with_capacity(self.positions.len() * 40 + self.triangles.len() * 30);
        let _ = writeln!(
            s,
            "# Kappe cap ceiling, printed beads; units m, z up\no {name}"
        );
        for p in &self.positions {
            let _ = writeln!(s, "v {:.6} {:.6} {:.6}", p[0], p[1], p[2]);
        }
        for t in &self.triangles {
            let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        s
    }

    /// Binary glTF 2.0 (one mesh, one primitive). glTF is y-up, so the mesh is rotated
    /// z-up → y-up (x, y, z) ↦ (x, z, −y) as the glTF spec asks.
    ///
    /// # Errors
    /// A mesh whose file would exceed the 4 GiB that a GLB header can state.
    pub fn to_glb(&self) -> Result<Vec<u8>, GlbError> {
        let mut bin: Vec<u8> =
            Vec::with_capacity(self.positions.len() * 12 + self.triangles.len() * 12);
        let mut min = [f32::INFINITY; 3];
        let mut max = [f32::NEG_INFINITY; 3];
        for p in &self.positions {
            let q = [p[0], p[2], -p[1]];
            for k in 0..3 {
                min[k] = min[k].min(q[k]);
                max[k] = max[k].max(q[k]);
                bin.extend_from_slice(&q[k].to_le_bytes());
            }
        }
        let pos_len = bin.len();
        for t in &self.triangles {
            for &i in t {
                bin.extend_from_slice(&i.to_le_bytes());
            }
        }
        let idx_len = bin.len() - pos_len;
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        if self.positions.is_empty() {
            min = [0.0; 3];
            max = [0.0; 3];
        }
        let json = serde_json::json!({
            "asset": {"version": "2.0", "generator": "kappe"},
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0, "name": "cap"}],
            "meshes": [{"name": "cap", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
            "materials": [{"name": "earth", "pbrMetallicRoughness": {"baseColorFactor": [0.72, 0.52, 0.38, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9}}],
            "buffers": [{"byteLength": bin.len()}],
            "bufferViews": [
                {"buffer": 0, "byteOffset": 0, "byteLength": pos_len, "target": 34962},
                {"buffer": 0, "byteOffset": pos_len, "byteLength": idx_len, "target": 34963}
            ],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": self.positions.len(), "type": "VEC3", "min": min, "max": max},
                {"bufferView": 1, "componentType": 5125, "count": self.triangles.len() * 3, "type": "SCALAR"}
            ]
        });
        let mut json_bytes =
            serde_json::to_vec(&json).map_err(|e| GlbError(format!("its JSON chunk: {e}")))?;
        while !json_bytes.len().is_multiple_of(4) {
            json_bytes.push(b' ');
        }
        let total = 12 + 8 + json_bytes.len() + 8 + bin.len();
        let size = |n: usize| {
            u32::try_from(n).map_err(|_| {
                GlbError(format!(
                    "{total} bytes: more than the 4 GiB a binary glTF can hold (write cap.obj)"
                ))
            })
        };
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&size(total)?.to_le_bytes());
        out.extend_from_slice(&size(json_bytes.len())?.to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json_bytes);
        out.extend_from_slice(&size(bin.len())?.to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        Ok(out)
    }
}

/// Why the beads cannot be written as a binary glTF.
#[derive(Debug, thiserror::Error)]
#[error("cannot write cap.glb: {0}")]
pub struct GlbError(String);
