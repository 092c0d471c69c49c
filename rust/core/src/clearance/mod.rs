//! Whole-arm clearance: how far the arm's body stays from the obstacles (paper, section III.C).
//!
//! Entry points:
//! - [`Clearance::from_scenario`] / [`Clearance::new`] — precompute the obstacle centres once.
//! - [`Clearance::clearance_cells`] — the smallest distance of one pose, in cells.
//! - [`Clearance::pose_is_clear`] — the same test with an early exit at the first violation.
//! - [`Clearance::motion_is_clear`] — a joint-space move, checked at every interpolation step.
//! - [`interpolate`] — joint-space interpolation along each joint's shortest angular difference.
//! - [`segment_point_distance`] — eq. 11 for one segment and one point.
//! - [`segment_aabb_distance_mm`] — the exact distance (mm) from a segment to a box, in closed
//!   form (the joint env's steps).
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
//! Boxes in mm (`obstacle_boxes_mm`, [`ObstacleBox`]): under the centres model a `centre`
//! box counts as its centre point (eq. 11, as the paper's cubes) and a `surface` box by the
//! exact distance from each segment to the box (parry), both against `arm_safe_distance`;
//! under the capsules model every box by its exact gap to the capsules. Set them with
//! [`Clearance::with_boxes`] ([`Clearance::from_scenario`] does).
//!
//! Parts: the [`Clearance`] type, interpolation and eq. 11 for one point here; the eq. 11
//! loop over all centres (built for the baseline target and for AVX) in `clearance/kernel.rs`;
//! the exact segment-to-box distances (parry's and the closed form) in
//! `clearance/box_distance.rs`, re-exported.
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

mod box_distance;
mod kernel;

use nalgebra::Vector3;

pub use box_distance::segment_aabb_distance_mm;
use box_distance::{capsule_cube_gap_mm, segment_box_distance_mm};
#[cfg(target_arch = "x86_64")]
use kernel::min_d2_avx;
use kernel::{cpu_has_avx, min_d2_segments, FAR, LANES};

use crate::kinematics::{wrap_angle, Arm, ArmPoints, Joints};
use crate::scenario::{Cell, ClearanceModel, DistanceTo, ObstacleBox, Scenario};

/// Whole-arm clearance against a fixed set of obstacles.
///
/// Obstacle centres are stored once, in cells, as structure-of-arrays padded to a multiple of
/// four (padding lies at `1e100` cells and never matters), so that the eq. 11 loop vectorises.
#[derive(Debug, Clone)]
pub struct Clearance {
    /// Obstacle centre x, cells, in chunks of four (padded).
    xs: Vec<[f64; LANES]>,
    /// Obstacle centre y, cells, in chunks of four (padded).
    ys: Vec<[f64; LANES]>,
    /// Obstacle centre z, cells, in chunks of four (padded).
    zs: Vec<[f64; LANES]>,
    /// Number of real obstacles.
    count: usize,
    /// Edge of a cell, mm.
    cell_mm: f64,
    /// The model in use.
    model: ClearanceModel,
    /// d_p, cells (centres model).
    arm_safe_distance_cells: f64,
    /// Whether the CPU has AVX (x86_64): runs the AVX build of the eq. 11 loop.
    avx: bool,
    /// Obstacle boxes in mm (the centres of `centre` boxes are also in `xs`/`ys`/`zs`,
    /// after the `count` cubes).
    boxes: Vec<ObstacleBox>,
    /// Number of centre points in `xs`/`ys`/`zs` (cubes, then `centre` boxes).
    centre_count: usize,
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
    std::array::from_fn(|i| {
        if f == 1.0 {
            wrap_exact(to[i])
        } else {
            wrap_exact(from[i] + wrap_exact(to[i] - from[i]) * f)
        }
    })
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

/// The links of the capsules model: the polyline's segments, zero-length ones left out (such
/// a ball lies inside its neighbour's capsule, the polyline being connected) unless all are.
fn capsule_links(points: &ArmPoints) -> impl Iterator<Item = (&Vector3<f64>, &Vector3<f64>)> {
    let all_zero = points.windows(2).all(|w| w[0] == w[1]);
    (0..7)
        .map(move |k| (&points[k], &points[k + 1]))
        .filter(move |(a, b)| a != b || (all_zero && std::ptr::eq(*a, &points[0])))
}

/// Whether every coordinate of the polyline is finite (a NaN pose is never clear).
#[inline]
fn all_finite(points: &ArmPoints) -> bool {
    points.iter().all(|p| p.iter().all(|x| x.is_finite()))
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
        let chunks = count.div_ceil(LANES);
        let mut xs = vec![[FAR; LANES]; chunks];
        let mut ys = vec![[FAR; LANES]; chunks];
        let mut zs = vec![[FAR; LANES]; chunks];
        for (i, c) in obstacles.iter().enumerate() {
            xs[i / LANES][i % LANES] = c[0] as f64;
            ys[i / LANES][i % LANES] = c[1] as f64;
            zs[i / LANES][i % LANES] = c[2] as f64;
        }
        Clearance {
            xs,
            ys,
            zs,
            count,
            cell_mm,
            model,
            arm_safe_distance_cells,
            avx: cpu_has_avx(),
            boxes: Vec::new(),
            centre_count: count,
        }
    }

