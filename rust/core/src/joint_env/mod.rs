//! The joint-space environment (`SixAxisAvoidJoint-v0`): the whole arm moves in joint space
//! with continuous actions, every step checked by the exact capsule clearance
//! ([`crate::clearance`]), the paper's reward shaping carried over (docs/JOINT.md).
//!
//! Entry points:
//! - [`JointOptions`] / [`JOINT_ENV_OPTIONS`] — the env's keywords, declared once (key,
//!   domain, unit, doc); [`JointOptions::from_options`] reads them from an
//!   [`Options`](crate::options::Options) map.
//! - [`JointModel::new`] — what every copy of the env shares: the arm, the clearance of the
//!   scenario's obstacles (boxes in mm), joint limits (rad), the target (mm), the workspace.
//! - [`JointEpisode`] — one running episode: [`JointEpisode::reset`] (to beta_0, rad),
//!   [`JointEpisode::step`] (an action in [-1, 1]^6).
//! - [`JointBatch`] — N episodes with Gymnasium 1.x next-step autoreset and a step cap,
//!   stepped together into caller-provided buffers ([`JointBuffers`]).
//! - [`JointModel::goal_rewards`] — the rewards of relabelled goals (HER), the step's own
//!   arithmetic.
//!
//! # Semantics (units in every line)
//!
//! - **State**: six joint angles q, radians, within the joint limits (the scenario's
//!   `arm.joint_limits_deg`, degrees; without them every joint in [-180°, 180°]).
//! - **Action**: six numbers in [-1, 1]; joint i moves by `a_i * max_joint_step_deg` degrees.
//! - **Refusal** (the paper's "move back", in joint space): a step is refused when the new
//!   angles leave the joint limits, or when any of the interpolated poses
//!   `q + (k / n) Δq`, `k = 1..=n`, brings a link capsule (segment, radius `link_radius_mm`)
//!   within `safe_distance_mm` of an obstacle box (gap <= safe distance, mm). The arm stays.
//! - **Sub-steps** `n = max(1, ceil(Σ_i |Δq_i| L_i / (substep_fraction · safe_distance_mm)))`,
//!   `Δq` in rad, `L_i` (mm) the length of the arm's polyline distal to joint i's origin, an
//!   upper bound of the distance from joint i's axis to any point it moves. The path of any
//!   arm point over one step is at most `Σ |Δq_i| L_i` mm long, so between two checked poses
//!   it moves at most `substep_fraction · safe_distance_mm` mm: every pose of the continuous
//!   motion keeps a gap >= `(1 - substep_fraction / 2) · safe_distance_mm` > 0, and no link
//!   passes through a box. The env's check (`JointModel::check_move`) gives the answer of
//!   measuring all n poses exactly, but measures a link at a pose only when no motion bound
//!   proves it clear, with closed-form segment-box distances (docs/JOINT.md, "Speed").
//! - **Observation** ([`JointModel::obs_dim`] float32, [`ObsLayout`]): sin q (6), cos q (6),
//!   terminal position / reach (3), target / reach (3) (reach: the polyline's length, mm, so
//!   both lie in [-1, 1]), per link the gap g (mm) as `g / (g + safe_distance_mm)` in [0, 1]
//!   (1 without obstacles), the unit vector from the terminal to the nearest point of the
//!   nearest obstacle box (3; zeros without obstacles), 1.0 if the last step was refused (1).
//! - **Reward** (times `reward_scale`): eq. 5: `+target_reward` when the step ends within
//!   `target_tolerance_mm` of the target, `-collision_penalty` when refused, else
//!   `-step_penalty`; eq. 10 (`assist`): `+progress_reward · (d_prev - d)` with d the
//!   terminal-target distance, mm; eq. 9 (`assist`), after a refused step: another refusal
//!   costs `-repeat_collision_penalty`, an accepted step `-reverse_after_collision_penalty ·
//!   max(0, -cos(a, a_refused))` (a step back along the refused action).
//! - **Episode end**: terminated when d <= `target_tolerance_mm`; a [`JointBatch`] also
//!   truncates after `max_episode_steps` steps; the step after either resets that lane
//!   (reward 0, neither flag).
//! - Distances of the reward and of termination are measured between the float32 goals of
//!   the observation (normalised positions times the reach, mm), so that
//!   [`JointModel::goal_rewards`] gives a step's own reward to the bit.
//!
//! ```
//! use sixaxis_core::joint_env::{JointEpisode, JointModel, JointOptions};
//! use sixaxis_core::Scenario;
//! let s = Scenario::builtin("paper_simple").unwrap();
//! let model = JointModel::new(&s, JointOptions::default()).unwrap();
//! let mut ep = JointEpisode::new(&model);
//! ep.reset(&model);
//! let out = ep.step(&model, &[0.5, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
//! assert!(!out.refused); // a 1° turn of the base is clear at beta_0
//! assert!((ep.joints_rad()[0] - (s.arm.beta0_deg[0] + 1.0).to_radians()).abs() < 1e-12);
//! let mut obs = vec![0f32; model.obs_dim()];
//! ep.write_obs(&model, &mut obs);
//! assert!(obs.iter().all(|v| (-1.0..=1.0).contains(v)));
//! ```
//!
//! The module's parts, one concern each: the model (its construction, accessors and
//! observation layout) here; the keywords ([`JOINT_ENV_OPTIONS`], [`JointOptions`]) in
//! `joint_env/options.rs`; the clearance check of a step's motion (sub-steps, motion
//! bounds, closed-form link gaps) in `joint_env/motion.rs`; the reward (eqs. 5, 9, 10 and
//! the HER relabelling) in `joint_env/reward.rs`; one episode in `joint_env/episode.rs`; the
//! batch in `joint_env/batch.rs` (the joint env's instance of [`crate::batch::Batch`]).
//! Everything public is re-exported here.

