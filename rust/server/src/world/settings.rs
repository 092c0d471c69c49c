//! A world's settings: the CreateWorld settings of docs/SERVER.md "CreateWorld settings",
//! each checked by the core's env option table ([`WorldSettings::from_settings`]), and the
//! uids of the actions and observations a world's specs name.

use std::collections::BTreeMap;

use sixaxis_core::env::env_option_info;
use sixaxis_core::options::{check_value, Domain, OptionValue};
use sixaxis_core::Scenario;

use crate::failure::Failure;
use crate::proto::tensor::Payload;
use crate::proto::{Settings, Tensor};

/// The uid of the action `action`.
pub const ACTION: u64 = 1;
/// Observation uid: `observation` (vector float32 `[.., 13]` or index int32).
pub const OBSERVATION: u64 = 1;
/// Observation uid: `reward` (float64).
pub const REWARD: u64 = 2;
/// Observation uid: `discount` (float32: 0 where the lane terminated, else 1).
pub const DISCOUNT: u64 = 3;
/// Observation uid: `achieved_goal` (obs_type `goal` only).
pub const ACHIEVED_GOAL: u64 = 4;
/// Observation uid: `desired_goal` (obs_type `goal` only).
pub const DESIRED_GOAL: u64 = 5;
/// Observation uid: `terminated` (bool).
pub const TERMINATED: u64 = 6;
/// Observation uid: `truncated` (bool).
pub const TRUNCATED: u64 = 7;
/// Observation uid: `is_success` (bool, as the envs' info).
pub const IS_SUCCESS: u64 = 8;
/// Observation uid: `collided` (bool, as the envs' info).
pub const COLLIDED: u64 = 9;
/// Observation uid: `distance_to_target` (float64 cells, as the envs' info).
pub const DISTANCE_TO_TARGET: u64 = 10;
/// Observation uid: `cell` (int32 `[.., 3]`, as the envs' info).
pub const CELL: u64 = 11;
/// Observation uid: `detour_penalty` (float64, as the envs' info).
pub const DETOUR_PENALTY: u64 = 12;

/// The CreateWorld settings, in the order docs/SERVER.md lists them.
pub const WORLD_SETTINGS: &[&str] = &[
    "scenario",
    "num_envs",
    "obs_type",
    "reward_scale",
    "max_episode_steps",
    "arm_aware",
    "random_target",
    "assist",
    "seed",
];

/// The built-in scenario of a world that names none.
pub const DEFAULT_SCENARIO: &str = "paper_simple";

/// What a world observes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObsType {
    /// The 13-float vector observation.
    Vector,
    /// The state number.
    Index,
    /// The vector observation and its goals (`SixAxisAvoidGoal-v0`).
    Goal,
}

/// A world's settings, checked.
#[derive(Debug, Clone)]
pub struct WorldSettings {
    /// The scenario.
    pub scenario: Scenario,
    /// Lanes.
    pub num_envs: usize,
    /// The observation.
    pub obs_type: ObsType,
    /// Factor of every reward.
    pub reward_scale: f64,
    /// Truncation.
    pub max_episode_steps: u32,
    /// Cells no clear arm pose reaches are obstacles.
    pub arm_aware: bool,
    /// A random target at every reset.
    pub random_target: bool,
    /// Assisted strategies on/off (None: the scenario's flags).
    pub assist: Option<bool>,
    /// The seed of the first reset.
    pub seed: Option<u64>,
}

/// The value of a setting tensor: a scalar bool, number or string. The error names the
/// setting.
pub fn setting_value(key: &str, t: &Tensor) -> Result<OptionValue, Failure> {
    let bad = |what: String| {
        Failure::argument(
            key,
            what,
            "a setting must be a scalar tensor (one bool, number or string)",
        )
    };
    let shape_ok = t.shape.iter().all(|&d| d == 1 || d == -1);
    let one = |len: usize, kind: &str| -> Result<(), Failure> {
        if len == 1 && shape_ok {
            Ok(())
        } else {
            Err(bad(format!(
                "{kind} tensor of {len} values, shape {:?}",
                t.shape
            )))
        }
    };
    Ok(match &t.payload {
        None => return Err(bad("an empty tensor".into())),
        Some(Payload::Floats(a)) => {
            one(a.array.len(), "float32")?;
            OptionValue::Float(f64::from(a.array[0]))
        }
        Some(Payload::Doubles(a)) => {
            one(a.array.len(), "float64")?;
            OptionValue::Float(a.array[0])
        }
        Some(Payload::Int8s(a)) => {
            one(a.array.len(), "int8")?;
            OptionValue::Int(i128::from(a.array[0] as i8))
        }
        Some(Payload::Uint8s(a)) => {
            one(a.array.len(), "uint8")?;
            OptionValue::Int(i128::from(a.array[0]))
        }
        Some(Payload::Int32s(a)) => {
            one(a.array.len(), "int32")?;
            OptionValue::Int(i128::from(a.array[0]))
        }
        Some(Payload::Int64s(a)) => {
            one(a.array.len(), "int64")?;
            OptionValue::Int(i128::from(a.array[0]))
        }
        Some(Payload::Uint32s(a)) => {
            one(a.array.len(), "uint32")?;
            OptionValue::Int(i128::from(a.array[0]))
        }
        Some(Payload::Uint64s(a)) => {
            one(a.array.len(), "uint64")?;
            OptionValue::Int(i128::from(a.array[0]))
        }
        Some(Payload::Bools(a)) => {
            one(a.array.len(), "bool")?;
            OptionValue::Bool(a.array[0])
        }
        Some(Payload::Strings(a)) => {
            one(a.array.len(), "string")?;
            OptionValue::Text(a.array[0].clone())
        }
        Some(Payload::Protos(_)) => return Err(bad("a proto tensor".into())),
    })
}

