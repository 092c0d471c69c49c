//! `sixaxis_avoid.Arm`: the modified D-H arm, forward and inverse kinematics.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use sixaxis_core::ik::IK_ROTATION_INPUT_TOL;
use sixaxis_core::kinematics::{rotation_from_rpy_deg, DhRow, PAPER_DH};
use sixaxis_core::{Arm, TerminalPose};

use crate::convert::{bounded_rows, joints6, repr, vec3};
use crate::errors::invalid_argument;
use crate::scenario::scenario_from_any;

/// A six-axis arm described by a modified (Craig) D-H table. Lengths in mm, angles of
/// joints in radians (names ending in ``_deg`` are degrees).
///
/// ``Arm()`` is the paper's Table 2 arm; ``Arm(dh=[(alpha_deg, a_mm, d_mm, offset_deg)] * 6)``
/// any arm of the same family; ``Arm.from_scenario(s)`` the arm of a scenario.
#[pyclass(name = "Arm", module = "sixaxis_avoid", frozen)]
#[derive(Clone)]
pub struct PyArm {
    pub inner: Arm,
}

/// `(position_mm (3,), rotation (3, 3))`.
type PoseArrays<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>);

fn mat3<'py>(py: Python<'py>, m: &nalgebra::Matrix3<f64>) -> Bound<'py, PyArray2<f64>> {
    let mut a = Array2::<f64>::zeros((3, 3));
    for r in 0..3 {
        for c in 0..3 {
            a[[r, c]] = m[(r, c)];
        }
    }
    a.into_pyarray(py)
}

