//! Hostile input, as a new user or an attacker might give it: every file in `tests/hostile/`
//! is run through the binary and must end with the exit code and the message its header
//! names (`# args:`, `# exit:`, `# expect:`); inputs too large or too strange to keep in the
//! repository are made here. Nothing may panic, hang, fill memory or write outside `out/`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn header<'a>(text: &'a str, tag: &str) -> Option<&'a str> {
    text.lines().find_map(|l| l.strip_prefix(tag).map(str::trim))
}

/// A scratch folder of its own for each case (the binary's `out/` goes there).
fn scratch(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("hostile").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch folder");
    d
}

/// Runs the binary in `cwd` with `args`, killed (by its id) if it is not done in 60 s.
fn run(cwd: &Path, args: &[String]) -> Output {
    let child = Command::new(env!("CARGO_BIN_EXE_proxform"))
        .args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starts");
    let id = child.id();
    let started = Instant::now();
    let watchdog = std::thread::spawn(move || {
        while started.elapsed() < Duration::from_secs(60) {
            std::thread::sleep(Duration::from_millis(100));
            if !Path::new(&format!("/proc/{id}")).exists() {
                return false;
            }
        }
        let _ = Command::new("kill").args(["-9", &id.to_string()]).status();
        true
    });
    let out = child.wait_with_output().expect("ends");
    let _ = watchdog;
    out
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

#[test]
fn every_hostile_file_ends_as_its_header_says() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/hostile");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir).expect("tests/hostile").flatten().map(|e| e.path()).collect();
    files.sort();
    assert!(files.len() >= 10, "only {} hostile files", files.len());
    for path in files {
        let name = path.file_stem().and_then(|s| s.to_str()).expect("name").to_string();
        let body = std::fs::read_to_string(&path).expect("readable");
        let cwd = scratch(&name);
        // The file is copied beside the run, so messages name it by its plain file name.
        let file = format!("{name}.toml");
        std::fs::write(cwd.join(&file), &body).expect("copy");
        let mut args: Vec<String> = header(&body, "# args:")
            .unwrap_or_else(|| panic!("{name}: no '# args:'"))
            .split_whitespace()
            .map(|a| if a == "OUT" { cwd.join("result").display().to_string() } else { a.to_string() })
            .collect();
        args.push(file);
        let o = run(&cwd, &args);
        let all = text(&o);
        let exit: i32 =
            header(&body, "# exit:").and_then(|e| e.parse().ok()).unwrap_or_else(|| panic!("{name}: no '# exit:'"));
        assert_eq!(o.status.code(), Some(exit), "{name}: {all}");
        let expect = header(&body, "# expect:").unwrap_or_else(|| panic!("{name}: no '# expect:'"));
        assert!(all.contains(expect), "{name}: expected «{expect}» in «{all}»");
        assert!(!all.contains("panicked"), "{name}: {all}");
    }
    // Names stay inside out/: nothing was written where the names pointed.
    assert!(!Path::new("/tmp/proxform-abs").exists(), "an absolute name escaped out/");
    let escape = scratch("escape_name_check");
    assert!(!escape.join("../../escape").exists());
}

