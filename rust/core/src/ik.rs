//! Closed-form inverse kinematics (eq. 13): every joint solution, up to 8, for a terminal
//! pose of a UR-style arm described in modified (Craig) D-H.
//!
//! Entry points:
//! - [`Arm::ik`] — all solutions for a [`TerminalPose`] (position in mm, rotation matrix),
//!   returned as an allocation-free [`IkSolutions`] (at most [`MAX_IK_SOLUTIONS`]).
//! - [`check_closed_form_family`] — whether a D-H table belongs to the family this closed
//!   form handles; [`Arm::ik`] returns no solution for an arm outside it.
//!
//! # Family
//! Rows `(alpha_{i-1}, a_{i-1}, d_i, offset_i)`, lengths in mm, angles in degrees:
//! alphas exactly `(0, 90, 0, 0, 90, -90)`, `a_0 = a_1 = a_4 = a_5 = 0`, `d_2 = d_3 = 0`;
//! free: `d_1`, `a_2`, `a_3` (both non-zero), `d_4`, `d_5`, `d_6` and every theta offset.
//! Table 2 of the paper is one member. Joints 2, 3, 4 are parallel, so the arm is a planar
//! two-link chain (`a_2`, `a_3`) carried by joint 1 and followed by a spherical-like wrist
//! with the offsets `d_4`, `d_5`, `d_6`.
//!
//! # Derivation (effective angles `t_i = q_i + offset_i`)
//! 1. Wrist point: `O5 = p - d_6 z_6` (`z_6` = third column of the rotation), taken relative
//!    to `O1 = (0, 0, d_1)`: `(x, y, z)`.
//! 2. Shoulder: in frame 1, O5 lies at `(rho, -d_4, z)`, so `-sin t1 x + cos t1 y = -d_4`:
//!    with `h = sqrt(x^2 + y^2 - d_4^2)` and `rho = ±h`,
//!    `t1 = atan2(rho y + d_4 x, rho x - d_4 y)` (shoulder left/right).
//! 3. Wrist: `M = RotX(90°)^T RotZ(-t1) R = RotZ(t234) RotY(-t5) RotZ(t6)` (ZYZ Euler
//!    angles), so `t5 = ±atan2(|s5|, M_22)`, `t6 = atan2(-M_21, M_20)` (+pi for the other
//!    sign) and `t234` from the sum `t234 + t6 = atan2(M_10 - M_01, M_00 + M_11)` (or the
//!    difference when `M_22 < 0`), which stays accurate when `s5` is small (wrist up/down).
//! 4. Elbow: `(X, Z) = (rho - d_5 sin t234, z + d_5 cos t234) = a_2 (c2, s2) + a_3 (c23, s23)`:
//!    `c3 = (X^2 + Z^2 - a_2^2 - a_3^2) / (2 a_2 a_3)`, `t3 = atan2(±s3, c3)`,
//!    `t2 = atan2(Z, X) - atan2(a_3 s3, a_2 + a_3 c3)` (from
//!    `(a_2 + a_3 e^{i t3}) e^{i t2} = X + i Z`; elbow up/down), and `t4 = t234 - t2 - t3`.
//!
//! Only 20 `atan2` calls and no `sin`/`cos` for 8 regular solutions: the second wrist branch
//! is `(-t5, t6 + pi, t234 + pi)`, the second elbow branch `(t2 + 2 psi, -t3)`, and the
//! cosines and sines of `t1` and `t234` come from normalised vectors.
//!
//! # Singular and boundary poses (deterministic choices)
//! `L = |d_1| + |a_2| + |a_3| + |d_4| + |d_5| + |d_6|` is the arm's size and `tol = 1e-10 L`
//! its length tolerance (about 1e-7 mm for Table 2): a wrist point within `tol` of a reach
//! boundary is put on it (two branches then coincide), farther outside is unreachable.
//! Near a boundary the branch angles move like the square root of the distance, so a
//! configuration within about `sqrt(tol / link length)` rad (~4e-5 rad for Table 2) of a
//! stretched elbow or of the shoulder boundary comes back as the boundary configuration.
//! - **Shoulder, wrist point on the joint-1 axis** (`sqrt(x^2 + y^2) <= tol`, only
//!   reachable when `|d_4| <= 2 tol`): any `q1` works; the canonical choice is
//!   `q1 = 0` and `q1 = pi` (the two shoulder branches of azimuth 0). If neither reaches
//!   (the wrist orientation then forces an elbow point out of reach), the `q1` pair that
//!   puts the elbow's planar point mid-way between its inner and outer reach is used.
//! - **Shoulder boundary** (wrist point within `tol` of distance `|d_4|` from the axis):
//!   the two shoulder branches coincide and are returned once (`rho = 0`).
//!   A wrist point closer than `|d_4| - tol` to the axis is unreachable.
//! - **Wrist singularity** (`|s5| <= 1e-10`): joints 4 and 6 are coupled (only
//!   `t234 + t6`, or `t234 - t6` when `t5 = pi`, is fixed); `q5` is snapped to the exact
//!   value (`t5 = 0` or `pi`) and the canonical split is `q6 = 0`, joint 4 taking the rest.
//!   Because `t234` moves the elbow's target, that split can leave it out of reach although
//!   other splits reach: then the split that puts the planar point mid-way between the
//!   elbow's inner and outer reach is used instead. One wrist branch instead of two.
//! - **Elbow stretched or folded** (`|sqrt(X^2 + Z^2) - (|a_2| + |a_3|)| <= tol`, or the
//!   same against `||a_2| - |a_3||`): the two elbow branches coincide, `s3 = 0`, returned
//!   once. Farther than `tol` outside `[||a_2| - |a_3||, |a_2| + |a_3|]`: no solution in
//!   that branch. If `|a_2| = |a_3|` and the wrist point sits on joint 2 (folded onto
//!   the shoulder) any `q2` works; the canonical choice is `q2 = 0`.
//!
//! Each of these choices moves the pose by at most a few `tol` (1e-7 mm for Table 2) and
//! `1e-10` in rotation. Candidates made through one of these branches get a final FK check
//! with loose tolerances ([`IK_CHECK_POSITION_MM`], [`IK_CHECK_ROTATION`]): it never rejects
//! an honest boundary solution and only drops numerically degenerate ones. Regular
//! candidates are exact by construction (the tests check them against FK at 1e-6 mm and
//! 1e-9 in rotation).
//!
//! # Input
//! Position and rotation must be finite, and the rotation a proper rotation within
//! [`IK_ROTATION_INPUT_TOL`] (max entry of `R^T R - I`, `det R > 0`); otherwise there is
//! no solution. A target farther than `L` from the base is rejected at once.
//!
//! Solutions are ordered shoulder (`rho = +h`, `-h`) × wrist (`s5 > 0`, `< 0`) × elbow
//! (`s3 > 0`, `< 0`), with every angle wrapped to (-pi, pi] and duplicates (every joint
//! within [`IK_DUPLICATE_TOL`] rad modulo 2 pi) removed.

