//! The integrated method (the paper's Algorithm 2): learn a terminal path, plan the arm's
//! poses along it, and re-plan around every path point no safe pose reaches.
//!
//! Entry points:
//! - [`plan`] — the whole loop for a scenario with any [`PathLearner`] (tabular Q-learning,
//!   [`QLearner`], when none is given); returns a [`PlanResult`] (success or a clear failure
//!   naming the points that could not be reached).
//! - [`PlanOptions`] — seed, episodes and assistance, defaulting to the scenario's.
//! - [`PathLearner`] — what learns the terminal's path in each round: [`QLearner`] (the
//!   paper's, the default), [`BfsLearner`] (the breadth-first shortest path), or your own.
//!   Every path a learner returns is checked ([`check_path`]) before Algorithm 1 sees it.
//!
//! Each round learns a path from scratch (a fresh Q-table) on the scenario's obstacles plus
//! every point added so far, then runs Algorithm 1 ([`crate::planner::PosePlanner`]) from
//! beta_0, in the scenario's `planning.mode`, with the orientation grid of round k's n_d
//! (`planning.orientation_divisions_for_round(k)`: the paper's "change n_d" on a re-plan).
//! A blocked point is added as an obstacle for the terminal only: the arm's clearance is
//! always measured against the scenario's own obstacles.
//!
//! Where the blocked point is the target itself (no clear motion reaches any pose there
//! from the pose at the point before), the point before is recorded instead, so that the
//! next path approaches the target another way. The run fails with a reason naming the
//! recorded points when the re-plan cap is reached, when the added points cut the target
//! off, or when the learned path does not reach the target.
//!
//! ```no_run
//! use sixaxis_core::{replanning::{plan, PlanOptions}, Scenario};
//! let s = Scenario::load("paper_simple").unwrap();
//! let result = plan(&s, &PlanOptions::from_scenario(&s), None, None).unwrap();
//! assert!(result.success);
//! ```
//!
//! With the breadth-first shortest path as the learner:
//!
//! ```no_run
//! use sixaxis_core::{replanning::{plan, BfsLearner, PlanOptions}, Scenario};
//! let s = Scenario::load("replan_clutter").unwrap();
//! let result = plan(&s, &PlanOptions::from_scenario(&s), Some(&mut BfsLearner), None).unwrap();
//! assert!(result.rounds.iter().all(|r| r.total_steps == 0));
//! ```

use std::time::Instant;

use serde::Serialize;

use crate::error::{Error, Result};
use crate::grid::GridWorld;
use crate::planner::{PosePlan, PosePlanner};
use crate::qlearning::{train, Learning};
use crate::scenario::{Cell, ClearanceModel, ObstacleBox, PoseSearchMode, Scenario};

/// Options of one Algorithm 2 run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlanOptions {
    /// Learning options of every round (episodes, seed, assistance, ...).
    pub train: Learning,
    /// Re-plans allowed before giving up.
    pub max_replans: u32,
}

impl PlanOptions {
    /// The scenario's own settings.
    pub fn from_scenario(s: &Scenario) -> Self {
        PlanOptions {
            train: Learning::from_scenario(s),
            max_replans: s.planning.max_replans,
        }
    }
}

/// What a [`PathLearner`] learned in one round of Algorithm 2.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct LearnedPath {
    /// The terminal's path, cells from start to target; `None` if the learner found none.
    pub path: Option<Vec<Cell>>,
    /// First episode from which the learned path no longer changed (learners with episodes).
    pub converged_episode: Option<u32>,
    /// First episode from which the learned path's length no longer changed.
    pub length_converged_episode: Option<u32>,
    /// Environment steps spent learning (0 for a planner such as BFS).
    pub total_steps: u64,
    /// Wall time of the learning, seconds.
    pub wall_time_s: f64,
    /// Why `path` is `None`, in the learner's own words (for example: the round's added
    /// points block the start); the run's failure reason is this text with ` (round k)`
    /// appended. `None` takes [`PathLearner::no_path_reason`]; ignored when a path was found.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub no_path_reason: Option<String>,
}

