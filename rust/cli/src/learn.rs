//! `sixaxis train` and `sixaxis plan`.

use std::path::PathBuf;

use clap::Args;
use serde_json::{json, Value};
use sixaxis_core::grid::GridWorld;
use sixaxis_core::qlearning::{train, QTable, TrainOptions, TrainResult};
use sixaxis_core::replanning::{plan, BfsLearner, PlanResult};
use sixaxis_core::request::{
    parse_episodes, parse_int, LearnerKind, PlanRequest, TrainRequest, EPISODE_CAP, MAX_REPLANS,
    MAX_STEPS, SEED,
};
use sixaxis_core::Scenario;

use crate::progress;
use crate::Failure;

/// Learning options shared by `train` and `plan`. Integers are taken as text and checked by
/// the core's request layer, so a bad value gets the same error as from Python.
#[derive(Args, Debug, Clone)]
pub struct LearnArgs {
    /// Scenario file or built-in name (paper_simple, paper_complex, replan_clutter).
    #[arg(long, value_name = "NAME_OR_FILE", default_value = "paper_simple")]
    pub scenario: String,
    /// Seed of the learner's random generator (default: the scenario's `learning.seed`).
    #[arg(long, allow_hyphen_values = true)]
    pub seed: Option<String>,
    /// Learning episodes (default: the scenario's `learning.episodes`, the paper's 10000), or
    /// `auto`: train until the greedy path reaches the target and stops changing, under
    /// `--episode-cap` (epsilon follows the run; see docs/SCENARIOS.md).
    #[arg(long, value_name = "N|auto", allow_hyphen_values = true)]
    pub episodes: Option<String>,
    /// Episode cap of `--episodes auto` (default 1000000).
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub episode_cap: Option<String>,
    /// Step cap of an episode (default: the scenario's `learning.max_steps_per_episode`).
    #[arg(long, allow_hyphen_values = true)]
    pub max_steps_per_episode: Option<String>,
    /// Turn both assisted strategies off (eq. 5 rewards alone).
    #[arg(long, conflicts_with = "assist")]
    pub no_assist: bool,
    /// Turn both assisted strategies on (eqs. 9 and 10), whatever the scenario says.
    #[arg(long)]
    pub assist: bool,
    /// Turn detour encouraging (eq. 9) off.
    #[arg(long, conflicts_with = "detour")]
    pub no_detour: bool,
    /// Turn detour encouraging (eq. 9) on.
    #[arg(long)]
    pub detour: bool,
    /// Turn distance assistance (eq. 10) off.
    #[arg(long, conflicts_with = "distance")]
    pub no_distance: bool,
    /// Turn distance assistance (eq. 10) on.
    #[arg(long)]
    pub distance: bool,
    /// How the Q-table starts: zero (the paper) or distance (an optimistic bound from the
    /// Manhattan distance to the target; see docs/SCENARIOS.md). Default: the scenario's
    /// `learning.initial_q`.
    #[arg(long, value_name = "zero|distance")]
    pub initial_q: Option<String>,
    /// The type of the Q-values: f64 (the default) or f32 (half the memory per state; see
    /// docs/SCENARIOS.md). Default: the scenario's `learning.q_precision`.
    #[arg(long, value_name = "f64|f32")]
    pub q_precision: Option<String>,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

/// `Some(true)` for `--on`, `Some(false)` for `--no-on`, `None` for neither.
fn switch(on: bool, off: bool) -> Option<bool> {
    (on || off).then_some(on)
}

impl LearnArgs {
    /// The training request these flags make (nothing resolved yet).
    pub fn request(&self) -> Result<TrainRequest, Failure> {
        let int = |domain, text: &Option<String>| -> Result<Option<i128>, Failure> {
            Ok(text.as_deref().map(|t| parse_int(domain, t)).transpose()?)
        };
        let (episodes, auto) = match self.episodes.as_deref() {
            Some(t) => parse_episodes(t)?,
            None => (None, false),
        };
        Ok(TrainRequest {
            episodes,
            episodes_auto: auto.then_some(true),
            episode_cap: int(EPISODE_CAP, &self.episode_cap)?,
            seed: int(SEED, &self.seed)?,
            assist: switch(self.assist, self.no_assist),
            detour: switch(self.detour, self.no_detour),
            distance: switch(self.distance, self.no_distance),
            max_steps_per_episode: int(MAX_STEPS, &self.max_steps_per_episode)?,
            initial_q: self.initial_q.clone(),
            q_precision: self.q_precision.clone(),
        })
    }

