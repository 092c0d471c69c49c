//! A scenario's environment as arrays: every transition, collision flag, reward,
//! termination flag and observation row of [`crate::env`], tabulated by the core, so that a
//! table-driven copy of the env (the JAX twin, `sixaxis_avoid.jax`) looks values up and
//! computes none of the equations again.
//!
//! Entry points:
//! - [`EnvTables::new`] — the tables of a scenario with the Gymnasium env's keywords
//!   ([`TABLE_KEYS`]: `assist`, `reward_scale`, `random_target`, `arm_aware`,
//!   `max_episode_steps`), each checked against the env's option table
//!   ([`ENV_OPTIONS`](crate::env::ENV_OPTIONS)).
//! - [`EnvTables::from_model`] — the tables of an [`EnvModel`] you built yourself.
//! - [`EnvTables::bytes`] — their memory cost.
//!
//! ```
//! use sixaxis_core::options::{OptionValue, Options};
//! use sixaxis_core::tables::{EnvTables, NO_MEMORY};
//! use sixaxis_core::Scenario;
//! let s = Scenario::builtin("paper_simple").unwrap();
//! let mut opts = Options::new();
//! opts.insert("random_target".into(), OptionValue::Bool(true));
//! let t = EnvTables::new(&s, &opts).unwrap();
//! assert_eq!(t.num_states, 7 * 9 * 8);
//! assert_eq!(t.num_targets, t.target_states.len());
//! // From the start, -z (action 5) moves without collision, with no eq. 9 memory:
//! let (s0, a) = (t.start_state as usize, 5);
//! let next = t.next_state[s0 * 6 + a] as usize;
//! let collided = t.collided[s0 * 6 + a];
//! let case = t.reward_case[(NO_MEMORY as usize * 6 + a) * 2 + collided as usize];
//! let reward = t.rewards[(0 * t.num_states + next) * 4 + case as usize]; // target 0
//! assert!(!collided && reward.is_finite());
//! assert!(t.bytes() < 5_000_000);
//! ```
//!
//! # Layout
//!
//! `S` is the number of states (cells inside the bounds, numbered as
//! [`GridWorld::state_of`](crate::grid::GridWorld::state_of) does), `T` the number of
//! targets: 1 (the scenario's) for fixed-target tasks, the candidate targets
//! ([`EnvModel::target_candidates`], free cells other than the start, in state order) with
//! `random_target`. Every array is flat, row-major; shapes below.
//!
//! An episode's state is `(s, m, t, steps)`: the terminal's state `s`, eq. 9's one-step
//! memory `m` (the action of the last step if it collided, else [`NO_MEMORY`] = 6), the
//! target index `t` and the steps taken. A step with action `a` is, by look-ups only:
//!
//! - `collided = collided[s, a]`, `next = next_state[s, a]` (`(S, 6)`; on a collision the
//!   terminal stays: `next = s`);
//! - `k = reward_case[m, a, collided]` (`(7, 6, 2)`): which of eq. 9's four cases applies
//!   ([`RewardCase`]);
//! - `reward = rewards[t, next, k]` (`(T, S, 4)`, `f32`): `(eq. 5 + eq. 10 + eq. 9) *
//!   reward_scale` exactly as [`Episode::step`](crate::env::Episode::step) computes it in
//!   `f64` ([`base_reward_of`] with the target's `d_o` and `d_t`, then
//!   [`GridWorld::detour_penalty`](crate::grid::GridWorld::detour_penalty)), rounded to the
//!   nearest `f32`;
//! - `terminated = terminates[t, next, k]` (`(T, S, 4)`, bool): the move reached the target
//!   (never on a collision);
//! - `m' = next_memory[a, collided]` (`(6, 2)`);
//! - the vector observation ([`crate::env`]'s 13 floats, as
//!   [`Episode::write_vector_obs`](crate::env::Episode::write_vector_obs)) is
//!   `obs_state[s] + obs_target[t] + obs_memory[m]` (`(S, 13)`, `(T, 13)`, `(7, 13)`): each
//!   row holds its own part and zeros elsewhere, so the sum is exact.
//!
//! A reset puts the terminal at `start_state` with `m = NO_MEMORY`, target index 0 (fixed
//! target) or a uniform draw from `0..T` (`random_target`), whose state and cell are
//! `target_states[t]` and `target_cells[t]`. `cells` (`(S, 3)`) gives each state's cell;
//! `max_episode_steps` is the truncation cap of the native vector env.
//!
//! # Memory
//!
//! [`EnvTables::bytes`]: `94 S + 68 T + 20 S T + 460` bytes (`next_state` `i32`, the flags
//! one byte each, rewards `f32`). A fixed-target task (`T = 1`) costs about 114 bytes a
//! cell: 58 kB for `paper_simple`'s 504 cells, 0.38 MB for its 50 mm regrid (3,315 cells),
//! 2.7 MB for the 25 mm one (23,925 cells). With random targets the target-indexed tables
//! grow as `S T`: 5.0 MB for `paper_simple` (484 targets), 201 MB at 50 mm (3,020
//! targets), and about 10 GB at 25 mm (21,200 targets): a random-target twin of that grid
//! needs a machine larger than the 24 GB this project is developed on.

