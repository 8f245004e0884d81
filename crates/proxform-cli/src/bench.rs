//! `proxform bench`: throughput and memory of both engines on the swarm scenario, N = 10^2 …
//! 10^6 (10^7 with `--max-uavs`), on one thread and on all, plus the naive all-pairs neighbour
//! search; and, where callgrind is installed (this machine's hardware counters are not
//! readable), instructions per agent-update of each.
//!
//! Every measurement runs in a child process so that its peak memory is its own.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::{Command, ExitCode};

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use proxform_scenario::{builtin, Scenario};
use proxform_sim::batch::throughput::{measure, measure_minimal, Throughput};
use proxform_sim::world::options::NeighbourSearch;
use proxform_sim::EngineKind;

use crate::memory::{mib, peak_rss_bytes};

/// Arguments of `proxform bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Largest swarm measured (powers of ten from 100 up to it).
    #[arg(long, default_value_t = 1_000_000, value_parser = clap::value_parser!(u64).range(100..=10_000_000))]
    max_uavs: u64,
    /// Largest swarm measured with the naive all-pairs search.
    #[arg(long, default_value_t = 10_000, value_parser = clap::value_parser!(u64).range(0..=1_000_000))]
    naive_max_uavs: u64,
    /// Largest swarm measured on the reference engine (10^6 UAVs take it about 1.8 GiB).
    #[arg(long, default_value_t = 1_000_000, value_parser = clap::value_parser!(u64).range(0..=10_000_000))]
    reference_max_uavs: u64,
    /// Steps per measurement [default: about three million updates, 5 to 200 steps].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=100_000))]
    steps: Option<u64>,
    /// Swarm size of the instruction counts (callgrind; 0: none; else 2 to --max-uavs), over
    /// --steps steps (5 unless given) [default: 10 000, or --max-uavs when smaller].
    #[arg(long, value_parser = clap::value_parser!(u64).range(0..=1_000_000))]
    instructions_uavs: Option<u64>,
    /// Output directory [default: out/bench].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Internal: measure one configuration and print it as JSON.
    #[arg(long, hide = true, num_args = 5, value_names = ["UAVS", "STEPS", "THREADS", "SEARCH", "ENGINE"])]
    one: Option<Vec<String>>,
}

/// One row of the report.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Row {
    uavs: u64,
    engine: String,
    search: String,
    threads: usize,
    steps: u64,
    updates_per_s: f64,
    ns_per_update: f64,
    setup_s: f64,
    peak_rss_bytes: Option<u64>,
    /// Instructions per agent-update (callgrind), on the rows counted.
    #[serde(default)]
    instructions_per_update: Option<f64>,
}

fn search_name(s: NeighbourSearch) -> &'static str {
    match s {
        NeighbourSearch::Grid => "grid",
        NeighbourSearch::AllPairs => "all-pairs",
    }
}

