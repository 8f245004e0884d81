//! proxform-py: the Python bindings of proxform, as the extension module `proxform._proxform`.
//!
//! The bindings are thin: scenarios are the scenario crate's checked [`proxform_scenario::Scenario`]
//! (loaded from a file's text, a TOML string, a Python dict or a built-in name, with the same
//! checks and located errors), runs and comparisons are the simulator's batches, and the
//! controller is the core's [`proxform_core::Agent`] step. Arrays cross the boundary as numpy
//! arrays, column by column; long runs release the GIL and stop on Ctrl-C. The Python package
//! in `python/proxform` adds what is easier said in Python (result tables, pandas, tqdm).
//!
//! Units at the boundary are the library's: SI and radians, world frame x forward, y left,
//! z up; UAVs are numbered from 1, as in scenario files and reports.

mod background;
mod compare;
mod controller;
mod errors;
mod run;
mod scenario;
mod shard;
mod values;

use pyo3::prelude::*;

/// The extension module.
#[pymodule]
fn _proxform(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("ScenarioError", m.py().get_type::<errors::ScenarioError>())?;
    m.add("MAX_SWEEP_CELLS", proxform_sim::batch::sweep::MAX_CELLS)?;
    m.add_class::<scenario::PyScenario>()?;
    m.add_class::<shard::PyRuns>()?;
    m.add_function(wrap_pyfunction!(shard::merge_runs, m)?)?;
    m.add_class::<controller::PyController>()?;
    m.add_class::<controller::PyControllers>()?;
    m.add_class::<controller::PyDecision>()?;
    m.add_function(wrap_pyfunction!(run::run, m)?)?;
    m.add_function(wrap_pyfunction!(compare::compare, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::builtin_names, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
