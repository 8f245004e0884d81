//! The `proxform` binary as a user runs it.

use std::path::{Path, PathBuf};
use std::process::Command;

fn proxform() -> Command {
    Command::new(env!("CARGO_BIN_EXE_proxform"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn run_writes_the_table_the_summary_and_the_figures() {
    let out = scratch("cli-run");
    let o = proxform().args(["run", "--runs", "4", "--seed", "3", "-q", "--out"]).arg(&out).output().expect("runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    for uav in ["UAV2", "UAV3", "UAV4", "UAV5", "UAV6"] {
        assert!(stdout.contains(uav), "{stdout}");
    }
    assert!(stdout.contains("PASS") && stdout.contains("eq.17"), "{stdout}");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).expect("summary.json")).expect("JSON");
    assert_eq!(summary["runs"], 4);
    assert_eq!(summary["seed"], 3);
    for key in ["pass_fraction", "min_separation_m", "adjustments_per_uav_minute"] {
        assert!(summary[key].is_number(), "{key} missing");
    }
    for key in ["x_m", "y_m", "z_m", "alpha_deg", "beta_deg", "gamma_deg"] {
        assert!(summary["worst_abs_error"][key].is_number(), "worst {key}");
        assert!(summary["p99_abs_error"][key].is_number(), "p99 {key}");
    }
    // One row per run; the worst of the runs is the summary's worst.
    let runs = std::fs::read_to_string(out.join("runs.csv")).expect("runs.csv");
    let mut lines = runs.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4);
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    assert!(rows.iter().enumerate().all(|(r, row)| row[col("seed")] == "3" && row[col("run")] == r.to_string()));
    for key in ["x_m", "gamma_deg"] {
        let worst = rows
            .iter()
            .map(|row| row[col(&format!("max_err_{key}"))].parse::<f64>().expect("number"))
            .fold(0.0, f64::max);
        let want = summary["worst_abs_error"][key].as_f64().expect("number");
        assert!((worst - want).abs() < 1e-5, "{key}: runs.csv {worst}, summary {want}");
    }
    for fig in [
        "fig4_x",
        "fig5_y",
        "fig6_z",
        "fig7_alpha",
        "fig8_beta",
        "fig9_gamma",
        "fig10a_tracks",
        "fig10b_attitude",
        "fig10c_plan",
    ] {
        for ext in ["png", "svg"] {
            let p = out.join(format!("{fig}.{ext}"));
            assert!(std::fs::metadata(&p).map(|m| m.len() > 1000).unwrap_or(false), "{}", p.display());
        }
    }
    // The figures draw data, not only axes: coloured curve pixels in the plot area (the
    // middle of the picture), for the curves of the UAVs and of their errors.
    for fig in ["fig5_y", "fig10c_plan"] {
        let (coloured, total) = coloured_pixels(&out.join(format!("{fig}.png")));
        assert!(coloured > total / 200, "{fig}: only {coloured} of {total} pixels in the plot area are coloured");
    }
    let csv = std::fs::read_to_string(out.join("trajectories.csv")).expect("trajectories.csv");
    let mut lines = csv.lines();
    assert!(lines.next().is_some_and(|h| h.starts_with("t_s,uav,x_m")));
    assert_eq!(lines.count(), 6 * 1001);
}

/// Pixels of saturated colour (curves; axes, grid and text are grey) in the middle 80 % of a
/// PNG, and the number of pixels there.
fn coloured_pixels(path: &Path) -> (usize, usize) {
    let decoder = png::Decoder::new(std::fs::File::open(path).expect("png"));
    let mut reader = decoder.read_info().expect("png header");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("png data");
    let channels = info.color_type.samples();
    assert!(channels >= 3, "{}: not an RGB image", path.display());
    let (w, h) = (info.width as usize, info.height as usize);
    let (mut coloured, mut total) = (0, 0);
    for y in h / 10..h * 9 / 10 {
        for x in w / 10..w * 9 / 10 {
            let p = &buf[(y * w + x) * channels..][..3];
            let (max, min) = (p.iter().max().copied().unwrap_or(0), p.iter().min().copied().unwrap_or(0));
            coloured += usize::from(max - min > 60);
            total += 1;
        }
    }
    (coloured, total)
}

#[test]
fn a_fixed_seed_gives_byte_identical_trajectories() {
    let a = scratch("cli-seed-a");
    let b = scratch("cli-seed-b");
    for dir in [&a, &b] {
        let o =
            proxform().args(["run", "--seed", "11", "--no-figures", "-q", "--out"]).arg(dir).output().expect("runs");
        assert!(o.status.success());
    }
    let ta = std::fs::read(a.join("trajectories.csv")).expect("a");
    let tb = std::fs::read(b.join("trajectories.csv")).expect("b");
    assert!(ta == tb, "trajectories differ");
}

