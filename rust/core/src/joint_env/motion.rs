//! The clearance check of one step's motion: how many sub-steps a move `from -> to` (rad)
//! needs, the bound of any arm point's path (mm), and the check itself, both the reference
//! (every sub-step by the clearance's parry query) and the env's own (closed-form link gaps
//! measured only where no motion bound proves a link clear; docs/JOINT.md, "Speed").
//!
//! Entry points (methods of [`JointModel`]):
//! - [`JointModel::substeps`] / [`JointModel::path_bound_mm`] — sub-steps of a move and the
//!   path bound `Σ |Δq_i| L_i`, mm.
//! - [`JointModel::motion_is_clear`] / [`JointModel::motion_is_clear_from`] — the reference
//!   check of a move.
//! - [`JointModel::link_gaps_mm`] — each link's exact gap, mm.
//! - `JointModel::check_move` — the env's check of a step (the same answer as
//!   [`JointModel::motion_is_clear`]), with `link_gap_fast` / `link_gaps_fast` (gaps, mm,
//!   by [`segment_aabb_distance_mm`]).

use nalgebra::Vector3;

use super::{JointModel, MAX_LINKS};
use crate::clearance::segment_aabb_distance_mm;
use crate::kinematics::{ArmPoints, Joints};

/// Lanes of the box lower-bound loop.
pub(super) const BOX_LANES: usize = 4;
/// Coordinate of padding boxes, mm: far from everything, its square finite.
const FAR_MM: f64 = 1.0e100;

/// Slack (mm) of the motion bounds of [`JointModel::check_move`]: a pose is taken as clear
/// without an exact query only when its bound beats the safe distance by more than this, so
/// that floating-point rounding (about 1e-13 mm on coordinates of at most a few metres)
/// never turns a pose the exact query would refuse into an accepted one (docs/JOINT.md,
/// "Speed").
const BOUND_SLACK_MM: f64 = 1e-9;

/// The obstacle boxes (min, max; mm) as structure-of-arrays in chunks of [`BOX_LANES`]
/// (lo x, y, z, hi x, y, z), padded with empty boxes at [`FAR_MM`] (never measured: see
/// `link_gap_fast`), for the lower-bound loop of `link_gap_fast`.
pub(super) fn box_lanes_of(boxes: &[([f64; 3], [f64; 3])]) -> Vec<[[f64; BOX_LANES]; 6]> {
    let mut box_lanes = vec![[[FAR_MM; BOX_LANES]; 6]; boxes.len().div_ceil(BOX_LANES)];
    for (j, (lo, hi)) in boxes.iter().enumerate() {
        for i in 0..3 {
            box_lanes[j / BOX_LANES][i][j % BOX_LANES] = lo[i];
            box_lanes[j / BOX_LANES][3 + i][j % BOX_LANES] = hi[i];
        }
    }
    box_lanes
}

impl JointModel {
    /// Sub-steps of the move `from -> to` (rad): `max(1, ceil(Σ |Δq_i| L_i / (substep_fraction ·
    /// safe_distance_mm)))` (the module docs derive the bound).
    pub fn substeps(&self, from: &Joints, to: &Joints) -> u32 {
        let path_mm = self.path_bound_mm(from, to);
        let per = self.opts.substep_fraction * self.safe_distance_mm;
        ((path_mm / per).ceil() as u32).max(1)
    }

    /// Upper bound (mm) of the path length of any arm point over the move `from -> to`
    /// (rad): `Σ_i |Δq_i| L_i`.
    #[inline]
    pub fn path_bound_mm(&self, from: &Joints, to: &Joints) -> f64 {
        (0..6)
            .map(|i| (to[i] - from[i]).abs() * self.lever_mm[i])
            .sum()
    }

    /// Whether the move `from -> to` (rad, linear in joint space) is clear at each of its
    /// [`JointModel::substeps`] interpolated poses (`k = 1..=n`, the end pose first), every
    /// pose measured by the clearance's parry query: the reference of the env's own,
    /// faster check (`check_move`, docs/JOINT.md "Speed"), which gives the same answer.
    pub fn motion_is_clear(&self, from: &Joints, to: &Joints) -> bool {
        self.motion_is_clear_from(from, to, 0.0)
    }

