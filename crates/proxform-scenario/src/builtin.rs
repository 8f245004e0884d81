//! The built-in scenarios and files: the paper's experiment, the large-swarm lattice, the
//! fixed-wing V, the annotated example and the built-in comparison.
//!
//! Each built-in is a spec, converted like any file: the paper's experiment is the file
//! `scenarios/paper.toml` of this crate (every other value its default), the swarm a spec
//! built for its size.

use crate::convert::SpecError;
use crate::scenario::Scenario;
use crate::spec::{AutoDepsSpec, FormationSpec, ScenarioSpec, ShapeSpec};

/// `scenarios/paper.toml`: the paper's six-UAV experiment (METHOD §9).
pub const PAPER: &str = include_str!("../scenarios/paper.toml");
/// `scenarios/fixed-wing-v.toml`: 12 fixed wings in a V, climb and 180° turn in turbulence.
pub const FIXED_WING_V: &str = include_str!("../scenarios/fixed-wing-v.toml");
/// `scenarios/aggregate.toml`: the paper's six from random starts within 1 km, then its path.
pub const AGGREGATE: &str = include_str!("../scenarios/aggregate.toml");
/// `scenarios/example.toml`: the annotated example `proxform init` writes.
pub const EXAMPLE: &str = include_str!("../scenarios/example.toml");
/// `scenarios/compare-paper.toml`: the built-in comparison.
pub const COMPARE_PAPER: &str = include_str!("../scenarios/compare-paper.toml");
/// `scenarios/multirotor-v12-circuit.toml`: 12 multirotors in a V around a square circuit in wind.
pub const MULTIROTOR_V12_CIRCUIT: &str = include_str!("../scenarios/multirotor-v12-circuit.toml");
/// `scenarios/multirotor-lattice50-eight.toml`: 50 multirotors take off, hover in a lattice and
/// fly a figure-eight.
pub const MULTIROTOR_LATTICE50_EIGHT: &str = include_str!("../scenarios/multirotor-lattice50-eight.toml");
/// `scenarios/fixed-wing-echelon7-crosswind.toml`: 7 fixed wings in an echelon through two 90°
/// turns in a 30 km/h crosswind.
pub const FIXED_WING_ECHELON7_CROSSWIND: &str = include_str!("../scenarios/fixed-wing-echelon7-crosswind.toml");

/// The built-in scenarios that are files of this crate: name and text.
pub const FILES: [(&str, &str); 5] = [
    ("fixed-wing-v", FIXED_WING_V),
    ("aggregate", AGGREGATE),
    ("multirotor-v12-circuit", MULTIROTOR_V12_CIRCUIT),
    ("multirotor-lattice50-eight", MULTIROTOR_LATTICE50_EIGHT),
    ("fixed-wing-echelon7-crosswind", FIXED_WING_ECHELON7_CROSSWIND),
];

/// Names of the built-in scenarios.
pub const NAMES: [&str; 7] = [
    "paper",
    "swarm",
    "fixed-wing-v",
    "aggregate",
    "multirotor-v12-circuit",
    "multirotor-lattice50-eight",
    "fixed-wing-echelon7-crosswind",
];

/// Horizontal spacing of the swarm's lattice (m).
pub const SWARM_SPACING_M: f64 = 50.0;
/// Vertical spacing of the swarm's levels (m).
pub const SWARM_LEVEL_M: f64 = 20.0;
/// Dependency degree of every swarm follower on the navigator, heard over the radio. Without
/// it errors grow along the reference chains of a deep lattice (see README, Large swarms).
pub const SWARM_NAVIGATOR_DEGREE: f64 = 0.3;
/// UAVs of the swarm when no size is given.
pub const SWARM_DEFAULT_UAVS: usize = 1000;

/// The spec of the paper's experiment.
pub fn paper_spec() -> ScenarioSpec {
    crate::load::parse_spec(PAPER, "paper.toml").expect("the built-in paper.toml parses")
}

/// The paper's experiment.
pub fn paper() -> Scenario {
    Scenario::try_from(paper_spec()).expect("the built-in paper.toml is a valid scenario")
}