/// One round of Algorithm 2, as a [`PathLearner`] sees it.
pub struct Round<'a> {
    /// Round number, from 0 (re-plan `k` is round `k`).
    pub index: u32,
    /// The scenario being planned (its own obstacles only).
    pub scenario: &'a Scenario,
    /// Points recorded as obstacles so far (for the terminal), in order.
    pub added_obstacles: &'a [Cell],
    /// `progress(episodes_done)` for learners with episodes; `None` when nobody listens.
    pub progress: Option<&'a dyn Fn(u32)>,
}

/// What learns the terminal's path in each round of Algorithm 2.
///
/// `world` is the round's grid world: the scenario's obstacles plus `round.added_obstacles`.
/// The returned path is checked by [`check_path`] before it is used; an error ends the run
/// with that error.
pub trait PathLearner {
    /// Learn a path from the world's start to its target.
    fn learn_path(&mut self, world: &GridWorld, round: &Round<'_>) -> Result<LearnedPath>;

    /// Why the run stops when [`PathLearner::learn_path`] found no path in round `round`
    /// and gave no reason of its own ([`LearnedPath::no_path_reason`]).
    fn no_path_reason(&self, round: u32) -> String {
        format!("the path learner found no path to the target (round {round})")
    }
}

/// The paper's learner: tabular Q-learning ([`crate::qlearning::train`]) from a fresh
/// Q-table in every round, with the same options (and so the same seed) each round.
#[derive(Debug, Clone, PartialEq)]
pub struct QLearner {
    /// Learning options of every round.
    pub opts: Learning,
}

impl PathLearner for QLearner {
    fn learn_path(&mut self, world: &GridWorld, round: &Round<'_>) -> Result<LearnedPath> {
        let r = train(world, &self.opts, None, round.progress)?;
        Ok(LearnedPath {
            path: r.path,
            converged_episode: r.converged_episode,
            length_converged_episode: r.length_converged_episode,
            total_steps: r.total_steps,
            wall_time_s: r.wall_time_s,
            no_path_reason: None,
        })
    }

    fn no_path_reason(&self, round: u32) -> String {
        // A run with an env-step budget stops at the budget, not at the episode cap.
        let spent = if self.opts.max_env_steps > 0 {
            format!("its budget of {} env steps", self.opts.max_env_steps)
        } else {
            format!("{} episodes", self.opts.episodes)
        };
        format!(
            "the learned greedy path does not reach the target after {spent} (round {round}, seed {})",
            self.opts.seed
        )
    }
}

/// The breadth-first shortest path of the round's world ([`GridWorld::shortest_path`]): the
/// optimal reference, no learning.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BfsLearner;

impl PathLearner for BfsLearner {
    fn learn_path(&mut self, world: &GridWorld, _round: &Round<'_>) -> Result<LearnedPath> {
        let t0 = Instant::now();
        let path = world.shortest_path();
        Ok(LearnedPath {
            path,
            wall_time_s: t0.elapsed().as_secs_f64(),
            ..LearnedPath::default()
        })
    }

