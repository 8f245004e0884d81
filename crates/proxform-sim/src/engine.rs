//! The stepping engine: fixed Δt, double-buffered state, seeded noise streams.
//!
//! Every UAV observes snapshot k before any UAV writes k + 1. Each follower gets a noisy
//! estimate of its own state and what its proximity sensor reports ([`crate::sensing`]),
//! runs its controller, and its plant applies the input with the actuation error. The
//! navigator flies its scripted path. All randomness comes from [`crate::rng`] streams keyed
//! by (seed, run, UAV, source) and the step number, so a UAV's update does not depend on
//! which thread runs it: large swarms are stepped in parallel with identical results.

use proxform_core::state::{self, Input, State9};
use proxform_core::{ControllerSetup, FormationController, ObservationSource, Outcome, UavId};
use rand::RngExt;
use rayon::prelude::*;

use crate::faults::{self, Fault, FaultStep};
use crate::grid::NeighbourGrid;
use crate::observer::{Observer, StepFrame, UavStep};
use crate::radio::RadioModel;
use crate::rng::{source_key, stream_key, uav_key, Source, StepRng};
use crate::scenario::{Scenario, ScenarioError};
use crate::sensing::{noisy, Link, NeighbourSearch, ProximitySensor, SensorScratch};

/// The read-only view of one step, built from the simulation's fields (a macro rather than a
/// method, so that the controllers can be borrowed mutably beside it).
macro_rules! step_context {
    ($sim:ident, $k:expr, $t:expr, $sent:expr, $env:expr, $warm:expr) => {
        StepContext {
            scenario: $sim.scenario,
            run_key: crate::rng::run_key($sim.seed, $sim.run),
            step_part: crate::rng::step_part($k),
            t: $t,
            start: $sim.start,
            current: &$sim.current,
            grid: &$sim.grid,
            sensor: &$sim.sensor,
            search: $sim.search,
            active: &$sim.active,
            faults: &$sim.faults,
            sent: $sent,
            broadcasts: &$sim.broadcasts,
            env: $env,
            warm: $warm,
        }
    };
}

/// Swarms at least this large are stepped in parallel within the run.
pub const PARALLEL_MIN_UAVS: usize = 1024;

/// One simulated flight.
#[derive(Debug)]
pub struct Simulation<'s> {
    scenario: &'s Scenario,
    seed: u64,
    run: u64,
    k: u64,
    current: Vec<State9>,
    next: Vec<State9>,
    controllers: Vec<Option<FormationController>>,
    uavs: Vec<UavStep>,
    grid: NeighbourGrid,
    /// Per-UAV environment (wind, position-fix bias, radio channel), empty when not needed.
    env: Vec<crate::environment::UavEnv>,
    /// The radio messages arriving this step (sender, state sent), computed once for all
    /// receivers.
    broadcasts: Vec<(u32, State9)>,
    /// True states of the last `delay + 1` steps, oldest first (radio with delay only).
    history: std::collections::VecDeque<Vec<State9>>,
    active: Vec<bool>,
    faults: FaultStep,
    sensor: ProximitySensor,
    search: NeighbourSearch,
    start: [f64; 3],
    parallel: bool,
}

impl<'s> Simulation<'s> {
    /// A flight of `scenario` for run `run` of seed `seed`.
    pub fn new(scenario: &'s Scenario, seed: u64, run: u64) -> Result<Self, ScenarioError> {
        scenario.validate()?;
        let n = scenario.len();
        let nav = scenario.navigator.index();
        let setup = ControllerSetup::new(controller_params(scenario), scenario.vehicle.clone())?;
        let mut controllers = Vec::with_capacity(n);
        for i in 0..n {
            controllers.push(if i == nav {
                None
            } else {
                Some(FormationController::new(
                    &scenario.method,
                    UavId(i as u32),
                    scenario.navigator,
                    setup.clone(),
                    scenario.formation.clone(),
                    scenario.dependencies[i].clone(),
                )?)
            });
        }
        let s0 = scenario.initial[nav];
        let areas = scenario.controller.areas;
        let parallel = n >= PARALLEL_MIN_UAVS;
        Ok(Self {
            scenario,
            seed,
            run,
            k: 0,
            current: scenario.initial.clone(),
            next: scenario.initial.clone(),
            controllers,
            uavs: vec![UavStep::default(); n],
            env: crate::environment::initial(scenario),
            grid: NeighbourGrid::new(),
            broadcasts: Vec::new(),
            history: std::collections::VecDeque::new(),
            active: (0..n).map(|i| faults::is_active(&scenario.faults, i, 0.0)).collect(),
            faults: FaultStep { radio_up: true, ..FaultStep::default() },
            sensor: ProximitySensor::new(areas.areas, areas.sensing_range_m, scenario.noise.sigma()),
            search: scenario.neighbour_search,
            start: [s0[state::X], s0[state::Y], s0[state::Z]],
            parallel,
        }
        .warmed())
    }

