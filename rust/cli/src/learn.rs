//! `sixaxis train` and `sixaxis plan`.

use std::path::PathBuf;

use clap::Args;
use serde_json::{json, Value};
use sixaxis_core::grid::{Assist, GridWorld};
use sixaxis_core::qlearning::{train, QTable, TrainOptions, TrainResult};
use sixaxis_core::replanning::{plan, PlanOptions, PlanResult};
use sixaxis_core::Scenario;

use crate::progress;
use crate::Failure;

/// Learning options shared by `train` and `plan`.
#[derive(Args, Debug, Clone)]
pub struct LearnArgs {
    /// Scenario file or built-in name (paper_simple, paper_complex, replan_clutter).
    #[arg(long, value_name = "NAME_OR_FILE", default_value = "paper_simple")]
    pub scenario: String,
    /// Seed of the learner's random generator (default: the scenario's `learning.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Learning episodes (default: the scenario's `learning.episodes`, the paper's 10000).
    #[arg(long)]
    pub episodes: Option<u32>,
    /// Turn both assisted strategies off (eq. 5 rewards alone).
    #[arg(long)]
    pub no_assist: bool,
    /// Turn detour encouraging (eq. 9) off.
    #[arg(long)]
    pub no_detour: bool,
    /// Turn distance assistance (eq. 10) off.
    #[arg(long)]
    pub no_distance: bool,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

impl LearnArgs {
    /// The scenario and the learning options these flags ask for.
    pub fn resolve(&self) -> Result<(Scenario, TrainOptions), Failure> {
        let s = Scenario::load(&self.scenario)?;
        let mut opts = TrainOptions::from_scenario(&s);
        if let Some(seed) = self.seed {
            opts.seed = seed;
        }
        if let Some(n) = self.episodes {
            if n == 0 {
                return Err(sixaxis_core::Error::argument("--episodes", 0, "must be > 0").into());
            }
            opts.episodes = n;
        }
        let mut assist: Assist = opts.assist;
        if self.no_assist {
            assist = Assist::off();
        }
        if self.no_detour {
            assist.detour = false;
        }
        if self.no_distance {
            assist.distance = false;
        }
        opts.assist = assist;
        Ok((s, opts))
    }
}

/// Flags of `sixaxis train`.
#[derive(Args, Debug, Clone)]
pub struct TrainArgs {
    #[command(flatten)]
    pub learn: LearnArgs,
    /// Start from this saved Q-table instead of zeros (resume).
    #[arg(long, value_name = "FILE")]
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
        "assist": opts.assist,
        "reached": r.path.is_some(),
        "path": r.path,
        "path_length": r.path.as_ref().map(|p| p.len() - 1),
        "shortest_path_length": shortest,
        "converged_episode": r.converged_episode,
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
    #[arg(long)]
    pub max_replans: Option<u32>,
}

/// `sixaxis plan`: Algorithm 2.
pub fn run_plan(a: &PlanArgs) -> Result<PlanResult, Failure> {
    let (s, train) = a.learn.resolve()?;
    let mut opts = PlanOptions::from_scenario(&s);
    opts.train = train;
    if let Some(m) = a.max_replans {
        opts.max_replans = m;
    }
    let pb = progress::bar(opts.train.episodes as u64, "round 0", a.learn.quiet);
    let tick = |round: u32, done: u32| {
        pb.set_prefix(format!("round {round}"));
        pb.set_position(done as u64);
    };
    let r = plan(&s, &opts, Some(&tick))?;
    pb.finish_and_clear();
    Ok(r)
}
