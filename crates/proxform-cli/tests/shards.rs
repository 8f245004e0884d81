//! Shards, merges, resumed batches and sweeps as a user runs them: every way of splitting or
//! interrupting a batch writes the same `summary.json` and `runs.csv` as the batch run whole.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn proxform() -> Command {
    Command::new(env!("CARGO_BIN_EXE_proxform"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

fn ok(o: Output) -> String {
    let text = format!("{}\n{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.code().is_some_and(|c| c <= 1), "{text}");
    text
}

fn refused(o: Output) -> String {
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(2), "{err}\n{}", String::from_utf8_lossy(&o.stdout));
    assert!(!err.contains("panicked"), "{err}");
    err
}

/// `proxform run` of `scenario` (a file or `None` for the paper) into `out` with `extra`.
fn run(scenario: Option<&Path>, out: &Path, extra: &[&str]) -> Output {
    let mut c = proxform();
    c.arg("run");
    if let Some(f) = scenario {
        c.arg(f);
    }
    c.args(["-q", "--no-figures", "--no-trajectories", "--out"]).arg(out).args(extra);
    if !extra.contains(&"--threads") {
        c.args(["--threads", "2"]);
    }
    c.output().expect("proxform runs")
}

fn same_outputs(a: &Path, b: &Path) {
    for f in ["summary.json", "runs.csv"] {
        let (x, y) = (std::fs::read(a.join(f)).expect("output"), std::fs::read(b.join(f)).expect("output"));
        assert!(x == y, "{f} of {} and {} differ", a.display(), b.display());
    }
}

/// Shards of `runs` runs each, `count` of them, merged, equal the batch of all of them.
fn shards_merge_to_the_batch(name: &str, scenario: Option<&Path>, count: u64, runs: u64) {
    let dir = scratch(name);
    let whole = dir.join("whole");
    ok(run(scenario, &whole, &["--runs", &(count * runs).to_string()]));
    let mut shards = Vec::new();
    // Shards in an order of their own, on another thread count: neither matters.
    for k in (0..count).rev() {
        let s = dir.join(format!("shard{k}"));
        let first = (k * runs).to_string();
        let mut extra = vec!["--runs".to_string(), runs.to_string(), "--first-run".into(), first];
        extra.extend(["--threads".into(), (1 + k % 2).to_string()]);
        let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
        ok(run(scenario, &s, &extra));
        shards.push(s);
    }
    let merged = dir.join("merged");
    let text = ok(proxform().arg("merge").args(&shards).arg("--out").arg(&merged).output().expect("merges"));
    assert!(text.contains(&format!("merged {count} shard(s)")), "{text}");
    same_outputs(&whole, &merged);
    // A merge merges again (its journal is a shard of the same batch).
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(merged.join("summary.json")).expect("summary")).expect("JSON");
    assert_eq!(summary["runs"], count * runs);
}

#[test]
fn ten_shards_of_the_paper_merge_to_the_batch_of_a_thousand_byte_for_byte() {
    shards_merge_to_the_batch("shards-paper", None, 10, 100);
}

#[test]
fn shards_with_faults_forming_and_a_lost_uav_merge_to_the_batch() {
    let dir = scratch("shards-faults-src");
    let base = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios/aggregate.toml"))
        .expect("aggregate.toml");
    let text = format!(
        "{base}\n[[fault]]\nkind = \"stuck_sensor\"\nuav = 4\nat_s = 150.0\nduration_s = 5.0\n\n\
         [[fault]]\nkind = \"glitch\"\nuav = 6\nat_s = 200.0\nduration_s = 2.0\noffset_m = [0.0, 8.0, 0.0]\n\n\
         [[fault]]\nkind = \"remove\"\nuav = 3\nat_s = 220.0\n"
    );
    let file = dir.join("forming-faults.toml");
    std::fs::write(&file, text).expect("scenario file");
    shards_merge_to_the_batch("shards-faults", Some(&file), 10, 10);
    let s: serde_json::Value = serde_json::from_slice(
        &std::fs::read(PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("shards-faults/merged/summary.json"))
            .expect("summary"),
    )
    .expect("JSON");
    assert!(s["sensor_faults"].is_object() && s["forming"].is_object(), "{s}");
}

#[test]
fn merges_refuse_shards_that_are_not_one_batch_naming_them() {
    let dir = scratch("shards-refused");
    let shard = |name: &str, extra: &[&str]| {
        let d = dir.join(name);
        ok(run(None, &d, extra));
        d
    };
    let a = shard("a", &["--runs", "3"]);
    let b = shard("b", &["--runs", "3", "--first-run", "3"]);
    let overlap = shard("overlap", &["--runs", "3", "--first-run", "2"]);
    let gap = shard("gap", &["--runs", "3", "--first-run", "7"]);
    let seed = shard("seed", &["--runs", "3", "--first-run", "3", "--seed", "9"]);
    let other = shard("other", &["--runs", "3", "--first-run", "3", "--lambda", "0.5"]);
    let merge =
        |dirs: &[&PathBuf]| proxform().arg("merge").args(dirs).arg("--out").arg(dir.join("m")).output().expect("runs");
    ok(merge(&[&b, &a]));
    let e = refused(merge(&[&a, &overlap]));
    assert!(e.contains("run 2 is in both") && e.contains("overlap"), "{e}");
    let e = refused(merge(&[&a, &gap]));
    assert!(e.contains("runs 3..=6 are in none"), "{e}");
    let e = refused(merge(&[&a, &seed]));
    assert!(e.contains("seeds 1 and 9") && e.contains("seed"), "{e}");
    let e = refused(merge(&[&a, &other]));
    assert!(e.contains("different scenarios") && e.contains("other"), "{e}");
    let e = refused(proxform().arg("merge").arg(&a).arg("--out").arg(&a).output().expect("runs"));
    assert!(e.contains("holds the shard"), "{e}");
    // Not a journal, and a journal cut inside its header.
    std::fs::write(dir.join("junk.journal"), b"PXFJRNL1 not really").expect("write");
    let e = refused(
        proxform().arg("merge").arg(dir.join("junk.journal")).arg("--out").arg(dir.join("m2")).output().expect("runs"),
    );
    assert!(e.contains("junk.journal"), "{e}");
    // An unfinished shard: its last commit cut off.
    let j = b.join("runs.journal");
    let bytes = std::fs::read(&j).expect("journal");
    std::fs::write(&j, &bytes[..bytes.len() - 3]).expect("write");
    let e = refused(merge(&[&a, &b]));
    assert!(e.contains("unfinished") && e.contains("0 of its 3 runs") && e.contains("--resume"), "{e}");
    // ... which --resume completes to the same outputs.
    ok(run(None, &b, &["--runs", "3", "--first-run", "3", "--resume"]));
    ok(merge(&[&a, &b]));
    // --resume of another batch is refused, naming what differs.
    let e = refused(run(None, &b, &["--runs", "4", "--first-run", "3", "--resume"]));
    assert!(e.contains("--runs 3") && e.contains("without --resume"), "{e}");
    // --resume where nothing was started starts the batch.
    let fresh = dir.join("fresh");
    let text = ok(run(None, &fresh, &["--runs", "3", "--resume"]));
    assert!(text.contains("resuming: 0 of 3 runs done"), "{text}");
    same_outputs(&a, &fresh);
}

#[test]
fn a_batch_killed_midway_resumes_to_the_outputs_of_an_uninterrupted_one() {
    let dir = scratch("resume");
    let (whole, cut) = (dir.join("whole"), dir.join("cut"));
    ok(run(None, &whole, &["--runs", "600"]));
    let mut child = proxform()
        .args(["run", "-q", "--no-figures", "--no-trajectories", "--threads", "2", "--runs", "600", "--out"])
        .arg(&cut)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("starts");
    // Killed once some runs are committed (the journal beyond its header), within 60 s.
    let journal = cut.join("runs.journal");
    let started = Instant::now();
    while std::fs::metadata(&journal).map_or(0, |m| m.len()) < 20_000 && started.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let status = child.wait().expect("ended");
    assert!(!status.success(), "the batch ended before it was killed: make it longer");
    assert!(!cut.join("summary.json").exists());
    // A torn tail as a kill during a write leaves it.
    let mut bytes = std::fs::read(&journal).expect("journal");
    bytes.extend_from_slice(&[2, 200, 1, 0, 0, 7, 7]);
    std::fs::write(&journal, bytes).expect("write");
    let text = ok(run(None, &cut, &["--runs", "600", "--resume"]));
    let done: u64 = text
        .split("resuming: ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no resume line in {text}"));
    assert!(done > 0 && done < 600, "{done} runs were done: {text}");
    same_outputs(&whole, &cut);
    // Resuming a finished batch flies nothing and writes the same again.
    let text = ok(run(None, &cut, &["--runs", "600", "--resume"]));
    assert!(text.contains("resuming: 600 of 600"), "{text}");
    same_outputs(&whole, &cut);
}