    fn warmed(mut self) -> Self {
        self.warm_up();
        self
    }

    /// The formation's flight before t = 0 (METHOD §9 Choice, see README): for
    /// `scenario.warmup_s`, every follower perceives its neighbours in the ideal formation
    /// around the navigator's path and runs its controller, whose inputs are discarded, so
    /// that at t = 0 its neighbour tracks know their rates. The formation is then maintained
    /// from an established flight rather than from a standing start.
    fn warm_up(&mut self) {
        let sc = self.scenario;
        let steps = (sc.warmup_s / sc.dt_s).round() as u64;
        if steps == 0 {
            return;
        }
        let nav = sc.navigator.index();
        let f = &sc.formation;
        // The ideal states are written into `next` (unused until the first step), in place.
        std::mem::swap(&mut self.current, &mut self.next);
        for w in 0..steps {
            let t = -((steps - w) as f64) * sc.dt_s;
            let nav_state = sc.path.state_at(t, self.start);
            for (i, s) in self.current.iter_mut().enumerate() {
                *s = if i == nav { nav_state } else { nav_state + f.w(&f.slots[i], &f.slots[nav], &nav_state) };
            }
            let range = sc.controller.areas.sensing_range_m;
            self.rebuild_grid(range);
            let k = WARMUP_STEP_BASE + w;
            fill_broadcasts(sc, self.seed, self.run, Some((&self.current[..], k)), self.parallel, &mut self.broadcasts);
            let ctx = step_context!(self, k, t, Some((&self.current[..], k)), &[], true);
            let m = sc.controller.areas.areas;
            if self.parallel {
                self.controllers
                    .par_iter_mut()
                    .enumerate()
                    .with_min_len(256)
                    .for_each_init(|| SensorScratch::new(m), |scratch, (i, ctrl)| ctx.warm(i, ctrl.as_mut(), scratch));
            } else {
                let mut scratch = SensorScratch::new(m);
                for (i, ctrl) in self.controllers.iter_mut().enumerate() {
                    ctx.warm(i, ctrl.as_mut(), &mut scratch);
                }
            }
        }
        std::mem::swap(&mut self.current, &mut self.next);
        for c in self.controllers.iter_mut().flatten() {
            c.forget_own_prediction();
        }
    }

    /// Forces serial or parallel stepping within the run (results are identical).
    pub fn with_parallel(mut self, parallel: bool) -> Self {
        self.parallel = parallel;
        self
    }

    /// Current step index.
    pub fn k(&self) -> u64 {
        self.k
    }

    /// Current time (s).
    pub fn t(&self) -> f64 {
        self.k as f64 * self.scenario.dt_s
    }

    /// Current true states.
    pub fn states(&self) -> &[State9] {
        &self.current
    }

    /// Bytes held by the engine's per-UAV buffers, the grid and the controllers (shared
    /// setup and scenario excluded).
    pub fn heap_bytes(&self) -> usize {
        let n = self.current.len();
        let controllers: usize = self
            .controllers
            .iter()
            .flatten()
            .map(|c| c.heap_bytes() + std::mem::size_of::<FormationController>())
            .sum();
        n * (2 * std::mem::size_of::<State9>() + std::mem::size_of::<UavStep>()) + self.grid.heap_bytes() + controllers
    }

