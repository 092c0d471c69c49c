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
//! Boxes in mm (`obstacle_boxes_mm`, [`ObstacleBox`]): under the centres model a `centre`
//! box counts as its centre point (eq. 11, as the paper's cubes) and a `surface` box by the
//! exact distance from each segment to the box (parry), both against `arm_safe_distance`;
//! under the capsules model every box by its exact gap to the capsules. Set them with
//! [`Clearance::with_boxes`] ([`Clearance::from_scenario`] does).
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
use crate::scenario::{Cell, ClearanceModel, DistanceTo, ObstacleBox, Scenario};

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

/// One segment prepared for the eq. 11 loop, in cells.
#[derive(Clone, Copy)]
struct Seg {
    a: [f64; 3],
    d: [f64; 3],
    /// `1 / |d|²`, or 0 for a zero-length segment (then `w = 0`: the distance to `a`).
    inv_dd: f64,
}

impl Seg {
    /// Segment `k` (0..7) of the polyline, or `None` if it has zero length: its point is an
    /// end of a neighbouring segment (the polyline is connected). `k = 7` stands for "every
    /// segment has zero length" and is asked for only when no segment was used: then the
    /// single point, once.
    #[inline(always)]
    fn pick(points: &ArmPoints, k: usize, scale: f64, used: bool) -> Option<Seg> {
        if k == 7 {
            return (!used).then(|| Seg::new(&points[0], &points[0], scale));
        }
        let s = Seg::new(&points[k], &points[k + 1], scale);
        (s.inv_dd > 0.0).then_some(s)
    }

