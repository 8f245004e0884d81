//! `proxform run`: a batch of seeded runs, the printed table and the output files.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use proxform_core::controller::MAX_HORIZON;
use proxform_core::Method;
use proxform_scenario::{Scenario, ScenarioSpec};
use proxform_sim::measure::trajectory::RowSink;
use proxform_sim::{RunOptions, Trajectory};

use crate::{figures, output, report};

/// Arguments of `proxform run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Scenario file (TOML) to run; see `proxform init` and docs/scenarios.md.
    file: Option<PathBuf>,
    /// Built-in scenario to run when no file is given (see `proxform scenarios`).
    #[arg(long, default_value = "paper", value_parser = crate::scenarios::NAMES)]
    scenario: String,
    /// Number of UAVs of the swarm scenario (2 to 10^7).
    #[arg(long, value_parser = clap::value_parser!(u64).range(2..=10_000_000))]
    uavs: Option<u64>,
    /// Flight duration override (s).
    #[arg(long)]
    duration_s: Option<f64>,
    /// Base seed; run r of a batch uses streams keyed by (seed, r).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Number of seeded runs, aggregated into one summary.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    runs: u64,
    /// Index of the batch's first run: the batch is runs K to K+N-1 of the seed, each the same
    /// as in any other batch (a shard; `proxform merge` makes shards one batch).
    #[arg(long, default_value_t = 0, value_name = "K", value_parser = clap::value_parser!(u64).range(0..=(1u64 << 52)))]
    first_run: u64,
    /// Complete the batch interrupted in the output folder (its runs.journal): the runs done
    /// are kept, the others flown, and the outputs are those of an uninterrupted batch.
    #[arg(long)]
    resume: bool,
    /// Set a key of the scenario, as in its file: `--set controller.lambda=0.5`,
    /// `--set radio.delay_s=0.2` (repeatable; TOML values, bare words as text).
    #[arg(long, value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Output directory [default: out/<scenario>].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads (0 = all cores, at most 256). Results do not depend on it.
    #[arg(long, default_value_t = 0, value_parser = threads)]
    threads: usize,
    /// Skip the figures (PNG and SVG).
    #[arg(long)]
    no_figures: bool,
    /// Skip report.html (the page with the tables, figures and a 3-D replay).
    #[arg(long)]
    no_report: bool,
    /// The figures' size, WIDTHxHEIGHT in pixels at 100 DPI (SVG at that size).
    #[arg(long, value_name = "WxH", default_value = "1000x760", value_parser = figure_size)]
    figure_size: (u32, u32),
    /// The PNG figures' resolution: their pixels, text and lines grow by DPI / 100 (300 for print).
    #[arg(long, value_name = "DPI", default_value_t = 100, value_parser = clap::value_parser!(u32).range(50..=600))]
    figure_dpi: u32,
    /// Skip trajectories.csv.
    #[arg(long)]
    no_trajectories: bool,
    /// UAVs whose trajectories the first run records (trajectories.csv and the figures), by
    /// number from 1: a list of numbers and ranges, e.g. `1,250-300` (the navigator is always
    /// recorded). Default: the first 64. More than 64 thin the steps recorded in proportion.
    #[arg(long, value_name = "LIST")]
    trajectory_uavs: Option<String>,
    /// Switch the controller's adjustment off (every input discarded): shows the check fail.
    #[arg(long)]
    no_adjust: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
    /// Override λ, the envelope centre's lean toward the main references, in [0, 1].
    #[arg(long)]
    lambda: Option<f64>,
    /// Override ρ, the envelope radius in permissible-error units, in (0, 1].
    #[arg(long)]
    rho: Option<f64>,
    /// Override τ, the position-closing time of the velocity reference (s); 0 switches it off.
    #[arg(long)]
    closing_time_s: Option<f64>,
    /// Override the neighbour predictor.
    #[arg(long, value_enum)]
    predictor: Option<Predictor>,
    /// Formation control method of the followers ("paper": the proximity method with the
    /// paper's choices; baselines with their default gains); the radio then carries what the
    /// method needs.
    #[arg(long, value_parser = method_labels())]
    method: Option<String>,
    /// Horizon H of the proximity method's predictive input (1: closed form; > 1: QP).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_HORIZON)))]
    horizon: Option<u32>,
    /// Print the scenario as it runs, every default filled in (TOML), and exit.
    #[arg(long)]
    print_scenario: bool,
    /// The distributed run's options.
    #[command(flatten)]
    pub net: crate::net_args::NetArgs,
}

