//! The joint-space environment (`SixAxisAvoidJoint-v0`): the whole arm moves in joint space
//! with continuous actions, every step checked by the exact capsule clearance
//! ([`crate::clearance`]), the paper's reward shaping carried over (docs/JOINT.md).
//!
//! Entry points:
//! - [`JointOptions`] / [`JOINT_ENV_OPTIONS`] — the env's keywords, declared once (key,
//!   domain, unit, doc); [`JointOptions::from_options`] reads them from an [`Options`] map.
//! - [`JointModel::new`] — what every copy of the env shares: the arm, the clearance of the
//!   scenario's obstacles (boxes in mm), joint limits (rad), the target (mm), the workspace.
//! - [`JointEpisode`] — one running episode: [`JointEpisode::reset`] (to beta_0, rad),
//!   [`JointEpisode::step`] (an action in [-1, 1]^6).
//! - [`JointBatch`] — N episodes with Gymnasium 1.x next-step autoreset and a step cap,
//!   stepped together into caller-provided buffers ([`JointBuffers`]).
//! - [`JointModel::goal_rewards`] — the rewards of relabelled goals (HER), the step's own
//!   arithmetic.
//!
//! # Semantics (units in every line)
//!
//! - **State**: six joint angles q, radians, within the joint limits (the scenario's
//!   `arm.joint_limits_deg`, degrees; without them every joint in [-180°, 180°]).
//! - **Action**: six numbers in [-1, 1]; joint i moves by `a_i * max_joint_step_deg` degrees.
//! - **Refusal** (the paper's "move back", in joint space): a step is refused when the new
//!   angles leave the joint limits, or when any of the interpolated poses
//!   `q + (k / n) Δq`, `k = 1..=n`, brings a link capsule (segment, radius `link_radius_mm`)
//!   within `safe_distance_mm` of an obstacle box (gap <= safe distance, mm). The arm stays.
//! - **Sub-steps** `n = max(1, ceil(Σ_i |Δq_i| L_i / (substep_fraction · safe_distance_mm)))`,
//!   `Δq` in rad, `L_i` (mm) the length of the arm's polyline distal to joint i's origin, an
//!   upper bound of the distance from joint i's axis to any point it moves. The path of any
//!   arm point over one step is at most `Σ |Δq_i| L_i` mm long, so between two checked poses
//!   it moves at most `substep_fraction · safe_distance_mm` mm: every pose of the continuous
//!   motion keeps a gap >= `(1 - substep_fraction / 2) · safe_distance_mm` > 0, and no link
//!   passes through a box. The env's check (`JointModel::check_move`) gives the answer of
//!   measuring all n poses exactly, but measures a link at a pose only when no motion bound
//!   proves it clear, with closed-form segment-box distances (docs/JOINT.md, "Speed").
//! - **Observation** ([`JointModel::obs_dim`] float32, [`ObsLayout`]): sin q (6), cos q (6),
//!   terminal position / reach (3), target / reach (3) (reach: the polyline's length, mm, so
//!   both lie in [-1, 1]), per link the gap g (mm) as `g / (g + safe_distance_mm)` in [0, 1]
//!   (1 without obstacles), the unit vector from the terminal to the nearest point of the
//!   nearest obstacle box (3; zeros without obstacles), 1.0 if the last step was refused (1).
//! - **Reward** (times `reward_scale`): eq. 5: `+target_reward` when the step ends within
//!   `target_tolerance_mm` of the target, `-collision_penalty` when refused, else
//!   `-step_penalty`; eq. 10 (`assist`): `+progress_reward · (d_prev - d)` with d the
//!   terminal-target distance, mm; eq. 9 (`assist`), after a refused step: another refusal
//!   costs `-repeat_collision_penalty`, an accepted step `-reverse_after_collision_penalty ·
//!   max(0, -cos(a, a_refused))` (a step back along the refused action).
//! - **Episode end**: terminated when d <= `target_tolerance_mm`; a [`JointBatch`] also
//!   truncates after `max_episode_steps` steps; the step after either resets that lane
//!   (reward 0, neither flag).
//! - Distances of the reward and of termination are measured between the float32 goals of
//!   the observation (normalised positions times the reach, mm), so that
//!   [`JointModel::goal_rewards`] gives a step's own reward to the bit.
//!
//! ```
//! use sixaxis_core::joint_env::{JointEpisode, JointModel, JointOptions};
//! use sixaxis_core::Scenario;
//! let s = Scenario::builtin("paper_simple").unwrap();
//! let model = JointModel::new(&s, JointOptions::default()).unwrap();
//! let mut ep = JointEpisode::new(&model);
//! ep.reset(&model);
//! let out = ep.step(&model, &[0.5, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
//! assert!(!out.refused); // a 1° turn of the base is clear at beta_0
//! assert!((ep.joints_rad()[0] - (s.arm.beta0_deg[0] + 1.0).to_radians()).abs() < 1e-12);
//! let mut obs = vec![0f32; model.obs_dim()];
//! ep.write_obs(&model, &mut obs);
//! assert!(obs.iter().all(|v| (-1.0..=1.0).contains(v)));
//! ```
//!
//! The module's parts: options and model here, the episode in `joint_env/episode.rs`, the
//! batch in `joint_env/batch.rs`.

use nalgebra::Vector3;

