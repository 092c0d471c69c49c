//! Scenarios: the world of one experiment, read from JSON (`envs/*.json`). The bottom layer
//! of the core: it knows nothing of the grid, the generator or the planner.
//!
//! Entry points:
//! - [`Scenario::open`] — by built-in name (`paper_simple`) or by file path;
//!   [`Scenario::load`] (in [`crate::names`], one layer up) also takes `generated:SEED`.
//! - [`Scenario::from_json`] / [`Scenario::to_json`] — text round trip; parsing rejects
//!   unknown fields and then runs [`Scenario::validate`].
//! - [`Scenario::builtin`] / [`BUILTIN_NAMES`] — the scenarios shipped with the crate
//!   (`rust/core/scenarios/`, equal to `envs/`), compiled in.
//!
//! Field names say what a value is; the paper's symbols are in each field's doc line and in
//! `docs/SCENARIOS.md`. Distances between cells are in cells (grid unit = `cell_mm` mm).
//!
//! **Physical worlds.** Besides the paper's unit cubes on cells (`obstacles`), a scenario may
//! state obstacles as axis-aligned boxes in mm ([`ObstacleBox`], `obstacle_boxes_mm`) and its
//! safe distances in mm (`terminal_safe_distance_mm`, `arm_safe_distance_mm`), independent of
//! `cell_mm`; [`crate::regrid`] writes the same world at another cell size. Which cells a box
//! blocks for the terminal is [`ObstacleBox::terminal_distance_mm`] `<= d_s` (mm).
//!
//! ```
//! use sixaxis_core::scenario::Scenario;
//! let s = Scenario::load("paper_simple").unwrap();
//! assert_eq!(s.start, [0, -2, 4]);
//! assert_eq!(s.target, [0, 3, 0]);
//! ```

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::kinematics::{Arm, DhRow, PAPER_BETA0_DEG, PAPER_DH};
use crate::options::{check_all, named_enum, option_set, Domain, FromOption, OptionValue};

/// A grid cell (integer coordinates, cells). Its centre is at `cell * cell_mm` mm.
pub type Cell = [i32; 3];

/// Largest scenario file [`Scenario::from_file`] reads, bytes (256 MiB: some 16 million
/// obstacle cells, the most a grid may hold).
pub const MAX_SCENARIO_BYTES: u64 = 256 << 20;

/// Position of the centre of cell `c` in a grid of `cell_mm` mm cells, mm (the one place
/// that says where a cell is).
pub fn cell_centre_mm(c: Cell, cell_mm: f64) -> nalgebra::Vector3<f64> {
    nalgebra::Vector3::new(c[0] as f64, c[1] as f64, c[2] as f64) * cell_mm
}

/// Built-in scenarios, by name: `rust/core/scenarios/*.json`, compiled into the crate (the
/// files in the repository's `envs/` are the user-facing copies, checked equal by a test).
pub const BUILTIN_NAMES: &[&str] = &["paper_simple", "paper_complex", "replan_clutter"];

pub(crate) fn builtin_text(name: &str) -> Option<&'static str> {
    Some(match name {
        "paper_simple" => include_str!("../scenarios/paper_simple.json"),
        "paper_complex" => include_str!("../scenarios/paper_complex.json"),
        "replan_clutter" => include_str!("../scenarios/replan_clutter.json"),
        _ => return None,
    })
}

/// Axis-aligned box of cells, both corners included.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bounds {
    /// Lowest corner cell (inclusive).
    pub min: Cell,
    /// Highest corner cell (inclusive).
    pub max: Cell,
}

impl Bounds {
    /// Whether `c` lies inside the box.
    #[inline]
    pub fn contains(&self, c: Cell) -> bool {
        (0..3).all(|i| c[i] >= self.min[i] && c[i] <= self.max[i])
    }

    /// Number of cells along each axis (in i64: `max - min + 1` overflows i32 for the
    /// widest boxes).
    pub fn size(&self) -> [usize; 3] {
        [0, 1, 2].map(|i| (self.max[i] as i64 - self.min[i] as i64 + 1).max(0) as usize)
    }

    /// Number of cells in the box, saturating at `usize::MAX` (a wrapped product let a box
    /// of 2^64 cells pass validation as an empty one).
    pub fn volume(&self) -> usize {
        self.size()
            .iter()
            .try_fold(1usize, |acc, &n| acc.checked_mul(n))
            .unwrap_or(usize::MAX)
    }
}

/// Where the safe distances to an [`ObstacleBox`] are measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DistanceTo {
    /// From the box itself (0 inside it): exact geometry, for boxes of any shape.
    #[default]
    Surface,
    /// From the box's centre point: the paper's reading of its cubes (eqs. 5 and 11 measure
    /// to an obstacle's centre). Only for cubes; [`crate::regrid`] writes the paper's cubes so.
    Centre,
}

