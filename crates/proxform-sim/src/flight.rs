//! A flight on the engine its scenario chooses (`engine`): the reference engine
//! ([`Simulation`]) or the fast one ([`FastSimulation`]).

use proxform_scenario::{EngineChoice, Scenario};

use crate::fast::{supports, FastSimulation, Unsupported};
use crate::measure::observer::Observer;
use crate::world::engine::Simulation;
use crate::world::options::RunOptions;

/// The engine that steps a flight.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EngineKind {
    /// One agent object per UAV ([`Simulation`]).
    Reference,
    /// Every phase over arrays ([`FastSimulation`]).
    Fast,
}

impl EngineKind {
    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            EngineKind::Reference => "reference",
            EngineKind::Fast => "fast",
        }
    }
}

/// The engine `sc` runs on: `engine = "fast"` the fast one (an error if it does not run the
/// scenario), `"reference"` the reference, `"auto"` the fast one from
/// [`EngineChoice::AUTO_FAST_FROM`] UAVs when it runs the scenario.
pub fn engine_for(sc: &Scenario) -> Result<EngineKind, Unsupported> {
    match sc.engine() {
        EngineChoice::Reference => Ok(EngineKind::Reference),
        EngineChoice::Fast => supports(sc).map(|()| EngineKind::Fast),
        EngineChoice::Auto if sc.len() >= EngineChoice::AUTO_FAST_FROM && supports(sc).is_ok() => Ok(EngineKind::Fast),
        EngineChoice::Auto => Ok(EngineKind::Reference),
    }
}

/// Bytes one flight of `sc` on `engine` will hold (the engine's arrays and agents; the
/// scenario itself is in memory already), estimated before the flight is built: to refuse or
/// announce a flight before allocating it.
pub fn bytes_estimate(sc: &Scenario, engine: EngineKind) -> usize {
    match engine {
        EngineKind::Reference => Simulation::bytes_estimate(sc),
        EngineKind::Fast => FastSimulation::bytes_estimate(sc),
    }
}

/// One flight on either engine.
#[derive(Debug)]
pub enum Flight<'s> {
    /// On the reference engine.
    Reference(Box<Simulation<'s>>),
    /// On the fast engine.
    Fast(Box<FastSimulation<'s>>),
}

impl<'s> Flight<'s> {
    /// Run `run` of seed `seed` of `sc` on `engine`; a scenario the fast engine does not run
    /// flies on the reference (callers check with [`engine_for`] first to report it).
    pub fn new(sc: &'s Scenario, engine: EngineKind, options: RunOptions, seed: u64, run: u64) -> Self {
        match engine {
            EngineKind::Fast => match FastSimulation::new(sc, options, seed, run) {
                Ok(f) => Flight::Fast(Box::new(f)),
                Err(_) => Flight::Reference(Box::new(Simulation::new(sc, options, seed, run))),
            },
            EngineKind::Reference => Flight::Reference(Box::new(Simulation::new(sc, options, seed, run))),
        }
    }

    /// Forces serial or parallel stepping within the run (results are identical).
    pub fn with_parallel(self, parallel: bool) -> Self {
        match self {
            Flight::Reference(s) => Flight::Reference(Box::new(s.with_parallel(parallel))),
            Flight::Fast(s) => Flight::Fast(Box::new(s.with_parallel(parallel))),
        }
    }

    /// Bytes held by the engine (the scenario excluded).
    pub fn heap_bytes(&self) -> usize {
        match self {
            Flight::Reference(s) => s.heap_bytes(),
            Flight::Fast(s) => s.heap_bytes(),
        }
    }

    /// Runs the whole flight, showing every step to `observer`.
    pub fn run(self, observer: &mut impl Observer) {
        match self {
            Flight::Reference(s) => s.run(observer),
            Flight::Fast(s) => s.run(observer),
        }
    }

    /// Runs `steps` update periods (or fewer if the flight ends first).
    pub fn run_steps(self, steps: u64, observer: &mut impl Observer) {
        match self {
            Flight::Reference(s) => s.run_steps(steps, observer),
            Flight::Fast(s) => s.run_steps(steps, observer),
        }
    }
}
