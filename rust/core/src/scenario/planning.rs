//! A scenario's arm and pose planning sections: [`ArmSpec`] (D-H rows in mm and degrees,
//! beta_0 in degrees, joint limits), [`ClearanceModel`], [`PoseSearchMode`] and [`Planning`]
//! (Algorithm 1's parameters).

use serde::{Deserialize, Serialize};

use crate::kinematics::{Arm, DhRow, PAPER_BETA0_DEG, PAPER_DH};

/// The arm: its D-H table, initial pose and optional joint limits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ArmSpec {
    /// Six modified D-H rows (Table 2 by default).
    pub dh: Vec<DhRow>,
    /// beta_0: the initial pose, degrees; its terminal must lie on the start cell.
    pub beta0_deg: [f64; 6],
    /// Optional joint limits, degrees, `[low, high]` per joint (the paper sets none).
    pub joint_limits_deg: Option<[[f64; 2]; 6]>,
}

impl Default for ArmSpec {
    fn default() -> Self {
        ArmSpec {
            dh: PAPER_DH.to_vec(),
            beta0_deg: PAPER_BETA0_DEG,
            joint_limits_deg: None,
        }
    }
}

impl ArmSpec {
    /// The kinematic arm of this spec (assumes a validated spec with six rows).
    pub fn arm(&self) -> Arm {
        let mut rows = PAPER_DH;
        for (dst, src) in rows.iter_mut().zip(&self.dh) {
            *dst = *src;
        }
        Arm::new(rows)
    }

    /// beta_0 in radians.
    pub fn beta0_rad(&self) -> [f64; 6] {
        self.beta0_deg.map(f64::to_radians)
    }
}

/// How the arm's clearance from obstacles is measured.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ClearanceModel {
    /// The paper's eq. 11: distance from each obstacle centre to each segment of the
    /// polyline, compared with `arm_safe_distance` (cells).
    Centres,
    /// Exact geometry (parry3d): links as capsules of radius `link_radius_mm`, obstacles
    /// as cubes of one cell; the gap between them must exceed `margin_mm`.
    Capsules {
        /// Radius of every link capsule, mm.
        link_radius_mm: f64,
        /// Required gap between a capsule and a cube, mm.
        margin_mm: f64,
    },
}

/// How Algorithm 1 searches the candidate poses of a path (`planning.mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PoseSearchMode {
    /// The paper's Algorithm 1 as written: at each path point the first candidate whose
    /// interpolated motion is clear is kept; a dead end stops the pass (no backtracking).
    Paper,
    /// Ours: the same candidate order searched depth first; after a dead end the search goes
    /// back to earlier points' next candidates, within `planning.backtrack_budget`.
    Backtracking,
}

impl PoseSearchMode {
    /// The name used in scenario files and results (`"paper"`, `"backtracking"`).
    pub fn name(self) -> &'static str {
        match self {
            PoseSearchMode::Paper => "paper",
            PoseSearchMode::Backtracking => "backtracking",
        }
    }
}

/// Pose planning parameters (Algorithms 1 and 2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Planning {
    /// t: interpolation steps between two poses.
    pub interpolation_steps: u32,
    /// n_d of the first pass: divisions of a full turn in the orientation grid (eq. 12).
    pub orientation_divisions: u32,
    /// Factor applied to n_d on every re-plan (Algorithm 1: "change n_d"): pass k uses
    /// `orientation_divisions * growth^k`, capped at `orientation_divisions_max`; 1 keeps
    /// n_d fixed.
    pub orientation_divisions_growth: u32,
    /// Cap of n_d over re-plans; with growth > 1 it must be `orientation_divisions *
    /// growth^j` so that every grid contains the one before.
    pub orientation_divisions_max: u32,
    /// How Algorithm 1 searches the candidate poses: the paper's greedy pass or ours with
    /// backtracking.
    pub mode: PoseSearchMode,
    /// Re-plans allowed before Algorithm 2 gives up.
    pub max_replans: u32,
    /// Clearance model of the whole-arm check.
    pub clearance_model: ClearanceModel,
    /// Joint-space motion checks Algorithm 1 may spend backtracking to earlier points' other
    /// poses after a dead end (mode `backtracking` only; our extension).
    pub backtrack_budget: u32,
}

impl Default for Planning {
    fn default() -> Self {
        Planning {
            interpolation_steps: 50,
            orientation_divisions: 8,
            orientation_divisions_growth: 2,
            orientation_divisions_max: 64,
            mode: PoseSearchMode::Paper,
            max_replans: 20,
            clearance_model: ClearanceModel::Centres,
            backtrack_budget: 2000,
        }
    }
}

impl Planning {
    /// n_d of pass `round` (0 = the first pass, k = the k-th re-plan):
    /// `orientation_divisions * orientation_divisions_growth^round`, capped at
    /// `orientation_divisions_max` (never below `orientation_divisions`).
    ///
    /// ```
    /// use sixaxis_core::scenario::Planning;
    /// let p = Planning::default();
    /// let n: Vec<u32> = (0..5).map(|k| p.orientation_divisions_for_round(k)).collect();
    /// assert_eq!(n, [8, 16, 32, 64, 64]);
    /// ```
    pub fn orientation_divisions_for_round(&self, round: u32) -> u32 {
        let mut n = self.orientation_divisions;
        for _ in 0..round {
            match n.checked_mul(self.orientation_divisions_growth) {
                Some(next) if next <= self.orientation_divisions_max && next != n => n = next,
                _ => break,
            }
        }
        n
    }

    /// The motion checks Algorithm 1 may spend backtracking: `backtrack_budget` in mode
    /// `backtracking`, 0 (the paper's greedy pass) in mode `paper`.
    pub fn effective_backtrack_budget(&self) -> u32 {
        match self.mode {
            PoseSearchMode::Paper => 0,
            PoseSearchMode::Backtracking => self.backtrack_budget,
        }
    }
}