/// An obstacle as an axis-aligned box in mm, independent of the grid.
///
/// The terminal collides in a cell whose centre lies within `terminal_safe_distance` of the
/// box, measured as [`DistanceTo`] says ([`ObstacleBox::terminal_distance_mm`]). The arm:
/// under the centres model, every segment keeps more than `arm_safe_distance` from the box
/// (its centre for `centre` boxes, eq. 11; the box itself for `surface` boxes); under the
/// capsules model, the exact gap between link capsules and the box exceeds `margin_mm`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleBox {
    /// Lowest corner, mm.
    pub min_mm: [f64; 3],
    /// Highest corner, mm.
    pub max_mm: [f64; 3],
    /// Where safe distances are measured from (default `surface`).
    #[serde(default, skip_serializing_if = "DistanceTo::is_surface")]
    pub distance_to: DistanceTo,
}

impl DistanceTo {
    fn is_surface(&self) -> bool {
        *self == DistanceTo::Surface
    }
}

impl ObstacleBox {
    /// The paper's cube of edge `cell_mm` centred on cell `c`, measured from its centre.
    pub fn paper_cube(c: Cell, cell_mm: f64) -> ObstacleBox {
        let h = 0.5 * cell_mm;
        let centre = c.map(|v| v as f64 * cell_mm);
        ObstacleBox {
            min_mm: centre.map(|v| v - h),
            max_mm: centre.map(|v| v + h),
            distance_to: DistanceTo::Centre,
        }
    }

    /// Centre of the box, mm.
    pub fn centre_mm(&self) -> [f64; 3] {
        std::array::from_fn(|i| 0.5 * (self.min_mm[i] + self.max_mm[i]))
    }

    /// Half its edge along each axis, mm.
    pub fn half_extents_mm(&self) -> [f64; 3] {
        std::array::from_fn(|i| 0.5 * (self.max_mm[i] - self.min_mm[i]))
    }

    /// Distance (mm) from point `p` (mm) to the box as the terminal's rule measures it: to
    /// the centre for `centre` boxes, to the box (0 inside or on it) for `surface` boxes.
    #[inline]
    pub fn terminal_distance_mm(&self, p: [f64; 3]) -> f64 {
        let d2: f64 = match self.distance_to {
            DistanceTo::Centre => {
                let c = self.centre_mm();
                (0..3).map(|i| (p[i] - c[i]) * (p[i] - c[i])).sum()
            }
            DistanceTo::Surface => (0..3)
                .map(|i| {
                    let d = (self.min_mm[i] - p[i]).max(p[i] - self.max_mm[i]).max(0.0);
                    d * d
                })
                .sum(),
        };
        d2.sqrt()
    }

    fn check(&self, field: &str) -> Result<()> {
        let all = self.min_mm.iter().chain(&self.max_mm);
        if !all.clone().all(|v| v.is_finite()) || (0..3).any(|i| self.min_mm[i] > self.max_mm[i]) {
            return Err(Error::invalid(
                field,
                format!("min_mm {:?} max_mm {:?}", self.min_mm, self.max_mm),
                "corners must be finite with min_mm <= max_mm on every axis",
            ));
        }
        if self.distance_to == DistanceTo::Centre {
            let h = self.half_extents_mm();
            let tol = 1e-9 * h[0].abs().max(1.0);
            if (h[1] - h[0]).abs() > tol || (h[2] - h[0]).abs() > tol {
                return Err(Error::invalid(
                    field,
                    format!("min_mm {:?} max_mm {:?}", self.min_mm, self.max_mm),
                    "a box measured from its centre (distance_to: centre) must be a cube",
                ));
            }
        }
        Ok(())
    }
}

/// Reward parameters (eqs. 5, 9, 10). Penalties are given as positive magnitudes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Rewards {
    /// r (eq. 5): reward for reaching the target.
    pub target_reward: f64,
    /// p (eq. 5): penalty of a step that neither collides nor reaches the target.
    pub step_penalty: f64,
    /// P (eq. 5): penalty of a collision (obstacle or bounds).
    pub collision_penalty: f64,
    /// p_e (eq. 9): extra penalty when the step after a collision collides again.
    pub repeat_collision_penalty: f64,
    /// p_o (eq. 9): extra penalty when the step after a collision takes the opposite action.
    pub reverse_after_collision_penalty: f64,
    /// r_e (eq. 10): reward per cell of progress, `r_e * (d_o - d_t)`.
    pub distance_reward: f64,
}

impl Default for Rewards {
    fn default() -> Self {
        Rewards {
            target_reward: 20000.0,
            step_penalty: 15000.0,
            collision_penalty: 8000.0,
            repeat_collision_penalty: 230000.0,
            reverse_after_collision_penalty: 10000.0,
            distance_reward: 40.0,
        }
    }
}

/// Default episode cap of `episodes = "auto"` (`--episodes auto`), episodes.
pub const AUTO_EPISODE_CAP: u32 = 1_000_000;