#[test]
fn switching_adjustment_off_fails_with_exit_code_1() {
    let out = scratch("cli-noadjust");
    let o = proxform()
        .args(["run", "--no-adjust", "--no-figures", "--no-trajectories", "-q", "--out"])
        .arg(&out)
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stdout).contains("FAIL"));
}

#[test]
fn invalid_arguments_are_refused_with_a_message() {
    for args in [
        vec!["run", "--runs", "0"],
        vec!["run", "--seed", "-4"],
        vec!["run", "--scenario", "nope"],
        vec!["run", "--threads", "many"],
        vec!["fly"],
    ] {
        let o = proxform().args(&args).output().expect("runs");
        assert!(!o.status.success(), "{args:?} accepted");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("error"), "{args:?}: {err}");
    }
}

#[test]
fn swarm_runs_at_any_size_and_keeps_files_small() {
    let out = scratch("cli-swarm");
    let o = proxform()
        .args(["run", "--scenario", "swarm", "--uavs", "3000", "--duration-s", "2", "--no-figures", "-q", "--out"])
        .arg(&out)
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("3000 UAVs") && stdout.contains("more followers") && stdout.contains("agent-updates"));
    // Trajectories are kept for a sample of UAVs only.
    let csv = std::fs::read_to_string(out.join("trajectories.csv")).expect("csv");
    assert_eq!(csv.lines().count() - 1, 64 * 21);
    let o = proxform().args(["run", "--uavs", "10"]).output().expect("runs");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--uavs applies to --scenario swarm"));
}

/// Figures are drawn from whatever the trajectory holds: a swarm's sample of UAVs, and UAVs
/// that stop flying part-way (a removal).
#[test]
fn figures_show_a_sampled_swarm_and_a_removed_uav() {
    let removal = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper-remove-uav2.toml");
    let removal = removal.to_string_lossy();
    let cases: [(&str, &[&str]); 2] = [
        ("cli-fig-swarm", &["run", "--scenario", "swarm", "--uavs", "200", "--duration-s", "3"]),
        ("cli-fig-removal", &["run", &removal, "--runs", "1", "--duration-s", "45"]),
    ];
    for (name, args) in cases {
        let out = scratch(name);
        let o = proxform().args(args).args(["-q", "--out"]).arg(&out).output().expect("runs");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
        assert!(matches!(o.status.code(), Some(0 | 1)), "{name}: {stderr}");
        for f in ["fig4_x.png", "fig9_gamma.svg", "fig10a_tracks.png", "fig10c_plan.svg"] {
            let len = std::fs::metadata(out.join(f)).map(|m| m.len()).unwrap_or(0);
            assert!(len > 1000, "{name}: {f} has {len} bytes");
        }
    }
}

#[test]
fn bench_measures_in_child_processes() {
    let out = scratch("cli-bench");
    let o = proxform()
        .args(["bench", "--max-uavs", "100", "--naive-max-uavs", "100", "--out"])
        .arg(&out)
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("all-pairs") && stdout.contains("MiB"), "{stdout}");
    for engine in ["fast", "reference", "minimal-law"] {
        assert!(stdout.contains(engine), "{engine}: {stdout}");
    }
    let csv = std::fs::read_to_string(out.join("bench.csv")).expect("bench.csv");
    assert!(csv.lines().count() >= 3, "{csv}");
    assert!(out.join("cost_per_update.png").exists());
}

#[test]
fn scenario_files_run_and_bad_ones_are_located() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    // The shipped paper file gives the built-in experiment's bytes.
    let (a, b) = (scratch("cli-file-a"), scratch("cli-file-b"));
    let o = proxform()
        .arg("run")
        .arg(root.join("scenarios/paper.toml"))
        .args(["--no-figures", "-q", "--out"])
        .arg(&a)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = proxform().args(["run", "--no-figures", "-q", "--out"]).arg(&b).output().expect("runs");
    assert!(o.status.success());
    let (ta, tb) =
        (std::fs::read(a.join("trajectories.csv")).expect("a"), std::fs::read(b.join("trajectories.csv")).expect("b"));
    assert!(ta == tb, "scenarios/paper.toml differs from the built-in experiment");
    // A bad file: exit code 2, file:line: key: message on stderr.
    let bad = root.join("crates/proxform-scenario/tests/bad/lambda_range.toml");
    let o = proxform().arg("run").arg(&bad).output().expect("runs");
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("lambda_range.toml:3: controller.lambda: λ must be in [0, 1], found 1.2"), "{err}");
    let o = proxform().args(["run", "/nonexistent/x.toml"]).output().expect("runs");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("cannot read scenario file /nonexistent/x.toml"));
}

