//! N joint-space episodes stepped together ([`JointBatch`], the joint env's instance of
//! [`crate::batch::Batch`]: next-step autoreset and a step cap), into caller-provided
//! buffers ([`JointBuffers`]).

use std::sync::Arc;

use super::{JointEpisode, JointModel, JOINT_ENV_OPTIONS};
use crate::batch::{Batch, Lane, LaneStep, StepRows};
use crate::error::{Error, Result};
use crate::options::{check_value, OptionValue};

/// Caller-provided output buffers of a batch step or reset (`n` lanes; row-major).
#[derive(Debug)]
pub struct JointBuffers<'a> {
    /// Observations, `n * obs_dim` float32.
    pub obs: &'a mut [f32],
    /// Rewards, `n`.
    pub rewards: &'a mut [f64],
    /// The lane reached its target, `n`.
    pub terminated: &'a mut [bool],
    /// The lane hit the step cap, `n`.
    pub truncated: &'a mut [bool],
    /// The step was refused, `n`.
    pub refused: &'a mut [bool],
    /// Terminal-target distance, mm, `n`.
    pub distance_mm: &'a mut [f64],
    /// Smallest link capsule gap, mm, `n` (`INFINITY` without obstacles).
    pub clearance_mm: &'a mut [f64],
    /// Eq. 9's part of the reward (<= 0, before `reward_scale`; 0 after a reset), `n`.
    pub detour_penalty: &'a mut [f64],
    /// Joint angles, radians, `6 n`.
    pub joints: &'a mut [f64],
    /// Terminal position, mm, `3 n`.
    pub terminal_mm: &'a mut [f64],
    /// The achieved goal before the step (float32, as the observation), `3 n`.
    pub previous_goal: &'a mut [f32],
}

/// N joint-space envs stepped together, with next-step autoreset and a step cap
/// (`max_episode_steps` of the model's options): the [`Batch`] of [`JointEpisode`]s (its
/// semantics: [`crate::batch`]).
pub type JointBatch = Batch<JointEpisode>;

impl Lane for JointEpisode {
    type Model = JointModel;
    type Buffers<'a> = JointBuffers<'a>;

    fn reset(&mut self, model: &JointModel) {
        JointEpisode::reset(self, model);
    }

    fn steps(&self) -> u32 {
        JointEpisode::steps(self)
    }

    fn check_buffers(model: &JointModel, n: usize, b: &JointBuffers<'_>) -> Result<()> {
        let d = model.obs_dim();
        let lengths = [
            ("obs", b.obs.len(), n * d),
            ("rewards", b.rewards.len(), n),
            ("terminated", b.terminated.len(), n),
            ("truncated", b.truncated.len(), n),
            ("refused", b.refused.len(), n),
            ("distance_mm", b.distance_mm.len(), n),
            ("clearance_mm", b.clearance_mm.len(), n),
            ("detour_penalty", b.detour_penalty.len(), n),
            ("joints", b.joints.len(), 6 * n),
            ("terminal_mm", b.terminal_mm.len(), 3 * n),
            ("previous_goal", b.previous_goal.len(), 3 * n),
        ];
        for (name, len, want) in lengths {
            if len != want {
                return Err(Error::argument(
                    name,
                    format!("{len} values"),
                    format!("the buffer must hold {want} ({n} envs)"),
                ));
            }
        }
        Ok(())
    }

    #[inline]
    fn step_rows<'b>(b: &'b mut JointBuffers<'_>) -> StepRows<'b> {
        StepRows {
            rewards: b.rewards,
            terminated: b.terminated,
            truncated: b.truncated,
            detour_penalty: b.detour_penalty,
        }
    }

    #[inline]
    fn write(&self, m: &JointModel, i: usize, b: &mut JointBuffers<'_>) {
        let d = m.obs_dim();
        self.write_obs(m, &mut b.obs[i * d..(i + 1) * d]);
        b.refused[i] = self.refused();
        b.distance_mm[i] = self.distance_to_target_mm(m);
        b.clearance_mm[i] = self.clearance_mm(m);
        b.joints[6 * i..6 * i + 6].copy_from_slice(&self.joints_rad());
        let t = self.terminal_mm();
        b.terminal_mm[3 * i..3 * i + 3].copy_from_slice(&[t.x, t.y, t.z]);
        b.previous_goal[3 * i..3 * i + 3].copy_from_slice(&self.previous_goal());
    }
}

impl Batch<JointEpisode> {
    /// `n` envs of `model` (`n` in `num_envs`' domain of [`JOINT_ENV_OPTIONS`]).
    pub fn new(model: Arc<JointModel>, n: usize) -> Result<JointBatch> {
        let info = JOINT_ENV_OPTIONS
            .iter()
            .find(|i| i.key == "num_envs")
            .expect("in the table");
        check_value("num_envs", &info.domain, &OptionValue::Int(n as i128))?;
        let ep = JointEpisode::new(&model);
        let cap = model.options().max_episode_steps;
        Ok(Batch::from_lane(model, ep, n, cap))
    }

    /// Step every lane with its action (`actions`: `6 n` numbers, row-major, each in
    /// [-1, 1]; all checked before any lane moves). Lanes whose episode ended at the
    /// previous step are reset instead (next-step autoreset; their action is ignored).
    pub fn step(&mut self, actions: &[f64], b: JointBuffers<'_>) -> Result<()> {
        self.check(&b)?;
        let n = self.len();
        if actions.len() != 6 * n {
            return Err(Error::argument(
                "actions",
                format!("{} values", actions.len()),
                format!("expected 6 per env ({n} envs, {})", 6 * n),
            ));
        }
        // Named (formatted) only when wrong: no allocation per lane on the hot path.
        if let Some(i) = (0..n).find(|&i| {
            !actions[6 * i..6 * i + 6]
                .iter()
                .all(|v| (-1.0..=1.0).contains(v))
        }) {
            JointModel::check_action(&format!("actions[{i}]"), &actions[6 * i..6 * i + 6])?;
        }
        self.step_checked(b, |ep, model, i| {
            let a: [f64; 6] = std::array::from_fn(|k| actions[6 * i + k]);
            let out = ep.step_unchecked(model, &a);
            LaneStep {
                reward: out.reward,
                reached: out.reached,
                detour_penalty: out.detour_penalty,
            }
        });
        Ok(())
    }
}
