//! Faults and degraded sensing on the paper experiment.

use nalgebra::Vector3;
use proxform_core::UavId;
use proxform_sim::batch::{run_batch, run_one};
use proxform_sim::faults::Fault;
use proxform_sim::Scenario;

#[test]
fn removing_uav2_keeps_the_rest_safe_and_in_formation() {
    let mut s = Scenario::paper();
    s.faults = vec![Fault::Remove { uav: UavId(1), at_s: 40.0 }];
    let r = run_batch(&s, 3, 60, false, &|| {}).expect("valid");
    assert!(r.summary.min_separation_m >= 50.0, "{}", r.summary.min_separation_m);
    let allow = r.summary.allowable_error.as_array();
    let worst = r.summary.worst_abs_error.as_array();
    for k in 0..6 {
        assert!(worst[k] <= 2.0 * allow[k], "axis {k}: {} > 2 × {}", worst[k], allow[k]);
    }
}

#[test]
fn losing_the_navigator_leaves_a_formation_that_holds_together() {
    let mut s = Scenario::paper();
    s.faults = vec![Fault::Remove { uav: UavId(0), at_s: 50.0 }];
    let (r, _) = run_one(&s, 5, 0, false).expect("valid");
    // Errors are measured against the formation's own estimate of the navigator's slot.
    assert!(r.max_abs_error[1] < 2.0, "{:?}", r.max_abs_error);
    assert!(r.min_separation_m > 50.0);
    assert!(r.connectivity_min >= 1.0);
}

#[test]
fn a_glitch_pushes_its_uav_off_and_a_joining_uav_takes_its_slot() {
    let base = Scenario::paper();
    let mut glitch = base.clone();
    glitch.faults =
        vec![Fault::Glitch { uav: UavId(4), at_s: 50.0, duration_s: 3.0, offset_m: Vector3::new(0.0, 5.0, 0.0) }];
    let (a, _) = run_one(&base, 1, 0, false).expect("valid");
    let (b, _) = run_one(&glitch, 1, 0, false).expect("valid");
    assert!(b.max_abs_error[1] > 2.0 && a.max_abs_error[1] < 1.0, "{:?} vs {:?}", b.max_abs_error, a.max_abs_error);

    let mut join = base.clone();
    join.faults = vec![Fault::Join { uav: UavId(5), at_s: 20.0, offset_m: Vector3::zeros() }];
    let (j, t) = run_one(&join, 1, 0, true).expect("valid");
    let rows = t.expect("recorded").rows;
    assert!(rows.iter().filter(|r| r.uav == 5).all(|r| r.t >= 20.0 - 1e-9), "UAV6 flew before joining");
    assert!(rows.iter().any(|r| r.uav == 5 && r.t > 90.0));
    assert!(j.min_separation_m > 50.0);
}

#[test]
fn a_stuck_sensor_misleads_its_uav() {
    let base = Scenario::paper();
    let mut stuck = base.clone();
    stuck.faults = vec![Fault::StuckSensor { uav: UavId(2), at_s: 20.0, duration_s: 2.0 }];
    let (a, _) = run_one(&base, 2, 0, false).expect("valid");
    let (b, _) = run_one(&stuck, 2, 0, false).expect("valid");
    assert!(
        b.max_abs_error.iter().zip(&a.max_abs_error).any(|(b, a)| b > &(2.0 * a)),
        "{:?} vs {:?}",
        b.max_abs_error,
        a.max_abs_error
    );
}

#[test]
fn dropout_degrades_gracefully() {
    let mut s = Scenario::paper();
    s.dropout = 0.1;
    let r = run_batch(&s, 11, 100, false, &|| {}).expect("valid");
    assert!(r.summary.pass_fraction >= 0.85, "{}", r.summary.pass_fraction);
    assert!(r.summary.swarm.within_allowable_fraction > 0.999);
    s.dropout = 1.0;
    let (all_lost, _) = run_one(&s, 11, 0, false).expect("valid");
    assert!(all_lost.alone_s_per_uav > 90.0, "{}", all_lost.alone_s_per_uav);
    assert!(!all_lost.pass);
}