/// The domain of eq. 6's alpha: (0, 1].
const UNIT_OPEN: Domain = Domain::Float {
    min: 0.0,
    max: 1.0,
    open_min: true,
};
/// The domain of a probability or a discount: [0, 1].
const UNIT: Domain = Domain::Float {
    min: 0.0,
    max: 1.0,
    open_min: false,
};

option_set! {
    /// Q-learning parameters (eqs. 6-7) and the assisted strategies: the scenario's
    /// `learning` section and the options of a training run (the one declaration of the
    /// learning options: the scenario schema, the request layer, the CLI's flags, the Python
    /// keywords, the stub and the docs' table are derived from it; see [`crate::options`]).
    pub struct Learning ("learning") {
        /// eta_set: learning episodes; with `episodes = "auto"` (ours), train until the
        /// greedy path reaches the target and stops changing, under `episode_cap`.
        episodes: u32 = 10_000; "episodes", Domain::IntOrAuto { min: 1, max: u32::MAX as i128 }, "episodes",
            set = set_episodes;
        /// Whether `episodes` is a cap and the run stops when the greedy path settles (set
        /// by `episodes = "auto"`; see docs/SCENARIOS.md).
        episodes_auto: bool = false; "", Domain::Bool, "";
        /// Seed of the learner's random generator.
        seed: u64 = 0; "seed", Domain::u64_from(0), "";
        /// Detour encouraging (eq. 9) on or off.
        assist_detour: bool = true; "detour", Domain::Bool, "";
        /// Distance assistance (eq. 10) on or off.
        assist_distance: bool = true; "distance", Domain::Bool, "";
        /// Step cap of an episode and of the greedy rollout (the paper gives none).
        max_steps_per_episode: u32 = 1000; "max_steps_per_episode", Domain::u32_from(1), "steps";
        /// How the Q-table starts: `zero` (the paper, eq. 6) or `distance` (ours: an
        /// optimistic bound from the Manhattan distance to the target; see docs/SCENARIOS.md).
        initial_q: InitialQ = InitialQ::Zero; "initial_q", InitialQ::DOMAIN, "";
        /// The type of the Q-values: `f64` (the paper's arithmetic) or `f32` (ours: half the
        /// memory per state; updates computed in f64, stored rounded).
        q_precision: QPrecision = QPrecision::F64; "q_precision", QPrecision::DOMAIN, "";
        /// alpha: learning rate of eq. 6.
        alpha: f64 = 0.05; "alpha", UNIT_OPEN, "";
        /// gamma: discount factor of eq. 6.
        gamma: f64 = 0.9; "gamma", UNIT, "";
        /// epsilon at episode 0 (eq. 7: 0.1).
        epsilon_start: f64 = 0.1; "epsilon_start", UNIT, "";
        /// M: episodes over which epsilon falls linearly to 0 (eq. 7).
        epsilon_decay_episodes: u32 = 9900; "epsilon_decay_episodes", Domain::u32_from(0), "episodes";
    }
}

/// `episodes`: a number of episodes, or `"auto"` (then `episodes` is the cap
/// [`AUTO_EPISODE_CAP`] until `episode_cap` says otherwise).
fn set_episodes(o: &mut Learning, key: &str, v: &OptionValue) -> Result<()> {
    const DOMAIN: Domain = Domain::IntOrAuto {
        min: 1,
        max: u32::MAX as i128,
    };
    // As a request key, a number is a fixed run; as the scenario field (`learning.episodes`,
    // a number only), it stays with the file's `episodes_auto`.
    let request = key == "episodes";
    if request && matches!(v, OptionValue::Text(t) if t == "auto") {
        o.episodes_auto = true;
        o.episodes = AUTO_EPISODE_CAP;
        return Ok(());
    }
    let domain = if request { DOMAIN } else { Domain::u32_from(1) };
    o.episodes = u32::from_option(key, &domain, v)?;
    if request {
        o.episodes_auto = false;
    }
    Ok(())
}

impl Learning {
    /// The scenario's `learning` section.
    pub fn from_scenario(s: &Scenario) -> Self {
        s.learning
    }

    /// The assisted strategies on or off (eqs. 9 and 10).
    pub fn assist(&self) -> Assist {
        Assist {
            detour: self.assist_detour,
            distance: self.assist_distance,
        }
    }

    /// Both strategies as one [`Assist`].
    pub fn set_assist(&mut self, a: Assist) {
        self.assist_detour = a.detour;
        self.assist_distance = a.distance;
    }

    /// `episodes = "auto"`: train until the greedy path settles, under [`AUTO_EPISODE_CAP`].
    pub fn auto(mut self) -> Self {
        self.episodes_auto = true;
        self.episodes = AUTO_EPISODE_CAP;
        self
    }

    /// Check the ranges; the error names the option.
    pub fn validate(&self) -> Result<()> {
        check_all(Self::OPTIONS, self, |i| {
            if i.key.is_empty() {
                i.field
            } else {
                i.key
            }
        })
    }

