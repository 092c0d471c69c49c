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
//!   into caller-provided buffers ([`BatchEnv::step`]).
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

use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};
use crate::grid::{base_reward_of, cell_distance, Assist, GridWorld, NUM_ACTIONS};
use crate::kinematics::{Joints, TerminalPose};
use crate::options::{check_value, Domain, OptionInfo, OptionValue};
use crate::planner::PosePlanner;
use crate::scenario::{Cell, Scenario};

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

impl Default for EnvOptions {
    fn default() -> Self {
        EnvOptions {
            assist: Assist::on(),
            reward_scale: 1.0,
            random_target: false,
            extra_obstacles: Vec::new(),
        }
    }
}

/// The domain of `reward_scale`: a finite number >= 0.
const REWARD_SCALE: Domain = Domain::Float {
    min: 0.0,
    max: f64::INFINITY,
    open_min: false,
};
/// The domain of `num_envs`: 1 to 2^24 environments in one batch.
const NUM_ENVS: Domain = Domain::Int {
    min: 1,
    max: 1 << 24,
};

const fn env_option(
    key: &'static str,
    domain: Domain,
    unit: &'static str,
    doc: &'static str,
) -> OptionInfo {
    OptionInfo {
        key,
        field: "",
        domain,
        unit,
        doc,
    }
}

/// The keywords of the Gymnasium envs (`SixAxisAvoid-v0` and its variants, the native vector
/// env), declared once: the envs check every keyword against this table through the
/// bindings, and [`EnvModel::new`] / [`BatchEnv::new`] check theirs with the same domains.
/// `ENV_NULLABLE` names those that may also be `None`.
pub static ENV_OPTIONS: [OptionInfo; 11] = [
    env_option("obs_type", Domain::Choice(&["vector", "index"]), "", "The observation: `vector` (terminal, target and neighbour flags, float32) or `index` (the state number); the goal-conditioned Dict is the id SixAxisAvoidGoal-v0."),
    env_option("assist", Domain::Bool, "", "The assisted strategies (eqs. 9 and 10) on or off; None: the scenario's `learning.assist_detour` / `learning.assist_distance` (docs/SCENARIOS.md, the `assist` default)."),
    env_option("reward_scale", REWARD_SCALE, "", "Factor applied to every reward."),
    env_option("random_target", Domain::Bool, "", "Draw the target from the free cells at every reset."),
    env_option("arm_aware", Domain::Bool, "", "Cells no clear arm pose reaches count as obstacles."),
    env_option("num_envs", NUM_ENVS, "envs", "Environments of the native vector env."),
    env_option("max_episode_steps", Domain::u32_from(1), "steps", "Truncation after this many steps; None: the scenario's `learning.max_steps_per_episode`."),
    env_option("render_mode", Domain::Choice(&["human", "rgb_array"]), "", "Gymnasium's render mode, or None."),
    env_option("render_arm", Domain::Bool, "", "Draw the arm's clearest pose in the rendered frames."),
    env_option("render_size", Domain::Int { min: 64, max: 4096 }, "pixels", "Edge of a rendered frame."),
    env_option("copy", Domain::Bool, "", "Return copies of the vector env's observation buffers (Gymnasium's `copy`)."),
];

/// The keywords of [`ENV_OPTIONS`] that may be `None`.
pub const ENV_NULLABLE: &[&str] = &["assist", "max_episode_steps", "render_mode"];

/// The entry of [`ENV_OPTIONS`] for `key`.
pub fn env_option_info(key: &str) -> Option<&'static OptionInfo> {
    ENV_OPTIONS.iter().find(|i| i.key == key)
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
            &REWARD_SCALE,
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

/// One step's outcome.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepOutcome {
    /// Reward, times `reward_scale`.
    pub reward: f64,
    /// The move collided (the terminal stayed).
    pub collided: bool,
    /// The terminal reached the target: the episode terminates.
    pub reached: bool,
    /// Eq. 9's part of the reward (<= 0, before `reward_scale`; 0 without detour assist).
    pub detour_penalty: f64,
}

/// One environment's running episode.
#[derive(Debug, Clone)]
pub struct Episode {
    state: u32,
    target: u32,
    last_collided_action: Option<u8>,
    collided: bool,
    steps: u32,
    rng: ChaCha8Rng,
    /// The world with this episode's target, when it differs from the model's.
    own_world: Option<GridWorld>,
}

impl Episode {
    /// A new episode at the model's start (call [`Episode::reset`] before stepping).
    pub fn new(model: &EnvModel) -> Episode {
        Episode {
            state: model.world.start() as u32,
            target: model.world.target() as u32,
            last_collided_action: None,
            collided: false,
            steps: 0,
            rng: ChaCha8Rng::seed_from_u64(0),
            own_world: None,
        }
    }

