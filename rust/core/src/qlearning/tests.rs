//! Unit tests of the learner, the tables and the file format.

use super::learner::train_impl;
use super::table::*;
use super::*;
use crate::grid::{GridWorld, NUM_ACTIONS};
use crate::scenario::{Assist, InitialQ, Scenario};

#[test]
fn epsilon_schedule() {
    let s = Scenario::builtin("paper_simple").unwrap();
    let o = Learning::from_scenario(&s);
    assert_eq!(o.epsilon(0), 0.1);
    assert!((o.epsilon(4950) - 0.05).abs() < 1e-15);
    assert_eq!(o.epsilon(9900), 0.0);
    assert_eq!(o.epsilon(9901), 0.0);
    let o0 = Learning {
        epsilon_decay_episodes: 0,
        ..o
    };
    assert_eq!(o0.epsilon(0), 0.0);
}

#[test]
fn argmax_ties_lowest() {
    assert_eq!(argmax_lowest(&[0.0; 6]), 0);
    assert_eq!(argmax_lowest(&[0.0, 1.0, 1.0, 0.0, 0.0, 0.0]), 1);
    assert_eq!(argmax_lowest(&[-1.0, -1.0, -1.0, -1.0, -1.0, -0.5]), 5);
    assert_eq!(row_max(&[-3.0, -2.0, -1.0, -4.0, -5.0, -6.0]), -1.0);
    assert_eq!(max_mask(&[0.0, 1.0, 1.0, 0.0, 1.0, 0.0]), 0b10110);
    assert_eq!(nth_set_bit(0b10110, 0), 1);
    assert_eq!(nth_set_bit(0b10110, 1), 2);
    assert_eq!(nth_set_bit(0b10110, 2), 4);
}

/// The optimum over collision-free moves (value iteration): the best return of any path
/// from each state to the target, under eq. 5 and (if on) eq. 10.
fn best_collision_free_return(world: &GridWorld, assist: Assist, gamma: f64) -> Vec<f64> {
    let n = world.num_states();
    let target = world.target();
    let mut v = vec![-1e12; n];
    v[target] = 0.0;
    loop {
        let mut change = 0.0f64;
        for s in 0..n {
            if s == target || world.is_blocked(s) {
                continue;
            }
            let mut best = f64::NEG_INFINITY;
            for a in 0..NUM_ACTIONS {
                let t = world.next_state(s, a);
                if t == s {
                    continue;
                }
                let r = world.base_reward(s, a, assist);
                best = best.max(if t == target { r } else { r + gamma * v[t] });
            }
            change = change.max((best - v[s]).abs());
            v[s] = best;
        }
        if change < 1e-9 {
            return v;
        }
    }
}