    fn no_path_reason(&self, round: u32) -> String {
        format!("breadth-first search finds no path to the target (round {round})")
    }
}

/// Check a learner's path against its world: it starts at the start, ends at the target,
/// every step moves to one of the six neighbouring cells, and no cell is out of bounds or
/// blocked. The error ([`Error::InvalidArgument`] named `path`) says which rule is broken where.
pub fn check_path(world: &GridWorld, path: &[Cell]) -> Result<()> {
    let bad = |why: String| Err(Error::argument("path", fmt_path(path), why));
    let (start, target) = (world.cell_of(world.start()), world.cell_of(world.target()));
    match (path.first(), path.last()) {
        (None, _) | (_, None) => return bad("the path learner returned an empty path".into()),
        (Some(&first), _) if first != start => {
            return bad(format!(
                "the path must start at the start cell {}, not {}",
                fmt_cell(start),
                fmt_cell(first)
            ))
        }
        (_, Some(&last)) if last != target => {
            return bad(format!(
                "the path must end at the target cell {}, not {}",
                fmt_cell(target),
                fmt_cell(last)
            ))
        }
        _ => {}
    }
    for (i, &c) in path.iter().enumerate() {
        match world.state_of(c) {
            None => return bad(format!("point {i} {} is out of bounds", fmt_cell(c))),
            Some(s) if world.is_blocked(s) => {
                return bad(format!("point {i} {} is an obstacle", fmt_cell(c)))
            }
            _ => {}
        }
        if i > 0 {
            check_move(path, i)?;
        }
    }
    Ok(())
}

/// Check that every step of `path` moves to one of the six neighbouring cells (the rule of
/// [`check_path`] that needs no world; Algorithm 1's `plan_poses` input is checked with it).
/// The error ([`Error::InvalidArgument`] named `path`) says which step breaks it.
pub fn check_moves(path: &[Cell]) -> Result<()> {
    (1..path.len()).try_for_each(|i| check_move(path, i))
}

/// Step `i` of `path` (from point `i - 1` to point `i`) is a move to a neighbouring cell.
fn check_move(path: &[Cell], i: usize) -> Result<()> {
    let (p, c) = (path[i - 1], path[i]);
    let d: i32 = (0..3).map(|k| (c[k] - p[k]).abs()).sum();
    if d == 1 {
        return Ok(());
    }
    Err(Error::argument(
        "path",
        fmt_path(path),
        format!(
            "step {i} from {} to {} is not a move to one of the six neighbouring cells",
            fmt_cell(p),
            fmt_cell(c)
        ),
    ))
}

/// Learning figures of one round of Algorithm 2.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RoundSummary {
    /// Obstacles added before this round (cumulative count).
    pub added_obstacles: usize,
    /// The learned path, if it reached the target.
    pub path: Option<Vec<Cell>>,
    /// First episode from which the greedy path no longer changed.
    pub converged_episode: Option<u32>,
    /// First episode from which the greedy path's length no longer changed.
    pub length_converged_episode: Option<u32>,
    /// Environment steps of this round's learning.
    pub total_steps: u64,
    /// Wall time of this round's learning, seconds.
    pub learning_time_s: f64,
    /// Where Algorithm 1 stopped, if it did: (index in the path, cell).
    pub blocked_at: Option<(usize, Cell)>,
    /// n_d of this round's orientation grid (eq. 12).
    pub orientation_divisions: u32,
    /// Algorithm 1's search mode in this round.
    pub mode: PoseSearchMode,
}

