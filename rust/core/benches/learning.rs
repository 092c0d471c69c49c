//! Q-learning speed on the paper's simple case (Table 1): 10,000 episodes, with and
//! without assisted learning. Throughput is reported in environment steps per second
//! (the run's `total_steps`, which is fixed by the seed, over the measured time).
//!
//! The `*_cpu` variants measure the benchmark thread's own CPU time (Linux
//! `/proc/thread-self/schedstat`; wall time elsewhere), which stays meaningful on a machine
//! shared with other jobs, where wall time includes the time the thread waited for a core.
//!
//! `cargo bench -p sixaxis-core --bench learning`

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use sixaxis_core::grid::{Assist, GridWorld};
use sixaxis_core::qlearning::{train, Learning};
use sixaxis_core::Scenario;

/// CPU time this thread has run, if the OS tells (Linux: first field of schedstat, ns).
fn thread_cpu_time() -> Option<Duration> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: u64 = text.split_whitespace().next()?.parse().ok()?;
    Some(Duration::from_nanos(ns))
}

fn bench_train(c: &mut Criterion) {
    let scenario = Scenario::builtin("paper_simple").expect("built-in scenario");
    let world = GridWorld::new(&scenario).expect("world");
    let mut group = c.benchmark_group("train_paper_simple_10k");
    group
        .sample_size(30)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(6));
    for (label, assist) in [("assist", Assist::on()), ("no_assist", Assist::off())] {
        let mut opts = Learning::from_scenario(&scenario);
        opts.set_assist(assist);
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
        group.bench_function(format!("{label}_cpu"), |b| {
            b.iter_custom(|iters| {
                let (cpu0, wall0) = (thread_cpu_time(), Instant::now());
                for _ in 0..iters {
                    black_box(
                        train(black_box(&world), black_box(&opts), None, None).expect("train"),
                    );
                }
                match (cpu0, thread_cpu_time()) {
                    (Some(a), Some(b)) => b - a,
                    _ => wall0.elapsed(),
                }
            })
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
