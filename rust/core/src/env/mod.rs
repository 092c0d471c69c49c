//! Reinforcement-learning environment logic: episodes on the [`GridWorld`], observations,
//! and a batch of environments stepped in one call.
//!
//! The Python package's Gymnasium env (`SixAxisAvoid-v0`) and its native vector env are thin
//! wrappers over this module, so one env and a batch of N give the same trajectories by
//! construction.
//!
//! Entry points:
//! - [`EnvModel`] — what every copy of an env shares: the world, per-state observation rows,
//!   the cells random targets are drawn from.
//! - [`Episode`] — one env's running episode: [`Episode::reset`], [`Episode::step`].
//! - [`BatchEnv`] — N episodes with next-step autoreset and a step cap, stepped together
//!   into caller-provided buffers ([`BatchEnv::step`]; owned ones: [`BatchOutputs`]).
//! - [`EnvModel::goal_rewards`] — the rewards of (achieved, desired) goal pairs, for
//!   hindsight relabelling (`SixAxisAvoidGoal-v0`'s `compute_reward`).
//!
//! # Semantics
//!
//! - Actions are the grid's six moves (`0:+x 1:-x 2:+y 3:-y 4:+z 5:-z`).
//! - The reward is [`GridWorld::step`]'s (eqs. 5, 9, 10, as selected by [`Assist`]) times
//!   `reward_scale`. Eq. 9's memory (the last colliding action) is reset with the episode.
//! - An episode *terminates* when the terminal reaches the target. A [`BatchEnv`] also
//!   *truncates* it after `max_episode_steps` steps (a single env leaves that to Gymnasium's
//!   `TimeLimit`).
//! - **Vector observation** ([`VECTOR_OBS_DIM`] = 13 `f32`): the terminal's cell normalised
//!   to the bounds (`2 (c - min) / max(max - min, 1) - 1`, in [-1, 1]), the target's cell
//!   normalised the same way, six flags (1 if the move of that action collides), and 1 if
//!   the last step collided ([`OBS_TERMINAL`], [`OBS_TARGET`], [`OBS_FLAGS`],
//!   [`OBS_COLLIDED`]). **Index observation**: the state number of the terminal's cell
//!   ([`GridWorld::state_of`]).
//! - **Random targets** (`random_target`): each reset draws the target uniformly from the
//!   free cells other than the start, with the episode's own `ChaCha8Rng` (seeded by
//!   [`Episode::seed`]; draws happen only at resets).
//! - **Extra obstacles** (the arm-aware variant): cells that count as blocked on top of the
//!   scenario's obstacles, e.g. cells no clear arm pose reaches. The start and the target
//!   must not be among them.
//! - **Arm-aware cells** ([`unreachable_cells`]): the free cells (start and target
//!   excluded) at which no pose of the whole arm is clear ([`PosePlanner::cell_reachable`]);
//!   passed as extra obstacles, a move into one counts as a collision.
//!   [`first_clear_pose`] gives a pose to draw at a cell.
//! - **Goals** (goal-conditioned learning): the achieved goal is the terminal's normalised
//!   cell, the desired goal the target's ([`OBS_TERMINAL`], [`OBS_TARGET`] of the vector
//!   observation). [`EnvModel::goal_cell`] inverts the normalisation;
//!   [`EnvModel::goal_rewards`] gives the reward a step that ended at the achieved cell would
//!   have earned with the desired cell as target, from the same eqs. 5 and 10 as the step
//!   ([`base_reward_of`]) plus the step's own eq. 9 term, times `reward_scale`: for the
//!   step's own goals it equals the step's reward to the bit.
//! - **Next-step autoreset** ([`BatchEnv`]): the step after an episode ends resets that env
//!   instead of moving it; that step's action is ignored, its reward is 0 and it neither
//!   terminates nor truncates.
//!
//! The module's parts: the model and the env keywords here, one running episode in
//! `env/episode.rs`, the batch in `env/batch.rs` (the grid's instance of
//! [`crate::batch::Batch`]); both re-exported.

use crate::error::{Error, Result};
use crate::grid::{base_reward_of, cell_distance, Assist, GridWorld, NUM_ACTIONS};
use crate::kinematics::{Joints, TerminalPose};
use crate::options::{check_value, Domain, OptionInfo, OptionValue};
use crate::planner::PosePlanner;
use crate::scenario::{Cell, Scenario};

mod batch;
mod episode;

pub use batch::{BatchBuffers, BatchEnv, BatchOutputs, ObsBuffer};
pub use episode::{Episode, StepOutcome};

/// Length of the vector observation.
pub const VECTOR_OBS_DIM: usize = 13;