    /// Seed the generator of random targets.
    pub fn seed(&mut self, seed: u64) {
        self.rng = ChaCha8Rng::seed_from_u64(seed);
    }

    #[inline]
    fn world<'a>(&'a self, model: &'a EnvModel) -> &'a GridWorld {
        self.own_world.as_ref().unwrap_or(&model.world)
    }

    /// Start a new episode at the start cell (drawing a target if `random_target`).
    pub fn reset(&mut self, model: &EnvModel) {
        let base = &model.world;
        self.state = base.start() as u32;
        self.last_collided_action = None;
        self.collided = false;
        self.steps = 0;
        if model.opts.random_target {
            let k = self.rng.random_range(0..model.target_states.len());
            let t = model.target_states[k];
            self.target = t;
            if t as usize == base.target() {
                self.own_world = None;
            } else {
                let w = self.own_world.get_or_insert_with(|| base.clone());
                w.set_target(base.cell_of(t as usize))
                    .expect("target candidates are free cells other than the start");
            }
        } else {
            self.target = base.target() as u32;
            self.own_world = None;
        }
    }

    /// Move the terminal with `action` (< 6; checked by the caller).
    #[inline]
    pub fn step(&mut self, model: &EnvModel, action: usize) -> StepOutcome {
        let assist = model.opts.assist;
        let last = self.last_collided_action.map(usize::from);
        let world = self.world(model);
        let t = world.step(self.state as usize, action, last, assist);
        let detour_penalty = if assist.detour {
            world.detour_penalty(action, t.collided, last)
        } else {
            0.0
        };
        self.state = t.next as u32;
        self.collided = t.collided;
        self.last_collided_action = if t.collided { Some(action as u8) } else { None };
        self.steps += 1;
        StepOutcome {
            reward: t.reward * model.opts.reward_scale,
            collided: t.collided,
            reached: t.reached,
            detour_penalty,
        }
    }

    /// The terminal's state.
    #[inline]
    pub fn state(&self) -> usize {
        self.state as usize
    }

    /// The target's state.
    #[inline]
    pub fn target(&self) -> usize {
        self.target as usize
    }

    /// Steps taken since the reset.
    #[inline]
    pub fn steps(&self) -> u32 {
        self.steps
    }

    /// Whether the last step collided.
    #[inline]
    pub fn last_collided(&self) -> bool {
        self.collided
    }

    /// The action of the last step if it collided (eq. 9's memory).
    #[inline]
    pub fn last_collided_action(&self) -> Option<usize> {
        self.last_collided_action.map(usize::from)
    }

    /// Distance from the terminal to the target, cells.
    #[inline]
    pub fn distance_to_target(&self, model: &EnvModel) -> f64 {
        self.world(model)
            .distance_to_target_cells(self.state as usize)
    }

    /// `d_o`: distance from the start to this episode's target, cells.
    pub fn start_distance(&self, model: &EnvModel) -> f64 {
        self.world(model).start_distance_cells()
    }

    /// Write the vector observation into `out` (length [`VECTOR_OBS_DIM`]).
    #[inline]
    pub fn write_vector_obs(&self, model: &EnvModel, out: &mut [f32]) {
        let row = &model.rows[self.state as usize];
        let trow = &model.rows[self.target as usize];
        out[OBS_TERMINAL].copy_from_slice(&row[..3]);
        out[OBS_TARGET].copy_from_slice(&trow[..3]);
        out[OBS_FLAGS].copy_from_slice(&row[3..9]);
        out[OBS_COLLIDED] = if self.collided { 1.0 } else { 0.0 };
    }
}

/// The observation buffer of a batch.
#[derive(Debug)]
pub enum ObsBuffer<'a> {
    /// `n * VECTOR_OBS_DIM` floats, row-major.
    Vector(&'a mut [f32]),
    /// `n` state numbers.
    Index(&'a mut [i64]),
}

/// Caller-provided output buffers of a batch step or reset (each of length `n`, `cells`
/// of length `3 n`).
#[derive(Debug)]
pub struct BatchBuffers<'a> {
    /// Observations.
    pub obs: ObsBuffer<'a>,
    /// Rewards.
    pub rewards: &'a mut [f64],
    /// The episode reached its target.
    pub terminated: &'a mut [bool],
    /// The episode hit the step cap.
    pub truncated: &'a mut [bool],
    /// The step collided.
    pub collided: &'a mut [bool],
    /// Distance from the terminal to the target, cells.
    pub distance: &'a mut [f64],
    /// The terminal's cell, row-major `(n, 3)`.
    pub cells: &'a mut [i32],
    /// Eq. 9's part of the step's reward (<= 0, before `reward_scale`; 0 after a reset).
    pub detour_penalty: &'a mut [f64],
}