use crate::clearance::{segment_aabb_distance_mm, Clearance};
use crate::error::{Error, Result};
use crate::kinematics::{Arm, ArmPoints, Joints};
use crate::options::{
    check_value, reject_unknown, Domain, FromOption, OptionInfo, OptionValue, Options,
};
use crate::scenario::{ClearanceModel, ObstacleBox, Scenario};

mod batch;
mod episode;

pub use batch::{JointBatch, JointBuffers};
pub use episode::{JointEpisode, JointStep};

/// Default joint limits where the scenario gives none, degrees: every joint in [-180, 180].
pub const DEFAULT_JOINT_LIMIT_DEG: [f64; 2] = [-180.0, 180.0];

/// Positive finite numbers (mm, deg, ...).
const POSITIVE: Domain = Domain::Float {
    min: 0.0,
    max: f64::INFINITY,
    open_min: true,
};
/// Finite numbers >= 0.
const NON_NEGATIVE: Domain = Domain::Float {
    min: 0.0,
    max: f64::INFINITY,
    open_min: false,
};

const fn joint_option(
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

/// The keywords of `SixAxisAvoidJoint-v0`, `SixAxisAvoidJointGoal-v0` and their vector
/// envs, declared once: the bindings check every keyword against this table
/// (`check_options("joint", ...)`), and [`JointOptions::from_options`] reads them with the
/// same domains. Defaults: [`JointOptions::default`]. [`JOINT_NULLABLE`] names those that
/// may be `None`.
pub static JOINT_ENV_OPTIONS: [OptionInfo; 17] = [
    joint_option("max_joint_step_deg", Domain::Float { min: 0.0, max: 30.0, open_min: true }, "deg", "Largest joint increment of one step: action a_i in [-1, 1] moves joint i by a_i times this (default 2)."),
    joint_option("target_tolerance_mm", POSITIVE, "mm", "The episode terminates when the terminal is within this distance of the target (the target cell's centre; default 20)."),
    joint_option("link_radius_mm", NON_NEGATIVE, "mm", "Radius of every link capsule; None: the scenario's capsules radius (planning.clearance_model), else 0 (the paper's segments)."),
    joint_option("safe_distance_mm", POSITIVE, "mm", "A pose whose capsule-to-box gap is <= this is refused; None: the scenario's capsules margin_mm, else arm_safe_distance in mm minus half a cell (eq. 11's centre distance as a gap to the cube's face)."),
    joint_option("substep_fraction", Domain::Float { min: 0.0, max: 1.0, open_min: true }, "", "Between two checked sub-steps no arm point moves more than this fraction of the safe distance (default 0.5)."),
    joint_option("assist", Domain::Bool, "", "The assisted terms on or off: eq. 10's progress reward and eq. 9's detour penalty (default True)."),
    joint_option("reward_scale", NON_NEGATIVE, "", "Factor applied to every reward (default 1)."),
    joint_option("target_reward", NON_NEGATIVE, "", "Eq. 5's r: reward of the step that reaches the target (default 10)."),
    joint_option("step_penalty", NON_NEGATIVE, "", "Eq. 5's p: penalty of an accepted step that does not reach the target (default 0.02)."),
    joint_option("collision_penalty", NON_NEGATIVE, "", "Eq. 5's P: penalty of a refused step (default 1)."),
    joint_option("repeat_collision_penalty", NON_NEGATIVE, "", "Eq. 9's p_e: extra penalty of a refused step after a refused step (default 2)."),
    joint_option("reverse_after_collision_penalty", NON_NEGATIVE, "", "Eq. 9's p_o: extra penalty, times max(0, -cos) of the angle to the refused action, of an accepted step after a refused one (default 0.5)."),
    joint_option("progress_reward", NON_NEGATIVE, "1/mm", "Eq. 10 in mm: reward per mm the terminal comes closer to the target (default 0.05)."),
    joint_option("max_episode_steps", Domain::u32_from(1), "steps", "Truncation after this many steps (default 500; the single env's by Gymnasium's TimeLimit)."),
    joint_option("num_envs", Domain::Int { min: 1, max: 1 << 24 }, "envs", "Environments of the native vector env."),
    joint_option("copy", Domain::Bool, "", "Return copies of the vector env's buffers (Gymnasium's `copy`)."),
    joint_option("render_mode", Domain::Choice(&["rgb_array"]), "", "Gymnasium's render mode: None (the joint envs do not render)."),
];

/// The keywords of [`JOINT_ENV_OPTIONS`] that may be `None`.
pub const JOINT_NULLABLE: &[&str] = &["link_radius_mm", "safe_distance_mm", "render_mode"];

/// The keywords of [`JOINT_ENV_OPTIONS`] that configure the model (the rest, `num_envs`,
/// `copy` and `render_mode`, belong to the Python envs).
const MODEL_KEYS: [&str; 14] = [
    "max_joint_step_deg",
    "target_tolerance_mm",
    "link_radius_mm",
    "safe_distance_mm",
    "substep_fraction",
    "assist",
    "reward_scale",
    "target_reward",
    "step_penalty",
    "collision_penalty",
    "repeat_collision_penalty",
    "reverse_after_collision_penalty",
    "progress_reward",
    "max_episode_steps",
];

/// The entry of [`JOINT_ENV_OPTIONS`] for `key`.
pub fn joint_option_info(key: &str) -> Option<&'static OptionInfo> {
    JOINT_ENV_OPTIONS.iter().find(|i| i.key == key)
}