/// The terminal's normalised cell in the vector observation (the achieved goal).
pub const OBS_TERMINAL: std::ops::Range<usize> = 0..3;
/// The target's normalised cell in the vector observation (the desired goal).
pub const OBS_TARGET: std::ops::Range<usize> = 3..6;
/// The six collision flags (one per action) in the vector observation.
pub const OBS_FLAGS: std::ops::Range<usize> = 6..12;
/// The flag "the last step collided" in the vector observation.
pub const OBS_COLLIDED: usize = 12;

/// Per-state part of the vector observation: normalised cell (3) and neighbour flags (6).
const STATE_ROW: usize = 9;

/// Options of an environment.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvOptions {
    /// Reward shaping (eqs. 9, 10).
    pub assist: Assist,
    /// Factor applied to every reward (finite, >= 0).
    pub reward_scale: f64,
    /// Draw the target from the free cells at each reset.
    pub random_target: bool,
    /// Cells that count as blocked on top of the scenario's obstacles.
    pub extra_obstacles: Vec<Cell>,
}

impl EnvOptions {
    /// The options an env of scenario `s` gets when no keyword is given: each default of
    /// [`ENV_OPTIONS`]; `assist` None means the scenario's `learning.assist_detour` /
    /// `learning.assist_distance` (docs/SCENARIOS.md, the `assist` default); no extra
    /// obstacles.
    pub fn for_scenario(s: &Scenario) -> EnvOptions {
        let flag = |key| matches!(env_option_default(key), Some(EnvDefault::Bool(true)));
        let reward_scale = match env_option_default("reward_scale") {
            Some(EnvDefault::Float(x)) => x,
            other => unreachable!("reward_scale's default is a number, not {other:?}"),
        };
        EnvOptions {
            assist: Assist::from_scenario(s),
            reward_scale,
            random_target: flag("random_target"),
            extra_obstacles: Vec::new(),
        }
    }
}

/// The domain of `num_envs`: 1 to 2^24 environments in one batch.
const NUM_ENVS: Domain = Domain::Int {
    min: 1,
    max: 1 << 24,
};

/// The default of an env keyword.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EnvDefault {
    /// `None`: left to the scenario or to Gymnasium (the keyword is nullable).
    None,
    /// A bool.
    Bool(bool),
    /// A whole number.
    Int(i64),
    /// A number.
    Float(f64),
    /// A name.
    Text(&'static str),
}

impl EnvDefault {
    /// The default as an option value (`None` for [`EnvDefault::None`]).
    pub fn value(self) -> Option<OptionValue> {
        match self {
            EnvDefault::None => None,
            EnvDefault::Bool(b) => Some(OptionValue::Bool(b)),
            EnvDefault::Int(i) => Some(OptionValue::Int(i as i128)),
            EnvDefault::Float(x) => Some(OptionValue::Float(x)),
            EnvDefault::Text(t) => Some(OptionValue::Text(t.to_string())),
        }
    }
}

/// An env keyword: its [`OptionInfo`] (key, domain, unit, doc) and its default.
#[derive(Debug, Clone, Copy)]
pub struct EnvOption {
    /// Key, domain, unit and doc line.
    pub info: OptionInfo,
    /// What an env built without the keyword gets.
    pub default: EnvDefault,
}

impl std::ops::Deref for EnvOption {
    type Target = OptionInfo;
    fn deref(&self) -> &OptionInfo {
        &self.info
    }
}

/// One line of an env keyword table (`ENV_OPTIONS`, the joint env's `JOINT_ENV_OPTIONS`).
pub(crate) const fn env_option(
    key: &'static str,
    domain: Domain,
    default: EnvDefault,
    unit: &'static str,
    doc: &'static str,
) -> EnvOption {
    EnvOption {
        info: OptionInfo {
            key,
            field: "",
            domain,
            unit,
            doc,
        },
        default,
    }
}

/// The keywords of the Gymnasium envs (`SixAxisAvoid-v0` and its variants, the native vector
/// env), declared once: the envs check every keyword against this table through the
/// bindings, and [`EnvModel::new`] / [`BatchEnv::new`] check theirs with the same domains.
/// Each line gives the keyword's default; `ENV_NULLABLE` names those that may also be `None`.
pub static ENV_OPTIONS: [EnvOption; 11] = [
    env_option("obs_type", Domain::Choice(&["vector", "index"]), EnvDefault::Text("vector"), "", "The observation: `vector` (terminal, target and neighbour flags, float32) or `index` (the state number); the goal-conditioned Dict is the id SixAxisAvoidGoal-v0."),
    env_option("assist", Domain::Bool, EnvDefault::None, "", "The assisted strategies (eqs. 9 and 10) on or off; None: the scenario's `learning.assist_detour` / `learning.assist_distance` (docs/SCENARIOS.md, the `assist` default)."),
    env_option("reward_scale", Domain::NON_NEGATIVE, EnvDefault::Float(1.0), "", "Factor applied to every reward."),
    env_option("random_target", Domain::Bool, EnvDefault::Bool(false), "", "Draw the target from the free cells at every reset."),
    env_option("arm_aware", Domain::Bool, EnvDefault::Bool(false), "", "Cells no clear arm pose reaches count as obstacles."),
    env_option("num_envs", NUM_ENVS, EnvDefault::Int(1), "envs", "Environments of the native vector env."),
    env_option("max_episode_steps", Domain::u32_from(1), EnvDefault::None, "steps", "Truncation after this many steps; None: the scenario's `learning.max_steps_per_episode`."),
    env_option("render_mode", Domain::Choice(&["human", "rgb_array"]), EnvDefault::None, "", "Gymnasium's render mode, or None."),
    env_option("render_arm", Domain::Bool, EnvDefault::Bool(false), "", "Draw the arm's clearest pose in the rendered frames."),
    env_option("render_size", Domain::Int { min: 64, max: 4096 }, EnvDefault::Int(512), "pixels", "Edge of a rendered frame."),
    env_option("copy", Domain::Bool, EnvDefault::Bool(true), "", "Return copies of the vector env's observation buffers (Gymnasium's `copy`)."),
];

