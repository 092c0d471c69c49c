//! The learner: [`train`] (eqs. 6-8 with the schedule and choices of the [`super`] module
//! docs), [`greedy_path`] (eq. 8), [`q_update`] (one update of eq. 6), [`TrainResult`].

use std::time::Instant;

use rand::{Rng, RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::initial::distance_bound_table;
use super::table::*;
use super::AUTO_MIN_HORIZON;
use crate::error::{Error, Result};
use crate::grid::{GridWorld, Transition, NUM_ACTIONS};
use crate::scenario::{Cell, EpsilonSchedule, InitialQ, Learning};

/// One update of eq. 6 for the step `state --action--> t`: bootstraps from
/// `max_a' Q(t.next, a')` unless `t.reached` (the target is terminal). Returns the new
/// Q(state, action) as stored (rounded to the nearest f32 in an f32 table). The learner
/// uses exactly this arithmetic.
pub fn q_update(
    q: &mut QTable,
    state: usize,
    action: usize,
    t: &Transition,
    alpha: f64,
    gamma: f64,
) -> f64 {
    let bootstrap = if t.reached { 0.0 } else { q.max_value(t.next) };
    let v = updated(q.get(state, action), t.reward, bootstrap, alpha, gamma);
    q.set(state, action, v);
    q.get(state, action)
}

/// The greedy path of the Q-table being learned, recorded during a run of
/// [`train_with_checkpoints`] after a given number of env steps (the run goes on).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// Env steps taken when it was recorded (over all episodes of the run).
    pub env_steps: u64,
    /// The episode (from 0) whose step was the `env_steps`-th.
    pub episode: u32,
    /// The greedy path (eq. 8, [`greedy_path`] with `max_steps_per_episode`) of the table
    /// after that step, start..=target; `None` if it fails.
    pub path: Option<Vec<Cell>>,
    /// Wall time since the call began, seconds.
    pub wall_time_s: f64,
    /// CPU time of the learning thread since the call began, seconds (`None` where the OS
    /// does not tell; see [`crate::host::thread_cpu_time_s`]).
    pub cpu_time_s: Option<f64>,
}

/// What [`train`] returns.
#[derive(Debug, Clone, Serialize)]
pub struct TrainResult {
    /// The learned path (greedy rollout, eq. 8), start..=target; `None` if it fails.
    pub path: Option<Vec<Cell>>,
    /// Steps of each episode.
    pub steps_per_episode: Vec<u32>,
    /// Whether each episode reached the target.
    pub reached_per_episode: Vec<bool>,
    /// First episode (from 0) from which the greedy path no longer changed; `None` if the
    /// final path fails.
    pub converged_episode: Option<u32>,
    /// First episode (from 0) from which the greedy path's *length* no longer changed
    /// (later changes, if any, swap equally long paths); `None` if the final path fails.
    pub length_converged_episode: Option<u32>,
    /// Environment steps over all episodes.
    pub total_steps: u64,
    /// Wall time of the call, seconds.
    pub wall_time_s: f64,
    /// The checkpoints of [`train_with_checkpoints`] the run reached, in order (empty for
    /// [`train`]).
    pub checkpoints: Vec<Checkpoint>,
    /// The learned Q-table.
    #[serde(skip)]
    pub q: QTable,
}

/// Greedy rollout from the start (ties: lowest action index), writing the visited states
/// into `out` and stamping each with `gen` in `stamp` (the visited set) and its greedy
/// action in `act`. Returns whether it reached the target.
fn rollout<V: QValue>(
    world: &GridWorld,
    q: &[[V; NUM_ACTIONS]],
    max_steps: u32,
    stamp: &mut [u32],
    act: &mut [u8],
    gen: u32,
    out: &mut Vec<u32>,
) -> bool {
    let next = world.transitions();
    let target = world.target();
    out.clear();
    let mut cur = world.start();
    out.push(cur as u32);
    stamp[cur] = gen;
    for _ in 0..max_steps {
        if cur == target {
            return true;
        }
        let a = argmax_lowest(&q[cur]);
        act[cur] = a as u8;
        let n = next[cur][a] as usize;
        if stamp[n] == gen {
            return false;
        }
        stamp[n] = gen;
        act[n] = argmax_lowest(&q[n]) as u8;
        out.push(n as u32);
        cur = n;
    }
    cur == target
}

