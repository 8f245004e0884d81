//! MAVLink 2 (the common dialect) between a proxform agent and an autopilot (PX4, ArduPilot),
//! and between a simulated world and whatever flies its UAVs: the frames (local NED and
//! geodetic against the method's), the link (UDP or a serial line, every frame checked), the modes as each
//! autopilot numbers them, the vehicle's side ([`served::Served`]) and the companion's
//! ([`autopilot::Autopilot`], with its safety policy). `docs/mavlink.md` says how they are used.

pub mod autopilot;
pub mod frame;
pub mod link;
pub mod modes;
pub mod serial;
pub mod served;
pub mod vehicle;

/// The messages of the common dialect, as the `mavlink` crate generates them.
pub use ::mavlink::dialects::common as messages;
/// Who sent a message (system, component, sequence).
pub use ::mavlink::MavHeader;
