//! Tabular Q-learning of the terminal's path (eqs. 6-8), and Q-table files.
//!
//! Submodules, one concern each: `table` (the [`QTable`] in f64 or f32), `file` (its file
//! format), `initial` (the `"distance"` start table), `learner` ([`train`],
//! [`greedy_path`], [`q_update`]), `report` ([`TrainReport`], the one serialisation of a
//! run). The options of a run are the scenario's [`Learning`] section.
//!
//! Entry points:
//! - [`train`] — learn a [`QTable`] on a [`GridWorld`](crate::grid::GridWorld) with [`Learning`]; returns the
//!   learned path, per-episode statistics and the converged episode ([`TrainResult`]).
//! - [`train_with_checkpoints`] — [`train`], recording the greedy path at given env-step
//!   counts on the way ([`Checkpoint`]: the learning curve of one run).
//! - [`greedy_path`] — the learned path (`place`, eq. 8) of a Q-table.
//! - [`q_update`] — one update of eq. 6 (the learner uses the same arithmetic).
//! - [`QTable::save`] / [`QTable::load`] — atomic Q-table files, checked against the world.
//! - [`QTable::zeros_with`] / [`QTable::precision`] / [`QTable::bytes_per_state`] — tables of
//!   f64 (the default) or f32 values ([`QPrecision`](crate::scenario::QPrecision)); values are read and written as f64.
//!
//! ```
//! use sixaxis_core::grid::GridWorld;
//! use sixaxis_core::qlearning::{train, Learning};
//! use sixaxis_core::Scenario;
//! let s = Scenario::builtin("paper_simple").unwrap();
//! let world = GridWorld::new(&s).unwrap();
//! let mut opts = Learning::from_scenario(&s); // the paper's 10,000 episodes ...
//! opts.episodes = 200; // ... fewer here
//! let r = train(&world, &opts, None, None).unwrap();
//! assert_eq!(r.steps_per_episode.len(), 200);
//! ```
//!
//! # Choices where the paper is silent (docs/SCENARIOS.md "The learner: choices where the paper is silent")
//!
//! - **Episodes are counted from 0**: episode `eta` in `0..episodes` explores with
//!   `epsilon = epsilon_start * (1 - eta / M)` for `eta <= M`, else 0
//!   (`M = epsilon_decay_episodes`; `M = 0` means no exploration at all). With the paper's
//!   M = 9900 and 10,000 episodes, episodes 9900..=9999 are purely greedy.
//! - **Action selection** per step: if `epsilon > 0`, draw `k = next_u32()` and explore if
//!   `k < ceil(epsilon * 2^32)` (that is `u < epsilon` for `u = k / 2^32` uniform in
//!   [0, 1)): then take an action uniformly from all six (`random_range(0..6u32)`). Otherwise take the greedy action;
//!   when several actions share the maximal Q-value, one of them is drawn uniformly
//!   (`random_range(0..ties)` over the tied actions in index order; a draw is made only
//!   when there is a tie). All draws come from one
//!   `ChaCha8Rng::seed_from_u64(seed)` per call of [`train`], in this order, so a run is
//!   fully determined by (world, options, initial Q-table).
//! - **Episode end**: on reaching the target (terminal state: the update does not
//!   bootstrap, `Q += alpha (R - Q)`), or after `max_steps_per_episode` steps (truncation:
//!   the last update bootstraps as usual).
//! - **Detour memory** (eq. 9) is reset at the start of every episode.
//! - **Greedy rollout** ([`greedy_path`], eq. 8): from the start, always the action of
//!   highest Q, ties broken by the *lowest action index* (deterministic); cells
//!   start..=target. It fails (`None`) if it does not reach the target within
//!   `max_steps_per_episode` steps or if it revisits a cell (a colliding greedy move
//!   revisits the cell it stays on).
//! - **Converged episode**: the index (from 0, of this call of [`train`]) of the first
//!   episode after whose updates the greedy path equals the greedy path after every later
//!   episode; `None` if the final greedy path fails. The path after the last episode is
//!   compared with the path after the one before, ..., and with the path of the initial
//!   Q-table for episode 0; if it never changed, the answer is 0. The learner recomputes
//!   the greedy path only after an episode whose updates changed the greedy action of a
//!   state the current rollout consults, which is exact and cheap. Late changes are
//!   usually swaps between equally short paths whose Q-values are still settling, so
//!   [`TrainResult::length_converged_episode`] also reports the first episode from which
//!   the path's length no longer changed.
//! - **`episodes_auto`** (`--episodes auto`, ours; the paper's fixed `episodes` and M stay
//!   the default): `episodes` is then a cap, and the run follows three phases.
//!   *Search*: `epsilon = epsilon_start` until the greedy path first reaches the target, after
//!   episode `e1`. *Settle*: epsilon falls linearly to 0 over the next
//!   `H = max(e1 + 1, AUTO_MIN_HORIZON)` episodes, `epsilon_start * (1 - (eta - e1) / H)`
//!   for `eta` in `e1 + 1 ..= e1 + H` (the horizon grows with the time the world needed to
//!   be solved, not a fixed M). *Confirm*: purely greedy; the run stops after the first
//!   episode `eta >= e1 + H` after which the greedy path reaches the target and has not
//!   changed for `H` episodes (tracked exactly after every episode). `epsilon_decay_episodes`
//!   is not used. Hitting the cap ends the run like a fixed run of that length.
//! - **Env-step budget** (`max_env_steps`, ours; 0, none, is the paper's): the run stops
//!   right after its `max_env_steps`-th env step over all episodes, mid-episode if need be
//!   (that last, cut episode counts in `steps_per_episode` and is not reached unless its last
//!   step reached the target), or after `episodes` episodes, whichever comes first.
//! - **`epsilon_schedule = "env_steps"`** (ours; `"episodes"`, eq. 7 over
//!   `epsilon_decay_episodes`, stays the default and gives the same results bit for bit):
//!   the `t`-th env step of the run (from 0) explores with
//!   `epsilon = epsilon_start * (1 - t / D)` for `t < D`, else 0, with
//!   `D = epsilon_decay_fraction * max_env_steps` (default 0.99, the paper's M / eta_set =
//!   9900 / 10000); it needs `max_env_steps` and does not combine with `episodes_auto`.
//!   The draw per step is the one described above, with this epsilon.
//! - **Checkpoints** ([`train_with_checkpoints`]): right after the run's `c`-th env step, for
//!   each requested `c`, the learner records the greedy path of the current table
//!   ([`greedy_path`] with `max_steps_per_episode`, computed on buffers of its own) with the
//!   episode, wall and CPU time so far, and goes on: the run is the same as without
//!   checkpoints, and each checkpoint's path is the final path of the same run stopped at
//!   `max_env_steps = c` with the same schedule (tested).
//! - **`initial_q = "distance"`** (`learning.initial_q`, `--initial-q distance`; ours, the
//!   paper's Q = 0 stays the default): with no table given, Q starts at
//!   [`distance_bound_table`], an optimistic bound of the return of each move. A move costs
//!   at least `1 + manhattan(next, target)` moves to the target in a 6-connected grid, and
//!   eq. 10 can pay at most `r_e (d_o - L_j)` at the `j`-th of them, where `L_j` is a lower
//!   bound of the distance left ([`distance_bound_values`]). The bound is at least the best
//!   return of every collision-free path (tested), so greedy learning from it behaves like
//!   A*/LRTA*: it follows moves that could still be optimal and lowers them when the world
//!   says otherwise, instead of trying every action of every state as Q = 0 with rewards
//!   of -p does. A colliding move counts as an ordinary step that stays put (its first
//!   reward is taken as `-p`, not `-P`), so the start table never prefers a wall. Caveat:
//!   with eq. 9 off and `P < p`, a state more than 9 moves from the target (at the
//!   defaults) is worth more colliding forever (`-P / (1 - gamma)` = -80,000) than any
//!   path; no start table changes that optimum, so no path is learned there.
//! - **`q_precision = "f32"`** (`learning.q_precision`, `--q-precision f32`; ours, the
//!   paper's f64 stays the default): the table stores f32 values, 24 bytes per state
//!   instead of 48 ([`QTable::bytes_per_state`]). Nothing else changes: each update of
//!   eq. 6 reads the stored values as f64, computes in f64 exactly as the f64 learner does,
//!   and stores the result rounded to the nearest f32; greedy choices and ties compare the
//!   stored values. The `"distance"` start table is computed in f64 and stored rounded. An
//!   f32 run is deterministic like an f64 run, but not equal to it: rounding makes
//!   different values tie or order differently, so the random stream and the learned path
//!   may differ (measured in docs/PERFORMANCE.md). The learner is generic over the value
//!   type and dispatched once per call of [`train`]; with f64 it is the identity and the
//!   results are bit for bit those of the f64-only learner.
//! - **Resuming** ([`train`] with `initial_q`): the run starts from that table but is
//!   otherwise a fresh run: its generator is seeded with `opts.seed`, episodes (and so the
//!   epsilon schedule) count from 0 again, and the converged episode is an index of this
//!   run. Pass a seed different from the first run's to avoid replaying its random stream,
//!   and e.g. `epsilon_start = 0` to continue purely greedily. A table whose precision is
//!   not `opts.q_precision` is converted first ([`QTable::into_precision`]: exact from f32
//!   to f64, rounded to the nearest f32 the other way, an error for a value beyond the f32
//!   range), so the result always has the run's precision.
//!
//!
//! The Q-table file format is described in the `file` submodule ([`QTable::save`]).

mod file;
mod initial;
mod learner;
mod report;
mod table;
#[cfg(test)]
mod tests;

pub use crate::scenario::{Learning, AUTO_EPISODE_CAP};
pub use initial::{distance_bound_table, distance_bound_values};
pub use learner::{greedy_path, q_update, train, train_with_checkpoints, Checkpoint, TrainResult};
pub use report::TrainReport;
pub use table::QTable;

/// Shortest settle horizon of `episodes_auto`, episodes.
pub const AUTO_MIN_HORIZON: u32 = 100;