    fn frame(&self) -> StepFrame<'_> {
        StepFrame { k: self.k, t: self.t(), states: &self.current, uavs: &self.uavs, active: &self.active }
    }

    /// Applies the schedule at the current time: removals, joins, and the sensor and radio
    /// faults in force.
    fn apply_faults(&mut self) {
        let sc = self.scenario;
        if sc.faults.is_empty() {
            return;
        }
        let t = self.t();
        let nav = sc.navigator.index();
        for f in &sc.faults {
            match *f {
                Fault::Remove { uav, .. } => self.active[uav.index()] = faults::is_active(&sc.faults, uav.index(), t),
                Fault::Join { uav, offset_m, .. } => {
                    let i = uav.index();
                    let now = faults::is_active(&sc.faults, i, t);
                    if now && !self.active[i] {
                        // Appears in its slot relative to the navigator (or to the formation's
                        // estimate of it), shifted by the offset.
                        let reference = crate::observer::navigator_reference(sc, &self.current, &self.active);
                        let f = &sc.formation;
                        let mut s = reference + f.w(&f.slots[i], &f.slots[nav], &reference);
                        s[0] += offset_m.x;
                        s[1] += offset_m.y;
                        s[2] += offset_m.z;
                        self.current[i] = s;
                    }
                    self.active[i] = now;
                }
                _ => {}
            }
        }
        let (seed, run, k) = (self.seed, self.run, self.k);
        let sigma = sc.noise.sigma();
        let current = &self.current;
        self.faults = faults::gather(&sc.faults, t, &self.faults, |i| {
            let mut rng = StepRng::new(stream_key(seed, run, i as u64, Source::OwnState), k);
            noisy(&current[i], &sigma, &mut rng)
        });
    }

    /// Advances one update period.
    pub fn step(&mut self) {
        self.apply_faults();
        let sc = self.scenario;
        let range = sc.controller.areas.sensing_range_m;
        if self.search == NeighbourSearch::Grid {
            self.rebuild_grid(range);
        }
        let (k, t) = (self.k, self.t());
        if !self.env.is_empty() {
            let (seed, run, current, active) = (self.seed, self.run, &self.current, &self.active);
            let adv = |(i, e): (usize, &mut crate::environment::UavEnv)| {
                if active[i] {
                    crate::environment::advance(sc, seed, run, k, t, i, &current[i], e);
                }
            };
            if self.parallel {
                self.env.par_iter_mut().enumerate().with_min_len(1024).for_each(adv);
            } else {
                self.env.iter_mut().enumerate().for_each(adv);
            }
        }
        let delay = u64::from(sc.radio.delay_steps);
        if delay > 0 {
            let mut old =
                if self.history.len() as u64 > delay { self.history.pop_front() } else { None }.unwrap_or_default();
            old.clear();
            old.extend_from_slice(&self.current);
            self.history.push_back(old);
        }
        let sent = if delay == 0 {
            Some((&self.current[..], k))
        } else if self.history.len() as u64 == delay + 1 {
            self.history.front().map(|h| (&h[..], k - delay))
        } else {
            None
        };
        fill_broadcasts(sc, self.seed, self.run, sent, self.parallel, &mut self.broadcasts);
        let ctx = step_context!(self, k, t, sent, &self.env, false);
        let m = sc.controller.areas.areas;
        if self.parallel {
            self.controllers
                .par_iter_mut()
                .zip(self.next.par_iter_mut())
                .zip(self.uavs.par_iter_mut())
                .enumerate()
                .with_min_len(256)
                .for_each_init(
                    || SensorScratch::new(m),
                    |scratch, (i, ((ctrl, next), aux))| ctx.update(i, ctrl.as_mut(), next, aux, scratch),
                );
        } else {
            let mut scratch = SensorScratch::new(m);
            for (i, ((ctrl, next), aux)) in
                self.controllers.iter_mut().zip(self.next.iter_mut()).zip(self.uavs.iter_mut()).enumerate()
            {
                ctx.update(i, ctrl.as_mut(), next, aux, &mut scratch);
            }
        }
        std::mem::swap(&mut self.current, &mut self.next);
        self.k += 1;
    }

    /// Runs the whole flight, showing every step (and the initial state) to `observer`.
    pub fn run(self, observer: &mut impl Observer) {
        let steps = self.scenario.steps();
        self.run_steps(steps, observer);
    }

    /// Runs `steps` update periods (or fewer if the flight ends first).
    pub fn run_steps(mut self, steps: u64, observer: &mut impl Observer) {
        if self.k == 0 {
            self.perceive_initial();
            observer.on_step(self.scenario, &self.frame());
        }
        let end = (self.k + steps).min(self.scenario.steps());
        while self.k < end {
            self.step();
            observer.on_step(self.scenario, &self.frame());
        }
    }

    fn rebuild_grid(&mut self, range: f64) {
        let active = &self.active;
        self.grid.rebuild_ids(
            self.current.iter().enumerate().filter(|(i, _)| active[*i]).map(|(i, s)| (i as u32, [s[0], s[1], s[2]])),
            range,
        );
    }

    /// Nearest-neighbour distances of the initial state, for the separation metric.
    fn perceive_initial(&mut self) {
        let range = self.scenario.controller.areas.sensing_range_m;
        self.rebuild_grid(range);
        for (i, s) in self.current.iter().enumerate() {
            if !self.active[i] {
                continue;
            }
            let mut best = (f64::INFINITY, u32::MAX);
            self.grid.for_each_within([s[0], s[1], s[2]], range, |j, _, d2| {
                if j as usize != i && d2 < best.0 {
                    best = (d2, j);
                }
            });
            self.uavs[i].nearest_m = best.0.sqrt();
            self.uavs[i].nearest_id = best.1;
        }
    }
}