use nalgebra::Vector3;

use crate::clearance::Clearance;
use crate::error::{Error, Result};
use crate::kinematics::{Arm, Joints};
use crate::scenario::{ClearanceModel, ObstacleBox, Scenario};

mod batch;
mod episode;
mod motion;
mod options;
mod reward;

pub use batch::{JointBatch, JointBuffers};
pub use episode::{JointEpisode, JointStep};
use motion::{box_lanes_of, BOX_LANES};
pub use options::{
    joint_option_default, joint_option_info, JointOptions, DEFAULT_JOINT_LIMIT_DEG,
    JOINT_ENV_OPTIONS, JOINT_NULLABLE,
};

/// Where each field sits in the observation (ranges of indices).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ObsLayout {
    /// sin of the six joints.
    pub sin: std::ops::Range<usize>,
    /// cos of the six joints.
    pub cos: std::ops::Range<usize>,
    /// Terminal position / reach (the achieved goal).
    pub terminal: std::ops::Range<usize>,
    /// Target / reach (the desired goal).
    pub target: std::ops::Range<usize>,
    /// Per link `g / (g + safe_distance_mm)`.
    pub clearance: std::ops::Range<usize>,
    /// Unit vector terminal -> nearest obstacle point.
    pub direction: std::ops::Range<usize>,
    /// 1.0 if the last step was refused.
    pub refused: usize,
}

/// What every copy of the joint env shares.
#[derive(Debug, Clone)]
pub struct JointModel {
    arm: Arm,
    clearance: Clearance,
    opts: JointOptions,
    link_radius_mm: f64,
    safe_distance_mm: f64,
    /// Polyline segments of non-zero length: index k of points k -> k + 1.
    links: Vec<usize>,
    /// `L_i`: polyline length distal to joint i's origin, mm.
    lever_mm: [f64; 6],
    /// `ℓ_{i,k}` per link (in `links` order): polyline length from joint i's origin to the
    /// far end of link k, mm (0 when joint i does not move link k): docs/JOINT.md, "Speed".
    link_lever_mm: [[f64; 6]; MAX_LINKS],
    /// Polyline length, mm (the workspace radius).
    reach_mm: f64,
    limits_rad: [[f64; 2]; 6],
    beta0: Joints,
    target_mm: Vector3<f64>,
    /// The target as the observation's float32 goal.
    target_goal: [f32; 3],
    /// Every obstacle as a box (min, max), mm: the cubes of the cells, then the boxes.
    boxes: Vec<([f64; 3], [f64; 3])>,
    /// The same boxes as structure-of-arrays in chunks of [`BOX_LANES`] (lo x, y, z, hi x,
    /// y, z), padded with empty far boxes (never measured: see `link_gap_fast`), so that
    /// the lower-bound loop vectorises.
    box_lanes: Vec<[[f64; BOX_LANES]; 6]>,
    max_step_rad: f64,
}

/// Index of the polyline point that is joint i's origin (base, O1, O2, O3, Aux, O4, O5, O6).
const JOINT_POINT: [usize; 6] = [1, 2, 3, 5, 6, 7];

/// Most links a polyline has (7 segments).
pub(crate) const MAX_LINKS: usize = 7;

