//! A scenario's geometry: its bounds (a box of cells) and obstacles as boxes in mm
//! ([`ObstacleBox`], with the distance rule of the terminal, [`DistanceTo`]). Units: cells
//! for [`Bounds`], mm for [`ObstacleBox`].

use serde::{Deserialize, Serialize};

use super::Cell;
use crate::error::{Error, Result};

/// Axis-aligned box of cells, both corners included.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bounds {
    /// Lowest corner cell (inclusive).
    pub min: Cell,
    /// Highest corner cell (inclusive).
    pub max: Cell,
}

impl Bounds {
    /// Whether `c` lies inside the box.
    #[inline]
    pub fn contains(&self, c: Cell) -> bool {
        (0..3).all(|i| c[i] >= self.min[i] && c[i] <= self.max[i])
    }

    /// Number of cells along each axis (in i64: `max - min + 1` overflows i32 for the
    /// widest boxes).
    pub fn size(&self) -> [usize; 3] {
        [0, 1, 2].map(|i| (self.max[i] as i64 - self.min[i] as i64 + 1).max(0) as usize)
    }

    /// Number of cells in the box, saturating at `usize::MAX` (a wrapped product let a box
    /// of 2^64 cells pass validation as an empty one).
    pub fn volume(&self) -> usize {
        self.size()
            .iter()
            .try_fold(1usize, |acc, &n| acc.checked_mul(n))
            .unwrap_or(usize::MAX)
    }
}

/// Where the safe distances to an [`ObstacleBox`] are measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DistanceTo {
    /// From the box itself (0 inside it): exact geometry, for boxes of any shape.
    #[default]
    Surface,
    /// From the box's centre point: the paper's reading of its cubes (eqs. 5 and 11 measure
    /// to an obstacle's centre). Only for cubes; [`crate::regrid`] writes the paper's cubes so.
    Centre,
}

/// An obstacle as an axis-aligned box in mm, independent of the grid.
///
/// The terminal collides in a cell whose centre lies within `terminal_safe_distance` of the
/// box, measured as [`DistanceTo`] says ([`ObstacleBox::terminal_distance_mm`]). The arm:
/// under the centres model, every segment keeps more than `arm_safe_distance` from the box
/// (its centre for `centre` boxes, eq. 11; the box itself for `surface` boxes); under the
/// capsules model, the exact gap between link capsules and the box exceeds `margin_mm`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleBox {
    /// Lowest corner, mm.
    pub min_mm: [f64; 3],
    /// Highest corner, mm.
    pub max_mm: [f64; 3],
    /// Where safe distances are measured from (default `surface`).
    #[serde(default, skip_serializing_if = "DistanceTo::is_surface")]
    pub distance_to: DistanceTo,
}

impl DistanceTo {
    fn is_surface(&self) -> bool {
        *self == DistanceTo::Surface
    }
}

impl ObstacleBox {
    /// The paper's cube of edge `cell_mm` centred on cell `c`, measured from its centre.
    pub fn paper_cube(c: Cell, cell_mm: f64) -> ObstacleBox {
        let h = 0.5 * cell_mm;
        let centre = c.map(|v| v as f64 * cell_mm);
        ObstacleBox {
            min_mm: centre.map(|v| v - h),
            max_mm: centre.map(|v| v + h),
            distance_to: DistanceTo::Centre,
        }
    }

    /// Centre of the box, mm.
    pub fn centre_mm(&self) -> [f64; 3] {
        std::array::from_fn(|i| 0.5 * (self.min_mm[i] + self.max_mm[i]))
    }

    /// Half its edge along each axis, mm.
    pub fn half_extents_mm(&self) -> [f64; 3] {
        std::array::from_fn(|i| 0.5 * (self.max_mm[i] - self.min_mm[i]))
    }

    /// Distance (mm) from point `p` (mm) to the box as the terminal's rule measures it: to
    /// the centre for `centre` boxes, to the box (0 inside or on it) for `surface` boxes.
    #[inline]
    pub fn terminal_distance_mm(&self, p: [f64; 3]) -> f64 {
        let d2: f64 = match self.distance_to {
            DistanceTo::Centre => {
                let c = self.centre_mm();
                (0..3).map(|i| (p[i] - c[i]) * (p[i] - c[i])).sum()
            }
            DistanceTo::Surface => (0..3)
                .map(|i| {
                    let d = (self.min_mm[i] - p[i]).max(p[i] - self.max_mm[i]).max(0.0);
                    d * d
                })
                .sum(),
        };
        d2.sqrt()
    }

    pub(crate) fn check(&self, field: &str) -> Result<()> {
        let all = self.min_mm.iter().chain(&self.max_mm);
        if !all.clone().all(|v| v.is_finite()) || (0..3).any(|i| self.min_mm[i] > self.max_mm[i]) {
            return Err(Error::invalid(
                field,
                format!("min_mm {:?} max_mm {:?}", self.min_mm, self.max_mm),
                "corners must be finite with min_mm <= max_mm on every axis",
            ));
        }
        if self.distance_to == DistanceTo::Centre {
            let h = self.half_extents_mm();
            let tol = 1e-9 * h[0].abs().max(1.0);
            if (h[1] - h[0]).abs() > tol || (h[2] - h[0]).abs() > tol {
                return Err(Error::invalid(
                    field,
                    format!("min_mm {:?} max_mm {:?}", self.min_mm, self.max_mm),
                    "a box measured from its centre (distance_to: centre) must be a cube",
                ));
            }
        }
        Ok(())
    }
}