/// A distributed batch (the world here, each follower's agent in its own process), with the
/// network's numbers printed to standard error.
#[cfg(feature = "net")]
fn distributed(
    scenario: &proxform_scenario::Scenario,
    options: RunOptions,
    seeds: (u64, u64),
    record: Option<Trajectory>,
    progress: &(dyn Fn() + Sync),
    net: &crate::net_args::NetArgs,
) -> Result<proxform_sim::BatchResult> {
    let d = crate::distributed::run(scenario, options, seeds, record, progress, net)?;
    let mut rt = d.stats.round_trips_s.clone();
    let (median, p99) = (
        proxform_sim::measure::stats::quantile_of(&mut rt, 0.5) * 1e3,
        proxform_sim::measure::stats::quantile_of(&mut rt, 0.99) * 1e3,
    );
    eprintln!(
        "distributed: {} agent process(es); {} decisions in time, {} missing (held), {} late, {} undecodable{}, {} on \
         another UAV's key, {} refused (not a number, beyond what the vehicle can do, or for an instant ahead of the flight; held), {} lost to [network] faults; \
         the network's round trip (before [network] delay_s) median \
         {:.3} ms, p99 {:.3} ms",
        d.processes,
        d.stats.answered,
        d.stats.missing,
        d.stats.late,
        d.stats.garbage,
        match d.stats.unsealed {
            0 => String::new(),
            n => format!(" ({n} not sealed with the flight's key: from a process without it)"),
        },
        d.stats.misplaced,
        d.stats.refused,
        d.stats.dropped,
        median,
        p99
    );
    if d.stats.steps > 0 {
        let mut ages = d.stats.ages_s.clone();
        let (a50, a99) = (
            proxform_sim::measure::stats::quantile_of(&mut ages, 0.5) * 1e3,
            proxform_sim::measure::stats::quantile_of(&mut ages, 0.99) * 1e3,
        );
        let mut applied = d.stats.applied_ages_s.clone();
        let commands = match applied.is_empty() {
            true => "no command was applied".to_string(),
            false => format!(
                "commands were {:.1} ms old (median), {:.1} ms (p99) of flight time when applied",
                proxform_sim::measure::stats::quantile_of(&mut applied, 0.5) * 1e3,
                proxform_sim::measure::stats::quantile_of(&mut applied, 0.99) * 1e3
            ),
        };
        eprintln!(
            "real time: {} of {} steps began late (> 0.1 Δt); the world fell a period behind {} time(s) and paused \
             the flight {:.3} s instead of replaying steps; updates were {a50:.3} ms old (median), {a99:.3} ms (p99) \
             when the agents stepped; {commands}; the radio went agent to agent (the report's radio line is the \
             world's model, not what the agents heard)",
            d.stats.late_steps, d.stats.steps, d.stats.paused.0, d.stats.paused.1
        );
    }
    for l in &d.losses {
        let back = match &l.restarted {
            Ok(n) => format!("started again (restart {n})"),
            Err(why) => format!("not started again: {why}"),
        };
        eprintln!("agent lost: {} ended ({}) in run {} at t = {:.2} s; {back}", l.label, l.status, l.at.0, l.at.1);
    }
    if !d.uncontrolled.is_empty() {
        let list: Vec<String> = d.uncontrolled.iter().map(|(u, s)| format!("UAV{u} {s:.1} s")).collect();
        eprintln!(
            "uncontrolled followers: {} (without their agent, or without its answers for more than \
             5 periods; holding their course, a multirotor hovering once its autopilot's failsafe took over)",
            list.join(", ")
        );
    }
    if d.stats.inbox_dropped > 0 {
        eprintln!(
            "{} message(s) dropped by the world's full inbox (more than {} MiB waiting: a flood)",
            d.stats.inbox_dropped,
            proxform_net::transport::INBOX_MAX_BYTES >> 20
        );
    }
    for (uav, spans) in &d.stats.rejoins {
        let said: Vec<String> = spans
            .iter()
            .map(|(from, to)| match to {
                Some(to) => format!("from {from:.1} s to {to:.1} s ({:.1} s)", to - from),
                None => format!("from {from:.1} s to the end"),
            })
            .collect();
        eprintln!(
            "UAV {uav} rejoined (back after flying without decisions; not followed until near its slot): {}",
            said.join(", ")
        );
    }
    for (uav, pids) in &d.stats.twins {
        let pids: Vec<String> = pids.iter().map(u32::to_string).collect();
        eprintln!(
            "warning: UAV {uav} had more than one agent at once (processes {}): their commands competed; run one \
             agent per UAV",
            pids.join(", ")
        );
    }
    if d.stats.foreign > 0 {
        eprintln!("{} announcement(s) or command(s) of agents running another scenario refused", d.stats.foreign);
    }
    if let Some(m) = &d.stats.mavlink {
        let flown: Vec<String> =
            m.uavs.iter().filter(|u| u.1 > 0).map(|u| format!("UAV{} {} steps", u.0, u.1)).collect();
        let (mut bad, mut refused) = (0, 0);
        for (_, _, link, r) in &m.uavs {
            bad += link.bad_crc + link.unknown + link.malformed;
            refused += r.foreign + r.invalid + r.commands;
        }
        eprintln!(
            "mavlink: {} UAV(s) served; flown by outside setpoints: {}; {bad} frame(s) undecodable, {refused} \
             message(s) refused (another system's, invalid values, commands not carried out)",
            m.uavs.len(),
            if flown.is_empty() { "none".to_string() } else { flown.join(", ") }
        );
    }
    if !d.usage.is_empty() {
        let n = d.usage.len() as f64;
        let cpu = d.usage.iter().map(|u| u.0).sum::<f64>() / n;
        let peak = d.usage.iter().map(|u| u.1).max().unwrap_or(0);
        eprintln!(
            "agent processes: CPU {cpu:.2} s each (mean; {:.1} % of the batch's {:.1} s), peak memory {} (largest)",
            100.0 * cpu / d.wall_s.max(1e-9),
            d.wall_s,
            crate::memory::mib(Some(peak))
        );
    }
    Ok(d.result)
}

