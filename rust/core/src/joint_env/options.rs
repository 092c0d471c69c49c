//! The joint env's keywords, declared once: [`JOINT_ENV_OPTIONS`] (key, domain, default,
//! unit and doc line of each); [`JointOptions`] holds the model's values, its
//! [`Default`] is the table's defaults, [`JointOptions::from_options`] reads an [`Options`]
//! map and [`JointOptions::check`] checks the values against the same domains. The bindings
//! derive Python's checks, `sixaxis_avoid.options("joint")` and docs/JOINT.md's keyword
//! table from the table (scripts/derive_options.py).
//!
//! Units are in each keyword's doc line: degrees for joint steps and limits, mm for
//! distances, 1/mm for the progress reward, steps for the step cap.

use crate::env::{env_option, EnvDefault, EnvOption};
use crate::error::Result;
use crate::options::{
    check_value, reject_unknown, Domain, FromOption, OptionInfo, OptionValue, Options,
};

/// Default joint limits where the scenario gives none, degrees: every joint in [-180, 180].
pub const DEFAULT_JOINT_LIMIT_DEG: [f64; 2] = [-180.0, 180.0];

/// The keywords of `SixAxisAvoidJoint-v0`, `SixAxisAvoidJointGoal-v0` and their vector
/// envs, declared once: the bindings check every keyword against this table
/// (`check_options("joint", ...)`), and [`JointOptions::from_options`] reads them with the
/// same domains. Each line gives the keyword's default ([`JointOptions::default`] is read
/// from here); [`JOINT_NULLABLE`] names those that may be `None` (exactly those whose
/// default is [`EnvDefault::None`], a unit test checks).
pub static JOINT_ENV_OPTIONS: [EnvOption; 17] = [
    env_option("max_joint_step_deg", Domain::Float { min: 0.0, max: 30.0, open_min: true }, EnvDefault::Float(2.0), "deg", "Largest joint increment of one step: action a_i in [-1, 1] moves joint i by a_i times this."),
    env_option("target_tolerance_mm", Domain::POSITIVE, EnvDefault::Float(20.0), "mm", "The episode terminates when the terminal is within this distance of the target (the target cell's centre)."),
    env_option("link_radius_mm", Domain::NON_NEGATIVE, EnvDefault::None, "mm", "Radius of every link capsule; None: the scenario's capsules radius (planning.clearance_model), else 0 (the paper's segments)."),
    env_option("safe_distance_mm", Domain::POSITIVE, EnvDefault::None, "mm", "A pose whose capsule-to-box gap is <= this is refused; None: the scenario's capsules margin_mm, else arm_safe_distance in mm minus half a cell (eq. 11's centre distance as a gap to the cube's face)."),
    env_option("substep_fraction", Domain::UNIT_OPEN, EnvDefault::Float(0.5), "", "Between two checked sub-steps no arm point moves more than this fraction of the safe distance."),
    env_option("assist", Domain::Bool, EnvDefault::Bool(true), "", "The assisted terms on or off: eq. 10's progress reward and eq. 9's detour penalty."),
    env_option("reward_scale", Domain::NON_NEGATIVE, EnvDefault::Float(1.0), "", "Factor applied to every reward."),
    env_option("target_reward", Domain::NON_NEGATIVE, EnvDefault::Float(10.0), "", "Eq. 5's r: reward of the step that reaches the target."),
    env_option("step_penalty", Domain::NON_NEGATIVE, EnvDefault::Float(0.02), "", "Eq. 5's p: penalty of an accepted step that does not reach the target."),
    env_option("collision_penalty", Domain::NON_NEGATIVE, EnvDefault::Float(1.0), "", "Eq. 5's P: penalty of a refused step."),
    env_option("repeat_collision_penalty", Domain::NON_NEGATIVE, EnvDefault::Float(2.0), "", "Eq. 9's p_e: extra penalty of a refused step after a refused step."),
    env_option("reverse_after_collision_penalty", Domain::NON_NEGATIVE, EnvDefault::Float(0.5), "", "Eq. 9's p_o: extra penalty, times max(0, -cos) of the angle to the refused action, of an accepted step after a refused one."),
    env_option("progress_reward", Domain::NON_NEGATIVE, EnvDefault::Float(0.05), "1/mm", "Eq. 10 in mm: reward per mm the terminal comes closer to the target."),
    env_option("max_episode_steps", Domain::u32_from(1), EnvDefault::Int(500), "steps", "Truncation after this many steps (the single env's by Gymnasium's TimeLimit, the vector envs' in Rust)."),
    env_option("num_envs", Domain::Int { min: 1, max: 1 << 24 }, EnvDefault::Int(1), "envs", "Environments of the native vector env."),
    env_option("copy", Domain::Bool, EnvDefault::Bool(true), "", "Return copies of the vector env's buffers (Gymnasium's `copy`)."),
    env_option("render_mode", Domain::Choice(&["rgb_array"]), EnvDefault::None, "", "Gymnasium's render mode: None (the joint envs do not render)."),
];