/// N environments stepped together, with next-step autoreset and a step cap.
#[derive(Debug)]
pub struct BatchEnv {
    model: Arc<EnvModel>,
    episodes: Vec<Episode>,
    needs_reset: Vec<bool>,
    max_episode_steps: u32,
}

impl BatchEnv {
    /// `n` environments of `model`, truncated after `max_episode_steps` steps.
    pub fn new(model: Arc<EnvModel>, n: usize, max_episode_steps: u32) -> Result<BatchEnv> {
        check_value("num_envs", &NUM_ENVS, &OptionValue::Int(n as i128))?;
        check_value(
            "max_episode_steps",
            &Domain::u32_from(1),
            &OptionValue::Int(max_episode_steps as i128),
        )?;
        let ep = Episode::new(&model);
        Ok(BatchEnv {
            episodes: vec![ep; n],
            needs_reset: vec![true; n],
            model,
            max_episode_steps,
        })
    }

    /// Number of environments.
    pub fn len(&self) -> usize {
        self.episodes.len()
    }

    /// Always false (a batch has at least one env).
    pub fn is_empty(&self) -> bool {
        self.episodes.is_empty()
    }

    /// The shared model.
    pub fn model(&self) -> &Arc<EnvModel> {
        &self.model
    }

    /// The episodes.
    pub fn episodes(&self) -> &[Episode] {
        &self.episodes
    }

    /// The step cap.
    pub fn max_episode_steps(&self) -> u32 {
        self.max_episode_steps
    }

    /// Seed env `i`'s generator (random targets).
    pub fn seed(&mut self, seeds: &[u64]) -> Result<()> {
        if seeds.len() != self.len() {
            return Err(Error::argument(
                "seeds",
                format!("{} seeds", seeds.len()),
                format!("expected one per env ({})", self.len()),
            ));
        }
        for (ep, &s) in self.episodes.iter_mut().zip(seeds) {
            ep.seed(s);
        }
        Ok(())
    }

    fn check(&self, buf: &BatchBuffers<'_>) -> Result<()> {
        let n = self.len();
        let obs_ok = match &buf.obs {
            ObsBuffer::Vector(o) => o.len() == n * VECTOR_OBS_DIM,
            ObsBuffer::Index(o) => o.len() == n,
        };
        let ok = obs_ok
            && buf.rewards.len() == n
            && buf.terminated.len() == n
            && buf.truncated.len() == n
            && buf.collided.len() == n
            && buf.distance.len() == n
            && buf.detour_penalty.len() == n
            && buf.cells.len() == 3 * n;
        if ok {
            Ok(())
        } else {
            Err(Error::argument(
                "buffers",
                "lengths",
                format!("every buffer must hold {n} envs"),
            ))
        }
    }

    #[inline]
    fn write(&self, i: usize, buf: &mut BatchBuffers<'_>) {
        let ep = &self.episodes[i];
        let m = &*self.model;
        match &mut buf.obs {
            ObsBuffer::Vector(o) => {
                ep.write_vector_obs(m, &mut o[i * VECTOR_OBS_DIM..(i + 1) * VECTOR_OBS_DIM])
            }
            ObsBuffer::Index(o) => o[i] = ep.state as i64,
        }
        buf.distance[i] = ep.distance_to_target(m);
        let c = m.world.cell_of(ep.state as usize);
        buf.cells[3 * i..3 * i + 3].copy_from_slice(&c);
        buf.collided[i] = ep.collided;
    }

    fn reset_one(&mut self, i: usize, buf: &mut BatchBuffers<'_>) {
        self.episodes[i].reset(&self.model);
        self.needs_reset[i] = false;
        buf.rewards[i] = 0.0;
        buf.terminated[i] = false;
        buf.truncated[i] = false;
        buf.detour_penalty[i] = 0.0;
        self.write(i, buf);
    }

    /// Reset the envs where `mask` is true (all if `None`) and write their observations.
    /// Entries of other envs are left as they were.
    pub fn reset(&mut self, mask: Option<&[bool]>, mut buf: BatchBuffers<'_>) -> Result<()> {
        self.check(&buf)?;
        if let Some(m) = mask {
            if m.len() != self.len() {
                return Err(Error::argument(
                    "reset_mask",
                    format!("{} entries", m.len()),
                    format!("expected one per env ({})", self.len()),
                ));
            }
        }
        for i in 0..self.len() {
            if mask.is_none_or(|m| m[i]) {
                self.reset_one(i, &mut buf);
            }
        }
        Ok(())
    }

