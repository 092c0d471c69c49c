//! Integration tests of forward and closed-form inverse kinematics.

use std::f64::consts::{PI, TAU};

use nalgebra::{Matrix3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sixaxis_core::kinematics::{
    orientation_grid, Arm, DhRow, Joints, TerminalPose, PAPER_BETA0_DEG, PAPER_DH,
};
use sixaxis_core::{check_closed_form_family, IkSolutions};

const POS_TOL_MM: f64 = 1e-6;
const ROT_TOL: f64 = 1e-9;

/// A second member of the family: other lengths, non-zero d_1, mixed signs of a_2/a_3,
/// non-zero offsets.
fn second_arm() -> Arm {
    Arm::new([
        DhRow::new(0.0, 0.0, 152.0, 10.0),
        DhRow::new(90.0, 0.0, 0.0, -20.0),
        DhRow::new(0.0, -425.0, 0.0, 30.0),
        DhRow::new(0.0, 392.0, 110.0, 5.0),
        DhRow::new(90.0, 0.0, 95.0, -15.0),
        DhRow::new(-90.0, 0.0, 82.0, 45.0),
    ])
}

/// A third member with d_4 = 0, so that the wrist point can sit on the joint-1 axis.
fn zero_d4_arm() -> Arm {
    Arm::new([
        DhRow::new(0.0, 0.0, 80.0, 0.0),
        DhRow::new(90.0, 0.0, 0.0, 90.0),
        DhRow::new(0.0, 250.0, 0.0, 0.0),
        DhRow::new(0.0, 200.0, 0.0, -90.0),
        DhRow::new(90.0, 0.0, 90.0, 0.0),
        DhRow::new(-90.0, 0.0, 60.0, 0.0),
    ])
}

fn offsets_rad(arm: &Arm) -> [f64; 6] {
    arm.dh_rows().map(|r| r.offset_deg.to_radians())
}

fn ang_dist(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(TAU);
    d.min(TAU - d)
}

fn same_joints(a: &Joints, b: &Joints, tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| ang_dist(*x, *y) <= tol)
}

fn random_joints(rng: &mut ChaCha8Rng) -> Joints {
    // Uniform in (-pi, pi].
    std::array::from_fn(|_| PI - rng.random::<f64>() * TAU)
}

/// Checks what every IK answer must satisfy; returns nothing, panics with context.
fn assert_valid_solutions(arm: &Arm, pose: &TerminalPose, sols: &IkSolutions, ctx: &str) {
    assert!(sols.len() <= 8, "{ctx}: {} solutions", sols.len());
    assert_eq!(sols.len(), sols.as_slice().len());
    for q in sols.iter() {
        for &v in q {
            assert!(v.is_finite(), "{ctx}: non-finite angle in {q:?}");
            assert!(v > -PI && v <= PI, "{ctx}: angle {v} not wrapped in {q:?}");
        }
        let f = arm.fk(q);
        let dp = (f.position_mm - pose.position_mm).norm();
        let dr = (f.rotation - pose.rotation).amax();
        assert!(
            dp <= POS_TOL_MM,
            "{ctx}: solution {q:?} misses position by {dp:e} mm"
        );
        assert!(
            dr <= ROT_TOL,
            "{ctx}: solution {q:?} misses rotation by {dr:e}"
        );
    }
    for (i, a) in sols.iter().enumerate() {
        for b in &sols[i + 1..] {
            assert!(
                !same_joints(a, b, 1e-9),
                "{ctx}: duplicate solutions {a:?} and {b:?}"
            );
        }
    }
}

/// Distance of the wrist point from the joint-1 axis minus |d_4| (how far the pose of `q`
/// is from the shoulder boundary), mm.
fn shoulder_margin(arm: &Arm, q: &Joints) -> f64 {
    let pose = arm.fk(q);
    let d6 = arm.dh_rows()[5].d_mm;
    let d4 = arm.dh_rows()[3].d_mm;
    let p5 = pose.position_mm - pose.rotation.column(2) * d6;
    p5.x.hypot(p5.y) - d4.abs()
}

