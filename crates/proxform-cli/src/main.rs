//! The `proxform` command-line tool.

mod batch;
mod bench;
mod compare;
#[cfg(feature = "net")]
mod distributed;
mod figures;
mod files;
mod html;
mod keys;
mod memory;
mod merge;
mod net_args;
mod output;
mod provenance;
mod report;
mod run;
mod scenarios;
mod sweep;

use clap::{Parser, Subcommand};

/// Distributed formation maintenance of UAV swarms from proximity observations.
#[derive(Debug, Parser)]
#[command(name = "proxform", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a scenario (by default the paper's six-UAV experiment) over one or more seeds.
    Run(run::RunArgs),
    /// Merge shards of one batch (`run --first-run K`) into the outputs of one batch.
    Merge(merge::MergeArgs),
    /// Run a grid of scenario values (`--set key=v1,v2`), a batch per cell, into one table.
    Sweep(sweep::SweepArgs),
    /// Compare formation control methods under radio loss, delay, noise and faults.
    Compare(compare::CompareArgs),
    /// Write report.html for an output folder (tables, figures over time and over the runs,
    /// a 3-D replay of the first run): one file that opens from disk.
    Report(ReportArgs),
    /// List the built-in scenarios.
    Scenarios,
    /// Write an annotated example scenario file.
    Init(scenarios::InitArgs),
    /// Measure agent-updates per second and peak memory of the swarm scenario, 10^2 … 10^6 UAVs.
    Bench(bench::BenchArgs),
    /// Serve the simulated world over Zenoh and wait for agents started elsewhere
    /// (`proxform run --distributed --external-agents`).
    World(run::RunArgs),
    /// Make a swarm's credentials (an authority, and a certificate and key per party) for
    /// authenticated flights over mutual TLS (`run --distributed --tls DIR`).
    Keys(keys::KeysArgs),
    /// Run one or more UAVs' controllers as this process (the `proxform-agent` program).
    #[command(disable_help_flag = true)]
    Agent {
        /// The agent's arguments (see `proxform agent --help`).
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<std::ffi::OsString>,
    },
}

/// `proxform agent …`: runs `proxform-agent` (beside this program) with the same arguments;
/// the controller never runs inside the program that links the simulator.
fn agent(args: &[std::ffi::OsString]) -> anyhow::Result<std::process::ExitCode> {
    use anyhow::Context;
    let bin = std::env::current_exe()
        .context("cannot locate this program")?
        .with_file_name(format!("proxform-agent{}", std::env::consts::EXE_SUFFIX));
    let status = std::process::Command::new(&bin).args(args).status().with_context(|| {
        format!("cannot run {} (build it with `cargo build --release -p proxform-net`)", bin.display())
    })?;
    Ok(std::process::ExitCode::from(status.code().map_or(2, |c| c.clamp(0, 255) as u8)))
}

/// `proxform report DIR`.
#[derive(Debug, clap::Args)]
struct ReportArgs {
    /// An output folder of `proxform run` (its summary.json; runs.csv, trajectories.csv and
    /// scenario.toml when there).
    dir: std::path::PathBuf,
}

fn report_folder(args: &ReportArgs) -> anyhow::Result<std::process::ExitCode> {
    if !args.dir.is_dir() {
        anyhow::bail!("{}: not a folder (give the output folder of a run)", args.dir.display());
    }
    let _lock = files::lock_folder(&args.dir)?;
    files::check_output(&args.dir.join(html::REPORT_FILE))?;
    let path = html::write(&args.dir, None)?;
    println!("wrote {}", path.display());
    Ok(std::process::ExitCode::SUCCESS)
}

/// `text` as it may go to a terminal: control characters (but the line breaks of a message of
/// several lines) and the characters that reorder text (bidirectional overrides) written as
/// escapes, so that a value quoted from a file or an argument cannot move the cursor, clear the
/// screen or disguise what is said.
pub fn terminal_safe(text: &str) -> std::borrow::Cow<'_, str> {
    let unsafe_char = |c: char| {
        (c.is_control() && c != '\n' && c != '\t')
            || matches!(c, '\u{200e}' | '\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
    };
    if !text.chars().any(unsafe_char) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 16);
    for c in text.chars() {
        match unsafe_char(c) {
            true => out.push_str(&format!("\\u{{{:x}}}", u32::from(c))),
            false => out.push(c),
        }
    }
    std::borrow::Cow::Owned(out)
}

/// A closed pipe (`proxform scenarios | head`) ends the output quietly, wherever it is printed:
/// `println!` panics on it (Rust ignores SIGPIPE), and that panic is not an error of ours.
fn quiet_on_closed_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let text = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if text.starts_with("failed printing to std") && text.contains("Broken pipe") {
            std::process::exit(0);
        }
        default(info);
    }));
}

fn main() -> std::process::ExitCode {
    quiet_on_closed_pipe();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run::run(&args),
        Command::World(mut args) => {
            args.net.distributed = true;
            args.net.external_agents = true;
            run::run(&args)
        }
        Command::Agent { args } => agent(&args),
        Command::Keys(args) => keys::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Merge(args) => merge::run(&args),
        Command::Sweep(args) => sweep::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Report(args) => report_folder(&args),
        Command::Scenarios => scenarios::list(),
        Command::Init(args) => scenarios::init(&args),
    };
    match result {
        Ok(code) => code,
        // A closed pipe (`proxform run | head`) ends the output, not the program with an error.
        Err(e) if e.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe) => {
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {}", terminal_safe(&format!("{e:#}")));
            std::process::ExitCode::from(2)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::terminal_safe;

    #[test]
    fn what_reaches_the_terminal_cannot_steer_it() {
        assert_eq!(terminal_safe("kind \"v\u{1b}[2J\""), "kind \"v\\u{1b}[2J\"");
        assert_eq!(terminal_safe("a\u{202e}b"), "a\\u{202e}b");
        assert_eq!(terminal_safe("two\nlines\tok"), "two\nlines\tok");
    }
}
