//! Controller steps: against the number of perceived neighbours, the predictive horizon, and the method.

use proxform_core::state::State9;
use proxform_core::{
    ControllerParams, ControllerSetup, DependencySet, FormationController, KinematicModel, Method, Observation,
    ObservationSource, PredictorKind, ProximityController, UavId, VehicleModel,
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
