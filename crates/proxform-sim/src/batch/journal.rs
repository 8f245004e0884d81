//! The journal of a batch: its runs' exact results as bytes, written as each run ends, from
//! which the batch's outputs are made, an interrupted batch resumes, and shards of one batch
//! run on many machines merge into the outputs one batch would have written.
//!
//! Layout (all integers little-endian): the 8 bytes `PXFJRNL1`, then frames. A frame is its
//! kind (1 byte: 1 header, 2 run, 3 totals), its payload's length (u32), the payload
//! (postcard) and a checksum (FNV-1a 64 over kind, length and payload). The first frame is
//! the [`JournalHeader`]; then run frames (a [`RunSummary`] without its per-follower detail,
//! every float to the bit) each followed, sooner or later, by a totals frame holding the
//! per-follower totals ([`PerUavTotals`]) of the runs since the previous one. Only runs
//! covered by a totals frame count as done: a journal cut short (a killed batch) keeps every
//! run up to its last totals frame, and what follows is dropped and flown again on resume.
//!
//! This module reads and writes bytes only (`std::io`); the caller owns the files.

use std::io::{Read, Seek, SeekFrom, Write};

use proxform_scenario::Scenario;

use crate::batch::runs::PerUavTotals;
use crate::measure::metrics::RunSummary;
use crate::world::options::RunOptions;

/// The first bytes of every journal.
pub const MAGIC: &[u8; 8] = b"PXFJRNL1";

const HEADER: u8 = 1;
const RUN: u8 = 2;
const TOTALS: u8 = 3;

/// Largest frame payload read back (a totals frame of 4096 followers is ~300 kB).
const MAX_FRAME: u32 = 64 << 20;

/// What a journal is of: which scenario, run how, which runs. Two journals merge only when
/// everything but the runs is the same.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JournalHeader {
    /// The proxform version that flew the runs.
    pub version: String,
    /// The scenario's name.
    pub scenario: String,
    /// FNV-1a 64 digest of the scenario as it runs (`resolved::to_toml`, every default filled
    /// in) and the run options: equal digests, equal flights.
    pub digest: u64,
    /// The scenario's spec as TOML (what was converted, the command line's overrides in it),
    /// from which a reader rebuilds the scenario exactly.
    pub spec_toml: String,
    /// Whether the controller's adjustment was on (`--no-adjust` off).
    pub adjust: bool,
    /// The batch's base seed.
    pub seed: u64,
    /// The batch's first run index.
    pub first_run: u64,
    /// Its number of runs.
    pub runs: u64,
}

/// A journal that cannot be read or does not fit.
#[derive(Debug, thiserror::Error)]
pub enum JournalError {
    /// Reading or writing failed.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// The bytes do not start as a journal.
    #[error("not a proxform batch journal (it does not start with \"PXFJRNL1\")")]
    NotAJournal,
    /// The journal's header frame is cut short or damaged (a write torn by a kill, or a change
    /// on disk): nothing in it can be trusted.
    #[error("a proxform batch journal whose header is cut short or damaged: start the batch again without --resume")]
    BadHeader,
    /// A frame that cannot be decoded although its checksum holds (another version's).
    #[error("byte {offset}: {message}")]
    Decode {
        /// Where the frame starts.
        offset: u64,
        /// What failed.
        message: String,
    },
    /// The scenario or options cannot be written or rebuilt.
    #[error("{0}")]
    Scenario(String),
    /// A run recorded twice, or outside the batch's runs.
    #[error("{0}")]
    Runs(String),
}

/// FNV-1a 64 of the bytes written to it.
struct Fnv1a(u64);

