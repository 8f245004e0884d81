//! `proxform run --distributed` and `proxform world`: the simulated world served over Zenoh,
//! each follower's controller in a `proxform-agent` process (started here, or elsewhere with
//! `--external-agents`). The world runs the same engine as an in-process run, with its
//! followers' decisions asked over the network (lockstep: the world advances when every live
//! agent has answered or the step's deadline passed), so a lockstep flight is the in-process
//! flight, byte for byte.

mod children;
mod mavlink;
mod pending;
mod supervise;
mod world;

use std::cell::RefCell;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use proxform_net::access::{acl_json5, Party};
use proxform_net::keys::Swarm;
use proxform_net::seal::{self, FlightKey};
use proxform_net::transport::{free_loopback_endpoint, Role, Secured, Session, Tls};
use proxform_net::wire::ClockMode;
use proxform_scenario::Scenario;
use proxform_sim::{run_batch_with_agents, BatchResult, RunOptions, Trajectory};

use crate::net_args::NetArgs;
use children::{Children, Recipe};
pub use supervise::Loss;
use supervise::Supervised;
pub use world::NetStats;
use world::{NavigatorTelemetry, NetAgents};

/// Set by Ctrl-C: the flight stops at its next step and everything is shut down.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

fn seconds(name: &str, v: f64) -> Result<Duration> {
    if !(v.is_finite() && (0.0..=86_400.0).contains(&v)) {
        bail!("--{name}: {v} s is not a duration from 0 to one day");
    }
    Ok(Duration::from_secs_f64(v))
}

/// A distributed batch: its result and what the network did.
pub struct Distributed {
    /// The batch, as an in-process one.
    pub result: BatchResult,
    /// The network's numbers.
    pub stats: NetStats,
    /// Agent processes started.
    pub processes: usize,
    /// Per agent process still running at the end: CPU time (s) and peak memory (bytes).
    pub usage: Vec<(f64, u64)>,
    /// Wall-clock time of the batch (s).
    pub wall_s: f64,
    /// Agent processes lost during the flight, and whether they were started again.
    pub losses: Vec<Loss>,
    /// Per follower (from 1) that flew uncontrolled, for how long (s, summed over the batch).
    pub uncontrolled: Vec<(u32, f64)>,
}

/// Every check of a distributed run that needs no network: made before any output is touched,
/// so that a refused start leaves an earlier run's files as they were.
pub fn preflight(scenario: &Scenario, runs: u64, args: &NetArgs) -> Result<()> {
    seconds("step-deadline-s", args.step_deadline_s)?;
    seconds("wait-agents-s", args.wait_agents_s)?;
    seconds("start-delay-s", args.start_delay_s)?;
    if runs > u64::from(u32::MAX) {
        bail!("--runs: at most {} runs in a distributed batch", u32::MAX);
    }
    if scenario.radio().relay_navigator {
        bail!(
            "radio.relay_navigator: the relays come from the agents' tracks, which a distributed run keeps in \
             the agents' processes; relaying is not part of the wire yet: fly it without --distributed"
        );
    }
    if scenario.reassign_on_loss().is_some() {
        bail!(
            "formation.reassign_on_loss: the new slots are handed to the agents in the simulator's process; \
             re-assignment is not part of the wire yet: fly it without --distributed"
        );
    }
    let navigator = scenario.navigator();
    if let Some(k) = scenario
        .faults()
        .iter()
        .position(|f| matches!(f, proxform_scenario::faults::Fault::Remove { uav, .. } if *uav == navigator))
    {
        bail!(
            "fault[{}]: the navigator's successor is named and handed its new table in the simulator's \
             process; succession is not part of the wire yet: fly it without --distributed",
            k + 1
        );
    }
    if let Some(e) = &args.listen {
        listen_allowed(e, args.tls.is_some(), args.insecure)?;
    }
    if let Some(dir) = &args.tls {
        secured(dir, &Swarm::new("preflight")?, scenario, args)?;
    }
    Ok(())
}

