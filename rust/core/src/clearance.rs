//! Whole-arm clearance: how far the arm's body stays from the obstacles (paper, section III.C).
//!
//! Entry points:
//! - [`Clearance::from_scenario`] / [`Clearance::new`] — precompute the obstacle centres once.
//! - [`Clearance::clearance_cells`] — the smallest distance of one pose, in cells.
//! - [`Clearance::pose_is_clear`] — the same test with an early exit at the first violation.
//! - [`Clearance::motion_is_clear`] — a joint-space move, checked at every interpolation step.
//! - [`interpolate`] — joint-space interpolation along each joint's shortest angular difference.
//! - [`segment_point_distance`] — eq. 11 for one segment and one point.
//!
//! Two models ([`ClearanceModel`]):
//! - **Centres** (the paper, eq. 11): the arm is the 7-segment polyline of
//!   [`Arm::points_mm`](crate::kinematics::Arm::points_mm); its clearance is the smallest
//!   distance from any obstacle *centre* to any segment, in cells. A pose is clear when that
//!   distance is strictly greater than `arm_safe_distance` (d_p).
//!   Eq. 11 as printed divides `KO·KL` by `|KL|`; the foot of the perpendicular lies inside the
//!   segment when `KO·KL / |KL|²` is in (0, 1), which is what is implemented (the printed
//!   cases `w <= 0`, `0 < w < 1`, `w >= 1` only make sense with that normalisation).
//! - **Capsules** (exact geometry, parry3d): every segment is a capsule of radius
//!   `link_radius_mm`, every obstacle a cube of edge `cell_mm` centred on its cell. The
//!   clearance is the smallest gap between a capsule and a cube (0 when they touch or
//!   overlap), in cells; a pose is clear when `gap * cell_mm > margin_mm`.
//!   A capsule is the Minkowski sum of its segment and a ball, so its gap to a cube is
//!   `max(0, dist(segment, cube) - radius)`: parry measures the segment (a polytope, for which
//!   its GJK terminates exactly) or, for a zero-length link, the point, and the radius is
//!   subtracted here. Cheap bounds prune the exact queries: with `h = cell_mm / 2` and `dc` the
//!   centre-to-segment distance, `max(0, dc - h√3 - r) <= gap <= max(0, dc - h - r)` (the cube
//!   lies between its inscribed and circumscribed balls).
//!
//! Units: positions in mm; clearances in cells unless a name says mm.
//!
//! ```
//! use sixaxis_core::clearance::Clearance;
//! use sixaxis_core::kinematics::PAPER_BETA0_DEG;
//! use sixaxis_core::scenario::Scenario;
//! let s = Scenario::builtin("paper_simple").unwrap();
//! let clearance = Clearance::from_scenario(&s);
//! let arm = s.arm();
//! let beta0 = PAPER_BETA0_DEG.map(f64::to_radians);
//! let points = arm.points_mm(&beta0);
//! assert!(clearance.clearance_cells(&points) > s.arm_safe_distance);
//! assert!(clearance.pose_is_clear(&points));
//! // A move from beta0 to itself is trivially clear.
//! assert!(clearance.motion_is_clear(&arm, &beta0, &beta0, 50));
//! ```

use nalgebra::Vector3;
use parry3d_f64::shape::{Ball, Cuboid, Segment};

use crate::kinematics::{wrap_angle, Arm, ArmPoints, Joints};
use crate::scenario::{Cell, ClearanceModel, Scenario};

/// Lanes of the obstacle loop; the centre arrays are padded to a multiple of this.
const LANES: usize = 4;
/// Coordinate of padding obstacles, cells: far from everything, and its square is finite.
const FAR: f64 = 1.0e100;

/// Whole-arm clearance against a fixed set of obstacles.
///
/// Obstacle centres are stored once, in cells, as structure-of-arrays padded to a multiple of
/// four (padding lies at `1e100` cells and never matters), so that the eq. 11 loop vectorises.
#[derive(Debug, Clone)]
pub struct Clearance {
    /// Obstacle centre x, cells (padded).
    xs: Vec<f64>,
    /// Obstacle centre y, cells (padded).
    ys: Vec<f64>,
    /// Obstacle centre z, cells (padded).
    zs: Vec<f64>,
    /// Number of real obstacles.
    count: usize,
    /// Edge of a cell, mm.
    cell_mm: f64,
    /// The model in use.
    model: ClearanceModel,
    /// d_p, cells (centres model).
    arm_safe_distance_cells: f64,
}

