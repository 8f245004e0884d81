//! The baselines and the proximity method on the paper experiment, on equal terms: with an
//! ideal radio every method holds the formation; under a total radio blackout only the
//! proximity method (onboard sensing) does; the horizon QP flies the formation too.

use proxform_scenario::builtin::paper_spec;
use proxform_scenario::spec::FaultSpec;
use proxform_scenario::{Scenario, ScenarioSpec};
use proxform_sim::{run_batch, run_one, RunOptions, Summary};

fn paper_with(label: &str, edit: impl FnOnce(&mut ScenarioSpec)) -> Scenario {
    let spec = paper_spec().with(|s| s.controller.method = Some(label.into()));
    Scenario::try_from(spec.with(edit)).expect("valid")
}

fn batch(s: &Scenario, options: RunOptions, seed: u64, runs: u64) -> Summary {
    run_batch(s, options, seed, runs, None, &|| {}).summary
}

#[test]
fn every_baseline_holds_the_paper_formation_over_an_ideal_radio() {
    for label in ["leader_follower", "consensus", "flocking"] {
        let s = paper_with(label, |_| {});
        let sum = batch(&s, RunOptions::default(), 1, 20);
        assert_eq!(sum.pass_fraction, 1.0, "{label}: {:?}", sum.p99_abs_error);
        assert!(sum.swarm.radio_used_per_uav_s > 1.0, "{label} hears the radio");
        // Switching the adjustment off breaks every one of them: the check can fail.
        let off = batch(&s, RunOptions { adjustment_enabled: false, ..RunOptions::default() }, 1, 3);
        assert_eq!(off.pass_fraction, 0.0, "{label} without adjustment");
    }
}

#[test]
fn under_a_total_blackout_only_the_proximity_method_keeps_the_formation() {
    let blackout = |label: &str| paper_with(label, |s| s.fault.push(FaultSpec::radio_blackout(0.0, 101.0)));
    let prox = batch(&blackout("proximity"), RunOptions::default(), 7, 100);
    assert!(prox.pass_fraction >= 0.99, "{}", prox.pass_fraction);
    for label in ["leader_follower", "consensus"] {
        let s = batch(&blackout(label), RunOptions::default(), 7, 5);
        assert_eq!(s.pass_fraction, 0.0, "{label}");
        assert!(s.swarm.alone_s_per_uav > 90.0, "{label}: {}", s.swarm.alone_s_per_uav);
    }
    let flock = batch(&blackout("flocking"), RunOptions::default(), 7, 5);
    assert_eq!(flock.pass_fraction, 0.0);
}

#[test]
fn radio_based_methods_read_only_the_radio() {
    // With the radio up but every message lost, leader-follower perceives nothing even though
    // its neighbours are within sensing range.
    let s = paper_with("leader_follower", |s| {
        s.radio.loss = Some(1.0);
        s.duration_s = Some(5.0);
    });
    let (run, _) = run_one(&s, RunOptions::default(), 3, 0, false);
    assert!(run.alone_s_per_uav > 4.0, "{}", run.alone_s_per_uav);
    assert_eq!(run.radio_used_per_uav_s, 0.0);
}

#[test]
fn a_longer_horizon_flies_the_formation_through_the_qp() {
    let with_horizon = |h: i64| {
        paper_with("proximity", |s| {
            s.controller.horizon = Some(h);
            s.duration_s = Some(40.0);
        })
    };
    let h5 =
        run_batch(&with_horizon(5), RunOptions::default(), 2, 4, Some(proxform_sim::Trajectory::default()), &|| {});
    assert_eq!(h5.summary.pass_fraction, 1.0, "{:?}", h5.summary.p99_abs_error);
    let h1 = run_batch(&with_horizon(1), RunOptions::default(), 2, 4, None, &|| {});
    // The QP is really used: the flights differ.
    assert_ne!(h5.runs[0].max_abs_error, h1.runs[0].max_abs_error);
    assert!(h5.runs[0].adjustments > 0);
}