/// The keywords of [`ENV_OPTIONS`] that may be `None`: those whose default is
/// [`EnvDefault::None`] (a unit test checks the two agree).
pub const ENV_NULLABLE: &[&str] = &["assist", "max_episode_steps", "render_mode"];

/// The entry of [`ENV_OPTIONS`] for `key`.
pub fn env_option_info(key: &str) -> Option<&'static OptionInfo> {
    ENV_OPTIONS.iter().find(|o| o.key == key).map(|o| &o.info)
}

/// The default of the env keyword `key` (None: no such keyword).
pub fn env_option_default(key: &str) -> Option<EnvDefault> {
    ENV_OPTIONS.iter().find(|o| o.key == key).map(|o| o.default)
}

/// What every copy of an environment shares.
#[derive(Debug)]
pub struct EnvModel {
    world: GridWorld,
    opts: EnvOptions,
    /// Per state: normalised cell and neighbour flags.
    rows: Vec<[f32; STATE_ROW]>,
    /// States random targets are drawn from (free, not the start), in state order.
    target_states: Vec<u32>,
}

impl EnvModel {
    /// The model of a scenario with these options.
    pub fn new(scenario: &Scenario, opts: EnvOptions) -> Result<EnvModel> {
        check_value(
            "reward_scale",
            &Domain::NON_NEGATIVE,
            &OptionValue::Float(opts.reward_scale),
        )?;
        for (what, c) in [("start", scenario.start), ("target", scenario.target)] {
            if opts.extra_obstacles.contains(&c) {
                return Err(Error::argument(
                    "extra_obstacles",
                    format!("[{}, {}, {}]", c[0], c[1], c[2]),
                    format!("contains the {what} cell"),
                ));
            }
        }
        let world = GridWorld::with_extra_obstacles(scenario, &opts.extra_obstacles)?;
        let b = world.bounds();
        let half: [f32; 3] = std::array::from_fn(|i| ((b.max[i] - b.min[i]).max(1)) as f32 / 2.0);
        let n = world.num_states();
        let rows = (0..n)
            .map(|s| {
                let c = world.cell_of(s);
                let mut r = [0f32; STATE_ROW];
                for i in 0..3 {
                    r[i] = (c[i] - b.min[i]) as f32 / half[i] - 1.0;
                }
                for a in 0..NUM_ACTIONS {
                    r[3 + a] = if world.move_collides(s, a) { 1.0 } else { 0.0 };
                }
                r
            })
            .collect();
        let start = world.start();
        let target_states: Vec<u32> = (0..n)
            .filter(|&s| s != start && !world.is_blocked(s))
            .map(|s| s as u32)
            .collect();
        if opts.random_target && target_states.is_empty() {
            return Err(Error::argument(
                "random_target",
                true,
                "the scenario has no free cell besides the start",
            ));
        }
        Ok(EnvModel {
            world,
            opts,
            rows,
            target_states,
        })
    }

    /// The world (with the extra obstacles, the scenario's target).
    pub fn world(&self) -> &GridWorld {
        &self.world
    }

    /// The options.
    pub fn options(&self) -> &EnvOptions {
        &self.opts
    }

    /// Number of states (cells inside bounds).
    pub fn num_states(&self) -> usize {
        self.world.num_states()
    }

    /// The candidate targets: the cells random targets are drawn from (free, not the
    /// start), in state order.
    pub fn target_candidates(&self) -> Vec<Cell> {
        self.target_states
            .iter()
            .map(|&s| self.world.cell_of(s as usize))
            .collect()
    }

    /// The normalised position of a state's cell (as in the vector observation).
    pub fn normalised(&self, state: usize) -> [f32; 3] {
        let r = &self.rows[state];
        [r[0], r[1], r[2]]
    }