/// Options of the joint-space env (see [`JOINT_ENV_OPTIONS`] for each one's doc and unit).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointOptions {
    /// Largest joint increment of a step, degrees.
    pub max_joint_step_deg: f64,
    /// Termination distance, mm.
    pub target_tolerance_mm: f64,
    /// Link capsule radius, mm (`None`: from the scenario).
    pub link_radius_mm: Option<f64>,
    /// Safe distance, mm (`None`: from the scenario).
    pub safe_distance_mm: Option<f64>,
    /// Largest point motion between checked sub-steps, as a fraction of the safe distance.
    pub substep_fraction: f64,
    /// Eqs. 9 and 10 on.
    pub assist: bool,
    /// Factor of every reward.
    pub reward_scale: f64,
    /// Eq. 5's r.
    pub target_reward: f64,
    /// Eq. 5's p.
    pub step_penalty: f64,
    /// Eq. 5's P (a refused step).
    pub collision_penalty: f64,
    /// Eq. 9's p_e.
    pub repeat_collision_penalty: f64,
    /// Eq. 9's p_o.
    pub reverse_after_collision_penalty: f64,
    /// Eq. 10 per mm of progress, 1/mm.
    pub progress_reward: f64,
    /// Step cap of a [`JointBatch`], steps.
    pub max_episode_steps: u32,
}

impl Default for JointOptions {
    fn default() -> Self {
        JointOptions {
            max_joint_step_deg: 2.0,
            target_tolerance_mm: 20.0,
            link_radius_mm: None,
            safe_distance_mm: None,
            substep_fraction: 0.5,
            assist: true,
            reward_scale: 1.0,
            target_reward: 10.0,
            step_penalty: 0.02,
            collision_penalty: 1.0,
            repeat_collision_penalty: 2.0,
            reverse_after_collision_penalty: 0.5,
            progress_reward: 0.05,
            max_episode_steps: 500,
        }
    }
}

impl JointOptions {
    /// The defaults with every model option of `values` set (keys and domains of
    /// [`JOINT_ENV_OPTIONS`]; a key that is not a model option is an error listing them).
    ///
    /// ```
    /// use sixaxis_core::joint_env::JointOptions;
    /// use sixaxis_core::options::{OptionValue, Options};
    /// let mut o = Options::new();
    /// o.insert("max_joint_step_deg".into(), OptionValue::Float(1.0));
    /// assert_eq!(JointOptions::from_options(&o).unwrap().max_joint_step_deg, 1.0);
    /// o.insert("max_joint_step_deg".into(), OptionValue::Float(-1.0));
    /// let e = JointOptions::from_options(&o).unwrap_err().to_string();
    /// assert!(e.contains("`max_joint_step_deg` = -1"), "{e}");
    /// ```
    pub fn from_options(values: &Options) -> Result<JointOptions> {
        reject_unknown(&MODEL_KEYS, values)?;
        let mut o = JointOptions::default();
        for (key, v) in values {
            let info = joint_option_info(key).expect("model keys are in the table");
            let d = &info.domain;
            let f = || f64::from_option(key, d, v);
            match key.as_str() {
                "max_joint_step_deg" => o.max_joint_step_deg = f()?,
                "target_tolerance_mm" => o.target_tolerance_mm = f()?,
                "link_radius_mm" => o.link_radius_mm = Some(f()?),
                "safe_distance_mm" => o.safe_distance_mm = Some(f()?),
                "substep_fraction" => o.substep_fraction = f()?,
                "assist" => o.assist = bool::from_option(key, d, v)?,
                "reward_scale" => o.reward_scale = f()?,
                "target_reward" => o.target_reward = f()?,
                "step_penalty" => o.step_penalty = f()?,
                "collision_penalty" => o.collision_penalty = f()?,
                "repeat_collision_penalty" => o.repeat_collision_penalty = f()?,
                "reverse_after_collision_penalty" => o.reverse_after_collision_penalty = f()?,
                "progress_reward" => o.progress_reward = f()?,
                "max_episode_steps" => o.max_episode_steps = u32::from_option(key, d, v)?,
                _ => unreachable!("MODEL_KEYS lists every arm of this match"),
            }
        }
        Ok(o)
    }

    /// Check every field against its domain in [`JOINT_ENV_OPTIONS`]; the error names it.
    pub fn check(&self) -> Result<()> {
        let floats = [
            ("max_joint_step_deg", Some(self.max_joint_step_deg)),
            ("target_tolerance_mm", Some(self.target_tolerance_mm)),
            ("link_radius_mm", self.link_radius_mm),
            ("safe_distance_mm", self.safe_distance_mm),
            ("substep_fraction", Some(self.substep_fraction)),
            ("reward_scale", Some(self.reward_scale)),
            ("target_reward", Some(self.target_reward)),
            ("step_penalty", Some(self.step_penalty)),
            ("collision_penalty", Some(self.collision_penalty)),
            (
                "repeat_collision_penalty",
                Some(self.repeat_collision_penalty),
            ),
            (
                "reverse_after_collision_penalty",
                Some(self.reverse_after_collision_penalty),
            ),
            ("progress_reward", Some(self.progress_reward)),
        ];
        for (key, v) in floats {
            if let Some(v) = v {
                let info = joint_option_info(key).expect("in the table");
                check_value(key, &info.domain, &OptionValue::Float(v))?;
            }
        }
        let info = joint_option_info("max_episode_steps").expect("in the table");
        check_value(
            "max_episode_steps",
            &info.domain,
            &OptionValue::Int(self.max_episode_steps.into()),
        )
    }
}

