//! Clearance benchmarks: one pose against the paper's 19 obstacles (centres and capsules
//! models), and a joint-space motion check of 50 steps.
//!
//! Run with `cargo bench -p sixaxis-core --bench clearance`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use sixaxis_core::clearance::Clearance;
use sixaxis_core::kinematics::PAPER_BETA0_DEG;
use sixaxis_core::scenario::{ClearanceModel, Scenario};

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

criterion_group!(benches, bench_clearance);
criterion_main!(benches);