/// The keywords of [`JOINT_ENV_OPTIONS`] that may be `None`.
pub const JOINT_NULLABLE: &[&str] = &["link_radius_mm", "safe_distance_mm", "render_mode"];

/// The keywords of [`JOINT_ENV_OPTIONS`] that configure the model (the rest, `num_envs`,
/// `copy` and `render_mode`, belong to the Python envs).
pub(super) const MODEL_KEYS: [&str; 14] = [
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
    JOINT_ENV_OPTIONS
        .iter()
        .find(|o| o.key == key)
        .map(|o| &o.info)
}

/// The default of the joint env keyword `key` (None: no such keyword).
pub fn joint_option_default(key: &str) -> Option<EnvDefault> {
    JOINT_ENV_OPTIONS
        .iter()
        .find(|o| o.key == key)
        .map(|o| o.default)
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
    /// Step cap of a [`JointBatch`](super::JointBatch), steps.
    pub max_episode_steps: u32,
}

impl Default for JointOptions {
    /// The defaults of [`JOINT_ENV_OPTIONS`]; `None` for the nullable keywords (then the
    /// scenario's value, see [`JointModel::new`](super::JointModel::new)).
    fn default() -> Self {
        // Every field is set from the table below but the nullable ones (a unit test checks
        // that every other model keyword has a default).
        let mut o = JointOptions {
            max_joint_step_deg: 0.0,
            target_tolerance_mm: 0.0,
            link_radius_mm: None,
            safe_distance_mm: None,
            substep_fraction: 0.0,
            assist: false,
            reward_scale: 0.0,
            target_reward: 0.0,
            step_penalty: 0.0,
            collision_penalty: 0.0,
            repeat_collision_penalty: 0.0,
            reverse_after_collision_penalty: 0.0,
            progress_reward: 0.0,
            max_episode_steps: 0,
        };
        for key in MODEL_KEYS {
            if let Some(v) = joint_option_default(key).and_then(EnvDefault::value) {
                o.set(key, &v)
                    .expect("the table's defaults lie in their domains (a unit test checks)");
            }
        }
        o
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
            o.set(key, v)?;
        }
        Ok(o)
    }

    /// Set the model keyword `key` to `v` (its domain in [`JOINT_ENV_OPTIONS`]); `key` is one
    /// of `MODEL_KEYS`.
    fn set(&mut self, key: &str, v: &OptionValue) -> Result<()> {
        let o = self;
        let info = joint_option_info(key).expect("model keys are in the table");
        let d = &info.domain;
        let f = || f64::from_option(key, d, v);
        match key {
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
        Ok(())
    }

    /// Each model keyword (`MODEL_KEYS`' order) with its value here (`None` for a nullable
    /// keyword left to the scenario): what [`JointOptions::from_options`] reads back.
    pub fn values(&self) -> Vec<(&'static str, Option<OptionValue>)> {
        let f = |x: f64| Some(OptionValue::Float(x));
        MODEL_KEYS
            .iter()
            .map(|&key| {
                let v = match key {
                    "max_joint_step_deg" => f(self.max_joint_step_deg),
                    "target_tolerance_mm" => f(self.target_tolerance_mm),
                    "link_radius_mm" => self.link_radius_mm.and_then(f),
                    "safe_distance_mm" => self.safe_distance_mm.and_then(f),
                    "substep_fraction" => f(self.substep_fraction),
                    "assist" => Some(OptionValue::Bool(self.assist)),
                    "reward_scale" => f(self.reward_scale),
                    "target_reward" => f(self.target_reward),
                    "step_penalty" => f(self.step_penalty),
                    "collision_penalty" => f(self.collision_penalty),
                    "repeat_collision_penalty" => f(self.repeat_collision_penalty),
                    "reverse_after_collision_penalty" => f(self.reverse_after_collision_penalty),
                    "progress_reward" => f(self.progress_reward),
                    "max_episode_steps" => Some(OptionValue::Int(self.max_episode_steps.into())),
                    _ => unreachable!("MODEL_KEYS lists every arm of this match"),
                };
                (key, v)
            })
            .collect()
    }

    /// Check every field against its domain in [`JOINT_ENV_OPTIONS`]; the error names it.
    pub fn check(&self) -> Result<()> {
        for (key, v) in self.values() {
            if let Some(v) = v {
                let info = joint_option_info(key).expect("model keys are in the table");
                check_value(key, &info.domain, &v)?;
            }
        }
        Ok(())
    }
}