/// Distance from point `p` to segment `a`-`b` (eq. 11), in the unit of the inputs.
///
/// With `w = (p - a)·(b - a) / |b - a|²`: `|p - a|` if `w <= 0`, `|p - b|` if `w >= 1`, else the
/// distance to the foot of the perpendicular `a + w (b - a)`. A zero-length segment is a point.
///
/// ```
/// use nalgebra::Vector3;
/// use sixaxis_core::clearance::segment_point_distance;
/// let (a, b) = (Vector3::new(0.0, 0.0, 0.0), Vector3::new(2.0, 0.0, 0.0));
/// assert_eq!(segment_point_distance(&a, &b, &Vector3::new(1.0, 3.0, 0.0)), 3.0);
/// assert_eq!(segment_point_distance(&a, &b, &Vector3::new(-4.0, 3.0, 0.0)), 5.0);
/// ```
#[inline]
pub fn segment_point_distance(a: &Vector3<f64>, b: &Vector3<f64>, p: &Vector3<f64>) -> f64 {
    let kl = b - a;
    let ko = p - a;
    let ll = kl.norm_squared();
    if ll == 0.0 {
        return ko.norm();
    }
    let w = ko.dot(&kl) / ll;
    if w <= 0.0 {
        ko.norm()
    } else if w >= 1.0 {
        (p - b).norm()
    } else {
        (ko - kl * w).norm()
    }
}

/// Joint-space interpolation (radians): each joint moves by its shortest angular difference
/// `wrap(to - from)`, `fraction` in [0, 1] (clamped); the result is wrapped to (-pi, pi].
/// `fraction = 0` gives `from` wrapped, `fraction = 1` gives `to` wrapped, exactly.
///
/// ```
/// use sixaxis_core::clearance::interpolate;
/// use std::f64::consts::PI;
/// let from = [0.9 * PI, 0.0, 0.0, 0.0, 0.0, 0.0];
/// let to = [-0.9 * PI, 0.0, 0.0, 0.0, 0.0, 0.0];
/// let mid = interpolate(&from, &to, 0.5);
/// assert!((mid[0] - PI).abs() < 1e-12); // across the seam, not through 0
/// ```
#[inline]
pub fn interpolate(from: &Joints, to: &Joints, fraction: f64) -> Joints {
    let f = fraction.clamp(0.0, 1.0);
    let mut out = [0.0; 6];
    for i in 0..6 {
        out[i] = if f == 1.0 {
            wrap_exact(to[i])
        } else {
            wrap_exact(from[i] + wrap_exact(to[i] - from[i]) * f)
        };
    }
    out
}

/// [`wrap_angle`] that leaves an angle already in (-pi, pi] untouched (bit for bit;
/// `wrap_angle` goes through `rem_euclid` and can move a negative angle by an ulp or two).
#[inline]
pub(crate) fn wrap_exact(a: f64) -> f64 {
    if a > -std::f64::consts::PI && a <= std::f64::consts::PI {
        a
    } else {
        wrap_angle(a)
    }
}

/// One segment prepared for the eq. 11 loop, in cells.
#[derive(Clone, Copy)]
struct Seg {
    a: [f64; 3],
    d: [f64; 3],
    /// `1 / |d|²`, or 0 for a zero-length segment (then `w = 0`: the distance to `a`).
    inv_dd: f64,
}

impl Seg {
    #[inline]
    fn new(a: &Vector3<f64>, b: &Vector3<f64>, scale: f64) -> Seg {
        let a = [a.x * scale, a.y * scale, a.z * scale];
        let d = [b.x * scale - a[0], b.y * scale - a[1], b.z * scale - a[2]];
        let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        Seg {
            a,
            d,
            inv_dd: if dd > 0.0 { 1.0 / dd } else { 0.0 },
        }
    }
}

/// The one place where nalgebra vectors become parry (glam) vectors.
#[inline]
fn to_parry(v: &Vector3<f64>) -> parry3d_f64::math::Vector {
    parry3d_f64::math::Vector::new(v.x, v.y, v.z)
}

/// Exact distance (mm) from segment `a`-`b` (mm, expressed relative to the cube's centre) to
/// an axis-aligned cube of half-extent `half_mm` at the origin. A zero-length segment is a
/// point. This is the only parry call of the crate.
fn segment_cube_distance_mm(a: &Vector3<f64>, b: &Vector3<f64>, half_mm: f64) -> f64 {
    use parry3d_f64::math::Pose;
    use parry3d_f64::query;
    let cube = Cuboid::new(parry3d_f64::math::Vector::splat(half_mm));
    let id = Pose::IDENTITY;
    let result = if (b - a).norm_squared() == 0.0 {
        query::distance(
            &Pose::from_translation(to_parry(a)),
            &Ball::new(0.0),
            &id,
            &cube,
        )
    } else {
        query::distance(&id, &Segment::new(to_parry(a), to_parry(b)), &id, &cube)
    };
    result
        .expect("parry supports segment/ball against cuboid")
        .distance
}