    /// Exploration rate of episode `episode` (counted from 0), eq. 7.
    pub fn epsilon(&self, episode: u32) -> f64 {
        let m = self.epsilon_decay_episodes;
        if m == 0 || episode > m {
            0.0
        } else {
            self.epsilon_start * (1.0 - episode as f64 / m as f64)
        }
    }
}

/// Which assisted-learning strategies shape the reward.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Assist {
    /// Detour encouraging, eq. 9.
    pub detour: bool,
    /// Distance assistance, eq. 10.
    pub distance: bool,
}

impl Assist {
    /// Both strategies on ("with assisted learning").
    pub fn on() -> Self {
        Assist {
            detour: true,
            distance: true,
        }
    }

    /// Both off: eq. 5 alone ("without assisted learning").
    pub fn off() -> Self {
        Assist {
            detour: false,
            distance: false,
        }
    }

    /// The scenario's `learning.assist_detour` / `learning.assist_distance`.
    pub fn from_scenario(s: &Scenario) -> Self {
        s.learning.assist()
    }
}

named_enum! {
    /// How the learner's Q-table starts (`learning.initial_q`).
    pub enum InitialQ (default Zero) {
        /// Q = 0 everywhere: the paper's learner, the default of every scenario.
        Zero = "zero",
        /// Ours: Q(s, a) starts at an optimistic bound of the return of reaching the target
        /// from the move's next cell in its Manhattan distance of moves (the rule of
        /// `crate::qlearning`).
        Distance = "distance",
    }
}

named_enum! {
    /// The type the learner stores its Q-values in (`learning.q_precision`).
    pub enum QPrecision (default F64) {
        /// 64-bit floats (48 bytes of Q-values per state): the default of every scenario.
        F64 = "f64",
        /// Ours: 32-bit floats (24 bytes per state). Every update is computed in f64 as with
        /// `F64` and its result rounded to the nearest f32 when stored.
        F32 = "f32",
    }
}

impl QPrecision {
    /// Bytes of one Q-value (8 or 4).
    pub fn value_bytes(self) -> usize {
        match self {
            QPrecision::F64 => 8,
            QPrecision::F32 => 4,
        }
    }
}

/// The arm: its D-H table, initial pose and optional joint limits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ArmSpec {
    /// Six modified D-H rows (Table 2 by default).
    pub dh: Vec<DhRow>,
    /// beta_0: the initial pose, degrees; its terminal must lie on the start cell.
    pub beta0_deg: [f64; 6],
    /// Optional joint limits, degrees, `[low, high]` per joint (the paper sets none).
    pub joint_limits_deg: Option<[[f64; 2]; 6]>,
}

impl Default for ArmSpec {
    fn default() -> Self {
        ArmSpec {
            dh: PAPER_DH.to_vec(),
            beta0_deg: PAPER_BETA0_DEG,
            joint_limits_deg: None,
        }
    }
}

impl ArmSpec {
    /// The kinematic arm of this spec (assumes a validated spec with six rows).
    pub fn arm(&self) -> Arm {
        let mut rows = PAPER_DH;
        for (dst, src) in rows.iter_mut().zip(&self.dh) {
            *dst = *src;
        }
        Arm::new(rows)
    }

    /// beta_0 in radians.
    pub fn beta0_rad(&self) -> [f64; 6] {
        self.beta0_deg.map(f64::to_radians)
    }
}

/// How the arm's clearance from obstacles is measured.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ClearanceModel {
    /// The paper's eq. 11: distance from each obstacle centre to each segment of the
    /// polyline, compared with `arm_safe_distance` (cells).
    Centres,
    /// Exact geometry (parry3d): links as capsules of radius `link_radius_mm`, obstacles
    /// as cubes of one cell; the gap between them must exceed `margin_mm`.
    Capsules {
        /// Radius of every link capsule, mm.
        link_radius_mm: f64,
        /// Required gap between a capsule and a cube, mm.
        margin_mm: f64,
    },
}

/// How Algorithm 1 searches the candidate poses of a path (`planning.mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PoseSearchMode {
    /// The paper's Algorithm 1 as written: at each path point the first candidate whose
    /// interpolated motion is clear is kept; a dead end stops the pass (no backtracking).
    Paper,
    /// Ours: the same candidate order searched depth first; after a dead end the search goes
    /// back to earlier points' next candidates, within `planning.backtrack_budget`.
    Backtracking,
}

impl PoseSearchMode {
    /// The name used in scenario files and results (`"paper"`, `"backtracking"`).
    pub fn name(self) -> &'static str {
        match self {
            PoseSearchMode::Paper => "paper",
            PoseSearchMode::Backtracking => "backtracking",
        }
    }
}

