//! The `"distance"` start table (`learning.initial_q = "distance"`, ours): an optimistic
//! bound of each move's return from its Manhattan distance to the target (the rule is in
//! the [`super`] module docs and docs/SCENARIOS.md).
//!
//! Entry points: [`distance_bound_table`], [`distance_bound_values`].

use super::table::{QTable, QValue, Rows};
use crate::grid::{base_reward_of, GridWorld, NUM_ACTIONS};
use crate::scenario::{Assist, Learning, QPrecision};

/// Eqs. 5 and 10 (no eq. 9: the bound counts no collision) as the learner's options select
/// them: the one reward function of the grid ([`base_reward_of`]).
fn assist_of(opts: &Learning) -> Assist {
    Assist {
        detour: false,
        distance: opts.assist_distance,
    }
}

/// The `"distance"` initial Q-table (`learning.initial_q`, ours; see the module docs):
/// `Q0(s, a) = R1(s, a) + gamma * V0(next(s, a))`, where `R1` is the first step's reward
/// with the move counted as an ordinary step (`-p`, or `+r` when it reaches the target,
/// plus eq. 10 when on) and `V0(n)` bounds from above the return of every collision-free
/// path from `n` to the target ([`distance_bound_values`]). The target's row is 0. The
/// table has `opts.q_precision` (values computed in f64, then stored).
pub fn distance_bound_table(world: &GridWorld, opts: &Learning) -> QTable {
    let rows = match opts.q_precision {
        QPrecision::F64 => Rows::F64(distance_bound_rows(world, opts)),
        QPrecision::F32 => Rows::F32(distance_bound_rows(world, opts)),
    };
    QTable { rows }
}

fn distance_bound_rows<V: QValue>(world: &GridWorld, opts: &Learning) -> Vec<[V; NUM_ACTIONS]> {
    let v0 = distance_bound_values(world, opts);
    let (rw, assist) = (world.rewards(), assist_of(opts));
    let d_o = world.start_distance_cells();
    let target = world.target();
    world
        .transitions()
        .iter()
        .enumerate()
        .map(|(s, next)| {
            if s == target {
                return [V::ZERO; NUM_ACTIONS];
            }
            next.map(|n| {
                let n = n as usize;
                let first = base_reward_of(
                    rw,
                    false,
                    n == target,
                    d_o,
                    world.distance_to_target_cells(n),
                    assist,
                );
                V::from_f64(if n == target {
                    first
                } else {
                    first + opts.gamma * v0[n]
                })
            })
        })
        .collect()
}

/// Per state `n`, an upper bound `V0(n)` of the discounted return (eqs. 5 and, when on, 10)
/// of any collision-free path from `n` to the target (0 at the target): with
/// `k = manhattan(n, target)` moves, at least `k` are needed, and after `j` moves the
/// distance to the target is at least `L_j = max(d_t(n) - j, (k - j) / sqrt 3, 0)` cells,
/// so `V0(n) = sum_{j=1}^{k-1} gamma^(j-1) (-p + r_e (d_o - L_j)) + gamma^(k-1) (r + r_e d_o)`.
/// While every step's reward is negative (`r_e d_o < p`), a longer path only lowers this
/// sum, so the bound holds for paths of every length. Exact on a straight free path.
pub fn distance_bound_values(world: &GridWorld, opts: &Learning) -> Vec<f64> {
    let (rw, assist, gamma) = (world.rewards(), assist_of(opts), opts.gamma);
    let d_o = world.start_distance_cells();
    let tc = world.cell_of(world.target());
    let inv_sqrt3 = 1.0 / 3f64.sqrt();
    (0..world.num_states())
        .map(|n| {
            let c = world.cell_of(n);
            let k: i64 = (0..3).map(|i| (c[i] - tc[i]).abs() as i64).sum();
            if k == 0 {
                return 0.0;
            }
            let d_n = world.distance_to_target_cells(n);
            let mut sum = 0.0;
            let mut disc = 1.0;
            for j in 1..k {
                let l = (d_n - j as f64).max((k - j) as f64 * inv_sqrt3).max(0.0);
                sum += disc * base_reward_of(rw, false, false, d_o, l, assist);
                disc *= gamma;
            }
            sum + disc * base_reward_of(rw, false, true, d_o, 0.0, assist)
        })
        .collect()
}
