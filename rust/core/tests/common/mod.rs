//! Checks shared by the integration tests: every plan is re-checked here without the
//! planner, with a naive eq. 11 loop built on `segment_point_distance`.
#![allow(dead_code)]

use nalgebra::Vector3;
use sixaxis_core::clearance::{interpolate, segment_point_distance, Clearance};
use sixaxis_core::kinematics::{rotation_from_rpy_deg, ArmPoints};
use sixaxis_core::scenario::{Cell, ClearanceModel, Scenario};

/// Centre of a cell, mm.
pub fn centre(c: Cell, cell_mm: f64) -> Vector3<f64> {
    Vector3::new(c[0] as f64, c[1] as f64, c[2] as f64) * cell_mm
}

/// Naive eq. 11: smallest distance from any obstacle centre to any polyline segment, cells.
pub fn naive_clearance(points: &ArmPoints, obstacles: &[Cell], cell_mm: f64) -> f64 {
    let mut m = f64::INFINITY;
    for w in points.windows(2) {
        for &o in obstacles {
            m = m.min(segment_point_distance(&w[0], &w[1], &centre(o, cell_mm)) / cell_mm);
        }
    }
    m
}

/// Every check of a plan, independent of the planner, on the first pass's orientation grid.
pub fn check_poses(s: &Scenario, path: &[Cell], poses: &[sixaxis_core::planner::PosePoint]) {
    check_poses_nd(s, path, poses, s.planning.orientation_divisions);
}

/// [`check_poses`] for a pass whose orientation grid has `n_d` divisions.
pub fn check_poses_nd(
    s: &Scenario,
    path: &[Cell],
    poses: &[sixaxis_core::planner::PosePoint],
    n_d: u32,
) {
    let grid_step_deg = 360.0 / n_d as f64;
    let arm = s.arm();
    let clearance = Clearance::from_scenario(s);
    let steps = s.planning.interpolation_steps;
    assert_eq!(poses[0].joints_rad, s.arm.beta0_rad());
    for (i, p) in poses.iter().enumerate() {
        assert_eq!(p.cell, path[i]);
        let fk = arm.fk(&p.joints_rad);
        let miss = (fk.position_mm - centre(p.cell, s.cell_mm)).norm();
        if i > 0 {
            assert!(
                miss < 1e-6,
                "pose {i}: terminal {miss} mm from the cell centre"
            );
            let want = rotation_from_rpy_deg(p.orientation_rpy_deg);
            assert!((fk.rotation - want).amax() < 1e-9, "pose {i}: orientation");
            for a in p.orientation_rpy_deg {
                assert_eq!(
                    a % grid_step_deg,
                    0.0,
                    "pose {i}: rpy on the n_d = {n_d} grid"
                );
            }
            for q in p.joints_rad {
                assert!(q > -std::f64::consts::PI && q <= std::f64::consts::PI);
            }
            let prev = &poses[i - 1].joints_rad;
            for k in 1..=steps {
                let q = interpolate(prev, &p.joints_rad, k as f64 / steps as f64);
                let pts = arm.points_mm(&q);
                assert!(clearance.pose_is_clear(&pts), "pose {i}, step {k}");
                if s.planning.clearance_model == ClearanceModel::Centres {
                    let c = naive_clearance(&pts, &s.obstacles, s.cell_mm);
                    assert!(c > s.arm_safe_distance, "pose {i}, step {k}: clearance {c}");
                }
                if let Some(lims) = s.arm.joint_limits_deg {
                    for (j, (a, [lo, hi])) in q.iter().zip(lims).enumerate() {
                        let d = a.to_degrees();
                        assert!(
                            [d, d - 360.0, d + 360.0]
                                .iter()
                                .any(|x| *x >= lo && *x <= hi),
                            "pose {i}, step {k}, joint {j}: {d} deg outside [{lo}, {hi}]"
                        );
                    }
                }
            }
        } else {
            assert!(miss < 0.1);
        }
    }
}

/// Cells in bounds that are not obstacles.
pub fn free_cells(s: &Scenario) -> Vec<Cell> {
    let b = s.bounds;
    let mut out = Vec::new();
    for x in b.min[0]..=b.max[0] {
        for y in b.min[1]..=b.max[1] {
            for z in b.min[2]..=b.max[2] {
                if !s.obstacles.contains(&[x, y, z]) {
                    out.push([x, y, z]);
                }
            }
        }
    }
    out
}

/// Exact distance (mm) from the polyline `points` (mm) to the nearest obstacle cube (edge
/// `cell_mm`, on its cell), without parry: the distance from a point to a box is closed form,
/// and along a segment it is convex, so a ternary search finds its minimum.
pub fn naive_cube_distance_mm(points: &ArmPoints, obstacles: &[Cell], cell_mm: f64) -> f64 {
    let h = cell_mm / 2.0;
    let point_box = |p: Vector3<f64>, c: Vector3<f64>| {
        let d = (p - c).abs().map(|x| (x - h).max(0.0));
        d.norm()
    };
    let mut m = f64::INFINITY;
    for w in points.windows(2) {
        for &o in obstacles {
            let c = centre(o, cell_mm);
            let at = |t: f64| point_box(w[0] + (w[1] - w[0]) * t, c);
            let (mut lo, mut hi) = (0.0f64, 1.0f64);
            for _ in 0..200 {
                let (a, b) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
                if at(a) <= at(b) {
                    hi = b;
                } else {
                    lo = a;
                }
            }
            m = m.min(at(0.5 * (lo + hi))).min(at(0.0)).min(at(1.0));
        }
    }
    m
}
