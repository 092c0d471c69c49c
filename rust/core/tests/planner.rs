//! Pose planning (Algorithm 1): every plan is re-checked here without the planner, with a
//! naive eq. 11 loop built on `segment_point_distance`.

use sixaxis_core::clearance::interpolate;
use sixaxis_core::kinematics::{orientation_grid, rotation_from_rpy_deg, Joints, TerminalPose};
use sixaxis_core::planner::{joint_distance, PosePlan, PosePlanner};
use sixaxis_core::scenario::{Cell, ClearanceModel, Scenario};

mod common;
use common::{centre, check_poses, free_cells, naive_clearance};

fn complete(plan: PosePlan) -> Vec<sixaxis_core::planner::PosePoint> {
    match plan {
        PosePlan::Complete(p) => p,
        PosePlan::Blocked { index, cell, .. } => panic!("blocked at {index}: {cell:?}"),
    }
}

/// Straight paths of free cells near the start of paper_simple.
const PATHS: [&[Cell]; 3] = [
    &[[0, -2, 4], [0, -2, 3], [0, -2, 2], [0, -2, 1]],
    &[[0, -2, 4], [0, -1, 4], [0, 0, 4], [0, 1, 4], [0, 2, 4]],
    &[[0, -2, 4], [1, -2, 4], [2, -2, 4], [2, -1, 4], [2, 0, 4]],
];

#[test]
fn complete_plans_pass_independent_checks() {
    for name in ["paper_simple", "paper_complex"] {
        let s = Scenario::builtin(name).unwrap();
        let planner = PosePlanner::from_scenario(&s);
        for path in PATHS {
            let poses = complete(planner.plan_poses(path, &s.arm.beta0_rad()));
            assert_eq!(poses.len(), path.len());
            check_poses(&s, path, &poses);
        }
    }
}

/// A shortest route from the start to the target of the paper's scenes, down the free column
/// (0, 2, z) and in from the side.
const TO_TARGET: &[Cell] = &[
    [0, -2, 4],
    [0, -1, 4],
    [0, 0, 4],
    [0, 1, 4],
    [0, 2, 4],
    [0, 2, 3],
    [0, 2, 2],
    [0, 2, 1],
    [0, 2, 0],
    [0, 3, 0],
];

#[test]
fn route_to_the_target_of_the_paper_scenes() {
    for name in ["paper_simple", "paper_complex"] {
        let s = Scenario::builtin(name).unwrap();
        let plan = PosePlanner::from_scenario(&s).plan_poses(TO_TARGET, &s.arm.beta0_rad());
        let n = plan.poses().len();
        check_poses(&s, &TO_TARGET[..n], plan.poses());
        match &plan {
            PosePlan::Complete(_) => println!("{name}: route to the target complete"),
            PosePlan::Blocked { index, cell, .. } => {
                println!("{name}: route to the target blocked at {index} {cell:?}")
            }
        }
        // With d_p = 0.76 the paper's experiment finishes along this route. (With 0.85 it
        // is blocked at [0, 2, 0] today, a cell that has clear static poses: no clear move
        // reaches one from the pose chosen at [0, 2, 1].)
        if name == "paper_simple" {
            assert!(plan.is_complete());
        }
    }
}

#[test]
fn first_passing_candidate_is_taken() {
    // Re-derive the first step of a plan by hand: orientations in the planner's order, IK
    // solutions by joint distance, the first whose whole move passes the naive check.
    let s = Scenario::builtin("paper_simple").unwrap();
    let planner = PosePlanner::from_scenario(&s);
    let arm = s.arm();
    let b0 = s.arm.beta0_rad();
    let next = [0, -2, 3];
    let poses = complete(planner.plan_poses(&[s.start, next], &b0));
    // beta0's orientation is the identity: grid orientation 0 is tried first.
    assert_eq!(planner.nearest_orientation(&arm.fk(&b0).rotation), 0);
    let steps = s.planning.interpolation_steps;
    let mut found: Option<(Joints, [f64; 3])> = None;
    'outer: for o in planner.orientation_order(0) {
        let orient = planner.orientations()[o];
        let sols = arm.ik(&TerminalPose {
            position_mm: centre(next, s.cell_mm),
            rotation: orient.rotation,
        });
        let mut sorted: Vec<Joints> = sols.to_vec();
        sorted.sort_by(|a, b| joint_distance(&b0, a).total_cmp(&joint_distance(&b0, b)));
        for q in sorted {
            let ok = (1..=steps).all(|k| {
                let p = arm.points_mm(&interpolate(&b0, &q, k as f64 / steps as f64));
                naive_clearance(&p, &s.obstacles, s.cell_mm) > s.arm_safe_distance
            });
            if ok {
                found = Some((q, orient.rpy_deg));
                break 'outer;
            }
        }
    }
    let (q, rpy) = found.expect("some candidate passes");
    assert_eq!(poses[1].joints_rad, q);
    assert_eq!(poses[1].orientation_rpy_deg, rpy);
}

