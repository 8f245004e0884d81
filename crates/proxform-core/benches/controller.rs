//! Controller steps: against the number of perceived neighbours, the predictive horizon, and the method.

use proxform_core::state::State9;
use proxform_core::{
    ControllerParams, ControllerSetup, DependencySet, FixedWingModel, FormationController, FormationFrame,
    KinematicModel, Method, MultirotorModel, Observation, ObservationSource, PredictorKind, ProximityController, UavId,
    VehicleModel,
};

mod support;

fn main() {
    divan::main();
}

/// A UAV at the origin with `n` neighbours on a 100 m ring, one per azimuth area.
fn setup(n: usize) -> (ProximityController, Vec<Observation>, State9) {
    setup_with(n, ControllerParams::default())
}

/// [`setup`] with the given parameters.
fn setup_with(n: usize, params: ControllerParams) -> (ProximityController, Vec<Observation>, State9) {
    let formation = support::ring::formation(n);
    let deps = DependencySet::new(UavId(0), n + 1, vec![(UavId(1), 0.7)]).expect("valid");
    let (obs, own) = support::ring::scene(&formation);
    let ctrl = ProximityController::standalone(
        UavId(0),
        params,
        formation,
        deps,
        VehicleModel::Kinematic(KinematicModel::default()),
    )
    .expect("valid");
    (ctrl, obs, own)
}

#[divan::bench(args = [1, 2, 4, 8])]
fn controller_step(bencher: divan::Bencher, neighbours: usize) {
    let (mut ctrl, obs, own) = setup(neighbours);
    let mut t = 0.0;
    // Sanity: every neighbour is perceived and the step adjusts.
    let d = ctrl.step(t, &own, &obs);
    assert_eq!(usize::from(d.occupied_areas), neighbours);
    assert!(matches!(d.outcome, proxform_core::Outcome::Adjusted { .. }));
    bencher.bench_local(|| {
        t += 0.1;
        divan::black_box(ctrl.step(t, divan::black_box(&own), divan::black_box(&obs)))
    });
}

/// One adjusting step with 8 neighbours against the predictive horizon H: H = 1 is the
/// closed-form step, H > 1 the Clarabel QP (METHOD §6 step 7).
#[divan::bench(args = [1, 2, 5, 10])]
fn controller_step_horizon(bencher: divan::Bencher, horizon: u32) {
    let (mut ctrl, obs, own) = setup_with(8, ControllerParams { horizon, ..ControllerParams::default() });
    let mut t = 0.0;
    let d = ctrl.step(t, &own, &obs);
    assert!(matches!(d.outcome, proxform_core::Outcome::Adjusted { .. }));
    bencher.bench_local(|| {
        t += 0.1;
        divan::black_box(ctrl.step(t, divan::black_box(&own), divan::black_box(&obs)))
    });
}

/// One step of each formation control method with 8 neighbours heard (the navigator among
/// them, as a radio message for the baselines that need it).
#[divan::bench(args = ["proximity", "leader_follower", "consensus", "flocking"])]
fn method_step(bencher: divan::Bencher, label: &str) {
    let (_, mut obs, own) = setup(8);
    for o in &mut obs {
        o.source = ObservationSource::Radio;
    }
    let formation = support::ring::formation(8);
    let setup = ControllerSetup::new(ControllerParams::default(), VehicleModel::Kinematic(KinematicModel::default()))
        .expect("valid");
    let deps = DependencySet::new(UavId(0), 9, vec![(UavId(1), 0.7)]).expect("valid");
    let method = Method::from_label(label).expect("known");
    let mut ctrl =
        FormationController::new(&method, UavId(0), UavId(1), setup, formation, deps).expect("valid controller");
    let mut t = 0.0;
    let d = ctrl.step(t, &own, &obs);
    assert!(matches!(d.outcome, proxform_core::Outcome::Adjusted { .. }), "{label}: {d:?}");
    bencher.bench_local(|| {
        t += 0.1;
        divan::black_box(ctrl.step(t, divan::black_box(&own), divan::black_box(&obs)))
    });
}