#[test]
fn init_writes_an_example_that_runs_and_scenarios_lists_the_built_ins() {
    let dir = scratch("cli-init");
    std::fs::create_dir_all(&dir).expect("dir");
    let file = dir.join("mine.toml");
    let o = proxform().arg("init").arg(&file).output().expect("runs");
    assert!(o.status.success());
    let o = proxform().arg("init").arg(&file).output().expect("runs");
    assert_eq!(o.status.code(), Some(2), "refuses to overwrite");
    let o = proxform()
        .arg("run")
        .arg(&file)
        .args(["--runs", "2", "--no-figures", "-q", "--out"])
        .arg(dir.join("out"))
        .output()
        .expect("runs");
    assert!(o.status.code().is_some_and(|c| c <= 1), "{}", String::from_utf8_lossy(&o.stderr));
    let o = proxform().arg("scenarios").output().expect("runs");
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("paper") && out.contains("swarm"));
}

#[test]
fn compare_writes_rows_cells_and_plots_and_refuses_bad_files() {
    let dir = scratch("cli-compare");
    std::fs::create_dir_all(&dir).expect("dir");
    let file = dir.join("small.toml");
    std::fs::write(
        &file,
        "name = 'small'\nscenario = 'paper'\nseeds = 2\nmethods = ['proximity', 'leader_follower']\n\
         [[condition]]\nname = 'ideal'\n[[condition]]\nname = 'loss 50%'\nradio_loss = 0.5\n\
         [[condition]]\nname = 'delay 0.3 s'\nradio_delay_s = 0.3\n[[condition]]\nname = 'dark'\nblackout = true\n",
    )
    .expect("write");
    let out = dir.join("out");
    let o = proxform()
        .args(["compare", "-q", "--duration-s", "20"])
        .arg(&file)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("leader_follower") && stdout.contains("dark"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("compare.csv")).expect("compare.csv");
    // Header + 2 methods × 4 conditions × 2 seeds.
    assert_eq!(csv.lines().count(), 1 + 16, "{csv}");
    assert!(csv.lines().next().is_some_and(|h| h.contains("max_error_m") && h.contains("messages_per_uav_min")));
    let cells = std::fs::read_to_string(out.join("compare_summary.csv")).expect("compare_summary.csv");
    assert_eq!(cells.lines().count(), 1 + 8);
    // Under the blackout the leader-follower cell fails and the proximity cell passes.
    let dark: Vec<&str> = cells.lines().filter(|l| l.contains(",dark,")).collect();
    assert!(dark.iter().any(|l| l.starts_with("proximity,dark,2,1")), "{dark:?}");
    assert!(dark.iter().any(|l| l.starts_with("leader_follower,dark,2,0")), "{dark:?}");
    // The pass fractions with their 95 % Wilson intervals (2 of 2: 0.342 to 1; 0 of 2: 0 to
    // 0.658), and the attitude errors beside the position's.
    assert!(dark.iter().any(|l| l.starts_with("proximity,dark,2,1.0,0.342")), "{dark:?}");
    assert!(dark.iter().any(|l| l.starts_with("leader_follower,dark,2,0.0,0.0,0.657")), "{dark:?}");
    assert!(csv.lines().next().is_some_and(|h| h.contains("max_alpha_deg") && h.contains("max_gamma_deg")));
    for plot in ["error_vs_loss.png", "error_vs_delay.svg", "pass_by_condition.png"] {
        assert!(out.join(plot).exists(), "{plot}");
    }

    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "name = 'b'\nscenario = 'paper'\nseeds = 2\nmethods = ['proximity']\n[[condition]]\nname = 'x'\nradio_loss = 2.0\n")
        .expect("write");
    let o = proxform().args(["compare", "-q"]).arg(&bad).output().expect("runs");
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("bad.toml:7: condition[1].radio_loss"), "{stderr}");
}