    /// The scenario and the learning options these flags ask for.
    pub fn resolve(&self) -> Result<(Scenario, TrainOptions), Failure> {
        let s = Scenario::load(&self.scenario)?;
        let opts = self.request()?.resolve(&s)?;
        Ok((s, opts))
    }
}

/// Flags of `sixaxis train`.
#[derive(Args, Debug, Clone)]
pub struct TrainArgs {
    #[command(flatten)]
    pub learn: LearnArgs,
    /// Start from this saved Q-table instead of zeros (resume); a table of the other
    /// precision is converted to the run's (`--q-precision`).
    #[arg(long, value_name = "FILE", conflicts_with = "initial_q")]
    pub q_in: Option<PathBuf>,
    /// Save the learned Q-table here (atomically).
    #[arg(long, value_name = "FILE")]
    pub q_out: Option<PathBuf>,
    /// Leave the per-episode step counts out of the JSON.
    #[arg(long)]
    pub no_curve: bool,
}

/// JSON of a training run (shared with `reproduce`).
pub fn train_json(
    s: &Scenario,
    world: &GridWorld,
    opts: &TrainOptions,
    r: &TrainResult,
    curve: bool,
) -> Value {
    let shortest = world.shortest_path().map(|p| p.len() - 1);
    let mut v = json!({
        "scenario": s.name,
        "seed": opts.seed,
        "episodes": opts.episodes,
        "episodes_auto": opts.episodes_auto,
        "initial_q": opts.initial_q.name(),
        "q_precision": opts.q_precision.name(),
        "q_table_bytes": r.q.num_states() * r.q.bytes_per_state(),
        "episodes_run": r.steps_per_episode.len(),
        "steps_to_converged": r.converged_episode.map(|e| {
            r.steps_per_episode[..=e as usize].iter().map(|&k| k as u64).sum::<u64>()
        }),
        "assist": opts.assist,
        "reached": r.path.is_some(),
        "path": r.path,
        "path_length": r.path.as_ref().map(|p| p.len() - 1),
        "shortest_path_length": shortest,
        "converged_episode": r.converged_episode,
        "length_converged_episode": r.length_converged_episode,
        "total_steps": r.total_steps,
        "wall_time_s": r.wall_time_s,
        "steps_per_second": if r.wall_time_s > 0.0 { r.total_steps as f64 / r.wall_time_s } else { 0.0 },
    });
    if curve {
        v["steps_per_episode"] = json!(r.steps_per_episode);
    }
    v
}

/// `sixaxis train`.
pub fn run_train(a: &TrainArgs) -> Result<Value, Failure> {
    let (s, opts) = a.learn.resolve()?;
    let world = GridWorld::new(&s)?;
    let initial = match &a.q_in {
        Some(p) => Some(QTable::load(p, &world)?),
        None => None,
    };
    let pb = progress::bar(opts.episodes as u64, "learning", a.learn.quiet);
    let tick = |done: u32| pb.set_position(done as u64);
    let r = train(&world, &opts, initial, Some(&tick))?;
    pb.finish_and_clear();
    if let Some(p) = &a.q_out {
        crate::interrupt::writing(|| r.q.save(p, &world))?;
    }
    Ok(train_json(&s, &world, &opts, &r, !a.no_curve))
}

/// Flags of `sixaxis plan`.
#[derive(Args, Debug, Clone)]
pub struct PlanArgs {
    #[command(flatten)]
    pub learn: LearnArgs,
    /// Re-plans allowed before giving up (default: the scenario's `planning.max_replans`).
    #[arg(long, allow_hyphen_values = true)]
    pub max_replans: Option<String>,
    /// The path learner of every round: qlearning (the paper's, default) or bfs.
    #[arg(long, value_name = "NAME")]
    pub learner: Option<String>,
}

/// `sixaxis plan`: Algorithm 2.
pub fn run_plan(a: &PlanArgs) -> Result<PlanResult, Failure> {
    let s = Scenario::load(&a.learn.scenario)?;
    let req = PlanRequest {
        train: a.learn.request()?,
        max_replans: a
            .max_replans
            .as_deref()
            .map(|t| parse_int(MAX_REPLANS, t))
            .transpose()?,
        learner: a.learner.clone(),
    };
    let (opts, learner) = req.resolve(&s)?;
    let pb = progress::bar(opts.train.episodes as u64, "round 0", a.learn.quiet);
    let tick = |round: u32, done: u32| {
        pb.set_prefix(format!("round {round}"));
        pb.set_position(done as u64);
    };
    let r = match learner {
        LearnerKind::Qlearning => plan(&s, &opts, None, Some(&tick))?,
        LearnerKind::Bfs => plan(&s, &opts, Some(&mut BfsLearner), Some(&tick))?,
    };
    pb.finish_and_clear();
    Ok(r)
}
