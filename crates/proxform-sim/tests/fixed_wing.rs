//! The fixed-wing V: a climb and a 180° turn in moderate Dryden turbulence, safely.

use proxform_scenario::builtin::FIXED_WING_V;
use proxform_scenario::load::{parse, parse_spec};
use proxform_scenario::{Scenario, ScenarioSpec};
use proxform_sim::{run_one as run_one_with, RunOptions, RunSummary};

fn scenario() -> Scenario {
    parse(FIXED_WING_V, "fixed-wing-v.toml").expect("valid")
}

fn edited(edit: impl FnOnce(&mut ScenarioSpec)) -> Scenario {
    Scenario::try_from(parse_spec(FIXED_WING_V, "fixed-wing-v.toml").expect("parses").with(edit)).expect("valid")
}

fn run_batch(s: &Scenario, seed: u64, runs: u64) -> proxform_sim::BatchResult {
    proxform_sim::run_batch(s, RunOptions::default(), seed, runs, None, &|| {})
}

fn run_one(s: &Scenario, seed: u64, run: u64) -> RunSummary {
    run_one_with(s, RunOptions::default(), seed, run, false).0
}

#[test]
fn the_v_turns_and_climbs_without_any_pair_closer_than_15_m() {
    let s = scenario();
    let r = run_batch(&s, 7, 40);
    assert!(r.summary.min_separation_m >= 15.0, "{}", r.summary.min_separation_m);
    assert_eq!(r.summary.swarm.close_pairs_max, 0);
    // It does turn: the navigator flew 180° and the followers' yaw errors stay bounded.
    assert!(r.summary.worst_abs_error.beta_deg < 60.0, "{:?}", r.summary.worst_abs_error);
    assert!(r.summary.worst_abs_error.z_m < 40.0, "{:?}", r.summary.worst_abs_error);
    // The turning frame keeps the arms in place: with the slots' velocities in the turn
    // (ω × r) and the formation's course recovered from each reference's heading, RMS
    // along-track and cross-track errors stay near 2-3 m (near 8 m with the reference's own
    // heading as the course, 18 m without the slot velocities).
    assert!(r.summary.rms_error.x_m < 5.0 && r.summary.rms_error.y_m < 5.0, "{:?}", r.summary.rms_error);
    // Errors are measured against the controllers' W, which in the turn gives each slot its
    // own heading and bank: RMS yaw and roll errors near 1.5° and 0.1° (8.7° and 1.8° against
    // the navigator's heading and bank).
    assert!(r.summary.rms_error.beta_deg < 3.0, "{:?}", r.summary.rms_error);
    assert!(r.summary.rms_error.gamma_deg < 0.5, "{:?}", r.summary.rms_error);
}

#[test]
fn a_v_written_without_thresholds_gets_the_fixed_wing_defaults_and_keeps_its_distances() {
    // A minimal file: no [controller] section at all.
    let text = r#"
        name = "minimal-fixed-wing-v"
        dt_s = 0.1
        duration_s = 80.0
        safety_distance_m = 15.0
        [formation]
        frame = "course"
        [formation.shape]
        kind = "v"
        uavs = 12
        spacing_m = 40.0
        angle_deg = 30.0
        [path]
        kind = "segments"
        speed_kmh = 180.0
        [[path.segment]]
        duration_s = 20.0
        [[path.segment]]
        duration_s = 30.0
        turn_rate_deg_s = 6.0
        [[path.segment]]
        duration_s = 30.0
        [vehicle]
        model = "fixed_wing"
        [wind]
        turbulence = "moderate"
    "#;
    let s = parse(text, "minimal.toml").expect("valid");
    assert_eq!(s.controller().envelope.thresholds, proxform_core::ControllerParams::fixed_wing_thresholds());
    assert!(s.controller().turn_feedforward, "on by default for the fixed wing");
    let r = run_batch(&s, 3, 20);
    assert!(r.summary.min_separation_m >= 15.0, "{}", r.summary.min_separation_m);
    assert!(r.summary.rms_error.x_m < 5.0 && r.summary.rms_error.y_m < 5.0, "{:?}", r.summary.rms_error);
    // A fixed wing's speed limits are on its airspeed: it may start on any course.
    let north = text.replace("speed_kmh = 180.0", "speed_kmh = 180.0\n        course_deg = 90.0");
    let s = parse(&north, "north.toml").expect("a fixed wing may fly north");
    let r = run_one(&s, 3, 0);
    assert!(r.min_separation_m >= 15.0, "{}", r.min_separation_m);
}