/// The distributed run's checks that need no network, before any output is touched.
#[cfg(feature = "net")]
fn preflight(scenario: &proxform_scenario::Scenario, runs: u64, net: &crate::net_args::NetArgs) -> Result<()> {
    crate::distributed::preflight(scenario, runs, net)
}

#[cfg(not(feature = "net"))]
fn preflight(_: &proxform_scenario::Scenario, _: u64, _: &crate::net_args::NetArgs) -> Result<()> {
    Ok(())
}

#[cfg(not(feature = "net"))]
fn distributed(
    _: &proxform_scenario::Scenario,
    _: RunOptions,
    _: (u64, u64),
    _: Option<Trajectory>,
    _: &(dyn Fn() + Sync),
    _: &crate::net_args::NetArgs,
) -> Result<proxform_sim::BatchResult> {
    bail!("this proxform was built without the network agent: build it with `cargo build --release --features net -p proxform-cli -p proxform-net`")
}

/// Parses `--threads`: 0 (all cores) to [`crate::files::MAX_THREADS`].
pub fn threads(s: &str) -> Result<usize, String> {
    let n: usize = s.parse().map_err(|_| format!("'{s}' is not a whole number"))?;
    if n > crate::files::MAX_THREADS {
        return Err(format!("{n} threads: at most {} (0 uses every core)", crate::files::MAX_THREADS));
    }
    Ok(n)
}

/// Neighbour predictors selectable from the command line.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum Predictor {
    /// α-β tracking filter (the default).
    AlphaBeta,
    /// The plain transition F on the latest observation.
    ConstantVelocity,
    /// A Kalman filter with a Singer manoeuvre model (σ_a 1 m/s², τ 1 s, the scenario's noise).
    Singer,
}

