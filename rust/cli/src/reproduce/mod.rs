//! `sixaxis reproduce`: the paper's experiments (simple and complex obstacles, with and
//! without assisted learning, over several seeds) plus our own re-plan scenario, each
//! planned (Algorithm 2) in three modes side by side: the paper's Algorithm 1 as written
//! (greedy, n_d doubles on a re-plan), our backtracking search (n_d fixed) and the greedy
//! pass with n_d fixed.
//!
//! Writes `reproduction.json` into `--out-dir`, draws the figures with
//! `scripts/reproduce_figures.py` (matplotlib) and writes the report `docs/REPRODUCTION.md`.
//! The seeds of one condition are independent runs: they run in parallel on all cores
//! (rayon) and are gathered in seed order, so every figure but the wall times is the same as
//! on one thread (`RAYON_NUM_THREADS=1`); a run's wall time is measured inside it, under
//! the load of the others.
//!
//! - this module — the flags and the runs: every run's options come from the core's request
//!   layer ([`TrainRequest`], [`PlanRequest`]), so `--episodes` is checked as `sixaxis train`'s.
//! - [`results`] — the typed results, serialised once as `reproduction.json`.
//! - [`stats`] — means and standard deviations over seeds.
//! - [`report`] — the figures and the Markdown report.

mod report;
mod results;
mod stats;

use std::path::PathBuf;

use clap::Args;
use rayon::prelude::*;
use serde::Serialize;
use sixaxis_core::grid::GridWorld;
use sixaxis_core::options::OptionValue;
use sixaxis_core::qlearning::{train, TrainReport};
use sixaxis_core::replanning::plan;
use sixaxis_core::request::{train_options, PlanRequest, TrainRequest};
use sixaxis_core::{Error, Scenario};

use crate::progress;
use crate::Failure;
pub use results::SummaryRow;
use results::{Condition, Mode, Modes, PlanSummary, Reproduction, ScenarioResult, SeedPlans};
use stats::ConditionStats;

