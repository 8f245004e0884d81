//! What one UAV owns, and its step: the piece the simulator, a network agent and Python share.
//!
//! An [`Agent`] owns its formation controller (whichever the method), its neighbour tracks
//! (inside the controller) and its estimate of its own state. One [`Agent::step`] is one update
//! period: the UAV's own measurement and what reached it since the last period (onboard
//! detections, radio messages) in, its [`Decision`] out. Where the observations come from,
//! noise, actuation and the plant stay outside it.

use std::sync::Arc;

use crate::assignment::{relabel, Reassignment};
use crate::controller::{ControllerSetup, Decision};
use crate::dependency::DependencySet;
use crate::error::ConfigError;
use crate::formation::Formation;
use crate::method::{FormationController, Method};
use crate::observation::{Observation, UavId};
use crate::own_estimate::OwnEstimate;
use crate::schedule::FormationSchedule;
use crate::state::State9;
use crate::vehicle::{Setpoint, VehicleModel};

/// What every agent of a formation shares: the method, the navigator (the baselines' leader),
/// the controller setup, the formation and every UAV's dependency table.
#[derive(Debug, Clone)]
pub struct AgentSetup {
    method: Method,
    navigator: UavId,
    controller: Arc<ControllerSetup>,
    formation: Arc<Formation>,
    dependencies: Vec<DependencySet>,
    /// Changes of formation in flight (none by default).
    schedule: Arc<FormationSchedule>,
}

impl AgentSetup {
    /// Checks that the navigator and every table belong to the formation.
    pub fn new(
        method: Method,
        navigator: UavId,
        controller: Arc<ControllerSetup>,
        formation: Arc<Formation>,
        dependencies: Vec<DependencySet>,
    ) -> Result<Self, ConfigError> {
        let n = formation.len();
        if navigator.index() >= n {
            return Err(ConfigError::UnknownUav { id: navigator, size: n });
        }
        if dependencies.len() != n {
            return Err(ConfigError::OutOfRange {
                field: "dependency tables",
                value: dependencies.len() as f64,
                expected: "one table per slot of the formation",
            });
        }
        method.validate()?;
        Ok(Self { method, navigator, controller, formation, dependencies, schedule: Arc::default() })
    }

    /// The same agents, changing formation in flight as `schedule` says (checked against the
    /// first formation's size).
    pub fn with_schedule(mut self, schedule: FormationSchedule) -> Result<Self, ConfigError> {
        let schedule = FormationSchedule::new(schedule.stages().to_vec(), self.formation.len())?;
        for stage in schedule.stages() {
            if stage.formation.slot(self.navigator).is_none() {
                return Err(ConfigError::UnknownUav { id: self.navigator, size: stage.formation.len() });
            }
        }
        self.schedule = Arc::new(schedule);
        Ok(self)
    }

    /// The changes of formation in flight.
    pub fn schedule(&self) -> &FormationSchedule {
        &self.schedule
    }

    /// The followers' method.
    pub fn method(&self) -> &Method {
        &self.method
    }

    /// The navigator.
    pub fn navigator(&self) -> UavId {
        self.navigator
    }

    /// The controller setup (parameters, vehicle, derived quantities).
    pub fn controller(&self) -> &Arc<ControllerSetup> {
        &self.controller
    }

    /// The formation.
    pub fn formation(&self) -> &Arc<Formation> {
        &self.formation
    }

    /// Every UAV's dependency table.
    pub fn dependencies(&self) -> &[DependencySet] {
        &self.dependencies
    }
}

/// One UAV: its controller, its tracks and its own-state estimate.
#[derive(Debug, Clone)]
pub struct Agent {
    controller: FormationController,
    /// The changes of formation still to come, with what the controller is rebuilt from
    /// (None when the formation never changes: agents of a swarm stay small).
    changes: Option<Box<Changes>>,
    /// Its estimate of its own state: the own-sensor check and the own-state filter.
    own: OwnEstimate,
    /// The setpoint its autopilot flies, for a vehicle flown by setpoints (None before the
    /// first adjustment, and for the other vehicles; boxed so that their agents stay small).
    setpoint: Option<Box<Setpoint>>,
}

/// What an agent needs to switch formation: the schedule, the next stage, and what its
/// controller is built from.
#[derive(Debug, Clone)]
struct Changes {
    schedule: Arc<FormationSchedule>,
    next: usize,
    /// Slots re-assigned in flight (None: every UAV keeps its own): later stages are flown
    /// relabelled by it.
    assignment: Option<Reassignment>,
    id: UavId,
    method: Method,
    navigator: UavId,
    setup: Arc<ControllerSetup>,
}