/// Gap (mm) between a capsule (segment `a`-`b`, radius `r`, mm) and the cube of edge `2 half`
/// centred at `c` (mm); 0 when they touch or overlap.
fn capsule_cube_gap_mm(
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    r: f64,
    c: &Vector3<f64>,
    half: f64,
) -> f64 {
    (segment_cube_distance_mm(&(a - c), &(b - c), half) - r).max(0.0)
}

impl Clearance {
    /// Clearance against `obstacles` (cells, cubes of edge `cell_mm` mm on their centres),
    /// with the given model and arm safe distance d_p (cells; used by the centres model).
    pub fn new(
        obstacles: &[Cell],
        cell_mm: f64,
        model: ClearanceModel,
        arm_safe_distance_cells: f64,
    ) -> Clearance {
        let count = obstacles.len();
        let padded = count.div_ceil(LANES) * LANES;
        let mut xs = vec![FAR; padded];
        let mut ys = vec![FAR; padded];
        let mut zs = vec![FAR; padded];
        for (i, c) in obstacles.iter().enumerate() {
            xs[i] = c[0] as f64;
            ys[i] = c[1] as f64;
            zs[i] = c[2] as f64;
        }
        Clearance {
            xs,
            ys,
            zs,
            count,
            cell_mm,
            model,
            arm_safe_distance_cells,
        }
    }

    /// Clearance against the scenario's own obstacles, with its `cell_mm`,
    /// `planning.clearance_model` and `arm_safe_distance`.
    pub fn from_scenario(s: &Scenario) -> Clearance {
        Clearance::new(
            &s.obstacles,
            s.cell_mm,
            s.planning.clearance_model,
            s.arm_safe_distance,
        )
    }

    /// Number of obstacles.
    pub fn obstacle_count(&self) -> usize {
        self.count
    }

    /// Obstacle centre `i`, cells.
    fn centre_cells(&self, i: usize) -> Vector3<f64> {
        Vector3::new(self.xs[i], self.ys[i], self.zs[i])
    }

    /// The model in use.
    pub fn model(&self) -> ClearanceModel {
        self.model
    }

    /// Edge of one cell, mm.
    pub fn cell_mm(&self) -> f64 {
        self.cell_mm
    }

    /// d_p, cells (the centres model's threshold).
    pub fn arm_safe_distance_cells(&self) -> f64 {
        self.arm_safe_distance_cells
    }

    /// Smallest squared distance (cells²) from any obstacle centre to one segment.
    #[inline]
    fn seg_min_d2(&self, s: &Seg) -> f64 {
        let mut acc = [f64::INFINITY; LANES];
        let chunks = self
            .xs
            .chunks_exact(LANES)
            .zip(self.ys.chunks_exact(LANES))
            .zip(self.zs.chunks_exact(LANES));
        for ((xs, ys), zs) in chunks {
            for l in 0..LANES {
                let px = xs[l] - s.a[0];
                let py = ys[l] - s.a[1];
                let pz = zs[l] - s.a[2];
                let w = ((px * s.d[0] + py * s.d[1] + pz * s.d[2]) * s.inv_dd).clamp(0.0, 1.0);
                let ex = px - w * s.d[0];
                let ey = py - w * s.d[1];
                let ez = pz - w * s.d[2];
                let d2 = ex * ex + ey * ey + ez * ez;
                acc[l] = if d2 < acc[l] { d2 } else { acc[l] };
            }
        }
        acc.iter()
            .fold(f64::INFINITY, |m, &v| if v < m { v } else { m })
    }

    /// Centres model (eq. 11): smallest distance from any obstacle centre to any of the 7
    /// polyline segments, in cells; `INFINITY` without obstacles.
    pub fn centres_clearance_cells(&self, points: &ArmPoints) -> f64 {
        let scale = 1.0 / self.cell_mm;
        let mut m = f64::INFINITY;
        for k in 0..7 {
            let d2 = self.seg_min_d2(&Seg::new(&points[k], &points[k + 1], scale));
            if d2 < m {
                m = d2;
            }
        }
        m.sqrt()
    }

