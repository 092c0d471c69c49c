//! Q-learning speed on the paper's simple case (Table 1): 10,000 episodes, with and
//! without assisted learning. Throughput is reported in environment steps per second
//! (the run's `total_steps`, which is fixed by the seed, over the measured time).
//!
//! `cargo bench -p sixaxis-core --bench learning`

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use sixaxis_core::grid::{Assist, GridWorld};
use sixaxis_core::qlearning::{train, TrainOptions};
use sixaxis_core::Scenario;

fn bench_train(c: &mut Criterion) {
    let scenario = Scenario::builtin("paper_simple").expect("built-in scenario");
    let world = GridWorld::new(&scenario).expect("world");
    let mut group = c.benchmark_group("train_paper_simple_10k");
    group
        .sample_size(30)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(6));
    for (label, assist) in [("assist", Assist::on()), ("no_assist", Assist::off())] {
        let mut opts = TrainOptions::from_scenario(&scenario);
        opts.assist = assist;
        opts.seed = 0;
        let probe = train(&world, &opts, None, None).expect("train");
        println!(
            "{label}: {} env steps per run, learned path {:?} steps, converged episode {:?}",
            probe.total_steps,
            probe.path.as_ref().map(|p| p.len() - 1),
            probe.converged_episode
        );
        group.throughput(Throughput::Elements(probe.total_steps));
        group.bench_function(label, |b| {
            b.iter(|| train(black_box(&world), black_box(&opts), None, None).expect("train"))
        });
    }
    group.finish();

    let mut group = c.benchmark_group("bfs_paper_simple");
    group.bench_function("shortest_path", |b| {
        b.iter(|| black_box(&world).shortest_path())
    });
    group.bench_function("grid_world_new", |b| {
        b.iter(|| GridWorld::new(black_box(&scenario)).expect("world"))
    });
    group.finish();
}

criterion_group!(benches, bench_train);
criterion_main!(benches);
