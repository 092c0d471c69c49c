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
    /// The eq. 11 kernel `min_d2` runs.
    kernel: Eq11Kernel,
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

/// Eq. 11 kernel, portable version: smallest squared distance (cells²) from the obstacle
/// centres (chunks of four) to one segment. Same operations, in the same order, as the SSE2
/// version, so both give the same bits.
#[allow(clippy::needless_range_loop)] // lanes of three arrays
#[inline(always)]
fn seg_min_d2_scalar(
    xs: &[[f64; LANES]],
    ys: &[[f64; LANES]],
    zs: &[[f64; LANES]],
    s: &Seg,
) -> f64 {
    let mut m = f64::INFINITY;
    for ((xs, ys), zs) in xs.iter().zip(ys).zip(zs) {
        for l in 0..LANES {
            let px = xs[l] - s.a[0];
            let py = ys[l] - s.a[1];
            let pz = zs[l] - s.a[2];
            let dot = px * s.d[0] + py * s.d[1] + pz * s.d[2];
            let w = dot * s.inv_dd;
            let w = if w > 0.0 { w } else { 0.0 };
            let w = if w < 1.0 { w } else { 1.0 };
            let ex = px - w * s.d[0];
            let ey = py - w * s.d[1];
            let ez = pz - w * s.d[2];
            let d2 = ex * ex + ey * ey + ez * ez;
            if d2 < m {
                m = d2;
            }
        }
    }
    m
}

/// Eq. 11 kernel with SSE2 (part of the x86_64 baseline, so no run-time detection is
/// needed): two obstacles per instruction.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn seg_min_d2_sse2(xs: &[[f64; LANES]], ys: &[[f64; LANES]], zs: &[[f64; LANES]], s: &Seg) -> f64 {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is always available on x86_64; every load reads two f64 of a [f64; 4]
    // at offset 0 or 2 (unaligned loads).
    #[allow(unused_unsafe)]
    unsafe {
        let (ax, ay, az) = (
            _mm_set1_pd(s.a[0]),
            _mm_set1_pd(s.a[1]),
            _mm_set1_pd(s.a[2]),
        );
        let (dx, dy, dz) = (
            _mm_set1_pd(s.d[0]),
            _mm_set1_pd(s.d[1]),
            _mm_set1_pd(s.d[2]),
        );
        let inv = _mm_set1_pd(s.inv_dd);
        let zero = _mm_setzero_pd();
        let one = _mm_set1_pd(1.0);
        let mut acc = _mm_set1_pd(f64::INFINITY);
        for ((x4, y4), z4) in xs.iter().zip(ys).zip(zs) {
            for half in [0usize, 2] {
                let px = _mm_sub_pd(_mm_loadu_pd(x4.as_ptr().add(half)), ax);
                let py = _mm_sub_pd(_mm_loadu_pd(y4.as_ptr().add(half)), ay);
                let pz = _mm_sub_pd(_mm_loadu_pd(z4.as_ptr().add(half)), az);
                let dot = _mm_add_pd(
                    _mm_add_pd(_mm_mul_pd(px, dx), _mm_mul_pd(py, dy)),
                    _mm_mul_pd(pz, dz),
                );
                // maxpd/minpd return the second operand on NaN, like the scalar `if`s.
                let w = _mm_min_pd(_mm_max_pd(_mm_mul_pd(dot, inv), zero), one);
                let ex = _mm_sub_pd(px, _mm_mul_pd(w, dx));
                let ey = _mm_sub_pd(py, _mm_mul_pd(w, dy));
                let ez = _mm_sub_pd(pz, _mm_mul_pd(w, dz));
                let d2 = _mm_add_pd(
                    _mm_add_pd(_mm_mul_pd(ex, ex), _mm_mul_pd(ey, ey)),
                    _mm_mul_pd(ez, ez),
                );
                acc = _mm_min_pd(d2, acc);
            }
        }
        let hi = _mm_unpackhi_pd(acc, acc);
        _mm_cvtsd_f64(_mm_min_sd(acc, hi))
    }
}

