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
    /// Swarm size of the instruction counts (callgrind; 0: none; at most --max-uavs).
    #[arg(long, default_value_t = 10_000, value_parser = clap::value_parser!(u64).range(0..=1_000_000))]
    instructions_uavs: u64,
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
    if args.instructions_uavs > 0 {
        let n = args.instructions_uavs.min(args.max_uavs);
        for engine in ["fast", "reference", "minimal-law"] {
            spinner.set_message(format!("counting instructions: {n} UAVs, {engine} (callgrind)"));
            match count_instructions(&exe, n, engine) {
                Ok(Some(row)) => {
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
    println!(
        "\nwrote {}, {}",
        out.join("bench.csv").display(),
        plot.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
    );
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

/// Instructions per agent-update of `engine` at `n` UAVs (grid search, one thread), counted by
/// callgrind over the timed steps only (`proxform_sim::batch::throughput::timed_steps`); None
/// when valgrind is not installed.
fn count_instructions(exe: &std::path::Path, n: u64, engine: &str) -> Result<Option<Row>> {
    let steps = 5u64;
    let one = [n.to_string(), steps.to_string(), "1".into(), "grid".into(), engine.into()];
    let output = match Command::new("valgrind")
        .args([
            "--tool=callgrind",
            "--callgrind-out-file=/dev/null",
            "--collect-atstart=no",
            "--toggle-collect=*timed_steps*",
        ])
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
