//! Behaviour of one proximity controller on hand-made observations.

use std::sync::Arc;

use proxform_core::angle::{deg, kmh};
use proxform_core::state::{self, State9};
use proxform_core::{
    ControllerParams, DependencySet, Formation, FormationFrame, FormationSlot, KinematicModel, Observation,
    ObservationSource, Outcome, PredictorKind, ProximityController, UavId, VehicleModel,
};

fn formation() -> Arc<Formation> {
    Arc::new(Formation {
        slots: vec![
            FormationSlot::at(0.0, 0.0, 0.0),
            FormationSlot::at(-86.6, 50.0, -10.0),
            FormationSlot::at(-86.6, -50.0, -10.0),
            FormationSlot::at(-173.2, 0.0, -20.0),
        ],
        frame: FormationFrame::World,
    })
}

fn cruise_at(slot: &FormationSlot) -> State9 {
    State9::from_column_slice(&[
        slot.offset_m.x,
        slot.offset_m.y,
        slot.offset_m.z,
        kmh(250.0),
        0.0,
        0.0,
        deg(5.0),
        deg(3.0),
        0.0,
    ])
}

fn controller(params: ControllerParams) -> ProximityController {
    let f = formation();
    let deps = DependencySet::new(UavId(1), 4, vec![(UavId(0), 0.7), (UavId(2), 0.3)]).expect("valid table");
    ProximityController::standalone(UavId(1), params, f, deps, VehicleModel::Kinematic(KinematicModel::default()))
        .expect("valid controller")
}

fn params() -> ControllerParams {
    ControllerParams { predictor: PredictorKind::ConstantVelocity, ..ControllerParams::default() }
}

fn observe(id: u32, s: State9) -> Observation {
    Observation { id: UavId(id), state: s, age_s: 0.0, source: ObservationSource::Onboard }
}

fn everyone_in_slot() -> Vec<State9> {
    formation().slots.iter().map(cruise_at).collect()
}

#[test]
fn holds_when_in_its_slot() {
    let mut c = controller(params());
    let s = everyone_in_slot();
    let obs: Vec<_> = [0, 2, 3].iter().map(|&j| observe(j, s[j as usize])).collect();
    let d = c.step(0.0, &s[1], &obs);
    assert_eq!(d.outcome, Outcome::Held);
    assert_eq!(d.input, proxform_core::Input::zeros());
    assert_eq!(d.main_refs, 2);
}

#[test]
fn adjusts_toward_the_centre_when_displaced() {
    let mut c = controller(params());
    let s = everyone_in_slot();
    let obs: Vec<_> = [0, 2, 3].iter().map(|&j| observe(j, s[j as usize])).collect();
    let mut me = s[1];
    me[state::Y] += 1.0; // 1 m too far left
    me[state::BETA] += deg(0.15); // and yawed
    let d = c.step(0.0, &me, &obs);
    assert!(matches!(d.outcome, Outcome::Adjusted { .. }), "{:?}", d.outcome);
    // Moves right (−y) and yaws back, within the per-step limits.
    assert!(d.input[1] < 0.0 && d.input[1] >= -0.5 - 1e-12, "Δvy = {}", d.input[1]);
    assert!(d.input[4] < 0.0 && d.input[4] >= -deg(0.2) - 1e-12, "Δβ = {}", d.input[4]);
    // The yaw error is within one step's reach, so it is cancelled.
    assert!((d.input[4] + deg(0.15)).abs() < deg(0.01));
}

#[test]
fn saturates_large_corrections_at_the_vehicle_limits() {
    let mut c = controller(params());
    let s = everyone_in_slot();
    let obs: Vec<_> = [0, 2, 3].iter().map(|&j| observe(j, s[j as usize])).collect();
    let mut me = s[1];
    me[state::Y] -= 30.0;
    me[state::GAMMA] = deg(-10.0);
    let d = c.step(0.0, &me, &obs);
    assert!((d.input[1] - 0.5).abs() < 1e-12, "Δvy saturates at 5 m/s² · 0.1 s: {}", d.input[1]);
    assert!((d.input[5] - deg(0.2)).abs() < 1e-12, "Δγ saturates at 2 °/s · 0.1 s: {}", d.input[5]);
}

