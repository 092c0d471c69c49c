//! Pose planning (Algorithm 1) and the arm-aware helpers of the env.

use std::sync::Arc;

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use sixaxis_core::clearance::Clearance;
use sixaxis_core::env::{first_clear_pose, unreachable_cells as core_unreachable};
use sixaxis_core::planner::{motion_steps, PosePlan, PosePoint};
use sixaxis_core::replanning::check_moves;
use sixaxis_core::scenario::DistanceTo;
use sixaxis_core::{PosePlanner, Scenario};

use crate::convert::{cell, joints6};
use crate::errors::{invalid_argument, run, run_attached};
use crate::scenario::{scenario_from_any, PyScenario};

/// Free cells (start and target excluded) at which no clear pose of the whole arm exists
/// (``PosePlanner.cell_reachable`` is false): the extra obstacles of ``arm_aware=True``.
/// Runs with the GIL released.
#[pyfunction]
#[pyo3(signature = (scenario=None))]
pub fn unreachable_cells<'py>(
    py: Python<'py>,
    scenario: Option<&Bound<'py, PyAny>>,
) -> PyResult<Vec<Bound<'py, PyTuple>>> {
    let s = scenario_from_any(py, scenario)?;
    let cells = run(py, || core_unreachable(&s))?;
    cells.iter().map(|c| PyTuple::new(py, c)).collect()
}

/// The first clear arm pose (radians, ``(6,)``) whose terminal is at the centre of ``cell``
/// (orientation grid order, then IK order), or ``None``.
#[pyfunction]
pub fn clear_pose_at<'py>(
    py: Python<'py>,
    scenario: &Bound<'py, PyAny>,
    cell_xyz: &Bound<'py, PyAny>,
) -> PyResult<Option<Bound<'py, PyArray1<f64>>>> {
    let s = scenario_from_any(py, Some(scenario))?;
    let c = cell(cell_xyz, "cell")?;
    let q = run(py, || {
        let planner = PosePlanner::from_scenario(&s);
        Ok(first_clear_pose(&planner, s.cell_mm, c))
    })?;
    Ok(q.map(|q| PyArray1::from_slice(py, &q)))
}

/// Algorithm 1: poses of the whole arm along a terminal path, with the scenario's arm,
/// clearance model (``arm_safe_distance``), orientation grid (n_d of pass ``round``),
/// interpolation steps, joint limits and ``planning.mode``.
#[pyclass(name = "PosePlanner", module = "sixaxis_avoid", frozen)]
pub struct PyPosePlanner {
    scenario: Arc<Scenario>,
    inner: PosePlanner,
}

fn poses_dict<'py>(py: Python<'py>, poses: &[PosePoint], d: &Bound<'py, PyDict>) -> PyResult<()> {
    let k = poses.len();
    let mut cells = Array2::<i32>::zeros((k, 3));
    let mut joints = Array2::<f64>::zeros((k, 6));
    let mut rpy = Array2::<f64>::zeros((k, 3));
    for (i, p) in poses.iter().enumerate() {
        for j in 0..3 {
            cells[[i, j]] = p.cell[j];
            rpy[[i, j]] = p.orientation_rpy_deg[j];
        }
        for j in 0..6 {
            joints[[i, j]] = p.joints_rad[j];
        }
    }
    d.set_item("cells", cells.into_pyarray(py))?;
    d.set_item("joints_rad", joints.into_pyarray(py))?;
    d.set_item("orientation_rpy_deg", rpy.into_pyarray(py))?;
    Ok(())
}

#[pymethods]
impl PyPosePlanner {
    #[new]
    #[pyo3(signature = (scenario=None, *, round=0))]
    fn py_new(py: Python<'_>, scenario: Option<&Bound<'_, PyAny>>, round: u32) -> PyResult<Self> {
        let s = scenario_from_any(py, scenario)?;
        let inner = PosePlanner::for_round(&s, round);
        Ok(PyPosePlanner { scenario: s, inner })
    }

    /// n_d of this planner's orientation grid: the scenario's n_d rule at pass ``round``
    /// (0 = the first pass; the paper's "change n_d" on every re-plan).
    #[getter]
    fn orientation_divisions(&self) -> u32 {
        self.inner.orientation_divisions()
    }

    /// The scenario.
    #[getter]
    fn scenario(&self) -> PyScenario {
        PyScenario {
            inner: self.scenario.clone(),
        }
    }

    /// Whether some clear pose (any grid orientation, any IK solution) reaches ``cell``.
    fn cell_reachable(&self, py: Python<'_>, cell_xyz: &Bound<'_, PyAny>) -> PyResult<bool> {
        let c = cell(cell_xyz, "cell")?;
        let p = &self.inner;
        run(py, || Ok(p.cell_reachable(c)))
    }

