//! Rigid transforms named the rerun way: `a_from_b` maps coordinates in frame `b` to frame `a`
//! (column vectors, `p_a = a_from_b · p_b`), so `world_from_tcp = world_from_base · base_from_flange
//! · flange_from_tcp` reads right to left.
//!
//! Public data uses plain row-major 4×4 arrays ([`Mat4`]); inside, [`Iso`] holds a glam rotation
//! matrix and translation (glam taken from parry's re-export, see `crates.md`).

use parry3d_f64::glamx::{DMat3, DQuat, DVec3};

/// A row-major homogeneous 4×4 matrix `T[row][col]` (the fixture layout).
pub type Mat4 = [[f64; 4]; 4];

/// A rigid transform `p ↦ R·p + t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Iso {
    /// Rotation part (orthonormal, det +1).
    pub r: DMat3,
    /// Translation part.
    pub t: DVec3,
}

impl Default for Iso {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Iso {
    /// The identity transform.
    pub const IDENTITY: Iso = Iso {
        r: DMat3::IDENTITY,
        t: DVec3::ZERO,
    };

    /// From rotation and translation.
    pub fn new(r: DMat3, t: DVec3) -> Self {
        Self { r, t }
    }

    /// A pure translation.
    pub fn translation(x: f64, y: f64, z: f64) -> Self {
        Self {
            r: DMat3::IDENTITY,
            t: DVec3::new(x, y, z),
        }
    }

    /// Rotation about the local z axis by `phi` (rad).
    pub fn rot_z(phi: f64) -> Self {
        Self {
            r: DMat3::from_rotation_z(phi),
            t: DVec3::ZERO,
        }
    }

    /// Rotation about the local x axis by `phi` (rad).
    pub fn rot_x(phi: f64) -> Self {
        Self {
            r: DMat3::from_rotation_x(phi),
            t: DVec3::ZERO,
        }
    }

    /// Composition `self · rhs` (apply `rhs` first).
    #[inline]
    pub fn mul(&self, rhs: &Iso) -> Iso {
        Iso {
            r: self.r * rhs.r,
            t: self.r * rhs.t + self.t,
        }
    }

    /// Rigid inverse `[Rᵀ | −Rᵀt]`.
    #[inline]
    pub fn inverse(&self) -> Iso {
        let rt = self.r.transpose();
        Iso {
            r: rt,
            t: -(rt * self.t),
        }
    }

    /// Transform a point.
    #[inline]
    pub fn point(&self, p: DVec3) -> DVec3 {
        self.r * p + self.t
    }

    /// Rotate a direction.
    #[inline]
    pub fn vector(&self, v: DVec3) -> DVec3 {
        self.r * v
    }

    /// Row-major 4×4.
    pub fn to_mat4(&self) -> Mat4 {
        let c = [self.r.x_axis, self.r.y_axis, self.r.z_axis];
        let mut m = [[0.0; 4]; 4];
        for (i, row) in m.iter_mut().take(3).enumerate() {
            for (j, col) in c.iter().enumerate() {
                row[j] = col[i];
            }
            row[3] = self.t[i];
        }
        m[3][3] = 1.0;
        m
    }

    /// From a row-major 4×4, checked: finite entries, last row `[0 0 0 1]` and an orthonormal
    /// rotation (columns orthonormal and det > 0 within `1e-6`, loose enough for matrices
    /// printed with ~9 digits and tight enough to reject a scaled or sheared matrix).
    pub fn from_mat4(m: &Mat4) -> Result<Iso, String> {
        if m.iter().flatten().any(|v| !v.is_finite()) {
            return Err("contains a non-finite entry".into());
        }
        let last = m[3];
        if last[0].abs() > 1e-9
            || last[1].abs() > 1e-9
            || last[2].abs() > 1e-9
            || (last[3] - 1.0).abs() > 1e-9
        {
            return Err(format!("last row is {last:?}, expected [0, 0, 0, 1]"));
        }
        let col = |j: usize| DVec3::new(m[0][j], m[1][j], m[2][j]);
        let r = DMat3::from_cols(col(0), col(1), col(2));
        let err = (r.transpose() * r - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |a, v| a.max(v.abs()));
        if err > 1e-6 || r.determinant() <= 0.0 {
            return Err(format!(
                "rotation part is not orthonormal with det +1 (max |RᵀR − I| = {err:.3e}, det = {:.6})",
                r.determinant()
            ));
        }
        Ok(Iso { r, t: col(3) })
    }

    /// Unchecked conversion from a row-major 4×4 (tests, fixtures, trusted data).
    pub fn from_mat4_unchecked(m: &Mat4) -> Iso {
        let col = |j: usize| DVec3::new(m[0][j], m[1][j], m[2][j]);
        Iso {
            r: DMat3::from_cols(col(0), col(1), col(2)),
            t: col(3),
        }
    }

    /// Rotation vector (axis · angle, rad), the orientation part of a URScript `p[...]` pose.
    pub fn rotation_vector(&self) -> DVec3 {
        DQuat::from_mat3(&self.r).normalize().to_scaled_axis()
    }

    /// Largest absolute entry difference of the 3×4 parts.
    pub fn max_abs_diff(&self, other: &Iso) -> f64 {
        let a = self.to_mat4();
        let b = other.to_mat4();
        let mut e = 0.0f64;
        for i in 0..3 {
            for j in 0..4 {
                e = e.max((a[i][j] - b[i][j]).abs());
            }
        }
        e
    }

    /// Rotation angle (rad) of `selfᵀ · other`, robust for small angles.
    pub fn rotation_angle_to(&self, other: &Iso) -> f64 {
        rotation_angle(&(self.r.transpose() * other.r))
    }
}

/// Angle of a rotation matrix, `atan2(‖axial(R − Rᵀ)‖/2, (tr R − 1)/2)`; accurate near 0 and π
/// unlike `acos((tr − 1)/2)`.
pub fn rotation_angle(r: &DMat3) -> f64 {
    let ax = DVec3::new(
        r.y_axis.z - r.z_axis.y,
        r.z_axis.x - r.x_axis.z,
        r.x_axis.y - r.y_axis.x,
    );
    let s = 0.5 * ax.length();
    let c = 0.5 * (r.x_axis.x + r.y_axis.y + r.z_axis.z - 1.0);
    s.atan2(c)
}

/// Angle between two directions (rad), via `atan2(|a×b|, a·b)`.
pub fn angle_between(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// A frame whose z axis is `z` (normalised) and whose x axis is the projection of `x_ref`
/// (falls back to a perpendicular of `z` when `x_ref` is parallel to it).
pub fn frame_from_z(origin: DVec3, z: DVec3, x_ref: DVec3) -> Iso {
    let z = z.normalize();
    let mut x = x_ref - z * z.dot(x_ref);
    if x.length_squared() < 1e-12 {
        x = z.any_orthonormal_vector();
    }
    let x = x.normalize();
    let y = z.cross(x);
    Iso::new(DMat3::from_cols(x, y, z), origin)
}
