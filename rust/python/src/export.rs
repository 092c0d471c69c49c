//! Export of a scenario as URDF (the arm) or MJCF (the MuJoCo scene).

use std::path::PathBuf;

use pyo3::prelude::*;
use sixaxis_core::export::{export, ExportFormat};

use crate::errors::run;
use crate::scenario::scenario_from_any;

/// The scenario as URDF (``format="urdf"``, the arm) or MJCF (``"mjcf"``, the arm, the
/// obstacles, the target and the start); lengths in metres. With ``path``, the text is also
/// written there atomically. Returns the text.
#[pyfunction]
#[pyo3(signature = (scenario=None, format="mjcf", path=None))]
pub fn export_scenario(
    py: Python<'_>,
    scenario: Option<&Bound<'_, PyAny>>,
    format: &str,
    path: Option<PathBuf>,
) -> PyResult<String> {
    let s = scenario_from_any(py, scenario)?;
    let format = format.to_string();
    run(py, move || {
        let f: ExportFormat = format.parse()?;
        let text = export(&s, f);
        if let Some(p) = &path {
            sixaxis_core::io::write_atomic(p, text.as_bytes())?;
        }
        Ok(text)
    })
}
