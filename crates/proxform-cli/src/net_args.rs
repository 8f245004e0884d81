//! The command line of a distributed run (`proxform run --distributed`, `proxform world`),
//! present in every build so that a build without the network agent says so.

use std::path::PathBuf;

/// How a distributed run is laid out.
#[derive(Debug, Clone, clap::Args)]
pub struct NetArgs {
    /// Fly with each follower's controller in its own process over Zenoh (lockstep; the same
    /// results as in-process). Needs a build with `--features net` and the `proxform-agent`
    /// binary beside `proxform`.
    #[arg(long)]
    pub distributed: bool,
    /// Do not start agents: wait for agents started elsewhere (`proxform world`). Needs
    /// `--distributed` on `run` (a world is distributed).
    #[arg(long)]
    pub external_agents: bool,
    /// UAVs per agent process.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub agents_per_process: u32,
    /// How the world's clock advances: `lockstep` (when every live agent has answered, or the
    /// step's deadline passed; the in-process results) or `realtime` (every process on its
    /// own wall clock at the scenario's period; observations carry their real age).
    #[arg(long, default_value = "lockstep", value_parser = ["lockstep", "realtime"])]
    pub clock: String,
    /// Longest wait for the agents' decisions in one step (s, lockstep); a missing one holds.
    #[arg(long, default_value_t = 2.0)]
    pub step_deadline_s: f64,
    /// Longest wait for every agent to announce itself (s).
    #[arg(long, default_value_t = 60.0)]
    pub wait_agents_s: f64,
    /// Pause after the agents are ready and before the flight (s), for outside clients.
    #[arg(long, default_value_t = 0.0)]
    pub start_delay_s: f64,
    /// The world's Zenoh endpoint [default: a free loopback port, TCP or with --tls TLS].
    /// Beyond loopback it takes `--tls` (or `--insecure`).
    #[arg(long)]
    pub listen: Option<String>,
    /// The swarm's credentials folder (`proxform keys`): serve over mutual TLS on a `tls/`
    /// endpoint, admit only peers with a certificate of the swarm's authority, and let each
    /// UAV's certificate publish that UAV's state, command and membership only (docs/wire.md,
    /// "Security"). Agents started here connect with their own certificates from it.
    #[arg(long)]
    pub tls: Option<PathBuf>,
    /// The flight's key file (docs/wire.md, "Sealed flights"): every message is sealed with
    /// the key in it, written there (readable by its owner only) if the file is new; give the
    /// same file to the agents started elsewhere (`proxform agent --flight-key FILE`). Agents
    /// started here always get a key of the flight's own; agents started elsewhere without one
    /// speak plain, and then any process that reaches the port can steer a UAV.
    #[arg(long)]
    pub flight_key: Option<PathBuf>,
    /// Listen beyond loopback without TLS: any peer that reaches the port can then join,
    /// publish commands and end the flight.
    #[arg(long, conflicts_with = "tls")]
    pub insecure: bool,
    /// The swarm's name (keys proxform/v1/<swarm>/…) [default: proxform-<process id>].
    #[arg(long)]
    pub swarm: Option<String>,
    /// Serve every UAV as a MAVLink system (system id = UAV number, a PX4 in local NED whose
    /// north is the formation's initial course) sending to 127.0.0.1:PORT + i − 1, as PX4
    /// SITL's instances send to 14540 + i; an outside controller that switches a follower to
    /// OFFBOARD and streams velocity setpoints flies it. Needs `--clock realtime`.
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..))]
    pub mavlink_port: Option<u16>,
    /// The agents started here fly their UAVs through these MAVLink systems (setpoints in
    /// OFFBOARD), one UAV per agent process.
    #[arg(long, requires = "mavlink_port")]
    pub agents_mavlink: bool,
    /// Where those agents take their updates: `world` (this world's sensing, the own state
    /// its measurement, as in process) or `autopilot` (the autopilot's state alone, neighbours by radio
    /// from the other agents: as on companion computers with no world; needs
    /// radio.broadcast_all).
    #[arg(long, default_value = "world", value_parser = ["world", "autopilot"], requires = "agents_mavlink")]
    pub agents_sensing: String,
    /// How many times each agent process started here is started again when it exits during
    /// the flight (crashed, killed); every loss is reported, and its UAVs fly uncontrolled
    /// until their agent is back.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(0..=1000))]
    pub agent_restarts: u32,
    /// The agent binary [default: proxform-agent beside this program].
    #[arg(long)]
    pub agent_bin: Option<PathBuf>,
}
