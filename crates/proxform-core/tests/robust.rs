//! The robust fusion (`isolation_gate`) and the own-sensor check (`own_gate_m`) on hand-made
//! observations (METHOD §8).

use std::sync::Arc;

use proxform_core::angle::kmh;
use proxform_core::state::{State9, VX, X, Y};
use proxform_core::{
    Agent, AgentSetup, ControllerParams, ControllerSetup, DependencySet, Formation, FormationFrame, FormationSlot,
    KinematicModel, Method, Observation, ObservationSource, Outcome, PredictorKind, ProximityController, UavId,
    VehicleModel,
};

/// The navigator (0) ahead, UAVs 1 and 2 ahead-left and ahead-right, UAVs 3 and 4 a little
/// behind left and right of UAV 5, which leans on 1 and 2; each in its own azimuth area (no
/// bearing on an area boundary). Upstream of UAV 5 (no farther from the navigator): 0, 1, 2;
/// downstream: 3, 4.
fn formation() -> Arc<Formation> {
    let at = |x, y| FormationSlot::at(x, y, 0.0);
    Arc::new(Formation {
        slots: vec![
            at(0.0, 0.0),
            at(-100.0, 120.0),
            at(-120.0, -90.0),
            at(-230.0, 150.0),
            at(-230.0, -70.0),
            at(-200.0, 40.0),
        ],
        frame: FormationFrame::World,
    })
}

fn params(gate: Option<f64>) -> ControllerParams {
    ControllerParams { predictor: PredictorKind::ConstantVelocity, isolation_gate: gate, ..ControllerParams::default() }
}

fn deps() -> DependencySet {
    DependencySet::new(UavId(5), 6, vec![(UavId(1), 0.5), (UavId(2), 0.5)]).expect("valid table")
}

fn controller(gate: Option<f64>) -> ProximityController {
    ProximityController::standalone(
        UavId(5),
        params(gate),
        formation(),
        deps(),
        VehicleModel::Kinematic(KinematicModel::default()),
    )
    .expect("valid")
    .with_navigator(UavId(0))
}

fn in_slot(i: usize) -> State9 {
    let s = formation().slots[i];
    let mut x = State9::zeros();
    x[X] = s.offset_m.x;
    x[Y] = s.offset_m.y;
    x[VX] = kmh(250.0);
    x
}

fn seen(i: u32, s: State9) -> Observation {
    Observation { id: UavId(i), state: s, age_s: 0.0, source: ObservationSource::Onboard }
}

/// Everyone but UAV 5 in its slot, `off` (m, to the left) added to the listed UAVs.
fn scene(displaced: &[u32], off: f64) -> Vec<Observation> {
    (0..5)
        .map(|i| {
            let mut s = in_slot(i as usize);
            if displaced.contains(&i) {
                s[Y] += off;
            }
            seen(i, s)
        })
        .collect()
}

/// UAV 5 0.3 m right of its slot: out of its envelope (ρ·Δy = 0.24 m), so that it adjusts,
/// and within the input's rate limit.
fn own() -> State9 {
    let mut s = in_slot(5);
    s[Y] -= 0.3;
    s
}

#[test]
fn a_neighbour_far_from_the_others_is_left_out_as_if_unseen() {
    let with_fault = scene(&[2], 10.0);
    let decided = controller(Some(1.0)).step(0.0, &own(), &with_fault);
    assert_eq!(decided.isolated, 1, "{decided:?}");
    // Left out, UAV 2 weighs nothing: the decision is the one taken without seeing it at all.
    let without: Vec<Observation> = with_fault.iter().copied().filter(|o| o.id != UavId(2)).collect();
    let unseen = controller(Some(1.0)).step(0.0, &own(), &without);
    assert_eq!(decided.input, unseen.input);
    assert_eq!((decided.occupied_areas, decided.main_refs), (unseen.occupied_areas, unseen.main_refs));
    // Without the fusion, the displaced UAV drags UAV 5 to the left (its input differs).
    let plain = controller(None).step(0.0, &own(), &with_fault);
    assert_eq!(plain.isolated, 0);
    assert!(decided.input[1] > 0.0 && decided.input[1] < 0.45, "{:?}", decided.input);
    assert!(plain.input[1] > decided.input[1] + 0.05, "{:?} vs {:?}", plain.input, decided.input);
    // A neighbour within the gate keeps its full weight.
    let near = controller(Some(1.0)).step(0.0, &own(), &scene(&[2], 0.3));
    let near_plain = controller(None).step(0.0, &own(), &scene(&[2], 0.3));
    assert_eq!((near.isolated, near.input), (0, near_plain.input));
}

