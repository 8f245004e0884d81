//! `proxform merge`: shards of one batch (output folders of `proxform run --first-run K`,
//! possibly from many machines) made the outputs one batch of all their runs would have
//! written, byte for byte.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use clap::Args;

use crate::{batch, report};

/// Arguments of `proxform merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Output folders of the shards (each with its runs.journal), or journals themselves.
    #[arg(required = true)]
    shards: Vec<PathBuf>,
    /// Folder to write the merged summary.json, runs.csv and runs.journal to (not one of the
    /// shards').
    #[arg(long)]
    out: PathBuf,
}

/// Runs the command; the exit code is 0 when every run passed, 1 otherwise.
pub fn run(args: &MergeArgs) -> Result<ExitCode> {
    let journals: Vec<PathBuf> =
        args.shards.iter().map(|p| if p.is_dir() { p.join(batch::JOURNAL) } else { p.clone() }).collect();
    for j in &journals {
        if !j.exists() {
            bail!("{} does not exist (a shard's output folder holds its runs.journal)", j.display());
        }
    }
    let _folder = crate::files::OutputFolder::new(&args.out, "output directory")?;
    let out = args.out.canonicalize().with_context(|| format!("cannot open {}", args.out.display()))?;
    let _lock = crate::files::lock_folder(&out)?;
    for j in &journals {
        let dir = j.canonicalize().with_context(|| format!("cannot open {}", j.display()))?;
        if dir.parent() == Some(out.as_path()) {
            bail!("--out {} holds the shard {}: write the merge to another folder", args.out.display(), j.display());
        }
    }
    let (scenario, summary) = batch::finish(&journals, &args.out, true)?;
    let mut stdout = std::io::stdout().lock();
    report::print(&mut stdout, &scenario, &summary, None)?;
    writeln!(
        stdout,
        "\nmerged {} shard(s): runs {}..={} of seed {}; wrote 3 files to {}",
        journals.len(),
        summary.first_run,
        summary.first_run + summary.runs.saturating_sub(1),
        summary.seed,
        args.out.display()
    )?;
    Ok(if summary.pass_fraction >= 1.0 { ExitCode::SUCCESS } else { ExitCode::from(1) })
}
