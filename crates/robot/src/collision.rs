//! Collision geometry: the UR10e capsule model v1 (robot.md §2.1), the 13 self-collision pairs
//! (§2.2), and the robot against the environment (beams, support, floor, mobile base, printed
//! layers; §2.3) with a clearance margin.
//!
//! Capsule–capsule distances use parry's segment–segment closest points minus the radii (70 ns,
//! exact) instead of the generic GJK `query::distance` (2.2 µs, ~1e-8 m noise). Robot capsules
//! against boxes, half-spaces and meshes go through `parry3d_f64::query::distance`. Printed layers
//! are chains of capsules (radius = half the bead width) grouped in chunks with bounding boxes so
//! that only nearby segments are measured; a generic parry broad phase would do the same work with
//! more indirection for this one shape type.

use parry3d_f64::glamx::{DQuat, DVec3};
use parry3d_f64::math::Pose;
use parry3d_f64::query;
use parry3d_f64::query::details::closest_points_segment_segment_with_locations_nD;
use parry3d_f64::shape::{Capsule, Cuboid, HalfSpace, SegmentPointLocation, SharedShape, TriMesh};
use serde::{Deserialize, Serialize};

use crate::error::RobotError;
use crate::frames::{Iso, Mat4};
use crate::kinematics::{Dh, Joints};

/// Link names of the model, in DH-frame order, plus the tool.
pub const LINK_NAMES: [&str; 8] = [
    "base",
    "shoulder",
    "upper_arm",
    "forearm",
    "wrist_1",
    "wrist_2",
    "wrist_3",
    "nozzle",
];

/// Index of the tool ("nozzle") link.
pub const TOOL_LINK: usize = 7;

/// The 13 checked self-collision pairs (robot.md §2.2): adjacent links and pairs that never
/// collide on the true meshes are skipped.
pub const SELF_PAIRS: [(usize, usize); 13] = [
    (0, 3),
    (0, 6),
    (0, 7),
    (1, 3),
    (1, 5),
    (1, 6),
    (1, 7),
    (2, 4),
    (2, 5),
    (2, 6),
    (2, 7),
    (3, 6),
    (3, 7),
];

/// One capsule: segment `a`–`b` in the DH frame of its link, radius `radius` (m).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CapsuleSpec {
    /// Link index into [`LINK_NAMES`].
    pub link: usize,
    /// Name within the link (e.g. "tube").
    pub name: String,
    pub a: [f64; 3],
    pub b: [f64; 3],
    pub radius: f64,
}

fn cap(link: usize, name: &str, a: [f64; 3], b: [f64; 3], radius: f64) -> CapsuleSpec {
    CapsuleSpec {
        link,
        name: name.into(),
        a,
        b,
        radius,
    }
}

/// The arm's capsule model v1 (robot.md §2.1): fitted to enclose the ROS visual meshes, end points
/// in each link's DH frame; link 0 base … 6 wrist_3. The tool's capsules come from [`crate::Tool`].
pub fn ur10e_arm_capsules() -> Vec<CapsuleSpec> {
    vec![
        cap(0, "body", [0.0, 0.0, 0.032], [0.0, 0.0, 0.033], 0.101),
        cap(1, "body", [0.0, -0.001, 0.0], [0.0, -0.001, 0.014], 0.111),
        cap(
            2,
            "elbow_housing",
            [0.034, 0.0, 0.135],
            [0.034, 0.0, 0.182],
            0.099,
        ),
        cap(2, "tube", [0.130, 0.0, 0.176], [0.505, 0.0, 0.176], 0.069),
        cap(
            2,
            "shoulder_housing",
            [0.582, -0.001, 0.133],
            [0.582, -0.001, 0.197],
            0.113,
        ),
        cap(
            3,
            "wrist1_housing",
            [0.020, 0.0, 0.023],
            [0.020, 0.0, 0.085],
            0.068,
        ),
        cap(3, "tube", [0.054, 0.0, 0.039], [0.455, 0.0, 0.039], 0.046),
        cap(
            3,
            "elbow_housing",
            [0.535, 0.0, 0.056],
            [0.535, 0.0, 0.056],
            0.105,
        ),
        cap(
            4,
            "body",
            [0.0, -0.019, -0.016],
            [0.0, -0.019, 0.045],
            0.068,
        ),
        cap(5, "body", [0.0, 0.014, -0.019], [0.0, 0.014, 0.050], 0.061),
        cap(
            6,
            "body",
            [0.0, -0.003, -0.029],
            [0.0, -0.003, -0.029],
            0.053,
        ),
    ]
}