/// Flags of `sixaxis reproduce`.
#[derive(Args, Debug, Clone)]
pub struct ReproduceArgs {
    /// Scenarios to run (built-in names, files or generated:SEED), comma-separated;
    /// generated:A..B stands for generated:A, ..., generated:B.
    #[arg(long, default_value = "paper_simple,paper_complex,replan_clutter")]
    pub scenarios: String,
    /// Seeds 0..N per experiment.
    #[arg(long, default_value_t = 10)]
    pub seeds: u64,
    /// Learning episodes per run, a number or `auto`, as `sixaxis train --episodes`
    /// (default: each scenario's, the paper's 10000).
    #[arg(long, value_name = "N|auto", allow_hyphen_values = true)]
    pub episodes: Option<String>,
    /// Where the JSON and the figures go.
    #[arg(long, default_value = "results/reproduce")]
    pub out_dir: PathBuf,
    /// Where the report goes.
    #[arg(long, default_value = "docs/REPRODUCTION.md")]
    pub report: PathBuf,
    /// The figure script (Python with matplotlib).
    #[arg(long, default_value = "scripts/reproduce_figures.py")]
    pub figures_script: PathBuf,
    /// Python interpreter for the figure script.
    #[arg(long, default_value = "python3")]
    pub python: String,
    /// Skip the figures (JSON and report only).
    #[arg(long)]
    pub no_figures: bool,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

impl ReproduceArgs {
    /// `--episodes` parsed as the request layer's `episodes` option.
    fn episodes(&self) -> Result<Option<OptionValue>, Failure> {
        let Some(text) = &self.episodes else {
            return Ok(None);
        };
        let info = train_options()
            .into_iter()
            .find(|i| i.key == "episodes")
            .expect("training has an `episodes` option");
        Ok(Some(info.domain.parse_text(info.key, text)?))
    }
}

/// The options shared by every run of one seed: the seed, assistance and `--episodes`.
fn request(seed: u64, assist: bool, episodes: &Option<OptionValue>) -> TrainRequest {
    let req = TrainRequest::default()
        .with("seed", seed)
        .with("assist", assist);
    match episodes {
        Some(n) => req.with("episodes", n.clone()),
        None => req,
    }
}

/// One learning condition over all seeds, learned in parallel (see the module docs).
fn learn_condition(
    s: &Scenario,
    world: &GridWorld,
    assist: bool,
    seeds: u64,
    episodes: &Option<OptionValue>,
    pb: &indicatif::ProgressBar,
) -> Result<Condition, Failure> {
    let learned = (0..seeds)
        .into_par_iter()
        .map(|seed| -> Result<_, Failure> {
            let opts = request(seed, assist, episodes).resolve(s)?;
            let r = train(world, &opts, None, None)?;
            pb.inc(1);
            Ok((opts, r))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let curves: Vec<&[u32]> = learned
        .iter()
        .map(|(_, r)| &r.steps_per_episode[..])
        .collect();
    let runs: Vec<TrainReport> = learned
        .iter()
        .map(|(opts, r)| {
            let mut report = TrainReport::new(s, world, opts, r, opts.seed == 0);
            // The figures keep one curve of steps (seed 0's) and no per-episode success.
            report.reached_per_episode = None;
            report
        })
        .collect();
    Ok(Condition {
        assist: learned.first().map(|(o, _)| o.assist()).expect("seeds > 0"),
        stats: ConditionStats::new(&runs, &curves),
        runs,
    })
}

/// Algorithm 2 with assistance for one seed: the scenario's own planning and each mode.
fn plan_seed(
    s: &Scenario,
    seed: u64,
    episodes: &Option<OptionValue>,
) -> Result<SeedPlans, Failure> {
    let (opts, _) = PlanRequest(request(seed, true, episodes).0).resolve(s)?;
    let r = plan(s, &opts, None, None)?;
    let run = |m: Mode| -> Result<PlanSummary, Failure> {
        let v = m.apply(s);
        Ok(if v.planning == s.planning {
            PlanSummary::new(&r, v.planning.mode)
        } else {
            PlanSummary::new(&plan(&v, &opts, None, None)?, v.planning.mode)
        })
    };
    let modes = Modes {
        paper: run(Mode::Paper)?,
        backtracking: run(Mode::Backtracking)?,
        fixed_nd: run(Mode::FixedNd)?,
    };
    let first = seed == 0;
    let arm = s.arm();
    Ok(SeedPlans {
        plan: PlanSummary::new(&r, s.planning.mode),
        arm_points_mm: first.then(|| {
            r.poses_rad
                .iter()
                .map(|q| arm.points_mm(q).iter().map(|p| [p.x, p.y, p.z]).collect())
                .collect()
        }),
        result: first.then(|| r.clone()),
        modes,
    })
}

/// What `sixaxis reproduce` prints: where it wrote and a summary per scenario.
#[derive(Debug, Clone, Serialize)]
pub struct ReproduceOutput {
    pub results: PathBuf,
    pub report: PathBuf,
    pub figures: Option<PathBuf>,
    pub summary: Vec<SummaryRow>,
}

/// `sixaxis reproduce`.
pub fn run(a: &ReproduceArgs) -> Result<ReproduceOutput, Failure> {
    if a.seeds == 0 {
        return Err(Error::argument("--seeds", 0, "must be > 0").into());
    }
    let episodes = a.episodes()?;
    let names = sixaxis_core::names::expand_names(&a.scenarios)?;
    let scenarios = names
        .iter()
        .map(|n| Scenario::load(n))
        .collect::<Result<Vec<_>, _>>()?;
    let total = scenarios.len() as u64 * a.seeds * 3;
    let pb = progress::bar(total, "reproducing", a.quiet);
    let mut out = Vec::new();
    for s in &scenarios {
        pb.set_message(s.name.clone());
        let world = GridWorld::new(s)?;
        let assisted = learn_condition(s, &world, true, a.seeds, &episodes, &pb)?;
        let unassisted = learn_condition(s, &world, false, a.seeds, &episodes, &pb)?;
        let plans = (0..a.seeds)
            .into_par_iter()
            .map(|seed| {
                let p = plan_seed(s, seed, &episodes);
                pb.inc(1);
                p
            })
            .collect::<Result<Vec<_>, _>>()?;
        out.push(ScenarioResult::new(
            s,
            world.shortest_path(),
            assisted,
            unassisted,
            plans,
        ));
    }
    pb.finish_and_clear();
    let result = Reproduction {
        machine: sixaxis_core::host::machine(),
        seeds: a.seeds,
        episodes,
        build: if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        },
        scenarios: out,
    };
    std::fs::create_dir_all(&a.out_dir).map_err(|e| Error::io(&a.out_dir, e))?;
    let json_path = a.out_dir.join("reproduction.json");
    let text = serde_json::to_string(&result).expect("the results serialise");
    crate::interrupt::writing(|| sixaxis_core::io::write_atomic(&json_path, text.as_bytes()))?;
    let figures = if a.no_figures {
        None
    } else {
        Some(report::draw_figures(a, &json_path)?)
    };
    let markdown = report::markdown(&result, figures.as_deref(), &json_path);
    if let Some(dir) = a.report.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
    }
    crate::interrupt::writing(|| sixaxis_core::io::write_atomic(&a.report, markdown.as_bytes()))?;
    Ok(ReproduceOutput {
        results: json_path,
        report: a.report.clone(),
        figures,
        summary: result.scenarios.iter().map(SummaryRow::new).collect(),
    })
}