fn round_trip(arm: &Arm, seed: u64, n: usize) {
    let off = offsets_rad(arm);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut near_singular, mut eight, mut total) = (0usize, 0usize, 0usize);
    for i in 0..n {
        let q = random_joints(&mut rng);
        let pose = arm.fk(&q);
        let sols = arm.ik(&pose);
        let ctx = format!("sample {i}, q = {q:?}");
        assert!(!sols.is_empty(), "{ctx}: no solution for a reachable pose");
        assert_valid_solutions(arm, &pose, &sols, &ctx);
        total += sols.len();
        if sols.len() == 8 {
            eight += 1;
        }
        let s5 = (q[4] + off[4]).sin().abs();
        let s3 = (q[2] + off[2]).sin().abs();
        let h = shoulder_margin(arm, &q);
        if s5 < 1e-6 || s3 < 1e-4 || h < 1e-6 {
            // Singular neighbourhood: covered by the explicit tests below.
            near_singular += 1;
            continue;
        }
        assert!(
            sols.iter().any(|s| same_joints(s, &q, 1e-6)),
            "{ctx}: the originating configuration is not among {:?}",
            sols.as_slice()
        );
    }
    // The exclusion above must stay rare, or the test would prove little.
    assert!(
        near_singular * 1000 < n,
        "{near_singular} near-singular samples"
    );
    assert!(eight * 2 > n, "only {eight} of {n} poses had 8 solutions");
    assert!(total >= n);
}

#[test]
fn fk_beta0_is_start_cell_with_identity_rotation() {
    let arm = Arm::paper();
    let pose = arm.fk(&PAPER_BETA0_DEG.map(f64::to_radians));
    let want = Vector3::new(0.0, -200.0, 400.0);
    assert!(
        (pose.position_mm - want).norm() < 0.1,
        "{:?}",
        pose.position_mm
    );
    assert!((pose.rotation - Matrix3::identity()).amax() < 1e-4);
}

#[test]
fn ik_of_beta0_pose_contains_beta0() {
    let arm = Arm::paper();
    let beta0 = PAPER_BETA0_DEG.map(f64::to_radians);
    let pose = arm.fk(&beta0);
    let sols = arm.ik(&pose);
    assert_valid_solutions(&arm, &pose, &sols, "beta0");
    assert_eq!(sols.len(), 8, "beta0 is a regular pose: 8 solutions");
    assert!(sols.iter().any(|s| same_joints(s, &beta0, 1e-9)));
    // The rounded start pose (0,-200,400) mm, identity rotation, is reachable too and
    // one of its solutions is within the rounding of beta0.
    let rounded = TerminalPose {
        position_mm: Vector3::new(0.0, -200.0, 400.0),
        rotation: Matrix3::identity(),
    };
    let sols = arm.ik(&rounded);
    assert_valid_solutions(&arm, &rounded, &sols, "rounded start");
    assert!(sols.iter().any(|s| same_joints(s, &beta0, 1e-3)));
}

#[test]
fn round_trip_paper_arm() {
    round_trip(&Arm::paper(), 2024, 20_000);
}

#[test]
fn round_trip_second_arm() {
    let arm = second_arm();
    check_closed_form_family(arm.dh_rows()).unwrap();
    round_trip(&arm, 7, 10_000);
}

#[test]
fn round_trip_zero_d4_arm() {
    round_trip(&zero_d4_arm(), 99, 10_000);
}