/// Most capsules a model may hold (arm 11 + tool); keeps per-configuration work allocation-free.
pub const MAX_CAPSULES: usize = 24;

/// A capsule placed in some frame (base or world).
#[derive(Clone, Copy, Debug, Default)]
pub struct PlacedCapsule {
    pub a: DVec3,
    pub b: DVec3,
    pub radius: f64,
    pub link: usize,
}

/// Capsules of one configuration, in the frame the model was posed in.
#[derive(Clone, Copy, Debug)]
pub struct PosedCapsules {
    pub caps: [PlacedCapsule; MAX_CAPSULES],
    pub n: usize,
}

impl PosedCapsules {
    pub fn as_slice(&self) -> &[PlacedCapsule] {
        &self.caps[..self.n]
    }
}

/// Distance between segments `a1b1` and `a2b2` (handles degenerate segments = spheres).
#[inline]
pub fn segment_distance(a1: DVec3, b1: DVec3, a2: DVec3, b2: DVec3) -> f64 {
    let (l1, l2) = closest_points_segment_segment_with_locations_nD((&a1, &b1), (&a2, &b2));
    let at = |a: DVec3, b: DVec3, l: SegmentPointLocation| match l {
        SegmentPointLocation::OnVertex(0) => a,
        SegmentPointLocation::OnVertex(_) => b,
        SegmentPointLocation::OnEdge([u, v]) => a * u + b * v,
    };
    (at(a1, b1, l1) - at(a2, b2, l2)).length()
}

/// Signed distance of two capsules (negative = overlap depth).
#[inline]
pub fn capsule_distance(c1: &PlacedCapsule, c2: &PlacedCapsule) -> f64 {
    segment_distance(c1.a, c1.b, c2.a, c2.b) - c1.radius - c2.radius
}

/// Capsule model of the arm plus tool.
#[derive(Clone, Debug)]
pub struct RobotModel {
    pub dh: Dh,
    /// Capsules sorted by link; link 7 capsules are in the flange frame (DH 6).
    pub capsules: Vec<CapsuleSpec>,
    /// Checked self-collision link pairs.
    pub self_pairs: Vec<(usize, usize)>,
    /// Capsule-index pairs expanded from `self_pairs`.
    cap_pairs: Vec<(u8, u8, u8)>,
}

impl RobotModel {
    /// Build from capsules (the tool's ones with `link == 7`, in the flange frame) and link pairs.
    pub fn new(
        dh: Dh,
        capsules: Vec<CapsuleSpec>,
        self_pairs: Vec<(usize, usize)>,
    ) -> Result<Self, RobotError> {
        if capsules.len() > MAX_CAPSULES {
            return Err(RobotError::invalid(
                "capsules",
                format!(
                    "{} capsules, at most {MAX_CAPSULES} are supported",
                    capsules.len()
                ),
            ));
        }
        for (i, c) in capsules.iter().enumerate() {
            let ok = c.link < LINK_NAMES.len()
                && c.radius.is_finite()
                && c.radius >= 0.0
                && c.a.iter().chain(&c.b).all(|v| v.is_finite());
            if !ok {
                return Err(RobotError::invalid(
                    format!("capsules[{i}] ({})", c.name),
                    format!(
                        "link {} radius {} a {:?} b {:?}: need link 0..=7, finite points, radius ≥ 0",
                        c.link, c.radius, c.a, c.b
                    ),
                ));
            }
        }
        let mut cap_pairs = Vec::new();
        for (pi, &(la, lb)) in self_pairs.iter().enumerate() {
            for (i, ci) in capsules.iter().enumerate() {
                for (j, cj) in capsules.iter().enumerate() {
                    if ci.link == la && cj.link == lb {
                        cap_pairs.push((pi as u8, i as u8, j as u8));
                    }
                }
            }
        }
        Ok(Self {
            dh,
            capsules,
            self_pairs,
            cap_pairs,
        })
    }