impl RunArgs {
    /// Writes the command line's overrides into the spec, so that every check applies to
    /// them; returns which key each flag set, to name the flag in an error.
    fn apply_overrides(&self, spec: &mut ScenarioSpec) -> Result<Vec<(String, String)>> {
        let mut set: Vec<(String, String)> = Vec::new();
        for kv in &self.set {
            let (key, value) = crate::sweep::key_value(kv)?;
            *spec =
                proxform_scenario::overrides::set(spec, key, value).map_err(|m| anyhow::anyhow!("--set {kv}: {m}"))?;
            set.push((key.to_string(), format!("--set {kv}")));
        }
        let mut set_flag = |key: &str, flag: &str| set.push((key.to_string(), flag.to_string()));
        let c = &mut spec.controller;
        if let Some(d) = self.duration_s {
            spec.duration_s = Some(d);
            set_flag("duration_s", "--duration-s");
        }
        if let Some(l) = self.lambda {
            c.lambda = Some(l);
            set_flag("controller.lambda", "--lambda");
        }
        if let Some(r) = self.rho {
            c.rho = Some(r);
            set_flag("controller.rho", "--rho");
        }
        if let Some(t) = self.closing_time_s {
            c.closing_time_s = Some(t);
            set_flag("controller.closing_time_s", "--closing-time-s");
        }
        if let Some(p) = self.predictor {
            c.predictor = Some(
                match p {
                    Predictor::AlphaBeta => "alpha_beta",
                    Predictor::ConstantVelocity => "constant_velocity",
                    Predictor::Singer => "singer",
                }
                .into(),
            );
            (c.predictor_alpha, c.predictor_beta) = (None, None);
        }
        if let Some(h) = self.horizon {
            c.horizon = Some(i64::from(h));
            set_flag("controller.horizon", "--horizon");
        }
        if let Some(m) = &self.method {
            c.method = Some(m.clone());
            c.gains = None;
        }
        Ok(set)
    }
}

