//! `proxform compare`: methods × conditions × seeds, the CSV, the printed table and the plots.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use proxform_scenario::comparison::{Comparison, BUILT_IN};
use proxform_scenario::{Scenario, ScenarioSpec};
use proxform_sim::compare::{flights, run_comparison, summarise, CellSummary};

use crate::scenarios::Source;

/// Arguments of `proxform compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Comparison file (TOML); without it, the built-in comparison (scenarios/compare-paper.toml).
    file: Option<PathBuf>,
    /// Seeds per cell, overriding the file's.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=proxform_scenario::comparison::MAX_SEEDS))]
    seeds: Option<u64>,
    /// Flight duration override (s), for quick looks.
    #[arg(long)]
    duration_s: Option<f64>,
    /// Output directory [default: out/<comparison name>].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads (0 = all cores, at most 256). Results do not depend on it.
    #[arg(long, default_value_t = 0, value_parser = crate::run::threads)]
    threads: usize,
    /// Skip the plots.
    #[arg(long)]
    no_figures: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

/// Loads the comparison: the file (its `scenario` a built-in name or a file beside it) or the
/// built-in one.
fn load(args: &CompareArgs) -> Result<Comparison> {
    let (text, name, dir) = match &args.file {
        Some(p) => (
            crate::files::read_input(p, "comparison file")?,
            p.display().to_string(),
            p.parent().map(Path::to_path_buf).unwrap_or_default(),
        ),
        None => (BUILT_IN.to_string(), "compare-paper (built-in)".to_string(), PathBuf::new()),
    };
    // The base scenario's spec, checked where it was read (a file's errors name the file),
    // with the command line's duration written in before the comparison checks its cells.
    let resolve = |s: &str| -> Result<ScenarioSpec, String> {
        let (mut spec, source) = if crate::scenarios::NAMES.contains(&s) {
            (crate::scenarios::built_in_spec(s, None).map_err(|e| format!("{e:#}"))?, Source::BuiltIn)
        } else {
            crate::scenarios::load_spec(&dir.join(s)).map_err(|e| format!("{e:#}"))?
        };
        let base = crate::scenarios::check(spec.clone(), &source).map_err(|e| format!("{e:#}"))?;
        crate::scenarios::warn(&base, &source);
        if let Some(d) = args.duration_s {
            spec.duration_s = Some(d);
            Scenario::try_from(spec.clone()).map_err(|e| format!("--duration-s: {}", e.message))?;
        }
        Ok(spec)
    };
    // The command line's seeds are written into the spec, so the file's limits apply to them.
    let parsed = Comparison::parse_spec(&text, &name).and_then(|mut spec| {
        if let Some(seeds) = args.seeds {
            spec.seeds = seeds;
        }
        Comparison::from_spec(spec, &text, &name, resolve)
    });
    if parsed.is_err() && crate::scenarios::kind_of(&text) == Some(crate::scenarios::FileKind::Scenario) {
        return parsed.with_context(|| {
            format!(
                "{name} is a scenario file: run it with `proxform run {name}`, or name it in a comparison file \
                 (scenario = \"{name}\")"
            )
        });
    }
    Ok(parsed?)
}

/// Runs the command. Exit code 0 once everything ran (the comparison has no pass criterion).
pub fn run(args: &CompareArgs) -> Result<ExitCode> {
    let cmp = load(args)?;
    let out = args.out.clone().unwrap_or_else(|| crate::files::default_out(&cmp.name));
    let _folder = crate::files::OutputFolder::new(&out, "output directory")?;
    let pool =
        rayon::ThreadPoolBuilder::new().num_threads(args.threads).build().context("cannot start worker threads")?;
    let bar = if args.quiet { ProgressBar::hidden() } else { ProgressBar::new(flights(&cmp)) };
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} runs ({per_sec}, eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let started = Instant::now();
    let rows = pool.install(|| run_comparison(&cmp, &|| bar.inc(1)))?;
    bar.finish_and_clear();
    let elapsed = started.elapsed();
    let cells = summarise(&rows);

    let mut written = vec![out.join("compare.csv"), out.join("compare_summary.csv")];
    write_csv(&written[0], &rows)?;
    write_csv(&written[1], &cells)?;
    if !args.no_figures {
        written.extend(crate::figures::compare_plots(&out, &cmp, &cells)?);
    }
    let mut w = std::io::stdout().lock();
    print(&mut w, &cmp, &cells, elapsed, pool.current_num_threads())?;
    writeln!(w, "\nwrote {} files to {}", written.len(), out.display())?;
    Ok(ExitCode::SUCCESS)
}

fn write_csv<T: serde::Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    let mut w = csv::Writer::from_writer(std::io::BufWriter::new(crate::files::create_output(path)?));
    for r in rows {
        w.serialize(r)?;
    }
    w.flush()?;
    Ok(())
}

/// The printed table: one block per condition, one line per method.
fn print(
    w: &mut impl Write,
    cmp: &Comparison,
    cells: &[CellSummary],
    elapsed: std::time::Duration,
    threads: usize,
) -> Result<()> {
    writeln!(
        w,
        "proxform compare: '{}' on scenario '{}' ({} UAVs): {} methods × {} conditions × {} seeds = {} runs \
         ({} flown: a method without radio shares its runs across radio conditions), {:.1} s on {} thread(s)\n",
        cmp.name,
        cmp.base.name(),
        cmp.base.len(),
        cmp.methods.len(),
        cmp.conditions.len(),
        cmp.seeds,
        cmp.runs(),
        flights(cmp),
        elapsed.as_secs_f64(),
        threads
    )?;
    writeln!(
        w,
        "err: largest |x|, |y| or |z| formation error of any follower over the flight (m); ratio: largest error over its \
         allowable error, any axis (≤ 1 passes); sep: smallest separation (m); adj, msg: adjustments and radio messages \
         per UAV-minute; effort: inputs over their per-step limits (RSS, median)"
    )?;
    let width = cmp.methods.iter().map(|m| m.name.len()).max().unwrap_or(8).max(8);
    for c in &cmp.conditions {
        writeln!(w, "\n{}", c.name)?;
        writeln!(
            w,
            "  {:width$}  {:>6}  {:>10}  {:>10}  {:>9}  {:>9}  {:>9}  {:>9}  {:>9}  {:>7}",
            "method",
            "pass",
            "err med m",
            "err p95 m",
            "ratio p95",
            "sep med",
            "sep p05",
            "adj/min",
            "msg/min",
            "effort"
        )?;
        for cell in cells.iter().filter(|x| x.condition == c.name) {
            writeln!(
                w,
                "  {:width$}  {:>5}%  {:>10} {:>11} {:>10}  {:>9.1}  {:>9.1}  {:>9.1}  {:>9.1}  {:>7.3}",
                cell.method,
                crate::report::percent(cell.pass_fraction),
                metres(cell.max_error_m_median),
                metres(cell.max_error_m_p95),
                metres(cell.error_ratio_p95),
                cell.min_separation_m_median,
                cell.min_separation_m_p05,
                cell.adjustments_per_uav_min,
                cell.messages_per_uav_min,
                cell.control_effort
            )?;
        }
    }
    Ok(())
}

/// Errors span metres to kilometres: three significant digits.
fn metres(v: f64) -> String {
    if !v.is_finite() {
        "—".into()
    } else if v < 10.0 {
        format!("{v:.3}")
    } else if v < 1000.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.3e}")
    }
}