    /// [`JointModel::motion_is_clear`] knowing that pose `from` has the gap `from_gap_mm`
    /// (mm; 0 when unknown): when `from_gap_mm - path_bound_mm(from, to) > safe_distance_mm`
    /// no point of the arm can come within the safe distance during the move (each moves at
    /// most the path bound), so no pose needs a check; otherwise every sub-step is checked.
    pub fn motion_is_clear_from(&self, from: &Joints, to: &Joints, from_gap_mm: f64) -> bool {
        if from_gap_mm - self.path_bound_mm(from, to) > self.safe_distance_mm {
            return true;
        }
        let n = self.substeps(from, to);
        if !self.pose_is_clear(to) {
            return false;
        }
        (1..n).all(|k| {
            let f = k as f64 / n as f64;
            let q: Joints = std::array::from_fn(|i| from[i] + (to[i] - from[i]) * f);
            self.pose_is_clear(&q)
        })
    }

    /// Exact gap (mm) of each link capsule to the nearest obstacle, in [`JointModel::links`]
    /// order, written into `out` (`INFINITY` without obstacles).
    pub fn link_gaps_mm(&self, points: &ArmPoints, out: &mut [f64]) {
        for (o, &k) in out.iter_mut().zip(&self.links) {
            // The polyline with every segment but k of zero length: the clearance's capsule
            // links leave zero-length segments out, so this measures link k alone.
            let mut one = [points[k]; 8];
            one[7] = points[k + 1];
            *o = self.clearance.capsules_gap_mm(&one, self.link_radius_mm);
        }
    }

    /// Exact gap (mm) of the capsule of segment `a`-`b` to the nearest obstacle box, by the
    /// closed form [`segment_aabb_distance_mm`], and that box's index; `(INFINITY, hint)`
    /// without obstacles. The box `hint` is measured first; every other box is first bounded
    /// below by the distance between the segment's bounding box and it (the segment lies in
    /// its bounding box), and measured exactly only when that bound could beat the best gap
    /// so far. Returns as soon as the best gap is `<= stop` (then some gap `<= stop`).
    #[inline]
    pub(crate) fn link_gap_fast(
        &self,
        a: &Vector3<f64>,
        b: &Vector3<f64>,
        stop: f64,
        hint: usize,
    ) -> (f64, usize) {
        let r = self.link_radius_mm;
        let (a, b) = ([a.x, a.y, a.z], [b.x, b.y, b.z]);
        let smin: [f64; 3] = std::array::from_fn(|i| a[i].min(b[i]));
        let smax: [f64; 3] = std::array::from_fn(|i| a[i].max(b[i]));
        let gap = |j: usize| {
            let (lo, hi) = &self.boxes[j];
            (segment_aabb_distance_mm(&a, &b, lo, hi) - r).max(0.0)
        };
        if self.boxes.is_empty() {
            return (f64::INFINITY, 0);
        }
        let hint = if hint < self.boxes.len() { hint } else { 0 };
        // A real box first: from here on `best` is finite, below the padding boxes' bound.
        let mut best = gap(hint);
        let mut at = hint;
        if best <= stop {
            return (best, at);
        }
        for (c, lanes) in self.box_lanes.iter().enumerate() {
            // Squared distance between the segment's bounding box and each box of the chunk:
            // a lower bound of the segment's (branch-free, four boxes at a time).
            let mut d2 = [0.0; BOX_LANES];
            for i in 0..3 {
                for (l, d) in d2.iter_mut().enumerate() {
                    let e = lanes[i][l] - smax[i];
                    let f = smin[i] - lanes[3 + i][l];
                    let e = if e > f { e } else { f };
                    let e = if e > 0.0 { e } else { 0.0 };
                    *d += e * e;
                }
            }
            for (l, &d) in d2.iter().enumerate() {
                // gap >= sqrt(d2) - r: measure only if sqrt(d2) - r < best.
                let reach = best + r;
                let j = c * BOX_LANES + l;
                if d >= reach * reach || j == hint {
                    continue;
                }
                let g = gap(j);
                if g < best {
                    best = g;
                    at = j;
                    if best <= stop {
                        return (best, at);
                    }
                }
            }
        }
        (best, at)
    }

