//! Pose planning (the paper's Algorithm 1): joint poses for a terminal path, so that the whole
//! arm keeps its clearance from the obstacles, in every pose and on the way between poses.
//!
//! Entry points:
//! - [`PosePlanner::from_scenario`] — the scenario's arm, obstacles, clearance model,
//!   orientation grid (eq. 12), interpolation steps `t`, joint limits and search mode.
//! - [`PosePlanner::for_round`] — the same for pass k of Algorithm 2: the orientation grid
//!   of n_d = `planning.orientation_divisions_for_round(k)` (the paper's "change n_d").
//! - [`PosePlanner::plan_poses`] — Algorithm 1 over a path of cells: [`PosePlan::Complete`]
//!   or [`PosePlan::Blocked`] at the first cell no pose reaches safely (Algorithm 2 then
//!   makes that cell an obstacle and learns again; that loop lives elsewhere).
//! - [`PosePlanner::best_clearance_at`] / [`PosePlanner::cell_reachable`] — what the best
//!   static pose at one cell can do.
//!
//! # Algorithm 1, as implemented (deterministic)
//! The start cell `path[0]` gets `beta0` (taken as given) and the orientation of
//! `FK(beta0)`, reported as rpy degrees; the start pose itself is not checked. The
//! *current orientation* is the grid orientation nearest to it (smallest rotation angle,
//! ties by grid order): for the paper's `beta0` that is the identity, within 1e-4.
//! For every later path cell, in order:
//! 1. Orientations: the current one first, then every other grid orientation by growing
//!    rotation angle from it (the angle of `R_curᵀ R_cand`, rounded to 1e-9 rad; ties by
//!    grid order).
//! 2. For each orientation, the IK solutions (eq. 13) sorted by joint distance from the
//!    current pose: the Euclidean norm of the per-joint differences, each wrapped to
//!    (-pi, pi]; ties by IK order.
//! 3. A solution is skipped if it breaks the scenario's joint limits (if set); else if its
//!    own pose is not clear (cheap rejection); else if some interpolation step
//!    `k = 1..t-1` of the joint-space move from the current pose is not clear or breaks the
//!    joint limits. The first survivor is recorded and becomes the current pose and
//!    orientation.
//! 4. If no orientation has a survivor, the plan is [`PosePlan::Blocked`] at that index
//!    (mode `paper`, the paper's Algorithm 1); mode `backtracking` first goes back to earlier
//!    points' next candidates (see [`PosePlanner::plan_poses`]).
//!
//! Candidates are generated lazily, one orientation's IK at a time, so a fine grid
//! (n_d = 32 or 64: 15424 or 127104 orientations) costs only what the search visits.
//!
//! Joint limits (`arm.joint_limits_deg`, `[low, high]` degrees per joint): an angle in
//! (-pi, pi] is within them when it, or it ± 360°, lies in `[low, high]`. Checking every
//! interpolation step also catches a move whose shortest way leaves the range.
//!
//! ```
//! use sixaxis_core::planner::{PosePlan, PosePlanner};
//! use sixaxis_core::scenario::Scenario;
//! let s = Scenario::builtin("paper_simple").unwrap();
//! let planner = PosePlanner::from_scenario(&s);
//! let path = [s.start, [0, -2, 3], [0, -1, 3]];
//! match planner.plan_poses(&path, &s.arm.beta0_rad()) {
//!     PosePlan::Complete(poses) => assert_eq!(poses.len(), path.len()),
//!     PosePlan::Blocked { index, cell, .. } => panic!("blocked at {index}: {cell:?}"),
//! }
//! // No pose reaches a cell 2 m above the base.
//! assert!(!planner.cell_reachable([0, 0, 20]));
//! ```

use nalgebra::{Matrix3, Vector3};
use serde::Serialize;

use crate::clearance::{interpolate, Clearance};
use crate::kinematics::{orientation_grid, wrap_angle, Arm, Joints, Orientation, TerminalPose};
use crate::scenario::{Cell, Scenario};