#[test]
fn unreachable_cells_block_the_plan() {
    let s = Scenario::builtin("paper_simple").unwrap();
    let planner = PosePlanner::from_scenario(&s);
    let b0 = s.arm.beta0_rad();
    // Farther than the arm's reach (2 m above the base): no IK solution at all.
    assert!(planner.best_clearance_at([0, 0, 20]).is_none());
    assert!(!planner.cell_reachable([0, 0, 20]));
    let path = [s.start, [0, -2, 3], [0, 0, 20], [0, -2, 2]];
    let plan = planner.plan_poses(&path, &b0);
    assert!(!plan.is_complete());
    let PosePlan::Blocked {
        reached,
        index,
        cell,
    } = plan.clone()
    else {
        unreachable!()
    };
    assert_eq!((index, cell), (2, [0, 0, 20]));
    assert_eq!(reached.len(), 2);
    assert_eq!(
        reached,
        complete(planner.plan_poses(&path[..2], &b0)),
        "the poses before the block are those of the shorter path"
    );
    assert_eq!(plan.poses(), &reached[..]);
    // Blocked right after the start.
    match planner.plan_poses(&[s.start, [9, 9, 9]], &b0) {
        PosePlan::Blocked {
            reached,
            index,
            cell,
        } => {
            assert_eq!((reached.len(), index, cell), (1, 1, [9, 9, 9]));
        }
        other => panic!("{other:?}"),
    }
    // A reachable-by-IK cell where no pose is clear also blocks (cell_reachable is then false
    // and no move can end there).
    let trapped = free_cells(&s)
        .into_iter()
        .find(|&c| planner.best_clearance_at(c).is_some() && !planner.cell_reachable(c))
        .expect("paper_simple has cells that IK reaches but no clear pose does");
    let best = planner.best_clearance_at(trapped).unwrap().0;
    assert!(best <= s.arm_safe_distance, "{trapped:?}: best {best}");
    match planner.plan_poses(&[s.start, trapped], &b0) {
        PosePlan::Blocked { index, cell, .. } => assert_eq!((index, cell), (1, trapped)),
        other => panic!("{trapped:?}: {other:?}"),
    }
    // Empty path.
    assert_eq!(planner.plan_poses(&[], &b0), PosePlan::Complete(vec![]));
}

#[test]
fn plans_are_deterministic_and_serialise() {
    let s = Scenario::builtin("paper_complex").unwrap();
    let planner = PosePlanner::from_scenario(&s);
    let b0 = s.arm.beta0_rad();
    let a = planner.plan_poses(PATHS[1], &b0);
    let b = PosePlanner::from_scenario(&s).plan_poses(PATHS[1], &b0);
    assert_eq!(a, b);
    let json = serde_json::to_string(&a).unwrap();
    assert!(json.starts_with("{\"Complete\":[{\"cell\":[0,-2,4],\"joints_rad\":["));
}

#[test]
fn joint_limits_are_respected() {
    let mut s = Scenario::builtin("paper_simple").unwrap();
    // beta0 = (58.0, -10.1, -132.9, 53.1, 90.0, 32.0) degrees lies inside.
    s.arm.joint_limits_deg = Some([
        [0.0, 150.0],
        [-120.0, 60.0],
        [-170.0, 0.0],
        [-180.0, 180.0],
        [0.0, 180.0],
        [-90.0, 90.0],
    ]);
    s.validate().unwrap();
    let planner = PosePlanner::from_scenario(&s);
    for path in PATHS {
        let plan = planner.plan_poses(path, &s.arm.beta0_rad());
        // Limits may block a path; what was planned must respect them at every step.
        let n = plan.poses().len();
        check_poses(&s, &path[..n], plan.poses());
    }
    assert!(planner
        .plan_poses(PATHS[0], &s.arm.beta0_rad())
        .is_complete());
}

#[test]
fn capsules_model_plans_pass_the_capsule_check() {
    let mut s = Scenario::builtin("paper_simple").unwrap();
    s.planning.clearance_model = ClearanceModel::Capsules {
        link_radius_mm: 20.0,
        margin_mm: 5.0,
    };
    let planner = PosePlanner::from_scenario(&s);
    let poses = complete(planner.plan_poses(PATHS[0], &s.arm.beta0_rad()));
    check_poses(&s, PATHS[0], &poses);
}

