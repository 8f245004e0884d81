//! `scenario.toml` in an output folder: the scenario as it ran, every default filled in
//! ([`proxform_scenario::resolved::write_toml`]), headed by what made it (the proxform version and
//! commit, the command line) and the command that flies the same runs again from the file.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use proxform_scenario::Scenario;

/// The file's name in an output folder.
pub const SCENARIO_FILE: &str = "scenario.toml";

/// The batch a folder holds: its seed, first run and number of runs, and whether the
/// adjustment was off (`--no-adjust`).
#[derive(Debug, Clone, Copy)]
pub struct Batch {
    pub seed: u64,
    pub first_run: u64,
    pub runs: u64,
    pub no_adjust: bool,
}

/// The version and commit of this build.
pub fn version() -> String {
    format!("proxform {} (commit {})", env!("CARGO_PKG_VERSION"), env!("PROXFORM_COMMIT"))
}

/// One argument as a shell reads it back: bare when it is plain, else in single quotes, with
/// control characters escaped (the header is one comment line per entry).
fn quoted(arg: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "_./:=,@+-%".contains(c);
    if !arg.is_empty() && arg.chars().all(plain) {
        return arg.to_string();
    }
    let mut s = String::from("'");
    for c in arg.chars() {
        match c {
            '\'' => s.push_str("'\\''"),
            c if c.is_control() => s.extend(c.escape_default()),
            c => s.push(c),
        }
    }
    s.push('\'');
    s
}

/// The command line this process was started with, quoted.
pub fn command_line() -> String {
    let mut args = std::env::args_os().map(|a| quoted(&a.to_string_lossy()));
    let first = args.next().map(|p| {
        // The program by its name, not the folder it was run from.
        Path::new(&p).file_name().map_or(p.clone(), |n| n.to_string_lossy().into_owned())
    });
    first.into_iter().chain(args).collect::<Vec<_>>().join(" ")
}

/// The text of `scenario.toml` for `scenario` flown as `batch`.
#[cfg(test)]
pub fn scenario_text(scenario: &Scenario, batch: Batch) -> Result<String> {
    let mut out = Vec::new();
    write_text(&mut out, scenario, batch)?;
    Ok(String::from_utf8(out)?)
}

/// Writes `scenario.toml`'s text for `scenario` flown as `batch` to `w`: its header, then the
/// scenario written a slot at a time (`resolved::write_toml`: a swarm's slots never held as
/// text).
fn write_text(w: &mut impl std::io::Write, scenario: &Scenario, batch: Batch) -> Result<()> {
    let mut again = format!("proxform run {SCENARIO_FILE} --seed {} --runs {}", batch.seed, batch.runs);
    if batch.first_run > 0 {
        again.push_str(&format!(" --first-run {}", batch.first_run));
    }
    if batch.no_adjust {
        again.push_str(" --no-adjust");
    }
    write!(
        w,
        "# The scenario as {} ran it, every default filled in.\n\
         # Command: {}\n\
         # Batch: seed {}, runs {} to {}. The same runs again (in process):\n\
         #   {again}\n\n",
        version(),
        command_line(),
        batch.seed,
        batch.first_run,
        (batch.first_run + batch.runs).saturating_sub(1),
    )?;
    proxform_scenario::resolved::write_toml(scenario, w).context("cannot write the scenario as TOML")
}

/// Writes `scenario.toml` into `dir` (fresh: never through a link).
pub fn write_scenario(dir: &Path, scenario: &Scenario, batch: Batch) -> Result<PathBuf> {
    let path = dir.join(SCENARIO_FILE);
    let mut file = std::io::BufWriter::new(crate::files::create_output(&path)?);
    write_text(&mut file, scenario, batch)
        .and_then(|()| Ok(std::io::Write::flush(&mut file)?))
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arguments_read_back_as_given() {
        assert_eq!(quoted("--seed"), "--seed");
        assert_eq!(quoted("a b"), "'a b'");
        assert_eq!(quoted("it's"), "'it'\\''s'");
        assert_eq!(quoted("x\ny"), "'x\\ny'");
        assert_eq!(quoted(""), "''");
    }

    #[test]
    fn the_header_says_what_made_it_and_how_to_fly_it_again() {
        let sc = proxform_scenario::builtin::paper();
        let text = scenario_text(&sc, Batch { seed: 7, first_run: 3, runs: 2, no_adjust: true }).expect("text");
        let header: Vec<&str> = text.lines().take_while(|l| l.starts_with('#')).collect();
        assert!(header[0].contains(env!("CARGO_PKG_VERSION")) && header[0].contains("commit "), "{header:?}");
        assert!(header.iter().any(|l| l.contains("seed 7, runs 3 to 4")), "{header:?}");
        assert!(
            header
                .iter()
                .any(|l| l.ends_with("proxform run scenario.toml --seed 7 --runs 2 --first-run 3 --no-adjust")),
            "{header:?}"
        );
        // And the rest is the scenario: it reads back to the same one.
        let back = proxform_scenario::load::parse(&text, "scenario.toml").expect("reads back");
        assert_eq!(proxform_scenario::resolved::to_toml(&back).ok(), proxform_scenario::resolved::to_toml(&sc).ok());
    }
}
