//! Grid world rewards (eqs. 5, 9, 10), the Q-update (eq. 6), the learner (eqs. 7-8),
//! breadth-first shortest paths and Q-table files.
//!
//! Run with `-- --nocapture` to see the reported figures (BFS length, learned path length,
//! converged episodes).

use rand::{Rng, RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sixaxis_core::grid::{opposite, Assist, GridWorld, Transition, ACTIONS};
use sixaxis_core::qlearning::{greedy_path, q_update, train, Learning, QTable};
use sixaxis_core::scenario::{Bounds, QPrecision};
use sixaxis_core::{Cell, Error, Scenario};

const PX: usize = 0;
const MX: usize = 1;
const PY: usize = 2;
const MY: usize = 3;
const PZ: usize = 4;
const MZ: usize = 5;

fn scenario(name: &str) -> Scenario {
    Scenario::builtin(name).unwrap()
}

fn world(name: &str) -> GridWorld {
    GridWorld::new(&scenario(name)).unwrap()
}

/// A 3x1x1 corridor x = 0..=2 at (y, z) = (-2, 4) (the start cell of the paper's arm, so
/// the scenario still validates), start x = 0, target x = 2, no obstacles, Table 1 rewards.
fn corridor() -> Scenario {
    let mut s = scenario("paper_simple");
    s.name = "corridor".into();
    s.bounds = Bounds {
        min: [0, -2, 4],
        max: [2, -2, 4],
    };
    s.start = [0, -2, 4];
    s.target = [2, -2, 4];
    s.obstacles.clear();
    s.validate().unwrap();
    s
}

fn only_detour() -> Assist {
    Assist {
        detour: true,
        distance: false,
    }
}

fn only_distance() -> Assist {
    Assist {
        detour: false,
        distance: true,
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()))
}

macro_rules! assert_close {
    ($a:expr, $b:expr) => {{
        let (a, b) = ($a, $b);
        assert!(close(a, b), "{} = {a}, expected {b}", stringify!($a));
    }};
}

fn dist(a: Cell, b: Cell) -> f64 {
    (0..3)
        .map(|i| ((a[i] - b[i]) as f64).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// The learner of the module docs, written plainly with `GridWorld::step` and `q_update`.
fn reference_train(world: &GridWorld, o: &Learning, q0: Option<QTable>) -> (QTable, Vec<u32>) {
    let mut rng = ChaCha8Rng::seed_from_u64(o.seed);
    let mut q = q0.unwrap_or_else(|| QTable::zeros(world.num_states()));
    let mut steps_per_episode = Vec::new();
    for ep in 0..o.episodes {
        let threshold = (o.epsilon(ep) * 4_294_967_296.0).ceil() as u64;
        let mut s = world.start();
        let mut last = None;
        let mut steps = 0;
        while steps < o.max_steps_per_episode {
            let a = if threshold > 0 && (rng.next_u32() as u64) < threshold {
                rng.random_range(0..6u32) as usize
            } else {
                let m = q.max_value(s);
                let ties: Vec<usize> = (0..6).filter(|&a| q.get(s, a) == m).collect();
                if ties.len() == 1 {
                    ties[0]
                } else {
                    ties[rng.random_range(0..ties.len() as u32) as usize]
                }
            };
            let t = world.step(s, a, last, o.assist());
            q_update(&mut q, s, a, &t, o.alpha, o.gamma);
            last = t.collided.then_some(a);
            s = t.next;
            steps += 1;
            if t.reached {
                break;
            }
        }
        steps_per_episode.push(steps);
    }
    (q, steps_per_episode)
}

fn check_path(w: &GridWorld, path: &[Cell]) {
    assert_eq!(path.first(), Some(&w.cell_of(w.start())));
    assert_eq!(path.last(), Some(&w.cell_of(w.target())));
    for pair in path.windows(2) {
        let d: i32 = (0..3).map(|i| (pair[1][i] - pair[0][i]).abs()).sum();
        assert_eq!(d, 1, "not contiguous: {pair:?}");
    }
    for (i, c) in path.iter().enumerate() {
        let s = w.state_of(*c).expect("inside bounds");
        assert!(!w.is_blocked(s), "{c:?} is blocked");
        for o in w.obstacles() {
            assert!(dist(*c, *o) > w.terminal_safe_distance());
        }
        assert!(!path[..i].contains(c), "{c:?} revisited");
    }
}

fn trained(w: &GridWorld, sc: &Scenario, episodes: u32, seed: u64) -> QTable {
    let mut o = Learning::from_scenario(sc);
    o.episodes = episodes;
    o.seed = seed;
    train(w, &o, None, None).unwrap().q
}

mod bfs;
mod budget;
mod f32;
mod files;
mod learner;
mod rewards;
mod update;