/// The domain of the `seed` setting (as Gymnasium's: a whole number >= 0).
const SEED: Domain = Domain::u64_from(0);

/// The settings of a Reset or ResetWorld (docs/SERVER.md "Episodes").
#[derive(Debug, Clone, Default)]
pub struct ResetSettings {
    /// `seed`: seeds every lane at the next Step.
    pub seed: Option<u64>,
    /// `reset_mask`: the lanes the next Step restarts (a bool per lane; absent: all),
    /// checked against the world's lanes by [`super::World::restart`].
    pub reset_mask: Option<Tensor>,
}

/// The settings of a Reset or ResetWorld: `seed` and `reset_mask`; any other is an error
/// naming it.
pub fn reset_settings(settings: &Settings) -> Result<ResetSettings, Failure> {
    let mut out = ResetSettings::default();
    for (key, t) in settings {
        match key.as_str() {
            "seed" => out.seed = Some(checked_seed(&setting_value(key, t)?)?),
            "reset_mask" => out.reset_mask = Some(t.clone()),
            _ => return Err(unknown_setting(key, t, &["seed", "reset_mask"])),
        }
    }
    Ok(out)
}

fn checked_seed(v: &OptionValue) -> Result<u64, Failure> {
    check_value("seed", &SEED, v)?;
    match v {
        OptionValue::Int(i) => Ok(*i as u64),
        _ => unreachable!("checked: an integer"),
    }
}

fn unknown_setting(key: &str, t: &Tensor, keys: &[&str]) -> Failure {
    let value = setting_value(key, t)
        .map(|v| v.to_string())
        .unwrap_or_else(|_| "a tensor".into());
    Failure::argument(
        key,
        value,
        format!("is no setting here; the settings are {}", keys.join(", ")),
    )
}

fn env_domain(key: &str) -> &'static Domain {
    &env_option_info(key)
        .expect("every env setting is in the core's ENV_OPTIONS")
        .domain
}

fn scenario_of(text: &str) -> Result<Scenario, Failure> {
    let t = text.trim();
    if t.starts_with('{') {
        return Ok(Scenario::from_json(t)?);
    }
    if t.starts_with(sixaxis_core::generator::GENERATED_PREFIX) {
        // `generated:SEED` (never a file: the server reads no client-named file).
        return Ok(Scenario::load(t)?);
    }
    Ok(Scenario::builtin(t)?)
}

impl WorldSettings {
    /// The settings of a CreateWorld request, each checked with the core's env option
    /// table (`ENV_OPTIONS`); the error names the setting and the value.
    pub fn from_settings(settings: &Settings) -> Result<WorldSettings, Failure> {
        let mut values = BTreeMap::new();
        for (key, t) in settings {
            if !WORLD_SETTINGS.contains(&key.as_str()) {
                return Err(unknown_setting(key, t, WORLD_SETTINGS));
            }
            values.insert(key.as_str(), setting_value(key, t)?);
        }
        let text = |key: &str, default: &str| -> Result<String, Failure> {
            match values.get(key) {
                None => Ok(default.to_string()),
                Some(OptionValue::Text(t)) => Ok(t.clone()),
                Some(v) => Err(Failure::argument(key, v, "must be a string")),
            }
        };
        let flag = |key: &str| -> Result<Option<bool>, Failure> {
            match values.get(key) {
                None => Ok(None),
                Some(v) => {
                    check_value(key, env_domain(key), v)?;
                    Ok(Some(matches!(v, OptionValue::Bool(true))))
                }
            }
        };
        let whole = |key: &str| -> Result<Option<i128>, Failure> {
            match values.get(key) {
                None => Ok(None),
                Some(v) => {
                    check_value(key, env_domain(key), v)?;
                    match v {
                        OptionValue::Int(i) => Ok(Some(*i)),
                        _ => unreachable!("checked: an integer"),
                    }
                }
            }
        };

        let scenario = scenario_of(&text("scenario", DEFAULT_SCENARIO)?)?;
        let obs_type = match values.get("obs_type") {
            None => ObsType::Vector,
            Some(OptionValue::Text(t)) if t == "goal" => ObsType::Goal,
            Some(v) => {
                check_value("obs_type", env_domain("obs_type"), v).map_err(|_| {
                    Failure::argument("obs_type", v, "must be one of vector, index, goal")
                })?;
                if matches!(v, OptionValue::Text(t) if t == "index") {
                    ObsType::Index
                } else {
                    ObsType::Vector
                }
            }
        };
        let num_envs = whole("num_envs")?.unwrap_or(1) as usize;
        let reward_scale = match values.get("reward_scale") {
            None => 1.0,
            Some(v) => {
                check_value("reward_scale", env_domain("reward_scale"), v)?;
                match v {
                    OptionValue::Float(x) => *x,
                    OptionValue::Int(i) => *i as f64,
                    _ => unreachable!("checked: a number"),
                }
            }
        };
        let max_episode_steps = match whole("max_episode_steps")? {
            Some(m) => m as u32,
            None => scenario.learning.max_steps_per_episode,
        };
        let arm_aware = flag("arm_aware")?.unwrap_or(false);
        let random_target = flag("random_target")?.unwrap_or(false);
        let assist = flag("assist")?;
        let seed = values.get("seed").map(checked_seed).transpose()?;
        if random_target && obs_type == ObsType::Index {
            return Err(Failure::argument(
                "random_target",
                true,
                "needs obs_type \"vector\" or \"goal\" (the \"index\" observation does not show the target)",
            ));
        }
        Ok(WorldSettings {
            scenario,
            num_envs,
            obs_type,
            reward_scale,
            max_episode_steps,
            arm_aware,
            random_target,
            assist,
            seed,
        })
    }
}