    /// Each link's exact gap (mm, [`JointModel::links`] order) at polyline `points` by
    /// [`JointModel::link_gap_fast`], into `gaps`, with `hints` (the nearest box of each
    /// link, updated). Stops with `false` at the first link whose gap is `<= stop`.
    #[inline]
    pub(crate) fn link_gaps_fast(
        &self,
        points: &ArmPoints,
        stop: f64,
        gaps: &mut [f64; MAX_LINKS],
        hints: &mut [u32; MAX_LINKS],
    ) -> bool {
        for (l, &k) in self.links.iter().enumerate() {
            let (g, h) = self.link_gap_fast(&points[k], &points[k + 1], stop, hints[l] as usize);
            gaps[l] = g;
            hints[l] = h as u32;
            if g <= stop {
                return false;
            }
        }
        true
    }

    /// The env's check of the move `from -> to` (rad, linear in joint space, within the
    /// limits), with `from_gaps` the exact link gaps at `from` (mm, [`JointModel::links`]
    /// order; `INFINITY` is a valid entry without obstacles). The same answer as
    /// [`JointModel::motion_is_clear`] (every pose `k/n`, `k = 1..=n`, `n` the
    /// [`JointModel::substeps`], has every link gap `> safe_distance_mm`), computed with
    /// fewer exact queries (docs/JOINT.md, "Speed"): the end pose is measured exactly
    /// (its gaps go to `gaps`, its polyline is returned when the move is clear); an interior
    /// pose is measured, link by link, only when no motion bound proves that link clear.
    ///
    /// The bound (docs/JOINT.md, "Speed"): along the move, every point of link k travels
    /// at most `P_k · |t - t'|` mm between the poses at fractions t and t', with
    /// `P_k = Σ_i |Δq_i| ℓ_{i,k}`; so a link whose exact gap at t is g has a gap of at least
    /// `g - P_k |t - t'|` at t' (every point of the moved segment is within that path of a
    /// point of the first, and a distance to a fixed box changes by at most the distance
    /// moved). A link is taken as clear at t' when that bound exceeds the safe distance by
    /// more than [`BOUND_SLACK_MM`], from the last pose where it was measured (t = 0 at
    /// first) or from the end pose (t = 1).
    pub(crate) fn check_move(
        &self,
        from: &Joints,
        to: &Joints,
        from_gaps: &[f64],
        gaps: &mut [f64; MAX_LINKS],
        hints: &mut [u32; MAX_LINKS],
    ) -> Option<ArmPoints> {
        let safe = self.safe_distance_mm;
        let nl = self.links.len();
        let dq: [f64; 6] = std::array::from_fn(|i| (to[i] - from[i]).abs());
        let mut path = [0.0; MAX_LINKS];
        for (p, lever) in path.iter_mut().zip(&self.link_lever_mm).take(nl) {
            *p = (0..6).map(|i| dq[i] * lever[i]).sum();
        }
        let end = self.arm.points_mm(to);
        if !self.link_gaps_fast(&end, safe, gaps, hints) {
            return None;
        }
        let n = self.substeps(from, to);
        // The last exact gap of each link and the fraction where it was measured.
        let mut last = [f64::INFINITY; MAX_LINKS];
        last[..nl].copy_from_slice(&from_gaps[..nl]);
        let mut last_t = [0.0f64; MAX_LINKS];
        let limit = safe + BOUND_SLACK_MM;
        for k in 1..n {
            let f = k as f64 / n as f64;
            let mut open = [false; MAX_LINKS];
            for l in 0..nl {
                open[l] = last[l] - path[l] * (f - last_t[l]) <= limit
                    && gaps[l] - path[l] * (1.0 - f) <= limit;
            }
            if !open.contains(&true) {
                continue;
            }
            let q: Joints = std::array::from_fn(|i| from[i] + (to[i] - from[i]) * f);
            let p = self.arm.points_mm(&q);
            for l in 0..nl {
                if !open[l] {
                    continue;
                }
                let kk = self.links[l];
                let (g, h) = self.link_gap_fast(&p[kk], &p[kk + 1], safe, hints[l] as usize);
                if g <= safe {
                    return None;
                }
                hints[l] = h as u32;
                last[l] = g;
                last_t[l] = f;
            }
        }
        Some(end)
    }
}
