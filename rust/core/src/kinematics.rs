//! Arm kinematics: the modified (Craig) D-H model of the paper's six-axis arm.
//!
//! Entry points:
//! - [`Arm::paper`] — the arm of the paper's Table 2; [`Arm::new`] for any 6R table of the
//!   same family.
//! - [`Arm::fk`] — forward kinematics: joint angles (radians) to the terminal pose (mm).
//! - [`Arm::points_mm`] — the arm's body as the 8-point polyline
//!   base → O1 → O2 → O3 → Aux → O4 → O5 → O6 (docs/SCENARIOS.md "Units and the arm"), in mm.
//! - `Arm::ik` (module `ik`) — closed-form inverse kinematics, every solution.
//! - [`orientation_grid`] — the paper's terminal orientations (eq. 12), duplicates removed.
//!
//! Link transform (modified D-H): `T_i = RotX(alpha_{i-1}) TransX(a_{i-1}) RotZ(theta_i + offset_i) TransZ(d_i)`.
//!
//! ```
//! use sixaxis_core::kinematics::{Arm, PAPER_BETA0_DEG};
//! let arm = Arm::paper();
//! let q = PAPER_BETA0_DEG.map(f64::to_radians);
//! let pose = arm.fk(&q);
//! assert!((pose.position_mm - nalgebra::Vector3::new(0.0, -200.0, 400.0)).norm() < 0.1);
//! ```

use nalgebra::{Matrix3, Rotation3, Vector3};
use serde::{Deserialize, Serialize};

/// Six joint angles, radians.
pub type Joints = [f64; 6];

/// The arm's body polyline: base, O1, O2, O3, Aux, O4, O5, O6 (terminal), in mm.
pub type ArmPoints = [Vector3<f64>; 8];

/// The initial pose of Table 1, degrees.
pub const PAPER_BETA0_DEG: Joints = [57.9948, -10.1070, -132.9377, 53.0502, 90.0002, 32.0054];

/// One row of a modified D-H table: (alpha_{i-1}, a_{i-1}, d_i, theta offset_i).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DhRow {
    /// Link twist alpha_{i-1}, degrees.
    pub alpha_deg: f64,
    /// Link length a_{i-1}, mm.
    pub a_mm: f64,
    /// Link offset d_i, mm.
    pub d_mm: f64,
    /// Joint angle offset added to theta_i, degrees.
    pub offset_deg: f64,
}

impl DhRow {
    /// A row from its four values (degrees, mm, mm, degrees).
    pub const fn new(alpha_deg: f64, a_mm: f64, d_mm: f64, offset_deg: f64) -> Self {
        DhRow {
            alpha_deg,
            a_mm,
            d_mm,
            offset_deg,
        }
    }
}

/// Table 2 of the paper, read as modified D-H rows.
pub const PAPER_DH: [DhRow; 6] = [
    DhRow::new(0.0, 0.0, 0.0, 0.0),
    DhRow::new(90.0, 0.0, 0.0, 0.0),
    DhRow::new(0.0, -300.0, 0.0, 0.0),
    DhRow::new(0.0, -300.0, 106.0, 0.0),
    DhRow::new(90.0, 0.0, 114.0, 0.0),
    DhRow::new(-90.0, 0.0, 167.0, 0.0),
];

/// The terminal (end effector) pose: position in mm and rotation matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TerminalPose {
    /// Position of the terminal, mm, base frame.
    pub position_mm: Vector3<f64>,
    /// Orientation of the terminal frame in the base frame.
    pub rotation: Matrix3<f64>,
}

/// Precomputed data of one link.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Link {
    pub(crate) ca: f64,
    pub(crate) sa: f64,
    pub(crate) a: f64,
    pub(crate) d: f64,
    pub(crate) offset: f64,
}

/// A six-axis arm described by a modified D-H table.
#[derive(Debug, Clone, PartialEq)]
pub struct Arm {
    rows: [DhRow; 6],
    pub(crate) links: [Link; 6],
}

impl Default for Arm {
    fn default() -> Self {
        Arm::paper()
    }
}

/// Rigid transform as rotation + translation (cheaper than a 4x4 product).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Frame {
    pub(crate) r: Matrix3<f64>,
    pub(crate) p: Vector3<f64>,
}

impl Frame {
    pub(crate) fn identity() -> Self {
        Frame {
            r: Matrix3::identity(),
            p: Vector3::zeros(),
        }
    }

