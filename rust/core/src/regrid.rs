//! Re-gridding: the same physical world at another cell size.
//!
//! Entry point: [`regrid`]. A scenario's world is physical: obstacle boxes and safe distances
//! in mm. Re-gridding keeps every length in mm and changes only the grid the terminal moves
//! on:
//! - every paper cube (`obstacles`, a cube of edge `cell_mm` centred on a cell) becomes a box
//!   in mm of the same place and size, measured from its centre (`distance_to: centre`), so
//!   eqs. 5 and 11 keep their meaning (d_s and d_p from the cube's centre); boxes in mm are
//!   kept as they are;
//! - the safe distances are written in mm (`*_safe_distance_mm`) and in cells of the new size;
//! - the bounds keep the same range of terminal positions: the new cells are those whose
//!   centre lies between `bounds.min * cell_mm` and `bounds.max * cell_mm` (mm) of the old grid;
//! - start and target stay at the same points in mm. A point that is not a cell centre of the
//!   new grid is an error (no snapping: a moved start would no longer be where `beta0` puts
//!   the terminal); pick a cell size that divides their coordinates;
//! - the step cap of an episode (`learning.max_steps_per_episode`) is scaled by
//!   `old / new` (rounded up), so an episode may still travel the same distance; every other
//!   learning, reward, arm and planning setting is kept.
//!
//! Re-gridding to the same cell size gives the same world (the same blocked cells, learned
//! path and poses, bit for bit) in the physical form.
//!
//! ```
//! use sixaxis_core::regrid::regrid;
//! use sixaxis_core::Scenario;
//! let s = Scenario::builtin("paper_simple").unwrap();
//! let fine = regrid(&s, 50.0).unwrap();
//! assert_eq!(fine.start, [0, -4, 8]); // (0, -200, 400) mm
//! assert_eq!(fine.terminal_safe_distance_mm, Some(96.0));
//! assert!(regrid(&s, 30.0).is_err()); // -200 mm is not a multiple of 30 mm
//! ```

use crate::error::{Error, Result};
use crate::scenario::{Bounds, Cell, ObstacleBox, Scenario};

/// Relative slack when a coordinate in mm is divided by the cell size (absorbs rounding).
const ON_GRID_TOL: f64 = 1e-9;

/// The same physical world as `s`, on cells of `cell_mm` mm (see the module docs).
pub fn regrid(s: &Scenario, cell_mm: f64) -> Result<Scenario> {
    if !(cell_mm.is_finite() && cell_mm > 0.0) {
        return Err(Error::argument(
            "cell_mm",
            cell_mm,
            "must be a finite number > 0",
        ));
    }
    let old = s.cell_mm;
    let ratio = old / cell_mm;
    let mut out = s.clone();
    out.cell_mm = cell_mm;
    out.obstacle_boxes_mm = s
        .obstacles
        .iter()
        .map(|&c| ObstacleBox::paper_cube(c, old))
        .chain(s.obstacle_boxes_mm.iter().copied())
        .collect();
    out.obstacles = Vec::new();
    let ds_mm = s.terminal_safe_distance_in_mm();
    let dp_mm = s.arm_safe_distance_in_mm();
    out.terminal_safe_distance_mm = Some(ds_mm);
    out.arm_safe_distance_mm = Some(dp_mm);
    out.terminal_safe_distance = ds_mm / cell_mm;
    out.arm_safe_distance = dp_mm / cell_mm;
    let scaled = |v: i32| v as f64 * ratio;
    out.bounds = Bounds {
        min: s.bounds.min.map(|v| {
            let x = scaled(v);
            (x - ON_GRID_TOL * x.abs().max(1.0)).ceil() as i32
        }),
        max: s.bounds.max.map(|v| {
            let x = scaled(v);
            (x + ON_GRID_TOL * x.abs().max(1.0)).floor() as i32
        }),
    };
    out.start = on_grid("start", s.start, old, cell_mm)?;
    out.target = on_grid("target", s.target, old, cell_mm)?;
    let steps = (s.learning.max_steps_per_episode as f64 * ratio).ceil();
    out.learning.max_steps_per_episode = steps.clamp(1.0, u32::MAX as f64) as u32;
    if cell_mm != old {
        out.name = format!("{}@{}mm", s.name, cell_mm);
        let note = format!(
            "Re-gridded from `{}` ({old} mm cells) to {cell_mm} mm cells: the same boxes and safe distances in mm.",
            s.name
        );
        out.notes = if s.notes.is_empty() {
            note
        } else {
            format!("{} {note}", s.notes)
        };
    }
    out.validate()?;
    Ok(out)
}

/// The cell of the new grid at the point of `c` (old grid), or an error naming the field.
fn on_grid(field: &str, c: Cell, old_mm: f64, new_mm: f64) -> Result<Cell> {
    let mut out = [0; 3];
    for i in 0..3 {
        let mm = c[i] as f64 * old_mm;
        let x = mm / new_mm;
        let r = x.round();
        if (x - r).abs() > ON_GRID_TOL * x.abs().max(1.0) || r.abs() > i32::MAX as f64 {
            let p = c.map(|v| v as f64 * old_mm);
            return Err(Error::argument(
                field,
                format!("({}, {}, {}) mm", p[0], p[1], p[2]),
                format!(
                    "is not a cell centre of the {new_mm} mm grid (centres lie at multiples of {new_mm} mm); choose a cell size that divides its coordinates"
                ),
            ));
        }
        out[i] = r as i32;
    }
    Ok(out)
}