/// Where each field sits in the observation (ranges of indices).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ObsLayout {
    /// sin of the six joints.
    pub sin: std::ops::Range<usize>,
    /// cos of the six joints.
    pub cos: std::ops::Range<usize>,
    /// Terminal position / reach (the achieved goal).
    pub terminal: std::ops::Range<usize>,
    /// Target / reach (the desired goal).
    pub target: std::ops::Range<usize>,
    /// Per link `g / (g + safe_distance_mm)`.
    pub clearance: std::ops::Range<usize>,
    /// Unit vector terminal -> nearest obstacle point.
    pub direction: std::ops::Range<usize>,
    /// 1.0 if the last step was refused.
    pub refused: usize,
}

/// What every copy of the joint env shares.
#[derive(Debug, Clone)]
pub struct JointModel {
    arm: Arm,
    clearance: Clearance,
    opts: JointOptions,
    link_radius_mm: f64,
    safe_distance_mm: f64,
    /// Polyline segments of non-zero length: index k of points k -> k + 1.
    links: Vec<usize>,
    /// `L_i`: polyline length distal to joint i's origin, mm.
    lever_mm: [f64; 6],
    /// `ℓ_{i,k}` per link (in `links` order): polyline length from joint i's origin to the
    /// far end of link k, mm (0 when joint i does not move link k): docs/JOINT.md, "Speed".
    link_lever_mm: [[f64; 6]; MAX_LINKS],
    /// Polyline length, mm (the workspace radius).
    reach_mm: f64,
    limits_rad: [[f64; 2]; 6],
    beta0: Joints,
    target_mm: Vector3<f64>,
    /// The target as the observation's float32 goal.
    target_goal: [f32; 3],
    /// Every obstacle as a box (min, max), mm: the cubes of the cells, then the boxes.
    boxes: Vec<([f64; 3], [f64; 3])>,
    /// The same boxes as structure-of-arrays in chunks of [`BOX_LANES`] (lo x, y, z, hi x,
    /// y, z), padded with empty far boxes (never measured: see `link_gap_fast`), so that
    /// the lower-bound loop vectorises.
    box_lanes: Vec<[[f64; BOX_LANES]; 6]>,
    max_step_rad: f64,
}

/// Index of the polyline point that is joint i's origin (base, O1, O2, O3, Aux, O4, O5, O6).
const JOINT_POINT: [usize; 6] = [1, 2, 3, 5, 6, 7];

/// Lanes of the box lower-bound loop.
const BOX_LANES: usize = 4;
/// Coordinate of padding boxes, mm: far from everything, its square finite.
const FAR_MM: f64 = 1.0e100;

/// Most links a polyline has (7 segments).
pub(crate) const MAX_LINKS: usize = 7;

/// Slack (mm) of the motion bounds of [`JointModel::check_move`]: a pose is taken as clear
/// without an exact query only when its bound beats the safe distance by more than this, so
/// that floating-point rounding (about 1e-13 mm on coordinates of at most a few metres)
/// never turns a pose the exact query would refuse into an accepted one (docs/JOINT.md,
/// "Speed").
const BOUND_SLACK_MM: f64 = 1e-9;