/// One planned point: the cell, the joint pose that reaches it and the terminal orientation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PosePoint {
    /// The path cell (cells).
    pub cell: Cell,
    /// Joint angles, radians.
    pub joints_rad: Joints,
    /// Terminal orientation (rt_x, rt_y, rt_z), degrees, `R = Rz Ry Rx`: a grid orientation,
    /// except at the start where it is that of `FK(beta0)`.
    pub orientation_rpy_deg: [f64; 3],
}

/// The outcome of Algorithm 1 over one path.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum PosePlan {
    /// One pose per path cell, start included.
    Complete(Vec<PosePoint>),
    /// No safe pose reaches `path[index]` (= `cell`) from the pose of `path[index - 1]`;
    /// `reached` holds the poses of `path[..index]`.
    Blocked {
        /// Poses planned before the blocked cell, start included.
        reached: Vec<PosePoint>,
        /// Index of the blocked cell in the path (>= 1).
        index: usize,
        /// The blocked cell.
        cell: Cell,
    },
}

impl PosePlan {
    /// Whether every path cell got a pose.
    pub fn is_complete(&self) -> bool {
        matches!(self, PosePlan::Complete(_))
    }

    /// The poses planned (all of them, or those before the blocked cell).
    pub fn poses(&self) -> &[PosePoint] {
        match self {
            PosePlan::Complete(p) => p,
            PosePlan::Blocked { reached, .. } => reached,
        }
    }
}

/// The `steps + 1` poses of the joint-space move from `from` to `to` (radians) at which the
/// planner checks a motion: `interpolate(from, to, k / steps)` for `k = 0..=steps` (each
/// joint along its shortest angular difference, [`interpolate`]). `steps = 0` counts as 1.
pub fn motion_steps(from: &Joints, to: &Joints, steps: u32) -> Vec<Joints> {
    let n = steps.max(1);
    (0..=n)
        .map(|k| interpolate(from, to, k as f64 / n as f64))
        .collect()
}

/// How close a planned motion comes to the obstacles, over every interpolation step
/// (`k = 0..=t` of every move, so every pose included), measured two ways.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MotionClearance {
    /// Eq. 11: smallest distance from an obstacle *centre* to the arm's polyline, cells.
    pub min_centre_clearance_cells: f64,
    /// Exact geometry (parry3d): smallest distance from the arm's polyline (its centre line)
    /// to an obstacle *cube* (edge `cell_mm`, on its cell), mm; 0 on contact.
    pub min_cube_distance_mm: f64,
}

/// Rotation angle (radians, in [0, pi]) between two rotations: the angle of `aᵀ b`.
/// Uses `atan2(|vee(M - Mᵀ)|, tr M - 1)`, accurate near 0 and near pi alike.
pub fn rotation_angle(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    let m = a.transpose() * b;
    let v = Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    );
    v.norm().atan2(m.trace() - 1.0)
}

/// (rt_x, rt_y, rt_z) in degrees with `R = Rz(rt_z) Ry(rt_y) Rx(rt_x)`
/// (inverse of [`rotation_from_rpy_deg`](crate::kinematics::rotation_from_rpy_deg);
/// rt_y in [-90, 90]; at rt_y = ±90 the split puts everything in rt_z, rt_x = 0).
pub fn rpy_deg_from_rotation(r: &Matrix3<f64>) -> [f64; 3] {
    let sy = -r[(2, 0)];
    let cy = r[(0, 0)].hypot(r[(1, 0)]);
    let ry = sy.atan2(cy);
    let (rx, rz) = if cy > 1e-12 {
        (r[(2, 1)].atan2(r[(2, 2)]), r[(1, 0)].atan2(r[(0, 0)]))
    } else {
        // Gimbal lock: only rz - sy * rx is fixed; take rx = 0.
        (0.0, (-r[(0, 1)]).atan2(r[(1, 1)]))
    };
    [rx.to_degrees(), ry.to_degrees(), rz.to_degrees()]
}

/// Joint distance (radians): Euclidean norm of the per-joint differences, each wrapped to
/// (-pi, pi].
pub fn joint_distance(a: &Joints, b: &Joints) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| {
            let d = wrap_angle(y - x);
            d * d
        })
        .sum::<f64>()
        .sqrt()
}

