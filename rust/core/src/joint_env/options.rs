//! The joint env's keywords, declared once: [`JOINT_ENV_OPTIONS`] (key, domain, unit, doc
//! line of each) and [`JointOptions`] (the values, with their defaults), read from an
//! [`Options`] map by [`JointOptions::from_options`] and checked by [`JointOptions::check`].
//!
//! Units are in each keyword's doc line: degrees for joint steps and limits, mm for
//! distances, 1/mm for the progress reward, steps for the step cap.

use crate::error::Result;
use crate::options::{
    check_value, reject_unknown, Domain, FromOption, OptionInfo, OptionValue, Options,
};

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
    /// Step cap of a [`JointBatch`](super::JointBatch), steps.
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