impl JointModel {
    /// The model of a scenario with these options. Errors: an option outside its domain; a
    /// joint limit with low >= high; beta_0 outside the limits or not clear; a target beyond
    /// the arm's reach.
    pub fn new(scenario: &Scenario, opts: JointOptions) -> Result<JointModel> {
        opts.check()?;
        let cell_mm = scenario.cell_mm;
        let (scen_r, scen_s) = match scenario.planning.clearance_model {
            ClearanceModel::Capsules {
                link_radius_mm,
                margin_mm,
            } => (link_radius_mm, margin_mm),
            ClearanceModel::Centres => (0.0, scenario.arm_safe_distance_in_mm() - 0.5 * cell_mm),
        };
        let link_radius_mm = opts.link_radius_mm.unwrap_or(scen_r);
        let safe_distance_mm = match opts.safe_distance_mm {
            Some(s) => s,
            None if scen_s > 0.0 && scen_s.is_finite() => scen_s,
            None => {
                return Err(Error::argument(
                    "safe_distance_mm",
                    "None",
                    format!(
                        "the scenario gives no positive safe distance for the joint env ({scen_s} mm); pass safe_distance_mm"
                    ),
                ))
            }
        };
        let arm = scenario.arm();
        let limits_deg = scenario
            .arm
            .joint_limits_deg
            .unwrap_or([DEFAULT_JOINT_LIMIT_DEG; 6]);
        for (i, l) in limits_deg.iter().enumerate() {
            if !(l[0].is_finite() && l[1].is_finite() && l[0] < l[1]) {
                return Err(Error::invalid(
                    format!("arm.joint_limits_deg[{i}]"),
                    format!("[{}, {}]", l[0], l[1]),
                    "must be finite with low < high",
                ));
            }
        }
        let limits_rad = limits_deg.map(|l| l.map(f64::to_radians));
        let beta0 = scenario.arm.beta0_rad();
        let clearance = Clearance::new(
            &scenario.obstacles,
            cell_mm,
            ClearanceModel::Capsules {
                link_radius_mm,
                margin_mm: safe_distance_mm,
            },
            0.0,
        )
        .with_boxes(&scenario.obstacle_boxes_mm);
        let p0 = arm.points_mm(&beta0);
        let seg_len: Vec<f64> = (0..7).map(|k| (p0[k + 1] - p0[k]).norm()).collect();
        let links: Vec<usize> = (0..7).filter(|&k| seg_len[k] > 0.0).collect();
        let reach_mm: f64 = seg_len.iter().sum();
        let lever_mm = JOINT_POINT.map(|j| seg_len[j..].iter().sum());
        let mut link_lever_mm = [[0.0; 6]; MAX_LINKS];
        for (l, &k) in links.iter().enumerate() {
            link_lever_mm[l] = JOINT_POINT.map(|j| {
                if k >= j {
                    seg_len[j..=k].iter().sum()
                } else {
                    0.0
                }
            });
        }
        let mut boxes: Vec<([f64; 3], [f64; 3])> = scenario
            .obstacles
            .iter()
            .map(|&c| {
                let b = ObstacleBox::paper_cube(c, cell_mm);
                (b.min_mm, b.max_mm)
            })
            .collect();
        boxes.extend(
            scenario
                .obstacle_boxes_mm
                .iter()
                .map(|b| (b.min_mm, b.max_mm)),
        );
        let mut box_lanes = vec![[[FAR_MM; BOX_LANES]; 6]; boxes.len().div_ceil(BOX_LANES)];
        for (j, (lo, hi)) in boxes.iter().enumerate() {
            for i in 0..3 {
                box_lanes[j / BOX_LANES][i][j % BOX_LANES] = lo[i];
                box_lanes[j / BOX_LANES][3 + i][j % BOX_LANES] = hi[i];
            }
        }
        let target_mm = scenario.cell_centre_mm(scenario.target);
        if target_mm.norm() > reach_mm {
            return Err(Error::invalid(
                "target",
                format!(
                    "[{}, {}, {}]",
                    scenario.target[0], scenario.target[1], scenario.target[2]
                ),
                format!(
                    "its centre is {:.1} mm from the base, beyond the arm's reach ({reach_mm:.1} mm)",
                    target_mm.norm()
                ),
            ));
        }
        let mut model = JointModel {
            arm,
            clearance,
            opts,
            link_radius_mm,
            safe_distance_mm,
            links,
            lever_mm,
            link_lever_mm,
            reach_mm,
            limits_rad,
            beta0,
            target_mm,
            target_goal: [0.0; 3],
            boxes,
            box_lanes,
            max_step_rad: opts.max_joint_step_deg.to_radians(),
        };
        model.target_goal = model.goal_of(&target_mm);
        if let Some(i) = (0..6).find(|&i| !model.within_limit(i, beta0[i])) {
            return Err(Error::invalid(
                format!("arm.beta0_deg[{i}]"),
                scenario.arm.beta0_deg[i],
                format!(
                    "outside the joint limits [{}, {}] deg",
                    limits_deg[i][0], limits_deg[i][1]
                ),
            ));
        }
        if !model.pose_is_clear(&beta0) {
            let gap = model.clearance.capsules_gap_mm(&p0, link_radius_mm);
            return Err(Error::invalid(
                "arm.beta0_deg",
                format!("{:?}", scenario.arm.beta0_deg),
                format!(
                    "the start pose is not clear: its capsule gap {gap:.1} mm is <= the safe distance {safe_distance_mm} mm"
                ),
            ));
        }
        Ok(model)
    }

    /// The options.
    pub fn options(&self) -> &JointOptions {
        &self.opts
    }

    /// The arm.
    pub fn arm(&self) -> &Arm {
        &self.arm
    }

    /// The clearance (capsules model) the steps are checked with.
    pub fn clearance(&self) -> &Clearance {
        &self.clearance
    }

    /// Link capsule radius in use, mm.
    pub fn link_radius_mm(&self) -> f64 {
        self.link_radius_mm
    }

    /// Safe distance in use, mm.
    pub fn safe_distance_mm(&self) -> f64 {
        self.safe_distance_mm
    }

    /// Number of links (polyline segments of non-zero length; one clearance each).
    pub fn num_links(&self) -> usize {
        self.links.len()
    }

    /// The polyline segments that are links: `k` stands for points `k -> k + 1`.
    pub fn links(&self) -> &[usize] {
        &self.links
    }

    /// The arm's reach (its polyline's length), mm: the workspace's radius.
    pub fn reach_mm(&self) -> f64 {
        self.reach_mm
    }

    /// `L_i` of the sub-step bound, mm.
    pub fn lever_mm(&self) -> [f64; 6] {
        self.lever_mm
    }

    /// Joint limits, radians, `[low, high]` per joint.
    pub fn limits_rad(&self) -> [[f64; 2]; 6] {
        self.limits_rad
    }

    /// beta_0, radians.
    pub fn beta0_rad(&self) -> Joints {
        self.beta0
    }

    /// The target, mm.
    pub fn target_mm(&self) -> Vector3<f64> {
        self.target_mm
    }

    /// Length of the observation: 22 + [`JointModel::num_links`].
    pub fn obs_dim(&self) -> usize {
        22 + self.links.len()
    }