    /// The UR10e capsule model v1 with the given tool capsules and the 13 pairs.
    pub fn ur10e_with_tool(tool_capsules: &[CapsuleSpec]) -> Result<Self, RobotError> {
        let mut caps = ur10e_arm_capsules();
        for c in tool_capsules {
            let mut c = c.clone();
            c.link = TOOL_LINK;
            caps.push(c);
        }
        Self::new(crate::kinematics::UR10E, caps, SELF_PAIRS.to_vec())
    }

    /// Place every capsule for configuration `q`, in the frame `frame_from_base` maps to.
    #[inline]
    pub fn pose(&self, q: &Joints, frame_from_base: &Iso) -> PosedCapsules {
        let frames = self.dh.fk_frames(q);
        let mut out = PosedCapsules {
            caps: [PlacedCapsule::default(); MAX_CAPSULES],
            n: self.capsules.len(),
        };
        let mut cache: [Option<Iso>; 7] = [None; 7];
        for (o, c) in out.caps.iter_mut().zip(&self.capsules) {
            let f = c.link.min(6);
            let t = *cache[f].get_or_insert_with(|| frame_from_base.mul(&frames[f]));
            *o = PlacedCapsule {
                a: t.point(DVec3::from(c.a)),
                b: t.point(DVec3::from(c.b)),
                radius: c.radius,
                link: c.link,
            };
        }
        out
    }

    /// Signed distance of every checked self pair (min over the pair's capsules), in
    /// `self_pairs` order.
    pub fn self_pair_distances(&self, q: &Joints) -> Vec<f64> {
        let posed = self.pose(q, &Iso::IDENTITY);
        let mut d = vec![f64::INFINITY; self.self_pairs.len()];
        for &(p, i, j) in &self.cap_pairs {
            let v = capsule_distance(&posed.caps[i as usize], &posed.caps[j as usize]);
            let slot = &mut d[p as usize];
            *slot = slot.min(v);
        }
        d
    }

    /// Smallest signed self distance and the link pair where it occurs.
    #[inline]
    pub fn min_self_distance_posed(&self, posed: &PosedCapsules) -> (f64, (usize, usize)) {
        let mut best = (f64::INFINITY, (0, 0));
        for &(p, i, j) in &self.cap_pairs {
            let v = capsule_distance(&posed.caps[i as usize], &posed.caps[j as usize]);
            if v < best.0 {
                best = (v, self.self_pairs[p as usize]);
            }
        }
        best
    }

    /// Whether `q` self-collides (any checked pair with signed distance < `margin`).
    pub fn self_collides(&self, q: &Joints, margin: f64) -> bool {
        let posed = self.pose(q, &Iso::IDENTITY);
        self.cap_pairs.iter().any(|&(_, i, j)| {
            capsule_distance(&posed.caps[i as usize], &posed.caps[j as usize]) < margin
        })
    }
}

/// An environment object in the world frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Obstacle {
    /// A box with centre, half extents and rotation about z (rad).
    Box {
        name: String,
        center: [f64; 3],
        half_extents: [f64; 3],
        #[serde(default)]
        yaw: f64,
    },
    /// The half-space below a plane: points p with (p − point)·normal < 0 are inside.
    HalfSpace {
        name: String,
        point: [f64; 3],
        normal: [f64; 3],
    },
    /// A chain of capsules through `points` (e.g. a bead centre line), radius `radius`.
    Capsules {
        name: String,
        points: Vec<[f64; 3]>,
        radius: f64,
    },
    /// A triangle mesh.
    Mesh {
        name: String,
        vertices: Vec<[f64; 3]>,
        triangles: Vec<[u32; 3]>,
    },
}

impl Obstacle {
    /// The object's name.
    pub fn name(&self) -> &str {
        match self {
            Obstacle::Box { name, .. }
            | Obstacle::HalfSpace { name, .. }
            | Obstacle::Capsules { name, .. }
            | Obstacle::Mesh { name, .. } => name,
        }
    }
}

/// One parry shape of the scene.
#[derive(Clone)]
struct SceneShape {
    name: String,
    pose: Pose,
    shape: SharedShape,
    /// Axis-aligned bounds (min, max) used to skip far objects; infinite for half-spaces.
    lo: DVec3,
    hi: DVec3,
    /// A box's half extents: a capsule's bounds in the box frame give a tighter lower bound of
    /// their distance than the world-axis bounds, before the GJK query.
    cuboid: Option<DVec3>,
}