/// Pose planning parameters (Algorithms 1 and 2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Planning {
    /// t: interpolation steps between two poses.
    pub interpolation_steps: u32,
    /// n_d of the first pass: divisions of a full turn in the orientation grid (eq. 12).
    pub orientation_divisions: u32,
    /// Factor applied to n_d on every re-plan (Algorithm 1: "change n_d"): pass k uses
    /// `orientation_divisions * growth^k`, capped at `orientation_divisions_max`; 1 keeps
    /// n_d fixed.
    pub orientation_divisions_growth: u32,
    /// Cap of n_d over re-plans; with growth > 1 it must be `orientation_divisions *
    /// growth^j` so that every grid contains the one before.
    pub orientation_divisions_max: u32,
    /// How Algorithm 1 searches the candidate poses: the paper's greedy pass or ours with
    /// backtracking.
    pub mode: PoseSearchMode,
    /// Re-plans allowed before Algorithm 2 gives up.
    pub max_replans: u32,
    /// Clearance model of the whole-arm check.
    pub clearance_model: ClearanceModel,
    /// Joint-space motion checks Algorithm 1 may spend backtracking to earlier points' other
    /// poses after a dead end (mode `backtracking` only; our extension).
    pub backtrack_budget: u32,
}

impl Default for Planning {
    fn default() -> Self {
        Planning {
            interpolation_steps: 50,
            orientation_divisions: 8,
            orientation_divisions_growth: 2,
            orientation_divisions_max: 64,
            mode: PoseSearchMode::Paper,
            max_replans: 20,
            clearance_model: ClearanceModel::Centres,
            backtrack_budget: 2000,
        }
    }
}

impl Planning {
    /// n_d of pass `round` (0 = the first pass, k = the k-th re-plan):
    /// `orientation_divisions * orientation_divisions_growth^round`, capped at
    /// `orientation_divisions_max` (never below `orientation_divisions`).
    ///
    /// ```
    /// use sixaxis_core::scenario::Planning;
    /// let p = Planning::default();
    /// let n: Vec<u32> = (0..5).map(|k| p.orientation_divisions_for_round(k)).collect();
    /// assert_eq!(n, [8, 16, 32, 64, 64]);
    /// ```
    pub fn orientation_divisions_for_round(&self, round: u32) -> u32 {
        let mut n = self.orientation_divisions;
        for _ in 0..round {
            match n.checked_mul(self.orientation_divisions_growth) {
                Some(next) if next <= self.orientation_divisions_max && next != n => n = next,
                _ => break,
            }
        }
        n
    }

    /// The motion checks Algorithm 1 may spend backtracking: `backtrack_budget` in mode
    /// `backtracking`, 0 (the paper's greedy pass) in mode `paper`.
    pub fn effective_backtrack_budget(&self) -> u32 {
        match self.mode {
            PoseSearchMode::Paper => 0,
            PoseSearchMode::Backtracking => self.backtrack_budget,
        }
    }
}

/// One experiment's world: grid, obstacles, arm, rewards, learning and planning parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Short name (the file stem for shipped scenarios).
    pub name: String,
    /// Free text: where the numbers come from, interpretations taken.
    #[serde(default)]
    pub notes: String,
    /// Edge of one grid cell, mm (the paper: 100).
    pub cell_mm: f64,
    /// The cells the terminal may occupy; a move out of them is a collision.
    pub bounds: Bounds,
    /// (x_0, y_0, z_0): the terminal's start cell.
    pub start: Cell,
    /// (x_tag, y_tag, z_tag): the target cell.
    pub target: Cell,
    /// Obstacle cells: unit cubes centred on these cells.
    pub obstacles: Vec<Cell>,
    /// Obstacles as boxes in mm, independent of the grid (beside `obstacles`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub obstacle_boxes_mm: Vec<ObstacleBox>,
    /// d_s (eq. 5): the terminal collides when its distance to an obstacle centre is <= this, cells.
    /// May be left out of a file that gives `terminal_safe_distance_mm`.
    #[serde(default = "unset_distance")]
    pub terminal_safe_distance: f64,
    /// d_p (eq. 11): every arm segment must stay farther than this from every obstacle centre, cells.
    /// May be left out of a file that gives `arm_safe_distance_mm`.
    #[serde(default = "unset_distance")]
    pub arm_safe_distance: f64,
    /// d_s in mm (the physical form); when given, `terminal_safe_distance` = this / `cell_mm`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub terminal_safe_distance_mm: Option<f64>,
    /// d_p in mm (the physical form); when given, `arm_safe_distance` = this / `cell_mm`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub arm_safe_distance_mm: Option<f64>,
    /// Reward parameters.
    #[serde(default)]
    pub rewards: Rewards,
    /// Learning parameters.
    #[serde(default)]
    pub learning: Learning,
    /// The arm.
    #[serde(default)]
    pub arm: ArmSpec,
    /// Pose planning parameters.
    #[serde(default)]
    pub planning: Planning,
}

fn fmt_cell(c: Cell) -> String {
    format!("[{}, {}, {}]", c[0], c[1], c[2])
}

/// Marks a safe distance in cells left out of a file (filled in from its mm form).
fn unset_distance() -> f64 {
    f64::NAN
}

