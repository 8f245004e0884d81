//! Throughput measurement: agent-updates per second of the stepping engine.
//!
//! Times the steps only (building the scenario and the controllers is reported apart), with
//! the observers a real run uses, so the figure includes neighbour search, perception,
//! control, plant and metrics.

use std::time::Instant;

use proxform_scenario::Scenario;

use crate::flight::{EngineKind, Flight};
use crate::measure::metrics::RunMetrics;
use crate::measure::observer::{Observer, StepFrame};
use crate::world::options::{NeighbourSearch, RunOptions};

/// One throughput measurement.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Throughput {
    /// UAVs in the scenario.
    pub uavs: u64,
    /// Steps timed.
    pub steps: u64,
    /// Engine that stepped the flight ("reference", "fast", or "minimal-law" for
    /// [`measure_minimal`]).
    pub engine: &'static str,
    /// Neighbour search used.
    pub search: NeighbourSearch,
    /// Worker threads of the pool the steps ran on.
    pub threads: usize,
    /// Seconds spent building the engine and controllers.
    pub setup_s: f64,
    /// Seconds spent stepping.
    pub step_s: f64,
    /// Follower updates per second of stepping.
    pub updates_per_s: f64,
    /// Nanoseconds per agent-update.
    pub ns_per_update: f64,
    /// Bytes held by the engine and controllers.
    pub heap_bytes: u64,
}

struct Metrics<'a>(&'a mut RunMetrics);

impl Observer for Metrics<'_> {
    fn on_step(&mut self, scenario: &Scenario, frame: &StepFrame<'_>) {
        self.0.on_step(scenario, frame);
    }
}

/// Runs `steps` steps of `sc` (seed 1, run 0; at most the flight's steps) on `engine` with
/// `search` (the fast engine always searches its grid), in parallel within the run when
/// `parallel`, on the current rayon pool.
pub fn measure(sc: &Scenario, engine: EngineKind, steps: u64, search: NeighbourSearch, parallel: bool) -> Throughput {
    let options = RunOptions { neighbour_search: search, ..RunOptions::default() };
    let t0 = Instant::now();
    let sim = Flight::new(sc, engine, options, 1, 0).with_parallel(parallel);
    let engine = match sim {
        Flight::Reference(_) => EngineKind::Reference,
        Flight::Fast(_) => EngineKind::Fast,
    }
    .name();
    let heap_bytes = sim.heap_bytes() as u64;
    let mut metrics = RunMetrics::new(sc);
    let setup_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    timed_steps(sim, steps, &mut metrics);
    let step_s = t1.elapsed().as_secs_f64();
    Throughput::of(sc.len() as u64, steps.min(sc.steps()), (engine, search), (setup_s, step_s), heap_bytes)
}

impl Throughput {
    /// The figures of `steps` steps of `uavs` UAVs that took `step_s` seconds (after `setup_s`).
    fn of(
        uavs: u64,
        steps: u64,
        (engine, search): (&'static str, NeighbourSearch),
        (setup_s, step_s): (f64, f64),
        heap_bytes: u64,
    ) -> Self {
        let updates = (uavs - 1) * steps;
        Throughput {
            uavs,
            steps,
            engine,
            search,
            threads: rayon::current_num_threads(),
            setup_s,
            step_s,
            updates_per_s: updates as f64 / step_s.max(1e-12),
            ns_per_update: step_s * 1e9 / updates.max(1) as f64,
            heap_bytes,
        }
    }
}

/// The steps measured (a function of its own, so that an instruction counter can count them
/// alone: `valgrind --tool=callgrind --toggle-collect='*timed_steps*'`).
#[inline(never)]
pub fn timed_steps(sim: Flight<'_>, steps: u64, metrics: &mut RunMetrics) {
    sim.run_steps(steps, &mut Metrics(metrics));
}

/// Runs `steps` steps of the minimal law ([`super::minimal`]) over `sc`'s slots, speed, sensing
/// range, Δt and acceleration limit: the floor the engines' cost is compared against.
pub fn measure_minimal(sc: &Scenario, steps: u64, parallel: bool) -> Throughput {
    let t0 = Instant::now();
    let slots: Vec<[f64; 3]> =
        sc.formation().slots.iter().map(|s| [s.offset_m.x, s.offset_m.y, s.offset_m.z]).collect();
    let speed = sc.initial()[sc.navigator().index()][proxform_core::state::VX];
    let accel = sc.vehicle().braking_mps2();
    let law = super::minimal::MinimalLaw::new(&slots, speed, sc.controller().areas.sensing_range_m, sc.dt_s(), accel)
        .with_parallel(parallel);
    let heap_bytes = law.heap_bytes() as u64;
    let setup_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    timed_steps_minimal(law, steps);
    let step_s = t1.elapsed().as_secs_f64();
    Throughput::of(sc.len() as u64, steps, ("minimal-law", NeighbourSearch::Grid), (setup_s, step_s), heap_bytes)
}

/// The minimal law's steps measured (for callgrind's `--toggle-collect='*timed_steps*'`).
#[inline(never)]
pub fn timed_steps_minimal(mut law: super::minimal::MinimalLaw, steps: u64) {
    for _ in 0..steps {
        law.step();
    }
}
