//! N episodes stepped together, the one batch logic of every env: [`Batch`] owns the lanes
//! (one [`Lane`] each, sharing one model), the per-lane reset mask, the step cap and
//! Gymnasium 1.x next-step autoreset; a lane type says how it resets, steps and fills its
//! rows of the caller's buffers. [`crate::env::BatchEnv`] (the grid env) and
//! [`crate::joint_env::JointBatch`] (the joint-space env) are its instances.
//!
//! # Semantics
//!
//! - [`Batch::reset`] resets the lanes where the mask is true (all without one) and writes
//!   their rows (reward 0, neither flag, eq. 9's part 0); the other lanes' rows are left as
//!   they were.
//! - A step moves every lane with its action, in lane order. A lane's episode *truncates*
//!   when it has taken `max_episode_steps` steps without reaching its target (a step that
//!   reaches the target terminates, never truncates).
//! - **Next-step autoreset**: the step after a lane's episode terminated or truncated
//!   resets that lane instead of moving it; that step's action is ignored, its reward is 0
//!   and it neither terminates nor truncates (docs/JOINT.md, docs/SERVER.md). A new batch's
//!   lanes start pending a reset.
//! - Every argument is checked before any lane moves; an error leaves the batch as it was.

use std::sync::Arc;

use crate::error::{Error, Result};

/// What one step of a lane's episode returns to the batch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaneStep {
    /// Reward, times `reward_scale`.
    pub reward: f64,
    /// The episode reached its target: it terminates.
    pub reached: bool,
    /// Eq. 9's part of the reward (<= 0, before `reward_scale`).
    pub detour_penalty: f64,
}

/// The rows every batch writes whatever its env: one entry per lane.
#[derive(Debug)]
pub struct StepRows<'b> {
    /// Rewards.
    pub rewards: &'b mut [f64],
    /// The lane reached its target.
    pub terminated: &'b mut [bool],
    /// The lane hit the step cap.
    pub truncated: &'b mut [bool],
    /// Eq. 9's part of the reward (<= 0, before `reward_scale`; 0 after a reset).
    pub detour_penalty: &'b mut [f64],
}

/// One lane's running episode, as a [`Batch`] drives it.
pub trait Lane: Clone {
    /// What every lane of a batch shares.
    type Model;
    /// The caller's output buffers of one [`Batch::reset`] or step (`n` lanes each).
    type Buffers<'a>;

    /// Start a new episode.
    fn reset(&mut self, model: &Self::Model);
    /// Steps since the reset.
    fn steps(&self) -> u32;
    /// Whether every buffer of `buf` holds `n` lanes (the error names what is wrong).
    fn check_buffers(model: &Self::Model, n: usize, buf: &Self::Buffers<'_>) -> Result<()>;
    /// The rows of `buf` that every batch writes ([`StepRows`]).
    fn step_rows<'b>(buf: &'b mut Self::Buffers<'_>) -> StepRows<'b>;
    /// Write this lane's own rows (observation, info) into lane `i` of `buf`.
    fn write(&self, model: &Self::Model, i: usize, buf: &mut Self::Buffers<'_>);
}

/// N lanes of one model stepped together, with next-step autoreset and a step cap.
pub struct Batch<L: Lane> {
    model: Arc<L::Model>,
    episodes: Vec<L>,
    needs_reset: Vec<bool>,
    max_episode_steps: u32,
}

impl<L> std::fmt::Debug for Batch<L>
where
    L: Lane + std::fmt::Debug,
    L::Model: std::fmt::Debug,
{
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Batch")
            .field("model", &self.model)
            .field("episodes", &self.episodes)
            .field("needs_reset", &self.needs_reset)
            .field("max_episode_steps", &self.max_episode_steps)
            .finish()
    }
}

impl<L: Lane> Batch<L> {
    /// `n` copies of `lane` (each pending a reset), truncated after `max_episode_steps`
    /// steps; the instance's constructor checks `n` and the cap.
    pub(crate) fn from_lane(
        model: Arc<L::Model>,
        lane: L,
        n: usize,
        max_episode_steps: u32,
    ) -> Batch<L> {
        Batch {
            episodes: vec![lane; n],
            needs_reset: vec![true; n],
            model,
            max_episode_steps,
        }
    }

    /// Number of lanes.
    pub fn len(&self) -> usize {
        self.episodes.len()
    }

    /// Always false (a batch has at least one lane).
    pub fn is_empty(&self) -> bool {
        self.episodes.is_empty()
    }

    /// The shared model.
    pub fn model(&self) -> &Arc<L::Model> {
        &self.model
    }

    /// The episodes, one per lane.
    pub fn episodes(&self) -> &[L] {
        &self.episodes
    }

    /// The step cap.
    pub fn max_episode_steps(&self) -> u32 {
        self.max_episode_steps
    }

    /// The episodes, to seed them (the instance's `seed` checks the seeds first).
    pub(crate) fn episodes_mut(&mut self) -> &mut [L] {
        &mut self.episodes
    }

    /// Whether every buffer of `buf` holds this batch's lanes.
    pub(crate) fn check(&self, buf: &L::Buffers<'_>) -> Result<()> {
        L::check_buffers(&self.model, self.len(), buf)
    }

    fn reset_one(&mut self, i: usize, buf: &mut L::Buffers<'_>) {
        self.episodes[i].reset(&self.model);
        self.needs_reset[i] = false;
        let rows = L::step_rows(buf);
        rows.rewards[i] = 0.0;
        rows.terminated[i] = false;
        rows.truncated[i] = false;
        rows.detour_penalty[i] = 0.0;
        self.episodes[i].write(&self.model, i, buf);
    }