use crate::env::{
    env_option_info, unreachable_cells, EnvModel, EnvOptions, OBS_COLLIDED, OBS_FLAGS, OBS_TARGET,
    OBS_TERMINAL, VECTOR_OBS_DIM,
};
use crate::error::{Error, Result};
use crate::grid::{base_reward_of, NUM_ACTIONS};
use crate::options::{check_value, reject_unknown, OptionValue, Options};
use crate::request::TrainRequest;
use crate::scenario::Scenario;

/// The keywords [`EnvTables::new`] takes: those of the Gymnasium env that change its
/// dynamics or rewards.
pub const TABLE_KEYS: [&str; 5] = [
    "assist",
    "reward_scale",
    "random_target",
    "arm_aware",
    "max_episode_steps",
];

/// Eq. 9's memory when the last step did not collide (or the episode just started).
pub const NO_MEMORY: u8 = NUM_ACTIONS as u8;
/// Number of memory values: the six actions and [`NO_MEMORY`].
pub const NUM_MEMORIES: usize = NUM_ACTIONS + 1;
/// Number of [`RewardCase`]s.
pub const NUM_CASES: usize = 4;

/// Eq. 9's cases, the last index of the `rewards` and `terminates` tables
/// (docs/SCENARIOS.md, "The grid world: states, actions, collisions, rewards").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum RewardCase {
    /// The move did not collide and eq. 9 adds nothing.
    Move = 0,
    /// The move did not collide and reverses the last step's colliding action.
    Reverse = 1,
    /// The move collided; the last step did not.
    Collide = 2,
    /// The move collided again after a colliding step.
    Repeat = 3,
}

impl RewardCase {
    /// The cases in index order.
    pub const ALL: [RewardCase; NUM_CASES] = [
        RewardCase::Move,
        RewardCase::Reverse,
        RewardCase::Collide,
        RewardCase::Repeat,
    ];

    /// A step `(action, collided, last colliding action)` of this case, the one the table
    /// evaluates the reward of.
    fn example(self) -> (usize, bool, Option<usize>) {
        match self {
            RewardCase::Move => (0, false, None),
            RewardCase::Reverse => (1, false, Some(0)),
            RewardCase::Collide => (0, true, None),
            RewardCase::Repeat => (0, true, Some(0)),
        }
    }
}

/// A scenario's environment as arrays (see the module's Layout).
#[derive(Debug, Clone, PartialEq)]
pub struct EnvTables {
    /// `S`: states (cells inside the bounds).
    pub num_states: usize,
    /// `T`: targets (1, or the candidates with `random_target`).
    pub num_targets: usize,
    /// `(S, 6)`: the next state (the same state on a collision).
    pub next_state: Vec<i32>,
    /// `(S, 6)`: the move collides.
    pub collided: Vec<bool>,
    /// `(6, 2)` by `(action, collided)`: eq. 9's memory after the step.
    pub next_memory: Vec<u8>,
    /// `(7, 6, 2)` by `(memory, action, collided)`: the [`RewardCase`] index.
    pub reward_case: Vec<u8>,
    /// `(T, S, 4)` by `(target, next state, case)`: the reward, times `reward_scale`.
    pub rewards: Vec<f32>,
    /// `(T, S, 4)`: the step reaches the target (the episode terminates).
    pub terminates: Vec<bool>,
    /// `(S, 13)`: the terminal's part of the vector observation (cell, six flags).
    pub obs_state: Vec<f32>,
    /// `(T, 13)`: the target's part (its normalised cell).
    pub obs_target: Vec<f32>,
    /// `(7, 13)`: the memory's part (1 if the last step collided).
    pub obs_memory: Vec<f32>,
    /// `(S, 3)`: each state's cell.
    pub cells: Vec<i32>,
    /// `(T,)`: each target's state.
    pub target_states: Vec<i32>,
    /// `(T, 3)`: each target's cell.
    pub target_cells: Vec<i32>,
    /// The start state.
    pub start_state: i32,
    /// Truncation after this many steps.
    pub max_episode_steps: u32,
    /// Whether each reset draws a target uniformly from `0..T`.
    pub random_target: bool,
}

