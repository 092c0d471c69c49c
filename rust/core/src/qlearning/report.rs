//! What a training run reports, serialised once: [`TrainReport`] is the JSON of
//! `sixaxis train` and of Python's `TrainResult.to_dict()`.

use serde::{Deserialize, Serialize};

use super::learner::{Checkpoint, TrainResult};
use crate::grid::GridWorld;
use crate::scenario::{Assist, Cell, EpsilonSchedule, InitialQ, Learning, QPrecision, Scenario};

/// What a training run reports: the options it ran with and what it learned, the one
/// serialisation of a run (the JSON of `sixaxis train` and Python's `TrainResult.to_dict()`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainReport {
    /// The scenario's name.
    pub scenario: String,
    /// Seed of the run's generator.
    pub seed: u64,
    /// Episodes asked for (the cap with `episodes_auto`).
    pub episodes: u32,
    /// Whether the run stopped when the greedy path settled (`episodes = "auto"`).
    pub episodes_auto: bool,
    /// The env-step budget (0: none).
    #[serde(default)]
    pub max_env_steps: u64,
    /// What epsilon fell over.
    #[serde(default)]
    pub epsilon_schedule: EpsilonSchedule,
    /// How the Q-table started.
    pub initial_q: InitialQ,
    /// The type of the Q-values.
    pub q_precision: QPrecision,
    /// Size of the Q-table's values, bytes.
    pub q_table_bytes: usize,
    /// Episodes run.
    pub episodes_run: usize,
    /// Environment steps up to and including the converged episode; `None` without one.
    pub steps_to_converged: Option<u64>,
    /// The assisted strategies of the run (eqs. 9 and 10).
    pub assist: Assist,
    /// Whether the learned path reaches the target.
    pub reached: bool,
    /// The learned path, start..=target (cells); `None` if it fails.
    pub path: Option<Vec<Cell>>,
    /// Moves of the learned path.
    pub path_length: Option<usize>,
    /// Moves of the shortest (BFS) path; `None` if the target is unreachable.
    pub shortest_path_length: Option<usize>,
    /// See [`TrainResult::converged_episode`].
    pub converged_episode: Option<u32>,
    /// See [`TrainResult::length_converged_episode`].
    pub length_converged_episode: Option<u32>,
    /// Environment steps over all episodes.
    pub total_steps: u64,
    /// Wall time of the run, s.
    pub wall_time_s: f64,
    /// `total_steps / wall_time_s`, environment steps per second (0 for no time).
    pub steps_per_second: f64,
    /// Steps of each episode (left out of a report without curves).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps_per_episode: Option<Vec<u32>>,
    /// Whether each episode reached the target (left out of a report without curves).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reached_per_episode: Option<Vec<bool>>,
    /// The checkpoints recorded ([`super::train_with_checkpoints`]; left out when none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub checkpoints: Vec<Checkpoint>,
}

impl TrainReport {
    /// The report of run `r` with options `opts` on `world` (of scenario `s`); `curves`
    /// keeps the per-episode figures.
    pub fn new(
        s: &Scenario,
        world: &GridWorld,
        opts: &Learning,
        r: &TrainResult,
        curves: bool,
    ) -> Self {
        TrainReport {
            scenario: s.name.clone(),
            seed: opts.seed,
            episodes: opts.episodes,
            episodes_auto: opts.episodes_auto,
            max_env_steps: opts.max_env_steps,
            epsilon_schedule: opts.epsilon_schedule,
            initial_q: opts.initial_q,
            q_precision: opts.q_precision,
            q_table_bytes: r.q.num_states() * r.q.bytes_per_state(),
            episodes_run: r.steps_per_episode.len(),
            steps_to_converged: r.converged_episode.map(|e| {
                r.steps_per_episode[..=e as usize]
                    .iter()
                    .map(|&k| k as u64)
                    .sum()
            }),
            assist: opts.assist(),
            reached: r.path.is_some(),
            path: r.path.clone(),
            path_length: r.path.as_ref().map(|p| p.len() - 1),
            shortest_path_length: world.shortest_path().map(|p| p.len() - 1),
            converged_episode: r.converged_episode,
            length_converged_episode: r.length_converged_episode,
            total_steps: r.total_steps,
            wall_time_s: r.wall_time_s,
            steps_per_second: if r.wall_time_s > 0.0 {
                r.total_steps as f64 / r.wall_time_s
            } else {
                0.0
            },
            steps_per_episode: curves.then(|| r.steps_per_episode.clone()),
            reached_per_episode: curves.then(|| r.reached_per_episode.clone()),
            checkpoints: r.checkpoints.clone(),
        }
    }
}