/// Runs the command; the exit code is 0 when every run passed, 1 otherwise.
pub fn run(args: &RunArgs) -> Result<ExitCode> {
    // `proxform world` is distributed whatever it was told; `run` is told so.
    for (given, flag) in
        [(args.net.external_agents, "--external-agents"), (args.net.mavlink_port.is_some(), "--mavlink-port")]
    {
        if given && !args.net.distributed {
            bail!("{flag} needs --distributed (or `proxform world`)");
        }
    }
    let (mut spec, source) = match &args.file {
        Some(path) => {
            if args.uavs.is_some() {
                bail!("--uavs applies to --scenario swarm only, not to a scenario file");
            }
            crate::scenarios::load_spec(path)?
        }
        None => (crate::scenarios::built_in_spec(&args.scenario, args.uavs)?, crate::scenarios::Source::BuiltIn),
    };
    let overridden = args.apply_overrides(&mut spec)?;
    let scenario = match proxform_scenario::Scenario::try_from(spec.clone()) {
        Ok(s) => s,
        Err(e) => match overridden.iter().find(|(key, _)| e.key == *key) {
            Some((_, flag)) => bail!("{flag}: {}", e.message),
            None => crate::scenarios::check(spec, &source)?,
        },
    };
    crate::scenarios::warn(&scenario, &source);
    let engine = crate::scenarios::engine(&scenario, &source)?;
    if args.print_scenario {
        use proxform_scenario::resolved::{write_toml, WriteError};
        let mut out = std::io::BufWriter::new(std::io::stdout().lock());
        match write_toml(&scenario, &mut out).and_then(|()| Ok(std::io::Write::flush(&mut out)?)) {
            // A reader that stopped early (`| head`) ends the output, not the program with an
            // error (`main`).
            Err(WriteError::Io(e)) if e.kind() == std::io::ErrorKind::BrokenPipe => return Err(e.into()),
            written => written.context("cannot write the scenario as TOML")?,
        }
        return Ok(ExitCode::SUCCESS);
    }
    let options = RunOptions { adjustment_enabled: !args.no_adjust, ..RunOptions::default() };
    let out = args.out.clone().unwrap_or_else(|| crate::files::default_out(scenario.name()));
    let look = figures::Look { size: args.figure_size, scale: f64::from(args.figure_dpi) / 100.0 };
    let (w, h) = (f64::from(look.size.0) * look.scale, f64::from(look.size.1) * look.scale);
    if w * h > figures::Look::MAX_PIXELS {
        bail!(
            "--figure-size {}x{} at --figure-dpi {}: PNGs of {w:.0} x {h:.0} pixels, more than the {:.0} million allowed",
            look.size.0,
            look.size.1,
            args.figure_dpi,
            figures::Look::MAX_PIXELS / 1e6
        );
    }
    // A bad list is refused before any file is written.
    let chosen = args.trajectory_uavs.as_deref().map(|l| uav_list(l, &scenario)).transpose()?;
    if args.net.distributed {
        preflight(&scenario, args.runs, &args.net)?;
    }
    // Said (or refused) before anything is allocated or written: runs fly one per worker.
    let workers = match args.threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    };
    let at_once = workers.min(usize::try_from(args.runs).unwrap_or(usize::MAX)).max(1);
    crate::memory::check_flights(&scenario, engine, at_once, crate::memory::available_bytes())?;
    let _folder = crate::files::OutputFolder::new(&out, "output directory")?;
    let _lock = crate::files::lock_folder(&out)?;
    // Outputs a link or FIFO would take are refused before anything flies.
    let outputs =
        ["summary.json", "runs.csv", "trajectories.csv", crate::batch::JOURNAL, crate::provenance::SCENARIO_FILE];
    for f in outputs.into_iter().chain([crate::html::REPORT_FILE]) {
        crate::files::check_output(&out.join(f))?;
    }
    // A new batch's folder holds no earlier batch's summary while it flies.
    for f in ["summary.json", "runs.csv"] {
        crate::files::clear_output(&out.join(f))?;
    }

    let pool =
        rayon::ThreadPoolBuilder::new().num_threads(args.threads).build().context("cannot start worker threads")?;
    // One bar tick per run, or per step for a single run (a long flight of a large swarm).
    let (len, unit) = if args.runs > 1 { (args.runs, "runs") } else { (scenario.steps(), "steps") };
    let show = !args.quiet && (args.runs > 1 || scenario.len() >= 1000 || scenario.steps() >= 100_000);
    let bar = if show { ProgressBar::new(len) } else { ProgressBar::hidden() };
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "{{spinner}} [{{elapsed_precise}}] {{bar:40}} {{pos}}/{{len}} {unit} ({{per_sec}}, eta {{eta}})"
        ))
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    // The first run's trajectory streams to its file as it flies; a decimated copy stays in
    // memory for the figures.
    let csv = out.join("trajectories.csv");
    let sink: Option<Box<dyn RowSink>> = match args.no_trajectories {
        true => None,
        false => Some(Box::new(output::TrajectoryCsv::create(&csv, scenario.dt_s())?)),
    };
    let record = (!(args.no_figures && args.no_trajectories)).then(|| {
        let t = Trajectory::for_flight(scenario.steps(), sink);
        match chosen {
            Some(uavs) => t.of_uavs(scenario.steps(), uavs),
            None => t,
        }
    });
    if args.net.distributed && (args.resume || args.first_run > 0) {
        bail!("--resume and --first-run are not available with --distributed: its agents fly a batch from run 0 to its end");
    }
    let batch = (args.seed, args.first_run, args.runs);
    let header = crate::batch::header(&scenario, options, batch)?;
    // What the folder holds says what made it, before it flies.
    let provenance = crate::provenance::Batch {
        seed: args.seed,
        first_run: args.first_run,
        runs: args.runs,
        no_adjust: args.no_adjust,
    };
    let scenario_file = crate::provenance::write_scenario(&out, &scenario, provenance)?;
    let started = Instant::now();
    let mut first_trajectory = if args.net.distributed {
        let d = distributed(&scenario, options, (args.seed, args.runs), record, &|| bar.inc(1), &args.net)?;
        bar.finish_and_clear();
        let shard = proxform_sim::Shard { header: header.clone(), runs: d.runs, totals: d.totals };
        let bytes = shard.to_bytes().map_err(anyhow::Error::msg)?;
        let path = out.join(crate::batch::JOURNAL);
        std::io::Write::write_all(&mut crate::files::create_output(&path)?, &bytes)
            .with_context(|| format!("cannot write {}", path.display()))?;
        d.first_trajectory
    } else {
        let opened = crate::batch::open(&out, &header, args.resume)?;
        if args.resume {
            eprintln!(
                "resuming: {} of {} runs done, flying the other {}",
                opened.resumed,
                args.runs,
                args.runs - opened.resumed
            );
            bar.set_length(if args.runs > 1 { args.runs - opened.resumed } else { len });
        }
        // A resumed batch whose first run is done flies it again for its trajectory alone.
        let first_done = opened.done.first().copied().unwrap_or(false);
        let (record, again) = if first_done { (None, record) } else { (record, None) };
        let mut traj = pool.install(|| crate::batch::fly_into(&scenario, &header, opened, record, &|| bar.inc(1)))?;
        if let Some(rec) = again {
            traj = proxform_sim::batch::runs::run_one_ticking(
                &scenario,
                options,
                (args.seed, args.first_run),
                Some(rec),
                &|| {},
            )
            .1;
        }
        traj
    };
    bar.finish_and_clear();
    let elapsed = started.elapsed();

    // Files first: a reader that closes the report early still gets them.
    let (_, summary) = crate::batch::finish(&[out.join(crate::batch::JOURNAL)], &out, false)?;
    let mut written =
        vec![out.join("summary.json"), out.join("runs.csv"), out.join(crate::batch::JOURNAL), scenario_file];
    if let Some(traj) = &mut first_trajectory {
        if let Some(mut sink) = traj.take_sink() {
            sink.finish().map_err(anyhow::Error::msg)?;
            written.push(csv);
        }
        if !args.no_figures {
            written.extend(figures::write_all(&out, &scenario, traj, &look)?);
        }
    }
    if !args.no_report {
        written.push(crate::html::write(&out, Some(&scenario))?);
    }
    let mut stdout = std::io::stdout().lock();
    report::print(&mut stdout, &scenario, &summary, Some((elapsed, pool.current_num_threads())))?;
    writeln!(stdout, "peak memory              {}", crate::memory::mib(crate::memory::peak_rss_bytes()))?;
    let engine = if args.net.distributed { "reference (agents in their own processes)" } else { engine.name() };
    writeln!(stdout, "engine                   {engine}")?;
    writeln!(stdout, "\nwrote {} files to {}", written.len(), out.display())?;
    Ok(if summary.pass_fraction >= 1.0 { ExitCode::SUCCESS } else { ExitCode::from(1) })
}

