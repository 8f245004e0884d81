//! `proxform sweep`: a grid over scenario keys, every cell a batch checked like a file and
//! written like `proxform run` (its own folder, journal and resume), and one table of the
//! cells (`sweep.csv`).

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use proxform_scenario::Scenario;
use proxform_sim::batch::sweep;
use proxform_sim::RunOptions;

use crate::batch;

/// Most cells of a sweep.
use proxform_sim::batch::sweep::MAX_CELLS;

/// Arguments of `proxform sweep`.
#[derive(Debug, Args)]
pub struct SweepArgs {
    /// Scenario file (TOML) to sweep.
    file: Option<PathBuf>,
    /// Built-in scenario to sweep when no file is given.
    #[arg(long, default_value = "paper", value_parser = crate::scenarios::NAMES)]
    scenario: String,
    /// A key and its values: `--set controller.lambda=0.5,0.8` (repeatable: the grid is every
    /// combination, the first key varying slowest; TOML values, bare words as text).
    #[arg(long = "set", value_name = "KEY=V1,V2,...", required = true)]
    set: Vec<String>,
    /// Base seed of every cell.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Seeded runs per cell.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    runs: u64,
    /// Output directory [default: out/sweep-<scenario>].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads (0 = all cores). Results do not depend on it.
    #[arg(long, default_value_t = 0, value_parser = crate::run::threads)]
    threads: usize,
    /// Complete an interrupted sweep in the output folder.
    #[arg(long)]
    resume: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

/// Splits `KEY=VALUE` at its first `=`.
pub fn key_value(kv: &str) -> Result<(&str, &str)> {
    match kv.split_once('=') {
        Some((k, v)) if !k.trim().is_empty() && !v.trim().is_empty() => Ok((k.trim(), v.trim())),
        _ => bail!("--set {kv}: expected KEY=VALUE, e.g. controller.lambda=0.5"),
    }
}

/// Splits a list of values at the commas outside brackets and quotes.
fn values(list: &str) -> Vec<String> {
    let (mut out, mut cur, mut depth, mut quote) = (Vec::new(), String::new(), 0i32, None::<char>);
    for c in list.chars() {
        match (c, quote) {
            ('"' | '\'', None) => quote = Some(c),
            (q, Some(open)) if q == open => quote = None,
            ('[' | '{', None) => depth += 1,
            (']' | '}', None) => depth -= 1,
            (',', None) if depth == 0 => {
                out.push(std::mem::take(&mut cur).trim().to_string());
                continue;
            }
            _ => {}
        }
        cur.push(c);
    }
    out.push(cur.trim().to_string());
    out
}

/// Runs the command; the exit code is 0 when every run of every cell passed, 1 otherwise.
pub fn run(args: &SweepArgs) -> Result<ExitCode> {
    let (spec, source) = match &args.file {
        Some(path) => crate::scenarios::load_spec(path)?,
        None => (crate::scenarios::built_in_spec(&args.scenario, None)?, crate::scenarios::Source::BuiltIn),
    };
    let mut axes: Vec<(String, Vec<String>)> = Vec::new();
    for kv in &args.set {
        let (key, list) = key_value(kv)?;
        if axes.iter().any(|(k, _)| k == key) {
            bail!("--set {key}: given twice (give all its values in one --set, comma-separated)");
        }
        let vs = values(list);
        if vs.iter().any(String::is_empty) {
            bail!("--set {kv}: an empty value");
        }
        axes.push((key.to_string(), vs));
    }
    let grid = sweep::cells(&axes);
    if grid.len() > MAX_CELLS {
        bail!("{} cells, more than the {MAX_CELLS} a sweep may have", grid.len());
    }
    // Every cell is checked before anything flies.
    let mut cells: Vec<(String, Scenario)> = Vec::with_capacity(grid.len());
    let mut warned = Vec::new();
    for cell in &grid {
        let label = cell.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(" ");
        let mut s = spec.clone();
        for (k, v) in cell {
            s = proxform_scenario::overrides::set(&s, k, v).map_err(|m| anyhow::anyhow!("cell {label}: {m}"))?;
        }
        let sc = match Scenario::try_from(s.clone()) {
            Ok(sc) => sc,
            Err(e) => match cell.iter().find(|(k, _)| e.key == *k) {
                Some((k, v)) => bail!("cell {label}: --set {k}={v}: {}", e.message),
                None => crate::scenarios::check(s, &source).with_context(|| format!("cell {label}"))?,
            },
        };
        crate::scenarios::engine(&sc, &source).with_context(|| format!("cell {label}"))?;
        crate::scenarios::warn_once(&sc, &source, &mut warned);
        cells.push((label, sc));
    }
    let name = cells.first().map_or("sweep", |c| c.1.name()).to_string();
    let out = args.out.clone().unwrap_or_else(|| crate::files::default_out(&format!("sweep-{name}")));
    let _folder = crate::files::OutputFolder::new(&out, "output directory")?;
    let _lock = crate::files::lock_folder(&out)?;
    let digits = cells.len().to_string().len().max(3);
    remove_stale_cells(&out, cells.len())?;
    let pool =
        rayon::ThreadPoolBuilder::new().num_threads(args.threads).build().context("cannot start worker threads")?;
    let total = args.runs.saturating_mul(cells.len() as u64);
    let bar = if args.quiet { ProgressBar::hidden() } else { ProgressBar::new(total) };
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} runs ({per_sec}, eta {eta}) {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let csv_path = out.join("sweep.csv");
    let mut table = csv::Writer::from_writer(std::io::BufWriter::new(crate::files::create_output(&csv_path)?));
    let mut all_pass = true;
    let mut stdout = std::io::stdout().lock();
    for (k, (label, sc)) in cells.iter().enumerate() {
        bar.set_message(label.clone());
        let dir = out.join(format!("cell-{:0digits$}", k + 1));
        std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
        let header = batch::header(sc, RunOptions::default(), (args.seed, 0, args.runs))?;
        let opened = batch::open(&dir, &header, args.resume)?;
        let cell_batch = crate::provenance::Batch { seed: args.seed, first_run: 0, runs: args.runs, no_adjust: false };
        crate::provenance::write_scenario(&dir, sc, cell_batch)?;
        bar.inc(opened.resumed);
        // A single run ticks per step: count it when it ends.
        let single = args.runs == 1;
        pool.install(|| {
            batch::fly_into(sc, &header, opened, None, &|| {
                if !single {
                    bar.inc(1)
                }
            })
        })?;
        if single {
            bar.inc(1);
        }
        let (_, summary) = batch::finish(&[dir.join(batch::JOURNAL)], &dir, false)?;
        let row = sweep::row(&summary);
        if k == 0 {
            let mut h = vec!["cell".to_string()];
            h.extend(axes.iter().map(|(key, _)| key.clone()));
            h.extend(row.iter().map(|(n, _)| n.to_string()));
            table.write_record(&h)?;
        }
        let mut rec = vec![(k + 1).to_string()];
        rec.extend(grid[k].iter().map(|(_, v)| v.to_string()));
        rec.extend(row.iter().map(|(_, v)| v.map_or_else(String::new, |v| v.to_string())));
        table.write_record(&rec).with_context(|| format!("cannot write {}", csv_path.display()))?;
        all_pass &= summary.pass_fraction >= 1.0;
        bar.suspend(|| {
            writeln!(
                stdout,
                "cell {:>w$}  {label:<40}  pass {:.4}  worst |y| {:.3} m  min separation {:.2} m",
                k + 1,
                summary.pass_fraction,
                summary.worst_abs_error.y_m,
                summary.min_separation_m,
                w = digits
            )
        })?;
    }
    table.flush().with_context(|| format!("cannot write {}", csv_path.display()))?;
    bar.finish_and_clear();
    writeln!(
        stdout,
        "\n{} cells × {} runs; wrote {} and a folder per cell to {}",
        cells.len(),
        args.runs,
        csv_path.display(),
        out.display()
    )?;
    Ok(if all_pass { ExitCode::SUCCESS } else { ExitCode::from(1) })
}

/// Removes the cells an earlier sweep into `out` left beyond this one's `cells`
/// (`cell-004` after a sweep of three): the folder then holds this sweep's cells alone. Only a
/// folder named as a cell that holds nothing but a batch's outputs is removed; another is
/// refused, named, before anything is removed or runs.
fn remove_stale_cells(out: &std::path::Path, cells: usize) -> Result<()> {
    const OUTPUTS: [&str; 5] = ["runs.csv", "runs.journal", "summary.json", "trajectories.csv", "scenario.toml"];
    let Ok(entries) = std::fs::read_dir(out) else { return Ok(()) };
    let mut stale = Vec::new();
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        let Some(k) = name.strip_prefix("cell-").and_then(|n| n.parse::<usize>().ok()) else { continue };
        if k >= 1 && k <= cells {
            continue;
        }
        let path = e.path();
        let ours = e.file_type().is_ok_and(|t| t.is_dir())
            && std::fs::read_dir(&path).is_ok_and(|inside| {
                inside.flatten().all(|f| {
                    f.file_type().is_ok_and(|t| t.is_file())
                        && OUTPUTS.contains(&f.file_name().to_string_lossy().as_ref())
                })
            });
        if !ours {
            bail!(
                "{} is left from an earlier sweep with more cells and holds more than a batch's outputs: \
                 move it away, or give another --out",
                path.display()
            );
        }
        stale.push(path);
    }
    for path in stale {
        std::fs::remove_dir_all(&path).with_context(|| format!("cannot remove {}", path.display()))?;
    }
    Ok(())
}
