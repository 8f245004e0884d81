//! Shards of one batch made one: the check that pieces (journals, or shards in memory) are
//! runs of the same scenario, seed and options, none twice and none missing, and the run
//! order in which their runs fold into the summary one batch of all of them would have had.

use crate::batch::aggregate::Aggregator;
use crate::batch::journal::{JournalHeader, Shard};
use crate::batch::runs::{PerUavTotals, Summary};

/// One piece of a batch to merge: its name in errors (a folder, say), its header and the
/// indices of the runs it holds (any order).
#[derive(Debug, Clone, Copy)]
pub struct Piece<'a> {
    /// Named in errors.
    pub name: &'a str,
    /// What its runs are of.
    pub header: &'a JournalHeader,
    /// Its runs' indices.
    pub runs: &'a [u64],
}

/// Pieces that do not make one batch.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct MergeError(pub String);

/// Where each run of the merged batch is: (run index, piece, position in the piece), in run
/// order, and the merged batch's header.
#[derive(Debug, Clone)]
pub struct Plan {
    /// The merged batch's header (its first run the smallest, its runs all of them).
    pub header: JournalHeader,
    /// Every run in run order: (run, piece, position in that piece's `runs`).
    pub order: Vec<(u64, u32, u32)>,
}

/// Checks that `pieces` are complete shards of one batch, none overlapping, together a
/// contiguous range of runs, and returns the plan of the merge.
pub fn plan(pieces: &[Piece<'_>]) -> Result<Plan, MergeError> {
    let Some(first) = pieces.first() else {
        return Err(MergeError("nothing to merge".into()));
    };
    let h0 = first.header;
    for p in pieces {
        let h = p.header;
        let differ =
            |what: String| MergeError(format!("{} and {} are not shards of one batch: {what}", first.name, p.name));
        if h.version != h0.version {
            return Err(differ(format!("flown by proxform {} and {}", h0.version, h.version)));
        }
        if h.adjust != h0.adjust {
            return Err(differ("one ran with --no-adjust, the other not".into()));
        }
        if h.digest != h0.digest {
            let at = h0.first_difference(h).map(|d| format!(": {d}")).unwrap_or_default();
            return Err(differ(format!(
                "different scenarios (\"{}\" and \"{}\"; their values differ{at}; compare `proxform run \
                 --print-scenario` of each)",
                h0.scenario, h.scenario
            )));
        }
        if h.seed != h0.seed {
            return Err(differ(format!("seeds {} and {}", h0.seed, h.seed)));
        }
        if p.runs.len() as u64 != h.runs {
            return Err(MergeError(format!(
                "{} is unfinished: {} of its {} runs (its journal ends, or is damaged, after them; complete it with \
                 `proxform run ... --resume`)",
                p.name,
                p.runs.len(),
                h.runs
            )));
        }
    }
    let total: usize = pieces.iter().map(|p| p.runs.len()).sum();
    let mut order = Vec::with_capacity(total);
    for (i, p) in pieces.iter().enumerate() {
        let i = u32::try_from(i).map_err(|_| MergeError("more than 2^32 pieces".into()))?;
        for (k, &r) in p.runs.iter().enumerate() {
            let k = u32::try_from(k).map_err(|_| MergeError(format!("{}: more than 2^32 runs", p.name)))?;
            order.push((r, i, k));
        }
    }
    order.sort_unstable();
    for w in order.windows(2) {
        if w[0].0 == w[1].0 {
            let (a, b) = (pieces[w[0].1 as usize].name, pieces[w[1].1 as usize].name);
            return Err(MergeError(format!("run {} is in both {a} and {b}: shards must not overlap", w[0].0)));
        }
        if w[1].0 != w[0].0 + 1 {
            return Err(MergeError(format!(
                "runs {}..={} are in none of the shards: the shards must make one batch of consecutive runs",
                w[0].0 + 1,
                w[1].0 - 1
            )));
        }
    }
    let first_run = order.first().map_or(h0.first_run, |o| o.0);
    let header = JournalHeader { first_run, runs: order.len() as u64, ..h0.clone() };
    Ok(Plan { header, order })
}

/// Shards in memory merged into one (checked as [`plan`] checks).
pub fn merge_shards(shards: &[(&str, &Shard)]) -> Result<Shard, MergeError> {
    let indices: Vec<Vec<u64>> = shards.iter().map(|(_, s)| s.runs.iter().map(|r| r.run).collect()).collect();
    let pieces: Vec<Piece<'_>> =
        shards.iter().zip(&indices).map(|((name, s), runs)| Piece { name, header: &s.header, runs }).collect();
    let plan = plan(&pieces)?;
    let mut totals = PerUavTotals::default();
    for (_, s) in shards {
        totals.merge(&s.totals);
    }
    let runs = plan.order.iter().map(|&(_, i, k)| shards[i as usize].1.runs[k as usize].clone()).collect();
    Ok(Shard { header: plan.header, runs, totals })
}

impl Shard {
    /// The summary of the shard's runs, as a batch of exactly them would have written it.
    pub fn summary(&self) -> Result<Summary, crate::batch::journal::JournalError> {
        let scenario = self.header.scenario()?;
        let mut fold = Aggregator::new(&scenario, self.runs.len() as u64);
        fold.add_totals(&self.totals);
        for r in &self.runs {
            fold.add(r);
        }
        Ok(fold.finish(&scenario, self.header.seed, self.header.first_run))
    }
}
