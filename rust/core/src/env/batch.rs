//! N episodes stepped together ([`BatchEnv`], the grid env's instance of
//! [`crate::batch::Batch`]: next-step autoreset and a step cap), into caller-provided
//! buffers ([`BatchBuffers`]): borrowed from numpy arrays by the bindings, or from an owned
//! [`BatchOutputs`] (the server, the tables' checks, tests).

use std::sync::Arc;

use super::{EnvModel, Episode, NUM_ENVS, VECTOR_OBS_DIM};
use crate::batch::{Batch, Lane, LaneStep, StepRows};
use crate::error::{Error, Result};
use crate::grid::NUM_ACTIONS;
use crate::options::{check_value, Domain, OptionValue};

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

/// Owned output buffers of a batch of `n` lanes: what [`BatchOutputs::buffers`] lends to
/// [`BatchEnv::reset`] and [`BatchEnv::step`], then read field by field.
///
/// ```
/// use std::sync::Arc;
/// use sixaxis_core::env::{BatchEnv, BatchOutputs, EnvModel, EnvOptions};
/// use sixaxis_core::scenario::Scenario;
///
/// let s = Scenario::builtin("paper_simple").unwrap();
/// let model = Arc::new(EnvModel::new(&s, EnvOptions::for_scenario(&s)).unwrap());
/// let mut batch = BatchEnv::new(model, 4, 200).unwrap();
/// let mut out = BatchOutputs::new(4, false);
/// batch.reset(None, out.buffers()).unwrap();
/// batch.step(&[2u8, 2, 2, 2], out.buffers()).unwrap();
/// assert_eq!(out.obs_vector.len(), 4 * 13);
/// assert_eq!(out.cells.len(), 4 * 3);
/// assert!(out.rewards.iter().all(|r| r.is_finite()));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct BatchOutputs {
    /// Vector observations, row-major `(n, VECTOR_OBS_DIM)`; empty for index observations.
    pub obs_vector: Vec<f32>,
    /// Index observations (state numbers), `n`; empty for vector observations.
    pub obs_index: Vec<i64>,
    /// Rewards (after `reward_scale`).
    pub rewards: Vec<f64>,
    /// The episode reached its target.
    pub terminated: Vec<bool>,
    /// The episode hit the step cap.
    pub truncated: Vec<bool>,
    /// The step collided.
    pub collided: Vec<bool>,
    /// Distance from the terminal to the target, cells.
    pub distance: Vec<f64>,
    /// The terminal's cell, row-major `(n, 3)`.
    pub cells: Vec<i32>,
    /// Eq. 9's part of the step's reward (<= 0, before `reward_scale`).
    pub detour_penalty: Vec<f64>,
    index_obs: bool,
}

impl BatchOutputs {
    /// Zeroed buffers for `n` lanes, with index observations if `index_obs` (state numbers),
    /// else vector observations.
    pub fn new(n: usize, index_obs: bool) -> BatchOutputs {
        let (nf, ni) = if index_obs {
            (0, n)
        } else {
            (n * VECTOR_OBS_DIM, 0)
        };
        BatchOutputs {
            obs_vector: vec![0.0; nf],
            obs_index: vec![0; ni],
            rewards: vec![0.0; n],
            terminated: vec![false; n],
            truncated: vec![false; n],
            collided: vec![false; n],
            distance: vec![0.0; n],
            cells: vec![0; 3 * n],
            detour_penalty: vec![0.0; n],
            index_obs,
        }
    }

    /// The number of lanes.
    pub fn len(&self) -> usize {
        self.rewards.len()
    }

    /// Whether there are no lanes.
    pub fn is_empty(&self) -> bool {
        self.rewards.is_empty()
    }

    /// Whether the observations are index observations.
    pub fn index_obs(&self) -> bool {
        self.index_obs
    }

    /// The buffers lent to one [`BatchEnv::reset`] or [`BatchEnv::step`].
    pub fn buffers(&mut self) -> BatchBuffers<'_> {
        BatchBuffers {
            obs: if self.index_obs {
                ObsBuffer::Index(&mut self.obs_index)
            } else {
                ObsBuffer::Vector(&mut self.obs_vector)
            },
            rewards: &mut self.rewards,
            terminated: &mut self.terminated,
            truncated: &mut self.truncated,
            collided: &mut self.collided,
            distance: &mut self.distance,
            cells: &mut self.cells,
            detour_penalty: &mut self.detour_penalty,
        }
    }
}

/// N environments stepped together, with next-step autoreset and a step cap: the
/// [`Batch`] of grid [`Episode`]s (its semantics: [`crate::batch`]).
pub type BatchEnv = Batch<Episode>;

impl Lane for Episode {
    type Model = EnvModel;
    type Buffers<'a> = BatchBuffers<'a>;

    fn reset(&mut self, model: &EnvModel) {
        Episode::reset(self, model);
    }

    fn steps(&self) -> u32 {
        self.steps
    }

    fn check_buffers(_: &EnvModel, n: usize, buf: &BatchBuffers<'_>) -> Result<()> {
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
    fn step_rows<'b>(buf: &'b mut BatchBuffers<'_>) -> StepRows<'b> {
        StepRows {
            rewards: buf.rewards,
            terminated: buf.terminated,
            truncated: buf.truncated,
            detour_penalty: buf.detour_penalty,
        }
    }

    #[inline]
    fn write(&self, m: &EnvModel, i: usize, buf: &mut BatchBuffers<'_>) {
        match &mut buf.obs {
            ObsBuffer::Vector(o) => {
                self.write_vector_obs(m, &mut o[i * VECTOR_OBS_DIM..(i + 1) * VECTOR_OBS_DIM])
            }
            ObsBuffer::Index(o) => o[i] = self.state as i64,
        }
        buf.distance[i] = self.distance_to_target(m);
        let c = m.world.cell_of(self.state as usize);
        buf.cells[3 * i..3 * i + 3].copy_from_slice(&c);
        buf.collided[i] = self.collided;
    }
}

impl Batch<Episode> {
    /// `n` environments of `model`, truncated after `max_episode_steps` steps.
    pub fn new(model: Arc<EnvModel>, n: usize, max_episode_steps: u32) -> Result<BatchEnv> {
        check_value("num_envs", &NUM_ENVS, &OptionValue::Int(n as i128))?;
        check_value(
            "max_episode_steps",
            &Domain::u32_from(1),
            &OptionValue::Int(max_episode_steps as i128),
        )?;
        let ep = Episode::new(&model);
        Ok(Batch::from_lane(model, ep, n, max_episode_steps))
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
        for (ep, &s) in self.episodes_mut().iter_mut().zip(seeds) {
            ep.seed(s);
        }
        Ok(())
    }

    /// Step every env with its action (each < 6, all checked before any env moves). Envs
    /// whose episode ended at the previous step are reset instead (next-step autoreset).
    pub fn step<A>(&mut self, actions: &[A], buf: BatchBuffers<'_>) -> Result<()>
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
        self.step_checked(buf, |ep, model, i| {
            let out = ep.step(model, actions[i].try_into().unwrap_or(0));
            LaneStep {
                reward: out.reward,
                reached: out.reached,
                detour_penalty: out.detour_penalty,
            }
        });
        Ok(())
    }
}