    /// Capsules model: smallest gap between the 7 link capsules and the obstacle cubes, mm
    /// (0 on contact or overlap); `INFINITY` without obstacles.
    pub fn capsules_gap_mm(&self, points: &ArmPoints, link_radius_mm: f64) -> f64 {
        let half = 0.5 * self.cell_mm;
        let half_diag = half * 3f64.sqrt();
        let r = link_radius_mm;
        let mut best = f64::INFINITY;
        for k in 0..7 {
            let (a, b) = (&points[k], &points[k + 1]);
            for i in 0..self.count {
                let c = self.centre_cells(i) * self.cell_mm;
                let dc = segment_point_distance(a, b, &c);
                let lower = (dc - half_diag - r).max(0.0);
                if lower >= best {
                    continue;
                }
                let gap = capsule_cube_gap_mm(a, b, r, &c, half);
                if gap < best {
                    best = gap;
                }
            }
        }
        best
    }

    /// Clearance of one pose, cells.
    ///
    /// Centres model: smallest distance from any obstacle centre to any of the 7 polyline
    /// segments (eq. 11). Capsules model: smallest gap between link capsules and obstacle
    /// cubes (0 on contact). `INFINITY` without obstacles.
    pub fn clearance_cells(&self, points: &ArmPoints) -> f64 {
        match self.model {
            ClearanceModel::Centres => self.centres_clearance_cells(points),
            ClearanceModel::Capsules { link_radius_mm, .. } => {
                self.capsules_gap_mm(points, link_radius_mm) / self.cell_mm
            }
        }
    }

    /// Whether one pose is clear; stops at the first violation.
    ///
    /// Centres model: clearance > `arm_safe_distance` (strict). Capsules model:
    /// `gap * cell_mm > margin_mm` (strict).
    pub fn pose_is_clear(&self, points: &ArmPoints) -> bool {
        match self.model {
            ClearanceModel::Centres => {
                let scale = 1.0 / self.cell_mm;
                let t = self.arm_safe_distance_cells;
                let t2 = t * t;
                (0..7).all(|k| self.seg_min_d2(&Seg::new(&points[k], &points[k + 1], scale)) > t2)
            }
            ClearanceModel::Capsules {
                link_radius_mm,
                margin_mm,
            } => {
                let half = 0.5 * self.cell_mm;
                let half_diag = half * 3f64.sqrt();
                let r = link_radius_mm;
                for k in 0..7 {
                    let (a, b) = (&points[k], &points[k + 1]);
                    for i in 0..self.count {
                        let c = self.centre_cells(i) * self.cell_mm;
                        let dc = segment_point_distance(a, b, &c);
                        if (dc - half_diag - r).max(0.0) > margin_mm {
                            continue;
                        }
                        if (dc - half - r).max(0.0) <= margin_mm {
                            return false;
                        }
                        if capsule_cube_gap_mm(a, b, r, &c, half) <= margin_mm {
                            return false;
                        }
                    }
                }
                true
            }
        }
    }

    /// Whether the joint-space move `from` -> `to` (radians) is clear: the pose
    /// `interpolate(from, to, k / steps)` is clear for every `k = 1..=steps`
    /// (`steps = 0` is read as 1). The end pose is checked first (cheap rejection).
    pub fn motion_is_clear(&self, arm: &Arm, from: &Joints, to: &Joints, steps: u32) -> bool {
        let steps = steps.max(1);
        if !self.pose_is_clear(&arm.points_mm(&interpolate(from, to, 1.0))) {
            return false;
        }
        self.motion_is_clear_before_end(arm, from, to, steps)
    }

    /// Steps `k = 1..steps` (end excluded) of [`Clearance::motion_is_clear`].
    pub(crate) fn motion_is_clear_before_end(
        &self,
        arm: &Arm,
        from: &Joints,
        to: &Joints,
        steps: u32,
    ) -> bool {
        let n = steps.max(1);
        (1..n).all(|k| {
            let q = interpolate(from, to, k as f64 / n as f64);
            self.pose_is_clear(&arm.points_mm(&q))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_cube_distance_cases() {
        // Segment parallel to the +x face, 2 mm outside it.
        let a = Vector3::new(7.0, -20.0, 0.0);
        let b = Vector3::new(7.0, 20.0, 3.0);
        assert!((segment_cube_distance_mm(&a, &b, 5.0) - 2.0).abs() < 1e-9);
        // A point off a corner.
        let p = Vector3::new(8.0, 9.0, 5.0);
        let want = (9.0f64 + 16.0).sqrt();
        assert!((segment_cube_distance_mm(&p, &p, 5.0) - want).abs() < 1e-9);
        // Through the cube.
        let a = Vector3::new(-10.0, 0.0, 0.0);
        let b = Vector3::new(10.0, 1.0, 0.0);
        assert_eq!(segment_cube_distance_mm(&a, &b, 5.0), 0.0);
    }
}