/// The radio messages arriving now (none before the first arrives, or without broadcasters).
fn fill_broadcasts(
    sc: &Scenario,
    seed: u64,
    run: u64,
    sent: Option<(&[State9], u64)>,
    parallel: bool,
    out: &mut Vec<(u32, State9)>,
) {
    match sent {
        Some((states, send_k)) => crate::sensing::broadcasts(
            &sc.radio,
            &sc.beacons,
            states,
            &sc.noise.sigma(),
            seed,
            run,
            send_k,
            parallel,
            out,
        ),
        None => out.clear(),
    }
}

/// The controllers' parameters: the scenario's, with separation keeping at twice the safety
/// distance unless the scenario sets it.
pub fn controller_params(scenario: &Scenario) -> proxform_core::ControllerParams {
    let mut p = scenario.controller.clone();
    p.separation_m = Some(p.separation_m.unwrap_or(SEPARATION_PER_SAFETY * scenario.safety_distance_m));
    p
}

/// Default separation-keeping distance, in safety distances.
pub const SEPARATION_PER_SAFETY: f64 = 2.0;

/// Read-only view of one step, shared by the threads that update the UAVs.
struct StepContext<'a> {
    scenario: &'a Scenario,
    /// The (seed, run) part of the run's stream keys ([`crate::rng::run_key`]).
    run_key: u64,
    /// The step's part of its generators ([`crate::rng::step_part`]).
    step_part: u64,
    t: f64,
    start: [f64; 3],
    current: &'a [State9],
    grid: &'a NeighbourGrid,
    sensor: &'a ProximitySensor,
    search: NeighbourSearch,
    active: &'a [bool],
    faults: &'a FaultStep,
    /// True states when the radio messages arriving now were sent, and that step.
    sent: Option<(&'a [State9], u64)>,
    /// The radio messages arriving now.
    broadcasts: &'a [(u32, State9)],
    /// Per-UAV environment (empty when the scenario needs none).
    env: &'a [crate::environment::UavEnv],
    /// Warm-up step: perceive and decide, change nothing.
    warm: bool,
}

/// Step counters of the warm-up draws, far from those of the flight.
const WARMUP_STEP_BASE: u64 = 1 << 62;

impl<'a> StepContext<'a> {
    /// The generator of stream `source` of the UAV of `uav_key` at this step: the same as
    /// `StepRng::new(stream_key(seed, run, uav, source), k)`, with the run's and the step's
    /// parts of the key mixed once.
    #[inline]
    fn rng(&self, uav_key: u64, source: Source) -> StepRng {
        StepRng::at(source_key(uav_key, source), self.step_part)
    }

