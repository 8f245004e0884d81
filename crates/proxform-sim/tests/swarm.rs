//! The large-swarm scenario: parallel stepping is bit-identical to serial stepping, the grid
//! finds what all-pairs finds, and the formation stays bounded and safe.

use proxform_scenario::builtin::swarm_spec;
use proxform_scenario::formation::lattice::lattice;
use proxform_scenario::{Scenario, ScenarioSpec};
use proxform_sim::world::options::NeighbourSearch;
use proxform_sim::{RunMetrics, RunOptions, Simulation};

fn run_with(scenario: &Scenario, options: RunOptions, threads: usize, parallel: bool) -> proxform_sim::RunSummary {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
    pool.install(|| {
        let sim = Simulation::new(scenario, options, 7, 0).with_parallel(parallel);
        let mut m = RunMetrics::new(scenario);
        sim.run(&mut m);
        m.finish(0, scenario.duration_s())
    })
}

fn run(scenario: &Scenario, threads: usize, parallel: bool) -> proxform_sim::RunSummary {
    run_with(scenario, RunOptions::default(), threads, parallel)
}

fn swarm(n: usize, edit: impl FnOnce(&mut ScenarioSpec)) -> Scenario {
    Scenario::try_from(swarm_spec(n).with(edit)).expect("valid")
}

#[test]
fn parallel_stepping_is_bit_identical_to_serial() {
    let s = swarm(1500, |s| s.duration_s = Some(3.0));
    let serial = run(&s, 1, false);
    let par1 = run(&s, 1, true);
    let par2 = run(&s, 2, true);
    let par3 = run(&s, 3, true);
    assert_eq!(serial, par1);
    assert_eq!(serial, par2);
    assert_eq!(serial, par3);
}

#[test]
fn grid_search_sees_what_all_pairs_sees() {
    let s = swarm(300, |s| s.duration_s = Some(5.0));
    let grid = run(&s, 2, false);
    let naive =
        run_with(&s, RunOptions { neighbour_search: NeighbourSearch::AllPairs, ..RunOptions::default() }, 2, false);
    assert_eq!(grid, naive);
}

#[test]
fn a_deep_swarm_stays_bounded_and_safe() {
    let s = swarm(2000, |_| {});
    let r = run(&s, 2, true);
    let allow = s.allowable().as_array();
    for k in 0..6 {
        assert!(r.max_abs_error[k] < allow[k], "axis {k}: {} ≥ {}", r.max_abs_error[k], allow[k]);
    }
    assert!(r.min_separation_m >= s.safety_distance_m(), "min separation {}", r.min_separation_m);
}

#[test]
fn without_the_navigator_beacon_errors_grow_along_the_chains() {
    // The same lattice with purely local dependency tables and no radio beacon.
    let local = swarm(2000, |s| {
        s.radio.beacons = None;
        if let Some(d) = &mut s.formation.dependencies {
            // Derived tables lean on the navigator unless told not to.
            d.navigator_degree = Some(0.0);
        }
    });
    let with = run(&swarm(2000, |_| {}), 2, true);
    let without = run(&local, 2, true);
    assert!(
        without.max_abs_error[1] > 3.0 * with.max_abs_error[1],
        "{:?} vs {:?}",
        without.max_abs_error,
        with.max_abs_error
    );
}

#[test]
fn the_swarm_file_builds_the_same_lattice_at_any_size() {
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios/swarm.toml")).expect("file");
    let small = text.replace("uavs = 10000", "uavs = 1500").replace("duration_s = 100.0", "duration_s = 3.0");
    let s = proxform_scenario::load::parse(&small, "swarm.toml").expect("valid");
    assert_eq!(s.len(), 1500);
    assert_eq!(s.formation().slots, lattice(1500), "the file's lattice is the built-in one");
    assert!(s.dependencies().iter().skip(1).all(|d| d.degree(proxform_core::UavId(0)).is_some()));
    let r = run(&s, 2, true);
    assert!(r.min_separation_m >= s.safety_distance_m());
    assert!(r.max_abs_error.iter().zip(s.allowable().as_array()).all(|(e, a)| *e < a), "{:?}", r.max_abs_error);
}