    /// Where each field sits in the observation.
    pub fn obs_layout(&self) -> ObsLayout {
        let l = self.links.len();
        ObsLayout {
            sin: 0..6,
            cos: 6..12,
            terminal: 12..15,
            target: 15..18,
            clearance: 18..18 + l,
            direction: 18 + l..21 + l,
            refused: 21 + l,
        }
    }

    /// A position (mm) as the observation's float32 goal: `p / reach`.
    #[inline]
    pub fn goal_of(&self, p: &Vector3<f64>) -> [f32; 3] {
        [0, 1, 2].map(|i| (p[i] / self.reach_mm) as f32)
    }

    /// Distance between two goals, mm (`|a - b| * reach`, in f64 from the f32 goals).
    #[inline]
    pub fn goal_distance_mm(&self, a: &[f32; 3], b: &[f32; 3]) -> f64 {
        let d2: f64 = (0..3)
            .map(|i| {
                let d = a[i] as f64 - b[i] as f64;
                d * d
            })
            .sum();
        d2.sqrt() * self.reach_mm
    }

    #[inline]
    fn within_limit(&self, i: usize, q: f64) -> bool {
        q >= self.limits_rad[i][0] && q <= self.limits_rad[i][1]
    }

    /// Whether every joint of `q` (rad) is within its limits (inclusive).
    pub fn within_limits(&self, q: &Joints) -> bool {
        (0..6).all(|i| self.within_limit(i, q[i]))
    }

    /// Whether pose `q` (rad) keeps every link capsule farther than the safe distance from
    /// every obstacle (gap > safe distance, mm).
    #[inline]
    pub fn pose_is_clear(&self, q: &Joints) -> bool {
        self.clearance.pose_is_clear(&self.arm.points_mm(q))
    }

    /// Sub-steps of the move `from -> to` (rad): `max(1, ceil(Σ |Δq_i| L_i / (substep_fraction ·
    /// safe_distance_mm)))` (the module docs derive the bound).
    pub fn substeps(&self, from: &Joints, to: &Joints) -> u32 {
        let path_mm = self.path_bound_mm(from, to);
        let per = self.opts.substep_fraction * self.safe_distance_mm;
        ((path_mm / per).ceil() as u32).max(1)
    }

    /// Upper bound (mm) of the path length of any arm point over the move `from -> to`
    /// (rad): `Σ_i |Δq_i| L_i`.
    #[inline]
    pub fn path_bound_mm(&self, from: &Joints, to: &Joints) -> f64 {
        (0..6)
            .map(|i| (to[i] - from[i]).abs() * self.lever_mm[i])
            .sum()
    }

    /// Whether the move `from -> to` (rad, linear in joint space) is clear at each of its
    /// [`JointModel::substeps`] interpolated poses (`k = 1..=n`, the end pose first), every
    /// pose measured by the clearance's parry query: the reference of the env's own,
    /// faster check (`check_move`, docs/JOINT.md "Speed"), which gives the same answer.
    pub fn motion_is_clear(&self, from: &Joints, to: &Joints) -> bool {
        self.motion_is_clear_from(from, to, 0.0)
    }

    /// [`JointModel::motion_is_clear`] knowing that pose `from` has the gap `from_gap_mm`
    /// (mm; 0 when unknown): when `from_gap_mm - path_bound_mm(from, to) > safe_distance_mm`
    /// no point of the arm can come within the safe distance during the move (each moves at
    /// most the path bound), so no pose needs a check; otherwise every sub-step is checked.
    pub fn motion_is_clear_from(&self, from: &Joints, to: &Joints, from_gap_mm: f64) -> bool {
        if from_gap_mm - self.path_bound_mm(from, to) > self.safe_distance_mm {
            return true;
        }
        let n = self.substeps(from, to);
        if !self.pose_is_clear(to) {
            return false;
        }
        (1..n).all(|k| {
            let f = k as f64 / n as f64;
            let q: Joints = std::array::from_fn(|i| from[i] + (to[i] - from[i]) * f);
            self.pose_is_clear(&q)
        })
    }

    /// Exact gap (mm) of each link capsule to the nearest obstacle, in [`JointModel::links`]
    /// order, written into `out` (`INFINITY` without obstacles).
    pub fn link_gaps_mm(&self, points: &ArmPoints, out: &mut [f64]) {
        for (o, &k) in out.iter_mut().zip(&self.links) {
            // The polyline with every segment but k of zero length: the clearance's capsule
            // links leave zero-length segments out, so this measures link k alone.
            let mut one = [points[k]; 8];
            one[7] = points[k + 1];
            *o = self.clearance.capsules_gap_mm(&one, self.link_radius_mm);
        }
    }