/// A large formation's rear ranks show: every follower has its per-UAV row in summary.json,
/// the console shows those farthest out, and `--trajectory-uavs` records the chosen UAVs
/// (and the navigator) only; a bad list is refused naming the flag.
#[test]
fn every_follower_has_its_detail_and_chosen_uavs_their_trajectories() {
    let out = scratch("cli-rear-ranks");
    let o = proxform()
        .args(["run", "--scenario", "swarm", "--uavs", "300", "--duration-s", "5", "--runs", "2"])
        .args(["--no-figures", "--trajectory-uavs", "290-300,150", "-q", "--out"])
        .arg(&out)
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{stdout}{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains(
            "… 289 more followers (shown: the 10 farthest out of their allowable errors, on their worst axis)"
        ),
        "{stdout}"
    );
    let summary = std::fs::read_to_string(out.join("summary.json")).expect("summary");
    let v: serde_json::Value = serde_json::from_str(&summary).expect("json");
    // The rows shown are the ten whose worst error over its allowable one is largest.
    let allow = &v["allowable_error"];
    let ratio = |w: &serde_json::Value| {
        ["x_m", "y_m", "z_m", "alpha_deg", "beta_deg", "gamma_deg"]
            .iter()
            .map(|k| w[k].as_f64().unwrap_or(0.0) / allow[k].as_f64().unwrap_or(1.0))
            .fold(0.0, f64::max)
    };
    let worst = v["per_uav_worst"].as_array().expect("list");
    let mut ranked: Vec<(f64, u64)> = worst
        .iter()
        .zip(v["per_uav"].as_array().expect("list"))
        .map(|(w, u)| (ratio(w), u.as_u64().unwrap_or(0)))
        .collect();
    ranked.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut top: Vec<u64> = ranked[..10].iter().map(|r| r.1).collect();
    top.sort_unstable();
    let shown: Vec<u64> =
        stdout.lines().filter_map(|l| l.strip_prefix("UAV")?.split_whitespace().next()?.parse().ok()).collect();
    assert_eq!(shown, top, "{stdout}");
    let per_uav: Vec<u64> = v["per_uav"].as_array().expect("list").iter().filter_map(|u| u.as_u64()).collect();
    assert_eq!(per_uav, (2..=300).collect::<Vec<u64>>());
    assert_eq!(v["per_uav_runs_flown"].as_array().map(Vec::len), Some(299));
    let csv = std::fs::read_to_string(out.join("trajectories.csv")).expect("trajectories");
    let mut uavs: Vec<u32> = csv.lines().skip(1).filter_map(|l| l.split(',').nth(1)?.parse().ok()).collect();
    uavs.sort_unstable();
    uavs.dedup();
    let mut want = vec![1, 150];
    want.extend(290..=300);
    assert_eq!(uavs, want);
    for (list, says) in
        [("0", "UAV 0 is not in the formation"), ("5-3", "runs backwards"), ("x", "\"x\" is not a UAV number")]
    {
        let o = proxform()
            .args(["run", "--runs", "1", "--trajectory-uavs", list, "--out"])
            .arg(&out)
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            o.status.code() == Some(2) && stderr.contains("--trajectory-uavs") && stderr.contains(says),
            "{list}: {stderr}"
        );
    }
}

/// The command `scenario.toml`'s header gives for flying its runs again, as arguments, with the
/// file's path in place of its name.
fn again_from(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("scenario.toml")).expect("scenario.toml");
    let line = text.lines().find_map(|l| l.strip_prefix("#   proxform ")).expect("the command again");
    line.split_whitespace()
        .map(|a| if a == "scenario.toml" { dir.join(a).display().to_string() } else { a.to_string() })
        .collect()
}