/// The model options and the step cap of the Gymnasium env's keywords ([`TABLE_KEYS`]);
/// a key left out takes the env's default (`assist`: the scenario's `learning.assist_*`;
/// `max_episode_steps`: its `learning.max_steps_per_episode`).
pub fn env_options_of(scenario: &Scenario, options: &Options) -> Result<(EnvOptions, u32)> {
    reject_unknown(&TABLE_KEYS, options)?;
    for (key, value) in options {
        let info = env_option_info(key).expect("TABLE_KEYS are keys of ENV_OPTIONS");
        check_value(key, &info.domain, value)?;
    }
    let mut opts = EnvOptions::for_scenario(scenario);
    let flag = |key: &str, default: bool| match options.get(key) {
        Some(OptionValue::Bool(b)) => *b,
        _ => default,
    };
    if let Some(OptionValue::Bool(a)) = options.get("assist") {
        opts.assist = TrainRequest::default()
            .with("assist", *a)
            .resolve(scenario)?
            .assist();
    }
    match options.get("reward_scale") {
        Some(OptionValue::Float(x)) => opts.reward_scale = *x,
        Some(OptionValue::Int(i)) => opts.reward_scale = *i as f64,
        _ => {}
    }
    opts.random_target = flag("random_target", opts.random_target);
    let max_episode_steps = match options.get("max_episode_steps") {
        Some(OptionValue::Int(i)) => *i as u32,
        _ => scenario.learning.max_steps_per_episode,
    };
    if flag("arm_aware", false) {
        opts.extra_obstacles = unreachable_cells(scenario)?;
    }
    Ok((opts, max_episode_steps))
}

impl EnvTables {
    /// The tables of `scenario` with the env keywords `options` ([`env_options_of`]).
    pub fn new(scenario: &Scenario, options: &Options) -> Result<EnvTables> {
        let (opts, max_episode_steps) = env_options_of(scenario, options)?;
        let model = EnvModel::new(scenario, opts)?;
        EnvTables::from_model(&model, max_episode_steps)
    }