#[test]
fn flies_alone_when_nothing_is_perceived() {
    let mut c = controller(params());
    let s = everyone_in_slot();
    let d = c.step(0.0, &s[1], &[]);
    assert_eq!(d.outcome, Outcome::Alone);
    // Onboard observations beyond the sensing range do not count either.
    let mut far = s[0];
    far[state::X] += 1000.0;
    let d = c.step(0.1, &s[1], &[observe(0, far)]);
    assert_eq!(d.outcome, Outcome::Alone);
    // The same state heard over the radio does.
    let radio = Observation { source: ObservationSource::Radio, ..observe(0, far) };
    let d = c.step(0.2, &s[1], &[radio]);
    assert!(matches!(d.outcome, Outcome::Adjusted { .. }));
}

#[test]
fn keeps_only_the_nearest_uav_of_an_area() {
    // Only λ = 0 (the area mean) decides here. UAV1 is ahead-right of UAV2, in area 0; a
    // far-away copy of UAV1's slot occupant placed in the same area must be ignored in favour
    // of the nearer one.
    let mut p = params();
    p.lambda = 0.0;
    let f = formation();
    let deps = DependencySet::new(UavId(1), 4, vec![]).expect("empty table");
    let mut c =
        ProximityController::standalone(UavId(1), p, f, deps, VehicleModel::Kinematic(KinematicModel::default()))
            .expect("valid");
    let s = everyone_in_slot();
    // UAV3 (id 2) displaced by 5 m in z but placed in area 0 behind UAV1 (id 0): further away.
    let mut decoy = s[0];
    decoy[state::X] += 100.0;
    decoy[state::Y] -= 30.0;
    decoy[state::Z] += 5.0;
    let d = c.step(0.0, &s[1], &[observe(0, s[0]), observe(2, decoy)]);
    assert_eq!(d.outcome, Outcome::Held, "the decoy should have been dropped: {:?}", d);
    assert_eq!(d.occupied_areas, 1);
}

#[test]
fn main_references_count_even_when_not_nearest_in_their_area() {
    // λ = 1: the centre is the dependency mean only. UAV1 (id 0, degree 0.7) is in area 0;
    // a nearer non-reference UAV (id 3) is placed in the same area.
    let mut p = params();
    p.lambda = 1.0;
    let mut c = controller(p);
    let s = everyone_in_slot();
    let mut nearer = s[1];
    nearer[state::X] += 40.0;
    nearer[state::Y] -= 10.0;
    let mut lead = s[0];
    lead[state::Z] += 2.0; // the navigator climbed 2 m: UAV2 must follow
    let d = c.step(0.0, &s[1], &[observe(0, lead), observe(2, s[2]), observe(3, nearer)]);
    assert!(matches!(d.outcome, Outcome::Adjusted { .. }));
    assert!(d.input[2] > 0.0, "climbs after its main reference: {:?}", d.input);
}

#[test]
fn rejects_invalid_parameters_by_name() {
    let mut p = params();
    p.lambda = 1.2;
    let f = formation();
    let deps = DependencySet::default();
    let err = ProximityController::standalone(
        UavId(1),
        p,
        f.clone(),
        deps.clone(),
        VehicleModel::Kinematic(KinematicModel::default()),
    )
    .expect_err("λ > 1");
    assert!(err.to_string().contains("lambda"), "{err}");
    let mut p = params();
    p.areas.areas = 0;
    let err = ProximityController::standalone(
        UavId(1),
        p,
        f.clone(),
        deps.clone(),
        VehicleModel::Kinematic(KinematicModel::default()),
    )
    .expect_err("m = 0");
    assert!(err.to_string().contains("areas"), "{err}");
    let err = ProximityController::standalone(
        UavId(9),
        params(),
        f,
        deps,
        VehicleModel::Kinematic(KinematicModel::default()),
    )
    .expect_err("not in formation");
    assert!(err.to_string().contains("UAV10"), "{err}");
}

