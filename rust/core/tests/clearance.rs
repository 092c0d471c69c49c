//! Clearance checks: eq. 11 (centres model), the exact capsules model, interpolation and
//! joint-space motion checks.

use nalgebra::Vector3;
use proptest::prelude::*;
use sixaxis_core::clearance::{interpolate, segment_point_distance, Clearance};
use sixaxis_core::kinematics::{wrap_angle, Arm, ArmPoints, PAPER_BETA0_DEG};
use sixaxis_core::scenario::{Cell, ClearanceModel, Scenario};
use std::f64::consts::PI;

fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
    Vector3::new(x, y, z)
}

fn beta0() -> [f64; 6] {
    PAPER_BETA0_DEG.map(f64::to_radians)
}

/// Naive eq. 11 over every segment and obstacle, cells.
fn naive_centres(points: &ArmPoints, obstacles: &[Cell], cell_mm: f64) -> f64 {
    let mut m = f64::INFINITY;
    for w in points.windows(2) {
        for c in obstacles {
            let o = v(c[0] as f64, c[1] as f64, c[2] as f64) * cell_mm;
            m = m.min(segment_point_distance(&w[0], &w[1], &o) / cell_mm);
        }
    }
    m
}

// ------------------------------------------- docs/SCENARIOS.md "Units and the arm"

#[test]
fn beta0_clearance_is_one_cell_with_table_1_obstacles() {
    let s = Scenario::builtin("paper_simple").unwrap();
    let mut obstacles = s.obstacles.clone();
    obstacles.push([0, 3, 0]); // Table 1 lists it too (it is the target)
    let points = s.arm().points_mm(&beta0());
    for d_p in [0.76, 0.85] {
        let c = Clearance::new(&obstacles, s.cell_mm, ClearanceModel::Centres, d_p);
        let got = c.clearance_cells(&points);
        assert!((got - 1.0).abs() < 1e-3, "clearance at beta0 = {got}");
        assert!((got - naive_centres(&points, &obstacles, s.cell_mm)).abs() < 1e-12);
        assert!(
            c.pose_is_clear(&points),
            "start pose must be valid for d_p = {d_p}"
        );
    }
    // The scenario's own obstacles (without the target) give the same figure.
    for name in ["paper_simple", "paper_complex"] {
        let s = Scenario::builtin(name).unwrap();
        let c = Clearance::from_scenario(&s);
        assert!((c.clearance_cells(&points) - 1.0).abs() < 1e-3);
        assert!(c.pose_is_clear(&points));
    }
}

// ---------------------------------------------------------------- eq. 11

#[test]
fn segment_point_distance_branches() {
    let a = v(1.0, 1.0, 1.0);
    let b = v(5.0, 1.0, 1.0);
    // w <= 0: before a -> |KO|.
    assert!((segment_point_distance(&a, &b, &v(-2.0, 5.0, 1.0)) - 5.0).abs() < 1e-12);
    // w == 0 exactly: perpendicular through a.
    assert!((segment_point_distance(&a, &b, &v(1.0, 4.0, 5.0)) - 5.0).abs() < 1e-12);
    // 0 < w < 1: foot J inside -> |JO|.
    assert!((segment_point_distance(&a, &b, &v(3.0, 4.0, 5.0)) - 5.0).abs() < 1e-12);
    // w >= 1: beyond b -> |LO|.
    assert!((segment_point_distance(&a, &b, &v(8.0, 5.0, 1.0)) - 5.0).abs() < 1e-12);
    // On the segment.
    assert_eq!(segment_point_distance(&a, &b, &v(2.5, 1.0, 1.0)), 0.0);
    // Symmetric in a and b.
    let p = v(7.0, -3.0, 2.0);
    assert_eq!(
        segment_point_distance(&a, &b, &p),
        segment_point_distance(&b, &a, &p)
    );
    // Degenerate segment: a point.
    assert!((segment_point_distance(&a, &a, &v(4.0, 5.0, 1.0)) - 5.0).abs() < 1e-12);
}

proptest! {
    #[test]
    fn segment_point_distance_is_the_minimum_over_the_segment(
        a in prop::array::uniform3(-5.0f64..5.0),
        b in prop::array::uniform3(-5.0f64..5.0),
        p in prop::array::uniform3(-5.0f64..5.0),
    ) {
        let (a, b, p) = (Vector3::from(a), Vector3::from(b), Vector3::from(p));
        let d = segment_point_distance(&a, &b, &p);
        // Dense sampling never beats it, and gets close to it.
        let mut best = f64::INFINITY;
        for i in 0..=2000 {
            let t = i as f64 / 2000.0;
            best = best.min((a + (b - a) * t - p).norm());
        }
        prop_assert!(d <= best + 1e-12);
        prop_assert!(best - d <= (b - a).norm() / 2000.0 + 1e-12);
    }
}

