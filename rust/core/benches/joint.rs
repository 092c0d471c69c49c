//! Joint-space env benchmarks (docs/JOINT.md, docs/PERFORMANCE.md "Joint-space env"): one
//! batch step of N = 1024 lanes of paper_simple (19 cubes) with random actions, and the
//! cost of one env step (N = 256) against 0, 19, 100 and 200 obstacle cubes (the worlds of
//! scripts/bench_joint.py: random cells in x, y, z -8..8 kept 2 cells from beta_0's polyline
//! and the target).
//!
//! Run with `cargo bench -p sixaxis-core --bench joint`.

use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sixaxis_core::joint_env::{JointBatch, JointBuffers, JointModel, JointOptions};
use sixaxis_core::scenario::{Cell, Scenario};

/// paper_simple's arm and target with `count` random obstacle cells (see the module docs).
fn world(count: usize, seed: u64) -> Scenario {
    let mut s = Scenario::builtin("paper_simple").unwrap();
    if count == 19 {
        return s;
    }
    let pts = s.arm().points_mm(&s.arm.beta0_rad());
    let mut keep_out: Vec<nalgebra::Vector3<f64>> = Vec::new();
    for w in pts.windows(2) {
        for k in 0..60 {
            keep_out.push(w[0] + (w[1] - w[0]) * (k as f64 / 59.0));
        }
    }
    keep_out.push(s.cell_centre_mm(s.target));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut cells: Vec<Cell> = Vec::new();
    while cells.len() < count {
        let c: Cell = std::array::from_fn(|_| rng.random_range(-8..=8));
        let p = s.cell_centre_mm(c);
        let far = keep_out.iter().all(|k| (k - p).norm() > 2.0 * s.cell_mm);
        if far && !cells.contains(&c) {
            cells.push(c);
        }
    }
    cells.sort();
    s.obstacles = cells;
    s
}

/// A batch of `n` lanes of `s`, its output buffers, and 8 rounds of random actions.
struct Bench {
    batch: JointBatch,
    obs: Vec<f32>,
    f64s: Vec<Vec<f64>>,
    bools: Vec<Vec<bool>>,
    joints: Vec<f64>,
    terminal: Vec<f64>,
    prev: Vec<f32>,
    actions: Vec<Vec<f64>>,
    round: usize,
}

impl Bench {
    fn new(s: &Scenario, n: usize) -> Bench {
        let model = Arc::new(JointModel::new(s, JointOptions::default()).unwrap());
        let d = model.obs_dim();
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let actions = (0..8)
            .map(|_| (0..6 * n).map(|_| rng.random_range(-1.0..=1.0)).collect())
            .collect();
        let mut b = Bench {
            batch: JointBatch::new(model, n).unwrap(),
            obs: vec![0.0; n * d],
            f64s: vec![vec![0.0; n]; 4],
            bools: vec![vec![false; n]; 3],
            joints: vec![0.0; 6 * n],
            terminal: vec![0.0; 3 * n],
            prev: vec![0.0; 3 * n],
            actions,
            round: 0,
        };
        b.step();
        b
    }

    fn step(&mut self) {
        let [rewards, distance, clearance, detour] = &mut self.f64s[..] else {
            unreachable!()
        };
        let [terminated, truncated, refused] = &mut self.bools[..] else {
            unreachable!()
        };
        let bufs = JointBuffers {
            obs: &mut self.obs,
            rewards,
            terminated,
            truncated,
            refused,
            distance_mm: distance,
            clearance_mm: clearance,
            detour_penalty: detour,
            joints: &mut self.joints,
            terminal_mm: &mut self.terminal,
            previous_goal: &mut self.prev,
        };
        self.round = (self.round + 1) % self.actions.len();
        self.batch
            .step(black_box(&self.actions[self.round]), bufs)
            .unwrap();
    }
}

fn bench_joint(c: &mut Criterion) {
    let mut g = c.benchmark_group("joint_batch_step");
    g.sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    let n = 1024;
    let mut b = Bench::new(&world(19, 0), n);
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("paper_simple_n1024", |it| it.iter(|| b.step()));
    let n = 256;
    g.throughput(Throughput::Elements(n as u64));
    for count in [0, 19, 100, 200] {
        let mut b = Bench::new(&world(count, 0), n);
        g.bench_function(format!("obstacles_{count}_n256"), |it| it.iter(|| b.step()));
    }
    g.finish();
}

criterion_group!(benches, bench_joint);
criterion_main!(benches);
