//! A world: one native batch of `num_envs` lanes ([`BatchEnv`]) with the specs, settings and
//! step semantics of docs/SERVER.md "CreateWorld settings" and docs/SERVER.md "Episodes".
//!
//! - The first Step after JoinWorld, Reset or ResetWorld resets every lane (seeding them
//!   first if a seed is pending) and returns the initial observations; its actions are
//!   ignored (the protocol's rule). It is `reset(seed=...)` of `sixaxis_avoid.vector`.
//! - Every other Step is `step(actions)` of the vector env: Gymnasium 1.x next-step
//!   autoreset, bit for bit (the same core code).
//! - With `num_envs = 1` the tensors are scalars and the state follows dm_env: TERMINATED
//!   when the target is reached, INTERRUPTED when truncated at `max_episode_steps`, and the
//!   Step after either starts a new episode (state RUNNING, the initial observation; that
//!   Step's action is ignored). With `num_envs > 1` the state is always RUNNING and the lanes'
//!   ends are the `terminated` / `truncated` observations.

use std::collections::BTreeMap;
use std::sync::Arc;

use sixaxis_core::env::{
    env_option_info, unreachable_cells, BatchEnv, BatchOutputs, EnvModel, EnvOptions, OBS_TARGET,
    OBS_TERMINAL, VECTOR_OBS_DIM,
};
use sixaxis_core::options::{check_value, Domain, OptionValue};
use sixaxis_core::request::TrainRequest;
use sixaxis_core::Scenario;
use tonic::Code;

use crate::failure::Failure;
use crate::proto::tensor::{BoolArray, DoubleArray, FloatArray, Int32Array, Payload, StringArray};
use crate::proto::tensor_spec::{Value, ValuePayload};
use crate::proto::{
    ActionObservationSpecs, DataType, EnvironmentStateType, Settings, StepRequest, StepResponse,
    Tensor, TensorSpec,
};
use crate::seeding;

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

