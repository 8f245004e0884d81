//! Scheduled faults: UAVs removed or joining, sensor glitches, stuck sensors, radio blackouts.
//!
//! A removed UAV vanishes: nobody perceives it, it is not stepped, and metrics ignore it. When
//! the navigator is removed, the followers keep flying on their remaining references (those
//! that leaned only on it fall back to their azimuth-area means), and formation errors are
//! measured against the formation's own estimate of the navigator's slot (the mean of the
//! followers' states minus their offsets). A joining UAV appears in its slot relative to the
//! navigator, shifted by `offset_m`, with the navigator's velocity and attitude.

use nalgebra::Vector3;
use proxform_core::state::State9;
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
    fn in_window(at_s: f64, duration_s: f64, t: f64) -> bool {
        t >= at_s - 1e-9 && t < at_s + duration_s - 1e-9
    }
}

/// Whether UAV `i` flies at time `t`.
pub fn is_active(faults: &[Fault], i: usize, t: f64) -> bool {
    faults.iter().all(|f| match *f {
        Fault::Remove { uav, at_s } => uav.index() != i || t < at_s - 1e-9,
        Fault::Join { uav, at_s, .. } => uav.index() != i || t >= at_s - 1e-9,
        _ => true,
    })
}

/// True when the radio is up at `t`.
pub fn radio_up(faults: &[Fault], t: f64) -> bool {
    !faults
        .iter()
        .any(|f| matches!(*f, Fault::RadioBlackout { at_s, duration_s } if Fault::in_window(at_s, duration_s, t)))
}

/// The faults in force during one step, gathered once so that per-UAV checks are cheap.
#[derive(Debug, Clone, Default)]
pub struct FaultStep {
    /// False during a radio blackout.
    pub radio_up: bool,
    /// Own-position offsets of glitching UAVs.
    pub glitches: Vec<(usize, Vector3<f64>)>,
    /// Frozen own-state estimates of UAVs with a stuck sensor.
    pub stuck: Vec<(usize, State9)>,
}

impl FaultStep {
    /// Applies the sensor faults of UAV `i` to its own-state estimate.
    #[inline]
    pub fn corrupt(&self, i: usize, own: &mut State9) {
        for (u, offset) in &self.glitches {
            if *u == i {
                own[0] += offset.x;
                own[1] += offset.y;
                own[2] += offset.z;
            }
        }
        for (u, frozen) in &self.stuck {
            if *u == i {
                *own = *frozen;
            }
        }
    }
}

/// Gathers the faults in force at `t`. `estimate(i)` gives UAV i's own-state estimate at this
/// step (used to freeze a sensor when it sticks); `previous` is the last step's gathering.
pub fn gather(faults: &[Fault], t: f64, previous: &FaultStep, estimate: impl Fn(usize) -> State9) -> FaultStep {
    let mut step = FaultStep { radio_up: radio_up(faults, t), ..FaultStep::default() };
    for f in faults {
        match *f {
            Fault::Glitch { uav, at_s, duration_s, offset_m } if Fault::in_window(at_s, duration_s, t) => {
                step.glitches.push((uav.index(), offset_m));
            }
            Fault::StuckSensor { uav, at_s, duration_s } if Fault::in_window(at_s, duration_s, t) => {
                let i = uav.index();
                let frozen = previous.stuck.iter().find(|(u, _)| *u == i).map_or_else(|| estimate(i), |(_, v)| *v);
                step.stuck.push((i, frozen));
            }
            _ => {}
        }
    }
    step
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
            Fault::StuckSensor { uav: UavId(3), at_s: 1.0, duration_s: 1.0 },
        ];
        assert!(is_active(&faults, 1, 39.9) && !is_active(&faults, 1, 40.0));
        assert!(!is_active(&faults, 2, 9.9) && is_active(&faults, 2, 10.0));
        assert!(radio_up(&faults, 4.9) && !radio_up(&faults, 5.0) && !radio_up(&faults, 6.9) && radio_up(&faults, 7.0));
        let s0 = gather(&faults, 0.5, &FaultStep::default(), |_| State9::from_element(0.0));
        assert!(s0.stuck.is_empty());
        let s1 = gather(&faults, 1.0, &s0, |_| State9::from_element(1.0));
        let s2 = gather(&faults, 1.5, &s1, |_| State9::from_element(2.0));
        let mut own = State9::from_element(2.0);
        s2.corrupt(3, &mut own);
        assert_eq!(own, State9::from_element(1.0), "frozen at its value at the start");
        let s3 = gather(&faults, 2.0, &s2, |_| State9::from_element(3.0));
        let mut after = State9::from_element(3.0);
        s3.corrupt(3, &mut after);
        assert_eq!(after, State9::from_element(3.0));
    }
}
