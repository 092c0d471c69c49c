//! `sixaxis train` and `sixaxis plan`.

use std::path::PathBuf;

use clap::Args;
use sixaxis_core::grid::GridWorld;
use sixaxis_core::qlearning::{train, Learning, QTable, TrainReport};
use sixaxis_core::replanning::{plan, BfsLearner, PlanResult};
use sixaxis_core::request::{LearnerKind, PlanRequest, TrainRequest};
use sixaxis_core::Scenario;

use crate::flags::{PlanFlags, TrainFlags};
use crate::progress;
use crate::Failure;

/// Learning options shared by `train` and `plan`: one flag per option of the core's table
/// ([`sixaxis_core::request::train_options`]), checked by the core's request layer, so a bad
/// value gets the same error as from Python.
#[derive(Args, Debug, Clone)]
pub struct LearnArgs {
    /// Scenario file or built-in name (paper_simple, paper_complex, replan_clutter).
    #[arg(long, value_name = "NAME_OR_FILE", default_value = "paper_simple")]
    pub scenario: String,
    #[command(flatten)]
    pub options: TrainFlags,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

impl LearnArgs {
    /// The training request these flags make (nothing resolved yet).
    pub fn request(&self) -> Result<TrainRequest, Failure> {
        Ok(TrainRequest(self.options.options()?))
    }

    /// The scenario and the learning options these flags ask for.
    pub fn resolve(&self) -> Result<(Scenario, Learning), Failure> {
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

/// `sixaxis train`.
pub fn run_train(a: &TrainArgs) -> Result<TrainReport, Failure> {
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
    Ok(TrainReport::new(&s, &world, &opts, &r, !a.no_curve))
}

/// Flags of `sixaxis plan`.
#[derive(Args, Debug, Clone)]
pub struct PlanArgs {
    #[command(flatten)]
    pub learn: LearnArgs,
    #[command(flatten)]
    pub plan: PlanFlags,
}

/// `sixaxis plan`: Algorithm 2.
pub fn run_plan(a: &PlanArgs) -> Result<PlanResult, Failure> {
    let s = Scenario::load(&a.learn.scenario)?;
    let mut options = a.learn.request()?.0;
    options.extend(a.plan.options()?);
    let req = PlanRequest(options);
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
