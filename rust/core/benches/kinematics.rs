//! Benchmarks of the arm's kinematics: forward kinematics, the full closed-form IK solve,
//! and the body polyline.
//!
//! Run: `cargo bench -p sixaxis-core --bench kinematics -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use sixaxis_core::kinematics::{Arm, PAPER_BETA0_DEG};

fn kinematics(c: &mut Criterion) {
    let arm = Arm::paper();
    let beta0 = PAPER_BETA0_DEG.map(f64::to_radians);
    let pose = arm.fk(&beta0);
    assert_eq!(
        arm.ik(&pose).len(),
        8,
        "benchmark pose must be a regular one"
    );

    c.bench_function("fk", |b| b.iter(|| arm.fk(black_box(&beta0))));
    c.bench_function("ik_full_solve_8_solutions", |b| {
        b.iter(|| arm.ik(black_box(&pose)))
    });
    c.bench_function("points_mm", |b| b.iter(|| arm.points_mm(black_box(&beta0))));
}

criterion_group!(benches, kinematics);
criterion_main!(benches);