    /// Exact gap (mm) of the capsule of segment `a`-`b` to the nearest obstacle box, by the
    /// closed form [`segment_aabb_distance_mm`], and that box's index; `(INFINITY, hint)`
    /// without obstacles. The box `hint` is measured first; every other box is first bounded
    /// below by the distance between the segment's bounding box and it (the segment lies in
    /// its bounding box), and measured exactly only when that bound could beat the best gap
    /// so far. Returns as soon as the best gap is `<= stop` (then some gap `<= stop`).
    #[inline]
    pub(crate) fn link_gap_fast(
        &self,
        a: &Vector3<f64>,
        b: &Vector3<f64>,
        stop: f64,
        hint: usize,
    ) -> (f64, usize) {
        let r = self.link_radius_mm;
        let (a, b) = ([a.x, a.y, a.z], [b.x, b.y, b.z]);
        let smin: [f64; 3] = std::array::from_fn(|i| a[i].min(b[i]));
        let smax: [f64; 3] = std::array::from_fn(|i| a[i].max(b[i]));
        let gap = |j: usize| {
            let (lo, hi) = &self.boxes[j];
            (segment_aabb_distance_mm(&a, &b, lo, hi) - r).max(0.0)
        };
        if self.boxes.is_empty() {
            return (f64::INFINITY, 0);
        }
        let hint = if hint < self.boxes.len() { hint } else { 0 };
        // A real box first: from here on `best` is finite, below the padding boxes' bound.
        let mut best = gap(hint);
        let mut at = hint;
        if best <= stop {
            return (best, at);
        }
        for (c, lanes) in self.box_lanes.iter().enumerate() {
            // Squared distance between the segment's bounding box and each box of the chunk:
            // a lower bound of the segment's (branch-free, four boxes at a time).
            let mut d2 = [0.0; BOX_LANES];
            for i in 0..3 {
                for (l, d) in d2.iter_mut().enumerate() {
                    let e = lanes[i][l] - smax[i];
                    let f = smin[i] - lanes[3 + i][l];
                    let e = if e > f { e } else { f };
                    let e = if e > 0.0 { e } else { 0.0 };
                    *d += e * e;
                }
            }
            for (l, &d) in d2.iter().enumerate() {
                // gap >= sqrt(d2) - r: measure only if sqrt(d2) - r < best.
                let reach = best + r;
                let j = c * BOX_LANES + l;
                if d >= reach * reach || j == hint {
                    continue;
                }
                let g = gap(j);
                if g < best {
                    best = g;
                    at = j;
                    if best <= stop {
                        return (best, at);
                    }
                }
            }
        }
        (best, at)
    }

    /// Each link's exact gap (mm, [`JointModel::links`] order) at polyline `points` by
    /// [`JointModel::link_gap_fast`], into `gaps`, with `hints` (the nearest box of each
    /// link, updated). Stops with `false` at the first link whose gap is `<= stop`.
    #[inline]
    pub(crate) fn link_gaps_fast(
        &self,
        points: &ArmPoints,
        stop: f64,
        gaps: &mut [f64; MAX_LINKS],
        hints: &mut [u32; MAX_LINKS],
    ) -> bool {
        for (l, &k) in self.links.iter().enumerate() {
            let (g, h) = self.link_gap_fast(&points[k], &points[k + 1], stop, hints[l] as usize);
            gaps[l] = g;
            hints[l] = h as u32;
            if g <= stop {
                return false;
            }
        }
        true
    }

    /// The env's check of the move `from -> to` (rad, linear in joint space, within the
    /// limits), with `from_gaps` the exact link gaps at `from` (mm, [`JointModel::links`]
    /// order; `INFINITY` is a valid entry without obstacles). The same answer as
    /// [`JointModel::motion_is_clear`] (every pose `k/n`, `k = 1..=n`, `n` the
    /// [`JointModel::substeps`], has every link gap `> safe_distance_mm`), computed with
    /// fewer exact queries (docs/JOINT.md, "Speed"): the end pose is measured exactly
    /// (its gaps go to `gaps`, its polyline is returned when the move is clear); an interior
    /// pose is measured, link by link, only when no motion bound proves that link clear.
    ///
    /// The bound (docs/JOINT.md, "Speed"): along the move, every point of link k travels
    /// at most `P_k · |t - t'|` mm between the poses at fractions t and t', with
    /// `P_k = Σ_i |Δq_i| ℓ_{i,k}`; so a link whose exact gap at t is g has a gap of at least
    /// `g - P_k |t - t'|` at t' (every point of the moved segment is within that path of a
    /// point of the first, and a distance to a fixed box changes by at most the distance
    /// moved). A link is taken as clear at t' when that bound exceeds the safe distance by
    /// more than [`BOUND_SLACK_MM`], from the last pose where it was measured (t = 0 at
    /// first) or from the end pose (t = 1).
    pub(crate) fn check_move(
        &self,
        from: &Joints,
        to: &Joints,
        from_gaps: &[f64],
        gaps: &mut [f64; MAX_LINKS],
        hints: &mut [u32; MAX_LINKS],
    ) -> Option<ArmPoints> {
        let safe = self.safe_distance_mm;
        let nl = self.links.len();
        let dq: [f64; 6] = std::array::from_fn(|i| (to[i] - from[i]).abs());
        let mut path = [0.0; MAX_LINKS];
        for (p, lever) in path.iter_mut().zip(&self.link_lever_mm).take(nl) {
            *p = (0..6).map(|i| dq[i] * lever[i]).sum();
        }
        let end = self.arm.points_mm(to);
        if !self.link_gaps_fast(&end, safe, gaps, hints) {
            return None;
        }
        let n = self.substeps(from, to);
        // The last exact gap of each link and the fraction where it was measured.
        let mut last = [f64::INFINITY; MAX_LINKS];
        last[..nl].copy_from_slice(&from_gaps[..nl]);
        let mut last_t = [0.0f64; MAX_LINKS];
        let limit = safe + BOUND_SLACK_MM;
        for k in 1..n {
            let f = k as f64 / n as f64;
            let mut open = [false; MAX_LINKS];
            for l in 0..nl {
                open[l] = last[l] - path[l] * (f - last_t[l]) <= limit
                    && gaps[l] - path[l] * (1.0 - f) <= limit;
            }
            if !open.contains(&true) {
                continue;
            }
            let q: Joints = std::array::from_fn(|i| from[i] + (to[i] - from[i]) * f);
            let p = self.arm.points_mm(&q);
            for l in 0..nl {
                if !open[l] {
                    continue;
                }
                let kk = self.links[l];
                let (g, h) = self.link_gap_fast(&p[kk], &p[kk + 1], safe, hints[l] as usize);
                if g <= safe {
                    return None;
                }
                hints[l] = h as u32;
                last[l] = g;
                last_t[l] = f;
            }
        }
        Some(end)
    }