#[test]
fn a_sweep_of_two_by_three_cells_equals_the_six_single_batches() {
    let dir = scratch("sweep");
    let out = dir.join("sweep");
    let text = ok(proxform()
        .args(["sweep", "-q", "--runs", "50", "--threads", "2"])
        .args(["--set", "controller.lambda=0.5,0.8", "--set", "sensing.dropout=0,0.1,0.3", "--out"])
        .arg(&out)
        .output()
        .expect("sweeps"));
    assert!(text.contains("6 cells × 50 runs"), "{text}");
    let table = std::fs::read_to_string(out.join("sweep.csv")).expect("sweep.csv");
    let rows: Vec<&str> = table.lines().collect();
    assert_eq!(rows.len(), 7, "{table}");
    assert!(rows[0].starts_with("cell,controller.lambda,sensing.dropout,runs,pass_fraction"), "{table}");
    let mut k = 0;
    for lambda in ["0.5", "0.8"] {
        for dropout in ["0", "0.1", "0.3"] {
            k += 1;
            let single = dir.join(format!("single{k}"));
            let (l, d) = (format!("controller.lambda={lambda}"), format!("sensing.dropout={dropout}"));
            ok(run(None, &single, &["--runs", "50", "--set", &l, "--set", &d]));
            same_outputs(&single, &out.join(format!("cell-{k:03}")));
            let cols: Vec<&str> = rows[k].split(',').collect();
            assert_eq!((cols[1], cols[2]), (lambda, dropout), "{}", rows[k]);
            let s: serde_json::Value =
                serde_json::from_slice(&std::fs::read(single.join("summary.json")).expect("summary")).expect("JSON");
            assert_eq!(cols[4].parse::<f64>().ok(), s["pass_fraction"].as_f64(), "{}", rows[k]);
        }
    }
    // Every cell is checked before anything flies; errors name the cell and the key.
    let bad = dir.join("bad");
    let e = refused(
        proxform()
            .args(["sweep", "-q", "--set", "controller.lambda=0.5,1.5", "--out"])
            .arg(&bad)
            .output()
            .expect("runs"),
    );
    assert!(e.contains("cell controller.lambda=1.5") && e.contains("--set controller.lambda=1.5"), "{e}");
    assert!(!bad.join("cell-001").exists(), "a cell flew before every cell was checked");
    let e = refused(
        proxform().args(["sweep", "-q", "--set", "controller.lamda=0.5", "--out"]).arg(&bad).output().expect("runs"),
    );
    assert!(e.contains("lamda"), "{e}");
    let e = refused(proxform().args(["run", "-q", "--set", "radio.delay_s"]).output().expect("runs"));
    assert!(e.contains("KEY=VALUE"), "{e}");
}

