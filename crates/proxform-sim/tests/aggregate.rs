//! Forming from scattered starts (`scenarios/aggregate.toml`, README "Forming from scattered
//! starts"): each check fails when its mechanism is switched off.

use proxform_scenario::load::{check, parse_spec};
use proxform_scenario::{Scenario, ScenarioSpec};
use proxform_sim::{run_batch, RunOptions, Summary};

fn aggregate(edit: impl FnOnce(&mut ScenarioSpec)) -> Scenario {
    let text = proxform_scenario::builtin::AGGREGATE;
    let spec = parse_spec(text, "aggregate.toml").expect("valid");
    check(spec.with(edit), text, "aggregate.toml").expect("valid")
}

fn batch(s: &Scenario, runs: u64) -> Summary {
    run_batch(s, RunOptions::default(), 7, runs, None, &|| {}).summary
}

#[test]
fn scattered_uavs_form_in_time_and_keep_apart_on_the_way_in() {
    let s = batch(&aggregate(|_| {}), 24);
    let f = s.forming.as_ref().expect("scattered starts are measured");
    assert_eq!(s.unsafe_runs, 0, "min separation {}", s.min_separation_m);
    assert!(s.min_separation_m >= 50.0, "{}", s.min_separation_m);
    assert_eq!(f.formed_fraction, 1.0, "{f:?}");
    assert!(f.time_to_form_s_max <= 120.0, "{f:?}");
    // The pass criterion of a scattered start: formed by form_within_s and formed to the end.
    assert_eq!(s.pass_fraction, 1.0);
}

#[test]
fn without_collision_avoidance_pairs_come_too_close() {
    // The same starts, nothing but the paper's centre and separation keeping: UAVs that cross
    // on their way to their slots come within the safety distance.
    let s = batch(&aggregate(|s| s.controller.avoid_m = Some(0.0)), 24);
    assert!(s.unsafe_runs >= 3, "unsafe runs {} of 24, min {}", s.unsafe_runs, s.min_separation_m);
}

#[test]
fn without_the_stopping_limit_uavs_overshoot_their_slots_and_form_later() {
    let with = batch(&aggregate(|_| {}), 24);
    let without = batch(&aggregate(|s| s.controller.stop_closing = Some(false)), 24);
    let (a, b) = (with.forming.expect("forming"), without.forming.expect("forming"));
    assert!(
        b.time_to_form_s_median > a.time_to_form_s_median + 3.0,
        "median time to form: {} with the limit, {} without",
        a.time_to_form_s_median,
        b.time_to_form_s_median
    );
}

#[test]
fn a_run_that_forms_too_late_fails() {
    // The same runs judged against a deadline before any of them formed.
    let s = batch(&aggregate(|s| s.initial.form_within_s = Some(20.0)), 6);
    assert_eq!(s.pass_fraction, 0.0);
    assert_eq!(s.forming.expect("forming").formed_fraction, 1.0);
}

fn takeoff(edit: impl FnOnce(&mut ScenarioSpec)) -> Scenario {
    let path = format!("{}/../../scenarios/takeoff-lattice100.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).expect("shipped scenario");
    let spec = parse_spec(&text, "takeoff-lattice100.toml").expect("valid");
    check(spec.with(edit), &text, "takeoff-lattice100.toml").expect("valid")
}

#[test]
fn a_hundred_uavs_take_off_from_a_row_into_a_lattice_apart() {
    let sc = takeoff(|_| {});
    let s = batch(&sc, 2);
    let f = s.forming.as_ref().expect("a take-off is measured");
    assert_eq!(f.formed_fraction, 1.0, "{f:?}");
    assert!(f.time_to_form_s_max <= 60.0, "{f:?}");
    assert!(s.min_separation_m >= sc.safety_distance_m(), "{}", s.min_separation_m);
    // Without collision avoidance the climbing UAVs pass each other far too close.
    let without = batch(&takeoff(|s| s.controller.avoid_m = Some(0.0)), 2);
    assert!(without.min_separation_m < 0.5 * sc.safety_distance_m(), "{}", without.min_separation_m);
}
