//! The flight modes the link asks for and reports, as each autopilot encodes them in
//! HEARTBEAT's `custom_mode` and in MAV_CMD_DO_SET_MODE's parameters: PX4's main and sub mode
//! (OFFBOARD is main mode 6, HOLD is AUTO.LOITER, main 4 sub 3), ArduPilot's Copter mode
//! numbers (GUIDED 4, LOITER 5).

use mavlink::dialects::common::MavAutopilot;

/// Which autopilot's mode numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flavour {
    /// PX4.
    Px4,
    /// ArduPilot (Copter's mode numbers).
    ArduPilot,
}

/// A mode the companion asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// The autopilot follows the companion's setpoints (PX4 OFFBOARD, ArduPilot GUIDED).
    Offboard,
    /// The autopilot holds its position by itself (PX4 HOLD, ArduPilot LOITER).
    Hold,
}

impl Flavour {
    /// The flavour of a HEARTBEAT's autopilot field (None: neither).
    pub fn of(autopilot: MavAutopilot) -> Option<Self> {
        match autopilot {
            MavAutopilot::MAV_AUTOPILOT_PX4 => Some(Self::Px4),
            MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA => Some(Self::ArduPilot),
            _ => None,
        }
    }

    /// The HEARTBEAT autopilot field.
    pub fn autopilot(self) -> MavAutopilot {
        match self {
            Self::Px4 => MavAutopilot::MAV_AUTOPILOT_PX4,
            Self::ArduPilot => MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
        }
    }

    /// MAV_CMD_DO_SET_MODE's param2 and param3 for `mode`.
    pub fn set_mode_params(self, mode: Mode) -> (f32, f32) {
        match (self, mode) {
            (Self::Px4, Mode::Offboard) => (6.0, 0.0),
            (Self::Px4, Mode::Hold) => (4.0, 3.0),
            (Self::ArduPilot, Mode::Offboard) => (4.0, 0.0),
            (Self::ArduPilot, Mode::Hold) => (5.0, 0.0),
        }
    }

    /// The mode of DO_SET_MODE parameters (None: another mode).
    pub fn mode_of_params(self, param2: f32, param3: f32) -> Option<Mode> {
        [Mode::Offboard, Mode::Hold].into_iter().find(|&m| {
            let (p2, p3) = self.set_mode_params(m);
            p2 == param2 && (self == Self::ArduPilot || p3 == param3)
        })
    }

    /// HEARTBEAT's custom_mode for `mode`.
    pub fn custom_mode(self, mode: Mode) -> u32 {
        let (main, sub) = self.set_mode_params(mode);
        match self {
            Self::Px4 => ((main as u32) << 16) | ((sub as u32) << 24),
            Self::ArduPilot => main as u32,
        }
    }

    /// The mode a HEARTBEAT's custom_mode reports (None: another mode).
    pub fn mode_of(self, custom_mode: u32) -> Option<Mode> {
        [Mode::Offboard, Mode::Hold].into_iter().find(|&m| self.custom_mode(m) == custom_mode)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modes_round_trip_as_each_autopilot_writes_them() {
        assert_eq!(Flavour::Px4.custom_mode(Mode::Offboard), 6 << 16);
        assert_eq!(Flavour::Px4.custom_mode(Mode::Hold), (4 << 16) | (3 << 24));
        assert_eq!(Flavour::ArduPilot.custom_mode(Mode::Offboard), 4);
        for f in [Flavour::Px4, Flavour::ArduPilot] {
            assert_eq!(Flavour::of(f.autopilot()), Some(f));
            for m in [Mode::Offboard, Mode::Hold] {
                assert_eq!(f.mode_of(f.custom_mode(m)), Some(m));
                let (p2, p3) = f.set_mode_params(m);
                assert_eq!(f.mode_of_params(p2, p3), Some(m));
            }
            assert_eq!(f.mode_of(12345), None);
        }
    }
}