use std::f64::consts::{PI, TAU};

use crate::kinematics::{wrap_angle, Arm, DhRow, Joints, TerminalPose};

/// The most closed-form solutions a pose can have (shoulder × wrist × elbow).
pub const MAX_IK_SOLUTIONS: usize = 8;

/// Two solutions whose joints all agree within this many radians (modulo 2 pi) are one.
pub const IK_DUPLICATE_TOL: f64 = 1e-9;

/// How far the input rotation may be from a rotation matrix (max entry of `R^T R - I`).
pub const IK_ROTATION_INPUT_TOL: f64 = 1e-6;

/// Final FK check of candidates from singular or boundary branches: position, mm.
pub const IK_CHECK_POSITION_MM: f64 = 1e-3;

/// Final FK check of candidates from singular or boundary branches: max rotation entry.
pub const IK_CHECK_ROTATION: f64 = 1e-5;

/// Length tolerance relative to the arm's size `L` (see the module docs).
const LENGTH_TOL_REL: f64 = 1e-10;

/// `|sin t5|` at or below which the wrist is treated as singular.
const WRIST_SINGULAR: f64 = 1e-10;

/// Up to 8 IK solutions (joint angles, radians, each in (-pi, pi]); fixed capacity, no
/// allocation. Dereferences to `&[Joints]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkSolutions {
    /// Solutions in `[..len]`; unused slots stay zero so that `==` compares contents.
    sols: [Joints; MAX_IK_SOLUTIONS],
    len: usize,
}

