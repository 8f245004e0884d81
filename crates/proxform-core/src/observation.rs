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
    /// With relative sensing, a UAV placed by the observer's own sensors from a relay: the
    /// position a neighbour reported of it relative to itself ([`NavigatorReport`]), added to
    /// the observer's onboard observation of that neighbour (its velocity and attitude are the
    /// neighbour's track of it). In the observer's own frame, as
    /// an onboard observation is, though not limited by the sensing range.
    Relayed,
}

/// What a UAV knows of the navigator, to forward to the others (`radio.relay_navigator`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavigatorReport {
    /// Its state: the reporter's track of it, at the track's last measurement. With
    /// `relative`, its position is relative to the reporter's own position fix at the moment
    /// of the report, not of the measurement (each UAV's fix has its own error: a relative
    /// position is free of it, and the receiver adds its own view of the reporter then; taken
    /// at the measurement, both would be moved back along straight lines over the whole age).
    pub state: State9,
    /// How old that state is at the time of the report (s).
    pub age_s: f64,
    /// Whether the position is relative to the reporter.
    pub relative: bool,
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