/// The result of [`plan`]; serialises to the JSON of `sixaxis plan`
/// (docs/SCENARIOS.md "JSON outputs of the CLI").
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlanResult {
    /// Whether every path point got a safe pose.
    pub success: bool,
    /// Edge of a cell, mm.
    pub cell_mm: f64,
    /// d_p, cells.
    pub arm_safe_distance: f64,
    /// Clearance model used for the arm.
    pub clearance_model: ClearanceModel,
    /// t: interpolation steps between poses.
    pub interpolation_steps: u32,
    /// Start and target cells.
    pub start: Cell,
    /// Target cell.
    pub target: Cell,
    /// The scenario's own obstacles (before any were added).
    pub obstacles: Vec<Cell>,
    /// The scenario's obstacles as boxes in mm (its `obstacle_boxes_mm`; empty for a world
    /// of cells only).
    pub obstacle_boxes_mm: Vec<ObstacleBox>,
    /// The final terminal path (cells, start to target); empty on failure before any path.
    pub path: Vec<Cell>,
    /// One pose per path point, start included, radians.
    pub poses_rad: Vec<[f64; 6]>,
    /// The terminal orientation (rt_x, rt_y, rt_z), degrees, chosen at each path point.
    pub orientations_rpy_deg: Vec<[f64; 3]>,
    /// Number of re-plans (rounds after the first).
    pub replans: u32,
    /// Points recorded as new obstacles, in order.
    pub added_obstacles: Vec<Cell>,
    /// None on success; otherwise why, naming the points that could not be reached.
    pub failure: Option<String>,
    /// Per-round learning figures.
    pub rounds: Vec<RoundSummary>,
    /// Seed of the learner.
    pub seed: u64,
    /// Wall time of the whole run, seconds.
    pub wall_time_s: f64,
    /// Eq. 11's figure for the final motion: smallest distance from an obstacle centre to
    /// the arm's polyline over every interpolation step, cells; None without poses.
    pub min_centre_clearance_cells: Option<f64>,
    /// Exact geometry for the same motion: smallest distance from the arm's polyline to an
    /// obstacle cube, mm; None without poses.
    pub min_cube_distance_mm: Option<f64>,
}

fn fmt_cell(c: Cell) -> String {
    format!("({}, {}, {})", c[0], c[1], c[2])
}

fn fmt_cells(cells: &[Cell]) -> String {
    let parts: Vec<String> = cells.iter().map(|&c| fmt_cell(c)).collect();
    parts.join(", ")
}

/// A path as `[(x, y, z), ...]`, shortened in the middle when long.
fn fmt_path(path: &[Cell]) -> String {
    if path.len() <= 12 {
        return format!("[{}]", fmt_cells(path));
    }
    format!(
        "[{}, ..., {}] ({} points)",
        fmt_cells(&path[..5]),
        fmt_cells(&path[path.len() - 5..]),
        path.len()
    )
}

