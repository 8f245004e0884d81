//! What one UAV knows of another at a given moment: an observed state, its age and its source.
//!
//! The controller consumes observations only; it never sees the world. The simulator builds
//! them from its snapshot, a network transport would build them from received messages.

use crate::state::State9;

/// Identifier of a UAV; also its index in the [`crate::Formation`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize)]
pub struct UavId(pub u32);

impl UavId {
    /// The id as an index.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

impl std::fmt::Display for UavId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // UAVs are numbered from 1 in reports, as in the paper.
        write!(f, "UAV{}", self.0 + 1)
    }
}

/// Where an observation came from (METHOD §2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObservationSource {
    /// The observer's own sensors: subject to its sensing range.
    Onboard,
    /// A message heard over the radio: not limited by the sensing range.
    Radio,
    /// A close-range detection by the observer's own sensors (every UAV within the collision
    /// avoidance's watch radius, beyond the nearest of each azimuth area): for collision
    /// avoidance only; the formation controller neither sorts it into areas nor tracks it.
    Close,
}

/// One observed state of a neighbour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// Who was observed.
    pub id: UavId,
    /// The observed state (SI, radians), measured `age_s` seconds ago.
    pub state: State9,
    /// Age of the measurement when the controller runs (s, ≥ 0).
    pub age_s: f64,
    /// Sensor or radio.
    pub source: ObservationSource,
}