impl Changes {
    /// UAV `id`'s, before the first stage.
    fn new(setup: &AgentSetup, id: UavId) -> Box<Self> {
        Box::new(Self {
            schedule: setup.schedule.clone(),
            next: 0,
            assignment: None,
            id,
            method: setup.method,
            navigator: setup.navigator,
            setup: setup.controller.clone(),
        })
    }
}

impl Agent {
    /// The agent of follower `id`.
    pub fn new(setup: &AgentSetup, id: UavId) -> Result<Self, ConfigError> {
        let deps = setup.dependencies.get(id.index()).cloned().unwrap_or_default();
        let controller = FormationController::new(
            &setup.method,
            id,
            setup.navigator,
            setup.controller.clone(),
            setup.formation.clone(),
            deps,
        )?;
        let changes = (!setup.schedule.is_empty()).then(|| Changes::new(setup, id));
        Ok(Self { controller, changes, own: OwnEstimate::default(), setpoint: None })
    }

    /// Switches to the formation in force at `now_s`: the controller is set up afresh for its
    /// slots and tables (its neighbour tracks restart from the next observations).
    fn follow_schedule(&mut self, now_s: f64) {
        let Some(ch) = self.changes.as_deref_mut() else { return };
        let stages = ch.schedule.stages();
        let mut switched = None;
        while ch.next < stages.len() && now_s >= stages[ch.next].at_s - 1e-9 {
            switched = Some(ch.next);
            ch.next += 1;
        }
        let Some(k) = switched else { return };
        let stage = &stages[k];
        let (formation, deps) = match &ch.assignment {
            None => (stage.formation.clone(), stage.dependencies.get(ch.id.index()).cloned().unwrap_or_default()),
            Some(a) => {
                let (f, mut tables) = relabel(&stage.formation, &stage.dependencies, &a.slot_of, &a.flying, a.lead);
                let own = std::mem::take(&mut tables[ch.id.index()]);
                (Arc::new(f), own)
            }
        };
        let setup = ch.setup.clone();
        // The stage was checked with the first formation's setup: the same UAVs, the same
        // navigator, tables of slots of its own formation (relabelled, of UAVs of it).
        self.controller = FormationController::new(&ch.method, ch.id, ch.navigator, setup, formation, deps)
            .expect("a checked schedule's stages are valid for every UAV");
    }

    /// Flies the slots of `assignment` from now on, led by its leader (and the later stages
    /// of the schedule relabelled by it). When slots moved, the controller is set up afresh
    /// for UAV `id`'s new slot and table (its neighbour tracks restart from the next
    /// observations), as at a change of formation; when only the leader changed (a
    /// succession), the proximity controller keeps what it knows of its neighbours.
    pub fn reassign(&mut self, setup: &AgentSetup, id: UavId, assignment: &Reassignment) -> Result<(), ConfigError> {
        let table = assignment.tables.get(id.index()).cloned().unwrap_or_default();
        let leader = assignment.lead.leader;
        match &mut self.controller {
            FormationController::Proximity(c) if !assignment.moved => {
                c.lead_by(leader, assignment.formation.clone(), table)?;
            }
            _ => {
                self.controller = FormationController::new(
                    &setup.method,
                    id,
                    leader,
                    setup.controller.clone(),
                    assignment.formation.clone(),
                    table,
                )?;
            }
        }
        // Without a schedule there is no stage to come (next = 0 = the number of stages).
        let ch = self.changes.get_or_insert_with(|| Changes::new(setup, id));
        ch.assignment = Some(assignment.clone());
        ch.navigator = leader;
        Ok(())
    }

    /// One update period at `now_s`: `own_measured` is the UAV's measurement of its own state,
    /// `heard` what reached it (a UAV reported more than once counts once). The own-sensor
    /// check (`own_gate_m`) refuses a measurement too far from the UAV's own prediction and
    /// flies on the prediction instead; the own-state filter (gain < 1) blends an accepted
    /// measurement with the prediction; then the controller decides.
    pub fn step(&mut self, now_s: f64, own_measured: &State9, heard: &[Observation]) -> Decision {
        self.follow_schedule(now_s);
        let params = self.controller.setup().params();
        let dt = params.dt_s;
        let (own, suspect) = self.own.estimate(params, now_s, own_measured);
        let mut decision = self.controller.step(now_s, &own, heard);
        decision.own_suspect = suspect;
        let vehicle = self.controller.setup().vehicle();
        // The autopilot of a vehicle flown by setpoints flies the last one it was given.
        match (decision.take_setpoint(vehicle, &own, dt, self.setpoint.as_deref()), self.setpoint.as_deref_mut()) {
            // (The box is allocated once and reused.)
            (Some(sp), Some(kept)) => *kept = sp,
            (sp, _) => self.setpoint = sp.map(Box::new),
        }
        let setup = self.controller.setup();
        if OwnEstimate::used(setup.params()) {
            // What the vehicle flies: its setpoint where it is flown by one.
            self.own.expect(setup, now_s, (&own, own_measured), &decision.flown_input(setup.vehicle(), &own));
        }
        decision
    }

