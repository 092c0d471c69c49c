//! Scenarios: the world of one experiment, read from JSON (`envs/*.json`). The bottom layer
//! of the core: it knows nothing of the grid, the generator or the planner.
//!
//! Entry points:
//! - [`Scenario::open`] — by built-in name (`paper_simple`) or by file path;
//!   [`Scenario::load`] (in [`crate::names`], one layer up) also takes `generated:SEED`.
//! - [`Scenario::from_json`] / [`Scenario::to_json`] — text round trip; parsing rejects
//!   unknown fields and then runs [`Scenario::validate`].
//! - [`Scenario::builtin`] / [`BUILTIN_NAMES`] — the scenarios shipped with the crate
//!   (`rust/core/scenarios/`, equal to `envs/`), compiled in.
//!
//! Field names say what a value is; the paper's symbols are in each field's doc line and in
//! `docs/SCENARIOS.md`. Distances between cells are in cells (grid unit = `cell_mm` mm).
//!
//! **Physical worlds.** Besides the paper's unit cubes on cells (`obstacles`), a scenario may
//! state obstacles as axis-aligned boxes in mm ([`ObstacleBox`], `obstacle_boxes_mm`) and its
//! safe distances in mm (`terminal_safe_distance_mm`, `arm_safe_distance_mm`), independent of
//! `cell_mm`; [`crate::regrid`] writes the same world at another cell size. Which cells a box
//! blocks for the terminal is [`ObstacleBox::terminal_distance_mm`] `<= d_s` (mm).
//!
//! ```
//! use sixaxis_core::scenario::Scenario;
//! let s = Scenario::load("paper_simple").unwrap();
//! assert_eq!(s.start, [0, -2, 4]);
//! assert_eq!(s.target, [0, 3, 0]);
//! ```
//!
//! The sections of a scenario live in sub-modules, re-exported here: [`geometry`] (bounds,
//! obstacle boxes in mm), [`learning`] (rewards, the learner's options, the assisted
//! strategies), [`planning`] (the arm and pose planning).

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::kinematics::{Arm, PAPER_DH};

pub mod geometry;
pub mod learning;
pub mod planning;

pub use geometry::{Bounds, DistanceTo, ObstacleBox};
pub use learning::{
    Assist, EpsilonSchedule, InitialQ, Learning, QPrecision, Rewards, AUTO_EPISODE_CAP,
};
pub use planning::{ArmSpec, ClearanceModel, Planning, PoseSearchMode};

/// A grid cell (integer coordinates, cells). Its centre is at `cell * cell_mm` mm.
pub type Cell = [i32; 3];

/// Largest scenario file [`Scenario::from_file`] reads, bytes (256 MiB: some 16 million
/// obstacle cells, the most a grid may hold).
pub const MAX_SCENARIO_BYTES: u64 = 256 << 20;

/// Position of the centre of cell `c` in a grid of `cell_mm` mm cells, mm (the one place
/// that says where a cell is).
pub fn cell_centre_mm(c: Cell, cell_mm: f64) -> nalgebra::Vector3<f64> {
    nalgebra::Vector3::new(c[0] as f64, c[1] as f64, c[2] as f64) * cell_mm
}

/// Built-in scenarios, by name: `rust/core/scenarios/*.json`, compiled into the crate (the
/// files in the repository's `envs/` are the user-facing copies, checked equal by a test).
pub const BUILTIN_NAMES: &[&str] = &["paper_simple", "paper_complex", "replan_clutter"];

pub(crate) fn builtin_text(name: &str) -> Option<&'static str> {
    Some(match name {
        "paper_simple" => include_str!("../../scenarios/paper_simple.json"),
        "paper_complex" => include_str!("../../scenarios/paper_complex.json"),
        "replan_clutter" => include_str!("../../scenarios/replan_clutter.json"),
        _ => return None,
    })
}