    /// The same clearance with obstacle boxes in mm added (see the module docs for how each
    /// model measures them). The centres of `centre` boxes join the eq. 11 centre points.
    pub fn with_boxes(mut self, boxes: &[ObstacleBox]) -> Clearance {
        let centres: Vec<[f64; 3]> = boxes
            .iter()
            .filter(|b| b.distance_to == DistanceTo::Centre)
            .map(|b| b.centre_mm().map(|v| v / self.cell_mm))
            .collect();
        let total = self.centre_count + centres.len();
        let chunks = total.div_ceil(LANES);
        for arr in [&mut self.xs, &mut self.ys, &mut self.zs] {
            arr.resize(chunks, [FAR; LANES]);
        }
        for (k, c) in centres.iter().enumerate() {
            let i = self.centre_count + k;
            self.xs[i / LANES][i % LANES] = c[0];
            self.ys[i / LANES][i % LANES] = c[1];
            self.zs[i / LANES][i % LANES] = c[2];
        }
        self.centre_count = total;
        self.boxes.extend_from_slice(boxes);
        self
    }

    /// Smallest exact distance (mm) from the polyline to the `surface` boxes (centres
    /// model), or to every box (`all`, capsules model, before subtracting the radius).
    fn boxes_distance_mm(&self, points: &ArmPoints, all: bool, stop: f64) -> f64 {
        let mut best = f64::INFINITY;
        for b in &self.boxes {
            if !all && b.distance_to == DistanceTo::Centre {
                continue;
            }
            let c = Vector3::from(b.centre_mm());
            let h = b.half_extents_mm();
            for (p, q) in capsule_links(points) {
                let d = segment_box_distance_mm(&(p - c), &(q - c), h);
                if d < best {
                    best = d;
                    if best <= stop {
                        return best;
                    }
                }
            }
        }
        best
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
        .with_boxes(&s.obstacle_boxes_mm)
    }

    /// Number of obstacles.
    pub fn obstacle_count(&self) -> usize {
        self.count + self.boxes.len()
    }

    /// Obstacle centre `i`, cells.
    fn centre_cells(&self, i: usize) -> Vector3<f64> {
        let (j, l) = (i / LANES, i % LANES);
        Vector3::new(self.xs[j][l], self.ys[j][l], self.zs[j][l])
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

    /// Smallest squared distance (cells²) from any obstacle centre to any segment of the
    /// polyline `points` (mm); stops early (with some value `<= stop`) once the minimum so
    /// far is `<= stop`. Zero-length segments are skipped (see `Seg::pick`).
    #[inline]
    fn min_d2(&self, points: &ArmPoints, stop: f64) -> f64 {
        if !all_finite(points) {
            return f64::NAN;
        }
        let scale = 1.0 / self.cell_mm;
        let (xs, ys, zs) = (&self.xs[..], &self.ys[..], &self.zs[..]);
        #[cfg(target_arch = "x86_64")]
        if self.avx {
            // SAFETY: `avx` is true only when the CPU supports AVX.
            return unsafe { min_d2_avx(xs, ys, zs, points, scale, stop) };
        }
        min_d2_segments(xs, ys, zs, points, scale, stop)
    }

    /// Centres model (eq. 11): smallest distance from any obstacle centre to any of the 7
    /// polyline segments, in cells; `INFINITY` without obstacles. `surface` boxes count by
    /// their exact distance.
    pub fn centres_clearance_cells(&self, points: &ArmPoints) -> f64 {
        let d = self.min_d2(points, -1.0).sqrt();
        if self.boxes.is_empty() || d.is_nan() {
            return d;
        }
        d.min(self.boxes_distance_mm(points, false, -1.0) / self.cell_mm)
    }

    /// Capsules model: smallest gap between the 7 link capsules and the obstacle cubes, mm
    /// (0 on contact or overlap); `INFINITY` without obstacles.
    pub fn capsules_gap_mm(&self, points: &ArmPoints, link_radius_mm: f64) -> f64 {
        if !all_finite(points) {
            return f64::NAN;
        }
        let half = 0.5 * self.cell_mm;
        let half_diag = half * 3f64.sqrt();
        let r = link_radius_mm;
        let mut best = f64::INFINITY;
        for (a, b) in capsule_links(points) {
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
        if !self.boxes.is_empty() {
            best = best.min((self.boxes_distance_mm(points, true, -1.0) - r).max(0.0));
        }
        best
    }

    /// Clearance of one pose, cells.
    ///
    /// Centres model: smallest distance from any obstacle centre to any of the 7 polyline
    /// segments (eq. 11). Capsules model: smallest gap between link capsules and obstacle
    /// cubes (0 on contact). `INFINITY` without obstacles, NaN if a point is not finite.
    pub fn clearance_cells(&self, points: &ArmPoints) -> f64 {
        match self.model {
            ClearanceModel::Centres => self.centres_clearance_cells(points),
            ClearanceModel::Capsules { link_radius_mm, .. } => {
                self.capsules_gap_mm(points, link_radius_mm) / self.cell_mm
            }
        }
    }

    /// Whether one pose is clear; stops at the first violation. A pose with a non-finite
    /// point is never clear.
    ///
    /// Centres model: clearance > `arm_safe_distance` (strict). Capsules model:
    /// `gap * cell_mm > margin_mm` (strict).
    pub fn pose_is_clear(&self, points: &ArmPoints) -> bool {
        match self.model {
            ClearanceModel::Centres => {
                let t = self.arm_safe_distance_cells;
                let t2 = t * t;
                self.min_d2(points, t2) > t2
                    && (self.boxes.is_empty()
                        || self.boxes_distance_mm(points, false, t * self.cell_mm)
                            > t * self.cell_mm)
            }
            ClearanceModel::Capsules {
                link_radius_mm,
                margin_mm,
            } => {
                if !all_finite(points) {
                    return false;
                }
                let half = 0.5 * self.cell_mm;
                let half_diag = half * 3f64.sqrt();
                let r = link_radius_mm;
                for (a, b) in capsule_links(points) {
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
                self.boxes.is_empty()
                    || self.boxes_distance_mm(points, true, margin_mm + r) - r > margin_mm
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