impl JointModel {
    /// The model of a scenario with these options. Errors: an option outside its domain; a
    /// joint limit with low >= high; beta_0 outside the limits or not clear; a target beyond
    /// the arm's reach.
    pub fn new(scenario: &Scenario, opts: JointOptions) -> Result<JointModel> {
        opts.check()?;
        let cell_mm = scenario.cell_mm;
        let (scen_r, scen_s) = match scenario.planning.clearance_model {
            ClearanceModel::Capsules {
                link_radius_mm,
                margin_mm,
            } => (link_radius_mm, margin_mm),
            ClearanceModel::Centres => (0.0, scenario.arm_safe_distance_in_mm() - 0.5 * cell_mm),
        };
        let link_radius_mm = opts.link_radius_mm.unwrap_or(scen_r);
        let safe_distance_mm = match opts.safe_distance_mm {
            Some(s) => s,
            None if scen_s > 0.0 && scen_s.is_finite() => scen_s,
            None => {
                return Err(Error::argument(
                    "safe_distance_mm",
                    "None",
                    format!(
                        "the scenario gives no positive safe distance for the joint env ({scen_s} mm); pass safe_distance_mm"
                    ),
                ))
            }
        };
        let arm = scenario.arm();
        let limits_deg = scenario
            .arm
            .joint_limits_deg
            .unwrap_or([DEFAULT_JOINT_LIMIT_DEG; 6]);
        for (i, l) in limits_deg.iter().enumerate() {
            if !(l[0].is_finite() && l[1].is_finite() && l[0] < l[1]) {
                return Err(Error::invalid(
                    format!("arm.joint_limits_deg[{i}]"),
                    format!("[{}, {}]", l[0], l[1]),
                    "must be finite with low < high",
                ));
            }
        }
        let limits_rad = limits_deg.map(|l| l.map(f64::to_radians));
        let beta0 = scenario.arm.beta0_rad();
        let clearance = Clearance::new(
            &scenario.obstacles,
            cell_mm,
            ClearanceModel::Capsules {
                link_radius_mm,
                margin_mm: safe_distance_mm,
            },
            0.0,
        )
        .with_boxes(&scenario.obstacle_boxes_mm);
        let p0 = arm.points_mm(&beta0);
        let seg_len: Vec<f64> = (0..7).map(|k| (p0[k + 1] - p0[k]).norm()).collect();
        let links: Vec<usize> = (0..7).filter(|&k| seg_len[k] > 0.0).collect();
        let reach_mm: f64 = seg_len.iter().sum();
        let lever_mm = JOINT_POINT.map(|j| seg_len[j..].iter().sum());
        let mut link_lever_mm = [[0.0; 6]; MAX_LINKS];
        for (l, &k) in links.iter().enumerate() {
            link_lever_mm[l] = JOINT_POINT.map(|j| {
                if k >= j {
                    seg_len[j..=k].iter().sum()
                } else {
                    0.0
                }
            });
        }
        let mut boxes: Vec<([f64; 3], [f64; 3])> = scenario
            .obstacles
            .iter()
            .map(|&c| {
                let b = ObstacleBox::paper_cube(c, cell_mm);
                (b.min_mm, b.max_mm)
            })
            .collect();
        boxes.extend(
            scenario
                .obstacle_boxes_mm
                .iter()
                .map(|b| (b.min_mm, b.max_mm)),
        );
        let box_lanes = box_lanes_of(&boxes);
        let target_mm = scenario.cell_centre_mm(scenario.target);
        if target_mm.norm() > reach_mm {
            return Err(Error::invalid(
                "target",
                format!(
                    "[{}, {}, {}]",
                    scenario.target[0], scenario.target[1], scenario.target[2]
                ),
                format!(
                    "its centre is {:.1} mm from the base, beyond the arm's reach ({reach_mm:.1} mm)",
                    target_mm.norm()
                ),
            ));
        }
        let mut model = JointModel {
            arm,
            clearance,
            opts,
            link_radius_mm,
            safe_distance_mm,
            links,
            lever_mm,
            link_lever_mm,
            reach_mm,
            limits_rad,
            beta0,
            target_mm,
            target_goal: [0.0; 3],
            boxes,
            box_lanes,
            max_step_rad: opts.max_joint_step_deg.to_radians(),
        };
        model.target_goal = model.goal_of(&target_mm);
        if let Some(i) = (0..6).find(|&i| !model.within_limit(i, beta0[i])) {
            return Err(Error::invalid(
                format!("arm.beta0_deg[{i}]"),
                scenario.arm.beta0_deg[i],
                format!(
                    "outside the joint limits [{}, {}] deg",
                    limits_deg[i][0], limits_deg[i][1]
                ),
            ));
        }
        if !model.pose_is_clear(&beta0) {
            let gap = model.clearance.capsules_gap_mm(&p0, link_radius_mm);
            return Err(Error::invalid(
                "arm.beta0_deg",
                format!("{:?}", scenario.arm.beta0_deg),
                format!(
                    "the start pose is not clear: its capsule gap {gap:.1} mm is <= the safe distance {safe_distance_mm} mm"
                ),
            ));
        }
        Ok(model)
    }