#[test]
fn the_navigator_is_never_left_out_and_followers_behind_do_not_outvote_those_ahead() {
    let nav_off = controller(Some(1.0)).step(0.0, &own(), &scene(&[0], 10.0));
    assert_eq!(nav_off.isolated, 0, "the navigator defines the formation");
    // UAVs 1 and 2 (ahead, the references) move 10 m left together; UAVs 3 and 4 (abeam, at the
    // same distance behind the navigator as UAV 5 or farther) stay: the median is taken over
    // the UAVs ahead, so the two abeam are the ones left out.
    // UAV 5 in its slot: it moves only if it follows UAVs 1 and 2.
    let refs_moved = controller(Some(1.0)).step(0.0, &in_slot(5), &scene(&[1, 2], 10.0));
    assert_eq!(refs_moved.isolated, 2, "{refs_moved:?}");
    assert!(refs_moved.input[1] > 0.1, "it follows its references to the left: {:?}", refs_moved.input);
}

#[test]
fn with_fewer_than_three_estimates_ahead_the_navigator_or_the_own_course_decides() {
    let seen = |ids: &[u32], moved: &[u32]| -> Vec<Observation> {
        scene(moved, 10.0).into_iter().filter(|o| ids.contains(&o.id.0)).collect()
    };
    let step = |obs: &[Observation]| controller(Some(1.0)).step(0.0, &in_slot(5), obs);
    // The navigator, 1 and the displaced 3: the others are weighed against the navigator.
    assert_eq!(step(&seen(&[0, 1, 3], &[3])).isolated, 1);
    // No navigator, two references ahead (1 and 2) of which 2 wanders off: the UAV's own
    // course breaks the tie, so 2 is left out and the UAV holds.
    let d = step(&seen(&[1, 2, 3, 4], &[2]));
    assert_eq!((d.isolated, d.outcome), (1, Outcome::Held), "{d:?}");
    // Both move together: they are followed, and the two behind left out.
    let d = step(&seen(&[1, 2, 3, 4], &[1, 2]));
    assert_eq!(d.isolated, 2, "{d:?}");
    assert!(d.input[1] > 0.1, "{d:?}");
    // One reference ahead: the others are weighed against it.
    assert_eq!(step(&seen(&[1, 3, 4], &[3])).isolated, 1);
    // None ahead: nothing is weighed.
    assert_eq!(step(&seen(&[3, 4], &[3])).isolated, 0);
}

fn agent(own_gate_m: Option<f64>) -> Agent {
    let p = ControllerParams { own_gate_m, ..params(None) };
    let setup = ControllerSetup::new(p, VehicleModel::Kinematic(KinematicModel::default())).expect("valid");
    let tables = (0..6).map(|i| if i == 5 { deps() } else { DependencySet::default() }).collect();
    let setup = AgentSetup::new(Method::Proximity, UavId(0), setup, formation(), tables).expect("valid");
    Agent::new(&setup, UavId(5)).expect("a follower")
}

/// The scene and UAV 5's true state at step k: everyone cruising along x in its slot.
fn at_step(k: u32) -> (State9, Vec<Observation>) {
    let t = f64::from(k) * 0.1;
    let shift = |mut s: State9| {
        s[X] += kmh(250.0) * t;
        s
    };
    (shift(in_slot(5)), (0..5).map(|i| seen(i, shift(in_slot(i as usize)))).collect())
}

#[test]
fn a_stuck_own_sensor_is_refused_and_flown_through_on_the_prediction() {
    let mut checked = agent(Some(3.0));
    let mut trusting = agent(None);
    let (stuck, _) = at_step(10);
    for k in 0..40 {
        let (truth, scene) = at_step(k);
        // Steps 10 to 19: the sensor repeats its reading of step 10.
        let measured = if (10..20).contains(&k) { stuck } else { truth };
        let a = checked.step(f64::from(k) * 0.1, &measured, &scene);
        let b = trusting.step(f64::from(k) * 0.1, &measured, &scene);
        // From step 11 the frozen reading falls behind the prediction by 6.9 m a step.
        assert_eq!(a.own_suspect, (11..20).contains(&k), "step {k}: {a:?}");
        assert!(!b.own_suspect);
        if (11..20).contains(&k) {
            assert_eq!(a.outcome, Outcome::Held, "step {k}: on its prediction it is in its slot");
            assert!(matches!(b.outcome, Outcome::Adjusted { .. }), "step {k}: the stuck reading looks far behind");
        }
    }
}

#[test]
fn a_lasting_offset_is_accepted_once_the_prediction_can_no_longer_be_trusted() {
    // The own position reads 20 m to the left from step 5 on, for good: the readings still
    // move, so the UAV dead-reckons with their velocity and the gate (3 m) widens by the dead
    // reckoning's drift (OWN_DRIFT_MPS, 0.25 m/s) while they are refused: the offset is
    // accepted after about 68 s (17 s when it widened at 1 m/s whatever the readings).
    let mut a = agent(Some(3.0));
    let mut refused = 0;
    for k in 0..800 {
        let (mut measured, scene) = at_step(k);
        if k >= 5 {
            measured[Y] += 20.0;
        }
        if a.step(f64::from(k) * 0.1, &measured, &scene).own_suspect {
            refused += 1;
        }
    }
    assert!((675..=685).contains(&refused), "{refused} steps refused");
}
