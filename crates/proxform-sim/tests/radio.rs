//! The paper formation kept over the radio alone (sensing range too short to see anyone).

use proxform_scenario::builtin::paper_spec;
use proxform_scenario::spec::FaultSpec;
use proxform_scenario::{Scenario, ScenarioSpec};
use proxform_sim::{run_batch, RunOptions, Summary};

fn radio_only(edit: impl FnOnce(&mut ScenarioSpec)) -> Scenario {
    let spec = paper_spec().with(|s| {
        s.controller.sensing_range_m = Some(50.0);
        s.radio.broadcast_all = Some(true);
    });
    Scenario::try_from(spec.with(edit)).expect("valid")
}

fn batch(s: &Scenario, seed: u64, runs: u64) -> Summary {
    run_batch(s, RunOptions::default(), seed, runs, None, &|| {}).summary
}

#[test]
fn an_ideal_radio_keeps_the_formation_and_a_blackout_loses_it() {
    let ideal = batch(&radio_only(|_| {}), 4, 30);
    assert!(ideal.pass_fraction >= 0.95, "{}", ideal.pass_fraction);
    assert!(ideal.swarm.radio_used_per_uav_s > 40.0, "{}", ideal.swarm.radio_used_per_uav_s);
    // Every UAV broadcasts every period: 10 messages sent per UAV per second, whatever is used.
    assert!((ideal.swarm.radio_sent_per_uav_s - 10.0).abs() < 1e-9, "{}", ideal.swarm.radio_sent_per_uav_s);
    let dark = batch(&radio_only(|s| s.fault = vec![FaultSpec::radio_blackout(20.0, 80.0)]), 4, 10);
    assert_eq!(dark.pass_fraction, 0.0);
    assert!(dark.swarm.alone_s_per_uav > 70.0, "{}", dark.swarm.alone_s_per_uav);
}

#[test]
fn delay_and_bursty_loss_cost_accuracy() {
    let base = batch(&radio_only(|_| {}), 8, 20);
    let slow = batch(&radio_only(|s| s.radio.delay_s = Some(0.3)), 8, 20);
    assert!(slow.p99_abs_error.y_m > base.p99_abs_error.y_m, "{:?} vs {:?}", slow.p99_abs_error, base.p99_abs_error);
    let bursty = batch(
        &radio_only(|s| {
            s.radio.burst_p_good_to_bad = Some(0.05);
            s.radio.burst_p_bad_to_good = Some(0.2);
            s.radio.burst_loss_bad = Some(1.0);
        }),
        8,
        20,
    );
    assert!(bursty.swarm.radio_used_per_uav_s < 0.9 * base.swarm.radio_used_per_uav_s);
    assert!(bursty.p99_abs_error.y_m > base.p99_abs_error.y_m);
}

#[test]
fn delayed_radio_reports_beside_onboard_detections_keep_the_formation() {
    // Onboard detections stamped `now` and delayed radio reports stamped `now − delay` for the
    // same neighbours: the two time stamps of one instant differ by rounding, which must not
    // become a rate. With each predictor that tracks.
    for predictor in ["alpha_beta", "singer"] {
        let spec = paper_spec().with(|s| {
            s.controller.predictor = Some(predictor.into());
            s.radio.broadcast_all = Some(true);
            s.radio.delay_s = Some(0.1);
        });
        let sum = batch(&Scenario::try_from(spec).expect("valid"), 11, 10);
        assert!(sum.pass_fraction >= 0.9, "{predictor}: {} {:?}", sum.pass_fraction, sum.p99_abs_error);
        assert!(sum.p99_abs_error.alpha_deg < 1.0, "{predictor}: {:?}", sum.p99_abs_error);
    }
}

#[test]
fn a_large_broadcasting_swarm_hears_through_the_index_what_it_would_hear_without() {
    // 300 UAVs all broadcasting with losses (above the 64 messages from which they are indexed
    // by sender position): with a range that reaches everyone, the index visits every message
    // in the order heard, so the flight is the one with an unlimited radio, bit for bit; with
    // a short range it hears only its neighbourhood.
    let lattice = |range: Option<f64>| {
        let spec = proxform_scenario::builtin::swarm_spec(300).with(|s| {
            s.duration_s = Some(5.0);
            s.radio.broadcast_all = Some(true);
            s.radio.loss = Some(0.3);
            s.sensing.dropout = Some(0.3);
            s.radio.range_m = range;
        });
        Scenario::try_from(spec).expect("valid")
    };
    let everywhere = batch(&lattice(None), 5, 2);
    let far = batch(&lattice(Some(1.0e6)), 5, 2);
    assert_eq!(everywhere, far);
    assert!(everywhere.swarm.radio_used_per_uav_s > 10.0, "{}", everywhere.swarm.radio_used_per_uav_s);
    let near = batch(&lattice(Some(120.0)), 5, 2);
    assert!(
        near.swarm.radio_used_per_uav_s < 0.5 * everywhere.swarm.radio_used_per_uav_s,
        "{} vs {}",
        near.swarm.radio_used_per_uav_s,
        everywhere.swarm.radio_used_per_uav_s
    );
}