impl Default for IkSolutions {
    fn default() -> Self {
        IkSolutions {
            sols: [[0.0; 6]; MAX_IK_SOLUTIONS],
            len: 0,
        }
    }
}

impl IkSolutions {
    /// Number of solutions (0..=8).
    #[inline]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there is no solution (pose unreachable or invalid input).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The solutions as a slice of joint vectors (radians).
    #[inline]
    pub fn as_slice(&self) -> &[Joints] {
        &self.sols[..self.len]
    }

    /// Iterator over the solutions (radians).
    #[inline]
    pub fn iter(&self) -> std::slice::Iter<'_, Joints> {
        self.as_slice().iter()
    }

    /// Whether `q` is already stored (every joint within [`IK_DUPLICATE_TOL`] mod 2 pi).
    fn contains_close(&self, q: &Joints) -> bool {
        self.as_slice().iter().any(|s| {
            s.iter().zip(q).all(|(a, b)| {
                let d = (a - b).abs();
                d.min(TAU - d) <= IK_DUPLICATE_TOL
            })
        })
    }

    /// Stores `q` unless it is full or `q` duplicates a stored solution.
    fn push_unique(&mut self, q: Joints) {
        if self.len < MAX_IK_SOLUTIONS && !self.contains_close(&q) {
            self.sols[self.len] = q;
            self.len += 1;
        }
    }
}

impl std::ops::Deref for IkSolutions {
    type Target = [Joints];
    #[inline]
    fn deref(&self) -> &[Joints] {
        self.as_slice()
    }
}