    /// Reset the lanes where `mask` is true (all if `None`) and write their rows; the
    /// other lanes' rows are left as they were.
    pub fn reset(&mut self, mask: Option<&[bool]>, mut buf: L::Buffers<'_>) -> Result<()> {
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

    /// One batch step once the buffers ([`Batch::check`]) and the actions are checked:
    /// `step(lane, model, i)` moves lane `i` with its action; lanes whose episode ended at
    /// the previous step are reset instead (next-step autoreset).
    #[inline]
    pub(crate) fn step_checked<F>(&mut self, mut buf: L::Buffers<'_>, mut step: F)
    where
        F: FnMut(&mut L, &L::Model, usize) -> LaneStep,
    {
        for i in 0..self.len() {
            if self.needs_reset[i] {
                self.reset_one(i, &mut buf);
                continue;
            }
            let ep = &mut self.episodes[i];
            let out = step(ep, &self.model, i);
            let truncated = !out.reached && ep.steps() >= self.max_episode_steps;
            let rows = L::step_rows(&mut buf);
            rows.rewards[i] = out.reward;
            rows.terminated[i] = out.reached;
            rows.truncated[i] = truncated;
            rows.detour_penalty[i] = out.detour_penalty;
            self.needs_reset[i] = out.reached || truncated;
            self.episodes[i].write(&self.model, i, &mut buf);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A lane that reaches its target after `reach` steps (never when 0) and writes its
    /// step count as its own row.
    #[derive(Debug, Clone)]
    struct Counter {
        steps: u32,
        reach: u32,
    }

    struct Bufs<'a> {
        rows: StepRows<'a>,
        steps: &'a mut [u32],
    }

    impl Lane for Counter {
        type Model = ();
        type Buffers<'a> = Bufs<'a>;

        fn reset(&mut self, _: &()) {
            self.steps = 0;
        }
        fn steps(&self) -> u32 {
            self.steps
        }
        fn check_buffers(_: &(), n: usize, b: &Bufs<'_>) -> Result<()> {
            if b.steps.len() == n && b.rows.rewards.len() == n {
                Ok(())
            } else {
                Err(Error::argument("steps", b.steps.len(), "one per lane"))
            }
        }
        fn step_rows<'b>(b: &'b mut Bufs<'_>) -> StepRows<'b> {
            StepRows {
                rewards: b.rows.rewards,
                terminated: b.rows.terminated,
                truncated: b.rows.truncated,
                detour_penalty: b.rows.detour_penalty,
            }
        }
        fn write(&self, _: &(), i: usize, b: &mut Bufs<'_>) {
            b.steps[i] = self.steps;
        }
    }

    /// Lane 0 reaches its target at its 2nd step, lane 1 never does (cap 3): each ends,
    /// then the next step resets it (reward 0, neither flag) whatever its action.
    #[test]
    fn lanes_end_then_reset_at_the_next_step() {
        let mut batch = Batch::from_lane(Arc::new(()), Counter { steps: 0, reach: 0 }, 2, 3);
        batch.episodes_mut()[0].reach = 2;
        let (mut r, mut te, mut tr, mut dp, mut st) = (
            vec![9.0; 2],
            vec![true; 2],
            vec![true; 2],
            vec![9.0; 2],
            vec![9; 2],
        );
        macro_rules! bufs {
            () => {
                Bufs {
                    rows: StepRows {
                        rewards: &mut r,
                        terminated: &mut te,
                        truncated: &mut tr,
                        detour_penalty: &mut dp,
                    },
                    steps: &mut st,
                }
            };
        }
        batch.reset(Some(&[false, true]), bufs!()).unwrap();
        assert_eq!(
            (r[0], te[0], st[0]),
            (9.0, true, 9),
            "masked-out lane untouched"
        );
        assert_eq!(
            (r[1], te[1], tr[1], dp[1], st[1]),
            (0.0, false, false, 0.0, 0)
        );
        assert!(batch.reset(Some(&[true]), bufs!()).is_err());
        let step = |batch: &mut Batch<Counter>, b: Bufs<'_>| {
            batch.step_checked(b, |lane, _, i| {
                lane.steps += 1;
                LaneStep {
                    reward: -1.0 - i as f64,
                    reached: lane.steps == lane.reach,
                    detour_penalty: -0.5,
                }
            })
        };
        // Lane 0 was never reset: its first step is the autoreset.
        let mut seen = Vec::new();
        for _ in 0..6 {
            step(&mut batch, bufs!());
            seen.push((st.clone(), te.clone(), tr.clone(), r.clone()));
        }
        let want = [
            (
                vec![0, 1],
                vec![false, false],
                vec![false, false],
                vec![0.0, -2.0],
            ),
            (
                vec![1, 2],
                vec![false, false],
                vec![false, false],
                vec![-1.0, -2.0],
            ),
            (
                vec![2, 3],
                vec![true, false],
                vec![false, true],
                vec![-1.0, -2.0],
            ),
            (
                vec![0, 0],
                vec![false, false],
                vec![false, false],
                vec![0.0, 0.0],
            ),
            (
                vec![1, 1],
                vec![false, false],
                vec![false, false],
                vec![-1.0, -2.0],
            ),
            (
                vec![2, 2],
                vec![true, false],
                vec![false, false],
                vec![-1.0, -2.0],
            ),
        ];
        assert_eq!(seen, want);
        assert_eq!(dp, vec![-0.5, -0.5]);
    }
}