/// Runs `runs` seeded flights of `scenario` with its followers' agents over the network.
pub fn run(
    scenario: &Scenario,
    options: RunOptions,
    (seed, runs): (u64, u64),
    record: Option<Trajectory>,
    progress: &(dyn Fn() + Sync),
    args: &NetArgs,
) -> Result<Distributed> {
    preflight(scenario, runs, args)?;
    let deadline = seconds("step-deadline-s", args.step_deadline_s)?;
    let wait = seconds("wait-agents-s", args.wait_agents_s)?;
    let delay = seconds("start-delay-s", args.start_delay_s)?;
    let swarm = Swarm::new(args.swarm.as_deref().unwrap_or(&format!("proxform-{}", std::process::id())))?;
    let secured = match &args.tls {
        Some(dir) => Some(secured(dir, &swarm, scenario, args)?),
        None => None,
    };
    // The flight's key (proxform_net::seal): the agents started here find it in their
    // environment; those started elsewhere read it from --flight-key FILE, or speak plain.
    let key = match (&args.flight_key, args.external_agents) {
        (Some(path), _) => Some(seal::key_file(path).with_context(|| format!("--flight-key {}", path.display()))?),
        (None, false) => Some(FlightKey::generate()?),
        (None, true) => None,
    };
    if key.is_none() && args.tls.is_none() {
        eprintln!(
            "world: the flight is not sealed: any process that reaches its port can steer a UAV or end the flight \
             (give the world and its agents --flight-key FILE, or serve it with --tls)"
        );
    }
    let (session, endpoint) = serve(args.listen.as_deref(), secured, args.insecure)?;
    let session = session.sealed(key.clone());
    let telemetry = NavigatorTelemetry::new(&session, &swarm, scenario)?;
    let mode = if args.clock == "realtime" { ClockMode::RealTime } else { ClockMode::Lockstep };
    let mut net = NetAgents::new(session, swarm, scenario, (mode, deadline, seed))?;
    let mut telemetry = match mode {
        ClockMode::RealTime => telemetry.timed(net.clock(), scenario.dt_s()),
        ClockMode::Lockstep => telemetry,
    };
    let mavlink = match args.mavlink_port {
        Some(_) if mode != ClockMode::RealTime => {
            bail!("--mavlink-port: MAVLink vehicles fly in real time (add --clock realtime)")
        }
        Some(port) => Some(Rc::new(RefCell::new(mavlink::MavlinkSwarm::new(scenario, port)?))),
        None => None,
    };
    let nav = scenario.navigator().0 + 1;
    let followers: Vec<u32> = (1..=scenario.len() as u32).filter(|u| *u != nav).collect();

    // The agents read the scenario as given (its spec), so they build the same agents.
    let spec_text = toml::to_string(scenario.spec()).context("cannot write the scenario for the agents")?;
    // In a private folder of the world's own, removed when the world ends (a name in the shared
    // temporary folder could be planted in advance as a link to overwrite).
    let temp = crate::files::PrivateTemp::new("proxform-world")?;
    let spec_file = temp.write("scenario.toml", &spec_text)?;

    let mut children = Children::default();
    if args.agents_mavlink && (args.external_agents || args.agents_per_process != 1) {
        bail!("--agents-mavlink: one UAV per agent process, started here (not with --external-agents)");
    }
    if args.agents_mavlink && !scenario.vehicle().flown_by_autopilot_targets() {
        bail!(
            "--agents-mavlink: this scenario's fixed wing is not flown by MAVLink targets here (its bank and load factor \
             are its autopilot's): fly a multirotor or the kinematic vehicle (vehicle.model)"
        );
    }
    if args.agents_sensing == "autopilot" && !scenario.radio().broadcast_all {
        bail!(
            "--agents-sensing autopilot: the agents' neighbours reach them only by radio, and this scenario's UAVs \
             do not all broadcast: set radio.broadcast_all = true"
        );
    }
    if !args.external_agents {
        let bin = agent_bin(args)?;
        for group in followers.chunks(args.agents_per_process as usize) {
            let list: Vec<String> = group.iter().map(u32::to_string).collect();
            let mut a: Vec<std::ffi::OsString> = vec![
                "--scenario".into(),
                spec_file.clone().into(),
                "--uavs".into(),
                list.join(",").into(),
                "--swarm".into(),
                net.swarm().name().into(),
                "--connect".into(),
                endpoint.clone().into(),
                "--idle-exit-s".into(),
                // Nothing reaches an agent while the world waits out --start-delay-s.
                format!("{}", (10.0 + delay.as_secs_f64()).min(86_400.0)).into(),
                "--exit-with-parent".into(),
            ];
            if let Some(dir) = &args.tls {
                a.extend(["--tls".into(), dir.clone().into()]);
            }
            if let (true, Some(base)) = (args.agents_mavlink, args.mavlink_port) {
                let uav = group[0];
                // UAV i's system sends to base + i − 1 (checked to fit when the systems opened).
                let port = u32::from(base) + uav - 1;
                a.extend([
                    "--mavlink".into(),
                    format!("udpin:127.0.0.1:{port}").into(),
                    "--mavlink-system".into(),
                    uav.to_string().into(),
                    "--sensing".into(),
                    args.agents_sensing.clone().into(),
                ]);
            }
            let env = key.iter().map(|k| (seal::ENV.into(), k.hex().into())).collect();
            children
                .spawn(Recipe { program: bin.clone(), args: a, env }, format!("agent of UAV(s) {}", list.join(",")))?;
        }
    } else {
        eprintln!(
            "world: serving swarm '{}' on {endpoint}; waiting for agents of UAVs {followers:?}",
            net.swarm().name()
        );
    }
    INTERRUPTED.store(false, Ordering::Relaxed);
    // A second Ctrl-C handler cannot be installed; the first one already sets the flag.
    let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::Relaxed));
    net.wait_for(&followers, wait, &mut || {
        if INTERRUPTED.load(Ordering::Relaxed) {
            bail!("interrupted");
        }
        children.check()
    })?;
    let ready = Instant::now();
    while ready.elapsed() < delay && !INTERRUPTED.load(Ordering::Relaxed) {
        net.keep_alive();
        std::thread::sleep(Duration::from_millis(20));
    }
    let flight = Instant::now();
    let net_clock = net.clock();
    // The supervision sees what the engine sees (a follower an outside MAVLink controller
    // flies is controlled).
    let (restarts, dt) = (args.agent_restarts, scenario.dt_s());
    let (result, (losses, uncontrolled)) = match &mavlink {
        Some(swarm) => {
            let mut with = mavlink::WithMavlink { agents: &mut net, swarm: swarm.clone() };
            let mut supervised = Supervised::new(&mut with, &mut children, restarts, dt);
            let result = run_batch_with_agents(
                scenario,
                options,
                (seed, runs),
                record,
                (progress, &INTERRUPTED),
                (
                    &mut supervised,
                    &mut (&mut telemetry, mavlink::MavlinkTelemetry(swarm.clone(), net_clock.clone(), dt)),
                ),
            );
            (result, supervised.finish())
        }
        None => {
            let mut supervised = Supervised::new(&mut net, &mut children, restarts, dt);
            let result = run_batch_with_agents(
                scenario,
                options,
                (seed, runs),
                record,
                (progress, &INTERRUPTED),
                (&mut supervised, &mut telemetry),
            );
            (result, supervised.finish())
        }
    };
    let wall_s = flight.elapsed().as_secs_f64();
    let usage = children.usage();
    // Whatever happened: tell the agents, give them a moment, end the rest by id.
    let _ = net.end(runs);
    let processes = children.pids().len();
    children.finish(Duration::from_secs(2));
    let mut stats = net.stats.clone();
    stats.dropped = net.dropped;
    stats.inbox_dropped = net.inbox_dropped();
    stats.mavlink = mavlink.map(|m| m.borrow().stats());
    net.into_session().close();
    match result {
        Some(result) => Ok(Distributed { result, stats, processes, usage, wall_s, losses, uncontrolled }),
        None => bail!("interrupted"),
    }
}