    /// Its own state one period after `own`, under `decision` acting over that period (its
    /// setpoint where the vehicle flies one; None: holding its course, no new input), by the
    /// vehicle's model (the fixed wing carried by the wind its state implies). An agent on its
    /// own clock brings an update forward to the period its next command will act in, through
    /// the commands already on their way.
    pub fn predict_period(&self, own: &State9, decision: Option<&Decision>) -> State9 {
        let setup = self.controller.setup();
        let (vehicle, dt) = (setup.vehicle(), setup.params().dt_s);
        let input = decision.map_or_else(crate::Input::zeros, |d| d.flown_input(vehicle, own));
        vehicle.predict(own, &input, dt)
    }

    /// Forgets the own-state prediction and the setpoint (after inputs that were not applied,
    /// such as a warm-up's).
    pub fn forget_own_estimate(&mut self) {
        self.own.forget();
        self.setpoint = None;
    }

    /// What this UAV knows of the navigator at `now_s`, to forward (its state at its last
    /// measurement and that measurement's age, s; with relative sensing, relative to its own
    /// fix): see `radio.relay_navigator`.
    pub fn navigator_report(&self, now_s: f64) -> Option<crate::NavigatorReport> {
        self.controller.navigator_report(now_s)
    }

    /// The vehicle model.
    pub fn vehicle(&self) -> &VehicleModel {
        self.controller.setup().vehicle()
    }

    /// The controller.
    pub fn controller(&self) -> &FormationController {
        &self.controller
    }