#[test]
fn an_echelon_flies_a_figure_eight_at_the_fixed_wing_defaults() {
    // Nothing but the vehicle, the shape and the path: the allowable errors, thresholds, frame
    // and turn feed-forward are the fixed wing's defaults.
    let text = r#"
        duration_s = 400.0
        [formation.shape]
        kind = "echelon"
        uavs = 4
        spacing_m = 60.0
        [path]
        kind = "segments"
        speed_kmh = 130.0
        [[path.segment]]
        duration_s = 20.0
        [[path.segment]]
        duration_s = 180.0
        turn_rate_deg_s = 2.0
        [[path.segment]]
        duration_s = 180.0
        turn_rate_deg_s = -2.0
        [vehicle]
        model = "fixed_wing"
    "#;
    let s = parse(text, "eight.toml").expect("valid");
    assert_eq!(s.allowable().position_m, [10.0; 3]);
    assert_eq!(s.formation().frame, proxform_core::FormationFrame::Course);
    let r = run_batch(&s, 1, 6);
    // Measured (50 runs): 4.1 m at the 99th percentile, yaw 3.9°.
    assert_eq!(r.summary.pass_fraction, 1.0, "{:?}", r.summary.worst_abs_error);
    let w = &r.summary.worst_abs_error;
    assert!(w.x_m.max(w.y_m) < 7.0, "{w:?}");
    assert!(r.summary.min_separation_m > s.safety_distance_m(), "{}", r.summary.min_separation_m);
}

#[test]
fn separation_keeping_holds_a_wide_v_apart_where_formation_keeping_alone_does_not() {
    // A V of half-angle 45° in severe turbulence: through the turn its inner arm must slow to
    // 42 m/s, and in a few runs in a hundred its tail comes near the UAV ahead (3 of 100 runs of
    // seed 1 come within 15 m without separation keeping, the closest, run 7, at 12.2 m; with
    // it none comes closer than 20.4 m; with collision avoidance only, run 7 keeps 19.0 m). In
    // moderate turbulence formation keeping alone now keeps them apart: since the controller's
    // view carries each fixed wing across its nose by the wind its state implies (METHOD §5),
    // none of 400 runs comes closer than 18.7 m, where 4 came within 15 m (8.0 m) before. All
    // with tables that do not lean on the navigator: with it in them (the fixed wing's default),
    // run 7 keeps 27.2 m by formation keeping alone.
    let text = FIXED_WING_V
        .replace("angle_deg = 30.0", "angle_deg = 45.0")
        .replace("\"moderate\"", "\"severe\"")
        .replace("max_distance_m = 90.0", "max_distance_m = 90.0\nnavigator_degree = 0.0");
    let wide = parse(&text, "wide-v.toml").expect("valid");
    assert_eq!(wide.controller().separation_m, Some(30.0), "by default twice the safety distance, 30 m");
    let spec = parse_spec(&text, "wide-v.toml").expect("parses");
    let off = Scenario::try_from(spec.clone().with(|s| {
        s.controller.separation_m = Some(0.0);
        s.controller.avoid_m = Some(0.0);
    }))
    .expect("valid");
    // Collision avoidance alone (off by default for the fixed wing; 1.25 × 15 m) also keeps them
    // apart.
    let avoid_only = Scenario::try_from(spec.with(|s| {
        s.controller.separation_m = Some(0.0);
        s.controller.avoid_m = Some(18.75);
    }))
    .expect("valid");
    let with = run_one(&wide, 1, 7);
    let without = run_one(&off, 1, 7);
    let avoiding = run_one(&avoid_only, 1, 7);
    assert!(without.min_separation_m < 13.0, "{}", without.min_separation_m);
    assert!(with.min_separation_m > 15.0, "{}", with.min_separation_m);
    assert!(avoiding.min_separation_m > 15.0, "{}", avoiding.min_separation_m);
}

#[test]
fn without_adjustment_the_v_falls_apart() {
    let s = scenario();
    let (r, _) = run_one_with(&s, RunOptions { adjustment_enabled: false, ..RunOptions::default() }, 7, 0, false);
    assert!(r.max_abs_error[0] > 200.0 || r.max_abs_error[1] > 200.0, "{:?}", r.max_abs_error);
}

#[test]
fn turbulence_costs_accuracy() {
    let s = scenario();
    let calm = edited(|s| s.wind = Default::default());
    let rough = run_batch(&s, 7, 10).summary;
    let calm = run_batch(&calm, 7, 10).summary;
    assert!(rough.rms_error.z_m > calm.rms_error.z_m, "{:?} vs {:?}", rough.rms_error, calm.rms_error);
}
