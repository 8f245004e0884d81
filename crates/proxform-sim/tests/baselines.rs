//! The baselines and the proximity method on the paper experiment, on equal terms: with an
//! ideal radio every method holds the formation; under a total radio blackout only the
//! proximity method (onboard sensing) does; the horizon QP flies the formation too.

use proxform_core::Method;
use proxform_sim::batch::run_batch;
use proxform_sim::faults::Fault;
use proxform_sim::Scenario;

fn paper_with(label: &str) -> Scenario {
    let mut s = Scenario::paper();
    s.set_method(Method::from_label(label).expect("known method"));
    s.validate().expect("valid");
    s
}

#[test]
fn every_baseline_holds_the_paper_formation_over_an_ideal_radio() {
    for label in ["leader_follower", "consensus", "flocking"] {
        let s = paper_with(label);
        let sum = run_batch(&s, 1, 20, false, &|| {}).expect("valid").summary;
        assert_eq!(sum.pass_fraction, 1.0, "{label}: {:?}", sum.p99_abs_error);
        assert!(sum.swarm.radio_msgs_per_uav_s > 1.0, "{label} hears the radio");
        // Switching the adjustment off breaks every one of them: the check can fail.
        let mut off = s.clone();
        off.adjustment_enabled = false;
        let off = run_batch(&off, 1, 3, false, &|| {}).expect("valid").summary;
        assert_eq!(off.pass_fraction, 0.0, "{label} without adjustment");
    }
}

#[test]
fn under_a_total_blackout_only_the_proximity_method_keeps_the_formation() {
    let blackout = |mut s: Scenario| {
        s.faults.push(Fault::RadioBlackout { at_s: 0.0, duration_s: s.duration_s + 1.0 });
        s
    };
    let prox = run_batch(&blackout(paper_with("proximity")), 7, 100, false, &|| {}).expect("valid").summary;
    assert!(prox.pass_fraction >= 0.99, "{}", prox.pass_fraction);
    for label in ["leader_follower", "consensus"] {
        let s = run_batch(&blackout(paper_with(label)), 7, 5, false, &|| {}).expect("valid").summary;
        assert_eq!(s.pass_fraction, 0.0, "{label}");
        assert!(s.swarm.alone_s_per_uav > 90.0, "{label}: {}", s.swarm.alone_s_per_uav);
    }
    let flock = run_batch(&blackout(paper_with("flocking")), 7, 5, false, &|| {}).expect("valid").summary;
    assert_eq!(flock.pass_fraction, 0.0);
}

#[test]
fn radio_based_methods_read_only_the_radio() {
    // With the radio up but every message lost, leader-follower perceives nothing even though
    // its neighbours are within sensing range.
    let mut s = paper_with("leader_follower");
    s.radio.loss = 1.0;
    s.duration_s = 5.0;
    let (run, _) = proxform_sim::batch::run_one(&s, 3, 0, false).expect("valid");
    assert!(run.alone_s_per_uav > 4.0, "{}", run.alone_s_per_uav);
    assert_eq!(run.radio_msgs_per_uav_s, 0.0);
}

#[test]
fn a_longer_horizon_flies_the_formation_through_the_qp() {
    let mut s = Scenario::paper();
    s.controller.horizon = 5;
    s.duration_s = 40.0;
    let h5 = run_batch(&s, 2, 4, true, &|| {}).expect("valid");
    assert_eq!(h5.summary.pass_fraction, 1.0, "{:?}", h5.summary.p99_abs_error);
    let mut one = s.clone();
    one.controller.horizon = 1;
    let h1 = run_batch(&one, 2, 4, false, &|| {}).expect("valid");
    // The QP is really used: the flights differ.
    assert_ne!(h5.runs[0].max_abs_error, h1.runs[0].max_abs_error);
    assert!(h5.runs[0].adjustments > 0);
}