    /// Bytes held on the heap (shared setup and formation excluded).
    pub fn heap_bytes(&self) -> usize {
        self.controller.heap_bytes()
            + self.own.heap_bytes()
            + self.changes.as_ref().map_or(0, |_| std::mem::size_of::<Changes>())
            + self.setpoint.as_ref().map_or(0, |_| std::mem::size_of::<Setpoint>())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::{ControllerParams, Outcome};
    use crate::formation::{FormationFrame, FormationSlot};
    use crate::observation::ObservationSource;
    use crate::state::{VX, Y};
    use crate::vehicle::KinematicModel;

    fn setup(gain: f64) -> AgentSetup {
        let params = ControllerParams { own_filter_gain: gain, ..ControllerParams::default() };
        let controller =
            ControllerSetup::new(params, VehicleModel::Kinematic(KinematicModel::default())).expect("valid");
        let slots = vec![FormationSlot::at(0.0, 0.0, 0.0), FormationSlot::at(-100.0, 50.0, 0.0)];
        let formation = Arc::new(Formation::new(slots, FormationFrame::World).expect("finite"));
        let deps =
            vec![DependencySet::default(), DependencySet::new(UavId(1), 2, vec![(UavId(0), 1.0)]).expect("valid")];
        AgentSetup::new(Method::Proximity, UavId(0), controller, formation, deps).expect("valid")
    }

    fn leader(t: f64) -> Observation {
        let mut s = State9::zeros();
        s[0] = 70.0 * t;
        s[VX] = 70.0;
        Observation { id: UavId(0), state: s, age_s: 0.0, source: ObservationSource::Onboard }
    }

    #[test]
    fn an_agent_in_its_slot_holds_and_one_off_its_slot_adjusts() {
        let setup = setup(1.0);
        let mut agent = Agent::new(&setup, UavId(1)).expect("a follower");
        let mut own = State9::zeros();
        own[0] = -100.0;
        own[Y] = 50.0;
        own[VX] = 70.0;
        for k in 0..5 {
            let t = k as f64 * 0.1;
            let mut me = own;
            me[0] += 70.0 * t;
            assert_eq!(agent.step(t, &me, &[leader(t)]).outcome, Outcome::Held, "step {k}");
        }
        let mut off = own;
        off[0] += 70.0 * 0.5;
        off[Y] += 3.0;
        let d = agent.step(0.5, &off, &[leader(0.5)]);
        assert!(matches!(d.outcome, Outcome::Adjusted { .. }), "{d:?}");
        assert!(d.input[1] < 0.0, "it moves right, back toward its slot: {:?}", d.input);
        // The leader missing for one period coasts on its track; gone for longer than
        // `coast_s`, nothing is left: alone.
        assert!(matches!(agent.step(0.6, &off, &[]).outcome, Outcome::Adjusted { .. }));
        assert_eq!(agent.step(2.0, &off, &[]).outcome, Outcome::Alone);
    }

    /// Two UAVs of `vehicle` 100 m apart side by side in a world frame, flying +x at `speed`,
    /// with the own-sensor check at `gate` (m).
    fn pair(vehicle: VehicleModel, speed: f64, gate: Option<f64>) -> (AgentSetup, State9, impl Fn(f64) -> Observation) {
        let params = ControllerParams { own_gate_m: gate, ..ControllerParams::default() };
        let controller = ControllerSetup::new(params, vehicle).expect("valid");
        let slots = vec![FormationSlot::at(0.0, 0.0, 0.0), FormationSlot::at(0.0, 100.0, 0.0)];
        let formation = Arc::new(Formation::new(slots, FormationFrame::World).expect("finite"));
        let deps =
            vec![DependencySet::default(), DependencySet::new(UavId(1), 2, vec![(UavId(0), 1.0)]).expect("valid")];
        let setup = AgentSetup::new(Method::Proximity, UavId(0), controller, formation, deps).expect("valid");
        let mut own = State9::zeros();
        own[Y] = 100.0;
        own[VX] = speed;
        let leader = move |t: f64| {
            let mut s = State9::zeros();
            s[0] = speed * t;
            s[VX] = speed;
            Observation { id: UavId(0), state: s, age_s: 0.0, source: ObservationSource::Onboard }
        };
        (setup, own, leader)
    }

    #[test]
    fn a_reading_frozen_in_place_is_refused_though_each_period_it_is_near_the_last() {
        // A multirotor at 10 m/s: a frozen reading is 1 m a period from the prediction made
        // from the last one, within the 3 m gate; it falls behind where the readings had
        // settled by about 10 m/s × OWN_SETTLE_S, and is refused within half a second.
        let (setup, own, leader) = pair(VehicleModel::Multirotor(crate::MultirotorModel::default()), 10.0, Some(3.0));
        let mut agent = Agent::new(&setup, UavId(1)).expect("a follower");
        let at = |t: f64| {
            let mut s = own;
            s[0] = 10.0 * t;
            s
        };
        for k in 0..50 {
            let t = k as f64 * 0.1;
            assert!(!agent.step(t, &at(t), &[leader(t)]).own_suspect, "healthy readings at {t} s");
        }
        let frozen = at(4.9);
        let refused_from = (50..70).find(|k| {
            let t = *k as f64 * 0.1;
            agent.step(t, &frozen, &[leader(t)]).own_suspect
        });
        assert!(refused_from.is_some_and(|k| k <= 55), "refused from step {refused_from:?}");
        // Refused to the end of the fault, then the live readings agree with the prediction.
        for k in refused_from.unwrap_or(70) + 1..100 {
            let t = k as f64 * 0.1;
            assert!(agent.step(t, &frozen, &[leader(t)]).own_suspect, "frozen reading at {t} s");
        }
        let back = (100..120).find(|k| {
            let t = *k as f64 * 0.1;
            !agent.step(t, &at(t), &[leader(t)]).own_suspect
        });
        assert_eq!(back, Some(100), "live readings accepted again at once");
    }

    #[test]
    fn a_reading_repeated_to_the_bit_while_the_uav_moves_is_stale() {
        // At 0.5 m/s a frozen reading would stay within the gate of both the prediction and
        // the settled position for long; repeated exactly, it is refused at once.
        let (setup, own, leader) = pair(VehicleModel::Multirotor(crate::MultirotorModel::default()), 0.5, Some(3.0));
        let mut agent = Agent::new(&setup, UavId(1)).expect("a follower");
        let at = |t: f64| {
            let mut s = own;
            s[0] = 0.5 * t;
            s
        };
        for k in 0..10 {
            let t = k as f64 * 0.1;
            assert!(!agent.step(t, &at(t), &[leader(t)]).own_suspect, "live at {t} s");
        }
        let frozen = at(0.9);
        for k in 10..20 {
            let t = k as f64 * 0.1;
            assert!(agent.step(t, &frozen, &[leader(t)]).own_suspect, "stale at {t} s");
        }
        assert!(!agent.step(2.0, &at(2.0), &[leader(2.0)]).own_suspect, "live again");
        // A UAV that does not move may read the same twice (a hover without noise).
        let (setup, mut still, leader) =
            pair(VehicleModel::Multirotor(crate::MultirotorModel::default()), 0.0, Some(3.0));
        still[VX] = 0.0;
        let mut agent = Agent::new(&setup, UavId(1)).expect("a follower");
        for k in 0..10 {
            assert!(!agent.step(k as f64 * 0.1, &still, &[leader(0.0)]).own_suspect);
        }
    }

    #[test]
    fn a_multirotor_flies_the_setpoint_it_chose_at_the_state_it_believed() {
        let (setup, own, leader) = pair(VehicleModel::Multirotor(crate::MultirotorModel::default()), 10.0, None);
        let mut agent = Agent::new(&setup, UavId(1)).expect("a follower");
        // In its slot it holds, and has been given no setpoint: the autopilot holds its own.
        let d = agent.step(0.0, &own, &[leader(0.0)]);
        assert_eq!((d.outcome, d.setpoint), (Outcome::Held, None));
        // One 5 m off to the left adjusts: the setpoint is what it believed plus its input.
        let mut agent = Agent::new(&setup, UavId(1)).expect("a follower");
        let mut off = own;
        off[Y] += 5.0;
        let d = agent.step(0.0, &off, &[leader(0.0)]);
        assert!(matches!(d.outcome, Outcome::Adjusted { .. }), "{d:?}");
        let sp = d.setpoint.expect("an adjustment gives a setpoint");
        assert_eq!(sp.velocity_mps, [off[VX] + d.input[0], off[VX + 1] + d.input[1], off[VX + 2] + d.input[2]]);
        assert!(sp.velocity_mps[1] < 0.0, "toward its slot: {sp:?}");
        // A period that holds keeps the autopilot on that setpoint, whatever the state now.
        let mut in_slot = own;
        in_slot[0] = 1.0;
        let later = agent.step(0.1, &in_slot, &[leader(0.1)]);
        assert_eq!((later.outcome, later.setpoint), (Outcome::Held, Some(sp)));
        // The kinematic vehicle's inputs act on the state it has: no setpoint.
        let (setup, own, leader) = pair(VehicleModel::Kinematic(KinematicModel::default()), 70.0, None);
        let mut agent = Agent::new(&setup, UavId(1)).expect("a follower");
        let mut off = own;
        off[Y] += 5.0;
        assert_eq!(agent.step(0.0, &off, &[leader(0.0)]).setpoint, None);
        // A warm-up's setpoint is forgotten with the own estimate.
        let (setup, own, leader) = pair(VehicleModel::Multirotor(crate::MultirotorModel::default()), 10.0, None);
        let mut agent = Agent::new(&setup, UavId(1)).expect("a follower");
        let mut off = own;
        off[Y] += 5.0;
        assert!(agent.step(0.0, &off, &[leader(0.0)]).setpoint.is_some());
        agent.forget_own_estimate();
        let mut in_slot = own;
        in_slot[0] = 1.0;
        let d = agent.step(0.1, &in_slot, &[leader(0.1)]);
        assert_eq!((d.outcome, d.setpoint), (Outcome::Held, None));
    }

    #[test]
    fn the_own_state_filter_blends_the_measurement_with_the_prediction() {
        // With gain 1 the measurement is used as is; with gain 0.5 a single jump of the
        // measurement moves the estimate half way, so the decisions differ.
        let setup_raw = setup(1.0);
        let setup_filtered = setup(0.5);
        let mut raw = Agent::new(&setup_raw, UavId(1)).expect("valid");
        let mut filtered = Agent::new(&setup_filtered, UavId(1)).expect("valid");
        let mut own = State9::zeros();
        own[0] = -100.0;
        own[Y] = 50.0;
        own[VX] = 70.0;
        raw.step(0.0, &own, &[leader(0.0)]);
        filtered.step(0.0, &own, &[leader(0.0)]);
        let mut jumped = own;
        jumped[0] += 7.0;
        jumped[Y] += 0.4;
        let a = raw.step(0.1, &jumped, &[leader(0.1)]);
        let b = filtered.step(0.1, &jumped, &[leader(0.1)]);
        assert_ne!(a.input, b.input);
        assert!(b.input[1].abs() < a.input[1].abs(), "{:?} vs {:?}", b.input, a.input);
        filtered.forget_own_estimate();
        assert!(filtered.heap_bytes() > 0);
    }
}
