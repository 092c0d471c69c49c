//! `sixaxis_avoid._core`: thin PyO3 bindings over `sixaxis-core`.
//!
//! Everything of substance lives in the core (`sixaxis_core::env` holds the episode and
//! batched-env logic, `sixaxis_core::batch` the batch both envs share); this crate converts
//! arguments, maps errors (`errors`) and releases the GIL around long calls (`errors::run`);
//! the two native vector engines share their NumPy glue (`vec_core`).

use pyo3::prelude::*;

mod arm;
mod client;
mod convert;
mod env_core;
mod errors;
mod export;
mod joint_core;
mod plan;
mod planner;
mod request;
mod scenario;
mod serve;
mod tables;
mod train;
mod util;
mod vec_core;

/// Raise the Python exception of one core error variant (for the tests of the mapping).
/// `kind` is the variant's name: `InvalidScenario`, `ScenarioParse`, `ScenarioNotFound`,
/// `InvalidArgument`, `QTableMismatch`, `Io`, or `Panic` for a caught Rust panic.
#[pyfunction]
fn _raise_core_error(py: Python<'_>, kind: &str) -> PyResult<()> {
    use sixaxis_core::Error;
    let kind = kind.to_string();
    errors::run(py, move || {
        Err(match kind.as_str() {
            "InvalidScenario" => Error::invalid("bounds", "x", "test"),
            "ScenarioParse" => Error::ScenarioParse("test".into()),
            "ScenarioNotFound" => Error::ScenarioNotFound {
                name: "nope".into(),
                known: "paper_simple".into(),
            },
            "InvalidArgument" => Error::argument("seed", -1, "test"),
            "QTableMismatch" => Error::QTableMismatch("test".into()),
            "Io" => Error::io(
                "/nonexistent/file.json",
                std::io::Error::from_raw_os_error(2),
            ),
            "Panic" => panic!("test panic"),
            other => Error::argument("kind", other, "unknown error kind"),
        })
    })
}

/// The extension module.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    m.add_class::<scenario::PyScenario>()?;
    m.add_class::<arm::PyArm>()?;
    m.add_class::<train::PyTrainResult>()?;
    m.add_class::<env_core::PyEnvCore>()?;
    m.add_class::<env_core::PyVecEnvCore>()?;
    m.add_class::<joint_core::PyJointEnvCore>()?;
    m.add_class::<joint_core::PyJointVecEnvCore>()?;
    m.add_function(wrap_pyfunction!(train::train, m)?)?;
    m.add_function(wrap_pyfunction!(request::options, m)?)?;
    m.add_function(wrap_pyfunction!(request::check_options, m)?)?;
    m.add_function(wrap_pyfunction!(train::load_q, m)?)?;
    m.add_function(wrap_pyfunction!(train::greedy_path_of, m)?)?;
    m.add_function(wrap_pyfunction!(train::shortest_path, m)?)?;
    m.add_class::<planner::PyPosePlanner>()?;
    m.add_function(wrap_pyfunction!(planner::unreachable_cells, m)?)?;
    m.add_function(wrap_pyfunction!(planner::clear_pose_at, m)?)?;
    m.add_function(wrap_pyfunction!(planner::cells_reachable, m)?)?;
    m.add_function(wrap_pyfunction!(planner::interpolate, m)?)?;
    m.add_function(wrap_pyfunction!(planner::centres_clearance_cells, m)?)?;
    m.add_class::<plan::PyPlanResult>()?;
    m.add_function(wrap_pyfunction!(plan::plan, m)?)?;
    m.add_function(wrap_pyfunction!(plan::generate_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(util::write_atomic, m)?)?;
    m.add_function(wrap_pyfunction!(util::machine, m)?)?;
    m.add_function(wrap_pyfunction!(util::expand_names, m)?)?;
    m.add_function(wrap_pyfunction!(export::export_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(tables::env_tables, m)?)?;
    m.add_class::<serve::PyServer>()?;
    m.add_function(wrap_pyfunction!(serve::serve, m)?)?;
    m.add_class::<client::PyDmEnvClient>()?;
    m.add("VECTOR_OBS_DIM", sixaxis_core::env::VECTOR_OBS_DIM)?;
    let (t, g) = (
        sixaxis_core::env::OBS_TERMINAL,
        sixaxis_core::env::OBS_TARGET,
    );
    m.add("VECTOR_OBS_TERMINAL", (t.start, t.end))?;
    m.add("VECTOR_OBS_TARGET", (g.start, g.end))?;
    m.add("DEFAULT_SCENARIO", scenario::DEFAULT_SCENARIO)?;
    m.add_function(wrap_pyfunction!(_raise_core_error, m)?)?;
    Ok(())
}
