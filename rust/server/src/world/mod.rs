//! A world: one native batch of `num_envs` lanes ([`BatchEnv`]) with the specs, settings and
//! step semantics of docs/SERVER.md "CreateWorld settings" and docs/SERVER.md "Episodes".
//!
//! - The first Step after JoinWorld, Reset or ResetWorld resets every lane (seeding them
//!   first if a seed is pending) and returns the initial observations; its actions are
//!   ignored (the protocol's rule). It is `reset(seed=...)` of `sixaxis_avoid.vector`.
//!   A Reset with `reset_mask` restarts only the lanes of the mask at that Step; the others
//!   are not stepped (`reset(options={"reset_mask": mask})`).
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
    unreachable_cells, BatchEnv, BatchOutputs, EnvModel, EnvOptions, OBS_TARGET, OBS_TERMINAL,
    VECTOR_OBS_DIM,
};
use sixaxis_core::request::TrainRequest;
use tonic::Code;

use crate::failure::Failure;
use crate::proto::tensor::{BoolArray, DoubleArray, FloatArray, Int32Array, Payload, StringArray};
use crate::proto::tensor_spec::{Value, ValuePayload};
use crate::proto::{
    ActionObservationSpecs, DataType, EnvironmentStateType, StepRequest, StepResponse, Tensor,
    TensorSpec,
};
use crate::seeding;

mod settings;

pub use settings::*;

/// A world: the batch, its buffers, its specs and where its episode stands.
#[derive(Debug)]
pub struct World {
    batch: BatchEnv,
    obs_type: ObsType,
    buf: BatchOutputs,
    specs: ActionObservationSpecs,
    /// The next Step resets the lanes instead of stepping them.
    needs_start: bool,
    /// The lanes that reset restarts (None: all).
    start_mask: Option<Vec<bool>>,
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
            start_mask: None,
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

    /// The next Step starts the episodes anew (JoinWorld, Reset, ResetWorld): every lane's,
    /// or those of `reset.reset_mask` (together with the lanes of a restart still pending),
    /// seeding every lane first with `reset.seed` if given. A mask that is no bool per lane
    /// is an error naming `reset_mask`, and changes nothing.
    pub fn restart(&mut self, reset: &ResetSettings) -> Result<(), Failure> {
        let mask = match &reset.reset_mask {
            None => None,
            Some(t) => Some(self.reset_mask(t)?),
        };
        self.start_mask = match (mask, self.start_mask.take()) {
            (Some(new), Some(mut old)) if self.needs_start => {
                old.iter_mut().zip(new).for_each(|(o, n)| *o |= n);
                Some(old)
            }
            // A whole restart still pending stays whole.
            (Some(_), None) if self.needs_start => None,
            (mask, _) => mask,
        };
        self.needs_start = true;
        if reset.seed.is_some() {
            self.pending_seed = reset.seed;
        }
        Ok(())
    }

    /// A `reset_mask` tensor's lanes: bools shaped as the lanes (`[N]`, a scalar for one
    /// lane), the protocol's shape rules (a -1 dimension, one value for every lane).
    fn reset_mask(&self, t: &Tensor) -> Result<Vec<bool>, Failure> {
        let n = self.batch.len();
        let Some(Payload::Bools(b)) = &t.payload else {
            return Err(Failure::argument(
                "reset_mask",
                "a tensor of another dtype",
                "must be a bool tensor, one value per lane",
            ));
        };
        check_shape("reset_mask", &t.shape, &self.lead(None), b.array.len())?;
        Ok(if b.array.len() == 1 {
            vec![b.array[0]; n]
        } else {
            b.array.clone()
        })
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
            let mask = self.start_mask.take();
            self.batch.reset(mask.as_deref(), self.buf.buffers())?;
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
        check_shape("action", &t.shape, &self.lead(None), values.len())?;
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
fn check_shape(name: &str, shape: &[i32], want: &[i32], len: usize) -> Result<(), Failure> {
    let bad = |why: &str| {
        Failure::argument(
            name,
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
mod tests;
