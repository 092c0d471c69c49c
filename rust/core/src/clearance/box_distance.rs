//! Exact distances (mm) from a segment to an axis-aligned box: parry's query, the crate's
//! only parry call, and the closed form of the joint env's steps.
//!
//! Entry points:
//! - [`segment_aabb_distance_mm`] — closed form, segment to box `[lo, hi]`, mm (public,
//!   re-exported as `clearance::segment_aabb_distance_mm`; docs/JOINT.md, "Speed").
//! - `segment_box_distance_mm` / `segment_cube_distance_mm` — parry's GJK distance, mm, from
//!   a segment relative to the box's centre to a box of given half-extents (a cube).
//! - `capsule_cube_gap_mm` — the gap (mm) between a link capsule and an obstacle cube.
//!
//! The tests check the closed form against parry within 1e-9 mm (proptests).

use nalgebra::Vector3;
use parry3d_f64::shape::{Ball, Cuboid, Segment};

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
pub(super) fn segment_box_distance_mm(
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    half_mm: [f64; 3],
) -> f64 {
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
pub(super) fn capsule_cube_gap_mm(
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    r: f64,
    c: &Vector3<f64>,
    half: f64,
) -> f64 {
    (segment_cube_distance_mm(&(a - c), &(b - c), half) - r).max(0.0)
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