#[test]
fn wrist_singularity_s5_zero() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let (mut cases, mut q6_zero) = (0, 0);
    for arm in [Arm::paper(), second_arm(), zero_d4_arm()] {
        let off = offsets_rad(&arm);
        for t5 in [0.0, PI, 1e-12, PI - 1e-12] {
            let flipped = t5 > 1.0;
            for i in 0..200 {
                let mut q = random_joints(&mut rng);
                q[4] = wrap(t5 - off[4]);
                let pose = arm.fk(&q);
                let sols = arm.ik(&pose);
                let ctx = format!("t5 = {t5}, sample {i}, q = {q:?}");
                assert!(!sols.is_empty(), "{ctx}");
                assert_valid_solutions(&arm, &pose, &sols, &ctx);
                // The originating shoulder branch: wrist branches merged, q5 exact,
                // the coupled sum (t5 = 0) or difference (t5 = pi) of joints 4 and 6 kept.
                let coupled = |s: &Joints| {
                    let t234: f64 = (1..4).map(|j| s[j] + off[j]).sum();
                    let t6 = s[5] + off[5];
                    if flipped {
                        t234 - t6
                    } else {
                        t234 + t6
                    }
                };
                let same_shoulder: Vec<&Joints> = sols
                    .iter()
                    .filter(|s| ang_dist(s[0], q[0]) < 1e-6)
                    .collect();
                assert!(
                    (1..=2).contains(&same_shoulder.len()),
                    "{ctx}: {:?}",
                    sols.as_slice()
                );
                for s in same_shoulder {
                    let t5_sol = wrap(s[4] + off[4]);
                    assert!(
                        ang_dist(t5_sol, if flipped { PI } else { 0.0 }) < 1e-12,
                        "{ctx}"
                    );
                    assert!(ang_dist(coupled(s), coupled(&q)) < 1e-6, "{ctx}: {s:?}");
                    cases += 1;
                    if s[5] == 0.0 {
                        q6_zero += 1;
                    }
                }
                // One wrist branch on this shoulder: at most 2 + 4 (other shoulder).
                assert!(sols.len() <= 6, "{ctx}: {} solutions", sols.len());
            }
        }
    }
    // The canonical split q6 = 0 is the rule; the mid-reach split the exception.
    assert!(q6_zero * 10 > cases * 8, "{q6_zero} of {cases} with q6 = 0");
    assert!(
        q6_zero < cases,
        "the mid-reach fallback was never exercised"
    );
}

#[test]
fn elbow_stretched_returns_branch_once() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for arm in [Arm::paper(), second_arm(), zero_d4_arm()] {
        let off = offsets_rad(&arm);
        for i in 0..300 {
            let mut q = random_joints(&mut rng);
            q[2] = wrap(0.0 - off[2]);
            let pose = arm.fk(&q);
            let sols = arm.ik(&pose);
            let ctx = format!("stretched sample {i}, q = {q:?}");
            assert_valid_solutions(&arm, &pose, &sols, &ctx);
            assert!(sols.iter().any(|s| same_joints(s, &q, 1e-6)), "{ctx}");
            // Same shoulder and wrist branch as q: only one elbow solution left.
            let same_branch = sols
                .iter()
                .filter(|s| [0, 4, 5].iter().all(|&j| ang_dist(s[j], q[j]) < 1e-6))
                .count();
            assert_eq!(same_branch, 1, "{ctx}: {:?}", sols.as_slice());
        }
    }
}

#[test]
fn elbow_folded_onto_shoulder_takes_canonical_q2() {
    // Table 2 has |a_2| = |a_3|: folded (t3 = pi), the wrist point sits on joint 2 and any
    // q2 reaches it; the canonical choice is q2 = 0.
    let arm = Arm::paper();
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for i in 0..300 {
        let mut q = random_joints(&mut rng);
        q[2] = PI;
        let pose = arm.fk(&q);
        let sols = arm.ik(&pose);
        let ctx = format!("folded sample {i}, q = {q:?}");
        assert!(!sols.is_empty(), "{ctx}");
        assert_valid_solutions(&arm, &pose, &sols, &ctx);
        let canon = sols
            .iter()
            .find(|s| [0, 4, 5].iter().all(|&j| ang_dist(s[j], q[j]) < 1e-6))
            .unwrap_or_else(|| panic!("{ctx}: branch missing in {:?}", sols.as_slice()));
        assert_eq!(canon[1], 0.0, "{ctx}");
        assert!(ang_dist(canon[2], PI) < 1e-9, "{ctx}");
    }
}

/// Joints with the wrist point at in-plane coordinate 0 in frame 1 (`rho = 0`), from
/// effective t3 and t234: solves `a2 c2 + a3 c23 + d5 s234 = 0` for t2.
fn rho_zero_joints(arm: &Arm, q1: f64, t3: f64, t234: f64, q5: f64, q6: f64) -> Joints {
    let rows = arm.dh_rows();
    let (a2, a3, d5) = (rows[2].a_mm, rows[3].a_mm, rows[4].d_mm);
    let off = offsets_rad(arm);
    let (k1, k2) = (a2 + a3 * t3.cos(), a3 * t3.sin());
    // k1 c2 - k2 s2 = A cos(t2 + phi) = -d5 s234.
    let amp = k1.hypot(k2);
    let phi = k2.atan2(k1);
    let t2 = (-d5 * t234.sin() / amp).acos() - phi;
    let t4 = t234 - t2 - t3;
    [
        q1,
        wrap(t2 - off[1]),
        wrap(t3 - off[2]),
        wrap(t4 - off[3]),
        q5,
        q6,
    ]
}

