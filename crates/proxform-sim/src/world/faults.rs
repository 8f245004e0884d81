//! The faults in force at one step: sensor glitches and stuck sensors applied to a UAV's own
//! estimate, and whether the radio is up. The schedule itself is the scenario's
//! ([`proxform_scenario::faults`]).

use nalgebra::Vector3;
use proxform_core::state::State9;
use proxform_scenario::faults::{radio_up, Fault};

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
    use proxform_core::UavId;

    #[test]
    fn a_stuck_sensor_freezes_at_its_value_at_the_start() {
        let faults = vec![
            Fault::StuckSensor { uav: UavId(3), at_s: 1.0, duration_s: 1.0 },
            Fault::Glitch { uav: UavId(2), at_s: 0.0, duration_s: 1.0, offset_m: Vector3::new(20.0, 0.0, -1.0) },
            Fault::RadioBlackout { at_s: 1.5, duration_s: 1.0 },
        ];
        let s0 = gather(&faults, 0.5, &FaultStep::default(), |_| State9::from_element(0.0));
        assert!(s0.stuck.is_empty() && s0.radio_up);
        let mut g = State9::zeros();
        s0.corrupt(2, &mut g);
        assert_eq!((g[0], g[1], g[2]), (20.0, 0.0, -1.0), "the glitch offsets the own position");
        let s1 = gather(&faults, 1.0, &s0, |_| State9::from_element(1.0));
        let s2 = gather(&faults, 1.5, &s1, |_| State9::from_element(2.0));
        assert!(!s2.radio_up);
        let mut own = State9::from_element(2.0);
        s2.corrupt(3, &mut own);
        assert_eq!(own, State9::from_element(1.0), "frozen at its value at the start");
        let s3 = gather(&faults, 2.0, &s2, |_| State9::from_element(3.0));
        let mut after = State9::from_element(3.0);
        s3.corrupt(3, &mut after);
        assert_eq!(after, State9::from_element(3.0));
    }
}