/// The learned path (eq. 8) of a Q-table: greedy rollout from the world's start, ties
/// broken by the lowest action index, cells start..=target; `None` if the target is not
/// reached within `max_steps` steps or a cell is revisited.
pub fn greedy_path(world: &GridWorld, q: &QTable, max_steps: u32) -> Option<Vec<Cell>> {
    if q.num_states() != world.num_states() {
        return None;
    }
    let n = world.num_states();
    let mut stamp = vec![0u32; n];
    let mut act = vec![0u8; n];
    let mut out = Vec::new();
    if with_rows!(&q.rows, r => rollout(world, r, max_steps, &mut stamp, &mut act, 1, &mut out)) {
        Some(out.iter().map(|&s| world.cell_of(s as usize)).collect())
    } else {
        None
    }
}

/// Learn a Q-table on `world` (eqs. 6-7), starting from `initial_q` or zeros. `progress`
/// is called with the number of episodes done, at most about 100 times. See the module
/// docs for the exact semantics; the result is a pure function of the arguments (but
/// `wall_time_s`).
pub fn train(
    world: &GridWorld,
    opts: &Learning,
    initial_q: Option<QTable>,
    progress: Option<&dyn Fn(u32)>,
) -> Result<TrainResult> {
    train_impl(world, opts, initial_q, progress, &[], false)
}

/// [`train`], recording a [`Checkpoint`] (the greedy path of the current table, wall and
/// CPU time) when the run has taken exactly `checkpoints[i]` env steps, without stopping
/// or changing the run: its result is [`train`]'s, plus the checkpoints. A checkpoint's
/// path is that of the final path of the same run stopped there (`max_env_steps` =
/// that count, the epsilon schedule unchanged; tested). `checkpoints` must be increasing
/// counts >= 1, none beyond `max_env_steps` when it is set; those after the run's last step
/// (its episodes done first) are not recorded.
pub fn train_with_checkpoints(
    world: &GridWorld,
    opts: &Learning,
    initial_q: Option<QTable>,
    progress: Option<&dyn Fn(u32)>,
    checkpoints: &[u64],
) -> Result<TrainResult> {
    train_impl(world, opts, initial_q, progress, checkpoints, false)
}

/// Checkpoint counts are increasing, >= 1 and within the budget; the error names
/// `checkpoints` and the value.
fn check_checkpoints(checkpoints: &[u64], opts: &Learning) -> Result<()> {
    let mut last = 0u64;
    for &c in checkpoints {
        if c <= last {
            let reason = if c == 0 {
                "every checkpoint must be >= 1 env step".to_string()
            } else {
                format!("checkpoints must increase (one after {last})")
            };
            return Err(Error::argument("checkpoints", c, reason));
        }
        if opts.max_env_steps > 0 && c > opts.max_env_steps {
            return Err(Error::argument(
                "checkpoints",
                c,
                format!("is beyond max_env_steps = {}", opts.max_env_steps),
            ));
        }
        last = c;
    }
    Ok(())
}

/// [`train_with_checkpoints`]; with `rollout_every_episode` the greedy path is recomputed
/// after every episode (the reference for the incremental bookkeeping, for tests).
pub(super) fn train_impl(
    world: &GridWorld,
    opts: &Learning,
    initial_q: Option<QTable>,
    progress: Option<&dyn Fn(u32)>,
    checkpoints: &[u64],
    rollout_every_episode: bool,
) -> Result<TrainResult> {
    let started = Instant::now();
    opts.validate()?;
    check_checkpoints(checkpoints, opts)?;
    let cpu_started = if checkpoints.is_empty() {
        None
    } else {
        crate::host::thread_cpu_time_s()
    };
    let n = world.num_states();
    let q = match initial_q {
        Some(q) if q.num_states() != n => {
            return Err(Error::QTableMismatch(format!(
                "initial Q-table has {} states, world has {n}",
                q.num_states()
            )))
        }
        // A table of the other precision is converted (see the module docs).
        Some(q) => q.into_precision(opts.q_precision)?,
        None => match opts.initial_q {
            InitialQ::Zero => QTable::zeros_with(n, opts.q_precision),
            InitialQ::Distance => distance_bound_table(world, opts),
        },
    };
    // One dispatch on the value type per run; the loop itself is generic.
    Ok(
        with_rows!(q.rows, rows => learn(world, opts, rows, progress, checkpoints, rollout_every_episode, (started, cpu_started))),
    )
}