fn wrap(a: f64) -> f64 {
    sixaxis_core::kinematics::wrap_angle(a)
}

#[test]
fn shoulder_boundary_branches_coincide() {
    // d_4 != 0: the wrist point at distance exactly |d_4| from the joint-1 axis; the two
    // shoulder branches coincide and every solution shares q1.
    for arm in [Arm::paper(), second_arm()] {
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        for i in 0..200 {
            let [q1, q5, q6]: [f64; 3] = std::array::from_fn(|_| PI - rng.random::<f64>() * TAU);
            let t3 = 0.3 + 2.0 * rng.random::<f64>();
            let t234 = 0.5 * (rng.random::<f64>() - 0.5);
            let q = rho_zero_joints(&arm, q1, t3, t234, q5, q6);
            assert!(shoulder_margin(&arm, &q).abs() < 1e-9, "construction");
            let pose = arm.fk(&q);
            let sols = arm.ik(&pose);
            let ctx = format!("shoulder sample {i}, q = {q:?}");
            assert!(!sols.is_empty(), "{ctx}");
            assert_valid_solutions(&arm, &pose, &sols, &ctx);
            assert!(sols.len() <= 4, "{ctx}: {} solutions", sols.len());
            assert!(sols.iter().all(|s| ang_dist(s[0], q1) < 1e-6), "{ctx}");
            assert!(sols.iter().any(|s| same_joints(s, &q, 1e-6)), "{ctx}");
        }
    }
}

#[test]
fn shoulder_on_axis_takes_canonical_q1() {
    // d_4 = 0: the wrist point on the joint-1 axis; any q1 works, the canonical ones are
    // 0 and pi.
    let arm = zero_d4_arm();
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    let mut with_original = 0;
    for i in 0..200 {
        let [q1, q5, q6]: [f64; 3] = std::array::from_fn(|_| PI - rng.random::<f64>() * TAU);
        let q1 = if i % 4 == 0 { 0.0 } else { q1 };
        let t3 = 0.3 + 2.0 * rng.random::<f64>();
        let t234 = 0.5 * (rng.random::<f64>() - 0.5);
        let q = rho_zero_joints(&arm, q1, t3, t234, q5, q6);
        let pose = arm.fk(&q);
        let p5 = pose.position_mm - pose.rotation.column(2) * arm.dh_rows()[5].d_mm;
        assert!(p5.x.hypot(p5.y) < 1e-9, "construction: {p5:?}");
        let sols = arm.ik(&pose);
        let ctx = format!("on-axis sample {i}, q = {q:?}");
        assert!(!sols.is_empty(), "{ctx}");
        assert_valid_solutions(&arm, &pose, &sols, &ctx);
        for s in sols.iter() {
            assert!(s[0] == 0.0 || s[0] == PI, "{ctx}: q1 = {}", s[0]);
        }
        assert!(sols.iter().any(|s| s[0] == 0.0), "{ctx}");
        assert!(sols.iter().any(|s| s[0] == PI), "{ctx}");
        if q1 == 0.0 {
            assert!(sols.iter().any(|s| same_joints(s, &q, 1e-6)), "{ctx}");
            with_original += 1;
        }
    }
    assert_eq!(with_original, 50);
}

