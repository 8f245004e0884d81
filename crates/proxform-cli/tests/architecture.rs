//! The crate boundaries are the architecture: dependencies point down only, and the lower
//! crates stay free of what they must not do. Fails when a forbidden arrow appears.
//!
//! Layers, bottom to top: `proxform-core` (the method) → `proxform-scenario` (the scenario
//! model and file format) → `proxform-sim` (the simulated world, measurement, batches); the
//! network agent (`proxform-net`) sits on core and scenario and never links the simulator; the
//! Python package and the binary sit on top.

use std::collections::BTreeMap;
use std::path::Path;

/// Each workspace crate and the proxform crates it may depend on.
const ALLOWED: [(&str, &[&str]); 6] = [
    ("proxform-core", &[]),
    ("proxform-scenario", &["proxform-core"]),
    ("proxform-sim", &["proxform-core", "proxform-scenario"]),
    ("proxform-net", &["proxform-core", "proxform-scenario"]),
    ("proxform-py", &["proxform-core", "proxform-scenario", "proxform-sim"]),
    ("proxform-cli", &["proxform-core", "proxform-scenario", "proxform-sim", "proxform-net"]),
];

fn crates_dir() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

/// Every crate of the workspace with its dependencies (normal and build; dev-dependencies
/// are for tests and may reach further).
fn manifests() -> BTreeMap<String, Vec<String>> {
    let mut out = BTreeMap::new();
    for entry in std::fs::read_dir(crates_dir()).expect("crates/") {
        let path = entry.expect("entry").path().join("Cargo.toml");
        let Ok(text) = std::fs::read_to_string(&path) else { continue };
        let doc: toml::Table = toml::from_str(&text).expect("a valid manifest");
        let name = doc["package"]["name"].as_str().expect("a package name").to_string();
        let mut deps = Vec::new();
        for section in ["dependencies", "build-dependencies"] {
            if let Some(t) = doc.get(section).and_then(|d| d.as_table()) {
                deps.extend(t.keys().cloned());
            }
        }
        out.insert(name, deps);
    }
    out
}

#[test]
fn dependencies_point_down_only() {
    let manifests = manifests();
    assert!(manifests.len() >= 4, "found only {:?}", manifests.keys());
    for (name, deps) in &manifests {
        let allowed = ALLOWED
            .iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("{name} has no place in the layers: add it to ALLOWED"))
            .1;
        for d in deps.iter().filter(|d| d.starts_with("proxform")) {
            assert!(allowed.contains(&d.as_str()), "{name} must not depend on {d} (allowed: {allowed:?})");
        }
    }
    // The method has no random numbers, threads or files of its own.
    let core = &manifests["proxform-core"];
    for banned in ["rand", "rayon", "indicatif", "csv"] {
        assert!(!core.iter().any(|d| d == banned), "proxform-core depends on {banned}");
    }
}

/// Rust sources of a crate.
fn sources(krate: &str) -> Vec<(String, String)> {
    fn walk(dir: &Path, out: &mut Vec<(String, String)>) {
        for e in std::fs::read_dir(dir).expect("readable").flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push((p.display().to_string(), std::fs::read_to_string(&p).expect("readable")));
            }
        }
    }
    let mut out = Vec::new();
    walk(&crates_dir().join(krate).join("src"), &mut out);
    out
}

#[test]
fn the_method_and_the_scenario_model_do_no_io_and_read_no_clock() {
    let banned = ["std::fs", "std::net", "std::thread", "Instant::now", "SystemTime", "std::env", "println!"];
    for krate in ["proxform-core", "proxform-scenario"] {
        for (file, text) in sources(krate) {
            for b in banned {
                assert!(!text.contains(b), "{file} uses {b}: {krate} does no I/O, reads no clock, starts no threads");
            }
        }
    }
    // The simulator writes no files either: output belongs to the caller.
    for (file, text) in sources("proxform-sim") {
        assert!(!text.contains("std::fs"), "{file} touches the file system");
    }
}