#[test]
fn a_sweep_prints_its_cells_warnings_once_each() {
    // The cell with position noise of 3 m flies a 3 m own-sensor gate within it: warned
    // about once (the other cell, 0.5 m, has none), as `proxform run` warns.
    let dir = scratch("sweep-warnings");
    let text = ok(proxform()
        .args(["sweep", "-q", "--set", "noise.position_m=0.5,3", "--set", "controller.own_gate_m=3,3.0", "--out"])
        .arg(dir.join("out"))
        .output()
        .expect("sweeps"));
    let warned = text.lines().filter(|l| l.starts_with("warning:") && l.contains("controller.own_gate_m")).count();
    assert_eq!(warned, 1, "{text}");
}

#[test]
fn a_batch_of_many_runs_holds_a_few_numbers_per_run_not_the_runs() {
    // 10^5 one-step runs: holding every run's summary costs ~1.2 kB each (126 MiB peak when
    // it did); the fold in run order and the journal on disk hold ~100 bytes (16 MiB).
    let out = scratch("many-runs");
    let text = ok(run(None, &out, &["--duration-s", "0.2", "--runs", "100000"]));
    let mib: f64 = text
        .lines()
        .find_map(|l| l.strip_prefix("peak memory"))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no peak memory line in {text}"));
    assert!(mib < 48.0, "peak memory {mib} MiB for 10^5 runs");
    let rows = std::fs::read_to_string(out.join("runs.csv")).expect("runs.csv").lines().count();
    assert_eq!(rows, 100_001);
}