#[pymethods]
impl PyArm {
    #[new]
    #[pyo3(signature = (dh = None))]
    fn py_new(py: Python<'_>, dh: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let Some(dh) = dh.filter(|d| !d.is_none()) else {
            return Ok(PyArm {
                inner: Arm::paper(),
            });
        };
        let rows: Vec<Vec<f64>> = bounded_rows(dh, 7, 5).ok_or_else(|| {
            invalid_argument(
                py,
                "dh",
                repr(dh),
                "must be 6 rows of (alpha_deg, a_mm, d_mm, offset_deg)",
            )
        })?;
        if rows.len() != 6 || rows.iter().any(|r| r.len() != 4) {
            return Err(invalid_argument(
                py,
                "dh",
                repr(dh),
                "must be 6 rows of 4 numbers (alpha_deg, a_mm, d_mm, offset_deg)",
            ));
        }
        if rows.iter().flatten().any(|v| !v.is_finite()) {
            return Err(invalid_argument(
                py,
                "dh",
                repr(dh),
                "every value must be finite",
            ));
        }
        let mut table = PAPER_DH;
        for (dst, r) in table.iter_mut().zip(&rows) {
            *dst = DhRow::new(r[0], r[1], r[2], r[3]);
        }
        Ok(PyArm {
            inner: Arm::new(table),
        })
    }

    /// The arm of a scenario (a Scenario, name, path or dict).
    #[staticmethod]
    fn from_scenario(py: Python<'_>, scenario: &Bound<'_, PyAny>) -> PyResult<Self> {
        let s = scenario_from_any(py, Some(scenario))?;
        Ok(PyArm { inner: s.arm() })
    }

    /// The D-H rows as ``[(alpha_deg, a_mm, d_mm, offset_deg)] * 6``.
    #[getter]
    fn dh(&self) -> Vec<(f64, f64, f64, f64)> {
        self.inner
            .dh_rows()
            .iter()
            .map(|r| (r.alpha_deg, r.a_mm, r.d_mm, r.offset_deg))
            .collect()
    }

    /// Forward kinematics: ``(position_mm (3,), rotation (3, 3))`` for joint angles in radians.
    fn fk<'py>(
        &self,
        py: Python<'py>,
        joints_rad: &Bound<'py, PyAny>,
    ) -> PyResult<PoseArrays<'py>> {
        let q = joints6(joints_rad, "joints_rad")?;
        let pose = self.inner.fk(&q);
        let p = pose.position_mm;
        Ok((
            PyArray1::from_slice(py, &[p.x, p.y, p.z]),
            mat3(py, &pose.rotation),
        ))
    }

    /// Terminal positions, mm, for a batch of poses: ``(n, 6)`` radians -> ``(n, 3)``.
    fn fk_batch<'py>(
        &self,
        py: Python<'py>,
        joints_rad: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let q = joints_rad.as_array();
        if q.ncols() != 6 {
            return Err(invalid_argument(
                py,
                "joints_rad",
                format!("array of shape {:?}", q.shape()),
                "must have shape (n, 6)",
            ));
        }
        let mut out = Array2::<f64>::zeros((q.nrows(), 3));
        for (i, row) in q.rows().into_iter().enumerate() {
            let j = [row[0], row[1], row[2], row[3], row[4], row[5]];
            let p = self.inner.fk(&j).position_mm;
            out[[i, 0]] = p.x;
            out[[i, 1]] = p.y;
            out[[i, 2]] = p.z;
        }
        Ok(out.into_pyarray(py))
    }

    /// The arm's body polyline, ``(8, 3)`` mm: base, O1, O2, O3, Aux ("joint 3.5"), O4, O5,
    /// O6 (the terminal).
    fn points_mm<'py>(
        &self,
        py: Python<'py>,
        joints_rad: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let q = joints6(joints_rad, "joints_rad")?;
        let pts = self.inner.points_mm(&q);
        let mut out = Array2::<f64>::zeros((8, 3));
        for (i, p) in pts.iter().enumerate() {
            out[[i, 0]] = p.x;
            out[[i, 1]] = p.y;
            out[[i, 2]] = p.z;
        }
        Ok(out.into_pyarray(py))
    }

    /// Inverse kinematics (eq. 13, closed form): every joint solution (up to 8, radians,
    /// each in (-pi, pi]) that puts the terminal at ``position_mm`` with orientation
    /// ``rotation`` (3x3) or ``rpy_deg`` (``R = Rz(rz) Ry(ry) Rx(rx)``, degrees). Returns a
    /// ``(k, 6)`` array, ``k = 0`` when the pose is out of reach.
    #[pyo3(signature = (position_mm, rotation = None, *, rpy_deg = None))]
    fn ik<'py>(
        &self,
        py: Python<'py>,
        position_mm: &Bound<'py, PyAny>,
        rotation: Option<&Bound<'py, PyAny>>,
        rpy_deg: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let p = vec3(position_mm, "position_mm")?;
        let rot = match (
            rotation.filter(|r| !r.is_none()),
            rpy_deg.filter(|r| !r.is_none()),
        ) {
            (Some(r), None) => {
                let rows: Vec<Vec<f64>> = bounded_rows(r, 4, 4).ok_or_else(|| {
                    invalid_argument(py, "rotation", repr(r), "must be a 3x3 matrix")
                })?;
                if rows.len() != 3 || rows.iter().any(|row| row.len() != 3) {
                    return Err(invalid_argument(
                        py,
                        "rotation",
                        repr(r),
                        "must be a 3x3 matrix",
                    ));
                }
                let m = nalgebra::Matrix3::from_fn(|i, j| rows[i][j]);
                let err = (m.transpose() * m - nalgebra::Matrix3::identity()).amax();
                if err.is_nan() || err > IK_ROTATION_INPUT_TOL || m.determinant() <= 0.0 {
                    return Err(invalid_argument(
                        py,
                        "rotation",
                        repr(r),
                        format!(
                            "must be a rotation matrix (R^T R = I within {IK_ROTATION_INPUT_TOL}, det R > 0)"
                        ),
                    ));
                }
                m
            }
            (None, Some(r)) => rotation_from_rpy_deg(vec3(r, "rpy_deg")?),
            _ => {
                return Err(invalid_argument(
                    py,
                    "rotation",
                    "None",
                    "give exactly one of `rotation` (3x3) and `rpy_deg` (3 angles)",
                ))
            }
        };
        let target = TerminalPose {
            position_mm: nalgebra::Vector3::new(p[0], p[1], p[2]),
            rotation: rot,
        };
        let sols = self.inner.ik(&target);
        let mut out = Array2::<f64>::zeros((sols.len(), 6));
        for (i, q) in sols.iter().enumerate() {
            for j in 0..6 {
                out[[i, j]] = q[j];
            }
        }
        Ok(out.into_pyarray(py))
    }

    fn __repr__(&self) -> String {
        format!("Arm(dh={:?})", self.dh())
    }
}
