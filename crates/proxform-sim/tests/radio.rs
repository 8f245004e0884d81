//! The paper formation kept over the radio alone (sensing range too short to see anyone).

use proxform_sim::batch::run_batch;
use proxform_sim::faults::Fault;
use proxform_sim::radio::{GilbertElliott, RadioModel};
use proxform_sim::Scenario;

fn radio_only() -> Scenario {
    let mut s = Scenario::paper();
    s.controller.areas.sensing_range_m = 50.0;
    s.radio = RadioModel { broadcast_all: true, ..RadioModel::default() };
    s
}

#[test]
fn an_ideal_radio_keeps_the_formation_and_a_blackout_loses_it() {
    let s = radio_only();
    let ideal = run_batch(&s, 4, 30, false, &|| {}).expect("valid").summary;
    assert!(ideal.pass_fraction >= 0.95, "{}", ideal.pass_fraction);
    assert!(ideal.swarm.radio_msgs_per_uav_s > 40.0, "{}", ideal.swarm.radio_msgs_per_uav_s);
    let mut dark = s.clone();
    dark.faults = vec![Fault::RadioBlackout { at_s: 20.0, duration_s: 80.0 }];
    let dark = run_batch(&dark, 4, 10, false, &|| {}).expect("valid").summary;
    assert_eq!(dark.pass_fraction, 0.0);
    assert!(dark.swarm.alone_s_per_uav > 70.0, "{}", dark.swarm.alone_s_per_uav);
}

#[test]
fn delay_and_bursty_loss_cost_accuracy() {
    let s = radio_only();
    let base = run_batch(&s, 8, 20, false, &|| {}).expect("valid").summary;
    let mut slow = s.clone();
    slow.radio.delay_steps = 3;
    let slow = run_batch(&slow, 8, 20, false, &|| {}).expect("valid").summary;
    assert!(slow.p99_abs_error.y_m > base.p99_abs_error.y_m, "{:?} vs {:?}", slow.p99_abs_error, base.p99_abs_error);
    let mut bursty = s.clone();
    bursty.radio.burst = Some(GilbertElliott { p_good_to_bad: 0.05, p_bad_to_good: 0.2, loss_bad: 1.0 });
    let bursty = run_batch(&bursty, 8, 20, false, &|| {}).expect("valid").summary;
    assert!(bursty.swarm.radio_msgs_per_uav_s < 0.9 * base.swarm.radio_msgs_per_uav_s);
    assert!(bursty.p99_abs_error.y_m > base.p99_abs_error.y_m);
}