// ---------------------------------------------------------------- interpolation

#[test]
fn interpolate_endpoints_are_exact() {
    let from = [0.1, -2.0, 3.0, -3.1, 0.0, PI];
    let to = [-0.4, 2.5, -3.0, 3.1, 1.0, -1.0];
    assert_eq!(interpolate(&from, &to, 0.0), from);
    assert_eq!(interpolate(&from, &to, 1.0), to);
    // Out-of-range fractions are clamped.
    assert_eq!(interpolate(&from, &to, -1.0), from);
    assert_eq!(interpolate(&from, &to, 2.0), to);
}

#[test]
fn interpolate_takes_the_shortest_way_across_the_seam() {
    let from = [
        170f64.to_radians(),
        -170f64.to_radians(),
        0.0,
        0.0,
        0.0,
        0.0,
    ];
    let to = [
        -170f64.to_radians(),
        170f64.to_radians(),
        0.0,
        0.0,
        0.0,
        0.0,
    ];
    let mid = interpolate(&from, &to, 0.5);
    assert!((mid[0] - PI).abs() < 1e-12, "{}", mid[0]);
    assert!((mid[1].abs() - PI).abs() < 1e-12, "{}", mid[1]);
    let q = interpolate(&from, &to, 0.25);
    assert!((q[0] - 175f64.to_radians()).abs() < 1e-12);
    assert!((q[1] + 175f64.to_radians()).abs() < 1e-12);
    // Every intermediate step moves at most 20/50 degrees from the previous one.
    let mut prev = from;
    for k in 1..=50 {
        let q = interpolate(&from, &to, k as f64 / 50.0);
        for (x, p) in q.iter().zip(&prev) {
            assert!(*x > -PI && *x <= PI);
            assert!(wrap_angle(x - p).abs() <= 0.4f64.to_radians() + 1e-12);
        }
        prev = q;
    }
    // Ordinary case: plain linear.
    let q = interpolate(&[0.0; 6], &[1.0, -1.0, 2.0, 0.0, 0.0, 0.0], 0.5);
    assert_eq!(q, [0.5, -0.5, 1.0, 0.0, 0.0, 0.0]);
}

// ---------------------------------------------------------------- motion

#[test]
fn motion_is_clear_matches_stepwise_checks_and_catches_a_midway_collision() {
    let arm = Arm::paper();
    let b0 = beta0();
    let mut from = b0;
    let mut to = b0;
    from[0] -= PI / 2.0;
    to[0] += PI / 2.0;
    // Halfway the arm is back at beta0, with its terminal on the start cell (0,-2,4).
    let obstacles = vec![[0, -2, 4]];
    let c = Clearance::new(&obstacles, 100.0, ClearanceModel::Centres, 0.76);
    assert!(c.pose_is_clear(&arm.points_mm(&from)));
    assert!(c.pose_is_clear(&arm.points_mm(&to)));
    assert!(!c.pose_is_clear(&arm.points_mm(&interpolate(&from, &to, 0.5))));
    assert!(!c.motion_is_clear(&arm, &from, &to, 50));
    // With an odd step count the exact midpoint is skipped but its neighbours still collide.
    assert!(!c.motion_is_clear(&arm, &from, &to, 51));
    // No obstacles: always clear.
    let free = Clearance::new(&[], 100.0, ClearanceModel::Centres, 0.76);
    assert!(free.motion_is_clear(&arm, &from, &to, 50));
    assert_eq!(free.clearance_cells(&arm.points_mm(&from)), f64::INFINITY);
    // Agrees with a hand loop on the paper's scene.
    let s = Scenario::builtin("paper_simple").unwrap();
    let c = Clearance::from_scenario(&s);
    for delta in [-1.0, -0.3, 0.2, 0.7, 1.5] {
        let mut to = b0;
        to[1] += delta;
        to[2] -= delta / 2.0;
        let manual = (1..=50)
            .all(|k| c.pose_is_clear(&arm.points_mm(&interpolate(&b0, &to, k as f64 / 50.0))));
        assert_eq!(
            c.motion_is_clear(&arm, &b0, &to, 50),
            manual,
            "delta {delta}"
        );
    }
}