    #[inline(always)]
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
/// point.
fn segment_cube_distance_mm(a: &Vector3<f64>, b: &Vector3<f64>, half_mm: f64) -> f64 {
    segment_box_distance_mm(a, b, [half_mm; 3])
}

/// Exact distance (mm) from segment `a`-`b` (mm, relative to the box's centre) to an
/// axis-aligned box of half-extents `half_mm` at the origin. This is the only parry call of
/// the crate.
fn segment_box_distance_mm(a: &Vector3<f64>, b: &Vector3<f64>, half_mm: [f64; 3]) -> f64 {
    use parry3d_f64::math::Pose;
    use parry3d_f64::query;
    let cube = Cuboid::new(parry3d_f64::math::Vector::new(
        half_mm[0], half_mm[1], half_mm[2],
    ));
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

/// Exact distance (mm) from segment `a`-`b` to the axis-aligned box `[lo, hi]` (all mm, in
/// one frame; `lo <= hi` per axis), in closed form: the closed-form counterpart of the
/// crate's parry query, for the joint env's steps (docs/JOINT.md, "Speed"). A zero-length
/// segment is a point; 0 when the segment touches or crosses the box.
///
/// With `p(t) = a + t (b - a)`, `t` in [0, 1], the squared distance
/// `f(t) = Σ_i (p_i(t) - clamp(p_i(t), lo_i, hi_i))²` is convex and continuously
/// differentiable, quadratic between the at most six `t` where `p(t)` crosses a face plane.
/// Its minimum on [0, 1] is at 0 if `f'(0) >= 0`, at 1 if `f'(1) <= 0`, else at the root of
/// `f'` (monotone, piecewise linear), found in the interval between consecutive crossings
/// where `f'` changes sign, where it is linear. The distance is then `|p(t*) - clamp(p(t*))|`.
///
/// ```
/// use sixaxis_core::clearance::segment_aabb_distance_mm;
/// let (lo, hi) = ([-5.0; 3], [5.0; 3]);
/// // Parallel to the +x face, 2 mm outside it.
/// let d = segment_aabb_distance_mm(&[7.0, -20.0, 0.0], &[7.0, 20.0, 3.0], &lo, &hi);
/// assert!((d - 2.0).abs() < 1e-12);
/// // Through the box.
/// assert_eq!(segment_aabb_distance_mm(&[-10.0, 0.0, 0.0], &[10.0, 1.0, 0.0], &lo, &hi), 0.0);
/// // Past an edge: the closest point of the segment is interior to it.
/// let d = segment_aabb_distance_mm(&[6.0, 9.0, 0.0], &[9.0, 6.0, 0.0], &lo, &hi);
/// assert!((d - (2.5f64 * 2.5 * 2.0).sqrt()).abs() < 1e-12);
/// ```
#[inline]
pub fn segment_aabb_distance_mm(a: &[f64; 3], b: &[f64; 3], lo: &[f64; 3], hi: &[f64; 3]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let at = |t: f64| -> [f64; 3] { std::array::from_fn(|i| a[i] + t * d[i]) };
    // f'(t) / 2.
    let slope = |t: f64| -> f64 {
        let p = at(t);
        (0..3)
            .map(|i| (p[i] - p[i].clamp(lo[i], hi[i])) * d[i])
            .sum()
    };
    let dist = |t: f64| -> f64 {
        let p = at(t);
        let e: [f64; 3] = std::array::from_fn(|i| p[i] - p[i].clamp(lo[i], hi[i]));
        (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt()
    };
    if slope(0.0) >= 0.0 {
        return dist(0.0);
    }
    if slope(1.0) <= 0.0 {
        return dist(1.0);
    }
    // The face-plane crossings inside (0, 1), sorted, then 1.
    let mut ts = [1.0f64; 7];
    let mut m = 0;
    for i in 0..3 {
        if d[i] != 0.0 {
            for c in [lo[i], hi[i]] {
                let t = (c - a[i]) / d[i];
                if t > 0.0 && t < 1.0 {
                    ts[m] = t;
                    m += 1;
                }
            }
        }
    }
    let ts = &mut ts[..=m];
    for j in 1..m {
        let mut k = j;
        while k > 0 && ts[k - 1] > ts[k] {
            ts.swap(k - 1, k);
            k -= 1;
        }
    }
    // f' < 0 at `t0`; the first crossing with f' >= 0 closes the interval holding the root
    // (the last entry, 1, has f'(1) > 0).
    let mut t0 = 0.0;
    for &t1 in ts.iter() {
        if t1 > t0 && slope(t1) >= 0.0 {
            // On (t0, t1) each axis is below, inside or above its slab throughout: read it at
            // the middle; f'/2 = Σ_active (a_i + t d_i - c_i) d_i there, a linear function.
            let p = at(0.5 * (t0 + t1));
            let (mut num, mut den) = (0.0, 0.0);
            for i in 0..3 {
                let c = if p[i] < lo[i] {
                    lo[i]
                } else if p[i] > hi[i] {
                    hi[i]
                } else {
                    continue;
                };
                num += (c - a[i]) * d[i];
                den += d[i] * d[i];
            }
            let t = if den > 0.0 {
                (num / den).clamp(t0, t1)
            } else {
                t0
            };
            return dist(t);
        }
        t0 = t0.max(t1);
    }
    dist(1.0)
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

/// Eq. 11 kernel: smallest squared distance (cells²) from the obstacle centres (chunks of
/// four) to one segment. Plain Rust that LLVM vectorises: one running minimum per lane, and
/// every `if` is an element-wise select that maps to `maxpd`/`minpd` (SSE2) or their AVX
/// forms. The same code is compiled twice, for the baseline target and with AVX
/// ([`min_d2_avx`]); both give the same bits (no FMA contraction in Rust). Hand-written SSE2
/// and AVX intrinsics were measured against it and dropped
/// (docs/PERFORMANCE.md, "Eq. 11 kernels").
#[allow(clippy::needless_range_loop)] // lanes of three arrays
#[inline(always)]
fn seg_min_d2(xs: &[[f64; LANES]], ys: &[[f64; LANES]], zs: &[[f64; LANES]], s: &Seg) -> f64 {
    let mut acc = [f64::INFINITY; LANES];
    for ((x4, y4), z4) in xs.iter().zip(ys).zip(zs) {
        for l in 0..LANES {
            let px = x4[l] - s.a[0];
            let py = y4[l] - s.a[1];
            let pz = z4[l] - s.a[2];
            let dot = px * s.d[0] + py * s.d[1] + pz * s.d[2];
            let w = dot * s.inv_dd;
            let w = if w > 0.0 { w } else { 0.0 };
            let w = if w < 1.0 { w } else { 1.0 };
            let ex = px - w * s.d[0];
            let ey = py - w * s.d[1];
            let ez = pz - w * s.d[2];
            let d2 = ex * ex + ey * ey + ez * ez;
            acc[l] = if d2 < acc[l] { d2 } else { acc[l] };
        }
    }
    let lo = if acc[0] < acc[2] { acc[0] } else { acc[2] };
    let hi = if acc[1] < acc[3] { acc[1] } else { acc[3] };
    if lo < hi {
        lo
    } else {
        hi
    }
}

/// Smallest squared distance (cells²) from the obstacle centres to the polyline `points`
/// (mm, scaled to cells by `scale`); stops early once the minimum so far is `<= stop`.
#[inline(always)]
fn min_d2_segments(
    xs: &[[f64; LANES]],
    ys: &[[f64; LANES]],
    zs: &[[f64; LANES]],
    points: &ArmPoints,
    scale: f64,
    stop: f64,
) -> f64 {
    let mut m = f64::INFINITY;
    let mut used = false;
    for k in 0..8 {
        let Some(s) = Seg::pick(points, k, scale, used) else {
            continue;
        };
        used = true;
        let d2 = seg_min_d2(xs, ys, zs, &s);
        if d2 < m {
            m = d2;
            if m <= stop {
                break;
            }
        }
    }
    m
}

/// [`min_d2_segments`] compiled with AVX (four obstacles per instruction instead of two).
///
/// # Safety
/// The CPU must support AVX (checked once in [`Clearance::new`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn min_d2_avx(
    xs: &[[f64; LANES]],
    ys: &[[f64; LANES]],
    zs: &[[f64; LANES]],
    points: &ArmPoints,
    scale: f64,
    stop: f64,
) -> f64 {
    min_d2_segments(xs, ys, zs, points, scale, stop)
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

/// Whether the AVX build of the eq. 11 loop can run here.
fn cpu_has_avx() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::PAPER_BETA0_DEG;
    use std::f64::consts::PI;

    /// Eq. 11 as a plain scalar loop with one running minimum: the test's reference.
    fn reference_d2(c: &Clearance, p: &ArmPoints) -> f64 {
        let mut m = f64::INFINITY;
        for w in p.windows(2) {
            let s = Seg::new(&w[0], &w[1], 1.0 / c.cell_mm);
            for ((x4, y4), z4) in c.xs.iter().zip(&c.ys).zip(&c.zs) {
                for l in 0..LANES {
                    let (px, py, pz) = (x4[l] - s.a[0], y4[l] - s.a[1], z4[l] - s.a[2]);
                    let w = ((px * s.d[0] + py * s.d[1] + pz * s.d[2]) * s.inv_dd).clamp(0.0, 1.0);
                    let (ex, ey, ez) = (px - w * s.d[0], py - w * s.d[1], pz - w * s.d[2]);
                    m = m.min(ex * ex + ey * ey + ez * ez);
                }
            }
        }
        m
    }

    /// `pose` under the AVX build (when the CPU has AVX) and the baseline build of the eq. 11
    /// loop, and the scalar reference: the same bits.
    fn assert_builds_agree(with_avx: &Clearance, p: &ArmPoints, what: &str) {
        let mut without = with_avx.clone();
        without.avx = false;
        let a = with_avx.clearance_cells(p);
        assert_eq!(a.to_bits(), without.clearance_cells(p).to_bits(), "{what}");
        if with_avx.boxes.is_empty() {
            assert_eq!(
                reference_d2(with_avx, p).sqrt().to_bits(),
                a.to_bits(),
                "{what}"
            );
        }
        assert_eq!(
            with_avx.pose_is_clear(p),
            without.pose_is_clear(p),
            "{what}"
        );
    }

    #[test]
    fn kernels_agree_bit_for_bit() {
        let s = Scenario::builtin("paper_simple").unwrap();
        let arm = s.arm();
        let with_avx = Clearance::from_scenario(&s);
        assert_eq!(with_avx.avx, cpu_has_avx());
        let b0 = PAPER_BETA0_DEG.map(f64::to_radians);
        for k in 0..300 {
            let mut q = b0;
            for (i, x) in q.iter_mut().enumerate() {
                *x += ((k * 7 + i * 5) % 29) as f64 * 0.2 - 2.8;
            }
            assert_builds_agree(&with_avx, &arm.points_mm(&q), &format!("pose {k}"));
        }
        // A polyline collapsed to one point.
        let p = [Vector3::new(0.0, 100.0, 200.0); 8];
        assert!((with_avx.clearance_cells(&p) - 1.0).abs() < 1e-12);
        assert_builds_agree(&with_avx, &p, "one point");
    }

    /// Random worlds (0..=41 obstacle cells, so every padding of the last chunk, and some
    /// `centre` boxes) and random poses. The same test compared this loop with the
    /// hand-written AVX and SSE2 kernels it replaced, bit for bit, before they were removed.
    #[test]
    fn kernels_agree_bit_for_bit_on_random_inputs() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let arm = Scenario::builtin("paper_simple").unwrap().arm();
        let mut clear = 0;
        for world in 0..60 {
            let cells: Vec<Cell> = (0..world % 42)
                .map(|_| std::array::from_fn(|_| rng.random_range(-8..=8)))
                .collect();
            let boxes: Vec<ObstacleBox> = (0..world % 3)
                .map(|_| {
                    let lo: [f64; 3] = std::array::from_fn(|_| rng.random_range(-800.0..700.0));
                    ObstacleBox {
                        min_mm: lo,
                        max_mm: lo.map(|v| v + rng.random_range(1.0..200.0)),
                        distance_to: DistanceTo::Centre,
                    }
                })
                .collect();
            let cell_mm = rng.random_range(20.0..150.0);
            let c =
                Clearance::new(&cells, cell_mm, ClearanceModel::Centres, 0.76).with_boxes(&boxes);
            for k in 0..50 {
                let q: Joints = std::array::from_fn(|_| rng.random_range(-PI..PI));
                let p = arm.points_mm(&q);
                clear += usize::from(c.pose_is_clear(&p));
                assert_builds_agree(&c, &p, &format!("world {world}, pose {k}"));
            }
        }
        // Both answers occur, so the early exit of `pose_is_clear` is exercised too.
        assert!(clear > 100 && clear < 2900, "{clear} of 3000 poses clear");
    }

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

    /// parry's exact distance (the crate's general query) for the box `[lo, hi]`.
    fn parry_segment_aabb(a: &[f64; 3], b: &[f64; 3], lo: &[f64; 3], hi: &[f64; 3]) -> f64 {
        let c: [f64; 3] = std::array::from_fn(|i| 0.5 * (lo[i] + hi[i]));
        let h: [f64; 3] = std::array::from_fn(|i| 0.5 * (hi[i] - lo[i]));
        let c = Vector3::from(c);
        segment_box_distance_mm(&(Vector3::from(*a) - c), &(Vector3::from(*b) - c), h)
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(4000))]
        /// The closed form equals parry's GJK within 1e-9 mm on random segments and boxes
        /// (mm scale of the arm: coordinates within ±1000 mm, boxes 1..300 mm), including
        /// points, segments through the box and segments on an axis.
        #[test]
        fn segment_aabb_distance_equals_parry(
            a in proptest::array::uniform3(-1000.0f64..1000.0),
            dir in proptest::array::uniform3(-600.0f64..600.0),
            lo in proptest::array::uniform3(-400.0f64..400.0),
            size in proptest::array::uniform3(1.0f64..300.0),
            kind in 0u8..4,
        ) {
            let b: [f64; 3] = match kind {
                0 => a,                                        // a point
                1 => [a[0] + dir[0], a[1], a[2]],              // along an axis
                _ => std::array::from_fn(|i| a[i] + dir[i]),
            };
            let hi: [f64; 3] = std::array::from_fn(|i| lo[i] + size[i]);
            let fast = segment_aabb_distance_mm(&a, &b, &lo, &hi);
            let want = parry_segment_aabb(&a, &b, &lo, &hi);
            proptest::prop_assert!((fast - want).abs() <= 1e-9, "{fast} vs parry {want}");
            let rev = segment_aabb_distance_mm(&b, &a, &lo, &hi);
            proptest::prop_assert!((rev - want).abs() <= 1e-9, "reversed {rev} vs {want}");
        }

        /// Segments that pass near the box (through a random point at most 30 mm from it):
        /// the cases where the closest point lies inside the segment, near faces and edges.
        #[test]
        fn segment_aabb_distance_equals_parry_near_the_box(
            lo in proptest::array::uniform3(-400.0f64..400.0),
            size in proptest::array::uniform3(1.0f64..300.0),
            u in proptest::array::uniform3(-0.1f64..1.1),
            dir in proptest::array::uniform3(-1.0f64..1.0),
            s0 in -500.0f64..0.0,
            s1 in 0.0f64..500.0,
        ) {
            let hi: [f64; 3] = std::array::from_fn(|i| lo[i] + size[i]);
            let p: [f64; 3] = std::array::from_fn(|i| lo[i] + u[i] * size[i]);
            let a: [f64; 3] = std::array::from_fn(|i| p[i] + s0 * dir[i]);
            let b: [f64; 3] = std::array::from_fn(|i| p[i] + s1 * dir[i]);
            let fast = segment_aabb_distance_mm(&a, &b, &lo, &hi);
            let want = parry_segment_aabb(&a, &b, &lo, &hi);
            proptest::prop_assert!((fast - want).abs() <= 1e-9, "{fast} vs parry {want}");
        }
    }
}
