//! Built-in scenarios, scenario files, `proxform scenarios` and `proxform init`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use clap::Args;
use proxform_sim::Scenario;

/// Names of the built-in scenarios.
pub const NAMES: [&str; 3] = ["paper", "swarm", "fixed-wing-v"];

/// The built-in fixed-wing scenario (also scenarios/fixed-wing-v.toml).
const FIXED_WING_V: &str = include_str!("../../../scenarios/fixed-wing-v.toml");

/// The annotated example written by `proxform init`.
const EXAMPLE: &str = include_str!("../../../scenarios/example.toml");

/// A built-in scenario by name; `uavs` sizes the swarm.
pub fn built_in(name: &str, uavs: Option<u64>) -> Result<Scenario> {
    Ok(match (name, uavs) {
        ("paper", None) => Scenario::paper(),
        ("paper", Some(_)) => bail!("--uavs applies to --scenario swarm only; the paper experiment has 6 UAVs"),
        ("swarm", n) => proxform_sim::swarm::scenario(n.unwrap_or(1000) as usize).context("invalid swarm")?,
        ("fixed-wing-v", None) => proxform_sim::load::parse(FIXED_WING_V, "fixed-wing-v.toml")?,
        ("fixed-wing-v", Some(_)) => bail!("--uavs applies to --scenario swarm only"),
        (other, _) => bail!("unknown scenario '{other}' (see `proxform scenarios`)"),
    })
}

/// Reads and checks a scenario file; errors name the file, line and key.
pub fn load_file(path: &Path) -> Result<Scenario> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read scenario file {}", path.display()))?;
    let parsed = proxform_sim::load::parse(&text, &path.display().to_string());
    if parsed.is_err() && kind_of(&text) == Some(FileKind::Comparison) {
        return parsed.with_context(|| {
            format!("{} is a comparison file: run it with `proxform compare {}`", path.display(), path.display())
        });
    }
    Ok(parsed?)
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
    if path.exists() && !args.force {
        bail!("{} already exists (use --force to overwrite)", path.display());
    }
    std::fs::write(&path, EXAMPLE).with_context(|| format!("cannot write {}", path.display()))?;
    println!("wrote {}; run it with `proxform run {}`", path.display(), path.display());
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_in_files_are_valid_scenarios() {
        let s = proxform_sim::load::parse(FIXED_WING_V, "fixed-wing-v.toml").expect("loads");
        assert_eq!(s.len(), 12);
    }

    #[test]
    fn scenario_and_comparison_files_are_told_apart() {
        assert_eq!(kind_of(EXAMPLE), Some(FileKind::Scenario));
        assert_eq!(kind_of(FIXED_WING_V), Some(FileKind::Scenario));
        assert_eq!(kind_of(proxform_sim::compare::BUILT_IN), Some(FileKind::Comparison));
        assert_eq!(kind_of("name = \"x\"\n"), None);
    }

    #[test]
    fn the_example_is_a_valid_scenario() {
        let s = proxform_sim::load::parse(EXAMPLE, "example.toml").expect("the example loads");
        assert!(s.len() >= 2);
    }
}