#[test]
fn pose_is_clear_agrees_with_clearance_cells() {
    let s = Scenario::builtin("paper_simple").unwrap();
    let arm = s.arm();
    let b0 = beta0();
    for d_p in [0.5, 0.76, 0.85, 0.96, 1.2] {
        let c = Clearance::new(&s.obstacles, s.cell_mm, ClearanceModel::Centres, d_p);
        for k in 0..200 {
            let mut q = b0;
            for (i, x) in q.iter_mut().enumerate() {
                *x += ((k * 7 + i * 13) % 23) as f64 * 0.13 - 1.4;
            }
            let p = arm.points_mm(&q);
            assert_eq!(c.pose_is_clear(&p), c.clearance_cells(&p) > d_p);
        }
    }
}

// ---------------------------------------------------------------- capsules

/// Polyline with one real link a-b; the other six are zero-length at `a` (balls).
fn one_link(a: Vector3<f64>, b: Vector3<f64>) -> ArmPoints {
    [a, a, a, a, a, a, a, b]
}

fn capsules(obstacles: &[Cell], r: f64, margin: f64) -> Clearance {
    Clearance::new(
        obstacles,
        100.0,
        ClearanceModel::Capsules {
            link_radius_mm: r,
            margin_mm: margin,
        },
        0.76,
    )
}

#[test]
fn capsules_hand_cases() {
    let c = capsules(&[[0, 0, 0]], 10.0, 15.0);
    // Capsule parallel to the +x face (x = 50), axis at x = 80: gap 80 - 50 - 10 = 20 mm.
    let p = one_link(v(80.0, -200.0, 0.0), v(80.0, 200.0, 30.0));
    assert!(
        (c.clearance_cells(&p) - 0.2).abs() < 1e-9,
        "{}",
        c.clearance_cells(&p)
    );
    assert!(c.pose_is_clear(&p)); // 20 mm > 15 mm
                                  // Parallel to the edge x = y = 50: distance sqrt(2) * 30 - 10.
    let p = one_link(v(80.0, 80.0, -300.0), v(80.0, 80.0, 300.0));
    let want = (2f64.sqrt() * 30.0 - 10.0) / 100.0;
    assert!((c.clearance_cells(&p) - want).abs() < 1e-9);
    // A ball (all points equal) off the corner (50,50,50): |(30,40,0)| - 10 = 40 mm.
    let q = v(80.0, 90.0, 50.0);
    let p = [q; 8];
    assert!((c.clearance_cells(&p) - 0.4).abs() < 1e-9);
    // A capsule that passes 12 mm above the top face: gap 2 mm, not clear with 15 mm margin.
    let p = one_link(v(-300.0, 10.0, 62.0), v(300.0, -10.0, 62.0));
    assert!((c.clearance_cells(&p) - 0.02).abs() < 1e-9);
    assert!(!c.pose_is_clear(&p));
    // Through the cube: 0.
    let p = one_link(v(-300.0, 0.0, 0.0), v(300.0, 0.0, 0.0));
    assert_eq!(c.clearance_cells(&p), 0.0);
    assert!(!c.pose_is_clear(&p));
    // The end point of a segment is the nearest feature (w >= 1 case).
    let p = one_link(v(400.0, 0.0, 0.0), v(150.0, 0.0, 0.0));
    assert!((c.clearance_cells(&p) - 0.9).abs() < 1e-9);
    // Nearest of two obstacles, with a zero radius and zero margin.
    let c = capsules(&[[0, 0, 0], [3, 0, 0]], 0.0, 0.0);
    let p = one_link(v(200.0, -100.0, 0.0), v(200.0, 100.0, 0.0));
    assert!((c.clearance_cells(&p) - 0.5).abs() < 1e-9);
    assert!(c.pose_is_clear(&p));
}

/// Exact point-to-cube distance (cube of half-extent `h` at `c`).
fn point_cube(p: &Vector3<f64>, c: &Vector3<f64>, h: f64) -> f64 {
    let d = (p - c).map(|x| (x.abs() - h).max(0.0));
    d.norm()
}