impl<'a> IntoIterator for &'a IkSolutions {
    type Item = &'a Joints;
    type IntoIter = std::slice::Iter<'a, Joints>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

/// What a family row must hold.
#[derive(Debug, Clone, Copy)]
enum Need {
    Finite,
    Exactly(f64),
    NonZero,
}

/// The first field of `rows` outside the family: (row 1..=6, field, value, need).
fn family_violation(rows: &[DhRow; 6]) -> Option<(usize, &'static str, f64, Need)> {
    const ALPHA: [f64; 6] = [0.0, 90.0, 0.0, 0.0, 90.0, -90.0];
    const ALPHA_NAME: [&str; 6] = [
        "alpha_0 (deg)",
        "alpha_1 (deg)",
        "alpha_2 (deg)",
        "alpha_3 (deg)",
        "alpha_4 (deg)",
        "alpha_5 (deg)",
    ];
    const A_NAME: [&str; 6] = [
        "a_0 (mm)", "a_1 (mm)", "a_2 (mm)", "a_3 (mm)", "a_4 (mm)", "a_5 (mm)",
    ];
    const D_NAME: [&str; 6] = [
        "d_1 (mm)", "d_2 (mm)", "d_3 (mm)", "d_4 (mm)", "d_5 (mm)", "d_6 (mm)",
    ];
    const OFF_NAME: [&str; 6] = [
        "offset_1 (deg)",
        "offset_2 (deg)",
        "offset_3 (deg)",
        "offset_4 (deg)",
        "offset_5 (deg)",
        "offset_6 (deg)",
    ];
    for (i, row) in rows.iter().enumerate() {
        let a_need = match i {
            2 | 3 => Need::NonZero,
            _ => Need::Exactly(0.0),
        };
        let d_need = match i {
            1 | 2 => Need::Exactly(0.0),
            _ => Need::Finite,
        };
        let fields = [
            (ALPHA_NAME[i], row.alpha_deg, Need::Exactly(ALPHA[i])),
            (A_NAME[i], row.a_mm, a_need),
            (D_NAME[i], row.d_mm, d_need),
            (OFF_NAME[i], row.offset_deg, Need::Finite),
        ];
        for (name, v, need) in fields {
            let ok = v.is_finite()
                && match need {
                    Need::Finite => true,
                    Need::Exactly(w) => v == w,
                    Need::NonZero => v != 0.0,
                };
            if !ok {
                return Some((i + 1, name, v, need));
            }
        }
    }
    None
}

/// [`family_violation`]`(rows).is_none()`, branch-light for the per-call check of [`Arm::ik`].
#[inline]
fn in_family(r: &[DhRow; 6]) -> bool {
    let alphas = r[0].alpha_deg == 0.0
        && r[1].alpha_deg == 90.0
        && r[2].alpha_deg == 0.0
        && r[3].alpha_deg == 0.0
        && r[4].alpha_deg == 90.0
        && r[5].alpha_deg == -90.0;
    let zeros = r[0].a_mm == 0.0
        && r[1].a_mm == 0.0
        && r[4].a_mm == 0.0
        && r[5].a_mm == 0.0
        && r[1].d_mm == 0.0
        && r[2].d_mm == 0.0;
    let free = [
        r[0].d_mm,
        r[3].d_mm,
        r[4].d_mm,
        r[5].d_mm,
        r[0].offset_deg,
        r[1].offset_deg,
        r[2].offset_deg,
        r[3].offset_deg,
        r[4].offset_deg,
        r[5].offset_deg,
    ];
    let nonzero = |v: f64| v != 0.0 && v.is_finite();
    alphas
        && zeros
        && nonzero(r[2].a_mm)
        && nonzero(r[3].a_mm)
        && free.iter().all(|v| v.is_finite())
}

/// Whether a D-H table belongs to the family the closed form handles (see the module
/// docs): alphas exactly `(0, 90, 0, 0, 90, -90)` degrees, `a_0 = a_1 = a_4 = a_5 = 0` and
/// `d_2 = d_3 = 0` (exact zeros), `a_2` and `a_3` non-zero, every value finite; `d_1`,
/// `d_4`, `d_5`, `d_6` (mm) and the theta offsets (degrees) free.
///
/// `Err` names the first row (1-based, row i holds `alpha_{i-1}, a_{i-1}, d_i, offset_i`),
/// the field with its unit, the value found and what is needed.
pub fn check_closed_form_family(rows: &[DhRow; 6]) -> Result<(), String> {
    match family_violation(rows) {
        None => Ok(()),
        Some((row, field, value, need)) => {
            let want = match need {
                Need::Finite => "a finite value".to_string(),
                Need::Exactly(w) => format!("exactly {w}"),
                Need::NonZero => "a finite non-zero value".to_string(),
            };
            Err(format!(
                "D-H row {row}: {field} = {value}, but the closed-form IK needs {want}"
            ))
        }
    }
}

/// Per-arm constants of the closed form (lengths mm, offsets rad).
struct Params {
    d1: f64,
    a2: f64,
    a3: f64,
    d4: f64,
    d5: f64,
    d6: f64,
    off: [f64; 6],
    /// Arm size `L`, mm.
    size: f64,
    /// Length tolerance, mm.
    tol: f64,
    /// `|a2| + |a3|` and `||a2| - |a3||`, mm.
    rmax: f64,
    rmin: f64,
}

impl Params {
    #[inline]
    fn of(arm: &Arm) -> Option<Params> {
        if !in_family(arm.dh_rows()) {
            return None;
        }
        let l = &arm.links;
        let (d1, a2, a3, d4, d5, d6) = (l[0].d, l[2].a, l[3].a, l[3].d, l[4].d, l[5].d);
        let size = d1.abs() + a2.abs() + a3.abs() + d4.abs() + d5.abs() + d6.abs();
        Some(Params {
            d1,
            a2,
            a3,
            d4,
            d5,
            d6,
            off: [
                l[0].offset,
                l[1].offset,
                l[2].offset,
                l[3].offset,
                l[4].offset,
                l[5].offset,
            ],
            size,
            tol: LENGTH_TOL_REL * size,
            rmax: a2.abs() + a3.abs(),
            rmin: (a2.abs() - a3.abs()).abs(),
        })
    }
}

/// Angle wrapped to (-pi, pi]; cheap for angles within one turn of the range.
#[inline]
fn wrap(a: f64) -> f64 {
    if a > PI {
        // Exact subtraction (Sterbenz) for a in (pi, 4pi].
        let w = a - TAU;
        if w <= PI {
            return w;
        }
    } else if a <= -PI {
        let w = a + TAU;
        if w > -PI {
            return w;
        }
    } else {
        return a;
    }
    wrap_angle(a)
}

/// Whether `r` is a proper rotation within [`IK_ROTATION_INPUT_TOL`].
#[inline]
fn is_rotation(r: &nalgebra::Matrix3<f64>) -> bool {
    let c = [r.column(0), r.column(1), r.column(2)];
    let mut worst: f64 = 0.0;
    for i in 0..3 {
        for j in i..3 {
            let want = if i == j { 1.0 } else { 0.0 };
            worst = worst.max((c[i].dot(&c[j]) - want).abs());
        }
    }
    worst <= IK_ROTATION_INPUT_TOL && r.determinant() > 0.0
}

impl Arm {
    /// Every closed-form inverse-kinematics solution (up to 8) that reaches `target`
    /// (position in mm, base frame; rotation of the terminal frame), as joint angles in
    /// radians wrapped to (-pi, pi], without duplicates.
    ///
    /// An unreachable pose, a non-finite input, a matrix that is not a rotation, or an arm
    /// outside [`check_closed_form_family`] gives no solution. Never NaN, never panics.
    /// Singular poses get the canonical choices of the [module docs](crate::ik).
    ///
    /// ```
    /// use sixaxis_core::kinematics::{Arm, PAPER_BETA0_DEG};
    /// let arm = Arm::paper();
    /// let beta0 = PAPER_BETA0_DEG.map(f64::to_radians);
    /// let pose = arm.fk(&beta0);
    /// let sols = arm.ik(&pose);
    /// assert!(!sols.is_empty() && sols.len() <= 8);
    /// // Every solution reproduces the pose ...
    /// for q in &sols {
    ///     let p = arm.fk(q);
    ///     assert!((p.position_mm - pose.position_mm).norm() < 1e-6);
    ///     assert!((p.rotation - pose.rotation).amax() < 1e-9);
    /// }
    /// // ... and beta_0 itself is one of them.
    /// assert!(sols
    ///     .iter()
    ///     .any(|q| q.iter().zip(&beta0).all(|(a, b)| (a - b).abs() < 1e-9)));
    /// ```
    pub fn ik(&self, target: &TerminalPose) -> IkSolutions {
        let mut out = IkSolutions::default();
        let Some(k) = Params::of(self) else {
            return out;
        };
        let p = &target.position_mm;
        let r = &target.rotation;
        if !(p.iter().all(|v| v.is_finite()) && r.iter().all(|v| v.is_finite())) {
            return out;
        }
        // Farther than the whole arm, or not a rotation: unreachable. (This also keeps
        // every square below far from overflow.)
        let within_arm = p.norm() <= k.size + k.tol;
        if !within_arm || !is_rotation(r) {
            return out;
        }
        // 1. Wrist point O5 relative to O1.
        let t = Target {
            pose: target,
            x: p.x - k.d6 * r[(0, 2)],
            y: p.y - k.d6 * r[(1, 2)],
            z: p.z - k.d6 * r[(2, 2)] - k.d1,
        };
        let rr2 = t.x * t.x + t.y * t.y;
        let rr = rr2.sqrt();

        // 2. Shoulder branches.
        if rr < k.d4.abs() - k.tol {
            return out;
        }
        if rr <= k.tol {
            // Wrist point on the joint-1 axis: canonical q1 = 0 and q1 = pi, or, when
            // neither reaches, the q1 pair that puts the elbow mid-reach.
            for t1 in [k.off[0], k.off[0] + PI] {
                self.ik_shoulder(&k, &t, Angle::of(t1), true, &mut out);
            }
            if out.is_empty() {
                let (t1s, n) = on_axis_shoulders(&k, &t);
                for &t1 in &t1s[..n] {
                    self.ik_shoulder(&k, &t, Angle::of(t1), true, &mut out);
                }
            }
            return out;
        }
        if rr - k.d4.abs() <= k.tol {
            // Shoulder boundary: both branches at rho = 0 (the constraint is then met to
            // second order, (rr - |d4|) at most).
            let t1 = Angle::atan2(k.d4 * t.x, -k.d4 * t.y);
            self.ik_shoulder(&k, &t, t1, true, &mut out);
        } else {
            let h = (rr2 - k.d4 * k.d4).max(0.0).sqrt();
            for rho in [h, -h] {
                let t1 = Angle::atan2(rho * t.y + k.d4 * t.x, rho * t.x - k.d4 * t.y);
                self.ik_shoulder(&k, &t, t1, false, &mut out);
            }
        }
        out
    }

