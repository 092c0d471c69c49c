//! The typed results of `sixaxis reproduce`, serialised once as `reproduction.json` (read by
//! `scripts/reproduce_figures.py`) and read by the report ([`super::report`]).
//!
//! - [`Reproduction`] — the whole file: the machine, the run's settings and one
//!   [`ScenarioResult`] per scenario.
//! - [`Condition`] — one learning condition over all seeds: the runs ([`TrainReport`], the
//!   core's one serialisation of a run) and their [`ConditionStats`].
//! - [`SeedPlans`] — Algorithm 2 for one seed: the scenario's own planning ([`PlanSummary`],
//!   with the full [`PlanResult`] for seed 0) and each [`Mode`] side by side ([`Modes`]).

use serde::{Serialize, Serializer};
use sixaxis_core::grid::Assist;
use sixaxis_core::options::OptionValue;
use sixaxis_core::qlearning::TrainReport;
use sixaxis_core::replanning::PlanResult;
use sixaxis_core::scenario::{Bounds, Cell, Planning, PoseSearchMode};
use sixaxis_core::Scenario;

use super::stats::ConditionStats;

/// `reproduction.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Reproduction {
    /// The machine the runs ran on ([`sixaxis_core::host::machine`]).
    pub machine: String,
    /// Seeds 0..N per condition.
    pub seeds: u64,
    /// `--episodes` as given (a number or `"auto"`); `null` for each scenario's own.
    pub episodes: Option<OptionValue>,
    /// `release` or `debug`.
    pub build: &'static str,
    /// One entry per scenario, in the order asked for.
    pub scenarios: Vec<ScenarioResult>,
}

/// One scenario: the world, both learning conditions and the plans of every seed.
#[derive(Debug, Clone, Serialize)]
pub struct ScenarioResult {
    pub name: String,
    pub notes: String,
    pub bounds: Bounds,
    pub start: Cell,
    pub target: Cell,
    pub obstacles: Vec<Cell>,
    /// d_s, cells.
    pub terminal_safe_distance: f64,
    /// d_p, cells.
    pub arm_safe_distance: f64,
    pub planning: Planning,
    /// The [`Mode`] the scenario's own planning matches, if any.
    pub default_mode: Option<Mode>,
    /// The breadth-first shortest path, start..=target.
    pub shortest_path: Option<Vec<Cell>>,
    /// Its moves.
    pub shortest_path_length: Option<usize>,
    pub assisted: Condition,
    pub unassisted: Condition,
    /// Algorithm 2, with assistance, per seed.
    pub plans: Vec<SeedPlans>,
}

impl ScenarioResult {
    /// The entry of scenario `s`.
    pub fn new(
        s: &Scenario,
        shortest_path: Option<Vec<Cell>>,
        assisted: Condition,
        unassisted: Condition,
        plans: Vec<SeedPlans>,
    ) -> Self {
        ScenarioResult {
            name: s.name.clone(),
            notes: s.notes.clone(),
            bounds: s.bounds,
            start: s.start,
            target: s.target,
            obstacles: s.obstacles.clone(),
            terminal_safe_distance: s.terminal_safe_distance,
            arm_safe_distance: s.arm_safe_distance,
            planning: s.planning,
            default_mode: Mode::of(s),
            shortest_path_length: shortest_path.as_ref().map(|p| p.len() - 1),
            shortest_path,
            assisted,
            unassisted,
            plans,
        }
    }
}

/// One learning condition over seeds 0..N.
#[derive(Debug, Clone, Serialize)]
pub struct Condition {
    pub assist: Assist,
    /// The runs in seed order. Only seed 0's keeps its path and curve of steps (the figures
    /// draw seed 0); no run keeps its per-episode success.
    #[serde(serialize_with = "runs_with_one_path")]
    pub runs: Vec<TrainReport>,
    #[serde(flatten)]
    pub stats: ConditionStats,
}

/// The runs, each without its `path` key but the first's.
fn runs_with_one_path<S: Serializer>(runs: &[TrainReport], ser: S) -> Result<S::Ok, S::Error> {
    struct Run<'a>(&'a TrainReport, bool);
    impl Serialize for Run<'_> {
        fn serialize<S: Serializer>(&self, ser: S) -> Result<S::Ok, S::Error> {
            let mut v = serde_json::to_value(self.0).map_err(serde::ser::Error::custom)?;
            if !self.1 {
                if let Some(o) = v.as_object_mut() {
                    o.remove("path");
                }
            }
            v.serialize(ser)
        }
    }
    ser.collect_seq(runs.iter().enumerate().map(|(i, r)| Run(r, i == 0)))
}

/// The three ways of planning compared (`planning.mode` and the n_d rule).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Greedy first fit, n_d doubles on every re-plan (Algorithm 1 as written).
    Paper,
    /// Backtracking search, n_d fixed (ours).
    Backtracking,
    /// Greedy first fit, n_d fixed.
    FixedNd,
}

impl Mode {
    /// Every mode, in the report's order.
    pub const ALL: [Mode; 3] = [Mode::Paper, Mode::Backtracking, Mode::FixedNd];

