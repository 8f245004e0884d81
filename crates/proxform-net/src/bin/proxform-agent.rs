//! `proxform-agent`: the controllers of one or more UAVs as a process, over Zenoh.
//!
//! It reads the same scenario as the simulator (a file, or a built-in name), connects to a
//! Zenoh router (a `proxform world`, or any router the swarm shares), announces the UAVs it
//! runs, and answers every update of theirs with a decision, until the world ends the batch
//! or goes silent. It links the method and the scenario model, never the simulator.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use anyhow::{bail, Context, Result};
use clap::Parser;
use proxform_net::access::Party;
use proxform_net::agent::{serve, Ended, Host, Timing};
use proxform_net::keys::Swarm;
use proxform_net::mavlink::autopilot::Autopilot;
use proxform_net::mavlink::frame::Frame;
use proxform_net::mavlink::link::{Endpoint, Link};
use proxform_net::mavlink::vehicle::{MavlinkVehicle, Sensing};
use proxform_net::seal;
use proxform_net::transport::{Role, Session, Tls};
use proxform_net::vehicle::NetVehicle;
use proxform_scenario::{builtin, load, Scenario};

/// Largest scenario file read (bytes), as `proxform run` reads.
const MAX_INPUT_BYTES: u64 = 16 << 20;

/// One or more UAVs' controllers as a process.
#[derive(Debug, Parser)]
#[command(name = "proxform-agent", version)]
struct Args {
    /// Scenario file (TOML), or a built-in scenario's name.
    #[arg(long)]
    scenario: String,
    /// The UAV to run (from 1; not the navigator).
    #[arg(long, conflicts_with = "uavs")]
    uav: Option<u32>,
    /// Several UAVs in this process, comma-separated: 2,3,4.
    #[arg(long, value_delimiter = ',')]
    uavs: Vec<u32>,
    /// The swarm's name (the key prefix proxform/v1/<swarm>/).
    #[arg(long, default_value = "proxform")]
    swarm: String,
    /// The router's endpoint.
    #[arg(long, default_value = "tcp/127.0.0.1:7447")]
    connect: String,
    /// The swarm's credentials folder (`proxform keys`): connect over mutual TLS (a `tls/`
    /// endpoint) as UAV N, with `ca.pem`, `uav-N.pem` and `uav-N.key` from there. One UAV per
    /// process: the world lets each certificate speak for its own UAV only.
    #[arg(long)]
    tls: Option<PathBuf>,
    /// The flight's key (a file of 64 hexadecimal digits, as the world wrote it with
    /// `--flight-key`): every message is sealed with it and only messages it sealed are taken.
    /// Launched by a world, an agent finds its key in the environment (PROXFORM_FLIGHT_KEY).
    #[arg(long)]
    flight_key: Option<PathBuf>,
    /// Exit when nothing arrived for this long (s).
    #[arg(long, default_value_t = 30.0)]
    idle_exit_s: f64,
    /// Wait this long for the router at start (s).
    #[arg(long, default_value_t = 10.0)]
    wait_s: f64,
    /// Fly the UAV (one) through its autopilot over MAVLink: `udpin:HOST:PORT` (listen where
    /// the autopilot sends, as PX4's offboard port 14540), `udpout:HOST:PORT`, or
    /// `serial:DEVICE[:BAUD]` (the flight controller's TELEM port; 57600 baud unless given;
    /// Linux). Its own state
    /// comes from the autopilot; each decision goes to it as a velocity and yaw setpoint in
    /// OFFBOARD (docs/mavlink.md).
    #[arg(long)]
    mavlink: Option<String>,
    /// Where the agent's updates come from with --mavlink: `world` (a world's sensing, own
    /// state included: the world is the UAV's sensors) or `autopilot` (no world needed: its own state from
    /// the autopilot on its own clock, its neighbours from their agents' broadcasts; the
    /// scenario must have every UAV broadcast, radio.broadcast_all).
    #[arg(long, default_value = "world", value_parser = ["world", "autopilot"], requires = "mavlink")]
    sensing: String,
    /// The autopilot's system id [default: the first autopilot heard].
    #[arg(long, requires = "mavlink", value_parser = clap::value_parser!(u8).range(1..))]
    mavlink_system: Option<u8>,
    /// The direction of the formation's x axis (its initial course) in the autopilot's local
    /// NED frame, degrees clockwise from north; the method's origin is NED's.
    #[arg(long, default_value_t = 0.0, requires = "mavlink")]
    course_deg: f64,
    /// Exit when the process that started this one exits (Linux; a launcher's agents never
    /// outlive it, even when it is killed).
    #[arg(long)]
    exit_with_parent: bool,
}