/// The world's router on `listen`, or on a free loopback port: a port found free may be taken
/// before the router binds it (by another program's connection), so a few are tried.
/// The world's identity in `dir` and the swarm's access rules; every file checked here, and
/// each agent started here one UAV per process (a certificate speaks for one UAV).
fn secured(dir: &std::path::Path, swarm: &Swarm, scenario: &Scenario, args: &NetArgs) -> Result<Secured> {
    if !args.external_agents && args.agents_per_process != 1 {
        bail!("--tls: one UAV per agent process (--agents-per-process 1): each certificate speaks for one UAV");
    }
    let tls = Tls::in_folder(dir, Party::World);
    let nav = scenario.navigator().0 + 1;
    let mut needed = vec![tls.ca.clone(), tls.cert.clone(), tls.key.clone()];
    if !args.external_agents {
        for u in (1..=scenario.len() as u32).filter(|u| *u != nav) {
            let t = Tls::in_folder(dir, Party::Uav(u));
            needed.extend([t.cert, t.key]);
        }
    }
    if let Some(missing) = needed.iter().find(|f| !f.is_file()) {
        bail!(
            "--tls {}: {} is missing: make the swarm's credentials with `proxform keys --uavs {} --out {}`",
            dir.display(),
            missing.display(),
            scenario.len(),
            dir.display()
        );
    }
    tls.check()?;
    if !args.external_agents {
        for u in (1..=scenario.len() as u32).filter(|u| *u != nav) {
            Tls::in_folder(dir, Party::Uav(u)).check()?;
        }
    }
    Ok(Secured { tls, acl_json5: acl_json5(swarm, scenario.len() as u32, nav) })
}