    /// The cell of a normalised position (a goal): the inverse of the vector observation's
    /// `2 (c - min) / max(max - min, 1) - 1`, rounded to the nearest cell. Positions outside
    /// [-1, 1] give cells outside the bounds.
    pub fn goal_cell(&self, goal: [f64; 3]) -> Cell {
        let b = self.world.bounds();
        std::array::from_fn(|i| {
            let half = ((b.max[i] - b.min[i]).max(1)) as f64 / 2.0;
            b.min[i] + ((goal[i] + 1.0) * half).round() as i32
        })
    }

    /// The rewards of `n` (achieved, desired) goal pairs (`achieved`, `desired`: `3 n`
    /// normalised coordinates, row-major, each finite and in [-1, 1]), given each step's
    /// `collided` flag and eq. 9 term (`detour_penalty`, as [`StepOutcome::detour_penalty`];
    /// used only with detour assist). Pair `i` gets eq. 5 + eq. 10 ([`base_reward_of`]) for a
    /// move that ended at the achieved cell with the desired cell as target (`d_o` from the
    /// start to the desired cell), plus `detour_penalty[i]`, times `reward_scale`: the same
    /// arithmetic as [`Episode::step`], so a step's own goals give its reward to the bit.
    pub fn goal_rewards(
        &self,
        achieved: &[f64],
        desired: &[f64],
        collided: &[bool],
        detour_penalty: &[f64],
    ) -> Result<Vec<f64>> {
        let n = collided.len();
        let lengths = [
            ("achieved_goal", achieved.len(), 3 * n),
            ("desired_goal", desired.len(), 3 * n),
            ("detour_penalty", detour_penalty.len(), n),
        ];
        for (name, len, want) in lengths {
            if len != want {
                return Err(Error::argument(
                    name,
                    format!("{len} values"),
                    format!("expected {want} (one per goal pair, {n} pairs)"),
                ));
            }
        }
        for (name, goals) in [("achieved_goal", achieved), ("desired_goal", desired)] {
            if let Some((i, g)) = goals
                .iter()
                .enumerate()
                .find(|(_, g)| !(-1.0..=1.0).contains(*g))
            {
                return Err(Error::argument(
                    name,
                    format!("{g} at pair {}", i / 3),
                    "goals are normalised cells: each coordinate must be a number in [-1, 1]",
                ));
            }
        }
        if let Some((i, d)) = detour_penalty
            .iter()
            .enumerate()
            .find(|(_, d)| !d.is_finite())
        {
            return Err(Error::argument(
                "detour_penalty",
                format!("{d} at pair {i}"),
                "must be a finite number (eq. 9's part of the step's reward)",
            ));
        }
        let w = &self.world;
        let start = w.cell_of(w.start());
        let (assist, scale) = (self.opts.assist, self.opts.reward_scale);
        let cell = |g: &[f64], i: usize| self.goal_cell([g[3 * i], g[3 * i + 1], g[3 * i + 2]]);
        Ok((0..n)
            .map(|i| {
                let (a, d) = (cell(achieved, i), cell(desired, i));
                let mut reward = base_reward_of(
                    w.rewards(),
                    collided[i],
                    a == d,
                    cell_distance(start, d),
                    cell_distance(a, d),
                    assist,
                );
                if assist.detour {
                    reward += detour_penalty[i];
                }
                reward * scale
            })
            .collect())
    }
}

/// The free cells of a scenario's grid, start and target excluded, at which no clear pose of
/// the whole arm exists (`!PosePlanner::cell_reachable`), in state order.
pub fn unreachable_cells(scenario: &Scenario) -> Result<Vec<Cell>> {
    let world = GridWorld::new(scenario)?;
    let planner = PosePlanner::from_scenario(scenario);
    let (start, target) = (world.start(), world.target());
    Ok((0..world.num_states())
        .filter(|&s| s != start && s != target && !world.is_blocked(s))
        .map(|s| world.cell_of(s))
        .filter(|&c| !planner.cell_reachable(c))
        .collect())
}

/// The first clear pose (radians) whose terminal is at the centre of `cell`: orientations
/// in the planner's grid order, IK solutions in IK order, within joint limits. `None` if
/// there is none.
pub fn first_clear_pose(planner: &PosePlanner, cell_mm: f64, cell: Cell) -> Option<Joints> {
    let position_mm = crate::scenario::cell_centre_mm(cell, cell_mm);
    let arm = planner.arm();
    planner.orientations().iter().find_map(|o| {
        arm.ik(&TerminalPose {
            position_mm,
            rotation: o.rotation,
        })
        .iter()
        .find(|q| planner.within_limits(q) && planner.clearance().pose_is_clear(&arm.points_mm(q)))
        .copied()
    })
}

#[cfg(test)]
mod tests;