/// Algorithm 1: pose planning over a terminal path.
#[derive(Debug, Clone)]
pub struct PosePlanner {
    arm: Arm,
    clearance: Clearance,
    grid: Vec<Orientation>,
    /// n_d of `grid`.
    divisions: u32,
    steps: u32,
    cell_mm: f64,
    /// Joint limits, radians, `[low, high]` per joint.
    limits_rad: Option<[[f64; 2]; 6]>,
    /// Motion checks allowed for backtracking after a dead end (0: the paper's greedy pass).
    backtrack_budget: u32,
}

impl PosePlanner {
    /// The planner of a scenario's first pass: its arm, [`Clearance::from_scenario`], the
    /// orientation grid of `planning.orientation_divisions`, `planning.interpolation_steps`,
    /// `arm.joint_limits_deg` and `planning.mode` (with its backtracking budget).
    pub fn from_scenario(s: &Scenario) -> PosePlanner {
        PosePlanner::for_round(s, 0)
    }

    /// The planner of pass `round` of Algorithm 2 (0 = first pass, k = k-th re-plan): as
    /// [`PosePlanner::from_scenario`], with the orientation grid of
    /// n_d = [`Planning::orientation_divisions_for_round`](crate::scenario::Planning::orientation_divisions_for_round).
    pub fn for_round(s: &Scenario, round: u32) -> PosePlanner {
        PosePlanner::new(
            s.arm(),
            Clearance::from_scenario(s),
            s.planning.orientation_divisions_for_round(round),
            s.planning.interpolation_steps,
            s.cell_mm,
            s.arm.joint_limits_deg,
        )
        .with_backtrack_budget(s.planning.effective_backtrack_budget())
    }

    /// A planner from its parts: arm, clearance, orientation grid divisions n_d (eq. 12),
    /// interpolation steps t, cell edge (mm) and optional joint limits (degrees).
    pub fn new(
        arm: Arm,
        clearance: Clearance,
        orientation_divisions: u32,
        interpolation_steps: u32,
        cell_mm: f64,
        joint_limits_deg: Option<[[f64; 2]; 6]>,
    ) -> PosePlanner {
        PosePlanner {
            arm,
            clearance,
            grid: orientation_grid(orientation_divisions),
            divisions: orientation_divisions.max(1),
            steps: interpolation_steps.max(1),
            cell_mm,
            limits_rad: joint_limits_deg
                .map(|l| l.map(|[lo, hi]| [lo.to_radians(), hi.to_radians()])),
            backtrack_budget: 0,
        }
    }

    /// The same planner with a backtracking budget: the number of joint-space motion checks
    /// [`PosePlanner::plan_poses`] may spend revisiting earlier points' poses after a dead
    /// end. 0 gives the paper's greedy Algorithm 1.
    pub fn with_backtrack_budget(mut self, motion_checks: u32) -> PosePlanner {
        self.backtrack_budget = motion_checks;
        self
    }

    /// The same planner with another clearance (e.g. with obstacles added by a re-plan).
    pub fn with_clearance(mut self, clearance: Clearance) -> PosePlanner {
        self.clearance = clearance;
        self
    }

    /// The arm.
    pub fn arm(&self) -> &Arm {
        &self.arm
    }

    /// The clearance check.
    pub fn clearance(&self) -> &Clearance {
        &self.clearance
    }

    /// The orientation grid, in grid order.
    pub fn orientations(&self) -> &[Orientation] {
        &self.grid
    }

    /// n_d of the orientation grid (eq. 12).
    pub fn orientation_divisions(&self) -> u32 {
        self.divisions
    }

    /// Interpolation steps t between two poses.
    pub fn interpolation_steps(&self) -> u32 {
        self.steps
    }

    /// Whether `q` (radians) is within the joint limits (always, without limits).
    pub fn within_limits(&self, q: &Joints) -> bool {
        use std::f64::consts::TAU;
        let Some(lims) = &self.limits_rad else {
            return true;
        };
        q.iter()
            .zip(lims)
            .all(|(&a, &[lo, hi])| [a, a - TAU, a + TAU].iter().any(|&x| x >= lo && x <= hi))
    }