    /// `self * RotX(alpha) TransX(a) RotZ(theta) TransZ(d)`.
    ///
    /// The local rotation is
    /// `[[ct, -st, 0], [st ca, ct ca, -sa], [st sa, ct sa, ca]]`; multiplied out by columns,
    /// with `e = R (0, ca, sa)`: new x = `R.x ct + e st`, new y = `-R.x st + e ct`,
    /// new z = `-R.y sa + R.z ca`, and the origin moves by `R.x a + (new z) d`.
    #[inline]
    pub(crate) fn then_link(&self, l: &Link, theta: f64) -> Frame {
        let (st, ct) = (theta + l.offset).sin_cos();
        let rx = self.r.column(0).into_owned();
        let ry = self.r.column(1).into_owned();
        let rz = self.r.column(2).into_owned();
        let e = ry * l.ca + rz * l.sa;
        let nz = rz * l.ca - ry * l.sa;
        let nx = rx * ct + e * st;
        let ny = e * ct - rx * st;
        Frame {
            r: Matrix3::from_columns(&[nx, ny, nz]),
            p: self.p + rx * l.a + nz * l.d,
        }
    }
}

impl Arm {
    /// The arm of the paper's Table 2.
    pub fn paper() -> Self {
        Arm::new(PAPER_DH)
    }

    /// An arm from any six modified D-H rows.
    pub fn new(rows: [DhRow; 6]) -> Self {
        let links = rows.map(|r| {
            let alpha = r.alpha_deg.to_radians();
            // Snap exact right angles so that cos(90°) is 0, not 6e-17.
            let (mut sa, mut ca) = alpha.sin_cos();
            for v in [&mut sa, &mut ca] {
                if v.abs() < 1e-15 {
                    *v = 0.0;
                }
            }
            Link {
                ca,
                sa,
                a: r.a_mm,
                d: r.d_mm,
                offset: r.offset_deg.to_radians(),
            }
        });
        Arm { rows, links }
    }

    /// The D-H rows the arm was built from.
    pub fn dh_rows(&self) -> &[DhRow; 6] {
        &self.rows
    }

    /// Frames 1..=6 of the arm for joint angles `q` (radians).
    #[inline]
    pub(crate) fn frames(&self, q: &Joints) -> [Frame; 6] {
        let mut out = [Frame::identity(); 6];
        let mut f = Frame::identity();
        for i in 0..6 {
            f = f.then_link(&self.links[i], q[i]);
            out[i] = f;
        }
        out
    }

    /// Forward kinematics: the terminal pose (mm) for joint angles `q` (radians).
    #[inline]
    pub fn fk(&self, q: &Joints) -> TerminalPose {
        let mut f = Frame::identity();
        for (link, &theta) in self.links.iter().zip(q) {
            f = f.then_link(link, theta);
        }
        TerminalPose {
            position_mm: f.p,
            rotation: f.r,
        }
    }

    /// The arm's body polyline for joint angles `q` (radians), mm:
    /// base (0,0,0), O1, O2, O3, Aux, O4, O5, O6.
    ///
    /// Aux ("joint 3.5") is frame 3 moved by the next link's twist and length,
    /// `T_3 * RotX(alpha_3) * TransX(a_3)`: for Table 2 the end of the 300 mm forearm
    /// before the 106 mm offset.
    #[inline]
    pub fn points_mm(&self, q: &Joints) -> ArmPoints {
        let fr = self.frames(q);
        let l4 = &self.links[3];
        // Aux = O3 + R3 * (a_3, 0, 0): RotX does not move the x axis.
        let aux = fr[2].p + fr[2].r.column(0) * l4.a;
        [
            Vector3::zeros(),
            fr[0].p,
            fr[1].p,
            fr[2].p,
            aux,
            fr[3].p,
            fr[4].p,
            fr[5].p,
        ]
    }
}

/// One terminal orientation of the paper's grid (eq. 12).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orientation {
    /// (rt_x, rt_y, rt_z), degrees.
    pub rpy_deg: [f64; 3],
    /// `Rz(rt_z) * Ry(rt_y) * Rx(rt_x)`.
    pub rotation: Matrix3<f64>,
}

/// Rotation `Rz(rz) * Ry(ry) * Rx(rx)` from angles in degrees.
pub fn rotation_from_rpy_deg(rpy_deg: [f64; 3]) -> Matrix3<f64> {
    let [rx, ry, rz] = rpy_deg.map(f64::to_radians);
    let r = Rotation3::from_axis_angle(&Vector3::z_axis(), rz)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), ry)
        * Rotation3::from_axis_angle(&Vector3::x_axis(), rx);
    r.into_inner()
}