/// The spec of the swarm scenario with `n` UAVs: a multi-level lattice (rows of columns 50 m
/// apart on up to four levels 20 m apart) behind the navigator, dependency tables derived from
/// the geometry with the navigator heard over the radio, the paper's lateral and speed
/// manoeuvres with gentler attitude sweeps; noise and vehicle are the paper's.
pub fn swarm_spec(n: usize) -> ScenarioSpec {
    let range = 1.6 * SWARM_SPACING_M;
    let mut s = ScenarioSpec { name: Some("swarm".into()), safety_distance_m: Some(10.0), ..ScenarioSpec::default() };
    s.formation = FormationSpec {
        shape: Some(ShapeSpec {
            kind: Some("lattice".into()),
            uavs: Some(n.min(u32::MAX as usize) as u32),
            spacing_m: Some(SWARM_SPACING_M),
            level_step_m: Some(-SWARM_LEVEL_M),
            ..ShapeSpec::default()
        }),
        dependencies: Some(AutoDepsSpec {
            k: Some(3),
            max_distance_m: Some(range),
            navigator_degree: Some(SWARM_NAVIGATOR_DEGREE),
        }),
        ..FormationSpec::default()
    };
    s.path.kind = Some("paper".into());
    s.path.height_amplitude_m = Some(10.0);
    s.path.pitch_swing_deg = Some(10.0);
    s.path.yaw_amplitude_deg = Some(5.0);
    s.path.roll_amplitude_deg = Some(10.0);
    s.controller.sensing_range_m = Some(range);
    // A lean swarm at every size (`proxform bench` compares the engines on it, and 10^6 UAVs
    // fit in 1 GiB): the own-sensor check (some 240 bytes a UAV) and the robust fusion are
    // stated off, so that the bench's figures stay those of the same work.
    s.controller.own_gate_m = Some(0.0);
    s.controller.isolation_gate = Some(0.0);
    s.allowable.x_m = Some(5.0);
    s.allowable.y_m = Some(5.0);
    s.allowable.z_m = Some(5.0);
    s.allowable.alpha_deg = Some(2.0);
    s.allowable.beta_deg = Some(2.0);
    s.allowable.gamma_deg = Some(3.0);
    s.radio.beacons = Some(vec![1]);
    s
}

/// The swarm scenario with `n ≥ 2` UAVs.
pub fn swarm(n: usize) -> Result<Scenario, SpecError> {
    Scenario::try_from(swarm_spec(n))
}