    /// ``(clearance_cells, joints_rad (6,), orientation_rpy_deg)`` of the pose of best
    /// static clearance at ``cell``, or ``None`` if no IK solution exists there.
    #[allow(clippy::type_complexity)]
    fn best_clearance_at<'py>(
        &self,
        py: Python<'py>,
        cell_xyz: &Bound<'py, PyAny>,
    ) -> PyResult<Option<(f64, Bound<'py, PyArray1<f64>>, (f64, f64, f64))>> {
        let c = cell(cell_xyz, "cell")?;
        let p = &self.inner;
        let best = run(py, || Ok(p.best_clearance_at(c)))?;
        Ok(best.map(|(cl, q, r)| (cl, PyArray1::from_slice(py, &q), (r[0], r[1], r[2]))))
    }

    /// Algorithm 1 over ``path`` (cells, ``path[0]`` = start) from ``beta0_rad`` (default:
    /// the scenario's beta_0). Returns a dict: ``complete`` (bool), ``cells`` ``(k, 3)``,
    /// ``joints_rad`` ``(k, 6)``, ``orientation_rpy_deg`` ``(k, 3)`` for the poses planned,
    /// and ``blocked_index`` / ``blocked_cell`` (``None`` when complete).
    #[pyo3(signature = (path, beta0_rad=None))]
    fn plan_poses<'py>(
        &self,
        py: Python<'py>,
        path: &Bound<'py, PyAny>,
        beta0_rad: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let cells = crate::convert::cells(Some(path), "path")?;
        run_attached(py, || check_moves(&cells))?;
        let beta0 = match beta0_rad.filter(|b| !b.is_none()) {
            Some(b) => joints6(b, "beta0_rad")?,
            None => self.scenario.arm.beta0_rad(),
        };
        let p = &self.inner;
        let plan = run(py, || Ok(p.plan_poses(&cells, &beta0)))?;
        let d = PyDict::new(py);
        d.set_item("complete", plan.is_complete())?;
        poses_dict(py, plan.poses(), &d)?;
        match &plan {
            PosePlan::Complete(_) => {
                d.set_item("blocked_index", py.None())?;
                d.set_item("blocked_cell", py.None())?;
            }
            PosePlan::Blocked { index, cell, .. } => {
                d.set_item("blocked_index", *index)?;
                d.set_item("blocked_cell", PyTuple::new(py, cell)?)?;
            }
        }
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!("PosePlanner(scenario={:?})", self.scenario.name)
    }
}

/// ``PosePlanner.cell_reachable`` for each of ``cells``: a ``(n,)`` bool array (GIL released).
#[pyfunction]
#[pyo3(signature = (cells, scenario=None))]
pub fn cells_reachable<'py>(
    py: Python<'py>,
    cells: &Bound<'py, PyAny>,
    scenario: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray1<bool>>> {
    let s = scenario_from_any(py, scenario)?;
    let cs = crate::convert::cells(Some(cells), "cells")?;
    let mask = run(py, || {
        let planner = PosePlanner::from_scenario(&s);
        Ok(cs
            .iter()
            .map(|&c| planner.cell_reachable(c))
            .collect::<Vec<_>>())
    })?;
    Ok(PyArray1::from_vec(py, mask))
}

/// The ``steps + 1`` poses (radians, ``(steps + 1, 6)``) of the joint-space move from ``q0``
/// to ``q1`` at which the planner checks a motion (the core's ``planner::motion_steps``:
/// each joint along its shortest angular difference, wrapped to (-pi, pi]).
#[pyfunction]
pub fn interpolate<'py>(
    py: Python<'py>,
    q0: &Bound<'py, PyAny>,
    q1: &Bound<'py, PyAny>,
    steps: i64,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (a, b) = (joints6(q0, "q0")?, joints6(q1, "q1")?);
    if !(1..=1_000_000).contains(&steps) {
        return Err(invalid_argument(
            py,
            "steps",
            steps,
            "must be an integer in 1..=1000000",
        ));
    }
    let poses = motion_steps(&a, &b, steps as u32);
    let rows: Vec<Vec<f64>> = poses.iter().map(|q| q.to_vec()).collect();
    Ok(PyArray2::from_vec2(py, &rows)?)
}

/// Eq. 11 for each pose of ``poses_rad`` (``(n, 6)``): the smallest distance (cells) from the
/// scenario arm's polyline to an obstacle centre — the scenario's obstacle cells and the
/// centres of its ``distance_to: "centre"`` boxes (``surface`` boxes are not centres and do
/// not count) — with cells of ``cell_mm`` (default: the scenario's). ``(n,)`` float64,
/// ``inf`` without centres. The core's ``Clearance::centres_clearance_cells``.
#[pyfunction]
#[pyo3(signature = (scenario, poses_rad, cell_mm=None))]
pub fn centres_clearance_cells<'py>(
    py: Python<'py>,
    scenario: &Bound<'py, PyAny>,
    poses_rad: &Bound<'py, PyAny>,
    cell_mm: Option<f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let s = scenario_from_any(py, Some(scenario))?;
    let cell_mm = cell_mm.unwrap_or(s.cell_mm);
    if !(cell_mm.is_finite() && cell_mm > 0.0) {
        return Err(invalid_argument(
            py,
            "cell_mm",
            cell_mm,
            "must be a finite number > 0",
        ));
    }
    let bad = || {
        invalid_argument(
            py,
            "poses_rad",
            crate::convert::repr(poses_rad),
            "must be a finite float64 array of shape (n, 6) (joint angles, radians)",
        )
    };
    let arr: numpy::PyReadonlyArray2<'_, f64> = poses_rad.extract().map_err(|_| bad())?;
    let view = arr.as_array();
    if view.ncols() != 6 || view.iter().any(|v| !v.is_finite()) {
        return Err(bad());
    }
    let poses: Vec<[f64; 6]> = view
        .rows()
        .into_iter()
        .map(|r| std::array::from_fn(|j| r[j]))
        .collect();
    let out = run(py, || {
        let centre_boxes: Vec<_> = s
            .obstacle_boxes_mm
            .iter()
            .filter(|b| b.distance_to == DistanceTo::Centre)
            .cloned()
            .collect();
        let clearance = Clearance::new(
            &s.obstacles,
            cell_mm,
            s.planning.clearance_model,
            s.arm_safe_distance,
        )
        .with_boxes(&centre_boxes);
        let arm = s.arm();
        Ok(poses
            .iter()
            .map(|q| clearance.centres_clearance_cells(&arm.points_mm(q)))
            .collect::<Vec<f64>>())
    })?;
    Ok(PyArray1::from_vec(py, out))
}