/// The paper's orientation grid: rt_x, rt_y, rt_z in {0, 360/n_d, ...} degrees,
/// `R = Rz(rt_z) Ry(rt_y) Rx(rt_x)`, with rotations that equal an earlier one (in the loop
/// order rt_x, rt_y, rt_z) removed. For n_d = 8 that leaves 208 of the 512 triples; 1824 for
/// n_d = 16, 15424 for 32, 127104 for 64. The grid of `k * n_d` contains every rotation of
/// the grid of `n_d`.
///
/// Duplicates are found exactly on the integer grid indices, in O(n_d³): with `h = n_d / 2`,
/// `(i_x, i_y, i_z)` and `(i_x + h, h - i_y, i_z + h)` (mod n_d) give the same rotation
/// (n_d even), and at rt_y = ±90° (n_d a multiple of 4) the rotation depends only on
/// `i_z ∓ i_x`; no other two triples coincide.
pub fn orientation_grid(divisions: u32) -> Vec<Orientation> {
    let n = divisions.max(1);
    let step = 360.0 / n as f64;
    let mut seen = std::collections::HashSet::new();
    let mut out: Vec<Orientation> = Vec::new();
    for ix in 0..n {
        for iy in 0..n {
            for iz in 0..n {
                if !seen.insert(grid_rotation_key(n, ix, iy, iz)) {
                    continue;
                }
                let rpy = [ix as f64 * step, iy as f64 * step, iz as f64 * step];
                out.push(Orientation {
                    rpy_deg: rpy,
                    rotation: rotation_from_rpy_deg(rpy),
                });
            }
        }
    }
    out
}

/// A key equal for two index triples of the n-division grid exactly when their rotations
/// are equal (see [`orientation_grid`]).
fn grid_rotation_key(n: u32, ix: u32, iy: u32, iz: u32) -> (u8, u32, u32, u32) {
    if n % 4 == 0 && iy == n / 4 {
        // rt_y = +90°: Rz(c) Ry(90°) Rx(a) depends on c - a.
        return (1, (iz + n - ix) % n, 0, 0);
    }
    if n % 4 == 0 && iy == 3 * n / 4 {
        // rt_y = -90°: depends on c + a.
        return (2, (iz + ix) % n, 0, 0);
    }
    if n % 2 == 0 {
        let h = n / 2;
        let twin = ((ix + h) % n, (h + n - iy) % n, (iz + h) % n);
        return (0, ix, iy, iz).min((0, twin.0, twin.1, twin.2));
    }
    (0, ix, iy, iz)
}

/// Angle wrapped to (-pi, pi].
#[inline]
pub fn wrap_angle(a: f64) -> f64 {
    use std::f64::consts::PI;
    let mut w = a.rem_euclid(2.0 * PI);
    if w > PI {
        w -= 2.0 * PI;
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn beta0_reaches_start_cell_with_identity_rotation() {
        let arm = Arm::paper();
        let q = PAPER_BETA0_DEG.map(f64::to_radians);
        let pose = arm.fk(&q);
        let want = Vector3::new(0.0, -200.0, 400.0);
        assert!(
            (pose.position_mm - want).norm() < 0.1,
            "terminal at {:?}",
            pose.position_mm
        );
        assert!(
            (pose.rotation - Matrix3::identity()).amax() < 1e-4,
            "rotation {:?}",
            pose.rotation
        );
        let pts = arm.points_mm(&q);
        assert_eq!(pts[7], pose.position_mm);
        // Aux is 300 mm from O3, O4 is 106 mm from Aux.
        assert!(((pts[4] - pts[3]).norm() - 300.0).abs() < 1e-9);
        assert!(((pts[5] - pts[4]).norm() - 106.0).abs() < 1e-9);
    }

    #[test]
    fn orientation_grid_removes_duplicates() {
        let g = orientation_grid(8);
        assert_eq!(g.len(), 208, "distinct rotations of the 45-degree grid");
        for (i, a) in g.iter().enumerate() {
            for b in &g[i + 1..] {
                assert!((a.rotation - b.rotation).amax() > 1e-9);
            }
        }
        assert_eq!(g[0].rpy_deg, [0.0, 0.0, 0.0]);
    }

    #[test]
    fn wrap_angle_range() {
        use std::f64::consts::PI;
        assert_eq!(wrap_angle(PI), PI);
        assert!((wrap_angle(-PI) - PI).abs() < 1e-12);
        assert!((wrap_angle(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-12);
    }

    /// The exact index dedupe keeps the same orientations, in the same order, as comparing
    /// every rotation with every earlier one (within 1e-9).
    #[test]
    fn orientation_grid_matches_brute_force_dedupe() {
        for n in 1..=16 {
            let step = 360.0 / n as f64;
            let mut brute: Vec<Orientation> = Vec::new();
            for ix in 0..n {
                for iy in 0..n {
                    for iz in 0..n {
                        let rpy = [ix as f64 * step, iy as f64 * step, iz as f64 * step];
                        let rotation = rotation_from_rpy_deg(rpy);
                        if !brute.iter().any(|o| (o.rotation - rotation).amax() < 1e-9) {
                            brute.push(Orientation {
                                rpy_deg: rpy,
                                rotation,
                            });
                        }
                    }
                }
            }
            let fast = orientation_grid(n);
            assert_eq!(fast.len(), brute.len(), "n_d = {n}");
            for (a, b) in fast.iter().zip(&brute) {
                assert_eq!(a.rpy_deg, b.rpy_deg, "n_d = {n}");
            }
        }
        assert_eq!(orientation_grid(8).len(), 208);
        assert_eq!(orientation_grid(32).len(), 15424);
    }
}
