//! One running episode of the joint-space env ([`JointEpisode`]): reset to beta_0, step,
//! the observation.

use nalgebra::Vector3;

use super::{JointModel, MAX_LINKS};
use crate::error::Result;
use crate::kinematics::{ArmPoints, Joints};

/// One step's outcome.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointStep {
    /// Reward, times `reward_scale`.
    pub reward: f64,
    /// The step was refused: the arm stayed.
    pub refused: bool,
    /// The terminal ended within `target_tolerance_mm` of the target: the episode terminates.
    pub reached: bool,
    /// Eq. 9's part of the reward (<= 0, before `reward_scale`; 0 without `assist`).
    pub detour_penalty: f64,
    /// Interpolated poses the check covers, `n` (each proven clear by a motion bound or
    /// measured, docs/JOINT.md "Speed"; 0 when the end pose left the joint limits).
    pub substeps: u32,
}

/// One joint-space episode: the joint angles and what the observation shows of them.
#[derive(Debug, Clone)]
pub struct JointEpisode {
    q: Joints,
    terminal_mm: Vector3<f64>,
    goal: [f32; 3],
    previous_goal: [f32; 3],
    gaps_mm: [f64; MAX_LINKS],
    /// sin q (6) and cos q (6) as the observation has them (computed once per pose).
    sincos: [f32; 12],
    /// The nearest obstacle box of each link (a hint of [`JointModel::check_move`]).
    hints: [u32; MAX_LINKS],
    direction: [f64; 3],
    refused: bool,
    /// The last action, when it was refused (eq. 9's memory).
    last_refused_action: Option<[f64; 6]>,
    steps: u32,
}

impl JointEpisode {
    /// A new episode at beta_0 (already reset).
    pub fn new(model: &JointModel) -> JointEpisode {
        let mut ep = JointEpisode {
            q: model.beta0_rad(),
            terminal_mm: Vector3::zeros(),
            goal: [0.0; 3],
            previous_goal: [0.0; 3],
            gaps_mm: [f64::INFINITY; MAX_LINKS],
            sincos: [0.0; 12],
            hints: [0; MAX_LINKS],
            direction: [0.0; 3],
            refused: false,
            last_refused_action: None,
            steps: 0,
        };
        ep.reset(model);
        ep
    }

    /// Start a new episode at beta_0.
    pub fn reset(&mut self, model: &JointModel) {
        self.q = model.beta0_rad();
        self.refused = false;
        self.last_refused_action = None;
        self.steps = 0;
        self.measure(model);
        self.previous_goal = self.goal;
    }

    /// Recompute the terminal, the goal, the link gaps and the nearest obstacle of `q`.
    fn measure(&mut self, model: &JointModel) {
        let points = model.arm().points_mm(&self.q);
        model.link_gaps_fast(
            &points,
            f64::NEG_INFINITY,
            &mut self.gaps_mm,
            &mut self.hints,
        );
        self.observe(model, &points);
    }

    /// sin and cos of `q`, the terminal, the goal and the nearest obstacle of polyline
    /// `points` (the polyline of `q`; the link gaps are already in `gaps_mm`).
    #[inline]
    fn observe(&mut self, model: &JointModel, points: &ArmPoints) {
        for i in 0..6 {
            let (s, c) = self.q[i].sin_cos();
            self.sincos[i] = s as f32;
            self.sincos[6 + i] = c as f32;
        }
        self.terminal_mm = points[7];
        self.goal = model.goal_of(&self.terminal_mm);
        self.direction = model.nearest_obstacle_direction(&self.terminal_mm).0;
    }

    /// Move the arm by `action` (six numbers in [-1, 1], checked: the error names `action`).
    /// A refused step leaves the joints as they were.
    pub fn step(&mut self, model: &JointModel, action: &[f64; 6]) -> Result<JointStep> {
        JointModel::check_action("action", action)?;
        Ok(self.step_unchecked(model, action))
    }

