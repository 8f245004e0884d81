//! The dependency table of one UAV (METHOD §6 step 3, the paper's Table 1).
//!
//! Each UAV names its main reference UAVs with dependency degrees `c_ij > 0`. The controller
//! uses the degree-weighted mean of the predictions from those it currently perceives.

use std::sync::Arc;

use crate::error::ConfigError;
use crate::observation::UavId;

/// Main references of one UAV with their dependency degrees.
/// The table is immutable and shared: cloning it (one copy for the scenario, one for the
/// controller) costs a reference count, not the entries. The tables of a whole formation built
/// with [`TableBuilder`] share one allocation: each is a span of it (24 bytes a UAV besides its
/// entries; a table of its own also carries its allocation's header and the allocator's).
#[derive(Clone)]
pub struct DependencySet {
    entries: Arc<[(UavId, f64)]>,
    start: u32,
    len: u32,
}

impl Default for DependencySet {
    fn default() -> Self {
        Self { entries: Arc::from(Vec::new()), start: 0, len: 0 }
    }
}

impl PartialEq for DependencySet {
    fn eq(&self, other: &Self) -> bool {
        self.refs() == other.refs()
    }
}

impl std::fmt::Debug for DependencySet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DependencySet").field("refs", &self.refs()).finish()
    }
}

/// The serialised form: the entries.
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(rename = "DependencySet")]
struct Repr<T> {
    refs: T,
}

impl serde::Serialize for DependencySet {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        Repr { refs: self.refs() }.serialize(s)
    }
}

impl<'de> serde::Deserialize<'de> for DependencySet {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let r = Repr::<Vec<(UavId, f64)>>::deserialize(d)?;
        let len = u32::try_from(r.refs.len()).map_err(serde::de::Error::custom)?;
        Ok(Self { entries: Arc::from(r.refs), start: 0, len })
    }
}

/// Checks one table (see [`DependencySet::new`]) and sorts it by id.
fn check(owner: UavId, size: usize, refs: &mut [(UavId, f64)]) -> Result<(), ConfigError> {
    for (k, &(id, degree)) in refs.iter().enumerate() {
        if id == owner {
            return Err(ConfigError::BadReference { owner, reference: id, reason: "a UAV cannot depend on itself" });
        }
        if id.index() >= size {
            return Err(ConfigError::BadReference { owner, reference: id, reason: "not in the formation" });
        }
        if !(degree.is_finite() && degree > 0.0) {
            return Err(ConfigError::OutOfRange {
                field: "dependency degree",
                value: degree,
                expected: "a finite degree > 0",
            });
        }
        if refs[..k].iter().any(|(other, _)| *other == id) {
            return Err(ConfigError::BadReference { owner, reference: id, reason: "named twice" });
        }
    }
    // Canonical order (by id), so that equal tables give equal sums bit for bit.
    refs.sort_by_key(|r| r.0);
    Ok(())
}

impl DependencySet {
    /// Builds the table of `owner` in a formation of `size` UAVs. Degrees must be finite and
    /// positive; references must be other UAVs of the formation, each named once. Entries are
    /// kept in id order.
    pub fn new(owner: UavId, size: usize, mut refs: Vec<(UavId, f64)>) -> Result<Self, ConfigError> {
        check(owner, size, &mut refs)?;
        let len = refs.len() as u32;
        Ok(Self { entries: Arc::from(refs), start: 0, len })
    }

    /// The dependency degree of `id`, if it is a main reference.
    #[inline]
    pub fn degree(&self, id: UavId) -> Option<f64> {
        self.refs().iter().find(|(r, _)| *r == id).map(|(_, c)| *c)
    }

    /// All main references.
    #[inline]
    pub fn refs(&self) -> &[(UavId, f64)] {
        &self.entries[self.start as usize..(self.start + self.len) as usize]
    }

    /// True when the UAV has no main references.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether the two tables are spans of one allocation (built together by a
    /// [`TableBuilder`], or clones of one table): a formation's tables take one allocation,
    /// not one per UAV.
    pub fn shares_entries_with(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.entries, &other.entries)
    }
}