/// The episodes of [`train_impl`], learning on `rows` (the run's table); `started` is when
/// the call began and the thread's CPU time then (for `wall_time_s` and the checkpoints).
fn learn<V: QValue>(
    world: &GridWorld,
    opts: &Learning,
    mut rows: Vec<[V; NUM_ACTIONS]>,
    progress: Option<&dyn Fn(u32)>,
    checkpoints: &[u64],
    rollout_every_episode: bool,
    (started, cpu_started): (Instant, Option<f64>),
) -> TrainResult {
    let n = world.num_states();
    let qr: &mut [[V; NUM_ACTIONS]] = &mut rows;
    // Rewards, computed exactly as `GridWorld::step` does: eq. 5 by kind of move
    // (plain, collision, reaching), plus eq. 10 by new state, plus eq. 9.
    let assist = opts.assist();
    let rw = world.rewards();
    let eq5 = [-rw.step_penalty, -rw.collision_penalty, rw.target_reward];
    let distance = assist.distance;
    let eq10: Vec<f64> = (0..n)
        .map(|s| {
            rw.distance_reward * (world.start_distance_cells() - world.distance_to_target_cells(s))
        })
        .collect();
    let detour = assist.detour;
    let repeat_pen = -world.rewards().repeat_collision_penalty;
    let reverse_pen = -world.rewards().reverse_after_collision_penalty;

    let next = world.transitions();
    let start = world.start();
    let target = world.target();
    let (alpha, gamma) = (opts.alpha, opts.gamma);
    let max_steps = opts.max_steps_per_episode;
    let episodes = opts.episodes;
    let chunk = episodes.div_ceil(100).max(1);
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);

    // The env-step budget (none: never reached), and the next step count at which the run
    // stops or records a checkpoint.
    let budget = if opts.max_env_steps > 0 {
        opts.max_env_steps
    } else {
        u64::MAX
    };
    let mut next_checkpoint = 0usize;
    let next_stop_of = |i: usize| checkpoints.get(i).map_or(budget, |&c| c.min(budget));
    let mut next_stop = next_stop_of(0);
    let mut recorded = Vec::with_capacity(checkpoints.len());
    let (mut cp_stamp, mut cp_act, mut cp_path) = (Vec::new(), Vec::new(), Vec::new());
    let mut cp_gen = 0u32;
    if !checkpoints.is_empty() {
        cp_stamp = vec![0u32; n];
        cp_act = vec![0u8; n];
    }
    let per_step_epsilon = opts.epsilon_schedule == EpsilonSchedule::EnvSteps;
    // A fixed run knows its length (at most); an auto run grows its vectors as it goes.
    let reserve = if opts.episodes_auto {
        0
    } else {
        (episodes as u64).min(budget) as usize
    };
    let mut steps_per_episode = Vec::with_capacity(reserve);
    let mut reached_per_episode = Vec::with_capacity(reserve);
    // episodes_auto: the episode after which the greedy path first reached the target.
    let mut first_reach: Option<u32> = None;
    // Env steps over all episodes so far (the step being taken is the `t`-th, from 0).
    let mut t = 0u64;
    let mut out_of_budget = false;

    // Greedy-path tracking for the converged episode.
    let mut stamp = vec![0u32; n];
    let mut act = vec![0u8; n];
    let mut gen = 1u32;
    let mut path = Vec::new();
    let mut path_ok = rollout(world, qr, max_steps, &mut stamp, &mut act, gen, &mut path);
    let mut new_path = Vec::new();
    let mut last_change = 0u32;
    let mut last_length_change = 0u32;

    const NO_ACTION: usize = usize::MAX;
    for ep in 0..episodes {
        // Explore when a uniform u32 is below epsilon * 2^32 (i.e. u < epsilon for
        // u = k / 2^32 uniform in [0, 1)).
        let epsilon = if opts.episodes_auto {
            match first_reach {
                None => opts.epsilon_start,
                Some(e1) => {
                    let h = (e1 + 1).max(AUTO_MIN_HORIZON);
                    let k = ep - e1;
                    if k >= h {
                        0.0
                    } else {
                        opts.epsilon_start * (1.0 - k as f64 / h as f64)
                    }
                }
            }
        } else {
            opts.epsilon(ep)
        };
        let mut explore_threshold = (epsilon * 4_294_967_296.0).ceil() as u64;
        let mut s = start;
        let mut last_collided = NO_ACTION;
        let mut steps = 0u32;
        let mut reached = false;
        let mut dirty = rollout_every_episode;
        // max_a Q(s, a), carried from the previous step's bootstrap when still valid.
        let mut s_max = row_max(&qr[s]);
        while steps < max_steps {
            if per_step_epsilon {
                explore_threshold = (opts.epsilon_at_step(t) * 4_294_967_296.0).ceil() as u64;
            }
            // Action selection (eq. 7).
            let a = if explore_threshold > 0 && (rng.next_u32() as u64) < explore_threshold {
                rng.random_range(0..NUM_ACTIONS as u32) as usize
            } else {
                let mask = mask_of(&qr[s], s_max);
                if mask & (mask - 1) == 0 {
                    mask.trailing_zeros() as usize
                } else {
                    nth_set_bit(mask, rng.random_range(0..mask.count_ones()))
                }
            };
            // Environment step (eqs. 5, 9, 10).
            let ns = next[s][a] as usize;
            let collided = ns == s;
            reached = ns == target && !collided;
            let mut reward = eq5[collided as usize + 2 * reached as usize];
            if distance {
                reward += eq10[ns];
            }
            if detour && last_collided != NO_ACTION {
                if collided {
                    reward += repeat_pen;
                } else if a ^ 1 == last_collided {
                    reward += reverse_pen;
                }
            }
            // Q-update (eq. 6), in f64 whatever the stored type.
            let next_max = row_max(&qr[ns]);
            let bootstrap = if reached { 0.0 } else { next_max.to_f64() };
            let old = qr[s][a].to_f64();
            qr[s][a] = V::from_f64(updated(old, reward, bootstrap, alpha, gamma));
            if !dirty && stamp[s] == gen && argmax_lowest(&qr[s]) != act[s] as usize {
                dirty = true;
            }
            // On a collision ns == s and its row just changed; otherwise row ns is untouched.
            s_max = if collided { row_max(&qr[s]) } else { next_max };
            last_collided = if collided { a } else { NO_ACTION };
            steps += 1;
            s = ns;
            t += 1;
            if t == next_stop {
                if next_checkpoint < checkpoints.len() && checkpoints[next_checkpoint] == t {
                    // A fresh rollout on scratch buffers: the tracked path's stamps stay.
                    cp_gen += 1;
                    let (stamp, act) = (&mut cp_stamp, &mut cp_act);
                    let ok = rollout(world, qr, max_steps, stamp, act, cp_gen, &mut cp_path);
                    recorded.push(Checkpoint {
                        env_steps: t,
                        episode: ep,
                        path: ok
                            .then(|| cp_path.iter().map(|&c| world.cell_of(c as usize)).collect()),
                        wall_time_s: started.elapsed().as_secs_f64(),
                        cpu_time_s: cpu_started
                            .and_then(|c0| crate::host::thread_cpu_time_s().map(|c| c - c0)),
                    });
                    next_checkpoint += 1;
                }
                if t == budget {
                    out_of_budget = true;
                    break;
                }
                next_stop = next_stop_of(next_checkpoint);
            }
            if reached {
                break;
            }
        }
        steps_per_episode.push(steps);
        reached_per_episode.push(reached);
        if dirty {
            if gen == u32::MAX {
                stamp.fill(0);
                gen = 0;
            }
            gen += 1;
            let ok = rollout(
                world,
                qr,
                max_steps,
                &mut stamp,
                &mut act,
                gen,
                &mut new_path,
            );
            let same = ok == path_ok && (!ok || new_path == path);
            if !same {
                last_change = ep;
                if ok != path_ok || (ok && new_path.len() != path.len()) {
                    last_length_change = ep;
                }
            }
            std::mem::swap(&mut path, &mut new_path);
            path_ok = ok;
        }
        if let Some(p) = progress {
            if (ep + 1) % chunk == 0 || ep + 1 == episodes || out_of_budget {
                p(ep + 1);
            }
        }
        if opts.episodes_auto && path_ok {
            let e1 = *first_reach.get_or_insert(ep);
            let h = (e1 + 1).max(AUTO_MIN_HORIZON);
            if ep >= e1 + h && ep - last_change >= h {
                break;
            }
        }
        if out_of_budget {
            break;
        }
    }

    let final_path = if path_ok {
        Some(path.iter().map(|&s| world.cell_of(s as usize)).collect())
    } else {
        None
    };
    TrainResult {
        path: final_path,
        steps_per_episode,
        reached_per_episode,
        converged_episode: path_ok.then_some(last_change),
        length_converged_episode: path_ok.then_some(last_length_change),
        total_steps: t,
        wall_time_s: started.elapsed().as_secs_f64(),
        checkpoints: recorded,
        q: QTable {
            rows: V::wrap(rows),
        },
    }
}
