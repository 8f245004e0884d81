//! A batch's files: its journal (`runs.journal`, every run's exact result written as it
//! ends), the resume of an interrupted batch from it, and the outputs (`summary.json`,
//! `runs.csv`) made from one journal or from the journals of shards merged, by one fold in
//! run order, so that they are the same bytes however the runs were split or interrupted.

use std::fs::{File, OpenOptions};
use std::io::{BufReader, BufWriter, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use proxform_scenario::Scenario;
use proxform_sim::batch::journal::{self, JournalHeader, JournalWriter, Scan};
use proxform_sim::batch::merge::{plan, Piece};
use proxform_sim::{fly_runs, Aggregator, RunOptions, RunSummary, Summary, Trajectory};

use crate::output::{self, RunColumns, RunsCsv};

/// The journal's file name in an output folder.
pub const JOURNAL: &str = "runs.journal";

/// Runs between two commits of the journal at most, and the longest time between two.
const COMMIT_RUNS: u64 = 64;
const COMMIT_EVERY: Duration = Duration::from_secs(1);

/// Reads the journal at `path` from its start.
fn scan_file(path: &Path) -> Result<Scan> {
    let f = File::open(path).with_context(|| format!("cannot read {}", path.display()))?;
    if !f.metadata().with_context(|| format!("cannot read {}", path.display()))?.is_file() {
        bail!("{} is not a regular file", path.display());
    }
    journal::scan(&mut BufReader::new(f)).with_context(|| format!("{}", path.display()))
}

/// A batch's journal opened for writing, and which of its runs are already done.
pub struct Opened {
    writer: JournalWriter<BufWriter<File>>,
    /// Per run of the batch (from its first): done already.
    pub done: Vec<bool>,
    /// How many are done.
    pub resumed: u64,
}

/// Opens the journal of the batch `header` in `out`: a new one, or with `resume` the one
/// there (which must be of the same batch), cut after its last complete commit (a new one
/// when there is none yet, so that a job can always be started with `--resume`).
pub fn open(out: &Path, header: &JournalHeader, resume: bool) -> Result<Opened> {
    let path = out.join(JOURNAL);
    let n = usize::try_from(header.runs).context("too many runs for this machine")?;
    if !resume || !path.exists() {
        let f = crate::files::create_output(&path)?;
        let writer = JournalWriter::create(BufWriter::new(f), header)
            .with_context(|| format!("cannot write {}", path.display()))?;
        return Ok(Opened { writer, done: vec![false; n], resumed: 0 });
    }
    let scan = scan_file(&path)?;
    let h = &scan.header;
    let differs = if h.adjust != header.adjust {
        Some("of a batch with the other --no-adjust".into())
    } else if h.digest != header.digest {
        let at = h.first_difference(header).map(|d| format!(": {d}")).unwrap_or_default();
        Some(format!("of another scenario (\"{}\", or other values{at})", h.scenario))
    } else if (h.seed, h.first_run, h.runs) != (header.seed, header.first_run, header.runs) {
        Some(format!("of --seed {} --first-run {} --runs {}", h.seed, h.first_run, h.runs))
    } else if h.version != header.version {
        Some(format!("of proxform {}", h.version))
    } else {
        None
    };
    if let Some(what) = differs {
        bail!(
            "--resume: {} is {what}, not of this batch (--seed {} --first-run {} --runs {}); run without --resume to start again",
            path.display(),
            header.seed,
            header.first_run,
            header.runs
        );
    }
    let mut done = vec![false; n];
    for &(r, _) in &scan.runs {
        done[(r - header.first_run) as usize] = true;
    }
    let f = OpenOptions::new().write(true).open(&path).with_context(|| format!("cannot write {}", path.display()))?;
    // What follows the last complete commit (an unfinished tail) is flown again.
    f.set_len(scan.end).with_context(|| format!("cannot write {}", path.display()))?;
    let mut f = f;
    f.seek(SeekFrom::End(0)).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(Opened { writer: JournalWriter::append(BufWriter::new(f)), done, resumed: scan.runs.len() as u64 })
}

/// Flies the runs of `header` not yet done into the journal (committing at least every
/// [`COMMIT_RUNS`] runs and every second), ticking `progress` after each; returns the
/// recorded trajectory of the batch's first run, if it was flown and `record` given.
pub fn fly_into(
    scenario: &Scenario,
    header: &JournalHeader,
    opened: Opened,
    record: Option<Trajectory>,
    progress: &(dyn Fn() + Sync),
) -> Result<Option<Trajectory>> {
    let Opened { writer, done, .. } = opened;
    let stop = AtomicBool::new(false);
    let state = Mutex::new((writer, Instant::now(), None::<anyhow::Error>));
    let first = header.first_run;
    let on_done = |s: RunSummary| {
        let Ok(mut st) = state.lock() else { return };
        if st.2.is_some() {
            return;
        }
        let mut r = st.0.push(&s);
        if r.is_ok() && (st.0.pending() >= COMMIT_RUNS || st.1.elapsed() >= COMMIT_EVERY) {
            r = st.0.commit();
            st.1 = Instant::now();
        }
        if let Err(e) = r {
            st.2 = Some(anyhow::Error::new(e).context(format!("cannot write the journal {JOURNAL}")));
            stop.store(true, Ordering::Relaxed);
        }
    };
    let skip = |r: u64| done.get((r - first) as usize).copied().unwrap_or(true);
    let traj = fly_runs(
        scenario,
        header.options(),
        (header.seed, header.run_range()),
        &skip,
        record,
        (progress, &stop),
        &on_done,
    );
    let (writer, _, error) = state.into_inner().map_err(|_| anyhow::anyhow!("a worker thread panicked"))?;
    if let Some(e) = error {
        return Err(e);
    }
    writer.finish().with_context(|| format!("cannot write the journal {JOURNAL}"))?;
    Ok(traj.flatten())
}

/// Writes `summary.json` and `runs.csv` into `out` from the journals `journals` (one batch's,
/// or complete shards of one batch), and with `merged_journal` also the merged journal (so
/// the result merges again); returns the scenario and the summary.
pub fn finish(journals: &[PathBuf], out: &Path, merged_journal: bool) -> Result<(Scenario, Summary)> {
    let names: Vec<String> = journals
        .iter()
        .map(|p| p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(p).display().to_string())
        .collect();
    let scans: Vec<Scan> = journals.iter().map(|p| scan_file(p)).collect::<Result<_>>()?;
    let indices: Vec<Vec<u64>> = scans.iter().map(|s| s.runs.iter().map(|r| r.0).collect()).collect();
    let pieces: Vec<Piece<'_>> = scans
        .iter()
        .zip(&indices)
        .zip(&names)
        .map(|((s, runs), name)| Piece { name, header: &s.header, runs })
        .collect();
    let plan = plan(&pieces).map_err(anyhow::Error::msg)?;
    let scenario = plan.header.scenario().with_context(|| names[0].clone())?;
    let mut files: Vec<BufReader<File>> = journals
        .iter()
        .map(|p| File::open(p).map(BufReader::new).with_context(|| format!("cannot read {}", p.display())))
        .collect::<Result<_>>()?;
    let mut buf = Vec::new();
    let mut read = |i: u32, k: u32| -> Result<RunSummary> {
        let (i, k) = (i as usize, k as usize);
        journal::read_run(&mut files[i], scans[i].runs[k].1, &mut buf)
            .with_context(|| journals[i].display().to_string())
    };
    // Pass 1: the summary (and which columns runs.csv has).
    let mut fold = Aggregator::new(&scenario, plan.order.len() as u64);
    for s in &scans {
        fold.add_totals(&s.totals);
    }
    let mut columns = RunColumns::default();
    for (n, &(_, i, k)) in plan.order.iter().enumerate() {
        let r = read(i, k)?;
        if n == 0 {
            columns = RunColumns::of(&r, None);
        }
        fold.add(&r);
    }
    let summary = fold.finish(&scenario, plan.header.seed, plan.header.first_run);
    if let Some(first) = plan.order.first() {
        columns = RunColumns::of(&read(first.1, first.2)?, Some(&summary));
    }
    // Pass 2: the rows (and the merged journal).
    let mut csv = RunsCsv::create(&out.join("runs.csv"), plan.header.seed, columns)?;
    let mut merged = match merged_journal {
        true => {
            let path = out.join(JOURNAL);
            let f = crate::files::create_output(&path)?;
            Some(JournalWriter::create(BufWriter::new(f), &plan.header).with_context(|| path.display().to_string())?)
        }
        false => None,
    };
    for &(_, i, k) in &plan.order {
        let r = read(i, k)?;
        csv.write(&r)?;
        if let Some(m) = &mut merged {
            m.push(&r).context(JOURNAL)?;
        }
    }
    csv.finish()?;
    if let Some(mut m) = merged {
        let mut totals = proxform_sim::batch::runs::PerUavTotals::default();
        for s in &scans {
            totals.merge(&s.totals);
        }
        m.commit_with(&totals).context(JOURNAL)?;
        m.finish().context(JOURNAL)?;
    }
    output::write_summary(&out.join("summary.json"), &summary)?;
    Ok((scenario, summary))
}

/// The header of runs `first_run ..` (`runs` of them) of `scenario`.
pub fn header(scenario: &Scenario, options: RunOptions, runs: (u64, u64, u64)) -> Result<JournalHeader> {
    JournalHeader::new(scenario, options, runs).map_err(anyhow::Error::msg)
}