/// `--figure-size WxH`: each side 200 to 20 000 pixels.
fn figure_size(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("\"{s}\" is not WIDTHxHEIGHT in pixels (each 200 to 20000), e.g. 1600x900");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let side = |v: &str| v.trim().parse::<u32>().ok().filter(|v| (200..=20_000).contains(v)).ok_or_else(bad);
    Ok((side(w)?, side(h)?))
}

/// `--trajectory-uavs`: UAV numbers (from 1) and ranges `a-b`, comma-separated, as indices,
/// with the navigator's.
fn uav_list(list: &str, scenario: &Scenario) -> Result<Vec<usize>> {
    let n = scenario.len();
    let number = |s: &str| -> Result<usize> {
        if s.trim().is_empty() {
            bail!("--trajectory-uavs: an empty entry in \"{list}\" (numbers from 1 and ranges a-b, comma-separated)");
        }
        let u: usize = s.trim().parse().map_err(|_| {
            anyhow::anyhow!(
                "--trajectory-uavs: \"{}\" is not a UAV number (numbers from 1 and ranges a-b, comma-separated)",
                s.trim()
            )
        })?;
        if u == 0 || u > n {
            bail!("--trajectory-uavs: UAV {u} is not in the formation (UAVs 1 to {n})");
        }
        Ok(u - 1)
    };
    let mut out = vec![scenario.navigator().index()];
    for part in list.split(',') {
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (number(a)?, number(b)?);
                if a > b {
                    bail!("--trajectory-uavs: the range {}-{} runs backwards", a + 1, b + 1);
                }
                out.extend(a..=b);
            }
            None => out.push(number(part)?),
        }
    }
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

/// The labels `--method` takes: the methods', and "paper".
fn method_labels() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(Method::LABELS.iter().copied().chain([proxform_scenario::convert::PAPER]))
}