    /// Steps 3 and 4 for one shoulder angle `t1` (effective).
    #[inline]
    fn ik_shoulder(&self, k: &Params, t: &Target, t1: Angle, deg1: bool, out: &mut IkSolutions) {
        let r = &t.pose.rotation;
        let (s1, c1) = (t1.s, t1.c);
        // In-plane coordinate of O5 in frame 1.
        let rho = c1 * t.x + s1 * t.y;
        // 3. M = RotX(90)^T RotZ(-t1) R = RotZ(t234) RotY(-t5) RotZ(t6).
        let m00 = c1 * r[(0, 0)] + s1 * r[(1, 0)];
        let m01 = c1 * r[(0, 1)] + s1 * r[(1, 1)];
        let m02 = c1 * r[(0, 2)] + s1 * r[(1, 2)];
        let (m10, m11, m12) = (r[(2, 0)], r[(2, 1)], r[(2, 2)]);
        let m20 = s1 * r[(0, 0)] - c1 * r[(1, 0)];
        let m21 = s1 * r[(0, 1)] - c1 * r[(1, 1)];
        let m22 = s1 * r[(0, 2)] - c1 * r[(1, 2)];
        let s5 = (m02 * m02 + m12 * m12).sqrt();
        // t234 + t6 (t5 near 0) or t234 - t6 (t5 near pi): accurate even for small s5.
        let up = m22 >= 0.0;
        let coupled = if up {
            Angle::atan2(m10 - m01, m00 + m11)
        } else {
            Angle::atan2(-(m10 + m01), m11 - m00)
        };
        if s5 <= WRIST_SINGULAR {
            // Joints 4 and 6 coupled: canonical split q6 = 0; if that leaves the wrist
            // point out of the elbow's reach, the split that puts it mid-reach.
            let t5 = if up { 0.0 } else { PI };
            let split = |t234: f64| {
                if up {
                    coupled.t - t234
                } else {
                    t234 - coupled.t
                }
            };
            let mut t6 = k.off[5];
            let mut t234 = if up { coupled.t - t6 } else { coupled.t + t6 };
            if !within_reach(k, rho, t.z, t234) {
                if let Some(a) = mid_reach_t234(k, rho, t.z) {
                    t234 = a;
                    t6 = split(a);
                }
            }
            let w = Wrist {
                t1: t1.t,
                t5,
                t6,
                t234: Angle::of(t234),
            };
            self.ik_planar(k, t, &w, rho, true, out);
        } else {
            let t5 = s5.atan2(m22);
            let t6 = Angle::atan2(-m21, m20);
            // t234 = coupled - t6 (up) or coupled + t6, with its cosine and sine.
            let t234 = if up {
                Angle {
                    t: coupled.t - t6.t,
                    c: coupled.c * t6.c + coupled.s * t6.s,
                    s: coupled.s * t6.c - coupled.c * t6.s,
                }
            } else {
                Angle {
                    t: coupled.t + t6.t,
                    c: coupled.c * t6.c - coupled.s * t6.s,
                    s: coupled.s * t6.c + coupled.c * t6.s,
                }
            };
            let w = Wrist {
                t1: t1.t,
                t5,
                t6: t6.t,
                t234,
            };
            self.ik_planar(k, t, &w, rho, deg1, out);
            let w = Wrist {
                t1: t1.t,
                t5: -t5,
                t6: t6.t + PI,
                t234: Angle {
                    t: t234.t + PI,
                    c: -t234.c,
                    s: -t234.s,
                },
            };
            self.ik_planar(k, t, &w, rho, deg1, out);
        }
    }

