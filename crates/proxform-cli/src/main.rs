//! The `proxform` command-line tool.

mod figures;
mod output;
mod report;
mod run;

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
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run::run(&args),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::from(2)
        }
    }
}
