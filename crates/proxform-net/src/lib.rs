//! proxform-net: one UAV's controller as a process, talking over real middleware (Zenoh).
//!
//! - [`wire`]: the messages and their bytes, apart from any transport (schema version 1,
//!   `docs/wire.md`).
//! - [`keys`]: the key expressions under which they travel (`proxform/v1/<swarm>/…`).
//! - [`transport`]: a Zenoh session on the given endpoints (multicast scouting off), with the
//!   publishers and subscribers of an agent or a world; mutual TLS where secured.
//! - [`seal`]: a flight's key, with which every message of a sealed flight is tagged (a
//!   process without it cannot speak in the flight).
//! - [`access`]: the parties of a swarm and the access rules the world's router enforces;
//!   [`credentials`]: the swarm's authority and its parties' certificates.
//! - [`vehicle`]: what an agent sees of its UAV (its own state and observations in, a command
//!   out): the network world implements it here, an autopilot over MAVLink in
//!   [`mavlink::vehicle`].
//! - [`radio`]: the formation's radio as an agent on its own clock hears it (other agents'
//!   broadcasts over the network, by the scenario's rules).
//! - [`watch`]: which neighbours fly under their agents (a silent one is avoided, not followed).
//! - [`link`]: how long an agent on its own clock expects its command to take back to the world.
//! - [`agent`]: the loop that steps the core's [`proxform_core::Agent`] over a vehicle.
//! - [`mavlink`]: MAVLink 2 to an autopilot (or a simulated vehicle): frames, the UDP link,
//!   modes, the vehicle's side and the companion's side with its safety policy.
//!
//! This crate reads the same checked [`proxform_scenario::Scenario`] as the simulator but never
//! links the simulator: an agent knows only its own measured state and what reaches it.

pub mod access;
pub mod agent;
pub mod credentials;
pub mod keys;
pub mod link;
pub mod mavlink;
pub mod radio;
pub mod seal;
pub mod transport;
pub mod vehicle;
pub mod watch;
pub mod wire;