    /// Centre of a cell, mm.
    fn centre_mm(&self, c: Cell) -> Vector3<f64> {
        crate::scenario::cell_centre_mm(c, self.cell_mm)
    }

    /// Index of the grid orientation nearest to `r` (ties by grid order).
    pub fn nearest_orientation(&self, r: &Matrix3<f64>) -> usize {
        let mut best = (f64::INFINITY, 0);
        for (i, o) in self.grid.iter().enumerate() {
            let a = rotation_angle(r, &o.rotation);
            if a < best.0 {
                best = (a, i);
            }
        }
        best.1
    }

    /// Grid indices by growing rotation angle from grid orientation `from` (itself first),
    /// angles rounded to 1e-9 rad, ties by grid order.
    pub fn orientation_order(&self, from: usize) -> Vec<usize> {
        let r = &self.grid[from].rotation;
        let mut keyed: Vec<(i64, usize)> = self
            .grid
            .iter()
            .enumerate()
            .map(|(i, o)| {
                let a = if i == from {
                    0.0
                } else {
                    rotation_angle(r, &o.rotation)
                };
                ((a * 1e9).round() as i64, i)
            })
            .collect();
        keyed.sort_unstable();
        keyed.into_iter().map(|(_, i)| i).collect()
    }

    /// Whether the move `from` -> `to` passes at every step `k = 1..t-1` (clearance and joint
    /// limits); the end pose is assumed checked already.
    fn motion_ok(&self, from: &Joints, to: &Joints) -> bool {
        let n = self.steps;
        (1..n).all(|k| {
            let q = interpolate(from, to, k as f64 / n as f64);
            self.within_limits(&q) && self.clearance.pose_is_clear(&self.arm.points_mm(&q))
        })
    }