#[test]
fn an_output_folders_scenario_file_flies_the_same_runs_again() {
    let scenarios = concat!(env!("CARGO_MANIFEST_DIR"), "/../proxform-scenario/scenarios/");
    let fault = format!("{scenarios}fault-triangle10.toml");
    let change = format!("{scenarios}change-v-column.toml");
    let cases: [(&str, Vec<&str>); 4] = [
        ("paper", vec!["--seed", "4", "--runs", "3", "--first-run", "2", "--no-adjust", "--set", "noise.scale=1.5"]),
        ("fault", vec![fault.as_str(), "--seed", "9", "--runs", "2", "--set", "wind.steady_kmh=[0,15,0]"]),
        ("change", vec![change.as_str(), "--seed", "1", "--runs", "2"]),
        ("swarm", vec!["--scenario", "swarm", "--uavs", "30", "--seed", "2", "--runs", "2"]),
    ];
    for (tag, args) in cases {
        let (first, again) = (scratch(&format!("cli-again-{tag}-1")), scratch(&format!("cli-again-{tag}-2")));
        let o = proxform()
            .arg("run")
            .args(&args)
            .args(["--duration-s", "8", "--no-figures", "--no-trajectories", "-q", "--out"])
            .arg(&first)
            .output()
            .expect("runs");
        assert!(o.status.code().is_some_and(|c| c <= 1), "{tag}: {}", String::from_utf8_lossy(&o.stderr));
        let o = proxform()
            .args(again_from(&first))
            .args(["--no-figures", "--no-trajectories", "-q", "--out"])
            .arg(&again)
            .output()
            .expect("runs");
        assert!(o.status.code().is_some_and(|c| c <= 1), "{tag}: {}", String::from_utf8_lossy(&o.stderr));
        let runs = |d: &Path| std::fs::read(d.join("runs.csv")).expect("runs.csv");
        assert!(runs(&first) == runs(&again), "{tag}: runs.csv differs when flown again from scenario.toml");
    }
    // A sweep's cells each say what they flew.
    let sweep = scratch("cli-again-sweep");
    let o = proxform()
        .args(["sweep", "--scenario", "paper", "--set", "noise.scale=0.5,2", "--runs", "2", "--seed", "3"])
        .args(["--set", "duration_s=6", "-q", "--out"])
        .arg(&sweep)
        .output()
        .expect("sweeps");
    assert!(o.status.code().is_some_and(|c| c <= 1), "{}", String::from_utf8_lossy(&o.stderr));
    let cell = sweep.join("cell-002");
    let again = scratch("cli-again-sweep-cell");
    let o =
        proxform().args(again_from(&cell)).args(["--no-figures", "-q", "--out"]).arg(&again).output().expect("runs");
    assert!(o.status.code().is_some_and(|c| c <= 1), "{}", String::from_utf8_lossy(&o.stderr));
    let runs = |d: &Path| std::fs::read(d.join("runs.csv")).expect("runs.csv");
    assert!(runs(&cell) == runs(&again), "the sweep's cell 2 differs when flown again");
}

#[test]
fn a_run_writes_a_report_page_that_fetches_nothing_and_report_remakes_it() {
    let dir = scratch("cli-report");
    let o = proxform()
        .args(["run", "--scenario", "paper", "--runs", "3", "--duration-s", "10", "--no-figures", "-q", "--out"])
        .arg(&dir)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let page = std::fs::read_to_string(dir.join("report.html")).expect("report.html");
    // One file: no address to fetch, every script and style inline.
    for fetch in ["http:", "https:", "src=", "href=", "@import", "fetch("] {
        assert!(!page.contains(fetch), "report.html holds {fetch}");
    }
    // Its data: the summary, the replay's frames from trajectories.csv, the scenario's links.
    let data = page.split("<script type=\"application/json\" id=\"data\">").nth(1).expect("data");
    let data: serde_json::Value = serde_json::from_str(data.split("</script>").next().expect("end")).expect("json");
    assert_eq!(data["summary"]["runs"], 3);
    assert_eq!(data["replay"]["uavs"].as_array().map(Vec::len), Some(6));
    let frames = data["replay"]["times"].as_array().map_or(0, Vec::len);
    assert_eq!(frames, 101, "every step of a 10 s flight");
    assert_eq!(data["replay"]["pos"].as_array().map(Vec::len), Some(frames * 6 * 3));
    assert!(data["scenario"]["links"].as_array().is_some_and(|l| !l.is_empty()));
    assert_eq!(data["hist"]["runs"], 3);
    // `proxform report` makes it again from the folder alone, the same page.
    std::fs::remove_file(dir.join("report.html")).expect("removed");
    let o = proxform().arg("report").arg(&dir).output().expect("reports");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let again = std::fs::read_to_string(dir.join("report.html")).expect("report.html again");
    assert_eq!(again, page, "the page from the folder is the page the run wrote");
    // A summary without what the page reads is refused, naming the key (the page stopped half
    // drawn, exit 0).
    let mut partial: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).expect("summary")).expect("json");
    partial.as_object_mut().expect("object").remove("p99_abs_error");
    std::fs::write(dir.join("summary.json"), partial.to_string()).expect("written");
    let o = proxform().arg("report").arg(&dir).output().expect("reports");
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("p99_abs_error: missing"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // A folder that is not a run's says so.
    let empty = scratch("cli-report-empty");
    std::fs::create_dir_all(&empty).expect("made");
    let o = proxform().arg("report").arg(&empty).output().expect("reports");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("summary.json"), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn a_reader_that_stops_early_ends_the_output_without_a_panic() {
    use std::io::Read;
    // Megabytes of text (a 20 000-UAV scenario printed), of which the reader takes 100 bytes.
    let mut child = proxform()
        .args(["run", "--scenario", "swarm", "--uavs", "20000", "--print-scenario"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("starts");
    let mut head = [0u8; 100];
    child.stdout.take().expect("stdout").read_exact(&mut head).expect("reads");
    let o = child.wait_with_output().expect("ends");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(o.status.code(), Some(0), "{stderr}");
}