#[test]
fn shoulder_on_axis_falls_back_when_canonical_q1_cannot_reach() {
    // Arm stretched upright with the wrist folded back up (t234 near pi): the wrist point
    // is on the axis near the top of the workspace, and with q1 = 0 or pi the wrist
    // orientation would force the elbow out of reach.
    let arm = zero_d4_arm();
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    let mut fallback = 0;
    for i in 0..300 {
        let [q1, q5, q6]: [f64; 3] = std::array::from_fn(|_| PI - rng.random::<f64>() * TAU);
        let t3 = 0.05 + 0.6 * rng.random::<f64>();
        let t234 = PI + 0.6 * (rng.random::<f64>() - 0.5);
        let q = rho_zero_joints(&arm, q1, t3, t234, q5, q6);
        let pose = arm.fk(&q);
        let sols = arm.ik(&pose);
        let ctx = format!("upright sample {i}, q = {q:?}");
        assert!(!sols.is_empty(), "{ctx}");
        assert_valid_solutions(&arm, &pose, &sols, &ctx);
        if sols.iter().all(|s| s[0] != 0.0 && s[0] != PI) {
            fallback += 1;
        } else {
            assert!(sols.iter().all(|s| s[0] == 0.0 || s[0] == PI), "{ctx}");
        }
    }
    assert!(fallback > 30, "fallback used {fallback} times");
}

#[test]
fn orientation_grid_poses_all_valid() {
    // The planner's exact 45-degree rotations hit wrist singularities (s5 = 0) often.
    let arm = Arm::paper();
    let grid = orientation_grid(8);
    let (mut solved, mut total) = (0, 0);
    for cell in [[0, -2, 4], [0, 3, 0], [2, 1, 3], [-3, 0, 1], [1, -1, -2]] {
        let position_mm = Vector3::new(cell[0] as f64, cell[1] as f64, cell[2] as f64) * 100.0;
        for o in &grid {
            let pose = TerminalPose {
                position_mm,
                rotation: o.rotation,
            };
            let sols = arm.ik(&pose);
            let ctx = format!("cell {cell:?}, rpy {:?}", o.rpy_deg);
            assert_valid_solutions(&arm, &pose, &sols, &ctx);
            if !sols.is_empty() {
                solved += 1;
            }
            total += sols.len();
        }
    }
    assert!(solved > 500, "{solved} poses solved");
    assert!(total > 4 * solved, "{total} solutions for {solved} poses");
}

#[test]
fn random_poses_give_only_valid_solutions() {
    // Arbitrary poses (most not reachable), not made by FK: whatever comes back must be
    // right, and some must come back.
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    for arm in [Arm::paper(), second_arm(), zero_d4_arm()] {
        let (mut solved, mut n_sols) = (0, 0);
        for i in 0..10_000 {
            let position_mm = Vector3::from_fn(|_, _| 1600.0 * (rng.random::<f64>() - 0.5));
            // Uniform random rotation: a unit quaternion by rejection sampling in the 4-ball.
            let quat = loop {
                let v = nalgebra::Vector4::from_fn(|_, _| 2.0 * rng.random::<f64>() - 1.0);
                if v.norm() > 1e-3 && v.norm() <= 1.0 {
                    break v.normalize();
                }
            };
            let rotation = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                quat[0], quat[1], quat[2], quat[3],
            ))
            .to_rotation_matrix()
            .into_inner();
            let pose = TerminalPose {
                position_mm,
                rotation,
            };
            let sols = arm.ik(&pose);
            assert_valid_solutions(&arm, &pose, &sols, &format!("random pose {i}"));
            if !sols.is_empty() {
                solved += 1;
                n_sols += sols.len();
            }
        }
        assert!(solved > 500, "only {solved} random poses solved");
        assert!(n_sols > 2 * solved);
    }
}

#[test]
fn nearly_orthonormal_rotation_is_accepted_far_from_one_is_not() {
    let arm = Arm::paper();
    let q = [0.3, -1.0, 1.2, 0.4, 0.9, -0.7];
    let exact = arm.fk(&q);
    let mut slightly_off = exact;
    slightly_off.rotation[(0, 1)] += 1e-8;
    let sols = arm.ik(&slightly_off);
    assert_eq!(sols.len(), 8);
    for s in sols.iter() {
        let f = arm.fk(s);
        assert!((f.position_mm - exact.position_mm).norm() < 1e-4);
        assert!((f.rotation - exact.rotation).amax() < 1e-6);
    }
    let mut far_off = exact;
    far_off.rotation[(0, 1)] += 1e-3;
    assert!(arm.ik(&far_off).is_empty());
}

