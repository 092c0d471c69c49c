//! Clearance and pose-planning benchmarks: one pose against the paper's 19 obstacles
//! (centres and capsules models), a joint-space motion check of 50 steps, Algorithm 1 on a
//! 10-cell route, and the static checks at the target.
//!
//! Run with `cargo bench -p sixaxis-core --bench clearance`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use sixaxis_core::clearance::Clearance;
use sixaxis_core::kinematics::PAPER_BETA0_DEG;
use sixaxis_core::planner::PosePlanner;
use sixaxis_core::scenario::{Cell, ClearanceModel, Scenario};

fn bench_clearance(c: &mut Criterion) {
    let s = Scenario::builtin("paper_simple").unwrap();
    let arm = s.arm();
    let b0 = PAPER_BETA0_DEG.map(f64::to_radians);
    let points = arm.points_mm(&b0);
    let centres = Clearance::from_scenario(&s);
    let capsules = Clearance::new(
        &s.obstacles,
        s.cell_mm,
        ClearanceModel::Capsules {
            link_radius_mm: 30.0,
            margin_mm: 10.0,
        },
        s.arm_safe_distance,
    );
    c.bench_function("centres_clearance_cells_19_obstacles", |b| {
        b.iter(|| centres.clearance_cells(black_box(&points)))
    });
    c.bench_function("centres_pose_is_clear_19_obstacles", |b| {
        b.iter(|| centres.pose_is_clear(black_box(&points)))
    });
    c.bench_function("capsules_clearance_cells_19_obstacles", |b| {
        b.iter(|| capsules.clearance_cells(black_box(&points)))
    });
    c.bench_function("capsules_pose_is_clear_19_obstacles", |b| {
        b.iter(|| capsules.pose_is_clear(black_box(&points)))
    });
    c.bench_function("points_mm_fk", |b| b.iter(|| arm.points_mm(black_box(&b0))));
    let mut to = b0;
    to[1] += 0.3;
    to[2] -= 0.2;
    c.bench_function("centres_motion_is_clear_50_steps", |b| {
        b.iter(|| centres.motion_is_clear(&arm, black_box(&b0), black_box(&to), 50))
    });
}

/// Algorithm 1 on the paper_simple route from the start to the target (10 cells, complete),
/// and the static checks at the target.
fn bench_planner(c: &mut Criterion) {
    let s = Scenario::builtin("paper_simple").unwrap();
    let planner = PosePlanner::from_scenario(&s);
    let b0 = s.arm.beta0_rad();
    let route: [Cell; 10] = [
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
    assert!(planner.plan_poses(&route, &b0).is_complete());
    let mut g = c.benchmark_group("planner");
    g.sample_size(20);
    g.bench_function("plan_poses_paper_simple_route_10_cells", |b| {
        b.iter(|| planner.plan_poses(black_box(&route), &b0))
    });
    g.bench_function("best_clearance_at_target", |b| {
        b.iter(|| planner.best_clearance_at(black_box(s.target)))
    });
    g.bench_function("cell_reachable_target", |b| {
        b.iter(|| planner.cell_reachable(black_box(s.target)))
    });
    g.finish();
}

criterion_group!(benches, bench_clearance, bench_planner);
criterion_main!(benches);
