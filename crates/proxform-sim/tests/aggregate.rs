//! Forming from scattered starts (`scenarios/aggregate.toml`, docs/manual.md "Forming from scattered
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
    // Each follower is judged by the same criterion: every one passed in every run, although
    // each was far outside its allowable errors on its way in.
    assert_eq!(s.per_uav_runs_passed, s.per_uav_runs_flown);
    assert!(s.per_uav_runs_flown.iter().all(|&n| n == 24));
    let allow = s.allowable_error.as_array();
    assert!(s.per_uav_worst.iter().all(|w| w.as_array()[0] > allow[0]), "{:?}", s.per_uav_worst);
}

#[test]
fn without_collision_avoidance_pairs_come_too_close() {
    // The same starts, nothing but the paper's centre and separation keeping: UAVs that cross
    // on their way to their slots come within the safety distance.
    let s = batch(&aggregate(|s| s.controller.avoid_m = Some(0.0)), 24);
    assert!(s.unsafe_runs >= 3, "unsafe runs {} of 24, min {}", s.unsafe_runs, s.min_separation_m);
    // A run with a pair inside the safety distance does not pass, whatever its errors.
    assert!(s.pass_fraction <= 1.0 - s.unsafe_runs as f64 / 24.0, "{} with {} unsafe", s.pass_fraction, s.unsafe_runs);
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

#[test]
fn a_follower_does_not_chase_a_neighbour_far_from_its_own_slot() {
    // UAV6 of the aggregate leans on UAV5 (0.5) and UAV3 (0.5). UAV5 is still 1.4 km right
    // of its slot, UAV6 150 m left of UAV5; UAV6 hears the navigator's broadcast and perceives
    // UAV5 only. With the paper's plain means UAV6 places itself by UAV5, away from its own
    // slot (and a UAV5 that yields to it drifts with it: in batches of 1000 runs a few formed
    // after 150 s); the robust fusion, on by default for scattered starts, weighs UAV5's
    // estimate against the navigator's, leaves it out and heads for the slot.
    use proxform_core::{Observation, ObservationSource, UavId};
    let default = aggregate(|_| {});
    assert_eq!(default.controller().isolation_gate, Some(1.0), "on by default for scattered starts");
    let plain = aggregate(|s| s.controller.isolation_gate = Some(0.0));
    let toward_slot = |sc: &Scenario| {
        let mut agent = sc.agent(UavId(5));
        let nav = sc.initial()[0];
        let mut five = sc.slot_state(4, &nav);
        five[1] -= 1400.0;
        let mut me = sc.slot_state(5, &nav);
        me[1] -= 1150.0;
        let heard = [
            Observation { id: UavId(0), state: nav, age_s: 0.0, source: ObservationSource::Radio },
            Observation { id: UavId(4), state: five, age_s: 0.0, source: ObservationSource::Onboard },
        ];
        let d = agent.step(0.0, &me, &heard);
        let next = agent.vehicle().propagate(&me, &d.input, sc.dt_s());
        (next[4] - me[4], d.isolated)
    };
    let (fused, left_out) = toward_slot(&default);
    let (plain_dv, none) = toward_slot(&plain);
    assert_eq!((left_out, none), (1, 0));
    assert!(fused > 0.1, "toward its slot (+y): {fused} m/s in a step");
    assert!(plain_dv < -0.1, "plain means pull it away from its slot, by UAV5: {plain_dv} m/s");
}

#[test]
fn a_follower_ahead_of_the_navigator_passes_it_to_reach_a_slot_behind() {
    // A V of twelve; UAV3 (slot 65 m behind and 46 m right of the navigator) starts 58 m
    // ahead and 28 m left of it, its slot straight through the navigator, which does not
    // give way; the others fly in their slots. The UAV must commit to a side and slide round:
    // comparing two open sides step by step, it swung between them and stayed where it was.
    let text = "duration_s = 60.0\nsafety_distance_m = 50.0\n[formation]\nframe = \"world\"\n\
                [formation.shape]\nkind = \"v\"\nuavs = 12\nspacing_m = 80.0\nangle_deg = 35.0\n\
                level_step_m = -3.0\n[formation.dependencies]\nnavigator_degree = 0.3\n\
                [path]\nkind = \"segments\"\nspeed_kmh = 250.0\n[[path.segment]]\nduration_s = 60.0\n";
    let sc = proxform_scenario::load::parse(text, "v12.toml").expect("valid");
    use proxform_core::{Observation, ObservationSource, UavId};
    let mut agent = sc.agent(UavId(2));
    let dt = sc.dt_s();
    let mut nav = sc.initial()[0];
    let mut me = nav;
    me[0] += 58.0;
    me[1] += 28.0;
    let slot = sc.slot_state(2, &nav);
    let (sx, sy) = (slot[0] - nav[0], slot[1] - nav[1]);
    let mut reached = None;
    for k in 0..400 {
        let t = k as f64 * dt;
        let mut seen = vec![Observation { id: UavId(0), state: nav, age_s: 0.0, source: ObservationSource::Onboard }];
        for i in (1..sc.len()).filter(|&i| i != 2) {
            let s = sc.slot_state(i, &nav);
            if (0..3).map(|a| (s[a] - me[a]).powi(2)).sum::<f64>() < 250.0 * 250.0 {
                seen.push(Observation {
                    id: UavId(i as u32),
                    state: s,
                    age_s: 0.0,
                    source: ObservationSource::Onboard,
                });
            }
        }
        let d = agent.step(t, &me, &seen);
        me = agent.vehicle().propagate(&me, &d.input, dt);
        nav[0] += nav[3] * dt;
        let off = (me[0] - nav[0] - sx).hypot(me[1] - nav[1] - sy);
        let from_nav = (me[0] - nav[0]).hypot(me[1] - nav[1]).hypot(me[2] - nav[2]);
        assert!(from_nav > 50.0, "{t} s: {from_nav} m from the navigator");
        if off < 1.0 && reached.is_none() {
            reached = Some(t);
        }
    }
    assert!(reached.is_some_and(|t| t < 30.0), "in its slot at {reached:?} s");
}

#[test]
fn scattered_followers_home_on_the_navigators_broadcast_by_default() {
    // The aggregate without its `[radio] beacons` line broadcasts the navigator all the same;
    // `beacons = []` says none, and then the followers out of everyone's sight never form.
    let default = aggregate(|s| s.radio.beacons = None);
    assert_eq!(default.beacons(), &[proxform_core::UavId(0)]);
    let none = aggregate(|s| s.radio.beacons = Some(Vec::new()));
    assert!(none.beacons().is_empty());
    let s = batch(&none, 4);
    assert_eq!(s.forming.expect("scattered").formed_fraction, 0.0);
    assert_eq!(batch(&default, 4).pass_fraction, 1.0);
}