#[test]
fn best_clearance_at_target_matches_brute_force() {
    // docs/SCENARIOS.md "Interpretations taken" states 0.87 cell at (0,3,0) with Table 1's
    // obstacles; the test asserts what a brute force over the same grid finds, and prints
    // the figure.
    let s = Scenario::builtin("paper_simple").unwrap();
    let planner = PosePlanner::from_scenario(&s);
    let arm = s.arm();
    let target = centre(s.target, s.cell_mm);
    let mut brute = f64::NEG_INFINITY;
    let mut count = 0;
    for o in orientation_grid(8) {
        for q in arm
            .ik(&TerminalPose {
                position_mm: target,
                rotation: o.rotation,
            })
            .iter()
        {
            let fk = arm.fk(q);
            assert!((fk.position_mm - target).norm() < 1e-6);
            assert!((fk.rotation - o.rotation).amax() < 1e-9);
            brute = brute.max(naive_clearance(&arm.points_mm(q), &s.obstacles, s.cell_mm));
            count += 1;
        }
    }
    let (best, q, rpy) = planner.best_clearance_at(s.target).unwrap();
    println!("best clearance at the target (0,3,0): {best:.6} cell over {count} poses, rpy {rpy:?}, q {q:?}");
    assert!((best - brute).abs() < 1e-9, "{best} vs {brute}");
    let fk = arm.fk(&q);
    assert!((fk.position_mm - target).norm() < 1e-6);
    assert!((fk.rotation - rotation_from_rpy_deg(rpy)).amax() < 1e-9);
    // Consistency with the two thresholds.
    for name in ["paper_simple", "paper_complex"] {
        let s = Scenario::builtin(name).unwrap();
        let p = PosePlanner::from_scenario(&s);
        assert_eq!(
            p.cell_reachable(s.target),
            best > s.arm_safe_distance,
            "{name}"
        );
    }
}

/// The paper's "change n_d": pass k uses n_d = 8·2^k, capped, and every grid contains the
/// rotations of the one before.
#[test]
fn nd_rule_doubles_on_each_replan_and_grids_nest() {
    let s = Scenario::builtin("paper_complex").unwrap();
    assert_eq!(s.planning.orientation_divisions, 8);
    let cap = s.planning.orientation_divisions_max;
    for k in 0..6u32 {
        let want = (8u32 << k).min(cap);
        assert_eq!(
            s.planning.orientation_divisions_for_round(k),
            want,
            "pass {k}"
        );
        if want <= 32 {
            let p = PosePlanner::for_round(&s, k);
            assert_eq!(p.orientation_divisions(), want);
            assert_eq!(p.orientations().len(), orientation_grid(want).len());
        }
    }
    assert_eq!(s.planning.orientation_divisions_for_round(10), cap);
    for (coarse, fine) in [(8, 16), (16, 32)] {
        let fine_grid = orientation_grid(fine);
        for o in orientation_grid(coarse) {
            assert!(
                fine_grid
                    .iter()
                    .any(|f| (f.rotation - o.rotation).amax() < 1e-9),
                "n_d {fine} lacks {:?} of n_d {coarse}",
                o.rpy_deg
            );
        }
    }
    // n_d fixed: every pass uses the first grid.
    let mut fixed = s.clone();
    fixed.planning.orientation_divisions_growth = 1;
    assert_eq!(fixed.planning.orientation_divisions_for_round(3), 8);
}

/// Both clearance figures of a motion agree with a naive recomputation over every step.
#[test]
fn motion_clearance_figures_match_naive_loops() {
    let s = Scenario::builtin("paper_simple").unwrap();
    let planner = PosePlanner::from_scenario(&s);
    let poses: Vec<Joints> = complete(planner.plan_poses(PATHS[1], &s.arm.beta0_rad()))
        .iter()
        .map(|p| p.joints_rad)
        .collect();
    let m = planner.motion_clearance(&poses).unwrap();
    let arm = s.arm();
    let t = s.planning.interpolation_steps;
    let (mut centre_min, mut cube_min) = (f64::INFINITY, f64::INFINITY);
    for w in poses.windows(2) {
        for k in 0..=t {
            let pts = arm.points_mm(&interpolate(&w[0], &w[1], k as f64 / t as f64));
            centre_min = centre_min.min(naive_clearance(&pts, &s.obstacles, s.cell_mm));
            cube_min = cube_min.min(common::naive_cube_distance_mm(
                &pts,
                &s.obstacles,
                s.cell_mm,
            ));
        }
    }
    assert!((m.min_centre_clearance_cells - centre_min).abs() < 1e-12);
    assert!(
        (m.min_cube_distance_mm - cube_min).abs() < 1e-6,
        "{m:?} vs {cube_min}"
    );
    // A cube lies within its circumscribed ball: the cube distance is at least the centre
    // distance minus half a diagonal, and at most it minus half an edge.
    let h = s.cell_mm / 2.0;
    assert!(
        m.min_cube_distance_mm >= m.min_centre_clearance_cells * s.cell_mm - h * 3f64.sqrt() - 1e-9
    );
    assert!(m.min_cube_distance_mm <= m.min_centre_clearance_cells * s.cell_mm - h + 1e-9);
    assert_eq!(planner.motion_clearance(&[]), None);
}