#[test]
fn distance_bound_is_admissible_and_tight_on_free_lines() {
    for (name, assist) in [
        ("paper_simple", Assist::on()),
        ("paper_simple", Assist::off()),
        ("paper_complex", Assist::on()),
    ] {
        let s = Scenario::builtin(name).unwrap();
        let w = GridWorld::new(&s).unwrap();
        let o = Learning {
            assist_detour: assist.detour,
            assist_distance: assist.distance,
            initial_q: InitialQ::Distance,
            ..Learning::from_scenario(&s)
        };
        let v0 = distance_bound_values(&w, &o);
        let best = best_collision_free_return(&w, assist, o.gamma);
        let q0 = distance_bound_table(&w, &o);
        for st in 0..w.num_states() {
            if w.is_blocked(st) || best[st] < -1e11 {
                continue;
            }
            assert!(
                v0[st] >= best[st] - 1e-6,
                "{name} {st}: {} < {}",
                v0[st],
                best[st]
            );
            // Q0 of a free move bounds that move's best return too.
            for a in 0..NUM_ACTIONS {
                let t = w.next_state(st, a);
                if st == w.target() || t == st || best[t] < -1e11 {
                    continue;
                }
                let r = w.base_reward(st, a, assist);
                let qa = if t == w.target() {
                    r
                } else {
                    r + o.gamma * best[t]
                };
                assert!(q0.get(st, a) >= qa - 1e-6, "{name} {st} {a}");
            }
        }
    }
    // Without obstacles the bound is exact on the axis lines through the target.
    let mut s = Scenario::builtin("paper_simple").unwrap();
    s.obstacles.clear();
    let w = GridWorld::new(&s).unwrap();
    for assist in [Assist::on(), Assist::off()] {
        let o = Learning {
            assist_detour: assist.detour,
            assist_distance: assist.distance,
            ..Learning::from_scenario(&s)
        };
        let v0 = distance_bound_values(&w, &o);
        let best = best_collision_free_return(&w, assist, o.gamma);
        let t = s.target;
        let mut on_line = 0;
        for st in 0..w.num_states() {
            let c = w.cell_of(st);
            if (0..3).filter(|&i| c[i] != t[i]).count() == 1 {
                on_line += 1;
                assert!(
                    (v0[st] - best[st]).abs() < 1e-6,
                    "{c:?}: {} {}",
                    v0[st],
                    best[st]
                );
            }
        }
        assert!(on_line >= 10);
    }
}

#[test]
fn initial_q_rule_and_explicit_table() {
    let s = Scenario::builtin("paper_simple").unwrap();
    let w = GridWorld::new(&s).unwrap();
    let zero = Learning::from_scenario(&s);
    assert_eq!(
        zero.initial_q,
        InitialQ::Zero,
        "the paper's learner by default"
    );
    let dist = Learning {
        episodes: 1,
        initial_q: InitialQ::Distance,
        epsilon_start: 0.0,
        ..zero
    };
    // One purely greedy episode from the distance table changes only the rows it visits.
    let r = train(&w, &dist, None, None).unwrap();
    let q0 = distance_bound_table(&w, &dist);
    let changed = (0..w.num_states())
        .filter(|&st| r.q.row(st) != q0.row(st))
        .count();
    assert!(changed >= 1 && changed <= r.total_steps as usize);
    // An explicit table wins over the rule.
    let given = QTable::zeros(w.num_states());
    let a = train(&w, &dist, Some(given), None).unwrap();
    let b = train(
        &w,
        &Learning {
            initial_q: InitialQ::Zero,
            ..dist
        },
        None,
        None,
    )
    .unwrap();
    assert_eq!(a.q, b.q);
}

#[test]
fn tracked_path_equals_fresh_rollout() {
    // The incremental converged-episode bookkeeping must agree with a fresh rollout.
    let s = Scenario::builtin("paper_simple").unwrap();
    let w = GridWorld::new(&s).unwrap();
    let mut o = Learning::from_scenario(&s);
    o.episodes = 300;
    o.epsilon_decay_episodes = 297;
    let r = train(&w, &o, None, None).unwrap();
    assert_eq!(r.path, greedy_path(&w, &r.q, o.max_steps_per_episode));
    for (name, seed, assist) in [
        ("paper_simple", 0, Assist::on()),
        ("paper_simple", 1, Assist::on()),
        ("paper_simple", 2, Assist::off()),
        ("paper_complex", 3, Assist::on()),
    ] {
        let s = Scenario::builtin(name).unwrap();
        let w = GridWorld::new(&s).unwrap();
        let mut o = Learning::from_scenario(&s);
        o.episodes = 2000;
        o.epsilon_decay_episodes = 1980;
        o.seed = seed;
        o.set_assist(assist);
        let fast = train_impl(&w, &o, None, None, &[], false).unwrap();
        let slow = train_impl(&w, &o, None, None, &[], true).unwrap();
        assert_eq!(fast.q, slow.q);
        assert_eq!(fast.path, slow.path);
        assert_eq!(
            fast.converged_episode, slow.converged_episode,
            "{name} {seed}"
        );
    }
}