/// The `seed` setting of a Reset or ResetWorld (the only one they take).
pub fn reset_seed(settings: &Settings) -> Result<Option<u64>, Failure> {
    let mut seed = None;
    for (key, t) in settings {
        if key != "seed" {
            return Err(unknown_setting(key, t, &["seed"]));
        }
        seed = Some(checked_seed(&setting_value(key, t)?)?);
    }
    Ok(seed)
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

/// A world: the batch, its buffers, its specs and where its episode stands.
#[derive(Debug)]
pub struct World {
    batch: BatchEnv,
    obs_type: ObsType,
    buf: BatchOutputs,
    specs: ActionObservationSpecs,
    /// The next Step resets the lanes instead of stepping them.
    needs_start: bool,
    /// The seed of that reset.
    pending_seed: Option<u64>,
    /// The lanes were seeded once (a reset without a seed then keeps their generators).
    seeded: bool,
}

fn spec(
    name: &str,
    shape: Vec<i32>,
    dtype: DataType,
    bounds: Option<(ValuePayload, ValuePayload)>,
) -> TensorSpec {
    let (min, max) = match bounds {
        Some((lo, hi)) => (
            Some(Value { payload: Some(lo) }),
            Some(Value { payload: Some(hi) }),
        ),
        None => (None, None),
    };
    TensorSpec {
        name: name.to_string(),
        shape,
        dtype: dtype as i32,
        min,
        max,
    }
}

fn f32_bounds(lo: f32, hi: f32) -> Option<(ValuePayload, ValuePayload)> {
    Some((
        ValuePayload::Floats(FloatArray { array: vec![lo] }),
        ValuePayload::Floats(FloatArray { array: vec![hi] }),
    ))
}

fn i32_bounds(lo: i32, hi: i32) -> Option<(ValuePayload, ValuePayload)> {
    Some((
        ValuePayload::Int32s(Int32Array { array: vec![lo] }),
        ValuePayload::Int32s(Int32Array { array: vec![hi] }),
    ))
}

impl World {
    /// The world of these settings (arm-aware worlds compute their blocked cells here:
    /// call it off the async reactor).
    pub fn new(s: &WorldSettings) -> Result<World, Failure> {
        let mut req = TrainRequest::default();
        if let Some(a) = s.assist {
            req = req.with("assist", a);
        }
        let assist = req.resolve(&s.scenario)?.assist();
        let extra_obstacles = if s.arm_aware {
            unreachable_cells(&s.scenario)?
        } else {
            Vec::new()
        };
        let model = EnvModel::new(
            &s.scenario,
            EnvOptions {
                assist,
                reward_scale: s.reward_scale,
                random_target: s.random_target,
                extra_obstacles,
            },
        )?;
        let num_states = model.num_states();
        let batch = BatchEnv::new(Arc::new(model), s.num_envs, s.max_episode_steps)?;
        Ok(World {
            specs: Self::make_specs(s.num_envs, s.obs_type, num_states),
            buf: BatchOutputs::new(s.num_envs, s.obs_type == ObsType::Index),
            batch,
            obs_type: s.obs_type,
            needs_start: true,
            pending_seed: s.seed,
            seeded: false,
        })
    }

    fn make_specs(n: usize, obs: ObsType, num_states: usize) -> ActionObservationSpecs {
        let lead: Vec<i32> = if n == 1 { vec![] } else { vec![n as i32] };
        let with = |extra: i32| {
            let mut s = lead.clone();
            s.push(extra);
            s
        };
        let mut actions = BTreeMap::new();
        actions.insert(
            ACTION,
            spec("action", lead.clone(), DataType::Int32, i32_bounds(0, 5)),
        );
        let mut o = BTreeMap::new();
        match obs {
            ObsType::Index => {
                let top = i32::try_from(num_states.saturating_sub(1)).unwrap_or(i32::MAX);
                o.insert(
                    OBSERVATION,
                    spec(
                        "observation",
                        lead.clone(),
                        DataType::Int32,
                        i32_bounds(0, top),
                    ),
                );
            }
            ObsType::Vector | ObsType::Goal => {
                o.insert(
                    OBSERVATION,
                    spec(
                        "observation",
                        with(VECTOR_OBS_DIM as i32),
                        DataType::Float,
                        f32_bounds(-1.0, 1.0),
                    ),
                );
            }
        }
        if obs == ObsType::Goal {
            o.insert(
                ACHIEVED_GOAL,
                spec(
                    "achieved_goal",
                    with(3),
                    DataType::Float,
                    f32_bounds(-1.0, 1.0),
                ),
            );
            o.insert(
                DESIRED_GOAL,
                spec(
                    "desired_goal",
                    with(3),
                    DataType::Float,
                    f32_bounds(-1.0, 1.0),
                ),
            );
        }
        o.insert(REWARD, spec("reward", lead.clone(), DataType::Double, None));
        o.insert(
            DISCOUNT,
            spec(
                "discount",
                lead.clone(),
                DataType::Float,
                f32_bounds(0.0, 1.0),
            ),
        );
        o.insert(
            TERMINATED,
            spec("terminated", lead.clone(), DataType::Bool, None),
        );
        o.insert(
            TRUNCATED,
            spec("truncated", lead.clone(), DataType::Bool, None),
        );
        o.insert(
            IS_SUCCESS,
            spec("is_success", lead.clone(), DataType::Bool, None),
        );
        o.insert(
            COLLIDED,
            spec("collided", lead.clone(), DataType::Bool, None),
        );
        o.insert(
            DISTANCE_TO_TARGET,
            spec("distance_to_target", lead.clone(), DataType::Double, None),
        );
        o.insert(CELL, spec("cell", with(3), DataType::Int32, None));
        o.insert(
            DETOUR_PENALTY,
            spec("detour_penalty", lead.clone(), DataType::Double, None),
        );
        ActionObservationSpecs {
            actions,
            observations: o,
        }
    }

    /// The specs (fixed for the world's life).
    pub fn specs(&self) -> &ActionObservationSpecs {
        &self.specs
    }

    /// Lanes.
    pub fn num_envs(&self) -> usize {
        self.batch.len()
    }

    /// The next Step starts the episodes anew (JoinWorld, Reset, ResetWorld), seeded with
    /// `seed` if given.
    pub fn restart(&mut self, seed: Option<u64>) {
        self.needs_start = true;
        if seed.is_some() {
            self.pending_seed = seed;
        }
    }

    /// One Step request (see the module docs).
    pub fn step(&mut self, req: &StepRequest) -> Result<StepResponse, Failure> {
        for &uid in &req.requested_observations {
            if !self.specs.observations.contains_key(&uid) {
                let known: Vec<String> = self
                    .specs
                    .observations
                    .keys()
                    .map(|k| k.to_string())
                    .collect();
                return Err(Failure::argument(
                    "requested_observations",
                    uid,
                    format!(
                        "is no observation uid of this world; the uids are {}",
                        known.join(", ")
                    ),
                ));
            }
        }
        let n = self.batch.len();
        let state = if self.needs_start {
            let seeds = match self.pending_seed.take() {
                Some(s) => Some(seeding::lane_seeds(s, n)),
                None if !self.seeded => Some(seeding::entropy_seeds(n)),
                None => None,
            };
            if let Some(seeds) = seeds {
                self.batch.seed(&seeds)?;
                self.seeded = true;
            }
            self.batch.reset(None, self.buf.buffers())?;
            self.needs_start = false;
            EnvironmentStateType::Running
        } else {
            let actions = self.actions(req)?;
            self.batch.step(&actions, self.buf.buffers())?;
            if n == 1 && self.buf.terminated[0] {
                EnvironmentStateType::Terminated
            } else if n == 1 && self.buf.truncated[0] {
                EnvironmentStateType::Interrupted
            } else {
                EnvironmentStateType::Running
            }
        };
        let mut observations = BTreeMap::new();
        for &uid in &req.requested_observations {
            observations
                .entry(uid)
                .or_insert_with(|| self.observation(uid));
        }
        Ok(StepResponse {
            state: state as i32,
            observations,
        })
    }

    fn actions(&self, req: &StepRequest) -> Result<Vec<i64>, Failure> {
        let n = self.batch.len();
        if let Some(uid) = req.actions.keys().find(|&&k| k != ACTION) {
            return Err(Failure::argument(
                "actions",
                format!("uid {uid}"),
                "is no action uid of this world; the one action is uid 1 (`action`)",
            ));
        }
        let Some(t) = req.actions.get(&ACTION) else {
            return Err(Failure::argument(
                "action",
                "missing",
                "a Step (other than the first after JoinWorld, Reset or ResetWorld) needs action uid 1",
            ));
        };
        let values = int_values(t)?;
        let want: Vec<i32> = if n == 1 { vec![] } else { vec![n as i32] };
        check_shape(&t.shape, &want, values.len())?;
        let actions: Vec<i64> = if values.len() == 1 {
            vec![values[0]; n]
        } else {
            values
        };
        if let Some((i, a)) = actions
            .iter()
            .enumerate()
            .find(|(_, a)| !(0..6).contains(*a))
        {
            return Err(Failure::argument(
                "action",
                if n == 1 {
                    a.to_string()
                } else {
                    format!("{a} at index {i}")
                },
                "each action must be an integer in 0..=5 (0:+x 1:-x 2:+y 3:-y 4:+z 5:-z)",
            ));
        }
        Ok(actions)
    }

    fn lead(&self, extra: Option<i32>) -> Vec<i32> {
        let n = self.batch.len();
        let mut s = if n == 1 { vec![] } else { vec![n as i32] };
        s.extend(extra);
        s
    }

    fn observation(&self, uid: u64) -> Tensor {
        let b = &self.buf;
        let goals = |range: std::ops::Range<usize>| -> Vec<f32> {
            b.obs_vector
                .chunks_exact(VECTOR_OBS_DIM)
                .flat_map(|row| row[range.clone()].iter().copied())
                .collect()
        };
        let (payload, shape) = match uid {
            OBSERVATION => match self.obs_type {
                ObsType::Index => (
                    Payload::Int32s(Int32Array {
                        array: b.obs_index.iter().map(|&s| s as i32).collect(),
                    }),
                    self.lead(None),
                ),
                _ => (
                    Payload::Floats(FloatArray {
                        array: b.obs_vector.clone(),
                    }),
                    self.lead(Some(VECTOR_OBS_DIM as i32)),
                ),
            },
            ACHIEVED_GOAL => (
                Payload::Floats(FloatArray {
                    array: goals(OBS_TERMINAL),
                }),
                self.lead(Some(3)),
            ),
            DESIRED_GOAL => (
                Payload::Floats(FloatArray {
                    array: goals(OBS_TARGET),
                }),
                self.lead(Some(3)),
            ),
            REWARD => (
                Payload::Doubles(DoubleArray {
                    array: b.rewards.clone(),
                }),
                self.lead(None),
            ),
            DISCOUNT => (
                Payload::Floats(FloatArray {
                    array: b
                        .terminated
                        .iter()
                        .map(|&t| if t { 0.0 } else { 1.0 })
                        .collect(),
                }),
                self.lead(None),
            ),
            TERMINATED | IS_SUCCESS => (
                Payload::Bools(BoolArray {
                    array: b.terminated.clone(),
                }),
                self.lead(None),
            ),
            TRUNCATED => (
                Payload::Bools(BoolArray {
                    array: b.truncated.clone(),
                }),
                self.lead(None),
            ),
            COLLIDED => (
                Payload::Bools(BoolArray {
                    array: b.collided.clone(),
                }),
                self.lead(None),
            ),
            DISTANCE_TO_TARGET => (
                Payload::Doubles(DoubleArray {
                    array: b.distance.clone(),
                }),
                self.lead(None),
            ),
            CELL => (
                Payload::Int32s(Int32Array {
                    array: b.cells.clone(),
                }),
                self.lead(Some(3)),
            ),
            DETOUR_PENALTY => (
                Payload::Doubles(DoubleArray {
                    array: b.detour_penalty.clone(),
                }),
                self.lead(None),
            ),
            _ => (Payload::Strings(StringArray { array: vec![] }), vec![0]),
        };
        Tensor {
            payload: Some(payload),
            shape,
        }
    }
}

/// The integer values of an action tensor (any integer dtype); another dtype is an error
/// naming it.
fn int_values(t: &Tensor) -> Result<Vec<i64>, Failure> {
    let wrong = |kind: &str| {
        Failure::argument(
            "action",
            format!("a {kind} tensor"),
            "must be an integer tensor (the spec's dtype is int32)",
        )
    };
    Ok(match &t.payload {
        Some(Payload::Int32s(a)) => a.array.iter().map(|&v| i64::from(v)).collect(),
        Some(Payload::Int64s(a)) => a.array.clone(),
        Some(Payload::Int8s(a)) => a.array.iter().map(|&v| i64::from(v as i8)).collect(),
        Some(Payload::Uint8s(a)) => a.array.iter().map(|&v| i64::from(v)).collect(),
        Some(Payload::Uint32s(a)) => a.array.iter().map(|&v| i64::from(v)).collect(),
        Some(Payload::Uint64s(a)) => a
            .array
            .iter()
            .map(|&v| i64::try_from(v).unwrap_or(i64::MAX))
            .collect(),
        Some(Payload::Floats(_)) => return Err(wrong("float32")),
        Some(Payload::Doubles(_)) => return Err(wrong("float64")),
        Some(Payload::Bools(_)) => return Err(wrong("bool")),
        Some(Payload::Strings(_)) => return Err(wrong("string")),
        Some(Payload::Protos(_)) => return Err(wrong("proto")),
        None => return Err(wrong("empty")),
    })
}

/// A tensor's shape against the spec's (`want`), with the protocol's rules: the same rank,
/// at most one dimension -1 (inferred from the payload), and a payload of one value is
/// broadcast to the shape.
fn check_shape(shape: &[i32], want: &[i32], len: usize) -> Result<(), Failure> {
    let bad = |why: &str| {
        Failure::argument(
            "action",
            format!("a tensor of shape {shape:?} with {len} values"),
            format!("{why} (the spec's shape is {want:?})"),
        )
    };
    if shape.len() != want.len() {
        return Err(bad("has the wrong number of dimensions"));
    }
    let variable = shape.iter().filter(|&&d| d == -1).count();
    if variable > 1 {
        return Err(bad("has more than one variable (-1) dimension"));
    }
    let total: usize = want.iter().map(|&d| d as usize).product();
    if variable == 1 {
        let known: usize = shape
            .iter()
            .filter(|&&d| d != -1)
            .map(|&d| d.max(0) as usize)
            .product();
        let inferred = len.checked_div(known).unwrap_or(0);
        if known * inferred != len {
            return Err(bad("has a payload that fills no whole shape"));
        }
        let full: Vec<i32> = shape
            .iter()
            .map(|&d| if d == -1 { inferred as i32 } else { d })
            .collect();
        if full != want {
            return Err(bad("does not match"));
        }
        return Ok(());
    }
    if shape != want {
        return Err(bad("does not match"));
    }
    if len != 1 && len != total {
        return Err(bad(
            "has a payload that is neither one value nor one per element",
        ));
    }
    Ok(())
}

/// The failure of a world that no longer exists or is broken (`Code::FailedPrecondition`).
pub fn gone(name: &str) -> Failure {
    Failure::new(
        Code::FailedPrecondition,
        format!("world `{name}` is gone (destroyed, or its creator's connection closed)"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(pairs: &[(&str, Tensor)]) -> Settings {
        pairs
            .iter()
            .map(|(k, t)| (k.to_string(), t.clone()))
            .collect()
    }

    fn int(v: i64) -> Tensor {
        Tensor {
            payload: Some(Payload::Int64s(crate::proto::tensor::Int64Array {
                array: vec![v],
            })),
            shape: vec![],
        }
    }

    fn text(v: &str) -> Tensor {
        Tensor {
            payload: Some(Payload::Strings(StringArray {
                array: vec![v.into()],
            })),
            shape: vec![],
        }
    }

    #[test]
    fn settings_are_checked_by_the_core_table() {
        let e = WorldSettings::from_settings(&settings(&[("num_envs", int(0))])).unwrap_err();
        assert_eq!(e.code, Code::InvalidArgument);
        assert!(e.message.contains("`num_envs` = 0"), "{}", e.message);
        let e =
            WorldSettings::from_settings(&settings(&[("obs_type", text("pixels"))])).unwrap_err();
        assert!(e.message.contains("`obs_type` = pixels"), "{}", e.message);
        let e = WorldSettings::from_settings(&settings(&[("colour", text("red"))])).unwrap_err();
        assert!(
            e.message.contains("`colour` = red: is no setting"),
            "{}",
            e.message
        );
        let e =
            WorldSettings::from_settings(&settings(&[("scenario", text("nowhere"))])).unwrap_err();
        assert_eq!(e.code, Code::NotFound);
        let e = WorldSettings::from_settings(&settings(&[("scenario", text("/etc/passwd"))]))
            .unwrap_err();
        assert_eq!(e.code, Code::NotFound, "{}", e.message);
        let s = WorldSettings::from_settings(&settings(&[
            ("num_envs", int(4)),
            ("obs_type", text("goal")),
            ("seed", int(3)),
        ]))
        .unwrap();
        assert_eq!(
            (s.num_envs, s.obs_type, s.seed),
            (4, ObsType::Goal, Some(3))
        );
        assert_eq!(
            s.max_episode_steps,
            s.scenario.learning.max_steps_per_episode
        );
    }

    #[test]
    fn shapes_follow_the_protocol() {
        assert!(check_shape(&[], &[], 1).is_ok());
        assert!(check_shape(&[1], &[], 1).is_err());
        assert!(check_shape(&[4], &[4], 4).is_ok());
        assert!(check_shape(&[4], &[4], 1).is_ok());
        assert!(check_shape(&[-1], &[4], 4).is_ok());
        assert!(check_shape(&[-1], &[4], 3).is_err());
        assert!(check_shape(&[4], &[4], 3).is_err());
        assert!(check_shape(&[-1, -1], &[4], 4).is_err());
    }
}