/// Capsule chain segments, chunked with bounding boxes, tagged by layer. Chunks are grouped
/// (consecutive chunks, `GROUP` at a time) under a second level of boxes with the group's
/// smallest layer tag, and groups (`SUPER` at a time) under a third, so that a query skips whole
/// groups that are far or not yet printed: a three-level bounding-volume hierarchy over the
/// print order (consecutive bead is near in space). Every level is a lower bound, so the result
/// is exact; and a level only skips what the level below would skip at the same bound, so the
/// segments measured, and every result, are the same as with two levels. The third level is for
/// long prints: a 1.5 m × 4 m bay has ~1,000 groups, which every query scanned.
#[derive(Clone, Debug, Default)]
pub struct SegmentSoup {
    segs: Vec<(DVec3, DVec3, f64)>,
    chunks: Vec<Chunk>,
    groups: Vec<Group>,
    /// Boxes over `SUPER` consecutive groups (`start..end` index `groups`).
    supers: Vec<Group>,
}

/// Groups per super-group (≈ 770 segments, ≈ 15 m of bead).
const SUPER: usize = 16;

#[derive(Clone, Debug)]
struct Group {
    min_layer: usize,
    start: usize,
    end: usize,
    lo: DVec3,
    hi: DVec3,
}

/// Chunks per group (≈ 48 segments, ≈ 1 m of bead at 2 cm spacing).
const GROUP: usize = 8;

#[derive(Clone, Debug)]
struct Chunk {
    layer: usize,
    name_idx: usize,
    start: usize,
    end: usize,
    lo: DVec3,
    hi: DVec3,
}

const CHUNK: usize = 6;

impl SegmentSoup {
    /// Add a polyline of capsules with radius `r`, tagged `layer` (chunks are kept sorted by
    /// insertion; add layers in print order).
    pub fn add_chain(&mut self, layer: usize, name_idx: usize, points: &[DVec3], r: f64) {
        if points.len() == 1 {
            self.add_segments(layer, name_idx, &[(points[0], points[0])], r);
            return;
        }
        let segs: Vec<(DVec3, DVec3)> = points.windows(2).map(|w| (w[0], w[1])).collect();
        self.add_segments(layer, name_idx, &segs, r);
    }

    fn add_segments(&mut self, layer: usize, name_idx: usize, segs: &[(DVec3, DVec3)], r: f64) {
        for group in segs.chunks(CHUNK) {
            let start = self.segs.len();
            let mut lo = DVec3::splat(f64::INFINITY);
            let mut hi = DVec3::splat(f64::NEG_INFINITY);
            for &(a, b) in group {
                self.segs.push((a, b, r));
                lo = lo.min(a.min(b) - DVec3::splat(r));
                hi = hi.max(a.max(b) + DVec3::splat(r));
            }
            self.chunks.push(Chunk {
                layer,
                name_idx,
                start,
                end: self.segs.len(),
                lo,
                hi,
            });
            let ci = self.chunks.len() - 1;
            push_into(&mut self.groups, GROUP, ci, layer, lo, hi);
            let gi = self.groups.len() - 1;
            push_into(&mut self.supers, SUPER, gi, layer, lo, hi);
        }
    }

    /// Chunks that may hold a segment with tag < `below_layer` within `lim` of the box
    /// `lo`–`hi`, group by group (`lim` is re-read per group, as the caller shrinks it).
    #[inline]
    fn near_chunks<'a>(
        &'a self,
        lo: DVec3,
        hi: DVec3,
        below_layer: usize,
        lim: &'a std::cell::Cell<f64>,
    ) -> impl Iterator<Item = &'a Chunk> + 'a {
        let near =
            move |g: &&Group| g.min_layer < below_layer && box_gap(lo, hi, g.lo, g.hi) <= lim.get();
        self.supers
            .iter()
            .filter(near)
            .flat_map(move |s| &self.groups[s.start..s.end])
            .filter(near)
            .flat_map(move |g| &self.chunks[g.start..g.end])
            .filter(move |ch| ch.layer < below_layer && box_gap(lo, hi, ch.lo, ch.hi) <= lim.get())
    }

    /// Smallest signed distance from capsule `c` to chunks with `layer < below_layer`, skipping
    /// chunks whose box is farther than `cutoff`; returns (distance, name index) or None.
    #[inline]
    fn min_distance(
        &self,
        c: &PlacedCapsule,
        below_layer: usize,
        cutoff: f64,
    ) -> Option<(f64, usize)> {
        let clo = c.a.min(c.b) - DVec3::splat(c.radius);
        let chi = c.a.max(c.b) + DVec3::splat(c.radius);
        let mut best: Option<(f64, usize)> = None;
        let lim = std::cell::Cell::new(cutoff);
        for ch in self.near_chunks(clo, chi, below_layer, &lim) {
            for &(a, b, r) in &self.segs[ch.start..ch.end] {
                let rr = DVec3::splat(r);
                if box_gap(clo, chi, a.min(b) - rr, a.max(b) + rr) > lim.get() {
                    continue;
                }
                let d = segment_distance(c.a, c.b, a, b) - c.radius - r;
                if d < lim.get() {
                    lim.set(d);
                    best = Some((d, ch.name_idx));
                }
            }
        }
        best
    }
}