impl Default for Fnv1a {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv1a {
    fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
}

impl Write for Fnv1a {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.update(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// FNV-1a 64 of `parts` one after the other.
fn fnv1a(parts: &[&[u8]]) -> u64 {
    let mut h = Fnv1a::default();
    for p in parts {
        h.update(p);
    }
    h.0
}

impl JournalHeader {
    /// The header of runs `first_run ..` (`runs` of them) of `scenario` with seed `seed`.
    pub fn new(
        scenario: &Scenario,
        options: RunOptions,
        (seed, first_run, runs): (u64, u64, u64),
    ) -> Result<Self, JournalError> {
        let spec_toml = toml::to_string(scenario.spec())
            .map_err(|e| JournalError::Scenario(format!("cannot write the scenario: {e}")))?;
        Ok(Self {
            version: env!("CARGO_PKG_VERSION").to_string(),
            scenario: scenario.name().to_string(),
            digest: digest(scenario, options)?,
            spec_toml,
            adjust: options.adjustment_enabled,
            seed,
            first_run,
            runs,
        })
    }

    /// The scenario the runs flew, rebuilt from its spec (and checked against the digest).
    pub fn scenario(&self) -> Result<Scenario, JournalError> {
        let sc = proxform_scenario::load::parse(&self.spec_toml, &self.scenario)
            .map_err(|e| JournalError::Scenario(format!("the journal's scenario does not load: {e}")))?;
        if digest(&sc, self.options())? != self.digest {
            return Err(JournalError::Scenario(
                "the journal's scenario does not rebuild as it ran (another proxform version?)".into(),
            ));
        }
        Ok(sc)
    }

    /// Where this batch's scenario as it runs (`--print-scenario`'s values) first differs
    /// from `other`'s: the two lines, or None when they read the same (or cannot be rebuilt).
    pub fn first_difference(&self, other: &JournalHeader) -> Option<String> {
        let text = |h: &JournalHeader| {
            let sc = proxform_scenario::load::parse(&h.spec_toml, &h.scenario).ok()?;
            proxform_scenario::resolved::to_toml(&sc).ok()
        };
        let (a, b) = (text(self)?, text(other)?);
        let mut section = "";
        for (x, y) in a.lines().zip(b.lines()) {
            if x.starts_with('[') {
                section = x;
            }
            if x != y {
                return Some(format!("{section} `{}` against `{}`", x.trim(), y.trim()).trim_start().to_string());
            }
        }
        (a.lines().count() != b.lines().count()).then(|| "one lists more values than the other".to_string())
    }

    /// The run options the runs flew with.
    pub fn options(&self) -> RunOptions {
        RunOptions { adjustment_enabled: self.adjust, ..RunOptions::default() }
    }

    /// The runs' indices.
    pub fn run_range(&self) -> std::ops::Range<u64> {
        self.first_run..self.first_run.saturating_add(self.runs)
    }
}

/// The digest of a scenario as it runs and of the options that change results.
/// The scenario's text is hashed as it is written, never held (a swarm's slots are hundreds of
/// megabytes of it).
pub fn digest(scenario: &Scenario, options: RunOptions) -> Result<u64, JournalError> {
    let mut h = Fnv1a::default();
    proxform_scenario::resolved::write_toml(scenario, &mut h)
        .map_err(|e| JournalError::Scenario(format!("cannot write the scenario: {e}")))?;
    h.update(&[u8::from(options.adjustment_enabled)]);
    Ok(h.0)
}

fn frame(w: &mut impl Write, kind: u8, payload: &[u8]) -> std::io::Result<u64> {
    let len = u32::try_from(payload.len()).map_err(|_| std::io::Error::other("a journal frame over 4 GiB"))?;
    let len = len.to_le_bytes();
    let sum = fnv1a(&[&[kind], &len, payload]);
    w.write_all(&[kind])?;
    w.write_all(&len)?;
    w.write_all(payload)?;
    w.write_all(&sum.to_le_bytes())?;
    Ok(1 + 4 + payload.len() as u64 + 8)
}

fn encode<T: serde::Serialize>(v: &T) -> Result<Vec<u8>, JournalError> {
    postcard::to_stdvec(v).map_err(|e| JournalError::Scenario(format!("cannot encode: {e}")))
}

/// Writes a journal: the header once, then runs as they end and their totals when committed.
pub struct JournalWriter<W: Write> {
    w: W,
    pending: PerUavTotals,
    pending_runs: u64,
    buf: Vec<u8>,
}

impl<W: Write> JournalWriter<W> {
    /// A new journal on `w`: writes the magic and the header.
    pub fn create(mut w: W, header: &JournalHeader) -> Result<Self, JournalError> {
        w.write_all(MAGIC)?;
        frame(&mut w, HEADER, &encode(header)?)?;
        w.flush()?;
        Ok(Self::append(w))
    }

    /// Goes on with a journal whose valid part `w` ends at (see [`scan`]).
    pub fn append(w: W) -> Self {
        Self { w, pending: PerUavTotals::default(), pending_runs: 0, buf: Vec::new() }
    }

    /// Writes a run that ended (its per-follower detail folded into the pending totals).
    pub fn push(&mut self, run: &RunSummary) -> Result<(), JournalError> {
        self.pending.add(&run.per_uav);
        self.buf.clear();
        let lean = RunSummary { per_uav: Vec::new(), ..run.clone() };
        self.buf = postcard::to_extend(&lean, std::mem::take(&mut self.buf))
            .map_err(|e| JournalError::Scenario(format!("cannot encode a run: {e}")))?;
        frame(&mut self.w, RUN, &self.buf)?;
        self.pending_runs += 1;
        Ok(())
    }

    /// Writes a totals frame of `totals` for the runs written since the last commit (runs
    /// pushed without their per-follower detail: a merge's, a shard's) and flushes.
    pub fn commit_with(&mut self, totals: &PerUavTotals) -> Result<(), JournalError> {
        self.pending.merge(totals);
        self.pending_runs = self.pending_runs.max(1);
        self.commit()
    }

    /// Runs written since the last commit.
    pub fn pending(&self) -> u64 {
        self.pending_runs
    }

    /// Writes the pending runs' totals and flushes: from here they count as done.
    pub fn commit(&mut self) -> Result<(), JournalError> {
        if self.pending_runs > 0 {
            frame(&mut self.w, TOTALS, &encode(&self.pending)?)?;
            self.pending = PerUavTotals::default();
            self.pending_runs = 0;
        }
        self.w.flush()?;
        Ok(())
    }

    /// Commits and gives the writer back.
    pub fn finish(mut self) -> Result<W, JournalError> {
        self.commit()?;
        Ok(self.w)
    }
}

/// What [`scan`] found in a journal.
#[derive(Debug, Clone)]
pub struct Scan {
    /// The header.
    pub header: JournalHeader,
    /// The done runs: (run index, byte offset of its frame), in the order written.
    pub runs: Vec<(u64, u64)>,
    /// The done runs' per-follower totals.
    pub totals: PerUavTotals,
    /// Where the valid part ends (after the last totals frame).
    pub end: u64,
    /// Bytes after it (an unfinished tail: runs flown again on resume).
    pub dropped_bytes: u64,
}

impl Scan {
    /// True when every run of the header is done.
    pub fn complete(&self) -> bool {
        self.runs.len() as u64 == self.header.runs
    }
}

/// Reads one frame at the reader's position: Ok(None) at a clean end or a torn or corrupt
/// tail.
fn read_frame(r: &mut impl Read, buf: &mut Vec<u8>) -> std::io::Result<Option<u8>> {
    let mut head = [0u8; 5];
    if read_full(r, &mut head)? < 5 {
        return Ok(None);
    }
    let len = u32::from_le_bytes([head[1], head[2], head[3], head[4]]);
    if len > MAX_FRAME || ![HEADER, RUN, TOTALS].contains(&head[0]) {
        return Ok(None);
    }
    buf.resize(len as usize + 8, 0);
    if read_full(r, buf)? < buf.len() {
        return Ok(None);
    }
    let (payload, sum) = buf.split_at(len as usize);
    let mut s = [0u8; 8];
    s.copy_from_slice(sum);
    if fnv1a(&[&[head[0]], &head[1..5], payload]) != u64::from_le_bytes(s) {
        return Ok(None);
    }
    buf.truncate(len as usize);
    Ok(Some(head[0]))
}

fn read_full(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

fn decode<'a, T: serde::Deserialize<'a>>(bytes: &'a [u8], offset: u64) -> Result<T, JournalError> {
    postcard::from_bytes(bytes)
        .map_err(|e| JournalError::Decode { offset, message: format!("cannot decode a frame: {e}") })
}

/// Reads a journal from its start: the header, the done runs and their totals, and where the
/// valid part ends. A run outside the header's runs is an error.
pub fn scan(r: &mut impl Read) -> Result<Scan, JournalError> {
    let mut magic = [0u8; 8];
    if read_full(r, &mut magic)? < 8 || &magic != MAGIC {
        return Err(JournalError::NotAJournal);
    }
    let mut buf = Vec::new();
    let mut at = MAGIC.len() as u64;
    let header: JournalHeader = match read_frame(r, &mut buf)? {
        Some(HEADER) => decode(&buf, at)?,
        _ => return Err(JournalError::BadHeader),
    };
    at += 13 + buf.len() as u64;
    let range = header.run_range();
    let (mut runs, mut pending) = (Vec::new(), Vec::new());
    let mut totals = PerUavTotals::default();
    let mut end = at;
    while let Some(kind) = read_frame(r, &mut buf)? {
        match kind {
            RUN => {
                let run: RunSummary = decode(&buf, at)?;
                if !range.contains(&run.run) {
                    return Err(JournalError::Runs(format!(
                        "byte {at}: run {} is not one of the journal's runs {}..={}",
                        run.run,
                        range.start,
                        range.end.saturating_sub(1)
                    )));
                }
                // A run recorded twice is found where the runs are ordered (`merge::plan`).
                pending.push((run.run, at));
            }
            TOTALS => {
                let t: PerUavTotals = decode(&buf, at)?;
                totals.merge(&t);
                runs.append(&mut pending);
                end = at + 13 + buf.len() as u64;
            }
            _ => {
                return Err(JournalError::Decode { offset: at, message: "a second header".into() });
            }
        }
        at += 13 + buf.len() as u64;
    }
    let mut rest = 0u64;
    let mut sink = [0u8; 8192];
    loop {
        let k = r.read(&mut sink)?;
        if k == 0 {
            break;
        }
        rest += k as u64;
    }
    Ok(Scan { header, runs, totals, end, dropped_bytes: at - end + rest })
}

/// Reads the run whose frame starts at `offset` (from [`Scan::runs`]).
pub fn read_run<R: Read + Seek>(r: &mut R, offset: u64, buf: &mut Vec<u8>) -> Result<RunSummary, JournalError> {
    r.seek(SeekFrom::Start(offset))?;
    match read_frame(r, buf)? {
        Some(RUN) => decode(buf, offset),
        _ => Err(JournalError::Decode { offset, message: "no run frame here (the file changed?)".into() }),
    }
}

/// A batch's runs held in memory with their header and totals (a shard in Python, pickled as
/// its journal's bytes).
#[derive(Debug, Clone, PartialEq)]
pub struct Shard {
    /// What the runs are of.
    pub header: JournalHeader,
    /// The runs, in run order, without per-follower detail.
    pub runs: Vec<RunSummary>,
    /// Their per-follower totals.
    pub totals: PerUavTotals,
}

impl Shard {
    /// The journal's bytes.
    pub fn to_bytes(&self) -> Result<Vec<u8>, JournalError> {
        let mut w = JournalWriter::create(Vec::new(), &self.header)?;
        for r in &self.runs {
            w.push(r)?;
        }
        w.commit_with(&self.totals)?;
        w.finish()
    }

    /// A shard from a journal's bytes: every run of its header must be done.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, JournalError> {
        let mut c = std::io::Cursor::new(bytes);
        let scan = scan(&mut c)?;
        if !scan.complete() {
            return Err(JournalError::Runs(format!(
                "an unfinished batch: {} of its {} runs",
                scan.runs.len(),
                scan.header.runs
            )));
        }
        let mut buf = Vec::new();
        let mut runs = Vec::with_capacity(scan.runs.len());
        for &(_, at) in &scan.runs {
            runs.push(read_run(&mut c, at, &mut buf)?);
        }
        runs.sort_by_key(|r| r.run);
        if let Some((k, r)) = runs.iter().enumerate().find(|(k, r)| r.run != scan.header.first_run + *k as u64) {
            return Err(JournalError::Runs(format!(
                "run {} recorded where run {} belongs (a run twice, another missing)",
                r.run,
                scan.header.first_run + k as u64
            )));
        }
        Ok(Self { header: scan.header, runs, totals: scan.totals })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::runs::run_batch_stoppable;

    fn shard(first: u64, runs: u64) -> Shard {
        let sc = proxform_scenario::builtin::paper();
        let never = std::sync::atomic::AtomicBool::new(false);
        let b = run_batch_stoppable(&sc, RunOptions::default(), (3, first, runs), None, &|| {}, &never).expect("ran");
        let header = JournalHeader::new(&sc, RunOptions::default(), (3, first, runs)).expect("header");
        Shard { header, runs: b.runs, totals: b.totals }
    }

    #[test]
    fn a_journal_keeps_every_bit_and_drops_only_an_unfinished_tail() {
        let s = shard(5, 3);
        let bytes = s.to_bytes().expect("bytes");
        assert_eq!(Shard::from_bytes(&bytes).expect("reads"), s);
        // Every cut short of the end loses the commit: the runs are not done, nothing panics;
        // a cut inside the header is a damaged header.
        let header_end = scan(&mut std::io::Cursor::new(&bytes[..])).expect("reads").runs[0].1 as usize;
        for cut in [bytes.len() - 1, bytes.len() - 9, (header_end + bytes.len()) / 2, header_end + 3, header_end] {
            let scan = scan(&mut std::io::Cursor::new(&bytes[..cut])).expect("a journal");
            assert!(scan.runs.is_empty(), "cut at {cut}: {:?}", scan.runs);
            assert!(Shard::from_bytes(&bytes[..cut]).is_err());
        }
        for cut in [header_end - 1, 20, 9] {
            assert!(matches!(scan(&mut std::io::Cursor::new(&bytes[..cut])), Err(JournalError::BadHeader)), "{cut}");
        }
        assert!(matches!(scan(&mut std::io::Cursor::new(&bytes[..3])), Err(JournalError::NotAJournal)));
        // A flipped bit anywhere after the header is a torn tail, never a wrong result.
        for at in (header_end..bytes.len()).step_by(37) {
            let mut b = bytes.clone();
            b[at] ^= 0x10;
            let scan = scan(&mut std::io::Cursor::new(&b)).expect("a journal");
            assert!(!scan.complete(), "a flipped bit at {at} went unnoticed");
        }
        assert!(matches!(scan(&mut std::io::Cursor::new(b"PXFJRNL0")), Err(JournalError::NotAJournal)));
        assert!(matches!(scan(&mut std::io::Cursor::new(b"")), Err(JournalError::NotAJournal)));
    }

    #[test]
    fn the_header_rebuilds_the_scenario_and_refuses_a_changed_one() {
        let s = shard(0, 1);
        let sc = s.header.scenario().expect("rebuilds");
        assert_eq!(digest(&sc, RunOptions::default()).expect("digest"), s.header.digest);
        let mut h = s.header.clone();
        h.spec_toml = h.spec_toml.replacen("[controller]", "[controller]\nlambda = 0.3", 1);
        assert!(h.spec_toml.contains("lambda = 0.3"), "{}", h.spec_toml);
        assert!(h.scenario().is_err());
    }
}