/// One adjusting step with 8 neighbours for each neighbour predictor: the default α-β
/// tracks, the plain transition, and the Kalman filter with a Singer manoeuvre model.
#[divan::bench(args = ["alpha_beta", "constant_velocity", "singer"])]
fn predictor_step(bencher: divan::Bencher, predictor: &str) {
    let kind = match predictor {
        "alpha_beta" => PredictorKind::default(),
        "constant_velocity" => PredictorKind::ConstantVelocity,
        _ => PredictorKind::singer(0.02, 0.05),
    };
    let (mut ctrl, obs, own) = setup_with(8, ControllerParams { predictor: kind, ..ControllerParams::default() });
    let mut t = 0.0;
    let d = ctrl.step(t, &own, &obs);
    assert!(matches!(d.outcome, proxform_core::Outcome::Adjusted { .. }), "{predictor}: {d:?}");
    bencher.bench_local(|| {
        t += 0.1;
        divan::black_box(ctrl.step(t, divan::black_box(&own), divan::black_box(&obs)))
    });
}

/// One agent step (own-state handling and the controller) with 8 neighbours for each variant
/// of the robust settings (docs/METHOD.md §8; `support/variants.rs`). Instruction counts of the
/// same steps: `scripts/callgrind-agent.sh`.
#[divan::bench(args = support::variants::VARIANTS)]
fn agent_step_variant(bencher: divan::Bencher, variant: &str) {
    let mut flight = support::variants::Flight::new(variant);
    bencher.bench_local(|| divan::black_box(flight.step()));
}

/// One adjusting step with 8 neighbours for each vehicle at its scenario defaults: the
/// multirotor's in a heading frame with the turn feed-forward and the setpoint lead, the fixed
/// wing's in a course frame with the turn feed-forward (its B by central differences).
#[divan::bench(args = ["kinematic", "multirotor", "fixed_wing"])]
fn controller_step_vehicle(bencher: divan::Bencher, vehicle: &str) {
    let (model, frame, thresholds) = match vehicle {
        "kinematic" => (
            VehicleModel::Kinematic(KinematicModel::default()),
            FormationFrame::World,
            ControllerParams::paper_thresholds(),
        ),
        "multirotor" => (
            VehicleModel::Multirotor(MultirotorModel::default()),
            FormationFrame::Heading,
            ControllerParams::multirotor_thresholds(),
        ),
        _ => (
            VehicleModel::FixedWing(FixedWingModel::default()),
            FormationFrame::Course,
            ControllerParams::fixed_wing_thresholds(),
        ),
    };
    let mut params = ControllerParams { turn_feedforward: vehicle != "kinematic", ..ControllerParams::default() };
    params.envelope.thresholds = thresholds.map(|d| d * 0.01); // always adjusting
    let mut formation = (*support::ring::formation(8)).clone();
    formation.frame = frame;
    let deps = DependencySet::new(UavId(0), 9, vec![(UavId(1), 0.7)]).expect("valid");
    let (obs, own) = support::ring::scene(&formation);
    let mut ctrl =
        ProximityController::standalone(UavId(0), params, std::sync::Arc::new(formation), deps, model).expect("valid");
    let mut t = 0.0;
    let d = ctrl.step(t, &own, &obs);
    assert_eq!(d.occupied_areas, 8);
    bencher.bench_local(|| {
        t += 0.1;
        divan::black_box(ctrl.step(t, divan::black_box(&own), divan::black_box(&obs)))
    });
}

/// The plant: one update period of each vehicle (the multirotor in 5 sub-steps of its inner
/// loop, in a wind).
#[divan::bench(args = ["kinematic", "multirotor", "fixed_wing"])]
fn plant_period(bencher: divan::Bencher, vehicle: &str) {
    let model = match vehicle {
        "kinematic" => VehicleModel::Kinematic(KinematicModel::default()),
        "multirotor" => VehicleModel::Multirotor(MultirotorModel::default()),
        _ => VehicleModel::FixedWing(FixedWingModel::default()),
    };
    let mut x = State9::zeros();
    x[3] = 20.0;
    let mut u = proxform_core::state::Input::zeros();
    u[0] = 0.1;
    u[1] = -0.05;
    bencher.bench_local(|| {
        divan::black_box(model.propagate_in_wind(divan::black_box(&x), &u, 0.1, [1.0, 2.0, 0.0], [1.1, 2.0, 0.0]))
    });
}