/// Run Algorithm 2 on a scenario with `learner` (`None`: tabular Q-learning with
/// `opts.train`, the paper's). `progress(round, episodes_done)` is called during learning.
///
/// Errors for invalid input, for an error of the learner, and for a learned path that
/// breaks the rules of [`check_path`]; a plan that cannot be completed is `Ok` with
/// `success == false` and a `failure` reason.
pub fn plan(
    scenario: &Scenario,
    opts: &PlanOptions,
    learner: Option<&mut dyn PathLearner>,
    progress: Option<&dyn Fn(u32, u32)>,
) -> Result<PlanResult> {
    let mut default_learner;
    let learner: &mut dyn PathLearner = match learner {
        Some(l) => l,
        None => {
            default_learner = QLearner { opts: opts.train };
            &mut default_learner
        }
    };
    let t0 = Instant::now();
    let beta0 = scenario.arm.beta0_rad();
    let mut result = PlanResult {
        success: false,
        cell_mm: scenario.cell_mm,
        arm_safe_distance: scenario.arm_safe_distance,
        clearance_model: scenario.planning.clearance_model,
        interpolation_steps: scenario.planning.interpolation_steps,
        start: scenario.start,
        target: scenario.target,
        obstacles: scenario.obstacles.clone(),
        obstacle_boxes_mm: scenario.obstacle_boxes_mm.clone(),
        path: Vec::new(),
        poses_rad: Vec::new(),
        orientations_rpy_deg: Vec::new(),
        replans: 0,
        added_obstacles: Vec::new(),
        failure: None,
        rounds: Vec::new(),
        seed: opts.train.seed,
        wall_time_s: 0.0,
        min_centre_clearance_cells: None,
        min_cube_distance_mm: None,
    };
    let finish = |mut r: PlanResult, failure: Option<String>| {
        r.success = failure.is_none();
        r.failure = failure;
        r.wall_time_s = t0.elapsed().as_secs_f64();
        r
    };
    let mut round: u32 = 0;
    loop {
        let world = GridWorld::with_extra_obstacles(scenario, &result.added_obstacles)?;
        if world.shortest_path().is_none() {
            let why = format!(
                "the target is cut off from the start once the points no arm pose reaches are obstacles; points that could not be reached: {}",
                fmt_cells(&result.added_obstacles)
            );
            return Ok(finish(result, Some(why)));
        }
        let cb = progress.map(|p| move |done: u32| p(round, done));
        let cb_ref: Option<&dyn Fn(u32)> = cb.as_ref().map(|f| f as &dyn Fn(u32));
        let learned = learner.learn_path(
            &world,
            &Round {
                index: round,
                scenario,
                added_obstacles: &result.added_obstacles,
                progress: cb_ref,
            },
        )?;
        if let Some(path) = &learned.path {
            check_path(&world, path)?;
        }
        let mut summary = RoundSummary {
            added_obstacles: result.added_obstacles.len(),
            path: learned.path.clone(),
            converged_episode: learned.converged_episode,
            length_converged_episode: learned.length_converged_episode,
            total_steps: learned.total_steps,
            learning_time_s: learned.wall_time_s,
            blocked_at: None,
            orientation_divisions: scenario.planning.orientation_divisions_for_round(round),
            mode: scenario.planning.mode,
        };
        let Some(path) = learned.path else {
            result.rounds.push(summary);
            let why = match learned.no_path_reason {
                Some(own) => format!("{own} (round {round})"),
                None => learner.no_path_reason(round),
            };
            return Ok(finish(result, Some(why)));
        };
        let planner = PosePlanner::for_round(scenario, round);
        match planner.plan_poses(&path, &beta0) {
            PosePlan::Complete(points) => {
                result.rounds.push(summary);
                result.path = path;
                result.poses_rad = points.iter().map(|p| p.joints_rad).collect();
                if let Some(m) = planner.motion_clearance(&result.poses_rad) {
                    result.min_centre_clearance_cells = Some(m.min_centre_clearance_cells);
                    result.min_cube_distance_mm = Some(m.min_cube_distance_mm);
                }
                result.orientations_rpy_deg =
                    points.iter().map(|p| p.orientation_rpy_deg).collect();
                return Ok(finish(result, None));
            }
            PosePlan::Blocked { index, cell, .. } => {
                summary.blocked_at = Some((index, cell));
                result.rounds.push(summary);
                result.path = path.clone();
                // The target cannot become an obstacle. When no clear motion reaches it
                // from the pose at the point before, that point is recorded instead, so the
                // next path approaches the target another way (our extension; the paper is
                // silent). Where that point is the start, nothing is left to try.
                let recorded = if cell == scenario.target {
                    path[index - 1]
                } else {
                    cell
                };
                if recorded == scenario.start {
                    let why = format!(
                        "no clear arm motion reaches the target ({}, {}, {}) from the start pose with clearance > {} cells; points that could not be reached: {}",
                        cell[0],
                        cell[1],
                        cell[2],
                        scenario.arm_safe_distance,
                        fmt_cells(&result.added_obstacles)
                    );
                    return Ok(finish(result, Some(why)));
                }
                result.added_obstacles.push(recorded);
                if round >= opts.max_replans {
                    let why = format!(
                        "re-plan cap ({}) reached; points that could not be reached: {}",
                        opts.max_replans,
                        fmt_cells(&result.added_obstacles)
                    );
                    return Ok(finish(result, Some(why)));
                }
                round += 1;
                result.replans = round;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_moves_names_the_first_jump() {
        assert!(check_moves(&[]).is_ok());
        assert!(check_moves(&[[0, 0, 0], [0, 0, 1], [0, -1, 1]]).is_ok());
        let err = check_moves(&[[0, 0, 0], [0, 0, 1], [1, 1, 1]]).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("path") && msg.contains("step 2"), "{msg}");
        assert!(check_moves(&[[0, 0, 0], [0, 0, 0]]).is_err()); // staying is no move
    }
}