    /// The tables of `model`, truncated after `max_episode_steps` (>= 1) steps.
    pub fn from_model(model: &EnvModel, max_episode_steps: u32) -> Result<EnvTables> {
        if max_episode_steps == 0 {
            return Err(Error::argument(
                "max_episode_steps",
                0,
                "must be an integer in 1..=4294967295",
            ));
        }
        let base = model.world();
        let n = base.num_states();
        let opts = model.options();
        let (assist, scale) = (opts.assist, opts.reward_scale);

        let mut next_state = Vec::with_capacity(n * NUM_ACTIONS);
        let mut collided = Vec::with_capacity(n * NUM_ACTIONS);
        let mut obs_state = vec![0f32; n * VECTOR_OBS_DIM];
        let mut cells = Vec::with_capacity(3 * n);
        for s in 0..n {
            let row = &mut obs_state[s * VECTOR_OBS_DIM..(s + 1) * VECTOR_OBS_DIM];
            row[OBS_TERMINAL].copy_from_slice(&model.normalised(s));
            for a in 0..NUM_ACTIONS {
                let c = base.move_collides(s, a);
                next_state.push(base.next_state(s, a) as i32);
                collided.push(c);
                row[OBS_FLAGS.start + a] = if c { 1.0 } else { 0.0 };
            }
            cells.extend_from_slice(&base.cell_of(s));
        }

        // Eq. 9's memory and case: the memory is the action of a colliding step (as
        // `Episode::step` keeps it); the case is the one whose example step has the same
        // collision flag and the same eq. 9 term (`GridWorld::detour_penalty`).
        let mut next_memory = Vec::with_capacity(NUM_ACTIONS * 2);
        for a in 0..NUM_ACTIONS {
            next_memory.extend([NO_MEMORY, a as u8]);
        }
        let mut reward_case = Vec::with_capacity(NUM_MEMORIES * NUM_ACTIONS * 2);
        for m in 0..NUM_MEMORIES {
            let last = (m < NUM_ACTIONS).then_some(m);
            for a in 0..NUM_ACTIONS {
                for c in [false, true] {
                    let d = base.detour_penalty(a, c, last);
                    let case = RewardCase::ALL
                        .iter()
                        .find(|k| {
                            let (ka, kc, kl) = k.example();
                            kc == c && base.detour_penalty(ka, kc, kl) == d
                        })
                        .expect("eq. 9 has a case for every step");
                    reward_case.push(*case as u8);
                }
            }
        }
        let mut obs_memory = vec![0f32; NUM_MEMORIES * VECTOR_OBS_DIM];
        for m in 0..NUM_ACTIONS {
            obs_memory[m * VECTOR_OBS_DIM + OBS_COLLIDED] = 1.0;
        }

        let target_states: Vec<usize> = if opts.random_target {
            model
                .target_candidates()
                .iter()
                .map(|&c| base.state_of(c).expect("candidates lie inside the bounds"))
                .collect()
        } else {
            vec![base.target()]
        };
        let t_count = target_states.len();
        let mut rewards = Vec::with_capacity(t_count * n * NUM_CASES);
        let mut terminates = Vec::with_capacity(t_count * n * NUM_CASES);
        let mut obs_target = vec![0f32; t_count * VECTOR_OBS_DIM];
        let mut target_cells = Vec::with_capacity(3 * t_count);
        let mut world = base.clone();
        for (i, &t) in target_states.iter().enumerate() {
            // The world with this target, as `Episode::reset` makes it.
            if t != world.target() {
                world.set_target(base.cell_of(t))?;
            }
            let (r, d_o) = (world.rewards(), world.start_distance_cells());
            for next in 0..n {
                for case in RewardCase::ALL {
                    let (a, c, last) = case.example();
                    // As `GridWorld::step`: (eq. 5 + eq. 10) + eq. 9, then `reward_scale`.
                    let at_target = next == t;
                    let d_t = world.distance_to_target_cells(next);
                    let mut reward = base_reward_of(r, c, at_target, d_o, d_t, assist);
                    if assist.detour {
                        reward += world.detour_penalty(a, c, last);
                    }
                    rewards.push((reward * scale) as f32);
                    terminates.push(!c && at_target);
                }
            }
            obs_target[i * VECTOR_OBS_DIM..(i + 1) * VECTOR_OBS_DIM][OBS_TARGET]
                .copy_from_slice(&model.normalised(t));
            target_cells.extend_from_slice(&base.cell_of(t));
        }
        Ok(EnvTables {
            num_states: n,
            num_targets: t_count,
            next_state,
            collided,
            next_memory,
            reward_case,
            rewards,
            terminates,
            obs_state,
            obs_target,
            obs_memory,
            cells,
            target_states: target_states.iter().map(|&t| t as i32).collect(),
            target_cells,
            start_state: base.start() as i32,
            max_episode_steps,
            random_target: opts.random_target,
        })
    }

