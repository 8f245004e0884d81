//! A printed scenario (`proxform run --print-scenario`, Python's `to_toml()`) runs the same as
//! the file it was printed from, bit for bit, for every shipped scenario; and a value the file
//! left to follow another key still follows it in the printed file.

use std::path::Path;

use proxform_scenario::load::{check, parse, parse_spec};
use proxform_scenario::resolved::to_toml;
use proxform_scenario::Scenario;
use proxform_sim::{run_batch, RunOptions, RunSummary};

/// The file's first 15 s (the whole flight when shorter), as written and as printed.
fn both(text: &str, name: &str) -> (Scenario, Scenario) {
    let spec = parse_spec(text, name).unwrap_or_else(|e| panic!("{name}: {e}"));
    let short = spec.clone().with(|s| s.duration_s = Some(s.duration_s.unwrap_or(f64::INFINITY).min(15.0)));
    let original = check(short, text, name).unwrap_or_else(|e| panic!("{name}: {e}"));
    let printed = to_toml(&original).expect("serialises");
    let again = parse(&printed, "printed.toml").unwrap_or_else(|e| panic!("{name} printed: {e}\n{printed}"));
    (original, again)
}

fn runs(s: &Scenario) -> Vec<RunSummary> {
    run_batch(s, RunOptions::default(), 7, 2, None, &|| {}).runs
}

#[test]
fn every_shipped_scenario_printed_runs_the_same_bit_for_bit() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../proxform-scenario/scenarios");
    let mut files: Vec<_> = std::fs::read_dir(&dir).expect("scenarios").map(|e| e.expect("entry").path()).collect();
    files.sort();
    let mut checked = 0;
    for path in files.iter().filter(|p| p.extension().is_some_and(|e| e == "toml")) {
        let name = path.file_name().and_then(|n| n.to_str()).expect("name").to_string();
        let text = std::fs::read_to_string(path).expect("readable");
        if name.starts_with("compare-") {
            continue; // a comparison's conditions, not a scenario
        }
        let (original, again) = both(&text, &name);
        assert_eq!(runs(&original), runs(&again), "{name}: the printed scenario runs differently");
        checked += 1;
    }
    assert!(checked >= 15, "only {checked} scenarios");
}

#[test]
fn a_value_left_to_follow_another_key_follows_it_in_the_printed_file() {
    // 30 % dropout, the reference dropout left to follow it; the printed file says so, and
    // changing the dropout there changes both.
    let text = proxform_scenario::builtin::PAPER.replace("dropout = 0.0", "dropout = 0.3");
    let (original, again) = both(&text, "dropout.toml");
    assert_eq!(again.reference_dropout(), 0.3);
    let printed = to_toml(&original).expect("serialises");
    assert!(printed.contains("# reference_dropout = 0.3"), "{printed}");
    let edited = printed.replace("dropout = 0.3\n", "dropout = 0.1\n");
    let s = parse(&edited, "edited.toml").expect("valid");
    assert_eq!((s.dropout(), s.reference_dropout()), (0.1, 0.1));
    // The separation and avoidance distances follow the safety distance the same way.
    let wider = printed.replace("safety_distance_m = 50.0", "safety_distance_m = 60.0");
    let s = parse(&wider, "wider.toml").expect("valid");
    assert_eq!(s.controller().separation_m, Some(120.0));
    // Units round-trip exactly: 0.18 km/h of velocity noise is the same m/s again.
    assert_eq!(again.noise().velocity_mps.to_bits(), original.noise().velocity_mps.to_bits());
}

#[test]
fn the_own_gates_growth_left_to_follow_the_turbulence_follows_it_in_the_printed_file() {
    // The own-sensor check set in the file, its growth left to the turbulence: printed, the
    // growth is a comment, and a changed turbulence changes it.
    let text = "name = \"g\"\n[formation.shape]\nkind = \"v\"\nuavs = 5\nspacing_m = 80.0\n[path]\nkind = \"paper\"\n\
                [wind]\nturbulence = \"light\"\n[controller]\nown_gate_m = 3.0\n";
    let (original, again) = both(text, "g.toml");
    assert_eq!(again.controller().own_gate_growth_mps, original.controller().own_gate_growth_mps);
    assert!(original.controller().own_gate_growth_mps > 3.0);
    let printed = to_toml(&original).expect("serialises");
    assert!(printed.contains("# own_gate_growth_mps = "), "{printed}");
    let calm = parse(&printed.replace("turbulence = \"light\"", "turbulence = \"none\""), "calm.toml").expect("valid");
    assert_eq!(calm.controller().own_gate_growth_mps, 1.0);
}