#[test]
fn a_correlated_position_bias_shows_in_the_formation_errors() {
    let base = Scenario::paper();
    let mut biased = base.clone();
    biased.gnss_bias = Some(proxform_sim::scenario::CorrelatedNoise { sigma_m: 0.1, tau_s: 30.0 });
    let a = run_batch(&base, 6, 20, false, &|| {}).expect("valid").summary;
    let b = run_batch(&biased, 6, 20, false, &|| {}).expect("valid").summary;
    // White noise averages out over a step; a bias that lasts 30 s does not.
    assert!(b.rms_error.z_m > 2.0 * a.rms_error.z_m, "{:?} vs {:?}", b.rms_error, a.rms_error);
}

#[test]
fn a_removed_uav_is_not_followed_as_a_ghost() {
    let mut s = Scenario::paper();
    s.faults = vec![Fault::Remove { uav: UavId(1), at_s: 40.0 }];
    let safe = run_batch(&s, 12, 100, false, &|| {}).expect("valid").summary;
    // Without fading and without the cap on extrapolated acceleration, the vanished UAV is
    // followed at full weight for coast_s.
    s.controller.coast_decay_s = 1000.0;
    s.controller.coast_accel_s = 1000.0;
    let ghost = run_batch(&s, 12, 100, false, &|| {}).expect("valid").summary;
    assert!(safe.pass_fraction >= 0.99, "{}", safe.pass_fraction);
    assert!(ghost.pass_fraction < safe.pass_fraction - 0.05, "{} vs {}", ghost.pass_fraction, safe.pass_fraction);
}

#[test]
fn under_30_percent_dropout_coasting_keeps_most_runs_within_the_tolerances() {
    let mut s = Scenario::paper();
    s.dropout = 0.3;
    let coast = run_batch(&s, 13, 100, false, &|| {}).expect("valid").summary;
    s.controller.coast_s = 0.0;
    let none = run_batch(&s, 13, 100, false, &|| {}).expect("valid").summary;
    assert!(coast.pass_fraction >= 0.7, "{}", coast.pass_fraction);
    assert!(none.pass_fraction < coast.pass_fraction - 0.2, "{} vs {}", none.pass_fraction, coast.pass_fraction);
    // Fading the coasting neighbours' weights matters as much.
    s.controller.coast_s = 0.5;
    s.controller.coast_decay_s = 1000.0;
    let unfaded = run_batch(&s, 13, 100, false, &|| {}).expect("valid").summary;
    assert!(unfaded.pass_fraction < coast.pass_fraction - 0.1, "{} vs {}", unfaded.pass_fraction, coast.pass_fraction);
}

#[test]
fn under_30_percent_dropout_the_losses_that_matter_are_those_of_the_main_references() {
    let mut s = Scenario::paper();
    s.dropout = 0.3;
    // The references tracked by a sensor that loses them one step in ten.
    s.reference_dropout = Some(0.1);
    let tracked = run_batch(&s, 17, 100, false, &|| {}).expect("valid").summary;
    assert!(tracked.pass_fraction >= 0.99, "{}", tracked.pass_fraction);
    // Only the references lost: as bad as losing everything.
    s.dropout = 0.0;
    s.reference_dropout = Some(0.3);
    let refs_lost = run_batch(&s, 17, 100, false, &|| {}).expect("valid").summary;
    assert!(refs_lost.pass_fraction < 0.95, "{}", refs_lost.pass_fraction);
    // And the method is what holds it: without adjustment nothing passes.
    s.dropout = 0.3;
    s.reference_dropout = Some(0.1);
    s.adjustment_enabled = false;
    let off = run_batch(&s, 17, 20, false, &|| {}).expect("valid").summary;
    assert_eq!(off.pass_fraction, 0.0);
}