/// Add item `i` (tag `layer`, box `lo`–`hi`) to the last box of `level` if it holds fewer than
/// `per` items or already holds `i` (the last group, grown by a chunk), else to a new box.
fn push_into(level: &mut Vec<Group>, per: usize, i: usize, layer: usize, lo: DVec3, hi: DVec3) {
    match level.last_mut() {
        Some(g) if g.end > i || g.end - g.start < per => {
            g.end = g.end.max(i + 1);
            g.min_layer = g.min_layer.min(layer);
            g.lo = g.lo.min(lo);
            g.hi = g.hi.max(hi);
        }
        _ => level.push(Group {
            min_layer: layer,
            start: i,
            end: i + 1,
            lo,
            hi,
        }),
    }
}

/// Gap between two boxes (0 if they overlap): a lower bound of the distance of their contents.
#[inline]
fn box_gap(alo: DVec3, ahi: DVec3, blo: DVec3, bhi: DVec3) -> f64 {
    let d = (blo - ahi).max(alo - bhi).max(DVec3::ZERO);
    d.length()
}

/// Static scene + printed layers, in the world frame.
#[derive(Clone, Default)]
pub struct Scene {
    shapes: Vec<SceneShape>,
    soup: SegmentSoup,
    names: Vec<String>,
}

/// The nearest environment object of one configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Clearance {
    /// Signed distance (m), capped at the query's cutoff.
    pub distance: f64,
    /// Robot link index ([`LINK_NAMES`]), meaningful when `object` is `Some`.
    pub link: usize,
    /// Name of the nearest object within the cutoff.
    pub object: Option<String>,
}

impl Scene {
    /// Build from obstacles (validated: finite numbers, positive sizes, valid meshes).
    pub fn new(obstacles: &[Obstacle]) -> Result<Self, RobotError> {
        let mut s = Scene::default();
        for (i, o) in obstacles.iter().enumerate() {
            s.add(i, o)?;
        }
        Ok(s)
    }