    /// What the links allow UAV updates this step.
    fn link(&self, radio: &'a RadioModel, dropout: f64, radio_up: bool, channel_bad: bool, delay_s: f64) -> Link<'a> {
        Link {
            active: self.active,
            dropout,
            reference_dropout: self.scenario.reference_dropout.unwrap_or(dropout),
            radio_up,
            radio,
            sent: self.sent.map(|s| s.0),
            broadcasts: self.broadcasts,
            delay_s,
            channel_bad,
            onboard: self.scenario.method.uses_onboard_sensing(),
        }
    }

    /// UAV `i`'s perception this step (into `scratch.observations`): its nearest neighbour's
    /// distance and id.
    fn perceive(
        &self,
        i: usize,
        uav_key: u64,
        link: &Link<'_>,
        radio_rng: &mut StepRng,
        scratch: &mut SensorScratch,
    ) -> (f64, u32) {
        let sc = self.scenario;
        let mut rng = self.rng(uav_key, Source::Sensing);
        self.sensor.perceive(
            i,
            self.current,
            self.search,
            self.grid,
            &sc.dependencies[i],
            link,
            &mut rng,
            radio_rng,
            scratch,
        )
    }

    /// A warm-up update of UAV `i`: perception and decision, nothing applied.
    fn warm(&self, i: usize, ctrl: Option<&mut FormationController>, scratch: &mut SensorScratch) {
        debug_assert!(self.warm);
        let Some(ctrl) = ctrl else { return };
        if !self.active[i] {
            return;
        }
        let sc = self.scenario;
        let uk = uav_key(self.run_key, i as u64);
        let ideal = sc.radio.ideal();
        let link = self.link(&ideal, 0.0, true, false, 0.0);
        let mut radio_rng = self.rng(uk, Source::Radio);
        self.perceive(i, uk, &link, &mut radio_rng, scratch);
        let mut rng = self.rng(uk, Source::OwnState);
        let own = noisy(&self.current[i], &sc.noise.sigma(), &mut rng);
        ctrl.step(self.t, &own, &scratch.observations);
    }

    /// Updates UAV `i`: perception, decision, plant.
    #[inline]
    fn update(
        &self,
        i: usize,
        ctrl: Option<&mut FormationController>,
        next: &mut State9,
        aux: &mut UavStep,
        scratch: &mut SensorScratch,
    ) {
        let sc = self.scenario;
        let dt = sc.dt_s;
        let uk = uav_key(self.run_key, i as u64);
        if !self.active[i] {
            *next = self.current[i];
            *aux = UavStep::default();
            return;
        }
        let env = self.env.get(i);
        let mut radio_rng = self.rng(uk, Source::Radio);
        let bad = env.is_some_and(|e| e.channel_bad);
        let link = self.link(&sc.radio, sc.dropout, self.faults.radio_up, bad, f64::from(sc.radio.delay_steps) * dt);
        let nearest = self.perceive(i, uk, &link, &mut radio_rng, scratch);
        (aux.nearest_m, aux.nearest_id) = nearest;
        aux.radio_msgs = scratch.observations.iter().filter(|o| o.source == ObservationSource::Radio).count() as u16;
        let Some(ctrl) = ctrl else {
            *next = sc.path.state_at(self.t + dt, self.start);
            aux.outcome = None;
            aux.model_error = [0.0; 9];
            return;
        };
        let me = &self.current[i];
        let mut rng = self.rng(uk, Source::OwnState);
        let mut own = noisy(me, &sc.noise.sigma(), &mut rng);
        if let Some(e) = env {
            for k in 0..3 {
                own[k] += e.gnss_bias[k];
            }
        }
        self.faults.corrupt(i, &mut own);
        let decision = ctrl.step(self.t, &own, &scratch.observations);
        let commanded = if sc.adjustment_enabled { decision.input } else { Input::zeros() };
        let applied = if matches!(decision.outcome, Outcome::Adjusted { .. }) && sc.actuation_error > 0.0 {
            let mut rng = self.rng(uk, Source::Actuation);
            commanded.map(|u| u * (1.0 + sc.actuation_error * rng.random_range(-1.0..=1.0)))
        } else {
            commanded
        };
        // The model error is zero when the input was applied as commanded: the plant is then
        // propagated once.
        let exact = applied == commanded;
        let model_error = if sc.wind.is_calm() {
            *next = sc.vehicle.propagate(me, &applied, dt);
            if exact {
                State9::zeros()
            } else {
                proxform_core::state::difference(next, &sc.vehicle.propagate(me, &commanded, dt))
            }
        } else {
            // The vehicle moves through the air; the wind carries it (crate::disturbance).
            let e = env.copied().unwrap_or_default();
            let (w_now, w_next) = (e.wind_now, e.wind_next);
            let mut air = *me;
            for k in 0..3 {
                air[3 + k] -= w_now[k];
            }
            let carry = |mut x: State9| {
                for k in 0..3 {
                    x[3 + k] += w_next[k];
                    x[k] += 0.5 * dt * (w_now[k] + w_next[k]);
                }
                x
            };
            *next = carry(sc.vehicle.propagate(&air, &applied, dt));
            if exact {
                State9::zeros()
            } else {
                proxform_core::state::difference(next, &carry(sc.vehicle.propagate(&air, &commanded, dt)))
            }
        };
        aux.model_error = std::array::from_fn(|k| model_error[k] as f32);
        aux.outcome = Some(decision.outcome);
        let scale = ctrl.vehicle().input_scale(dt);
        aux.effort = (0..ctrl.vehicle().n_inputs())
            .map(|j| if scale[j] > 0.0 { (decision.input[j] / scale[j]).powi(2) } else { 0.0 })
            .sum::<f64>()
            .sqrt() as f32;
    }
}
