//! The dependency table of one UAV (METHOD §6 step 3, the paper's Table 1).
//!
//! Each UAV names its main reference UAVs with dependency degrees `c_ij > 0`. The controller
//! uses the degree-weighted mean of the predictions from those it currently perceives.

use std::sync::Arc;

use crate::error::ConfigError;
use crate::observation::UavId;

/// Main references of one UAV with their dependency degrees.
/// The table is immutable and shared: cloning it (one copy for the scenario, one for the
/// controller) costs a reference count, not the entries.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct DependencySet {
    refs: Arc<[(UavId, f64)]>,
}

impl DependencySet {
    /// Builds the table of `owner` in a formation of `size` UAVs. Degrees must be finite and
    /// positive; references must be other UAVs of the formation, each named once. Entries are
    /// kept in id order.
    pub fn new(owner: UavId, size: usize, refs: Vec<(UavId, f64)>) -> Result<Self, ConfigError> {
        Self::from_slice(owner, size, &refs)
    }

    /// [`Self::new`] from a slice (a caller's scratch buffer): the table is the one
    /// allocation it makes.
    pub fn from_slice(owner: UavId, size: usize, refs: &[(UavId, f64)]) -> Result<Self, ConfigError> {
        for (k, &(id, degree)) in refs.iter().enumerate() {
            if id == owner {
                return Err(ConfigError::BadReference {
                    owner,
                    reference: id,
                    reason: "a UAV cannot depend on itself",
                });
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
        let mut refs: Arc<[(UavId, f64)]> = Arc::from(refs);
        if let Some(r) = Arc::get_mut(&mut refs) {
            r.sort_by_key(|r| r.0);
        }
        Ok(Self { refs })
    }

    /// The dependency degree of `id`, if it is a main reference.
    #[inline]
    pub fn degree(&self, id: UavId) -> Option<f64> {
        self.refs.iter().find(|(r, _)| *r == id).map(|(_, c)| *c)
    }

    /// All main references.
    pub fn refs(&self) -> &[(UavId, f64)] {
        &self.refs
    }

    /// True when the UAV has no main references.
    pub fn is_empty(&self) -> bool {
        self.refs.is_empty()
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
}