#[test]
fn a_neighbour_too_close_pushes_the_uav_away_unless_the_slots_are_that_close() {
    let s = everyone_in_slot();
    // UAV4 (id 3), whose slot is 100 m from UAV2's, has drifted to 12 m behind UAV2 (id 1).
    let mut intruder = s[1];
    intruder[state::X] -= 12.0;
    let obs = [observe(0, s[0]), observe(2, s[2]), observe(3, intruder)];
    let step = |separation_m: Option<f64>| {
        // λ = 1: only the main references, in their slots, place the centre.
        let mut c = controller(ControllerParams { separation_m, lambda: 1.0, ..params() });
        c.step(0.0, &s[1], &obs)
    };
    // Off (None or 0): UAV2 is in its slot as its references see it and holds.
    assert_eq!(step(None).outcome, Outcome::Held);
    assert_eq!(step(Some(0.0)).outcome, Outcome::Held);
    // On at 30 m: it speeds up, away from the intruder behind it.
    let d = step(Some(30.0));
    assert!(matches!(d.outcome, Outcome::Adjusted { .. }), "{:?}", d.outcome);
    assert!(d.input[0] > 0.1, "Δvx = {}", d.input[0]);
    // A formation whose slots are 12.5 m apart is not pushed apart at 12 m: 80 % of 12.5 m is
    // 10 m, and the intruder is further than that.
    let close = Arc::new(Formation {
        slots: vec![
            FormationSlot::at(0.0, 0.0, 0.0),
            FormationSlot::at(-86.6, 50.0, -10.0),
            FormationSlot::at(-86.6, -50.0, -10.0),
            FormationSlot::at(-99.1, 50.0, -10.0),
        ],
        frame: FormationFrame::World,
    });
    let deps = DependencySet::new(UavId(1), 4, vec![(UavId(0), 0.7), (UavId(2), 0.3)]).expect("valid table");
    let p = ControllerParams { separation_m: Some(30.0), lambda: 1.0, ..params() };
    let mut c =
        ProximityController::standalone(UavId(1), p, close, deps, VehicleModel::Kinematic(KinematicModel::default()))
            .expect("valid");
    assert_eq!(c.step(0.0, &s[1], &obs).outcome, Outcome::Held);
}

#[test]
fn a_negative_separation_is_refused() {
    let p = ControllerParams { separation_m: Some(-1.0), ..params() };
    let err = ProximityController::standalone(
        UavId(1),
        p,
        formation(),
        DependencySet::new(UavId(1), 4, vec![]).expect("empty"),
        VehicleModel::Kinematic(KinematicModel::default()),
    );
    assert!(err.is_err());
}

#[test]
fn a_neighbour_reported_twice_counts_once() {
    // The same UAV detected onboard and heard over the radio takes one area, not two.
    let states = everyone_in_slot();
    let mut obs: Vec<Observation> = [0u32, 2, 3].iter().map(|&j| observe(j, states[j as usize])).collect();
    let mut c = controller(params());
    let once = c.clone().step(0.0, &states[1], &obs);
    // The radio report puts UAV1 a metre nearer: it must still not take a place of its own.
    let mut again = obs[0];
    again.source = ObservationSource::Radio;
    again.state[0] -= 1.0;
    obs.push(again);
    let twice = c.step(0.0, &states[1], &obs);
    assert_eq!(once.occupied_areas, twice.occupied_areas);
    assert_eq!(once.main_refs, twice.main_refs);
    assert_eq!(once.outcome, twice.outcome);
}
