//! Algorithm 2 end to end: learn the path (10,000 episodes), plan the poses, re-plan.
//! Goal (issue 3): a whole run on the paper's scenarios at most 0.5 s.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use sixaxis_core::replanning::{plan, PlanOptions};
use sixaxis_core::Scenario;

fn bench_algorithm2(c: &mut Criterion) {
    let mut group = c.benchmark_group("algorithm2");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(8));
    for name in ["paper_simple", "paper_complex", "replan_clutter"] {
        let s = Scenario::builtin(name).expect("built-in scenario");
        let opts = PlanOptions::from_scenario(&s);
        let probe = plan(&s, &opts, None, None).expect("plan");
        println!(
            "{name}: success {}, {} re-plans, path {} steps",
            probe.success,
            probe.replans,
            probe.path.len().saturating_sub(1)
        );
        group.bench_function(format!("plan_{name}"), |b| {
            b.iter(|| plan(black_box(&s), black_box(&opts), None, None).expect("plan"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_algorithm2);
criterion_main!(benches);
