//! Formation changes in flight (`scenarios/change-v-column.toml`) and a UAV joining next to
//! its slot: each check fails when its mechanism is switched off.

use proxform_scenario::load::{check, parse_spec};
use proxform_scenario::{Scenario, ScenarioSpec};
use proxform_sim::{run_batch, RunOptions, Summary};

fn file(name: &str, edit: impl FnOnce(&mut ScenarioSpec)) -> Scenario {
    let path = format!("{}/../../scenarios/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).expect("shipped scenario");
    let spec = parse_spec(&text, name).expect("valid");
    check(spec.with(edit), &text, name).expect("valid")
}

fn batch(s: &Scenario, runs: u64) -> Summary {
    run_batch(s, RunOptions::default(), 3, runs, None, &|| {}).summary
}

#[test]
fn a_v_closes_into_a_column_and_opens_again_without_a_close_pair() {
    let s = file("change-v-column.toml", |_| {});
    assert_eq!(s.schedule().stages().len(), 2);
    // The column: every slot straight behind the navigator.
    assert!(s.formation_at(100.0).slots.iter().all(|slot| slot.offset_m.y.abs() < 1e-9));
    assert!(s.formation_at(10.0).slots.iter().any(|slot| slot.offset_m.y.abs() > 10.0));
    let r = batch(&s, 12);
    let c = r.transitions.as_ref().expect("the scenario changes formation");
    assert_eq!(c.completed_fraction, 1.0, "{c:?}");
    assert!(c.transition_s_max < 60.0, "{c:?}");
    assert_eq!(r.unsafe_runs, 0, "closest {}", r.min_separation_m);
    assert_eq!(r.pass_fraction, 1.0);
    // The closest pair during the changes: no closer than over the whole flight, and as far as
    // the slots' spacing allows (the V's pairs are 100 m apart).
    assert!(c.closest_m >= r.min_separation_m && c.closest_m >= 50.0 && c.closest_m < 100.0, "{c:?}");
}

#[test]
fn without_collision_avoidance_the_changing_uavs_come_too_close() {
    let r = batch(&file("change-v-column.toml", |s| s.controller.avoid_m = Some(0.0)), 12);
    assert!(r.unsafe_runs >= 6, "{} of 12, closest {}", r.unsafe_runs, r.min_separation_m);
}

#[test]
fn a_change_that_is_never_flown_to_fails_the_run() {
    // Without adjustment nobody moves to the column: the change is never completed.
    let s = file("change-v-column.toml", |_| {});
    let r = run_batch(&s, RunOptions { adjustment_enabled: false, ..RunOptions::default() }, 3, 2, None, &|| {});
    assert_eq!(r.summary.pass_fraction, 0.0);
    assert_eq!(r.summary.transitions.expect("changes").completed_fraction, 0.0);
}

#[test]
fn a_uav_joining_behind_its_slot_leaves_the_others_in_place_by_default() {
    // UAV5 of the paper appears 20 m behind its slot at 30 s. UAVs 4 and 6 lean on it with
    // degree 0.5: with the paper's plain means they follow it out of their allowable errors;
    // the robust fusion, on by default where a UAV joins, weighs its estimate against those
    // of the UAVs ahead and leaves it out.
    let join = |gate: Option<f64>| {
        Scenario::try_from(proxform_scenario::builtin::paper_spec().with(|s| {
            s.controller.isolation_gate = gate;
            s.fault = vec![proxform_scenario::spec::FaultSpec {
                kind: Some("join".into()),
                uav: Some(5),
                at_s: Some(30.0),
                duration_s: None,
                offset_m: Some([-20.0, 0.0, 0.0]),
            }];
        }))
        .expect("valid")
    };
    let worst_x = |s: &Summary, uav: u32| {
        let k = s.per_uav.iter().position(|&u| u == uav).expect("detail");
        s.per_uav_worst[k].as_array()[0]
    };
    let by_default = join(None);
    assert_eq!(by_default.controller().isolation_gate, Some(1.0), "on by default with a join");
    let fused = batch(&by_default, 10);
    let plain = batch(&join(Some(0.0)), 10);
    for uav in [2, 3, 4, 6] {
        let (w, a) = (worst_x(&fused, uav), fused.allowable_error.as_array()[0]);
        assert!(w <= a, "UAV{} x error {w} with the fusion", uav);
    }
    assert!(worst_x(&plain, 4) > 2.0, "{}", worst_x(&plain, 4));
    // A join passes when the others kept their errors and the joiner formed.
    let (f, p) = (fused.forming.as_ref().expect("a join forms"), plain.forming.as_ref().expect("a join forms"));
    assert!(f.settled_error_ratio_max.is_some_and(|r| r <= 1.0), "{f:?}");
    assert!(p.settled_error_ratio_max.is_some_and(|r| r > 4.0), "{p:?}");
    assert_eq!((fused.pass_fraction, plain.pass_fraction), (1.0, 0.0));
    // The paper itself, nobody joining, keeps the paper's plain means.
    assert_eq!(proxform_scenario::builtin::paper().controller().isolation_gate, None);
}

/// The paper's six, UAV2 (leaned on by UAVs 3, 4 and 5) lost at 40 s.
fn loss(reassign: bool, by: Option<&str>) -> Scenario {
    Scenario::try_from(proxform_scenario::builtin::paper_spec().with(|s| {
        s.formation.reassign_on_loss = Some(reassign);
        s.initial.assign_by = by.map(String::from);
        s.fault = vec![proxform_scenario::spec::FaultSpec::remove(2, 40.0)];
    }))
    .expect("valid")
}

/// Where UAV `uav` ends, relative to where slot `slot` of the paper's formation is then.
fn end_offset(sc: &Scenario, uav: usize, slot: usize) -> f64 {
    let mut sim = proxform_sim::Simulation::new(sc, RunOptions::default(), 3, 0);
    while sim.k() < sc.steps() {
        sim.step();
    }
    let s = sim.states();
    let f = sc.formation();
    let at = s[0] + f.w(&f.slots[slot], &f.slots[0], &s[0]);
    ((s[uav][0] - at[0]).powi(2) + (s[uav][1] - at[1]).powi(2) + (s[uav][2] - at[2]).powi(2)).sqrt()
}

#[test]
fn a_lost_uav_inside_the_formation_is_replaced_from_its_edge() {
    // Slots 4 and 6 are the edge (nobody leans on them); UAV4 is the nearer to slot 2.
    let sc = loss(true, None);
    assert!(end_offset(&sc, 3, 1) < 1.0, "UAV4 flies slot 2 at the end: {} m off", end_offset(&sc, 3, 1));
    let r = batch(&sc, 6);
    let c = r.transitions.as_ref().expect("a re-assignment is a change of formation");
    assert_eq!((c.completed_fraction, r.pass_fraction), (1.0, 1.0), "{c:?}");
    assert!(c.transition_s_max < 30.0, "{c:?}");
    assert_eq!(r.unsafe_runs, 0);
    // Without re-assignment slot 2 stays empty and UAV4 in its own.
    let fixed = loss(false, None);
    assert!(end_offset(&fixed, 3, 3) < 1.0 && end_offset(&fixed, 3, 1) > 50.0);
    assert!(batch(&fixed, 2).transitions.is_none());
}

#[test]
fn a_lost_uav_at_the_edge_moves_nobody() {
    let sc = Scenario::try_from(proxform_scenario::builtin::paper_spec().with(|s| {
        s.formation.reassign_on_loss = Some(true);
        s.fault = vec![proxform_scenario::spec::FaultSpec::remove(6, 40.0)];
    }))
    .expect("valid");
    let r = batch(&sc, 4);
    let c = r.transitions.as_ref().expect("re-assigned");
    assert_eq!(c.transition_s_max, 0.0, "{c:?}");
    assert!(c.transient_error_ratio_max <= 1.0, "{c:?}");
    assert_eq!(r.pass_fraction, 1.0);
}

#[test]
fn after_a_loss_a_later_formation_leaves_its_own_edge_empty() {
    // The V of nine loses UAV2 at 60 s, then becomes a column of 100 m spacing at 100 s: the
    // column's last slot (800 m behind the navigator) is the one left empty, not the V's
    // (which in the column lies 700 m behind, between two UAVs).
    let sc = file("reassign-v-loss.toml", |s| {
        let column = proxform_scenario::spec::ShapeSpec {
            kind: Some("column".into()),
            uavs: Some(9),
            spacing_m: Some(100.0),
            level_step_m: Some(-5.0),
            ..Default::default()
        };
        s.formation.change = vec![proxform_scenario::spec::FormationChangeSpec {
            at_s: Some(100.0),
            shape: Some(column),
            dependencies: s.formation.dependencies.clone(),
            ..Default::default()
        }];
    });
    let mut sim = proxform_sim::Simulation::new(&sc, RunOptions::default(), 3, 0);
    while sim.k() < sc.steps() {
        sim.step();
    }
    let s = sim.states();
    let mut behind: Vec<f64> = (1..9).filter(|&i| i != 1).map(|i| s[0][0] - s[i][0]).collect();
    behind.sort_by(f64::total_cmp);
    for (k, b) in behind.iter().enumerate() {
        assert!((b - 100.0 * (k + 1) as f64).abs() < 1.0, "the column's places 100 to 700 m: {behind:?}");
    }
    let r = batch(&sc, 4);
    let c = r.transitions.expect("a loss and a change");
    assert_eq!((c.completed_fraction, r.pass_fraction), (1.0, 1.0), "{c:?}");
}

/// Agents that step as the in-process ones and count, from a second after the first change of
/// formation on, each follower's main references of the new tables within its sensing range
/// (`checked`) that its sensors did not report onboard (`missed`).
struct Watching<'c> {
    inner: proxform_sim::world::remote::LocalAgents,
    tables: Vec<proxform_core::DependencySet>,
    from_s: f64,
    range_m: f64,
    counts: &'c std::cell::Cell<(usize, usize)>,
}

