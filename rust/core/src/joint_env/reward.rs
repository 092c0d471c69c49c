//! The joint env's reward (docs/JOINT.md, "Rewards"): eq. 5's target reward, step and
//! collision penalties, eq. 10 as progress in mm (`progress_reward`, 1/mm) and eq. 9's detour
//! penalty, times `reward_scale`; and the same arithmetic for relabelled goals (HER).
//!
//! Entry points (methods of [`JointModel`]):
//! - [`JointModel::reward_of`] — one step's reward from its float32 goals (positions /
//!   reach), and whether it reached the target (within `target_tolerance_mm`, mm).
//! - [`JointModel::goal_rewards`] — the rewards of `n` relabelled transitions, checked input.

use super::JointModel;
use crate::error::{Error, Result};

impl JointModel {
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
    /// arithmetic of [`JointEpisode::step`](super::JointEpisode::step): a step's own goals
    /// give its reward to the bit.
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
}