/// Asks the kernel to kill this process when its parent exits.
#[cfg(target_os = "linux")]
fn exit_with_parent() -> Result<()> {
    let parent = nix::unistd::getppid();
    nix::sys::prctl::set_pdeathsig(nix::sys::signal::Signal::SIGKILL).context("cannot follow the parent process")?;
    // The parent may have exited before the request: then this process was re-parented.
    if nix::unistd::getppid() != parent {
        bail!("the parent process has already exited");
    }
    Ok(())
}

#[cfg(not(target_os = "linux"))]
fn exit_with_parent() -> Result<()> {
    Ok(())
}

fn scenario(arg: &str) -> Result<Scenario> {
    if builtin::NAMES.contains(&arg) {
        let spec = builtin::spec_by_name(arg, None).map_err(anyhow::Error::msg)?;
        return Scenario::try_from(spec).context("invalid built-in scenario");
    }
    let path = PathBuf::from(arg);
    let meta = std::fs::metadata(&path).with_context(|| format!("cannot read scenario file {arg}"))?;
    if !meta.is_file() || meta.len() > MAX_INPUT_BYTES {
        bail!("scenario file {arg} is not a regular file of at most {} MiB", MAX_INPUT_BYTES >> 20);
    }
    let text = std::fs::read_to_string(&path).with_context(|| format!("cannot read scenario file {arg} as UTF-8"))?;
    Ok(load::parse(&text, arg)?)
}

fn seconds(name: &str, v: f64) -> Result<Duration> {
    if !(v.is_finite() && v > 0.0 && v <= 86_400.0) {
        bail!("--{name}: {v} s is not a duration from 0 to one day");
    }
    Ok(Duration::from_secs_f64(v))
}

