//! The distributed run: the world in `proxform`, each follower's controller in its own
//! `proxform-agent` process, over Zenoh on loopback (multicast scouting off). In lockstep it
//! is the in-process run, byte for byte.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_proxform")
}

fn out(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("proxform-distributed-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn run(args: &[&str], out: &Path) -> std::process::Output {
    let o = Command::new(bin())
        .arg("run")
        .args(args)
        .args(["--no-figures", "-q", "--out"])
        .arg(out)
        .output()
        .expect("proxform runs");
    assert!(o.status.code().is_some_and(|c| c <= 1), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

#[test]
fn lockstep_over_zenoh_is_the_in_process_run_byte_for_byte() {
    let (a, b) = (out("local"), out("net"));
    run(&["--seed", "3", "--duration-s", "40"], &a);
    let o = run(&["--seed", "3", "--duration-s", "40", "--distributed"], &b);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("5 agent process(es)") && stderr.contains(" 0 missing"), "{stderr}");
    for f in ["trajectories.csv", "summary.json", "runs.csv"] {
        let (x, y) = (std::fs::read(a.join(f)).expect("local"), std::fs::read(b.join(f)).expect("distributed"));
        assert!(x == y, "{f} differs between the in-process and the distributed run");
    }
    let _ = (std::fs::remove_dir_all(a), std::fs::remove_dir_all(b));
}
