//! Scheduled faults: UAVs removed or joining, sensor glitches, stuck sensors, radio blackouts.
//! This module holds the schedule; the simulator applies it step by step.
//!
//! A removed UAV vanishes: nobody perceives it, it is not stepped, and metrics ignore it. When
//! the navigator is removed, a successor leads once the loss is known (METHOD §8, "Navigator
//! succession"), and formation errors are measured against the formation's own estimate of
//! the navigator's slot (fitted to the followers' states and their offsets). A joining UAV appears in its slot relative to the
//! navigator, shifted by `offset_m`, with the navigator's velocity and attitude.

use nalgebra::Vector3;
use proxform_core::UavId;

/// One scheduled fault. Times in s, offsets in m (world frame).
#[derive(Debug, Clone, PartialEq)]
pub enum Fault {
    /// The UAV vanishes at `at_s`.
    Remove {
        /// Which.
        uav: UavId,
        /// When (s).
        at_s: f64,
    },
    /// The UAV is absent until `at_s`, then appears.
    Join {
        /// Which.
        uav: UavId,
        /// When (s).
        at_s: f64,
        /// Offset from its slot when it appears (m, world frame).
        offset_m: Vector3<f64>,
    },
    /// The UAV's own position estimate is off by `offset_m` during the window.
    Glitch {
        /// Which.
        uav: UavId,
        /// Start (s).
        at_s: f64,
        /// Length (s).
        duration_s: f64,
        /// Offset (m).
        offset_m: Vector3<f64>,
    },
    /// The UAV's own state estimate is frozen at its value at `at_s` during the window.
    StuckSensor {
        /// Which.
        uav: UavId,
        /// Start (s).
        at_s: f64,
        /// Length (s).
        duration_s: f64,
    },
    /// No radio message gets through during the window.
    RadioBlackout {
        /// Start (s).
        at_s: f64,
        /// Length (s).
        duration_s: f64,
    },
}

impl Fault {
    /// The UAV concerned, if any.
    pub fn uav(&self) -> Option<UavId> {
        match self {
            Fault::Remove { uav, .. }
            | Fault::Join { uav, .. }
            | Fault::Glitch { uav, .. }
            | Fault::StuckSensor { uav, .. } => Some(*uav),
            Fault::RadioBlackout { .. } => None,
        }
    }

    /// True when a windowed fault is in force at `t`.
    pub fn in_window(at_s: f64, duration_s: f64, t: f64) -> bool {
        t >= at_s - 1e-9 && t < at_s + duration_s - 1e-9
    }
}

/// Whether fault `f` lets its UAV fly at time `t` (a removal until it happens, a join once it
/// has; other faults do not ground anybody).
pub fn allows(f: &Fault, t: f64) -> bool {
    match *f {
        Fault::Remove { at_s, .. } => t < at_s - 1e-9,
        Fault::Join { at_s, .. } => t >= at_s - 1e-9,
        _ => true,
    }
}

/// Whether UAV `i` flies at time `t`.
pub fn is_active(faults: &[Fault], i: usize, t: f64) -> bool {
    faults.iter().filter(|f| f.uav().is_some_and(|u| u.index() == i)).all(|f| allows(f, t))
}

/// True when the radio is up at `t`.
pub fn radio_up(faults: &[Fault], t: f64) -> bool {
    !faults
        .iter()
        .any(|f| matches!(*f, Fault::RadioBlackout { at_s, duration_s } if Fault::in_window(at_s, duration_s, t)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedules_apply_in_their_windows() {
        let faults = vec![
            Fault::Remove { uav: UavId(1), at_s: 40.0 },
            Fault::Join { uav: UavId(2), at_s: 10.0, offset_m: Vector3::zeros() },
            Fault::RadioBlackout { at_s: 5.0, duration_s: 2.0 },
        ];
        assert!(is_active(&faults, 1, 39.9) && !is_active(&faults, 1, 40.0));
        assert!(!is_active(&faults, 2, 9.9) && is_active(&faults, 2, 10.0));
        assert!(is_active(&faults, 0, 50.0));
        assert!(radio_up(&faults, 4.9) && !radio_up(&faults, 5.0) && !radio_up(&faults, 6.9) && radio_up(&faults, 7.0));
    }
}