    /// The options.
    pub fn options(&self) -> &JointOptions {
        &self.opts
    }

    /// The arm.
    pub fn arm(&self) -> &Arm {
        &self.arm
    }

    /// The clearance (capsules model) the steps are checked with.
    pub fn clearance(&self) -> &Clearance {
        &self.clearance
    }

    /// Link capsule radius in use, mm.
    pub fn link_radius_mm(&self) -> f64 {
        self.link_radius_mm
    }

    /// Safe distance in use, mm.
    pub fn safe_distance_mm(&self) -> f64 {
        self.safe_distance_mm
    }

    /// Number of links (polyline segments of non-zero length; one clearance each).
    pub fn num_links(&self) -> usize {
        self.links.len()
    }

    /// The polyline segments that are links: `k` stands for points `k -> k + 1`.
    pub fn links(&self) -> &[usize] {
        &self.links
    }

    /// The arm's reach (its polyline's length), mm: the workspace's radius.
    pub fn reach_mm(&self) -> f64 {
        self.reach_mm
    }

    /// `L_i` of the sub-step bound, mm.
    pub fn lever_mm(&self) -> [f64; 6] {
        self.lever_mm
    }

    /// Joint limits, radians, `[low, high]` per joint.
    pub fn limits_rad(&self) -> [[f64; 2]; 6] {
        self.limits_rad
    }

    /// beta_0, radians.
    pub fn beta0_rad(&self) -> Joints {
        self.beta0
    }

    /// The target, mm.
    pub fn target_mm(&self) -> Vector3<f64> {
        self.target_mm
    }

    /// Length of the observation: 22 + [`JointModel::num_links`].
    pub fn obs_dim(&self) -> usize {
        22 + self.links.len()
    }

    /// Where each field sits in the observation.
    pub fn obs_layout(&self) -> ObsLayout {
        let l = self.links.len();
        ObsLayout {
            sin: 0..6,
            cos: 6..12,
            terminal: 12..15,
            target: 15..18,
            clearance: 18..18 + l,
            direction: 18 + l..21 + l,
            refused: 21 + l,
        }
    }

    /// A position (mm) as the observation's float32 goal: `p / reach`.
    #[inline]
    pub fn goal_of(&self, p: &Vector3<f64>) -> [f32; 3] {
        [0, 1, 2].map(|i| (p[i] / self.reach_mm) as f32)
    }

    /// Distance between two goals, mm (`|a - b| * reach`, in f64 from the f32 goals).
    #[inline]
    pub fn goal_distance_mm(&self, a: &[f32; 3], b: &[f32; 3]) -> f64 {
        let d2: f64 = (0..3)
            .map(|i| {
                let d = a[i] as f64 - b[i] as f64;
                d * d
            })
            .sum();
        d2.sqrt() * self.reach_mm
    }

    #[inline]
    fn within_limit(&self, i: usize, q: f64) -> bool {
        q >= self.limits_rad[i][0] && q <= self.limits_rad[i][1]
    }

    /// Whether every joint of `q` (rad) is within its limits (inclusive).
    pub fn within_limits(&self, q: &Joints) -> bool {
        (0..6).all(|i| self.within_limit(i, q[i]))
    }

    /// Whether pose `q` (rad) keeps every link capsule farther than the safe distance from
    /// every obstacle (gap > safe distance, mm).
    #[inline]
    pub fn pose_is_clear(&self, q: &Joints) -> bool {
        self.clearance.pose_is_clear(&self.arm.points_mm(q))
    }

    /// Unit vector from `p` (mm) to the nearest point of the nearest obstacle box, and that
    /// distance (mm); zeros and `INFINITY` without obstacles (zeros also inside a box).
    pub fn nearest_obstacle_direction(&self, p: &Vector3<f64>) -> ([f64; 3], f64) {
        let mut best = f64::INFINITY;
        let mut dir = [0.0; 3];
        for (lo, hi) in &self.boxes {
            let d: [f64; 3] = std::array::from_fn(|i| p[i].clamp(lo[i], hi[i]) - p[i]);
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if n < best {
                best = n;
                dir = if n > 0.0 { d.map(|v| v / n) } else { [0.0; 3] };
            }
        }
        (dir, best)
    }

    /// Check an action: six finite numbers in [-1, 1]; the error names `name` and the value.
    pub fn check_action(name: &str, a: &[f64]) -> Result<()> {
        if a.len() != 6 {
            return Err(Error::argument(
                name,
                format!("{} values", a.len()),
                "an action is six numbers in [-1, 1]",
            ));
        }
        if let Some((i, v)) = a
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && (-1.0..=1.0).contains(*v)))
        {
            return Err(Error::argument(
                name,
                format!("{v} at joint {i}"),
                "each component must be a number in [-1, 1]",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