#[test]
fn strange_files_and_arguments_are_refused_at_once() {
    let cwd = scratch("strange");
    // Not regular files: a device that never ends, a FIFO with no writer, a folder.
    let fifo = cwd.join("fifo.toml");
    let made = Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success());
    let mut cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["run".into(), "/dev/zero".into()], "is not a regular file"),
        (vec!["run".into(), cwd.display().to_string()], "is not a regular file"),
        (vec!["run".into(), "--threads".into(), "99999".into()], "at most 256"),
        (vec!["compare".into(), "--seeds".into(), "0".into()], "--seeds"),
        (
            vec!["run".into(), "--duration-s".into(), "1e12".into()],
            "--duration-s: 1e12 s at Δt = 0.1 s is more than 1e8 steps",
        ),
        (vec!["run".into(), "--lambda".into(), "nan".into()], "--lambda"),
    ];
    if made {
        cases.push((vec!["run".into(), fifo.display().to_string()], "is not a regular file"));
    }
    // Outputs are never written through a link, nor opened when a FIFO or folder took their name.
    let target = cwd.join("elsewhere.json");
    std::fs::write(&target, "keep").expect("write");
    let outs = |k: &str| {
        let d = cwd.join(format!("outs-{k}"));
        std::fs::create_dir_all(&d).expect("folder");
        d
    };
    let (o1, o2, o3) = (outs("link"), outs("fifo"), outs("folder"));
    if std::os::unix::fs::symlink(&target, o1.join("summary.json")).is_ok() {
        cases.push((
            vec!["run".into(), "--no-trajectories".into(), "--out".into(), o1.display().to_string()],
            "is a symbolic link",
        ));
    }
    if Command::new("mkfifo").arg(o2.join("trajectories.csv")).status().is_ok_and(|s| s.success()) {
        cases.push((
            vec!["run".into(), "--out".into(), o2.display().to_string()],
            "trajectories.csv exists and is not a regular file",
        ));
    }
    std::fs::create_dir_all(o3.join("runs.journal")).expect("folder");
    cases.push((
        vec!["run".into(), "--no-trajectories".into(), "--no-figures".into(), "--out".into(), o3.display().to_string()],
        "runs.journal exists and is not a regular file",
    ));
    let dangling = cwd.join("dangling.toml");
    if std::os::unix::fs::symlink(cwd.join("nowhere"), &dangling).is_ok() {
        cases.push((vec!["init".into(), dangling.display().to_string()], "already exists"));
        cases.push((vec!["init".into(), "--force".into(), dangling.display().to_string()], "is a symbolic link"));
    }
    // A 20 MB file of waypoints is refused before it is parsed.
    let big = cwd.join("big.toml");
    let mut waypoints = String::from("[formation.shape]\nkind = \"v\"\nuavs = 3\nspacing_m = 100.0\n[path]\nkind = \"waypoints\"\nspeed_kmh = 250.0\nturn_radius_m = 500.0\npoints_m = [\n");
    while waypoints.len() < 20 << 20 {
        waypoints.push_str("[123456.0, 654321.0, 100.0],\n");
    }
    waypoints.push_str("]\n");
    std::fs::write(&big, waypoints).expect("big file");
    cases.push((vec!["run".into(), big.display().to_string()], "bytes, more than the 16777216 bytes (16 MiB)"));
    for (args, expect) in cases {
        let started = Instant::now();
        let o = run(&cwd, &args);
        assert_eq!(std::fs::read_to_string(&target).ok().as_deref(), Some("keep"), "{args:?} wrote through a link");
        let all = text(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {all}");
        assert!(all.contains(expect), "{args:?}: expected «{expect}» in «{all}»");
        assert!(started.elapsed() < Duration::from_secs(20), "{args:?} took {:?}", started.elapsed());
    }
}

#[test]
fn a_refused_command_leaves_no_folder_and_a_sweep_none_of_an_earlier_ones_cells() {
    let dir = scratch("folders");
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    let short = ["--duration-s", "1", "--no-figures", "-q"];
    let a = run(&dir, &[s(&["run", "--runs", "2", "--out", "a"]), s(&short)].concat());
    let b = run(
        &dir,
        &[s(&["run", "--scenario", "swarm", "--uavs", "10", "--first-run", "2", "--out", "b"]), s(&short)].concat(),
    );
    assert!(a.status.code().is_some() && b.status.code().is_some());
    // Shards of two scenarios: refused, and the --out it made is gone again.
    let m = run(&dir, &s(&["merge", "a", "b", "--out", "merged"]));
    assert_eq!(m.status.code(), Some(2), "{}", text(&m));
    assert!(!dir.join("merged").exists(), "a refused merge left its folder");
    // A folder that was there is left.
    std::fs::create_dir_all(dir.join("there")).expect("folder");
    run(&dir, &s(&["merge", "a", "b", "--out", "there"]));
    assert!(dir.join("there").is_dir());
    // A sweep of one cell after one of three: only its own cell is left.
    let sweep = |values: &str| {
        run(&dir, &s(&["sweep", "--set", values, "--set", "duration_s=1", "--runs", "1", "-q", "--out", "sw"]))
    };
    sweep("controller.lambda=0.3,0.5,0.7");
    assert!(dir.join("sw/cell-003/summary.json").is_file());
    std::fs::write(dir.join("sw/cell-003/notes.txt"), "mine").expect("written");
    let refused = sweep("controller.lambda=0.3");
    assert_eq!(refused.status.code(), Some(2), "{}", text(&refused));
    assert!(text(&refused).contains("cell-003 is left from an earlier sweep"), "{}", text(&refused));
    assert!(dir.join("sw/cell-002").is_dir(), "nothing removed before the refusal");
    std::fs::remove_file(dir.join("sw/cell-003/notes.txt")).expect("removed");
    let o = sweep("controller.lambda=0.3");
    assert!(o.status.code().is_some_and(|c| c < 2), "{}", text(&o));
    let mut left: Vec<String> = std::fs::read_dir(dir.join("sw"))
        .expect("sw")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().to_string())
        .collect();
    left.sort();
    assert_eq!(left, ["cell-001", "sweep.csv"]);
}