    fn add(&mut self, i: usize, o: &Obstacle) -> Result<(), RobotError> {
        let field = || format!("obstacles[{i}] ({:?})", o.name());
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        match o {
            Obstacle::Box {
                name,
                center,
                half_extents,
                yaw,
            } => {
                if !finite(center)
                    || !finite(half_extents)
                    || !yaw.is_finite()
                    || half_extents.iter().any(|h| *h <= 0.0)
                {
                    return Err(RobotError::invalid(
                        field(),
                        format!(
                            "box center {center:?} half_extents {half_extents:?} yaw {yaw}: need finite values and half extents > 0"
                        ),
                    ));
                }
                let pose = Pose::from_parts(DVec3::from(*center), DQuat::from_rotation_z(*yaw));
                let he = DVec3::from(*half_extents);
                // Bounding box of the rotated box: |R|·h.
                let (s, c) = yaw.sin_cos();
                let ext = DVec3::new(
                    c.abs() * he.x + s.abs() * he.y,
                    s.abs() * he.x + c.abs() * he.y,
                    he.z,
                );
                self.shapes.push(SceneShape {
                    name: name.clone(),
                    pose,
                    shape: SharedShape::new(Cuboid::new(he)),
                    lo: DVec3::from(*center) - ext,
                    hi: DVec3::from(*center) + ext,
                    cuboid: Some(he),
                });
            }
            Obstacle::HalfSpace {
                name,
                point,
                normal,
            } => {
                let n = DVec3::from(*normal);
                if !finite(point) || !finite(normal) || n.length() < 1e-12 {
                    return Err(RobotError::invalid(
                        field(),
                        format!(
                            "half-space point {point:?} normal {normal:?}: need finite values and a non-zero normal"
                        ),
                    ));
                }
                // parry's HalfSpace is { x : x·n ≤ 0 } with an outward normal n.
                let pose = Pose::from_translation(DVec3::from(*point));
                self.shapes.push(SceneShape {
                    name: name.clone(),
                    pose,
                    shape: SharedShape::new(HalfSpace::new(n.normalize())),
                    lo: DVec3::splat(f64::NEG_INFINITY),
                    hi: DVec3::splat(f64::INFINITY),
                    cuboid: None,
                });
            }
            Obstacle::Capsules {
                name,
                points,
                radius,
            } => {
                if points.is_empty()
                    || !points.iter().all(|p| finite(p))
                    || !radius.is_finite()
                    || *radius < 0.0
                {
                    return Err(RobotError::invalid(
                        field(),
                        format!(
                            "capsule chain of {} points, radius {radius}: need ≥ 1 finite point and radius ≥ 0",
                            points.len()
                        ),
                    ));
                }
                let pts: Vec<DVec3> = points.iter().map(|p| DVec3::from(*p)).collect();
                let idx = self.names.len();
                self.names.push(name.clone());
                self.soup.add_chain(0, idx, &pts, *radius);
            }
            Obstacle::Mesh {
                name,
                vertices,
                triangles,
            } => {
                if !vertices.iter().all(|p| finite(p)) {
                    return Err(RobotError::invalid(field(), "mesh has a non-finite vertex"));
                }
                let verts: Vec<DVec3> = vertices.iter().map(|p| DVec3::from(*p)).collect();
                let mut lo = DVec3::splat(f64::INFINITY);
                let mut hi = DVec3::splat(f64::NEG_INFINITY);
                for v in &verts {
                    lo = lo.min(*v);
                    hi = hi.max(*v);
                }
                let mesh = TriMesh::new(verts, triangles.clone()).map_err(|e| {
                    RobotError::invalid(field(), format!("invalid triangle mesh: {e}"))
                })?;
                self.shapes.push(SceneShape {
                    name: name.clone(),
                    pose: Pose::IDENTITY,
                    shape: SharedShape::new(mesh),
                    lo,
                    hi,
                    cuboid: None,
                });
            }
        }
        Ok(())
    }

    /// Add a printed layer's bead centre line (capsule radius = half the bead width). Layers must
    /// be added in print order; a query for layer k sees only layers added with a smaller tag.
    pub fn add_printed_layer(
        &mut self,
        layer_tag: usize,
        name: String,
        points: &[DVec3],
        radius: f64,
    ) {
        let idx = self.names.len();
        self.names.push(name);
        self.soup.add_chain(layer_tag + 1, idx, points, radius);
    }

    /// Smallest distance between this scene's static shapes and obstacle `o` (None if either
    /// has no static shape, e.g. capsule chains).
    pub fn distance_to(&self, o: &Obstacle) -> Option<f64> {
        let other = Scene::new(std::slice::from_ref(o)).ok()?;
        let mut best: Option<f64> = None;
        for a in &self.shapes {
            for b in &other.shapes {
                if let Ok(d) = query::distance(&a.pose, a.shape.as_ref(), &b.pose, b.shape.as_ref())
                {
                    best = Some(best.map_or(d.distance, |x: f64| x.min(d.distance)));
                }
            }
        }
        best
    }