impl Scenario {
    /// A scenario by file path or built-in name (no generated names: those are
    /// [`Scenario::load`]'s, one layer up). A name ending in `.json` or containing a path
    /// separator is always read as a file.
    pub fn open(name_or_path: &str) -> Result<Scenario> {
        let path = Path::new(name_or_path);
        if path.is_file() {
            return Scenario::from_file(path);
        }
        if let Some(text) = builtin_text(name_or_path) {
            return Scenario::from_json(text);
        }
        if name_or_path.ends_with(".json") || name_or_path.contains(std::path::MAIN_SEPARATOR) {
            // Reading it gives the precise I/O error (missing file, permission, ...).
            return Scenario::from_file(path);
        }
        Err(Error::ScenarioNotFound {
            name: name_or_path.to_string(),
            known: BUILTIN_NAMES.join(", "),
        })
    }

    /// A built-in scenario by name.
    pub fn builtin(name: &str) -> Result<Scenario> {
        match builtin_text(name) {
            Some(t) => Scenario::from_json(t),
            None => Err(Error::ScenarioNotFound {
                name: name.to_string(),
                known: BUILTIN_NAMES.join(", "),
            }),
        }
    }

    /// Read and validate a scenario file (at most [`MAX_SCENARIO_BYTES`]: `/dev/zero` or an
    /// endless pipe gives an error, not an exhausted memory).
    pub fn from_file(path: &Path) -> Result<Scenario> {
        let bytes = crate::io::read_bounded(path, MAX_SCENARIO_BYTES)?;
        let text = String::from_utf8(bytes).map_err(|e| {
            Error::io(
                path,
                std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()),
            )
        })?;
        Scenario::from_json(&text)
    }

    /// Parse and validate scenario JSON. A parse error names the field at fault
    /// (`field `learning.alpha`: invalid type: ...`).
    pub fn from_json(text: &str) -> Result<Scenario> {
        let mut de = serde_json::Deserializer::from_str(text);
        let mut s: Scenario = serde_path_to_error::deserialize(&mut de).map_err(|e| {
            let path = e.path().to_string();
            if path == "." {
                Error::ScenarioParse(e.into_inner().to_string())
            } else {
                // A value outside a named set says `= value: reason` (see `named_enum!`).
                let msg = e.into_inner().to_string();
                let sep = if msg.starts_with("= ") { " " } else { ": " };
                Error::ScenarioParse(format!("field `{path}`{sep}{msg}"))
            }
        })?;
        // Trailing text after the object is an error, as with `serde_json::from_str`.
        de.end().map_err(|e| Error::ScenarioParse(e.to_string()))?;
        s.fill_distances_from_mm()?;
        s.validate()?;
        Ok(s)
    }

    /// Pretty JSON text of the scenario.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a scenario always serialises")
    }

    /// The kinematic arm of this scenario.
    pub fn arm(&self) -> Arm {
        self.arm.arm()
    }

    /// Position of a cell's centre, mm.
    pub fn cell_centre_mm(&self, c: Cell) -> nalgebra::Vector3<f64> {
        cell_centre_mm(c, self.cell_mm)
    }

    /// A safe distance in cells left out of a file takes its mm form / `cell_mm`; one given
    /// in neither form is an error naming both fields.
    fn fill_distances_from_mm(&mut self) -> Result<()> {
        let cell_mm = self.cell_mm;
        for (field, cells, mm) in [
            (
                "terminal_safe_distance",
                &mut self.terminal_safe_distance,
                self.terminal_safe_distance_mm,
            ),
            (
                "arm_safe_distance",
                &mut self.arm_safe_distance,
                self.arm_safe_distance_mm,
            ),
        ] {
            if !cells.is_nan() {
                continue;
            }
            match mm {
                Some(mm) if cell_mm.is_finite() && cell_mm > 0.0 => *cells = mm / cell_mm,
                Some(_) => {}
                None => {
                    return Err(Error::ScenarioParse(format!(
                        "missing field `{field}` (cells) or `{field}_mm` (mm)"
                    )))
                }
            }
        }
        Ok(())
    }

    /// d_s in mm: `terminal_safe_distance_mm` if given, else `terminal_safe_distance * cell_mm`.
    pub fn terminal_safe_distance_in_mm(&self) -> f64 {
        self.terminal_safe_distance_mm
            .unwrap_or(self.terminal_safe_distance * self.cell_mm)
    }

    /// d_p in mm: `arm_safe_distance_mm` if given, else `arm_safe_distance * cell_mm`.
    pub fn arm_safe_distance_in_mm(&self) -> f64 {
        self.arm_safe_distance_mm
            .unwrap_or(self.arm_safe_distance * self.cell_mm)
    }

    /// The obstacle that blocks cell `c` for the terminal, if any, described for an error
    /// message: a paper cube whose centre is within `terminal_safe_distance` cells, or a box
    /// within `terminal_safe_distance` mm by [`ObstacleBox::terminal_distance_mm`].
    pub fn terminal_blocker(&self, c: Cell) -> Option<String> {
        let d_s = self.terminal_safe_distance;
        for o in &self.obstacles {
            let d2: i64 = (0..3)
                .map(|i| (c[i] - o[i]) as i64 * (c[i] - o[i]) as i64)
                .sum();
            if (d2 as f64).sqrt() <= d_s {
                return Some(format!("obstacle {}", fmt_cell(*o)));
            }
        }
        let d_s_mm = self.terminal_safe_distance_in_mm();
        let p = c.map(|v| v as f64 * self.cell_mm);
        self.obstacle_boxes_mm
            .iter()
            .enumerate()
            .find_map(|(i, b)| {
                (b.terminal_distance_mm(p) <= d_s_mm).then(|| format!("obstacle_boxes_mm[{i}]"))
            })
    }

    /// Check every field; the error names the field and the value.
    pub fn validate(&self) -> Result<()> {
        fn finite_pos(field: &str, v: f64, allow_zero: bool) -> Result<()> {
            if !v.is_finite() || v < 0.0 || (!allow_zero && v == 0.0) {
                let what = if allow_zero {
                    "must be a finite number >= 0"
                } else {
                    "must be a finite number > 0"
                };
                return Err(Error::invalid(field, v, what));
            }
            Ok(())
        }
        if self.name.trim().is_empty() {
            return Err(Error::invalid("name", "\"\"", "must not be empty"));
        }
        finite_pos("cell_mm", self.cell_mm, false)?;
        let b = &self.bounds;
        for i in 0..3 {
            if b.min[i] > b.max[i] {
                return Err(Error::invalid(
                    "bounds",
                    format!("min {} max {}", fmt_cell(b.min), fmt_cell(b.max)),
                    format!("empty along axis {}: min > max", ["x", "y", "z"][i]),
                ));
            }
        }
        if b.volume() > 1 << 24 {
            return Err(Error::invalid(
                "bounds",
                format!("min {} max {}", fmt_cell(b.min), fmt_cell(b.max)),
                "more than 16,777,216 cells",
            ));
        }
        for (field, c) in [("start", self.start), ("target", self.target)] {
            if !b.contains(c) {
                return Err(Error::invalid(field, fmt_cell(c), "lies outside bounds"));
            }
            if self.obstacles.contains(&c) {
                return Err(Error::invalid(
                    field,
                    fmt_cell(c),
                    "lies inside an obstacle",
                ));
            }
        }
        for (i, ob) in self.obstacle_boxes_mm.iter().enumerate() {
            ob.check(&format!("obstacle_boxes_mm[{i}]"))?;
        }
        if self.start == self.target {
            return Err(Error::invalid(
                "target",
                fmt_cell(self.target),
                "equals the start cell",
            ));
        }
        finite_pos("terminal_safe_distance", self.terminal_safe_distance, true)?;
        finite_pos("arm_safe_distance", self.arm_safe_distance, true)?;
        for (field, cells, mm) in [
            (
                "terminal_safe_distance_mm",
                self.terminal_safe_distance,
                self.terminal_safe_distance_mm,
            ),
            (
                "arm_safe_distance_mm",
                self.arm_safe_distance,
                self.arm_safe_distance_mm,
            ),
        ] {
            let Some(mm) = mm else { continue };
            finite_pos(field, mm, true)?;
            if (cells * self.cell_mm - mm).abs() > 1e-9 * mm.max(1.0) {
                return Err(Error::invalid(
                    field,
                    mm,
                    format!(
                        "disagrees with `{}` = {cells} cells of {} mm; give one of the two, or both equal",
                        field.trim_end_matches("_mm"),
                        self.cell_mm
                    ),
                ));
            }
        }
        // The paper's scenarios have d_s < 1 cell: each cube blocks its own cell. A larger
        // d_s (e.g. a paper world re-gridded to finer cells) blocks a ball of cells around
        // each centre; the start and the target must stay free.
        for (field, c) in [("start", self.start), ("target", self.target)] {
            if let Some(what) = self.terminal_blocker(c) {
                return Err(Error::invalid(
                    field,
                    fmt_cell(c),
                    format!(
                        "is blocked: within terminal_safe_distance ({} mm) of {what}",
                        self.terminal_safe_distance_in_mm()
                    ),
                ));
            }
        }
        let r = &self.rewards;
        for (f, v) in [
            ("rewards.target_reward", r.target_reward),
            ("rewards.step_penalty", r.step_penalty),
            ("rewards.collision_penalty", r.collision_penalty),
            (
                "rewards.repeat_collision_penalty",
                r.repeat_collision_penalty,
            ),
            (
                "rewards.reverse_after_collision_penalty",
                r.reverse_after_collision_penalty,
            ),
            ("rewards.distance_reward", r.distance_reward),
        ] {
            finite_pos(f, v, true)?;
        }
        self.learning.check()?;
        let a = &self.arm;
        if a.dh.len() != 6 {
            return Err(Error::invalid(
                "arm.dh",
                format!("{} rows", a.dh.len()),
                "must have exactly 6 rows",
            ));
        }
        for (i, row) in a.dh.iter().enumerate() {
            for (n, v) in [
                ("alpha_deg", row.alpha_deg),
                ("a_mm", row.a_mm),
                ("d_mm", row.d_mm),
                ("offset_deg", row.offset_deg),
            ] {
                if !v.is_finite() {
                    return Err(Error::invalid(
                        format!("arm.dh[{i}].{n}"),
                        v,
                        "must be finite",
                    ));
                }
            }
        }
        let mut rows = PAPER_DH;
        rows.copy_from_slice(&a.dh);
        if let Err(why) = crate::ik::check_closed_form_family(&rows) {
            return Err(Error::invalid(
                "arm.dh",
                "(table)",
                format!("the closed-form inverse kinematics does not cover this table: {why}"),
            ));
        }
        for (i, v) in a.beta0_deg.iter().enumerate() {
            if !v.is_finite() {
                return Err(Error::invalid(
                    format!("arm.beta0_deg[{i}]"),
                    v,
                    "must be finite",
                ));
            }
        }
        if let Some(lims) = &a.joint_limits_deg {
            for (i, [lo, hi]) in lims.iter().enumerate() {
                if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                    return Err(Error::invalid(
                        format!("arm.joint_limits_deg[{i}]"),
                        format!("[{lo}, {hi}]"),
                        "must be finite with low < high",
                    ));
                }
            }
        }
        let arm = self.arm();
        let reached = arm.fk(&a.beta0_rad()).position_mm;
        let start_mm = self.cell_centre_mm(self.start);
        let miss = (reached - start_mm).norm();
        if miss.is_nan() || miss > 1.0 {
            return Err(Error::invalid(
                "arm.beta0_deg",
                format!("{:?}", a.beta0_deg),
                format!(
                    "its forward kinematics reaches ({:.1}, {:.1}, {:.1}) mm, {:.1} mm from the start cell's centre (at most 1 mm allowed)",
                    reached.x, reached.y, reached.z, miss
                ),
            ));
        }
        let p = &self.planning;
        if p.interpolation_steps == 0 {
            return Err(Error::invalid(
                "planning.interpolation_steps",
                0,
                "must be > 0",
            ));
        }
        if p.orientation_divisions == 0 || p.orientation_divisions > 72 {
            return Err(Error::invalid(
                "planning.orientation_divisions",
                p.orientation_divisions,
                "must be in 1..=72",
            ));
        }
        if p.orientation_divisions_growth == 0 {
            return Err(Error::invalid(
                "planning.orientation_divisions_growth",
                0,
                "must be >= 1 (1 keeps n_d fixed, 2 doubles it on every re-plan)",
            ));
        }
        let cap = p.orientation_divisions_max;
        if cap < p.orientation_divisions || cap > 72 {
            return Err(Error::invalid(
                "planning.orientation_divisions_max",
                cap,
                format!(
                    "must be in {}..=72 (at least planning.orientation_divisions)",
                    p.orientation_divisions
                ),
            ));
        }
        if p.orientation_divisions_growth > 1 {
            let mut n = p.orientation_divisions;
            while n < cap {
                n = n.saturating_mul(p.orientation_divisions_growth);
            }
            if n != cap {
                return Err(Error::invalid(
                    "planning.orientation_divisions_max",
                    cap,
                    format!(
                        "must be orientation_divisions × growth^j ({} × {}^j) so that every orientation grid contains the one before",
                        p.orientation_divisions, p.orientation_divisions_growth
                    ),
                ));
            }
        }
        if let ClearanceModel::Capsules {
            link_radius_mm,
            margin_mm,
        } = p.clearance_model
        {
            finite_pos(
                "planning.clearance_model.link_radius_mm",
                link_radius_mm,
                true,
            )?;
            finite_pos("planning.clearance_model.margin_mm", margin_mm, true)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_load_and_roundtrip() {
        for name in BUILTIN_NAMES {
            let s = Scenario::builtin(name).unwrap();
            let again = Scenario::from_json(&s.to_json()).unwrap();
            assert_eq!(s, again);
        }
    }

    #[test]
    fn paper_simple_matches_table_1() {
        let s = Scenario::builtin("paper_simple").unwrap();
        assert_eq!(s.start, [0, -2, 4]);
        assert_eq!(s.target, [0, 3, 0]);
        assert_eq!(s.obstacles.len(), 19);
        assert_eq!(s.terminal_safe_distance, 0.96);
        assert_eq!(s.arm_safe_distance, 0.76);
        assert_eq!(s.rewards, Rewards::default());
        assert_eq!(s.cell_mm, 100.0);
        let c = Scenario::builtin("paper_complex").unwrap();
        assert_eq!(c.obstacles, s.obstacles);
        assert_eq!(c.terminal_safe_distance, 0.95);
        assert_eq!(c.arm_safe_distance, 0.85);
    }
}