/// Runs the command.
pub fn run(args: &BenchArgs) -> Result<ExitCode> {
    if let Some(one) = &args.one {
        return measure_one(one);
    }
    let instructions_uavs = match args.instructions_uavs {
        Some(n) if n == 1 || n > args.max_uavs => bail!(
            "--instructions-uavs {n} is no swarm this bench measures: give 0 (none) or 2 to --max-uavs ({})",
            args.max_uavs
        ),
        Some(n) => n,
        None => 10_000.min(args.max_uavs),
    };
    let out = args.out.clone().unwrap_or_else(|| PathBuf::from("out/bench"));
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    let mut sizes = Vec::new();
    let mut n = 100u64;
    while n <= args.max_uavs {
        sizes.push(n);
        n *= 10;
    }
    let mut plan: Vec<(u64, usize, NeighbourSearch, &str)> = Vec::new();
    for &n in &sizes {
        for threads in [1, cores] {
            plan.push((n, threads, NeighbourSearch::Grid, "fast"));
            if n <= args.reference_max_uavs {
                plan.push((n, threads, NeighbourSearch::Grid, "reference"));
            }
        }
        if n <= args.naive_max_uavs {
            plan.push((n, cores, NeighbourSearch::AllPairs, "reference"));
        }
        // The floor: the minimal law over the same slots (not the method).
        plan.push((n, cores, NeighbourSearch::Grid, "minimal-law"));
    }
    plan.dedup();
    println!("proxform bench: swarm scenario, {} core(s); each line is one child process\n", cores);
    println!(
        "{:>9} {:>11} {:>10} {:>8} {:>6} {:>16} {:>12} {:>10}",
        "UAVs", "engine", "search", "threads", "steps", "updates/s", "ns/update", "peak mem"
    );
    let exe = std::env::current_exe().context("cannot find the proxform executable")?;
    let mut rows = Vec::new();
    // A spinner on stderr while a child measures (a 10^6-UAV row takes a minute or two).
    let spinner = if std::io::stderr().is_terminal() { ProgressBar::new_spinner() } else { ProgressBar::hidden() };
    spinner.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    spinner.enable_steady_tick(std::time::Duration::from_millis(200));
    for (n, threads, search, engine) in plan {
        // Enough steps for about three million updates (all-pairs: N² work), at least 5.
        let work = if search == NeighbourSearch::AllPairs { (n * n / 200).max(n) } else { n };
        let steps = args.steps.unwrap_or((3_000_000 / work).clamp(5, 200));
        spinner.set_message(format!(
            "measuring {n} UAVs, {}, {}, {threads} thread(s), {steps} steps",
            engine,
            search_name(search)
        ));
        let one = [n.to_string(), steps.to_string(), threads.to_string(), search_name(search).into(), engine.into()];
        let output = Command::new(&exe)
            .arg("bench")
            .arg("--one")
            .args(&one)
            .output()
            .context("cannot start a measurement process")?;
        spinner.set_message("");
        if !output.status.success() {
            bail!("measurement of {n} UAVs failed: {}", String::from_utf8_lossy(&output.stderr));
        }
        let row: Row = serde_json::from_slice(&output.stdout).context("unreadable measurement")?;
        spinner.suspend(|| {
            println!(
                "{:>9} {:>11} {:>10} {:>8} {:>6} {:>16.3e} {:>12.0} {:>10}",
                row.uavs,
                row.engine,
                row.search,
                row.threads,
                row.steps,
                row.updates_per_s,
                row.ns_per_update,
                mib(row.peak_rss_bytes)
            )
        });
        rows.push(row);
    }
    // Instructions per update, counted by callgrind where it is installed.
    let mut by_phase: Vec<(String, Vec<(&'static str, f64)>)> = Vec::new();
    let mut wrote = vec![out.join("bench.csv")];
    if instructions_uavs > 0 {
        let n = instructions_uavs;
        for engine in ["fast", "reference", "minimal-law"] {
            spinner.set_message(format!("counting instructions: {n} UAVs, {engine} (callgrind)"));
            let profile = out.join(format!("callgrind.{engine}.out"));
            match count_instructions(&exe, (n, args.steps.unwrap_or(5)), engine, &profile) {
                Ok(Some(row)) => {
                    wrote.push(profile.clone());
                    let updates = ((n - 1) * row.steps) as f64;
                    if engine != "minimal-law" {
                        match phases(&profile, updates) {
                            Ok(p) => by_phase.push((engine.to_string(), p)),
                            Err(e) => spinner.suspend(|| println!("(no instructions by phase: {e:#})")),
                        }
                    }
                    let per = row.instructions_per_update.unwrap_or(f64::NAN);
                    spinner.suspend(|| {
                        println!(
                            "{:>9} {:>11} {:>10} {:>8} {:>6} {:>16.0} instructions/update (callgrind)",
                            row.uavs, row.engine, row.search, row.threads, row.steps, per
                        )
                    });
                    rows.push(row);
                }
                Ok(None) => {
                    spinner.suspend(|| println!("(no instruction counts: valgrind is not installed)"));
                    break;
                }
                Err(e) => bail!("counting instructions failed: {e:#}"),
            }
        }
    }
    spinner.finish_and_clear();
    if let Some((_, first)) = by_phase.first() {
        println!("\ninstructions per agent-update by phase (callgrind, the steps only; {}):", out.display());
        print!("{:<12}", "phase");
        for (engine, _) in &by_phase {
            print!(" {engine:>10}");
        }
        println!();
        let mut w =
            csv::Writer::from_writer(std::io::BufWriter::new(crate::files::create_output(&out.join("phases.csv"))?));
        w.write_record(["engine", "phase", "instructions_per_update"])?;
        for (k, (phase, _)) in first.iter().enumerate() {
            print!("{phase:<12}");
            for (engine, p) in &by_phase {
                print!(" {:>10.0}", p[k].1);
                w.write_record([engine.as_str(), phase, &format!("{:.1}", p[k].1)])?;
            }
            println!();
        }
        w.flush()?;
        wrote.push(out.join("phases.csv"));
    }
    let mut w = csv::Writer::from_writer(std::io::BufWriter::new(crate::files::create_output(&out.join("bench.csv"))?));
    for r in &rows {
        w.serialize(r)?;
    }
    w.flush()?;
    let timed = rows.iter().filter(|r| r.instructions_per_update.is_none());
    let plot = crate::figures::bench_plot(
        &out,
        &timed.map(|r| (r.uavs, format!("{}, {}", r.engine, r.search), r.threads, r.ns_per_update)).collect::<Vec<_>>(),
    )?;
    wrote.extend(plot);
    println!("\nwrote {}", wrote.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "));
    Ok(ExitCode::SUCCESS)
}

fn measure_one(one: &[String]) -> Result<ExitCode> {
    let parse = |k: usize| -> Result<u64> { one[k].parse().with_context(|| format!("bad --one argument {}", one[k])) };
    let (n, steps, threads) = (parse(0)?, parse(1)?, parse(2)? as usize);
    let search = match one[3].as_str() {
        "grid" => NeighbourSearch::Grid,
        "all-pairs" => NeighbourSearch::AllPairs,
        other => bail!("unknown search '{other}'"),
    };
    let engine = match one[4].as_str() {
        "fast" => Some(EngineKind::Fast),
        "reference" => Some(EngineKind::Reference),
        "minimal-law" => None,
        other => bail!("unknown engine '{other}'"),
    };
    // A flight long enough for the steps measured.
    let mut spec = builtin::swarm_spec(n as usize);
    let dt = spec.dt_s.unwrap_or(proxform_scenario::defaults::DT_S);
    spec.duration_s = Some(proxform_scenario::defaults::DURATION_S.max((steps as f64 + 1.0) * dt));
    let scenario = Scenario::try_from(spec)?;
    if let Some(engine) = engine {
        crate::memory::check_flights(&scenario, engine, 1, crate::memory::available_bytes())?;
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let t: Throughput = pool.install(|| match engine {
        Some(engine) => measure(&scenario, engine, steps, search, threads > 1),
        None => measure_minimal(&scenario, steps, threads > 1),
    });
    let row = Row {
        uavs: t.uavs,
        engine: t.engine.into(),
        search: search_name(search).into(),
        threads: t.threads,
        steps: t.steps,
        updates_per_s: t.updates_per_s,
        ns_per_update: t.ns_per_update,
        setup_s: t.setup_s,
        peak_rss_bytes: peak_rss_bytes(),
        instructions_per_update: None,
    };
    println!("{}", serde_json::to_string(&row)?);
    Ok(ExitCode::SUCCESS)
}

/// Instructions per agent-update of `engine` at `n` UAVs over `steps` steps (grid search, one thread), counted by
/// callgrind over the timed steps only (`proxform_sim::batch::throughput::timed_steps`), its
/// profile written to `profile` (for `callgrind_annotate`); None when valgrind is not
/// installed.
fn count_instructions(
    exe: &std::path::Path,
    (n, steps): (u64, u64),
    engine: &str,
    profile: &std::path::Path,
) -> Result<Option<Row>> {
    let one = [n.to_string(), steps.to_string(), "1".into(), "grid".into(), engine.into()];
    let output = match Command::new("valgrind")
        .args(["--tool=callgrind", "--collect-atstart=no", "--toggle-collect=*timed_steps*"])
        .arg(format!("--callgrind-out-file={}", profile.display()))
        .arg(exe)
        .arg("bench")
        .arg("--one")
        .args(&one)
        .output()
    {
        Ok(o) => o,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e).context("cannot start valgrind"),
    };
    let stderr = String::from_utf8_lossy(&output.stderr);
    if !output.status.success() {
        bail!("valgrind failed: {stderr}");
    }
    let collected = stderr
        .lines()
        .find_map(|l| l.split("Collected :").nth(1))
        .and_then(|v| v.trim().parse::<f64>().ok())
        .context("callgrind reported no instruction count")?;
    let mut row: Row = serde_json::from_slice(&output.stdout).context("unreadable measurement")?;
    row.instructions_per_update = Some(collected / ((n - 1) * row.steps) as f64);
    Ok(Some(row))
}

/// The phases of an agent-update and the functions whose instructions (with all they call)
/// each counts, in either engine: the functions are kept apart from their callers
/// (`#[inline(never)]`) so that a profile names them. The functions in `less` are called only
/// inside this phase's and counted in another phase: they are taken out of this one.
struct Phase {
    name: &'static str,
    functions: &'static [&'static str],
    less: &'static [&'static str],
}

const TRACKS: [&str; 4] = [
    "proxform_core::predictor::NeighbourTracks::predict",
    "proxform_core::predictor::NeighbourTracks::state_at",
    "<proxform_sim::fast::tracks::StepTracks<S> as proxform_core::controller::tracks::Tracks>::predict",
    "<proxform_sim::fast::tracks::StepTracks<S> as proxform_core::controller::tracks::Tracks>::state_at",
];
const AVOIDANCE: [&str; 3] = [
    "proxform_core::controller::avoid::Avoidance::may_bind",
    "proxform_core::controller::avoid::Avoidance::perceive",
    "proxform_core::controller::avoid::Avoidance::limit",
];
const TRACKS_AND_AVOIDANCE: [&str; 7] =
    [TRACKS[0], TRACKS[1], TRACKS[2], TRACKS[3], AVOIDANCE[0], AVOIDANCE[1], AVOIDANCE[2]];

const PHASES: [Phase; 8] = [
    Phase {
        name: "perception",
        functions: &["proxform_sim::fast::update::perceive", "proxform_sim::world::sensing::ProximitySensor::perceive"],
        less: &["proxform_sim::world::sensing::ProximitySensor::observe"],
    },
    Phase {
        name: "noise",
        functions: &[
            "proxform_sim::fast::update::build_observations",
            "proxform_sim::fast::update::own_measurement",
            "proxform_sim::world::sensing::noisy",
        ],
        less: &[],
    },
    Phase { name: "tracks", functions: &TRACKS, less: &[] },
    Phase { name: "avoidance", functions: &AVOIDANCE, less: &[] },
    Phase {
        name: "controller",
        functions: &["proxform_core::controller::UavView<T>::step"],
        less: &TRACKS_AND_AVOIDANCE,
    },
    Phase {
        name: "index",
        // (The engines' own: the grid's functions serve the metrics too.)
        functions: &[
            "proxform_sim::fast::FastSimulation::index_positions",
            "proxform_sim::world::engine::World::index_positions",
        ],
        less: &[],
    },
    Phase {
        name: "propagate",
        functions: &[
            "proxform_sim::fast::FastSimulation::propagate",
            "proxform_sim::world::phases::StepContext::propagate",
        ],
        less: &[],
    },
    Phase {
        name: "metrics",
        functions: &[
            "<proxform_sim::measure::metrics::RunMetrics as proxform_sim::measure::observer::Observer>::on_step",
        ],
        less: &[],
    },
];

/// Instructions per update by phase from callgrind `profile` over `updates` agent-updates
/// (read with `callgrind_annotate`): each phase of [`PHASES`], then the rest of the step as
/// "other" and the whole as "total".
fn phases(profile: &std::path::Path, updates: f64) -> Result<Vec<(&'static str, f64)>> {
    let output = Command::new("callgrind_annotate")
        .args(["--inclusive=yes", "--threshold=100"])
        .arg(profile)
        .output()
        .context("cannot start callgrind_annotate")?;
    if !output.status.success() {
        bail!("callgrind_annotate failed: {}", String::from_utf8_lossy(&output.stderr));
    }
    let (total, inclusive) = inclusive_costs(&String::from_utf8_lossy(&output.stdout))?;
    let sum = |functions: &[&str]| -> f64 { functions.iter().filter_map(|f| inclusive.get(*f)).sum() };
    let mut rows: Vec<(&'static str, f64)> =
        PHASES.iter().map(|p| (p.name, (sum(p.functions) - sum(p.less)).max(0.0))).collect();
    let phased: f64 = rows.iter().map(|r| r.1).sum();
    rows.push(("other", (total - phased).max(0.0)));
    rows.push(("total", total));
    Ok(rows.into_iter().map(|(n, v)| (n, v / updates)).collect())
}

/// From `callgrind_annotate --inclusive=yes` output: the program's total and each function's
/// inclusive count (the lines that name a function of an object file; inlined code, listed by
/// the file it came from, is part of its caller's).
fn inclusive_costs(text: &str) -> Result<(f64, std::collections::HashMap<String, f64>)> {
    let count = |field: &str| field.replace(',', "").parse::<f64>().ok();
    let mut total = None;
    let mut functions = std::collections::HashMap::new();
    for line in text.lines() {
        let line = line.trim();
        let Some((n, rest)) = line.split_once(' ') else { continue };
        let Some(n) = count(n) else { continue };
        if rest.ends_with("PROGRAM TOTALS") {
            total = Some(n);
            continue;
        }
        // "N (p%)  file:function [object]"
        let Some(rest) = rest.split_once(")  ").map(|r| r.1) else { continue };
        let Some((site, _object)) = rest.rsplit_once(" [") else { continue };
        let Some((_file, function)) = site.split_once(':') else { continue };
        *functions.entry(function.to_string()).or_insert(0.0) += n;
    }
    Ok((total.context("callgrind_annotate printed no total")?, functions))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instructions_are_read_by_function_and_phase() {
        let text = "\
--------------------------------------------------------------------------------
1,000 (100.0%)  PROGRAM TOTALS
--------------------------------------------------------------------------------
  900 (90.00%)  /w/crates/proxform-core/src/controller/mod.rs:proxform_core::controller::UavView<T>::step [/bin/proxform]
  300 (30.00%)  /w/crates/proxform-core/src/predictor.rs:proxform_core::predictor::NeighbourTracks::predict [/bin/proxform]
  200 (20.00%)  /w/crates/proxform-core/src/azimuth.rs:proxform_core::controller::UavView<T>::step
   50 ( 5.00%)  /w/crates/proxform-core/src/controller/avoid.rs:proxform_core::controller::avoid::Avoidance::may_bind [/bin/proxform]
";
        let (total, f) = inclusive_costs(text).expect("read");
        assert_eq!(total, 1000.0);
        assert_eq!(
            f.get("proxform_core::controller::UavView<T>::step"),
            Some(&900.0),
            "inlined code is not a function"
        );
        assert_eq!(f.get("proxform_core::predictor::NeighbourTracks::predict"), Some(&300.0));
        assert!(inclusive_costs("nothing").is_err());
    }
}