/// One experiment's world: grid, obstacles, arm, rewards, learning and planning parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Short name (the file stem for shipped scenarios).
    pub name: String,
    /// Free text: where the numbers come from, interpretations taken.
    #[serde(default)]
    pub notes: String,
    /// Edge of one grid cell, mm (the paper: 100).
    pub cell_mm: f64,
    /// The cells the terminal may occupy; a move out of them is a collision.
    pub bounds: Bounds,
    /// (x_0, y_0, z_0): the terminal's start cell.
    pub start: Cell,
    /// (x_tag, y_tag, z_tag): the target cell.
    pub target: Cell,
    /// Obstacle cells: unit cubes centred on these cells.
    pub obstacles: Vec<Cell>,
    /// Obstacles as boxes in mm, independent of the grid (beside `obstacles`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub obstacle_boxes_mm: Vec<ObstacleBox>,
    /// d_s (eq. 5): the terminal collides when its distance to an obstacle centre is <= this, cells.
    /// May be left out of a file that gives `terminal_safe_distance_mm`.
    #[serde(default = "unset_distance")]
    pub terminal_safe_distance: f64,
    /// d_p (eq. 11): every arm segment must stay farther than this from every obstacle centre, cells.
    /// May be left out of a file that gives `arm_safe_distance_mm`.
    #[serde(default = "unset_distance")]
    pub arm_safe_distance: f64,
    /// d_s in mm (the physical form); when given, `terminal_safe_distance` = this / `cell_mm`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub terminal_safe_distance_mm: Option<f64>,
    /// d_p in mm (the physical form); when given, `arm_safe_distance` = this / `cell_mm`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub arm_safe_distance_mm: Option<f64>,
    /// Reward parameters.
    #[serde(default)]
    pub rewards: Rewards,
    /// Learning parameters.
    #[serde(default)]
    pub learning: Learning,
    /// The arm.
    #[serde(default)]
    pub arm: ArmSpec,
    /// Pose planning parameters.
    #[serde(default)]
    pub planning: Planning,
}

fn fmt_cell(c: Cell) -> String {
    format!("[{}, {}, {}]", c[0], c[1], c[2])
}

/// Marks a safe distance in cells left out of a file (filled in from its mm form).
fn unset_distance() -> f64 {
    f64::NAN
}

impl Scenario {
    /// A scenario by file path or built-in name (no generated names: those are
    /// [`Scenario::load`]'s, one layer up). A name ending in `.json` or containing a path
    /// separator is always read as a file.
    pub fn open(name_or_path: &str) -> Result<Scenario> {
        let path = Path::new(name_or_path);
        if path.is_file() {
            return Scenario::from_file(path);
        }
        if let Some(text) = builtin_text(name_or_path) {
            return Scenario::from_json(text);
        }
        if name_or_path.ends_with(".json") || name_or_path.contains(std::path::MAIN_SEPARATOR) {
            // Reading it gives the precise I/O error (missing file, permission, ...).
            return Scenario::from_file(path);
        }
        Err(Error::ScenarioNotFound {
            name: name_or_path.to_string(),
            known: BUILTIN_NAMES.join(", "),
        })
    }

    /// A built-in scenario by name.
    pub fn builtin(name: &str) -> Result<Scenario> {
        match builtin_text(name) {
            Some(t) => Scenario::from_json(t),
            None => Err(Error::ScenarioNotFound {
                name: name.to_string(),
                known: BUILTIN_NAMES.join(", "),
            }),
        }
    }