fn run(args: Args) -> Result<Ended> {
    if args.exit_with_parent {
        exit_with_parent()?;
    }
    let uavs: Vec<u32> = match args.uav {
        Some(u) => vec![u],
        None if !args.uavs.is_empty() => args.uavs.clone(),
        None => bail!("name the UAV to run: --uav N or --uavs 2,3,4"),
    };
    let sc = Arc::new(scenario(&args.scenario)?);
    // The MAVLink options are checked before anything is opened.
    let mavlink = match &args.mavlink {
        None => None,
        Some(endpoint) => {
            if uavs.len() != 1 {
                bail!("--mavlink: one UAV per autopilot (--uav N)");
            }
            if !(args.course_deg.is_finite() && args.course_deg.abs() <= 360.0) {
                bail!("--course-deg: not an angle from -360 to 360 degrees");
            }
            if args.sensing == "autopilot" && !sc.radio().broadcast_all {
                bail!(
                    "--sensing autopilot: its neighbours reach the agent only by radio, and this scenario's UAVs \
                     do not all broadcast: set radio.broadcast_all = true"
                );
            }
            if !sc.vehicle().flown_by_autopilot_targets() {
                bail!(
                    "--mavlink: this scenario's fixed wing is not flown by MAVLink targets here (its bank and load factor \
                     are its autopilot's): fly a multirotor or the kinematic vehicle (vehicle.model)"
                );
            }
            Some(endpoint.parse::<Endpoint>()?)
        }
    };
    let mut host = Host::new(sc.clone(), &uavs)?;
    let swarm = Swarm::new(&args.swarm)?;
    let timing = Timing { idle_exit: seconds("idle-exit-s", args.idle_exit_s)?, ..Timing::default() };
    let tls = match (&args.tls, args.connect.starts_with("tls/")) {
        (Some(_), _) if uavs.len() != 1 => {
            bail!("--tls: one UAV per process (--uav N): each certificate speaks for its own UAV only")
        }
        (Some(dir), true) => {
            let tls = Tls::in_folder(dir, Party::Uav(uavs[0]));
            tls.check().context("--tls")?;
            Some(tls)
        }
        (Some(_), false) => bail!("--tls: connect to the world's tls/ endpoint (--connect tls/HOST:PORT)"),
        (None, true) => bail!("--connect {}: a tls/ endpoint needs the swarm's credentials (--tls DIR)", args.connect),
        (None, false) => None,
    };
    let role =
        Role::Client { connect: vec![args.connect.clone()], wait_for_router: seconds("wait-s", args.wait_s)?, tls };
    let key = match &args.flight_key {
        Some(path) => Some(seal::read_key_file(path).with_context(|| format!("--flight-key {}", path.display()))?),
        None => seal::from_env().with_context(|| format!("the environment's {}", seal::ENV))?,
    };
    let session =
        Session::open(&role).with_context(|| format!("cannot reach the router at {}", args.connect))?.sealed(key);
    let vehicle = NetVehicle::new(session, swarm, &host.members())?;
    let Some(endpoint) = mavlink else {
        let mut vehicle = vehicle;
        let ended = serve(&mut host, &mut vehicle, timing)?;
        report(&uavs, &host, vehicle.garbage);
        return Ok(ended);
    };
    // The companion's system id is the UAV's; component 191 (an onboard computer).
    let link = Link::open(endpoint, uavs[0].min(255) as u8, 191)?;
    let autopilot = Autopilot::new(link, args.mavlink_system);
    let frame = Frame { origin_ned: [0.0; 3], course_rad: args.course_deg.to_radians() };
    let sensing = if args.sensing == "autopilot" { Sensing::Autopilot } else { Sensing::World };
    let mut vehicle =
        MavlinkVehicle::new(vehicle, autopilot, frame, (sc.vehicle().clone(), sc.dt_s())).with_sensing(sensing);
    let ended = serve(&mut host, &mut vehicle, timing)?;
    report(&uavs, &host, 0);
    let s = vehicle.autopilot().link().stats;
    let line = format!(
        "proxform-agent {uavs:?} over MAVLink: {} setpoints sent, HOLD asked {} time(s){}; {} frames undecodable, \
         {} messages from other systems; sensing from {} ({} updates of a world's sensing not used)\n",
        vehicle.setpoints,
        vehicle.holds.0,
        vehicle.holds.1.map(|w| format!(" (last: {w})")).unwrap_or_default(),
        s.bad_crc + s.unknown + s.malformed,
        vehicle.autopilot().foreign,
        args.sensing,
        vehicle.ignored
    );
    use std::io::Write;
    let _ = std::io::stderr().write_all(line.as_bytes());
    Ok(ended)
}

/// What the agents refused, skipped and left out, when anything (one write, so that the lines
/// of agents sharing a terminal do not interleave).
fn report(uavs: &[u32], host: &Host, garbage: u64) {
    let c = host.counts();
    if c.dropped + c.refused + c.skipped + c.stale + c.unfollowed + garbage > 0 {
        let line = format!(
            "proxform-agent {uavs:?}: {} observations dropped, {} updates refused, {} undecodable or on another \
             UAV's key; own clock: {} updates skipped for newer ones, {} too old to step on, {} observations of \
             silent neighbours avoided but not followed\n",
            c.dropped, c.refused, garbage, c.skipped, c.stale, c.unfollowed
        );
        use std::io::Write;
        let _ = std::io::stderr().write_all(line.as_bytes());
    }
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(Ended::Done) => ExitCode::SUCCESS,
        Ok(Ended::Idle) => {
            eprintln!("proxform-agent: nothing heard from the world for too long; exiting");
            ExitCode::from(3)
        }
        Err(e) => {
            eprintln!("proxform-agent: {e:#}");
            ExitCode::from(2)
        }
    }
}