    /// Unit vector from `p` (mm) to the nearest point of the nearest obstacle box, and that
    /// distance (mm); zeros and `INFINITY` without obstacles (zeros also inside a box).
    pub fn nearest_obstacle_direction(&self, p: &Vector3<f64>) -> ([f64; 3], f64) {
        let mut best = f64::INFINITY;
        let mut dir = [0.0; 3];
        for (lo, hi) in &self.boxes {
            let d: [f64; 3] = std::array::from_fn(|i| p[i].clamp(lo[i], hi[i]) - p[i]);
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if n < best {
                best = n;
                dir = if n > 0.0 { d.map(|v| v / n) } else { [0.0; 3] };
            }
        }
        (dir, best)
    }

    /// The reward (times `reward_scale`) of a step that started with the terminal at goal
    /// `previous` and ended at goal `achieved`, with `desired` as the target, `refused` and
    /// eq. 9's `detour_penalty` (<= 0, unscaled) as the step had them; and whether it
    /// reached the target (within `target_tolerance_mm`, mm).
    #[inline]
    pub fn reward_of(
        &self,
        previous: &[f32; 3],
        achieved: &[f32; 3],
        desired: &[f32; 3],
        refused: bool,
        detour_penalty: f64,
    ) -> (f64, bool) {
        let o = &self.opts;
        let d = self.goal_distance_mm(achieved, desired);
        let reached = !refused && d <= o.target_tolerance_mm;
        let mut r = if reached {
            o.target_reward
        } else if refused {
            -o.collision_penalty
        } else {
            -o.step_penalty
        };
        if o.assist {
            r += o.progress_reward * (self.goal_distance_mm(previous, desired) - d);
            r += detour_penalty;
        }
        (r * o.reward_scale, reached)
    }

    /// The rewards of `n` relabelled transitions (HER): `previous`, `achieved`, `desired`
    /// are `3 n` goals (normalised positions as in the observation, finite, row-major),
    /// with each step's `refused` flag and eq. 9 term (`detour_penalty`, <= 0, finite). The
    /// arithmetic of [`JointEpisode::step`]: a step's own goals give its reward to the bit.
    pub fn goal_rewards(
        &self,
        previous: &[f32],
        achieved: &[f32],
        desired: &[f32],
        refused: &[bool],
        detour_penalty: &[f64],
    ) -> Result<Vec<f64>> {
        let n = refused.len();
        for (name, len, want) in [
            ("previous_achieved_goal", previous.len(), 3 * n),
            ("achieved_goal", achieved.len(), 3 * n),
            ("desired_goal", desired.len(), 3 * n),
            ("detour_penalty", detour_penalty.len(), n),
        ] {
            if len != want {
                return Err(Error::argument(
                    name,
                    format!("{len} values"),
                    format!("expected {want} (one per transition, {n} transitions)"),
                ));
            }
        }
        for (name, g) in [
            ("previous_achieved_goal", previous),
            ("achieved_goal", achieved),
            ("desired_goal", desired),
        ] {
            if let Some((i, v)) = g.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(Error::argument(
                    name,
                    format!("{v} at transition {}", i / 3),
                    "goals must be finite numbers (positions / reach)",
                ));
            }
        }
        if let Some((i, v)) = detour_penalty
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v <= 0.0))
        {
            return Err(Error::argument(
                "detour_penalty",
                format!("{v} at transition {i}"),
                "must be a finite number <= 0 (eq. 9's part of the step's reward)",
            ));
        }
        let g = |s: &[f32], i: usize| [s[3 * i], s[3 * i + 1], s[3 * i + 2]];
        Ok((0..n)
            .map(|i| {
                self.reward_of(
                    &g(previous, i),
                    &g(achieved, i),
                    &g(desired, i),
                    refused[i],
                    detour_penalty[i],
                )
                .0
            })
            .collect())
    }

    /// Check an action: six finite numbers in [-1, 1]; the error names `name` and the value.
    pub fn check_action(name: &str, a: &[f64]) -> Result<()> {
        if a.len() != 6 {
            return Err(Error::argument(
                name,
                format!("{} values", a.len()),
                "an action is six numbers in [-1, 1]",
            ));
        }
        if let Some((i, v)) = a
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && (-1.0..=1.0).contains(*v)))
        {
            return Err(Error::argument(
                name,
                format!("{v} at joint {i}"),
                "each component must be a number in [-1, 1]",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