    /// Step every env with its action (each < 6, all checked before any env moves). Envs
    /// whose episode ended at the previous step are reset instead (next-step autoreset).
    pub fn step<A>(&mut self, actions: &[A], mut buf: BatchBuffers<'_>) -> Result<()>
    where
        A: Copy + TryInto<usize> + std::fmt::Display,
    {
        self.check(&buf)?;
        let n = self.len();
        if actions.len() != n {
            return Err(Error::argument(
                "actions",
                format!("{} actions", actions.len()),
                format!("expected one per env ({n})"),
            ));
        }
        for (i, &a) in actions.iter().enumerate() {
            match a.try_into() {
                Ok(v) if v < NUM_ACTIONS => {}
                _ => {
                    return Err(Error::argument(
                        "actions",
                        format!("{a} at index {i}"),
                        "each action must be an integer in 0..6",
                    ))
                }
            }
        }
        let model = Arc::clone(&self.model);
        for (i, &action) in actions.iter().enumerate() {
            if self.needs_reset[i] {
                self.reset_one(i, &mut buf);
                continue;
            }
            let a = action.try_into().unwrap_or(0);
            let ep = &mut self.episodes[i];
            let out = ep.step(&model, a);
            let truncated = !out.reached && ep.steps >= self.max_episode_steps;
            buf.rewards[i] = out.reward;
            buf.terminated[i] = out.reached;
            buf.truncated[i] = truncated;
            buf.detour_penalty[i] = out.detour_penalty;
            self.needs_reset[i] = out.reached || truncated;
            self.write(i, &mut buf);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(random_target: bool) -> Arc<EnvModel> {
        let s = Scenario::builtin("paper_simple").unwrap();
        Arc::new(
            EnvModel::new(
                &s,
                EnvOptions {
                    random_target,
                    ..EnvOptions::default()
                },
            )
            .unwrap(),
        )
    }

    #[test]
    fn episode_follows_grid_world() {
        let m = model(false);
        let mut ep = Episode::new(&m);
        ep.reset(&m);
        let w = m.world().clone();
        let mut s = w.start();
        let mut last = None;
        for a in [5usize, 5, 3, 2, 2, 2, 0, 0, 1, 4] {
            let t = w.step(s, a, last, Assist::on());
            let o = ep.step(&m, a);
            assert_eq!(o.reward, t.reward);
            assert_eq!(o.collided, t.collided);
            s = t.next;
            last = if t.collided { Some(a) } else { None };
            assert_eq!(ep.state(), s);
        }
        let mut obs = [0f32; VECTOR_OBS_DIM];
        ep.write_vector_obs(&m, &mut obs);
        assert!(obs.iter().all(|v| (-1.0..=1.0).contains(v)));
    }

    #[test]
    fn shortest_path_terminates_with_target_reward() {
        let m = model(false);
        let w = m.world();
        let path = w.shortest_path().unwrap();
        let mut ep = Episode::new(&m);
        ep.reset(&m);
        let mut last = None;
        for pair in path.windows(2) {
            let d = [0, 1, 2].map(|i| pair[1][i] - pair[0][i]);
            let a = crate::grid::ACTIONS.iter().position(|m| *m == d).unwrap();
            last = Some(ep.step(&m, a));
        }
        assert!(last.unwrap().reached);
        assert_eq!(ep.distance_to_target(&m), 0.0);
    }

    #[test]
    fn goal_rewards_equal_step_rewards_to_the_bit() {
        for (random_target, assist, scale) in [
            (true, Assist::on(), 1.0),
            (true, Assist::off(), 1e-4),
            (false, Assist::on(), 0.3),
        ] {
            let s = Scenario::builtin("paper_simple").unwrap();
            let m = EnvModel::new(
                &s,
                EnvOptions {
                    random_target,
                    assist,
                    reward_scale: scale,
                    ..EnvOptions::default()
                },
            )
            .unwrap();
            let mut ep = Episode::new(&m);
            ep.seed(7);
            let mut rng = ChaCha8Rng::seed_from_u64(3);
            let (mut ach, mut des, mut col, mut det, mut want) =
                (vec![], vec![], vec![], vec![], vec![]);
            let mut collisions = 0;
            for _ in 0..20 {
                ep.reset(&m);
                for _ in 0..30 {
                    let out = ep.step(&m, rng.random_range(0..NUM_ACTIONS));
                    let mut obs = [0f32; VECTOR_OBS_DIM];
                    ep.write_vector_obs(&m, &mut obs);
                    ach.extend(obs[OBS_TERMINAL].iter().map(|&v| v as f64));
                    des.extend(obs[OBS_TARGET].iter().map(|&v| v as f64));
                    col.push(out.collided);
                    det.push(out.detour_penalty);
                    want.push(out.reward);
                    collisions += out.collided as usize;
                    if out.reached {
                        break;
                    }
                }
            }
            assert!(collisions > 0);
            let got = m.goal_rewards(&ach, &des, &col, &det).unwrap();
            assert_eq!(
                got.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                want.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            );
        }
    }

    #[test]
    fn goal_rewards_relabel_and_check_their_inputs() {
        let m = model(false);
        let w = m.world();
        let t = m.normalised(w.target()).map(f64::from);
        let r = m.goal_rewards(&t, &t, &[false], &[0.0]).unwrap();
        // Reaching the desired cell: +r plus eq. 10's r_e * d_o (d_t = 0).
        assert_eq!(r[0], 20000.0 + 40.0 * w.start_distance_cells());
        let c = m.goal_rewards(&t, &t, &[true], &[0.0]).unwrap();
        assert_eq!(c[0], -8000.0 + 40.0 * w.start_distance_cells());
        let err = m.goal_rewards(&t, &t[..2], &[false], &[0.0]).unwrap_err();
        assert!(err.to_string().contains("desired_goal"), "{err}");
        let err = m
            .goal_rewards(&[2.0, 0.0, 0.0], &t, &[false], &[0.0])
            .unwrap_err();
        assert!(err.to_string().contains("achieved_goal"), "{err}");
        let err = m.goal_rewards(&t, &t, &[false], &[f64::NAN]).unwrap_err();
        assert!(err.to_string().contains("detour_penalty"), "{err}");
        for s in 0..w.num_states() {
            assert_eq!(m.goal_cell(m.normalised(s).map(f64::from)), w.cell_of(s));
        }
    }

    #[test]
    fn arm_aware_cells() {
        let s = Scenario::builtin("paper_simple").unwrap();
        let cells = unreachable_cells(&s).unwrap();
        assert!(!cells.contains(&s.start) && !cells.contains(&s.target));
        assert!(!cells.iter().any(|c| s.obstacles.contains(c)));
        let planner = PosePlanner::from_scenario(&s);
        for c in &cells {
            assert!(first_clear_pose(&planner, s.cell_mm, *c).is_none());
        }
        let q = first_clear_pose(&planner, s.cell_mm, s.target).expect("the target is reachable");
        let p = planner.arm().fk(&q).position_mm;
        assert!((p - s.cell_centre_mm(s.target)).norm() < 1e-6);
        // The arm-aware model blocks those cells.
        let m = EnvModel::new(
            &s,
            EnvOptions {
                extra_obstacles: cells.clone(),
                ..EnvOptions::default()
            },
        )
        .unwrap();
        for c in &cells {
            assert!(m.world().is_blocked(m.world().state_of(*c).unwrap()));
        }
    }

    #[test]
    fn batch_truncates_and_autoresets_next_step() {
        let m = model(true);
        let n = 3;
        let mut b = BatchEnv::new(m, n, 4).unwrap();
        b.seed(&[1, 2, 3]).unwrap();
        let mut obs = vec![0f32; n * VECTOR_OBS_DIM];
        let (mut r, mut te, mut tr, mut co, mut d) = (
            vec![0.0; n],
            vec![false; n],
            vec![false; n],
            vec![false; n],
            vec![0.0; n],
        );
        let mut cells = vec![0i32; 3 * n];
        let mut detour = vec![0.0; n];
        macro_rules! bufs {
            () => {
                BatchBuffers {
                    obs: ObsBuffer::Vector(&mut obs),
                    rewards: &mut r,
                    terminated: &mut te,
                    truncated: &mut tr,
                    collided: &mut co,
                    distance: &mut d,
                    cells: &mut cells,
                    detour_penalty: &mut detour,
                }
            };
        }
        b.reset(None, bufs!()).unwrap();
        for k in 1..=4 {
            b.step(&[1u8, 1, 1], bufs!()).unwrap();
            assert_eq!(tr, vec![k == 4; n]);
        }
        b.step(&[1u8, 1, 1], bufs!()).unwrap();
        assert_eq!(r, vec![0.0; n]);
        assert!(b.episodes().iter().all(|e| e.steps() == 0));
        assert!(b.step(&[6u8, 0, 0], bufs!()).is_err());
    }
}