/// Whether an endpoint's address is this machine's loopback (`127.x`, `[::1]`, `localhost`).
fn is_loopback(endpoint: &str) -> bool {
    let addr = endpoint.split_once('/').map_or(endpoint, |(_, a)| a);
    let addr = addr.split('#').next().unwrap_or(addr);
    let host = match addr.rsplit_once(':') {
        Some((h, _)) => h,
        None => addr,
    };
    let host = host.trim_start_matches('[').trim_end_matches(']');
    host == "localhost" || host.parse::<std::net::IpAddr>().is_ok_and(|ip| ip.is_loopback())
}

/// Whether the world may listen on `e`: a port it can tell the agents, TLS on a `tls/`
/// endpoint only, and beyond loopback only with TLS (or `--insecure`).
fn listen_allowed(e: &str, tls: bool, insecure: bool) -> Result<()> {
    // The agents are told this endpoint: a port the system would choose cannot be told.
    let port = e.split('#').next().unwrap_or(e).rsplit_once(':').map(|(_, p)| p);
    match port.map(str::parse::<u16>) {
        Some(Ok(0)) => bail!("--listen {e}: port 0 cannot be told to the agents: name a port, or leave --listen out"),
        Some(Ok(_)) => {}
        _ => bail!("--listen {e}: expected PROTOCOL/HOST:PORT with a port from 1 to 65535 (tcp/127.0.0.1:7447)"),
    }
    match (tls, e.starts_with("tls/")) {
        (true, false) => bail!("--listen {e}: with --tls the world listens on a tls/ endpoint (tls/HOST:PORT)"),
        (false, true) => bail!("--listen {e}: a tls/ endpoint needs the swarm's credentials (--tls DIR)"),
        (false, false) if !is_loopback(e) && !insecure => bail!(
            "--listen {e}: beyond loopback any peer that reaches the port could fly the swarm; serve it with \
             --tls DIR (`proxform keys`), or say --insecure"
        ),
        _ => Ok(()),
    }
}

fn serve(listen: Option<&str>, secured: Option<Secured>, insecure: bool) -> Result<(Session, String)> {
    if let Some(e) = listen {
        listen_allowed(e, secured.is_some(), insecure)?;
        let session = Session::open(&Role::Router { listen: vec![e.to_string()], secured })
            .with_context(|| format!("cannot serve the world on {e}"))?;
        return Ok((session, e.to_string()));
    }
    let mut last = None;
    for _ in 0..10 {
        let e = match secured {
            Some(_) => free_loopback_endpoint()?.replacen("tcp/", "tls/", 1),
            None => free_loopback_endpoint()?,
        };
        match Session::open(&Role::Router { listen: vec![e.clone()], secured: secured.clone() }) {
            Ok(session) => return Ok((session, e)),
            Err(err) => last = Some(err),
        }
    }
    match last {
        Some(e) => Err(anyhow::Error::new(e).context("cannot serve the world on a free loopback port")),
        None => bail!("cannot serve the world on a free loopback port"),
    }
}

/// The agent binary: the one named, or `proxform-agent` beside this program.
fn agent_bin(args: &NetArgs) -> Result<PathBuf> {
    let bin = match &args.agent_bin {
        Some(p) => p.clone(),
        None => std::env::current_exe()
            .context("cannot locate this program")?
            .with_file_name(format!("proxform-agent{}", std::env::consts::EXE_SUFFIX)),
    };
    if !bin.is_file() {
        bail!(
            "{} not found: build it with `cargo build --release -p proxform-net` (or name it with --agent-bin)",
            bin.display()
        );
    }
    Ok(bin)
}