#[test]
fn unreachable_and_invalid_inputs_give_no_solution() {
    let arm = Arm::paper();
    let far = TerminalPose {
        position_mm: Vector3::new(5000.0, 0.0, 0.0),
        rotation: Matrix3::identity(),
    };
    assert!(arm.ik(&far).is_empty());
    // Just beyond the arm's reach along its stretched direction.
    let near_far = TerminalPose {
        position_mm: Vector3::new(0.0, 0.0, 900.0),
        rotation: Matrix3::identity(),
    };
    assert!(arm.ik(&near_far).is_empty());
    // Wrist point inside the |d_4| = 106 mm cylinder round the joint-1 axis.
    let inside = TerminalPose {
        position_mm: Vector3::new(0.0, 0.0, 300.0),
        rotation: Matrix3::identity(),
    };
    assert!(arm.ik(&inside).is_empty());
    let reachable = arm.fk(&PAPER_BETA0_DEG.map(f64::to_radians));
    let mut bad = reachable;
    bad.position_mm.y = f64::NAN;
    assert!(arm.ik(&bad).is_empty());
    let mut bad = reachable;
    bad.rotation[(1, 2)] = f64::NAN;
    assert!(arm.ik(&bad).is_empty());
    let mut bad = reachable;
    bad.position_mm.x = f64::INFINITY;
    assert!(arm.ik(&bad).is_empty());
    let mut bad = reachable;
    bad.position_mm = Vector3::repeat(1e300);
    assert!(arm.ik(&bad).is_empty());
    // Not a rotation: scaled, or a reflection.
    let mut bad = reachable;
    bad.rotation *= 2.0;
    assert!(arm.ik(&bad).is_empty());
    let mut bad = reachable;
    bad.rotation = -bad.rotation;
    assert!(arm.ik(&bad).is_empty());
    // The unmodified pose solves.
    assert_eq!(arm.ik(&reachable).len(), 8);
}

#[test]
fn family_check_accepts_family_and_names_rejected_row() {
    assert_eq!(check_closed_form_family(&PAPER_DH), Ok(()));
    assert_eq!(check_closed_form_family(second_arm().dh_rows()), Ok(()));
    assert_eq!(check_closed_form_family(zero_d4_arm().dh_rows()), Ok(()));

    let mut rows = PAPER_DH;
    rows[1].alpha_deg = 45.0;
    let err = check_closed_form_family(&rows).unwrap_err();
    assert!(
        err.contains("row 2") && err.contains("alpha_1") && err.contains("45"),
        "{err}"
    );
    assert!(Arm::new(rows).ik(&Arm::new(rows).fk(&[0.1; 6])).is_empty());

    let mut rows = PAPER_DH;
    rows[2].a_mm = 0.0;
    let err = check_closed_form_family(&rows).unwrap_err();
    assert!(err.contains("row 3") && err.contains("a_2"), "{err}");

    let mut rows = PAPER_DH;
    rows[2].d_mm = 5.0;
    let err = check_closed_form_family(&rows).unwrap_err();
    assert!(
        err.contains("row 3") && err.contains("d_3") && err.contains('5'),
        "{err}"
    );

    let mut rows = PAPER_DH;
    rows[5].a_mm = 1.0;
    let err = check_closed_form_family(&rows).unwrap_err();
    assert!(err.contains("row 6") && err.contains("a_5"), "{err}");

    let mut rows = PAPER_DH;
    rows[0].d_mm = f64::NAN;
    let err = check_closed_form_family(&rows).unwrap_err();
    assert!(err.contains("row 1") && err.contains("d_1"), "{err}");
}

#[test]
fn ik_solutions_api() {
    let arm = Arm::paper();
    let pose = arm.fk(&[0.3, -1.0, 1.2, 0.4, 0.9, -0.7]);
    let sols = arm.ik(&pose);
    assert_eq!(sols.len(), 8);
    assert_eq!(sols.iter().count(), 8);
    assert_eq!((&sols).into_iter().count(), 8);
    // Deref to a slice.
    let first: &Joints = &sols[0];
    assert_eq!(first, &sols.as_slice()[0]);
    // Deterministic: the same pose gives the same answer.
    assert_eq!(arm.ik(&pose), sols);
    let none = IkSolutions::default();
    assert!(none.is_empty() && none.as_slice().is_empty() && none.iter().next().is_none());
}