/// The spec of a built-in scenario by name; `uavs` sizes the swarm (and only the swarm).
pub fn spec_by_name(name: &str, uavs: Option<usize>) -> Result<ScenarioSpec, String> {
    match (name, uavs) {
        ("paper", None) => Ok(paper_spec()),
        ("swarm", n) => Ok(swarm_spec(n.unwrap_or(SWARM_DEFAULT_UAVS))),
        (name, uavs) => match FILES.iter().find(|f| f.0 == name) {
            _ if NAMES.contains(&name) && uavs.is_some() => {
                Err(format!("a number of UAVs applies to the built-in swarm only, not to {name}"))
            }
            Some((name, text)) => {
                Ok(crate::load::parse_spec(text, &format!("{name}.toml")).expect("the built-in file parses"))
            }
            None => Err(format!("unknown scenario '{name}' (built-in: {})", NAMES.join(", "))),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_built_in_is_valid() {
        let p = paper();
        assert_eq!((p.len(), p.steps()), (6, 1000));
        assert_eq!(p.dependencies()[4].degree(proxform_core::UavId(0)), Some(0.3));
        assert_eq!(p.dependencies()[3].refs().len(), 2);
        let s = swarm(500).expect("valid");
        assert!(s.dependencies().iter().skip(1).all(|d| !d.is_empty()));
        assert_eq!(s.beacons(), &[proxform_core::UavId(0)]);
        for name in NAMES {
            Scenario::try_from(spec_by_name(name, None).expect("known")).expect("valid");
        }
        let e = crate::load::parse(EXAMPLE, "example.toml").expect("the example loads");
        assert!(e.len() >= 2);
        assert!(swarm(1).is_err(), "one UAV is no swarm");
    }

    #[test]
    fn derived_tables_that_lean_on_the_navigator_make_it_broadcast() {
        let v = |degree: f64| {
            crate::load::parse(
                &format!(
                    "[formation.shape]\nkind = \"v\"\nuavs = 9\nspacing_m = 80.0\n\
                     [formation.dependencies]\nnavigator_degree = {degree}\n"
                ),
                "v.toml",
            )
            .expect("valid")
        };
        assert_eq!(v(0.4).beacons(), &[proxform_core::UavId(0)]);
        assert!(v(0.4).dependencies()[8].degree(proxform_core::UavId(0)).is_some());
        assert!(v(0.0).beacons().is_empty());
        assert!(v(0.4).warnings().is_empty());
        // A radio that does not reach the rear of the V: those UAVs are named.
        let short = crate::load::parse(
            "[formation.shape]\nkind = \"v\"\nuavs = 9\nspacing_m = 100.0\n\
             [formation.dependencies]\nnavigator_degree = 0.4\n[radio]\nrange_m = 260.0\n\
             [controller]\nsensing_range_m = 250.0\n",
            "v.toml",
        )
        .expect("valid");
        let w: Vec<String> = short.warnings().iter().map(|w| w.to_string()).collect();
        assert!(
            w.iter().any(|w| w.contains("UAVs 6, 7, 8, 9 fly beyond the reach of the navigator's radio (260 m)")),
            "{w:?}"
        );
        // Relayed hop by hop, the navigator's state reaches every UAV of the V.
        let relayed = crate::load::parse(
            "[formation.shape]\nkind = \"v\"\nuavs = 9\nspacing_m = 100.0\n\
             [formation.dependencies]\nnavigator_degree = 0.4\n[radio]\nrange_m = 260.0\nrelay_navigator = true\n\
             [controller]\nsensing_range_m = 250.0\n",
            "v.toml",
        )
        .expect("valid");
        assert!(relayed.warnings().is_empty(), "{:?}", relayed.warnings());
        assert!(relayed.radio().relay_navigator);
    }

    #[test]
    fn the_paper_method_leaves_out_what_proxform_adds_unless_the_file_sets_it() {
        let v = |controller: &str| {
            crate::load::parse(
                &format!("[formation.shape]\nkind = \"v\"\nuavs = 9\nspacing_m = 80.0\n[controller]\n{controller}\n"),
                "v.toml",
            )
            .expect("valid")
        };
        let nav = proxform_core::UavId(0);
        let default = v("");
        assert!(default.dependencies()[8].degree(nav).is_some());
        assert!(default.controller().plan_forward);
        let paper = v("method = \"paper\"");
        assert!(paper.dependencies()[8].degree(nav).is_none(), "the paper's derived tables hold neighbours only");
        assert!(paper.beacons().is_empty());
        assert!(!paper.controller().plan_forward);
        assert!(paper.controller().isolation_gate.is_none());
        assert_eq!((default.controller().own_gate_m, paper.controller().own_gate_m), (Some(3.0), None));
        // Above the position noise: 4 √2 σ where that exceeds 3 m; a gate set within it warns.
        let noisy = v("\n[noise]\nposition_m = 1.5");
        let gate = noisy.controller().own_gate_m.expect("on");
        assert!((gate - 4.0 * std::f64::consts::SQRT_2 * 1.5).abs() < 1e-9, "{gate}");
        assert!(noisy.warnings().iter().all(|w| w.key != "controller.own_gate_m"));
        let set = v("own_gate_m = 3.0\n[noise]\nposition_m = 1.5");
        assert_eq!(set.controller().own_gate_m, Some(3.0), "the file's own");
        assert!(set.warnings().iter().any(|w| w.key == "controller.own_gate_m"), "{:?}", set.warnings());
        // Keys the file sets win.
        assert!(v("method = \"paper\"\nplan_forward = true").controller().plan_forward);
        let e = crate::load::parse(
            "[formation.shape]\nkind = \"v\"\nuavs = 3\nspacing_m = 80.0\n[controller]\nmethod = \"papers\"\n",
            "m.toml",
        )
        .expect_err("unknown");
        assert!(e.to_string().contains("\"paper\""), "{e}");
    }
}