    /// Nearest object to the given capsules (already in world coordinates), considering printed
    /// layers with tag < `layer_tag` and everything static. Distances above `cutoff` are reported
    /// as `cutoff` with no object.
    pub fn clearance(&self, caps: &[PlacedCapsule], layer_tag: usize, cutoff: f64) -> Clearance {
        let mut best = Clearance {
            distance: cutoff,
            link: 0,
            object: None,
        };
        let mut best_name: Option<&str> = None;
        // The tool and wrist come last in the models and are usually the nearest to the work:
        // measuring them first shrinks the bound early, so that the rest is mostly pruned.
        for c in caps.iter().rev() {
            let clo = c.a.min(c.b) - DVec3::splat(c.radius);
            let chi = c.a.max(c.b) + DVec3::splat(c.radius);
            for s in &self.shapes {
                if box_gap(clo, chi, s.lo, s.hi) > best.distance {
                    continue;
                }
                if let Some(h) = s.cuboid {
                    let (la, lb) = (
                        s.pose.inverse_transform_point(c.a),
                        s.pose.inverse_transform_point(c.b),
                    );
                    let r = DVec3::splat(c.radius);
                    if box_gap(la.min(lb) - r, la.max(lb) + r, -h, h) > best.distance {
                        continue;
                    }
                }
                let capsule = Capsule::new(c.a, c.b, c.radius);
                let d = match query::distance(&Pose::IDENTITY, &capsule, &s.pose, s.shape.as_ref())
                {
                    Ok(d) => d.distance,
                    Err(_) => continue,
                };
                // parry reports 0 for any overlap; a penetration depth is not needed to reject.
                if d < best.distance {
                    best.distance = d;
                    best.link = c.link;
                    best_name = Some(&s.name);
                }
            }
            if let Some((d, ni)) = self.soup.min_distance(c, layer_tag + 1, best.distance)
                && d < best.distance
            {
                best.distance = d;
                best.link = c.link;
                best_name = self.names.get(ni).map(String::as_str);
            }
        }
        best.object = best_name.map(str::to_owned);
        best
    }
}

impl Scene {
    /// Nearest object to an arbitrary parry shape at `pose` (world), e.g. a link's convex
    /// collision mesh: static shapes and printed layers with tag < `layer_tag`, pruned by
    /// bounding boxes. Returns (distance capped at `cutoff`, object name).
    pub fn shape_clearance(
        &self,
        pose: &Pose,
        shape: &dyn parry3d_f64::shape::Shape,
        layer_tag: usize,
        cutoff: f64,
    ) -> (f64, Option<String>) {
        let aabb = shape.compute_aabb(pose);
        let (lo, hi) = (aabb.mins, aabb.maxs);
        let mut best = cutoff;
        let mut name: Option<&str> = None;
        for s in &self.shapes {
            if box_gap(lo, hi, s.lo, s.hi) > best {
                continue;
            }
            if let Ok(d) = query::distance(pose, shape, &s.pose, s.shape.as_ref())
                && d.distance < best
            {
                best = d.distance;
                name = Some(&s.name);
            }
        }
        let lim = std::cell::Cell::new(best);
        for ch in self.soup.near_chunks(lo, hi, layer_tag + 1, &lim) {
            for &(a, b, r) in &self.soup.segs[ch.start..ch.end] {
                let seg_lo = a.min(b) - DVec3::splat(r);
                let seg_hi = a.max(b) + DVec3::splat(r);
                if box_gap(lo, hi, seg_lo, seg_hi) > lim.get() {
                    continue;
                }
                let c = Capsule::new(a, b, r);
                if let Ok(d) = query::distance(pose, shape, &Pose::IDENTITY, &c)
                    && d.distance < lim.get()
                {
                    lim.set(d.distance);
                    name = self.names.get(ch.name_idx).map(String::as_str);
                }
            }
        }
        (lim.get(), name.map(str::to_owned))
    }
}

/// A mobile-base body box, in the robot base frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyBox {
    pub name: String,
    /// Centre in the robot base frame (m).
    pub center: [f64; 3],
    /// Half extents (m).
    pub half_extents: [f64; 3],
}

impl BodyBox {
    /// The box as a world obstacle for base pose `world_from_base` (yaw only: the base stands
    /// on the floor, so its rotation is about z; the box uses the base's yaw).
    pub fn to_world(&self, world_from_base: &Iso) -> Obstacle {
        let c = world_from_base.point(DVec3::from(self.center));
        let x = world_from_base.r.x_axis;
        Obstacle::Box {
            name: self.name.clone(),
            center: c.to_array(),
            half_extents: self.half_extents,
            yaw: x.y.atan2(x.x),
        }
    }
}

/// Convert a row-major matrix into an [`Iso`] or a [`RobotError`] naming `field`.
pub fn iso_field(field: &str, m: &Mat4) -> Result<Iso, RobotError> {
    Iso::from_mat4(m).map_err(|e| RobotError::invalid(field, e))
}
