//! Built-in scenarios, scenario files, `proxform scenarios` and `proxform init`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use clap::Args;
use proxform_scenario::builtin::{self, EXAMPLE};
use proxform_scenario::{load, Scenario, ScenarioSpec};

pub use builtin::NAMES;

/// Where a spec came from: a file's text (to locate errors in it) or a built-in.
#[derive(Debug, Clone)]
pub enum Source {
    /// A file: its name and text.
    File {
        /// The file's name, as given.
        name: String,
        /// Its text.
        text: String,
    },
    /// A built-in scenario.
    BuiltIn,
}

/// A built-in scenario's spec by name; `uavs` sizes the swarm.
pub fn built_in_spec(name: &str, uavs: Option<u64>) -> Result<ScenarioSpec> {
    if uavs.is_some() && name != "swarm" && builtin::NAMES.contains(&name) {
        bail!("--uavs applies to --scenario swarm only, not to {name}");
    }
    builtin::spec_by_name(name, uavs.map(|n| n as usize)).map_err(anyhow::Error::msg)
}

/// Reads a scenario file into its spec; errors name the file and line.
pub fn load_spec(path: &Path) -> Result<(ScenarioSpec, Source)> {
    let text = crate::files::read_input(path, "scenario file")?;
    let name = path.display().to_string();
    match load::parse_spec(&text, &name) {
        Ok(spec) => Ok((spec, Source::File { name, text })),
        Err(e) if kind_of(&text) == Some(FileKind::Comparison) => Err(anyhow::Error::new(e)
            .context(format!("{name} is a comparison file: run it with `proxform compare {name}`"))),
        Err(e) => Err(e.into()),
    }
}

/// Prints the scenario's warnings to standard error, located in its file when it has one.
pub fn warn(scenario: &Scenario, source: &Source) {
    warn_once(scenario, source, &mut Vec::new());
}

/// [`warn`], but for the warnings not among `said` yet (the cells of a sweep, which share
/// most of theirs), which it records.
pub fn warn_once(scenario: &Scenario, source: &Source, said: &mut Vec<String>) {
    for w in scenario.warnings() {
        let line = match source {
            Source::File { name, text } => match load::locate(text, &w.key) {
                Some(line) => format!("warning: {name}:{line}: {w}"),
                None => format!("warning: {name}: {w}"),
            },
            Source::BuiltIn => format!("warning: {w}"),
        };
        if !said.contains(&line) {
            eprintln!("{}", crate::terminal_safe(&line));
            said.push(line);
        }
    }
}

/// Converts a spec into a checked scenario; errors name the file, line and key.
pub fn check(spec: ScenarioSpec, source: &Source) -> Result<Scenario> {
    match source {
        Source::File { name, text } => Ok(load::check(spec, text, name)?),
        Source::BuiltIn => Scenario::try_from(spec).context("invalid scenario"),
    }
}

/// The engine the scenario runs on; `engine = "fast"` on a scenario the fast engine does not
/// run is an error naming the file, line and key.
pub fn engine(scenario: &Scenario, source: &Source) -> Result<proxform_sim::EngineKind> {
    proxform_sim::engine_for(scenario).map_err(|e| match source {
        Source::File { name, text } => match load::locate(text, "engine") {
            Some(line) => anyhow::anyhow!("{name}:{line}: engine: {e}"),
            None => anyhow::anyhow!("{name}: engine: {e}"),
        },
        Source::BuiltIn => anyhow::anyhow!("engine: {e}"),
    })
}

/// What a TOML file of proxform describes, judged by its tables and top-level keys.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    /// A scenario (`proxform run FILE`).
    Scenario,
    /// A comparison (`proxform compare FILE`).
    Comparison,
}

/// The kind of file `text` looks like, if it looks like one: used to point a user who gave a
/// file to the wrong command at the right one.
pub fn kind_of(text: &str) -> Option<FileKind> {
    let mut top_level = true;
    for line in text.lines().map(str::trim) {
        if line.starts_with("[[condition]]")
            || (top_level && (line.starts_with("methods") || line.starts_with("seeds")))
        {
            return Some(FileKind::Comparison);
        }
        if ["[formation", "[path", "[allowable", "[vehicle", "[controller"].iter().any(|t| line.starts_with(t)) {
            return Some(FileKind::Scenario);
        }
        top_level &= !line.starts_with('[');
    }
    None
}

/// Prints the built-in scenarios.
pub fn list() -> Result<ExitCode> {
    println!("Built-in scenarios (proxform run --scenario NAME):");
    println!("  paper   the paper's six-UAV experiment (METHOD §9); also scenarios/paper.toml");
    println!("  swarm   N UAVs (--uavs N, default 1000) in a multi-level lattice, for large-swarm runs");
    println!("  fixed-wing-v  12 fixed-wing UAVs in a V: climb and 180° turn in moderate turbulence;");
    println!("                also scenarios/fixed-wing-v.toml");
    println!("  aggregate     the paper's six from random starts within 1 km, forming, then the paper's");
    println!("                path; also scenarios/aggregate.toml");
    println!("  multirotor-v12-circuit  12 multirotors in a V around a square circuit (four 90° turns)");
    println!("                in a 25 km/h wind; also scenarios/multirotor-v12-circuit.toml");
    println!("  multirotor-lattice50-eight  50 multirotors take off, hover in a lattice, fly a");
    println!("                figure-eight; also scenarios/multirotor-lattice50-eight.toml");
    println!("  fixed-wing-echelon7-crosswind  7 fixed wings in an echelon through two 90° turns in a");
    println!("                30 km/h crosswind; also scenarios/fixed-wing-echelon7-crosswind.toml");
    println!("\nScenario files in scenarios/ run with `proxform run FILE.toml`; `proxform init` writes an");
    println!("annotated example; docs/scenarios.md lists every key.");
    Ok(ExitCode::SUCCESS)
}

/// Arguments of `proxform init`.
#[derive(Debug, Args)]
pub struct InitArgs {
    /// Where to write the example [default: scenario.toml].
    path: Option<PathBuf>,
    /// Overwrite an existing file.
    #[arg(long)]
    force: bool,
}

/// Writes the annotated example scenario.
pub fn init(args: &InitArgs) -> Result<ExitCode> {
    let path = args.path.clone().unwrap_or_else(|| PathBuf::from("scenario.toml"));
    // A dangling link "exists" too: nothing is written through it without --force, nor with it.
    if std::fs::symlink_metadata(&path).is_ok() && !args.force {
        bail!("{} already exists (use --force to overwrite)", path.display());
    }
    std::io::Write::write_all(&mut crate::files::create_output(&path)?, EXAMPLE.as_bytes())
        .with_context(|| format!("cannot write {}", path.display()))?;
    println!("wrote {}; run it with `proxform run {}`", path.display(), path.display());
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenario_and_comparison_files_are_told_apart() {
        assert_eq!(kind_of(EXAMPLE), Some(FileKind::Scenario));
        assert_eq!(kind_of(builtin::FIXED_WING_V), Some(FileKind::Scenario));
        assert_eq!(kind_of(builtin::COMPARE_PAPER), Some(FileKind::Comparison));
        assert_eq!(kind_of("name = \"x\"\n"), None);
    }
}
