//! The eq. 11 kernel of the centres model: the smallest squared distance (cells²) from the
//! obstacle centres to the arm's polyline, in one plain loop that LLVM vectorises.
//!
//! Entry points (for [`Clearance`](super::Clearance)):
//! - `min_d2_segments` — the smallest squared distance (cells²) from the centres to the
//!   polyline (mm, scaled to cells), with an early exit; `min_d2_avx` is the same code
//!   compiled with AVX, chosen at run time by `cpu_has_avx`.
//! - `LANES` / `FAR` — the structure-of-arrays layout of the centres (chunks of four,
//!   padding at `1e100` cells).
//!
//! Why one loop built twice and not hand-written SIMD: docs/PERFORMANCE.md, "Eq. 11 kernels".
//! The tests here hold both builds and a scalar reference to the same bits.

use nalgebra::Vector3;

use crate::kinematics::ArmPoints;

/// Lanes of the obstacle loop; the centre arrays are padded to a multiple of this.
pub(super) const LANES: usize = 4;
/// Coordinate of padding obstacles, cells: far from everything, and its square is finite.
pub(super) const FAR: f64 = 1.0e100;
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
pub(super) fn min_d2_segments(
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
/// The CPU must support AVX (checked once in [`Clearance::new`](super::Clearance::new)).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
pub(super) unsafe fn min_d2_avx(
    xs: &[[f64; LANES]],
    ys: &[[f64; LANES]],
    zs: &[[f64; LANES]],
    points: &ArmPoints,
    scale: f64,
    stop: f64,
) -> f64 {
    min_d2_segments(xs, ys, zs, points, scale, stop)
}

/// Whether the AVX build of the eq. 11 loop can run here.
pub(super) fn cpu_has_avx() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clearance::Clearance;
    use crate::kinematics::{Joints, PAPER_BETA0_DEG};
    use crate::scenario::{Cell, ClearanceModel, DistanceTo, ObstacleBox, Scenario};
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
}