    /// The candidates of Algorithm 1 at `cell` from pose `cur` with grid orientation
    /// `cur_orient`, in the order they are tried: orientations by growing angle from the
    /// current one, then IK solutions by joint distance from `cur`. Each is
    /// `(orientation index, solution index, pose)`; an orientation's IK is solved only when
    /// the search reaches it.
    fn candidates<'a>(
        &'a self,
        cur: &'a Joints,
        cur_orient: usize,
        cell: Cell,
    ) -> impl Iterator<Item = (usize, usize, Joints)> + 'a {
        let position_mm = self.centre_mm(cell);
        self.orientation_order(cur_orient)
            .into_iter()
            .flat_map(move |o| {
                let sols = self.arm.ik(&TerminalPose {
                    position_mm,
                    rotation: self.grid[o].rotation,
                });
                let mut order: Vec<(f64, usize)> = sols
                    .iter()
                    .enumerate()
                    .map(|(i, q)| (joint_distance(cur, q), i))
                    .collect();
                order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                order
                    .into_iter()
                    .map(move |(_, i)| (o, i, sols[i]))
                    .collect::<Vec<_>>()
            })
    }

    /// Depth-first search of Algorithm 1 from path index `i`: the first candidate whose
    /// motion from `cur` is clear is taken, as in the paper; only when the rest of the path
    /// then fails are later candidates tried (within the budget). `out` holds the poses so far.
    fn descend(
        &self,
        path: &[Cell],
        i: usize,
        cur: &Joints,
        cur_orient: usize,
        st: &mut Search,
        out: &mut Vec<PosePoint>,
    ) -> bool {
        let Some(&cell) = path.get(i) else {
            return true;
        };
        if i > st.deepest {
            st.deepest = i;
            st.deepest_reached = out.clone();
        }
        for (o, k, q) in self.candidates(cur, cur_orient, cell) {
            if st.dead.contains(&(i, o, k))
                || !self.within_limits(&q)
                || !self.clearance.pose_is_clear(&self.arm.points_mm(&q))
            {
                continue;
            }
            if st.backtracking {
                if st.checks >= self.backtrack_budget {
                    return false;
                }
                st.checks += 1;
            }
            if !self.motion_ok(cur, &q) {
                continue;
            }
            out.push(PosePoint {
                cell,
                joints_rad: q,
                orientation_rpy_deg: self.grid[o].rpy_deg,
            });
            if self.descend(path, i + 1, &q, o, st, out) {
                return true;
            }
            out.pop();
            // Whether the rest of the path can be done from this pose does not depend on
            // how it was reached: remember the dead end.
            st.dead.insert((i, o, k));
            st.backtracking = true;
            if st.checks >= self.backtrack_budget {
                return false;
            }
        }
        false
    }

    /// Algorithm 1 over a terminal path (cells, `path[0]` = start) from pose `beta0`
    /// (radians). The start gets `beta0` and the orientation of `FK(beta0)` as rpy degrees;
    /// `Complete` holds one [`PosePoint`] per path cell, start included. An empty path gives
    /// an empty `Complete`.
    ///
    /// At each point the first candidate (orientations by growing angle from the current
    /// one, IK solutions by joint distance) whose interpolated motion keeps the clearance is
    /// taken. With a backtracking budget (`planning.backtrack_budget`), a dead end further on
    /// sends the search back to try the next candidates of earlier points, spending at most
    /// that many motion checks; with budget 0 this is the paper's greedy pass, and whenever
    /// the greedy pass succeeds both give the same poses. `Blocked` names the farthest point
    /// that no explored pose could reach.
    pub fn plan_poses(&self, path: &[Cell], beta0: &Joints) -> PosePlan {
        let Some(&start) = path.first() else {
            return PosePlan::Complete(Vec::new());
        };
        let start_rot = self.arm.fk(beta0).rotation;
        let mut poses = Vec::with_capacity(path.len());
        poses.push(PosePoint {
            cell: start,
            joints_rad: *beta0,
            orientation_rpy_deg: rpy_deg_from_rotation(&start_rot),
        });
        let mut st = Search::default();
        let orient = self.nearest_orientation(&start_rot);
        if self.descend(path, 1, beta0, orient, &mut st, &mut poses) {
            return PosePlan::Complete(poses);
        }
        let mut reached = vec![poses[0].clone()];
        reached.extend(st.deepest_reached.into_iter().skip(1));
        PosePlan::Blocked {
            reached,
            index: st.deepest,
            cell: path[st.deepest],
        }
    }

    /// The two clearance figures of the motion through `poses` (radians, in order), against
    /// this planner's obstacles, over every interpolation step; `None` for no poses.
    pub fn motion_clearance(&self, poses: &[Joints]) -> Option<MotionClearance> {
        let first = poses.first()?;
        let mut steps = vec![*first];
        for w in poses.windows(2) {
            steps.extend_from_slice(&motion_steps(&w[0], &w[1], self.steps)[1..]);
        }
        let mut m = MotionClearance {
            min_centre_clearance_cells: f64::INFINITY,
            min_cube_distance_mm: f64::INFINITY,
        };
        for q in &steps {
            let points = self.arm.points_mm(q);
            m.min_centre_clearance_cells = m
                .min_centre_clearance_cells
                .min(self.clearance.centres_clearance_cells(&points));
            m.min_cube_distance_mm = m
                .min_cube_distance_mm
                .min(self.clearance.capsules_gap_mm(&points, 0.0));
        }
        Some(m)
    }

    /// Best static clearance (cells) over every IK solution (within joint limits) of every
    /// grid orientation at `cell`, with that pose (radians) and its orientation (rpy
    /// degrees); the first of equal ones in grid and IK order. `None` if no IK solution at
    /// all.
    pub fn best_clearance_at(&self, cell: Cell) -> Option<(f64, Joints, [f64; 3])> {
        let position_mm = self.centre_mm(cell);
        let mut best: Option<(f64, Joints, [f64; 3])> = None;
        for o in &self.grid {
            let sols = self.arm.ik(&TerminalPose {
                position_mm,
                rotation: o.rotation,
            });
            for q in sols.iter().filter(|q| self.within_limits(q)) {
                let c = self.clearance.clearance_cells(&self.arm.points_mm(q));
                if best.as_ref().is_none_or(|b| c > b.0) {
                    best = Some((c, *q, o.rpy_deg));
                }
            }
        }
        best
    }

    /// Whether some pose at `cell` (any grid orientation, any IK solution, within joint
    /// limits) is clear.
    pub fn cell_reachable(&self, cell: Cell) -> bool {
        let position_mm = self.centre_mm(cell);
        self.grid.iter().any(|o| {
            self.arm
                .ik(&TerminalPose {
                    position_mm,
                    rotation: o.rotation,
                })
                .iter()
                .any(|q| {
                    self.within_limits(q) && self.clearance.pose_is_clear(&self.arm.points_mm(q))
                })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::rotation_from_rpy_deg;

    #[test]
    fn rpy_round_trip_and_angles() {
        for rpy in [
            [0.0, 0.0, 0.0],
            [10.0, -20.0, 30.0],
            [135.0, 45.0, -90.0],
            [-170.0, 80.0, 5.0],
        ] {
            let r = rotation_from_rpy_deg(rpy);
            let back = rpy_deg_from_rotation(&r);
            assert!(
                (rotation_from_rpy_deg(back) - r).amax() < 1e-12,
                "{rpy:?} -> {back:?}"
            );
        }
        let r = rotation_from_rpy_deg([0.0, 90.0, 30.0]);
        assert!((rotation_from_rpy_deg(rpy_deg_from_rotation(&r)) - r).amax() < 1e-12);
        let id = Matrix3::identity();
        assert_eq!(rotation_angle(&id, &id), 0.0);
        let a = rotation_from_rpy_deg([0.0, 0.0, 45.0]);
        assert!((rotation_angle(&id, &a) - 45f64.to_radians()).abs() < 1e-12);
        let b = rotation_from_rpy_deg([180.0, 0.0, 0.0]);
        assert!((rotation_angle(&id, &b) - std::f64::consts::PI).abs() < 1e-12);
    }

    #[test]
    fn orientation_order_starts_at_itself_and_grows() {
        let s = Scenario::builtin("paper_simple").unwrap();
        let p = PosePlanner::from_scenario(&s);
        for from in [0, 7, 100] {
            let order = p.orientation_order(from);
            assert_eq!(order[0], from);
            assert_eq!(order.len(), p.grid.len());
            let r = &p.grid[from].rotation;
            for w in order.windows(2) {
                let (a, b) = (
                    rotation_angle(r, &p.grid[w[0]].rotation),
                    rotation_angle(r, &p.grid[w[1]].rotation),
                );
                assert!(a <= b + 1e-9);
                if (a - b).abs() < 1e-9 && w[0] != from {
                    assert!(w[0] < w[1]);
                }
            }
        }
    }

    #[test]
    fn joint_limits_wrap() {
        let mut s = Scenario::builtin("paper_simple").unwrap();
        s.arm.joint_limits_deg = Some([[0.0, 350.0]; 6]);
        let p = PosePlanner::from_scenario(&s);
        // -5.7 deg is 354.3 deg: outside [0, 350]; -11.5 deg is 348.5 deg: inside.
        assert!(!p.within_limits(&[-0.1; 6]));
        assert!(p.within_limits(&[-0.2; 6]));
        assert!(p.within_limits(&[0.5, 1.0, 2.0, 3.0, -1.0, -3.0]));
        let mut q = [0.5; 6];
        q[3] = -0.1;
        assert!(!p.within_limits(&q));
        s.arm.joint_limits_deg = None;
        assert!(PosePlanner::from_scenario(&s).within_limits(&[-0.1; 6]));
    }
}

/// Book-keeping of one [`PosePlanner::plan_poses`] search.
#[derive(Default)]
struct Search {
    /// (path index, orientation index, solution index) from which the rest failed.
    dead: std::collections::HashSet<(usize, usize, usize)>,
    /// Set after the first dead end: motion checks count against the budget from then on.
    backtracking: bool,
    /// Motion checks spent while backtracking.
    checks: u32,
    /// Farthest path index the search tried to reach, and the poses up to it.
    deepest: usize,
    deepest_reached: Vec<PosePoint>,
}