/// Eq. 11 kernel with AVX: four obstacles per instruction; the same operations in the same
/// order as the other kernels (no FMA), so the same bits.
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
    use std::arch::x86_64::*;
    let mut m = f64::INFINITY;
    let mut used = false;
    for k in 0..8 {
        let Some(s) = Seg::pick(points, k, scale, used) else {
            continue;
        };
        used = true;
        // SAFETY: AVX is enabled on this function; loads read one whole [f64; 4].
        #[allow(unused_unsafe)]
        let d2min = unsafe {
            let (ax, ay, az) = (
                _mm256_set1_pd(s.a[0]),
                _mm256_set1_pd(s.a[1]),
                _mm256_set1_pd(s.a[2]),
            );
            let (dx, dy, dz) = (
                _mm256_set1_pd(s.d[0]),
                _mm256_set1_pd(s.d[1]),
                _mm256_set1_pd(s.d[2]),
            );
            let inv = _mm256_set1_pd(s.inv_dd);
            let zero = _mm256_setzero_pd();
            let one = _mm256_set1_pd(1.0);
            let mut acc = _mm256_set1_pd(f64::INFINITY);
            for ((x4, y4), z4) in xs.iter().zip(ys).zip(zs) {
                let px = _mm256_sub_pd(_mm256_loadu_pd(x4.as_ptr()), ax);
                let py = _mm256_sub_pd(_mm256_loadu_pd(y4.as_ptr()), ay);
                let pz = _mm256_sub_pd(_mm256_loadu_pd(z4.as_ptr()), az);
                let dot = _mm256_add_pd(
                    _mm256_add_pd(_mm256_mul_pd(px, dx), _mm256_mul_pd(py, dy)),
                    _mm256_mul_pd(pz, dz),
                );
                let w = _mm256_min_pd(_mm256_max_pd(_mm256_mul_pd(dot, inv), zero), one);
                let ex = _mm256_sub_pd(px, _mm256_mul_pd(w, dx));
                let ey = _mm256_sub_pd(py, _mm256_mul_pd(w, dy));
                let ez = _mm256_sub_pd(pz, _mm256_mul_pd(w, dz));
                let d2 = _mm256_add_pd(
                    _mm256_add_pd(_mm256_mul_pd(ex, ex), _mm256_mul_pd(ey, ey)),
                    _mm256_mul_pd(ez, ez),
                );
                acc = _mm256_min_pd(d2, acc);
            }
            let lo = _mm256_castpd256_pd128(acc);
            let hi = _mm256_extractf128_pd(acc, 1);
            let two = _mm_min_pd(lo, hi);
            _mm_cvtsd_f64(_mm_min_sd(two, _mm_unpackhi_pd(two, two)))
        };
        if d2min < m {
            m = d2min;
            if m <= stop {
                break;
            }
        }
    }
    m
}

/// The eq. 11 kernels under comparison (docs/PERFORMANCE.md, "Eq. 11 kernels").
#[doc(hidden)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Eq11Kernel {
    /// Hand-written AVX intrinsics (run-time detected).
    Avx,
    /// Hand-written SSE2 intrinsics.
    Sse2,
    /// Plain loop with one running minimum.
    Scalar,
    /// Plain loop with one running minimum per lane (auto-vectorised, baseline target).
    Lanes,
    /// The same plain loop compiled with AVX enabled (run-time detected).
    LanesAvx,
    /// The `wide` crate's `f64x4`.
    Wide,
}

