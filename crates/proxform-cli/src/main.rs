//! The `proxform` command-line tool.

mod bench;
mod compare;
mod figures;
mod files;
mod memory;
mod output;
mod report;
mod run;
mod scenarios;

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
    /// Compare formation control methods under radio loss, delay, noise and faults.
    Compare(compare::CompareArgs),
    /// List the built-in scenarios.
    Scenarios,
    /// Write an annotated example scenario file.
    Init(scenarios::InitArgs),
    /// Measure agent-updates per second and peak memory of the swarm scenario, 10^2 … 10^6 UAVs.
    Bench(bench::BenchArgs),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Compare(args) => compare::run(&args),
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
            eprintln!("error: {e:#}");
            std::process::ExitCode::from(2)
        }
    }
}