/// Independent segment-to-cube distance: the distance to a convex set is convex along the
/// segment, so a ternary search finds its minimum.
fn segment_cube_ternary(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>, h: f64) -> f64 {
    let f = |t: f64| point_cube(&(a + (b - a) * t), c, h);
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..200 {
        let m1 = lo + (hi - lo) / 3.0;
        let m2 = hi - (hi - lo) / 3.0;
        if f(m1) <= f(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    f(0.5 * (lo + hi)).min(f(0.0)).min(f(1.0))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    #[test]
    fn capsules_match_an_independent_search_and_stay_within_centre_bounds(
        a in prop::array::uniform3(-400.0f64..400.0),
        b in prop::array::uniform3(-400.0f64..400.0),
        cell in prop::array::uniform3(-2i32..=2),
        r in 0.0f64..60.0,
    ) {
        let (a, b) = (Vector3::from(a), Vector3::from(b));
        let c = capsules(&[cell], r, 0.0);
        let gap_mm = c.clearance_cells(&one_link(a, b)) * 100.0;
        let centre = v(cell[0] as f64, cell[1] as f64, cell[2] as f64) * 100.0;
        // Exactness: the link is a capsule, the obstacle a 100 mm cube. The six zero-length
        // links sit at `a`, inside the capsule, so they never change the answer.
        let want = (segment_cube_ternary(&a, &b, &centre, 50.0) - r).max(0.0);
        prop_assert!((gap_mm - want).abs() < 1e-6, "gap {} want {}", gap_mm, want);
        // Geometric sanity: the cube lies between its inscribed ball (radius 50 mm) and its
        // circumscribed ball (radius 50 sqrt 3 mm), so the capsule gap is bounded by the
        // centre distance of eq. 11.
        let dc = segment_point_distance(&a, &b, &centre);
        prop_assert!(gap_mm <= (dc - 50.0 - r).max(0.0) + 1e-9);
        prop_assert!(gap_mm >= (dc - 50.0 * 3f64.sqrt() - r).max(0.0) - 1e-9);
    }
}

#[test]
fn capsules_on_the_paper_scene_agree_with_naive_search_and_bounds() {
    let s = Scenario::builtin("paper_simple").unwrap();
    let arm = s.arm();
    let r = 30.0;
    let c = Clearance::new(
        &s.obstacles,
        s.cell_mm,
        ClearanceModel::Capsules {
            link_radius_mm: r,
            margin_mm: 10.0,
        },
        s.arm_safe_distance,
    );
    let centres = Clearance::from_scenario(&s);
    let b0 = beta0();
    for k in 0..100 {
        let mut q = b0;
        for (i, x) in q.iter_mut().enumerate() {
            *x += ((k * 5 + i * 11) % 19) as f64 * 0.17 - 1.5;
        }
        let p = arm.points_mm(&q);
        let gap = c.clearance_cells(&p);
        let mut want = f64::INFINITY;
        for w in p.windows(2) {
            for o in &s.obstacles {
                let centre = v(o[0] as f64, o[1] as f64, o[2] as f64) * 100.0;
                want = want.min((segment_cube_ternary(&w[0], &w[1], &centre, 50.0) - r).max(0.0));
            }
        }
        assert!(
            (gap * 100.0 - want).abs() < 1e-6,
            "pose {k}: {gap} vs {}",
            want / 100.0
        );
        let dc = centres.clearance_cells(&p);
        assert!(gap <= (dc - 0.5 - r / 100.0).max(0.0) + 1e-12);
        assert!(gap >= (dc - 0.5 * 3f64.sqrt() - r / 100.0).max(0.0) - 1e-12);
        assert_eq!(c.pose_is_clear(&p), gap * 100.0 > 10.0, "pose {k}");
    }
}

#[test]
fn non_finite_poses_are_never_clear() {
    let s = Scenario::builtin("paper_simple").unwrap();
    let arm = s.arm();
    let mut p = arm.points_mm(&beta0());
    p[5].y = f64::NAN;
    for model in [
        ClearanceModel::Centres,
        ClearanceModel::Capsules {
            link_radius_mm: 10.0,
            margin_mm: 0.0,
        },
    ] {
        let c = Clearance::new(&s.obstacles, s.cell_mm, model, s.arm_safe_distance);
        assert!(c.clearance_cells(&p).is_nan());
        assert!(!c.pose_is_clear(&p));
        let mut q = p;
        q[7].z = f64::INFINITY;
        assert!(!c.pose_is_clear(&q));
        let bad = [f64::NAN; 6];
        assert!(!c.motion_is_clear(&arm, &beta0(), &bad, 10));
    }
}