/// Eq. 11 kernel, plain loop with a running minimum per lane: the element-wise `if`s are
/// `maxpd`/`minpd`, so LLVM vectorises it and it gives the same bits as the other kernels.
#[allow(clippy::needless_range_loop)] // lanes of three arrays
#[inline(always)]
fn seg_min_d2_lanes(xs: &[[f64; LANES]], ys: &[[f64; LANES]], zs: &[[f64; LANES]], s: &Seg) -> f64 {
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

/// Eq. 11 kernel with the `wide` crate (SSE2 pairs unless the build enables AVX).
#[inline(always)]
fn seg_min_d2_wide(xs: &[[f64; LANES]], ys: &[[f64; LANES]], zs: &[[f64; LANES]], s: &Seg) -> f64 {
    use wide::f64x4;
    let (ax, ay, az) = (
        f64x4::splat(s.a[0]),
        f64x4::splat(s.a[1]),
        f64x4::splat(s.a[2]),
    );
    let (dx, dy, dz) = (
        f64x4::splat(s.d[0]),
        f64x4::splat(s.d[1]),
        f64x4::splat(s.d[2]),
    );
    let inv = f64x4::splat(s.inv_dd);
    let zero = f64x4::splat(0.0);
    let one = f64x4::splat(1.0);
    let mut acc = f64x4::splat(f64::INFINITY);
    for ((x4, y4), z4) in xs.iter().zip(ys).zip(zs) {
        let px = f64x4::new(*x4) - ax;
        let py = f64x4::new(*y4) - ay;
        let pz = f64x4::new(*z4) - az;
        let dot = px * dx + py * dy + pz * dz;
        let w = (dot * inv).fast_max(zero).fast_min(one);
        let ex = px - w * dx;
        let ey = py - w * dy;
        let ez = pz - w * dz;
        let d2 = ex * ex + ey * ey + ez * ez;
        acc = d2.fast_min(acc);
    }
    let a = acc.to_array();
    let lo = if a[0] < a[2] { a[0] } else { a[2] };
    let hi = if a[1] < a[3] { a[1] } else { a[3] };
    if lo < hi {
        lo
    } else {
        hi
    }
}

/// The segment loop of `min_d2` around one per-segment kernel.
#[inline(always)]
fn min_d2_segments(points: &ArmPoints, scale: f64, stop: f64, kernel: impl Fn(&Seg) -> f64) -> f64 {
    let mut m = f64::INFINITY;
    let mut used = false;
    for k in 0..8 {
        let Some(s) = Seg::pick(points, k, scale, used) else {
            continue;
        };
        used = true;
        let d2 = kernel(&s);
        if d2 < m {
            m = d2;
            if m <= stop {
                break;
            }
        }
    }
    m
}

/// [`seg_min_d2_lanes`] compiled with AVX.
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn min_d2_lanes_avx(
    xs: &[[f64; LANES]],
    ys: &[[f64; LANES]],
    zs: &[[f64; LANES]],
    points: &ArmPoints,
    scale: f64,
    stop: f64,
) -> f64 {
    min_d2_segments(points, scale, stop, |s| seg_min_d2_lanes(xs, ys, zs, s))
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

/// Whether the 4-wide AVX kernel can run here.
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
            kernel: if cpu_has_avx() {
                Eq11Kernel::Avx
            } else {
                Eq11Kernel::Sse2
            },
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
        match self.kernel {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `Avx` is chosen only when the CPU supports AVX.
            Eq11Kernel::Avx => unsafe { min_d2_avx(xs, ys, zs, points, scale, stop) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above.
            Eq11Kernel::LanesAvx => unsafe { min_d2_lanes_avx(xs, ys, zs, points, scale, stop) },
            #[cfg(target_arch = "x86_64")]
            Eq11Kernel::Sse2 => {
                min_d2_segments(points, scale, stop, |s| seg_min_d2_sse2(xs, ys, zs, s))
            }
            Eq11Kernel::Scalar => {
                min_d2_segments(points, scale, stop, |s| seg_min_d2_scalar(xs, ys, zs, s))
            }
            Eq11Kernel::Lanes => {
                min_d2_segments(points, scale, stop, |s| seg_min_d2_lanes(xs, ys, zs, s))
            }
            Eq11Kernel::Wide => {
                min_d2_segments(points, scale, stop, |s| seg_min_d2_wide(xs, ys, zs, s))
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => min_d2_segments(points, scale, stop, |s| seg_min_d2_scalar(xs, ys, zs, s)),
        }
    }

    /// The same clearance with another eq. 11 kernel (A/B measurement only).
    ///
    /// # Panics
    /// If the kernel needs AVX and the CPU has none.
    #[doc(hidden)]
    pub fn with_eq11_kernel(mut self, kernel: Eq11Kernel) -> Clearance {
        if matches!(kernel, Eq11Kernel::Avx | Eq11Kernel::LanesAvx) {
            assert!(cpu_has_avx(), "kernel {kernel:?} needs AVX");
        }
        self.kernel = kernel;
        self
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

    /// The AVX, SSE2 and portable kernels give the same bits.
    #[test]
    fn kernels_agree_bit_for_bit() {
        let s = Scenario::builtin("paper_simple").unwrap();
        let arm = s.arm();
        let with_avx = Clearance::from_scenario(&s);
        let mut without = with_avx.clone();
        without.kernel = Eq11Kernel::Sse2;
        let b0 = PAPER_BETA0_DEG.map(f64::to_radians);
        for k in 0..300 {
            let mut q = b0;
            for (i, x) in q.iter_mut().enumerate() {
                *x += ((k * 7 + i * 5) % 29) as f64 * 0.2 - 2.8;
            }
            let p = arm.points_mm(&q);
            let a = with_avx.clearance_cells(&p);
            let b = without.clearance_cells(&p);
            assert_eq!(a.to_bits(), b.to_bits(), "pose {k}");
            let mut m = f64::INFINITY;
            for w in p.windows(2) {
                let seg = Seg::new(&w[0], &w[1], 0.01);
                m = m.min(seg_min_d2_scalar(
                    &with_avx.xs,
                    &with_avx.ys,
                    &with_avx.zs,
                    &seg,
                ));
            }
            assert_eq!(m.sqrt().to_bits(), a.to_bits(), "pose {k}");
            assert_eq!(with_avx.pose_is_clear(&p), without.pose_is_clear(&p));
        }
        // A polyline collapsed to one point.
        let p = [Vector3::new(0.0, 100.0, 200.0); 8];
        assert!((with_avx.clearance_cells(&p) - 1.0).abs() < 1e-12);
        assert_eq!(with_avx.clearance_cells(&p), without.clearance_cells(&p));
    }

    /// Random worlds (0..=41 obstacle cells, some `centre` boxes) and random poses: every
    /// eq. 11 kernel gives the bits of the hand-written AVX (or SSE2) kernel.
    #[test]
    fn kernels_agree_bit_for_bit_on_random_inputs() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let arm = Scenario::builtin("paper_simple").unwrap().arm();
        let reference = if cpu_has_avx() {
            Eq11Kernel::Avx
        } else {
            Eq11Kernel::Sse2
        };
        let mut kernels = vec![
            Eq11Kernel::Sse2,
            Eq11Kernel::Scalar,
            Eq11Kernel::Lanes,
            Eq11Kernel::Wide,
        ];
        if cpu_has_avx() {
            kernels.push(Eq11Kernel::LanesAvx);
        }
        let (mut compared, mut clear) = (0, 0);
        for world in 0..60 {
            let n = world % 42;
            let cells: Vec<Cell> = (0..n)
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
            let base = Clearance::new(&cells, cell_mm, ClearanceModel::Centres, 0.76)
                .with_boxes(&boxes)
                .with_eq11_kernel(reference);
            for _ in 0..50 {
                let q: Joints = std::array::from_fn(|_| rng.random_range(-PI..PI));
                let p = arm.points_mm(&q);
                let want = base.clearance_cells(&p);
                clear += usize::from(base.pose_is_clear(&p));
                for &k in &kernels {
                    let c = base.clone().with_eq11_kernel(k);
                    assert_eq!(c.clearance_cells(&p).to_bits(), want.to_bits(), "{k:?}");
                    assert_eq!(c.pose_is_clear(&p), base.pose_is_clear(&p), "{k:?}");
                    compared += 1;
                }
            }
        }
        assert!(compared >= 60 * 50 * 4);
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
}