    /// Step 4: the planar two-link chain for one shoulder and wrist branch; pushes up to
    /// two solutions (elbow branches).
    #[inline]
    fn ik_planar(
        &self,
        k: &Params,
        t: &Target,
        w: &Wrist,
        rho: f64,
        degenerate: bool,
        out: &mut IkSolutions,
    ) {
        let xx = rho - k.d5 * w.t234.s;
        let zz = t.z + k.d5 * w.t234.c;
        let n2 = xx * xx + zz * zz;
        let n = n2.sqrt();
        if !(n <= k.rmax + k.tol && n >= k.rmin - k.tol) {
            return;
        }
        // (a2 + a3 e^{i t3}) e^{i t2} = X + i Z: t2 = atan2(Z, X) - arg(k1 + i k2).
        let phi = zz.atan2(xx);
        if (n - k.rmax).abs() <= k.tol || (n - k.rmin).abs() <= k.tol {
            // Stretched (c3 = sign(a2 a3)) or folded (the other sign): one elbow branch.
            let stretched = (n - k.rmax).abs() <= (n - k.rmin).abs();
            let c3 = if stretched { 1.0 } else { -1.0 } * (k.a2 * k.a3).signum();
            let k1 = k.a2 + k.a3 * c3;
            let t3 = if c3 > 0.0 { 0.0 } else { PI };
            let t2 = if k1.abs() <= k.tol {
                // Folded onto the shoulder with |a2| = |a3|: canonical q2 = 0.
                k.off[1]
            } else if k1 > 0.0 {
                phi
            } else {
                phi - PI
            };
            self.push_checked(k, t, w, t2, t3, true, out);
        } else {
            let c3 = (n2 - k.a2 * k.a2 - k.a3 * k.a3) / (2.0 * k.a2 * k.a3);
            let clamped = c3.clamp(-1.0, 1.0);
            let s3 = (1.0 - clamped * clamped).max(0.0).sqrt();
            let t3 = s3.atan2(clamped);
            let psi = (k.a3 * s3).atan2(k.a2 + k.a3 * clamped);
            let deg = degenerate || clamped != c3;
            self.push_checked(k, t, w, phi - psi, t3, deg, out);
            self.push_checked(k, t, w, phi + psi, -t3, deg, out);
        }
    }