    /// Bytes the arrays hold (see the module's Memory).
    pub fn bytes(&self) -> usize {
        4 * (self.next_state.len()
            + self.rewards.len()
            + self.obs_state.len()
            + self.obs_target.len()
            + self.obs_memory.len()
            + self.cells.len()
            + self.target_states.len()
            + self.target_cells.len())
            + self.collided.len()
            + self.next_memory.len()
            + self.reward_case.len()
            + self.terminates.len()
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::env::{BatchEnv, BatchOutputs};
    use crate::grid::{Assist, GridWorld};

    fn options(pairs: &[(&str, OptionValue)]) -> Options {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect()
    }

    /// The world of target index `t`, as `Episode::reset` makes it.
    fn world_of(t: &EnvTables, model: &EnvModel, ti: usize) -> GridWorld {
        let mut w = model.world().clone();
        let s = t.target_states[ti] as usize;
        if s != w.target() {
            w.set_target(w.cell_of(s)).unwrap();
        }
        w
    }

    /// Every (target, state, memory, action) of the tables against `GridWorld::step` of the
    /// world with that target, times `reward_scale`, to the bit of the f32.
    fn check_exhaustively(model: &EnvModel, t: &EnvTables) -> usize {
        let n = t.num_states;
        let scale = model.options().reward_scale;
        let assist = model.options().assist;
        let mut checked = 0;
        for ti in 0..t.num_targets {
            let w = world_of(t, model, ti);
            for s in 0..n {
                for m in 0..NUM_MEMORIES {
                    let last = (m < NUM_ACTIONS).then_some(m);
                    for a in 0..NUM_ACTIONS {
                        let want = w.step(s, a, last, assist);
                        let c = t.collided[s * 6 + a];
                        let next = t.next_state[s * 6 + a] as usize;
                        let k = t.reward_case[(m * 6 + a) * 2 + c as usize] as usize;
                        let cell = (t.num_states * ti + next) * NUM_CASES + k;
                        assert_eq!((next, c), (want.next, want.collided));
                        assert_eq!(
                            t.rewards[cell].to_bits(),
                            ((want.reward * scale) as f32).to_bits(),
                            "target {ti} state {s} memory {m} action {a}"
                        );
                        assert_eq!(t.terminates[cell], want.reached);
                        let m2 = t.next_memory[a * 2 + c as usize];
                        assert_eq!(m2, if want.collided { a as u8 } else { NO_MEMORY });
                        checked += 1;
                    }
                }
            }
        }
        checked
    }

    #[test]
    fn tables_equal_the_grid_worlds_step_everywhere() {
        let s = Scenario::builtin("paper_simple").unwrap();
        for opts in [
            options(&[]),
            options(&[("random_target", OptionValue::Bool(true))]),
            options(&[
                ("assist", OptionValue::Bool(false)),
                ("reward_scale", OptionValue::Float(1e-4)),
                ("arm_aware", OptionValue::Bool(true)),
            ]),
        ] {
            let (eo, _) = env_options_of(&s, &opts).unwrap();
            let model = EnvModel::new(&s, eo).unwrap();
            let t = EnvTables::new(&s, &opts).unwrap();
            let checked = check_exhaustively(&model, &t);
            assert_eq!(checked, t.num_targets * t.num_states * NUM_MEMORIES * 6);
            assert!(t.terminates.iter().any(|&b| b));
        }
    }

    #[test]
    fn random_target_covers_the_candidates() {
        let s = Scenario::builtin("paper_simple").unwrap();
        let t =
            EnvTables::new(&s, &options(&[("random_target", OptionValue::Bool(true))])).unwrap();
        assert_eq!(t.num_targets, s_free(&s) - 1);
        assert!(!t.target_states.contains(&t.start_state));
        assert_eq!(t.max_episode_steps, s.learning.max_steps_per_episode);
        let fixed = EnvTables::new(&s, &Options::new()).unwrap();
        assert_eq!(fixed.num_targets, 1);
        assert_eq!(fixed.target_cells, s.target.to_vec());
        for x in [&fixed, &t] {
            let (n, nt) = (x.num_states, x.num_targets);
            assert_eq!(x.bytes(), 94 * n + 68 * nt + 20 * n * nt + 460);
        }
        assert!(fixed.bytes() < 70_000, "{}", fixed.bytes());
        assert!(t.bytes() < 5_500_000, "{}", t.bytes());
    }

    fn s_free(s: &Scenario) -> usize {
        GridWorld::new(s).unwrap().free_cells().len()
    }

    #[test]
    fn options_are_checked_by_the_env_table() {
        let s = Scenario::builtin("paper_simple").unwrap();
        let cases = [
            ("reward_scale", OptionValue::Float(-1.0), "reward_scale"),
            (
                "max_episode_steps",
                OptionValue::Int(0),
                "max_episode_steps",
            ),
            ("random_target", OptionValue::Int(1), "random_target"),
            ("num_envs", OptionValue::Int(4), "num_envs"),
        ];
        for (k, v, name) in cases {
            let err = EnvTables::new(&s, &options(&[(k, v)])).unwrap_err();
            assert!(err.to_string().contains(name), "{err}");
        }
        let t = EnvTables::new(
            &s,
            &options(&[
                ("max_episode_steps", OptionValue::Int(7)),
                ("assist", OptionValue::Bool(false)),
            ]),
        )
        .unwrap();
        assert_eq!(t.max_episode_steps, 7);
        let (eo, _) =
            env_options_of(&s, &options(&[("assist", OptionValue::Bool(false))])).unwrap();
        assert_eq!(eo.assist, Assist::off());
    }

    /// The tables stepped by look-ups only, against the batch env over random steps: same
    /// cells, flags, rewards (f32), terminations, truncations and observations.
    #[test]
    fn table_steps_follow_the_batch_env() {
        let s = Scenario::builtin("paper_simple").unwrap();
        let opts = options(&[
            ("random_target", OptionValue::Bool(true)),
            ("max_episode_steps", OptionValue::Int(40)),
        ]);
        let (eo, cap) = env_options_of(&s, &opts).unwrap();
        let t = EnvTables::new(&s, &opts).unwrap();
        let model = Arc::new(EnvModel::new(&s, eo).unwrap());
        let n = 8;
        let mut b = BatchEnv::new(model, n, cap).unwrap();
        b.seed(&(0..n as u64).collect::<Vec<_>>()).unwrap();
        let mut out = BatchOutputs::new(n, false);
        let target_index = |b: &BatchEnv, i: usize| {
            let ts = b.episodes()[i].target() as i32;
            t.target_states.iter().position(|&x| x == ts).unwrap()
        };
        let table_obs = |s: usize, m: usize, ti: usize| -> Vec<f32> {
            (0..VECTOR_OBS_DIM)
                .map(|j| {
                    t.obs_state[s * 13 + j] + t.obs_target[ti * 13 + j] + t.obs_memory[m * 13 + j]
                })
                .collect()
        };
        b.reset(None, out.buffers()).unwrap();
        let mut st: Vec<(usize, usize, usize, u32)> = (0..n)
            .map(|i| {
                (
                    t.start_state as usize,
                    NO_MEMORY as usize,
                    target_index(&b, i),
                    0,
                )
            })
            .collect();
        let mut done = vec![false; n];
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let (mut compared, mut terms, mut truncs, mut hits) = (0, 0, 0, 0);
        for _ in 0..3000 {
            let actions: Vec<u8> = (0..n).map(|_| rng.random_range(0..6u8)).collect();
            b.step(&actions, out.buffers()).unwrap();
            for i in 0..n {
                if done[i] {
                    // Next-step autoreset: the batch drew a new target.
                    done[i] = false;
                    st[i] = (
                        t.start_state as usize,
                        NO_MEMORY as usize,
                        target_index(&b, i),
                        0,
                    );
                } else {
                    let (s0, m, ti, steps) = st[i];
                    let a = actions[i] as usize;
                    let c = t.collided[s0 * 6 + a];
                    let next = t.next_state[s0 * 6 + a] as usize;
                    let k = t.reward_case[(m * 6 + a) * 2 + c as usize] as usize;
                    let idx = (ti * t.num_states + next) * NUM_CASES + k;
                    let term = t.terminates[idx];
                    let trunc = !term && steps + 1 >= t.max_episode_steps;
                    assert_eq!(c, out.collided[i]);
                    assert_eq!(t.rewards[idx], out.rewards[i] as f32);
                    assert_eq!((term, trunc), (out.terminated[i], out.truncated[i]));
                    assert_eq!(
                        &t.cells[next * 3..next * 3 + 3],
                        &out.cells[3 * i..3 * i + 3]
                    );
                    st[i] = (
                        next,
                        t.next_memory[a * 2 + c as usize] as usize,
                        ti,
                        steps + 1,
                    );
                    done[i] = term || trunc;
                    compared += 1;
                    terms += term as usize;
                    truncs += trunc as usize;
                    hits += c as usize;
                }
                let (s1, m1, t1, _) = st[i];
                assert_eq!(
                    table_obs(s1, m1, t1),
                    out.obs_vector[i * 13..(i + 1) * 13].to_vec()
                );
            }
        }
        assert!(compared > 20_000, "{compared}");
        assert!(
            terms > 0 && truncs > 0 && hits > 0,
            "{terms} {truncs} {hits}"
        );
    }
}