    /// The key in `reproduction.json` and the report.
    pub fn key(self) -> &'static str {
        match self {
            Mode::Paper => "paper",
            Mode::Backtracking => "backtracking",
            Mode::FixedNd => "fixed_nd",
        }
    }

    /// What the mode is, for the report.
    pub fn what(self) -> &'static str {
        match self {
            Mode::Paper => {
                "greedy first fit, n_d doubles on every re-plan (Algorithm 1 as written)"
            }
            Mode::Backtracking => "backtracking search, n_d fixed (ours)",
            Mode::FixedNd => "greedy first fit, n_d fixed (the paper without its n_d change)",
        }
    }

    /// The scenario with its planning set to this mode. The paper mode keeps the scenario's
    /// n_d rule if it grows, else doubles n_d up to the largest `n_d · 2^j <= 64`.
    pub fn apply(self, s: &Scenario) -> Scenario {
        let mut v = s.clone();
        let p = &mut v.planning;
        match self {
            Mode::Paper => {
                p.mode = PoseSearchMode::Paper;
                if p.orientation_divisions_growth == 1 {
                    p.orientation_divisions_growth = 2;
                    let mut cap = p.orientation_divisions;
                    while cap * 2 <= 64 {
                        cap *= 2;
                    }
                    p.orientation_divisions_max = cap;
                }
            }
            Mode::Backtracking => {
                p.mode = PoseSearchMode::Backtracking;
                p.orientation_divisions_growth = 1;
            }
            Mode::FixedNd => {
                p.mode = PoseSearchMode::Paper;
                p.orientation_divisions_growth = 1;
            }
        }
        v
    }

    /// The mode a scenario's own planning matches, if any.
    pub fn of(s: &Scenario) -> Option<Mode> {
        Mode::ALL
            .into_iter()
            .find(|m| m.apply(s).planning == s.planning)
    }
}

/// One Algorithm 2 run, as the report and the figures read it.
#[derive(Debug, Clone, Serialize)]
pub struct PlanSummary {
    pub seed: u64,
    pub mode: PoseSearchMode,
    pub success: bool,
    pub replans: u32,
    /// Cells recorded as new obstacles, in order.
    pub added_obstacles: Vec<Cell>,
    pub failure: Option<String>,
    /// Moves of the final path; `None` without one.
    pub path_length: Option<usize>,
    /// Moves of the learned path of each pass.
    pub path_lengths: Vec<Option<usize>>,
    /// n_d of each pass.
    pub orientation_divisions: Vec<u32>,
    /// Eq. 11's smallest clearance of the final motion, cells.
    pub min_centre_clearance_cells: Option<f64>,
    /// The exact smallest distance from the arm's centre line to a cube, mm.
    pub min_cube_distance_mm: Option<f64>,
    pub wall_time_s: f64,
}

impl PlanSummary {
    /// The summary of `r`, planned under `planning_mode`.
    pub fn new(r: &PlanResult, planning_mode: PoseSearchMode) -> Self {
        PlanSummary {
            seed: r.seed,
            mode: planning_mode,
            success: r.success,
            replans: r.replans,
            added_obstacles: r.added_obstacles.clone(),
            failure: r.failure.clone(),
            path_length: (!r.path.is_empty()).then(|| r.path.len() - 1),
            path_lengths: r
                .rounds
                .iter()
                .map(|x| x.path.as_ref().map(|p| p.len() - 1))
                .collect(),
            orientation_divisions: r.rounds.iter().map(|x| x.orientation_divisions).collect(),
            min_centre_clearance_cells: r.min_centre_clearance_cells,
            min_cube_distance_mm: r.min_cube_distance_mm,
            wall_time_s: r.wall_time_s,
        }
    }
}

/// The three modes' runs of one seed.
#[derive(Debug, Clone, Serialize)]
pub struct Modes {
    pub paper: PlanSummary,
    pub backtracking: PlanSummary,
    pub fixed_nd: PlanSummary,
}

impl Modes {
    /// The run of mode `m`.
    pub fn get(&self, m: Mode) -> &PlanSummary {
        match m {
            Mode::Paper => &self.paper,
            Mode::Backtracking => &self.backtracking,
            Mode::FixedNd => &self.fixed_nd,
        }
    }
}

/// Algorithm 2 for one seed: the scenario's own planning, and each mode.
#[derive(Debug, Clone, Serialize)]
pub struct SeedPlans {
    #[serde(flatten)]
    pub plan: PlanSummary,
    /// The whole result (seed 0 only: the figures draw it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub result: Option<PlanResult>,
    /// The arm's 8 points (mm) at every pose of the final motion (seed 0 only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arm_points_mm: Option<Vec<Vec<[f64; 3]>>>,
    pub modes: Modes,
}

/// One row of the summary `sixaxis reproduce` prints.
#[derive(Debug, Clone, Serialize)]
pub struct SummaryRow {
    pub scenario: String,
    pub learning_time_s_assisted: f64,
    pub learning_time_s_unassisted: f64,
    pub ratio_unassisted_over_assisted: f64,
    pub plans_succeeded: usize,
    pub plans: usize,
    pub replans_seed0: Option<u32>,
}

impl SummaryRow {
    /// The row of one scenario.
    pub fn new(s: &ScenarioResult) -> Self {
        let with = s.assisted.stats.wall_time_s_mean;
        let without = s.unassisted.stats.wall_time_s_mean;
        SummaryRow {
            scenario: s.name.clone(),
            learning_time_s_assisted: with,
            learning_time_s_unassisted: without,
            ratio_unassisted_over_assisted: without / with,
            plans_succeeded: s.plans.iter().filter(|p| p.plan.success).count(),
            plans: s.plans.len(),
            replans_seed0: s.plans.first().map(|p| p.plan.replans),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mode_keys_are_their_json_names() {
        for m in Mode::ALL {
            assert_eq!(serde_json::to_value(m).unwrap(), m.key());
        }
    }

    #[test]
    fn each_mode_is_recognised_after_it_is_applied() {
        let s = Scenario::builtin("paper_complex").unwrap();
        for m in Mode::ALL {
            assert_eq!(Mode::of(&m.apply(&s)), Some(m), "{m:?}");
        }
    }
}