    /// Wraps one candidate into joint angles, FK-checks it if it came through a singular
    /// or boundary branch, and stores it unless it duplicates a stored one.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn push_checked(
        &self,
        k: &Params,
        t: &Target,
        w: &Wrist,
        t2: f64,
        t3: f64,
        degenerate: bool,
        out: &mut IkSolutions,
    ) {
        let t4 = w.t234.t - t2 - t3;
        let q = [
            wrap(w.t1 - k.off[0]),
            wrap(t2 - k.off[1]),
            wrap(t3 - k.off[2]),
            wrap(t4 - k.off[3]),
            wrap(w.t5 - k.off[4]),
            wrap(w.t6 - k.off[5]),
        ];
        if !q.iter().all(|v| v.is_finite()) {
            return;
        }
        if degenerate {
            let f = self.fk(&q);
            let ok = (f.position_mm - t.pose.position_mm).norm() <= IK_CHECK_POSITION_MM
                && (f.rotation - t.pose.rotation).amax() <= IK_CHECK_ROTATION;
            if !ok {
                return;
            }
        }
        out.push_unique(q);
    }
}

/// An angle (rad) with its cosine and sine.
#[derive(Clone, Copy)]
struct Angle {
    t: f64,
    c: f64,
    s: f64,
}

impl Angle {
    /// From an angle.
    #[inline]
    fn of(t: f64) -> Angle {
        let (s, c) = t.sin_cos();
        Angle { t, c, s }
    }

    /// The angle of the vector `(x, y)`; `(0, 0)` gives angle 0.
    #[inline]
    fn atan2(y: f64, x: f64) -> Angle {
        let n = (x * x + y * y).sqrt();
        if n > 0.0 && n.is_finite() {
            Angle {
                t: y.atan2(x),
                c: x / n,
                s: y / n,
            }
        } else {
            Angle::of(y.atan2(x))
        }
    }
}

/// One shoulder and wrist branch: effective t1, t5, t6 (rad) and t234.
struct Wrist {
    t1: f64,
    t5: f64,
    t6: f64,
    t234: Angle,
}

/// The target with its wrist point O5 relative to O1 (mm, base axes).
struct Target<'a> {
    pose: &'a TerminalPose,
    x: f64,
    y: f64,
    z: f64,
}