    /// [`JointEpisode::step`] for an action already checked.
    #[inline]
    pub(super) fn step_unchecked(&mut self, model: &JointModel, action: &[f64; 6]) -> JointStep {
        let o = model.options();
        let dq = action.map(|a| a * model.max_step_rad);
        let to: Joints = std::array::from_fn(|i| self.q[i] + dq[i]);
        let mut gaps = [f64::INFINITY; MAX_LINKS];
        let mut hints = self.hints;
        let (end, substeps) = if model.within_limits(&to) {
            (
                model.check_move(&self.q, &to, &self.gaps_mm, &mut gaps, &mut hints),
                model.substeps(&self.q, &to),
            )
        } else {
            (None, 0)
        };
        let refused = end.is_none();
        let detour_penalty = match (o.assist, self.last_refused_action) {
            (true, Some(_)) if refused => -o.repeat_collision_penalty,
            (true, Some(last)) => {
                -o.reverse_after_collision_penalty * reverse_weight(action, &last)
            }
            _ => 0.0,
        };
        self.previous_goal = self.goal;
        if let Some(points) = end {
            self.q = to;
            self.gaps_mm = gaps;
            self.observe(model, &points);
        }
        // The hints only steer the search order: keep what the check learnt either way.
        self.hints = hints;
        self.refused = refused;
        self.last_refused_action = refused.then_some(*action);
        self.steps += 1;
        let (reward, reached) = model.reward_of(
            &self.previous_goal,
            &self.goal,
            &model.target_goal,
            refused,
            detour_penalty,
        );
        JointStep {
            reward,
            refused,
            reached,
            detour_penalty,
            substeps,
        }
    }

    /// Write the observation into `out` (length [`JointModel::obs_dim`]; see
    /// [`JointModel::obs_layout`]).
    #[inline]
    pub fn write_obs(&self, model: &JointModel, out: &mut [f32]) {
        let l = model.num_links();
        out[..12].copy_from_slice(&self.sincos);
        out[12..15].copy_from_slice(&self.goal);
        out[15..18].copy_from_slice(&model.target_goal);
        let s = model.safe_distance_mm();
        for k in 0..l {
            let g = self.gaps_mm[k];
            out[18 + k] = if g.is_finite() {
                (g / (g + s)) as f32
            } else {
                1.0
            };
        }
        for i in 0..3 {
            out[18 + l + i] = self.direction[i] as f32;
        }
        out[21 + l] = if self.refused { 1.0 } else { 0.0 };
    }

    /// The joint angles, radians.
    #[inline]
    pub fn joints_rad(&self) -> Joints {
        self.q
    }

    /// The terminal's position, mm.
    #[inline]
    pub fn terminal_mm(&self) -> Vector3<f64> {
        self.terminal_mm
    }

    /// The achieved goal (terminal / reach, float32, as in the observation).
    #[inline]
    pub fn goal(&self) -> [f32; 3] {
        self.goal
    }

    /// The achieved goal before the last step (equal to [`JointEpisode::goal`] after a
    /// reset or a refused step).
    #[inline]
    pub fn previous_goal(&self) -> [f32; 3] {
        self.previous_goal
    }

    /// Distance from the terminal to the target, mm (between the float32 goals).
    #[inline]
    pub fn distance_to_target_mm(&self, model: &JointModel) -> f64 {
        model.goal_distance_mm(&self.goal, &model.target_goal)
    }

    /// Each link's exact capsule gap, mm ([`JointModel::links`] order).
    #[inline]
    pub fn link_gaps_mm<'a>(&'a self, model: &JointModel) -> &'a [f64] {
        &self.gaps_mm[..model.num_links()]
    }

    /// The smallest link gap, mm (`INFINITY` without obstacles).
    #[inline]
    pub fn clearance_mm(&self, model: &JointModel) -> f64 {
        self.link_gaps_mm(model)
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }

    /// Whether the last step was refused.
    #[inline]
    pub fn refused(&self) -> bool {
        self.refused
    }

    /// Steps since the reset.
    #[inline]
    pub fn steps(&self) -> u32 {
        self.steps
    }
}

/// Eq. 9's "opposite action" in joint space: `max(0, -cos)` of the angle between the action
/// and the refused one (1 for the exact reverse, 0 for a zero action).
#[inline]
fn reverse_weight(a: &[f64; 6], refused: &[f64; 6]) -> f64 {
    let dot: f64 = (0..6).map(|i| a[i] * refused[i]).sum();
    let na: f64 = a.iter().map(|v| v * v).sum::<f64>().sqrt();
    let nb: f64 = refused.iter().map(|v| v * v).sum::<f64>().sqrt();
    if na == 0.0 || nb == 0.0 {
        0.0
    } else {
        (-dot / (na * nb)).clamp(0.0, 1.0)
    }
}