impl proxform_sim::world::remote::Agents for Watching<'_> {
    fn decide(
        &mut self,
        request: &proxform_sim::world::remote::StepRequest<'_>,
        out: &mut Vec<proxform_core::Decision>,
    ) {
        self.inner.decide(request, out);
        if request.phase != proxform_sim::world::remote::Phase::Fly || request.t_s < self.from_s {
            return;
        }
        let (mut checked, mut missed) = self.counts.get();
        let s = request.sensed;
        for (j, u) in s.uavs.iter().enumerate() {
            let heard = &s.heard[s.spans[j].clone()];
            let me = &request.truth[u.index()];
            for &(r, _) in self.tables[u.index()].refs() {
                let q = &request.truth[r.index()];
                let d2: f64 = (0..3).map(|k| (q[k] - me[k]).powi(2)).sum();
                if r == *u || d2 > self.range_m * self.range_m {
                    continue;
                }
                checked += 1;
                let onboard = heard.iter().any(|o| o.id == r && o.source == proxform_core::ObservationSource::Onboard);
                missed += usize::from(!onboard);
            }
        }
        self.counts.set((checked, missed));
    }
}

#[test]
fn after_a_change_of_formation_the_sensors_report_the_new_main_references() {
    // The shipped V that closes into a column at 60 s, without dropout: every main reference
    // of a follower's new table within its sensing range is reported onboard (the sensor reads
    // the tables flown now, as the controller does; it read the first formation's before).
    let sc = file("change-v-column.toml", |s| {
        s.sensing.dropout = Some(0.0);
        s.sensing.reference_dropout = Some(0.0);
        s.duration_s = Some(90.0);
    });
    let stage = &sc.schedule().stages()[0];
    let counts = std::cell::Cell::new((0, 0));
    let agents = Watching {
        inner: proxform_sim::world::remote::LocalAgents::new(&sc),
        tables: stage.dependencies.to_vec(),
        from_s: stage.at_s + 1.0,
        range_m: sc.controller().areas.sensing_range_m,
        counts: &counts,
    };
    let sim = proxform_sim::Simulation::with_agents(&sc, RunOptions::default(), (1, 0), Box::new(agents));
    let mut m = proxform_sim::RunMetrics::new(&sc);
    sim.run(&mut m);
    let (checked, missed) = counts.get();
    assert!(checked > 1000, "main references in range after the change: {checked}");
    assert_eq!(missed, 0, "of {checked} main references in range, {missed} not reported onboard");
}