/// Whether the elbow reaches the planar point of `t234` (within `tol`).
#[inline]
fn within_reach(k: &Params, rho: f64, z: f64, t234: f64) -> bool {
    let (s, c) = t234.sin_cos();
    let n = (rho - k.d5 * s).hypot(z + k.d5 * c);
    n <= k.rmax + k.tol && n >= k.rmin - k.tol
}

/// The t234 (effective, rad) whose planar point `(rho - d5 sin, z + d5 cos)` lies closest
/// to the middle of the elbow's reach `(rmin + rmax) / 2`; `None` when t234 does not
/// move that distance (`d5` or `(rho, z)` zero).
fn mid_reach_t234(k: &Params, rho: f64, z: f64) -> Option<f64> {
    // |P|^2 = c^2 + d5^2 + 2 d5 c cos(t234 + g), c = |(rho, z)|, g = atan2(rho, z).
    let c = rho.hypot(z);
    if (k.d5 * c).abs() <= k.tol * k.tol {
        return None;
    }
    let m = 0.5 * (k.rmin + k.rmax);
    let kappa = ((m * m - c * c - k.d5 * k.d5) / (2.0 * k.d5 * c)).clamp(-1.0, 1.0);
    Some(kappa.acos() - rho.atan2(z))
}

/// Shoulder angles (effective, rad) for a wrist point on the joint-1 axis when the
/// canonical q1 = 0 / pi reach nothing: the pair that puts the elbow mid-reach.
fn on_axis_shoulders(k: &Params, t: &Target) -> ([f64; 2], usize) {
    let r = &t.pose.rotation;
    let (r02, r12, r22) = (r[(0, 2)], r[(1, 2)], r[(2, 2)]);
    // With rho = 0, |P|^2 = d5^2 + z^2 + 2 z d5 c234, and for the s5 > 0 branch
    // s5 c234 = -w, s5 = sqrt(w^2 + r22^2), w = mu cos(t1 - beta).
    let mu = r02.hypot(r12);
    if (t.z * k.d5).abs() <= k.tol * k.tol || mu <= 1e-12 {
        return ([0.0; 2], 0);
    }
    let beta = r12.atan2(r02);
    let m = 0.5 * (k.rmin + k.rmax);
    let c = ((m * m - k.d5 * k.d5 - t.z * t.z) / (2.0 * t.z * k.d5)).clamp(-1.0, 1.0);
    if c.abs() >= mu {
        // Best reachable: the extreme c234 = -sign(w) mu.
        let t1 = if c < 0.0 { beta } else { beta + PI };
        return ([t1, 0.0], 1);
    }
    let w = -c * r22.abs() / (1.0 - c * c).sqrt();
    let a = (w / mu).clamp(-1.0, 1.0).acos();
    ([beta + a, beta - a], 2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::PAPER_DH;

    #[test]
    fn fast_family_check_agrees_with_named_one() {
        let values = [0.0, -0.0, 90.0, -90.0, 45.0, 1.0, f64::NAN, f64::INFINITY];
        let mut checked = 0;
        for row in 0..6 {
            for field in 0..4 {
                for &v in &values {
                    let mut rows = PAPER_DH;
                    let r = &mut rows[row];
                    *[
                        &mut r.alpha_deg,
                        &mut r.a_mm,
                        &mut r.d_mm,
                        &mut r.offset_deg,
                    ][field] = v;
                    assert_eq!(
                        in_family(&rows),
                        family_violation(&rows).is_none(),
                        "row {row} field {field} value {v}"
                    );
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 6 * 4 * values.len());
        assert!(in_family(&PAPER_DH));
    }

    #[test]
    fn wrap_matches_wrap_angle() {
        for i in -2000..=2000 {
            let a = i as f64 * 0.01 + 1e-3;
            assert!((wrap(a) - wrap_angle(a)).abs() < 1e-12, "{a}");
            assert!(wrap(a) > -PI && wrap(a) <= PI);
        }
        for a in [PI, -PI, 3.0 * PI, -3.0 * PI, TAU, 0.0, 1e3, -1e3] {
            let w = wrap(a);
            assert!(w > -PI && w <= PI, "{a} -> {w}");
        }
        assert_eq!(wrap(-PI), PI);
    }
}