/// The tables of a formation, UAV after UAV, into one shared allocation.
#[derive(Debug, Default)]
pub struct TableBuilder {
    size: usize,
    entries: Vec<(UavId, f64)>,
    spans: Vec<(u32, u32)>,
}

impl TableBuilder {
    /// For a formation of `size` UAVs, with room for `entries` references in all.
    pub fn new(size: usize, entries: usize) -> Self {
        Self { size, entries: Vec::with_capacity(entries), spans: Vec::with_capacity(size) }
    }

    /// The table of the next UAV, `owner` (checked as [`DependencySet::new`] does).
    pub fn push(&mut self, owner: UavId, refs: &[(UavId, f64)]) -> Result<(), ConfigError> {
        let start = self.entries.len();
        self.entries.extend_from_slice(refs);
        if let Err(e) = check(owner, self.size, &mut self.entries[start..]) {
            self.entries.truncate(start);
            return Err(e);
        }
        let too_many = |_| ConfigError::OutOfRange {
            field: "dependency entries",
            value: self.entries.len() as f64,
            expected: "at most 4 294 967 295 in a formation",
        };
        let (start32, end32) =
            (u32::try_from(start).map_err(too_many)?, u32::try_from(self.entries.len()).map_err(too_many)?);
        self.spans.push((start32, end32 - start32));
        Ok(())
    }

    /// The tables pushed, in order.
    pub fn finish(self) -> Vec<DependencySet> {
        let entries: Arc<[(UavId, f64)]> = Arc::from(self.entries);
        self.spans.into_iter().map(|(start, len)| DependencySet { entries: entries.clone(), start, len }).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checks_references() {
        let me = UavId(1);
        assert!(DependencySet::new(me, 6, vec![(UavId(0), 0.7), (UavId(2), 0.3)]).is_ok());
        assert!(DependencySet::new(me, 6, vec![(me, 1.0)]).is_err());
        assert!(DependencySet::new(me, 6, vec![(UavId(9), 1.0)]).is_err());
        assert!(DependencySet::new(me, 6, vec![(UavId(0), 0.0)]).is_err());
        assert!(DependencySet::new(me, 6, vec![(UavId(0), f64::NAN)]).is_err());
        assert!(DependencySet::new(me, 6, vec![(UavId(0), 0.5), (UavId(0), 0.5)]).is_err());
        let d = DependencySet::new(me, 6, vec![(UavId(0), 0.7)]).expect("valid");
        assert_eq!(d.degree(UavId(0)), Some(0.7));
        assert_eq!(d.degree(UavId(3)), None);
    }

    #[test]
    fn tables_built_together_equal_tables_built_alone() {
        let rows: [(u32, &[(u32, f64)]); 4] =
            [(0, &[]), (1, &[(3, 0.2), (0, 0.8)]), (2, &[(1, 1.0)]), (3, &[(2, 0.5), (1, 0.25), (0, 0.25)])];
        let mut b = TableBuilder::new(4, 6);
        let mut alone = Vec::new();
        for (owner, refs) in rows {
            let refs: Vec<(UavId, f64)> = refs.iter().map(|&(j, c)| (UavId(j), c)).collect();
            b.push(UavId(owner), &refs).expect("valid");
            alone.push(DependencySet::new(UavId(owner), 4, refs).expect("valid"));
        }
        // A bad row is refused and leaves the others as they were.
        assert!(b.push(UavId(0), &[(UavId(0), 1.0)]).is_err());
        let together = b.finish();
        assert_eq!(together, alone);
        assert_eq!(together[1].refs(), &[(UavId(0), 0.8), (UavId(3), 0.2)], "sorted by id");
        assert_eq!(together[3].degree(UavId(1)), Some(0.25));
        assert!(together[0].is_empty() && together[0].refs().is_empty());
        assert!(together[1].shares_entries_with(&together[3]));
        assert!(!alone[1].shares_entries_with(&alone[3]));
        // The same serialised form either way.
        let json = |d: &DependencySet| serde_json::to_string(d).expect("serialisable");
        assert_eq!(json(&together[3]), json(&alone[3]));
        let back: DependencySet = serde_json::from_str(&json(&together[3])).expect("readable");
        assert_eq!(back, alone[3]);
    }
}