    /// Read and validate a scenario file (at most [`MAX_SCENARIO_BYTES`]: `/dev/zero` or an
    /// endless pipe gives an error, not an exhausted memory).
    pub fn from_file(path: &Path) -> Result<Scenario> {
        let bytes = crate::io::read_bounded(path, MAX_SCENARIO_BYTES)?;
        let text = String::from_utf8(bytes).map_err(|e| {
            Error::io(
                path,
                std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()),
            )
        })?;
        Scenario::from_json(&text)
    }

    /// Parse and validate scenario JSON. A parse error names the field at fault
    /// (`field `learning.alpha`: invalid type: ...`).
    pub fn from_json(text: &str) -> Result<Scenario> {
        let mut de = serde_json::Deserializer::from_str(text);
        let mut s: Scenario = serde_path_to_error::deserialize(&mut de).map_err(|e| {
            let path = e.path().to_string();
            if path == "." {
                Error::ScenarioParse(e.into_inner().to_string())
            } else {
                // A value outside a named set says `= value: reason` (see `named_enum!`).
                let msg = e.into_inner().to_string();
                let sep = if msg.starts_with("= ") { " " } else { ": " };
                Error::ScenarioParse(format!("field `{path}`{sep}{msg}"))
            }
        })?;
        // Trailing text after the object is an error, as with `serde_json::from_str`.
        de.end().map_err(|e| Error::ScenarioParse(e.to_string()))?;
        s.fill_distances_from_mm()?;
        s.validate()?;
        Ok(s)
    }

    /// Pretty JSON text of the scenario.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a scenario always serialises")
    }

    /// The kinematic arm of this scenario.
    pub fn arm(&self) -> Arm {
        self.arm.arm()
    }

    /// Position of a cell's centre, mm.
    pub fn cell_centre_mm(&self, c: Cell) -> nalgebra::Vector3<f64> {
        cell_centre_mm(c, self.cell_mm)
    }

    /// A safe distance in cells left out of a file takes its mm form / `cell_mm`; one given
    /// in neither form is an error naming both fields.
    fn fill_distances_from_mm(&mut self) -> Result<()> {
        let cell_mm = self.cell_mm;
        for (field, cells, mm) in [
            (
                "terminal_safe_distance",
                &mut self.terminal_safe_distance,
                self.terminal_safe_distance_mm,
            ),
            (
                "arm_safe_distance",
                &mut self.arm_safe_distance,
                self.arm_safe_distance_mm,
            ),
        ] {
            if !cells.is_nan() {
                continue;
            }
            match mm {
                Some(mm) if cell_mm.is_finite() && cell_mm > 0.0 => *cells = mm / cell_mm,
                Some(_) => {}
                None => {
                    return Err(Error::ScenarioParse(format!(
                        "missing field `{field}` (cells) or `{field}_mm` (mm)"
                    )))
                }
            }
        }
        Ok(())
    }

    /// d_s in mm: `terminal_safe_distance_mm` if given, else `terminal_safe_distance * cell_mm`.
    pub fn terminal_safe_distance_in_mm(&self) -> f64 {
        self.terminal_safe_distance_mm
            .unwrap_or(self.terminal_safe_distance * self.cell_mm)
    }

    /// d_p in mm: `arm_safe_distance_mm` if given, else `arm_safe_distance * cell_mm`.
    pub fn arm_safe_distance_in_mm(&self) -> f64 {
        self.arm_safe_distance_mm
            .unwrap_or(self.arm_safe_distance * self.cell_mm)
    }

    /// The obstacle that blocks cell `c` for the terminal, if any, described for an error
    /// message: a paper cube whose centre is within `terminal_safe_distance` cells, or a box
    /// within `terminal_safe_distance` mm by [`ObstacleBox::terminal_distance_mm`].
    pub fn terminal_blocker(&self, c: Cell) -> Option<String> {
        let d_s = self.terminal_safe_distance;
        for o in &self.obstacles {
            let d2: i64 = (0..3)
                .map(|i| (c[i] - o[i]) as i64 * (c[i] - o[i]) as i64)
                .sum();
            if (d2 as f64).sqrt() <= d_s {
                return Some(format!("obstacle {}", fmt_cell(*o)));
            }
        }
        let d_s_mm = self.terminal_safe_distance_in_mm();
        let p = c.map(|v| v as f64 * self.cell_mm);
        self.obstacle_boxes_mm
            .iter()
            .enumerate()
            .find_map(|(i, b)| {
                (b.terminal_distance_mm(p) <= d_s_mm).then(|| format!("obstacle_boxes_mm[{i}]"))
            })
    }

    /// Check every field; the error names the field and the value.
    pub fn validate(&self) -> Result<()> {
        fn finite_pos(field: &str, v: f64, allow_zero: bool) -> Result<()> {
            if !v.is_finite() || v < 0.0 || (!allow_zero && v == 0.0) {
                let what = if allow_zero {
                    "must be a finite number >= 0"
                } else {
                    "must be a finite number > 0"
                };
                return Err(Error::invalid(field, v, what));
            }
            Ok(())
        }
        if self.name.trim().is_empty() {
            return Err(Error::invalid("name", "\"\"", "must not be empty"));
        }
        finite_pos("cell_mm", self.cell_mm, false)?;
        let b = &self.bounds;
        for i in 0..3 {
            if b.min[i] > b.max[i] {
                return Err(Error::invalid(
                    "bounds",
                    format!("min {} max {}", fmt_cell(b.min), fmt_cell(b.max)),
                    format!("empty along axis {}: min > max", ["x", "y", "z"][i]),
                ));
            }
        }
        if b.volume() > 1 << 24 {
            return Err(Error::invalid(
                "bounds",
                format!("min {} max {}", fmt_cell(b.min), fmt_cell(b.max)),
                "more than 16,777,216 cells",
            ));
        }
        for (field, c) in [("start", self.start), ("target", self.target)] {
            if !b.contains(c) {
                return Err(Error::invalid(field, fmt_cell(c), "lies outside bounds"));
            }
            if self.obstacles.contains(&c) {
                return Err(Error::invalid(
                    field,
                    fmt_cell(c),
                    "lies inside an obstacle",
                ));
            }
        }
        for (i, ob) in self.obstacle_boxes_mm.iter().enumerate() {
            ob.check(&format!("obstacle_boxes_mm[{i}]"))?;
        }
        if self.start == self.target {
            return Err(Error::invalid(
                "target",
                fmt_cell(self.target),
                "equals the start cell",
            ));
        }
        finite_pos("terminal_safe_distance", self.terminal_safe_distance, true)?;
        finite_pos("arm_safe_distance", self.arm_safe_distance, true)?;
        for (field, cells, mm) in [
            (
                "terminal_safe_distance_mm",
                self.terminal_safe_distance,
                self.terminal_safe_distance_mm,
            ),
            (
                "arm_safe_distance_mm",
                self.arm_safe_distance,
                self.arm_safe_distance_mm,
            ),
        ] {
            let Some(mm) = mm else { continue };
            finite_pos(field, mm, true)?;
            if (cells * self.cell_mm - mm).abs() > 1e-9 * mm.max(1.0) {
                return Err(Error::invalid(
                    field,
                    mm,
                    format!(
                        "disagrees with `{}` = {cells} cells of {} mm; give one of the two, or both equal",
                        field.trim_end_matches("_mm"),
                        self.cell_mm
                    ),
                ));
            }
        }
        // The paper's scenarios have d_s < 1 cell: each cube blocks its own cell. A larger
        // d_s (e.g. a paper world re-gridded to finer cells) blocks a ball of cells around
        // each centre; the start and the target must stay free.
        for (field, c) in [("start", self.start), ("target", self.target)] {
            if let Some(what) = self.terminal_blocker(c) {
                return Err(Error::invalid(
                    field,
                    fmt_cell(c),
                    format!(
                        "is blocked: within terminal_safe_distance ({} mm) of {what}",
                        self.terminal_safe_distance_in_mm()
                    ),
                ));
            }
        }
        let r = &self.rewards;
        for (f, v) in [
            ("rewards.target_reward", r.target_reward),
            ("rewards.step_penalty", r.step_penalty),
            ("rewards.collision_penalty", r.collision_penalty),
            (
                "rewards.repeat_collision_penalty",
                r.repeat_collision_penalty,
            ),
            (
                "rewards.reverse_after_collision_penalty",
                r.reverse_after_collision_penalty,
            ),
            ("rewards.distance_reward", r.distance_reward),
        ] {
            finite_pos(f, v, true)?;
        }
        self.learning.check()?;
        let a = &self.arm;
        if a.dh.len() != 6 {
            return Err(Error::invalid(
                "arm.dh",
                format!("{} rows", a.dh.len()),
                "must have exactly 6 rows",
            ));
        }
        for (i, row) in a.dh.iter().enumerate() {
            for (n, v) in [
                ("alpha_deg", row.alpha_deg),
                ("a_mm", row.a_mm),
                ("d_mm", row.d_mm),
                ("offset_deg", row.offset_deg),
            ] {
                if !v.is_finite() {
                    return Err(Error::invalid(
                        format!("arm.dh[{i}].{n}"),
                        v,
                        "must be finite",
                    ));
                }
            }
        }
        let mut rows = PAPER_DH;
        rows.copy_from_slice(&a.dh);
        if let Err(why) = crate::ik::check_closed_form_family(&rows) {
            return Err(Error::invalid(
                "arm.dh",
                "(table)",
                format!("the closed-form inverse kinematics does not cover this table: {why}"),
            ));
        }
        for (i, v) in a.beta0_deg.iter().enumerate() {
            if !v.is_finite() {
                return Err(Error::invalid(
                    format!("arm.beta0_deg[{i}]"),
                    v,
                    "must be finite",
                ));
            }
        }
        if let Some(lims) = &a.joint_limits_deg {
            for (i, [lo, hi]) in lims.iter().enumerate() {
                if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                    return Err(Error::invalid(
                        format!("arm.joint_limits_deg[{i}]"),
                        format!("[{lo}, {hi}]"),
                        "must be finite with low < high",
                    ));
                }
            }
        }
        let arm = self.arm();
        let reached = arm.fk(&a.beta0_rad()).position_mm;
        let start_mm = self.cell_centre_mm(self.start);
        let miss = (reached - start_mm).norm();
        if miss.is_nan() || miss > 1.0 {
            return Err(Error::invalid(
                "arm.beta0_deg",
                format!("{:?}", a.beta0_deg),
                format!(
                    "its forward kinematics reaches ({:.1}, {:.1}, {:.1}) mm, {:.1} mm from the start cell's centre (at most 1 mm allowed)",
                    reached.x, reached.y, reached.z, miss
                ),
            ));
        }
        let p = &self.planning;
        if p.interpolation_steps == 0 {
            return Err(Error::invalid(
                "planning.interpolation_steps",
                0,
                "must be > 0",
            ));
        }
        if p.orientation_divisions == 0 || p.orientation_divisions > 72 {
            return Err(Error::invalid(
                "planning.orientation_divisions",
                p.orientation_divisions,
                "must be in 1..=72",
            ));
        }
        if p.orientation_divisions_growth == 0 {
            return Err(Error::invalid(
                "planning.orientation_divisions_growth",
                0,
                "must be >= 1 (1 keeps n_d fixed, 2 doubles it on every re-plan)",
            ));
        }
        let cap = p.orientation_divisions_max;
        if cap < p.orientation_divisions || cap > 72 {
            return Err(Error::invalid(
                "planning.orientation_divisions_max",
                cap,
                format!(
                    "must be in {}..=72 (at least planning.orientation_divisions)",
                    p.orientation_divisions
                ),
            ));
        }
        if p.orientation_divisions_growth > 1 {
            let mut n = p.orientation_divisions;
            while n < cap {
                n = n.saturating_mul(p.orientation_divisions_growth);
            }
            if n != cap {
                return Err(Error::invalid(
                    "planning.orientation_divisions_max",
                    cap,
                    format!(
                        "must be orientation_divisions × growth^j ({} × {}^j) so that every orientation grid contains the one before",
                        p.orientation_divisions, p.orientation_divisions_growth
                    ),
                ));
            }
        }
        if let ClearanceModel::Capsules {
            link_radius_mm,
            margin_mm,
        } = p.clearance_model
        {
            finite_pos(
                "planning.clearance_model.link_radius_mm",
                link_radius_mm,
                true,
            )?;
            finite_pos("planning.clearance_model.margin_mm", margin_mm, true)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_load_and_roundtrip() {
        for name in BUILTIN_NAMES {
            let s = Scenario::builtin(name).unwrap();
            let again = Scenario::from_json(&s.to_json()).unwrap();
            assert_eq!(s, again);
        }
    }

    #[test]
    fn paper_simple_matches_table_1() {
        let s = Scenario::builtin("paper_simple").unwrap();
        assert_eq!(s.start, [0, -2, 4]);
        assert_eq!(s.target, [0, 3, 0]);
        assert_eq!(s.obstacles.len(), 19);
        assert_eq!(s.terminal_safe_distance, 0.96);
        assert_eq!(s.arm_safe_distance, 0.76);
        assert_eq!(s.rewards, Rewards::default());
        assert_eq!(s.cell_mm, 100.0);
        let c = Scenario::builtin("paper_complex").unwrap();
        assert_eq!(c.obstacles, s.obstacles);
        assert_eq!(c.terminal_safe_distance, 0.95);
        assert_eq!(c.arm_safe_distance, 0.85);
    }
}
