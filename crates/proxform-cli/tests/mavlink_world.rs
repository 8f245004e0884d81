//! The world's UAVs as MAVLink systems (`--mavlink-port`): an outside offboard controller (the
//! companion side of `proxform_net::mavlink`, over loopback UDP) finds UAV 3, reads where it is
//! (the positions of trajectories.csv, to the centimetre), switches it to OFFBOARD and flies it
//! by velocity setpoints 3 m/s east of its own velocity, then stops: the report names the
//! steps it flew, UAV 3 leaves its slot meanwhile, and with the setpoints gone it falls back
//! to HOLD and its agent's decisions. The world and its agents are ended by their ids.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use proxform_net::mavlink::autopilot::Autopilot;
use proxform_net::mavlink::frame::Frame;
use proxform_net::mavlink::link::Link;
use proxform_net::mavlink::modes::Mode;

/// One real-time flight at a time in this file: its checks compare errors with an in-process
/// flight's, and several flights with their agents at once on two cores make each one late
/// (the paper's 0.2 m and 0.4° failed so).
static ONE_FLIGHT: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn one_flight() -> std::sync::MutexGuard<'static, ()> {
    ONE_FLIGHT.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Kills a child by its id when dropped (a failing test leaves nothing running).
struct Reap(Option<std::process::Child>);

impl Drop for Reap {
    fn drop(&mut self) {
        if let Some(c) = &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// A base port whose next six UDP ports are free now.
fn free_ports() -> u16 {
    free_ports_for(6)
}

/// A base port whose next `n` UDP ports are free now.
fn free_ports_for(n: u16) -> u16 {
    for _ in 0..50 {
        let s = std::net::UdpSocket::bind("127.0.0.1:0").expect("a port");
        let base = s.local_addr().expect("bound").port();
        if base > 60_000 {
            continue;
        }
        drop(s);
        if (0..n).all(|i| std::net::UdpSocket::bind(("127.0.0.1", base + i)).is_ok()) {
            return base;
        }
    }
    panic!("no {n} free UDP ports");
}

#[test]
fn an_outside_offboard_controller_flies_a_simulated_uav_and_hands_it_back() {
    let _flight = one_flight();
    let base = free_ports();
    let dir = std::env::temp_dir().join(format!("proxform-mavlink-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    // UAV 3 (system 3) sends to base + 2: listen there before the world starts.
    let link = Link::open(format!("udpin:127.0.0.1:{}", base + 2).parse().expect("endpoint"), 255, 190).expect("bound");
    let mut ap = Autopilot::new(link, Some(3));
    let mut world = Reap(Some(
        Command::new(env!("CARGO_BIN_EXE_proxform"))
            .args(["run", "--distributed", "--clock", "realtime", "--duration-s", "14", "--seed", "5"])
            .args(["--mavlink-port", &base.to_string(), "--no-figures", "-q", "--out"])
            .arg(&dir)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("proxform runs"),
    ));
    let frame = Frame::default();
    let mut seen: Vec<[f64; 3]> = Vec::new();
    let start = Instant::now();
    // Until the flight is seen (the agents start first), at most 60 s.
    while start.elapsed() < Duration::from_secs(60) {
        ap.poll(Duration::from_millis(50)).expect("io");
        if let Some((s, _)) = ap.state(&frame, Instant::now()) {
            seen.push([s[0], s[1], s[2]]);
            if seen.len() > 20 {
                break;
            }
        }
    }
    assert!(seen.len() > 20, "UAV 3 said nothing in 60 s");
    assert_eq!(ap.mode(), Some(Mode::Hold));
    // Three seconds of setpoints 3 m/s east of its own velocity; OFFBOARD asked once they stream.
    let fly = Instant::now();
    let mut asked = false;
    while fly.elapsed() < Duration::from_secs(3) {
        ap.poll(Duration::from_millis(20)).expect("io");
        let Some((ned, _)) = ap.ned(Instant::now()) else { continue };
        let v = ned.velocity;
        assert!(ap.send_velocity([v[0], v[1] + 3.0, v[2]], ned.attitude[2], 0).expect("io"));
        if !asked && fly.elapsed() > Duration::from_millis(300) {
            ap.request(Mode::Offboard).expect("sent");
            asked = true;
        }
    }
    assert_eq!(ap.mode(), Some(Mode::Offboard), "the vehicle took OFFBOARD");
    // Silence: back to HOLD within a second and a half.
    let quiet = Instant::now();
    while ap.mode() != Some(Mode::Hold) && quiet.elapsed() < Duration::from_secs(3) {
        ap.poll(Duration::from_millis(50)).expect("io");
    }
    assert_eq!(ap.mode(), Some(Mode::Hold));
    let out = world.0.take().expect("the world").wait_with_output_bounded(Duration::from_secs(60));
    let stderr = String::from_utf8_lossy(&out);
    assert!(stderr.contains("mavlink: 6 UAV(s) served; flown by outside setpoints: UAV3 "), "{stderr}");
    assert!(stderr.contains("0 frame(s) undecodable, 0 message(s) refused"), "{stderr}");
    // Where UAV 3 said it was is where trajectories.csv has it (to the centimetre).
    let rows = trajectory(&dir.join("trajectories.csv"), 3);
    for p in seen.iter().skip(5) {
        let d = rows.iter().map(|r| ((r[0] - p[0]).powi(2) + (r[1] - p[1]).powi(2) + (r[2] - p[2]).powi(2)).sqrt());
        let nearest = d.fold(f64::INFINITY, f64::min);
        assert!(nearest < 0.01, "UAV 3 said {p:?}, {nearest} m from every row of trajectories.csv");
    }
    // Flown 3 m/s across for seconds, UAV 3 left its slot (its y error is metres).
    let summary = std::fs::read_to_string(dir.join("summary.json")).expect("summary");
    let s: serde_json::Value = serde_json::from_str(&summary).expect("json");
    let k = s["per_uav"].as_array().expect("per UAV").iter().position(|u| u == 3).expect("UAV 3");
    let y = s["per_uav_worst"][k]["y_m"].as_f64().expect("y");
    assert!(y > 2.0, "UAV 3's worst y error {y} m");
    let _ = std::fs::remove_dir_all(dir);
}

/// Positions (x, y, z) of `uav` in a trajectories.csv.
fn trajectory(path: &Path, uav: u32) -> Vec<[f64; 3]> {
    let text = std::fs::read_to_string(path).expect("trajectories.csv");
    text.lines()
        .skip(1)
        .filter_map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f.get(1)?.parse::<u32>().ok()? == uav)
                .then(|| [f[2], f[3], f[4]].map(|v| v.parse::<f64>().expect("a number")))
        })
        .collect()
}

trait Bounded {
    fn wait_with_output_bounded(self, limit: Duration) -> Vec<u8>;
}

impl Bounded for std::process::Child {
    /// Its stderr once it exits, killing it after `limit`.
    fn wait_with_output_bounded(mut self, limit: Duration) -> Vec<u8> {
        let start = Instant::now();
        while start.elapsed() < limit {
            if self.try_wait().expect("wait").is_some() {
                break;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        let _ = self.kill();
        self.wait_with_output().expect("output").stderr
    }
}

/// Flies `scenario` (arguments naming it) for `seconds` with every follower's agent reading its
/// own state from its UAV's MAVLink system and flying it in OFFBOARD (`--agents-mavlink`), and
/// in process: both pass, every follower flew on its setpoints, and the errors over MAVLink on
/// `axes` are near the in-process ones.
/// Flies `scenario` with every follower's agent over MAVLink and in process, and checks every
/// axis's worst error over MAVLink is at most `times` the in-process one's plus `plus`; the two
/// summaries (MAVLink, in process).
fn flies_over_mavlink_as_in_process(
    scenario: &[&str],
    (uavs, seconds): (u16, u32),
    axes: &[&str],
    tag: &str,
    (times, plus): (f64, f64),
) -> (serde_json::Value, serde_json::Value) {
    let _flight = one_flight();
    let base = free_ports_for(uavs);
    let dir = std::env::temp_dir().join(format!("proxform-mavlink-agents-{tag}-{}", std::process::id()));
    let local = std::env::temp_dir().join(format!("proxform-mavlink-local-{tag}-{}", std::process::id()));
    let duration = seconds.to_string();
    let common = ["--duration-s", &duration, "--seed", "2", "--no-figures", "--no-trajectories", "-q", "--out"];
    let o = Command::new(env!("CARGO_BIN_EXE_proxform")).arg("run").args(scenario).args(common).arg(&local).output();
    assert!(o.expect("runs").status.success());
    let world = Command::new(env!("CARGO_BIN_EXE_proxform"))
        .arg("run")
        .args(scenario)
        .args(["--distributed", "--clock", "realtime", "--agents-mavlink", "--mavlink-port", &base.to_string()])
        .args(common)
        .arg(&dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("proxform runs");
    let stderr = String::from_utf8_lossy(&world.wait_with_output_bounded(Duration::from_secs(120))).to_string();
    let flown: Vec<u64> = (2..=u32::from(uavs))
        .map(|u| {
            let tag = format!("UAV{u} ");
            let at = stderr.find(&tag).unwrap_or_else(|| panic!("UAV {u} not flown by setpoints: {stderr}"));
            stderr[at + tag.len()..].split(' ').next().and_then(|n| n.parse().ok()).expect("steps")
        })
        .collect();
    let steps = 10 * u64::from(seconds);
    assert!(flown.iter().all(|&k| k >= steps - 10), "steps flown on setpoints {flown:?} of {steps}: {stderr}");
    let summary = |d: &Path| -> serde_json::Value {
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).expect("summary")).expect("json");
        assert_eq!(s["pass_fraction"].as_f64(), Some(1.0), "{}", d.display());
        s
    };
    let (net, inproc) = (summary(&dir), summary(&local));
    for axis in axes {
        let a = net["worst_abs_error"][axis].as_f64().expect("error");
        let b = inproc["worst_abs_error"][axis].as_f64().expect("error");
        assert!(a <= times * b + plus, "{tag} {axis}: {a} over MAVLink against {b} in-process");
    }
    let _ = (std::fs::remove_dir_all(dir), std::fs::remove_dir_all(local));
    (net, inproc)
}

#[test]
fn proxform_agents_fly_a_multirotor_formation_through_its_mavlink_vehicles() {
    // By velocity and yaw setpoints.
    let scenario = concat!(env!("CARGO_MANIFEST_DIR"), "/../proxform-scenario/scenarios/multirotor-v12-circuit.toml");
    let _ = flies_over_mavlink_as_in_process(&[scenario], (12, 15), &["x_m", "y_m", "z_m"], "multirotor", (1.5, 0.05));
}

#[test]
fn proxform_agents_fly_the_papers_vehicles_through_mavlink_with_attitude_targets() {
    // The paper's kinematic vehicle steers its attitude apart from its velocity: its agents send
    // SET_ATTITUDE_TARGET beside the velocity setpoints. Without them the attitude stayed where
    // it was while the navigator's rolled and pitched: after 30 s every follower failed (y up to
    // 2.1 m, α 1.2°), against 0.15 m and 0.26° in process.
    let axes = ["x_m", "y_m", "z_m", "alpha_deg", "beta_deg", "gamma_deg"];
    let _ = flies_over_mavlink_as_in_process(&["--scenario", "paper"], (6, 30), &axes, "paper", (1.5, 0.05));
}

#[test]
fn without_measurement_noise_the_paper_over_mavlink_is_the_in_process_flight() {
    // Without measurement noise the flight is the in-process one: each agent's targets are its
    // input from the state it decided at (the last adjusted ones again while it holds), and the
    // vehicle flies them from where it is, as the in-process world applies the input. (The
    // world turning targets back into inputs by the controller's least squares, or the agent
    // taking them from a state its commands on their way had left, made γ 1.4× as large.)
    let axes = ["x_m", "y_m", "z_m", "alpha_deg", "beta_deg", "gamma_deg"];
    let quiet = ["--scenario", "paper", "--set", "noise.scale=0"];
    let (net, inproc) = flies_over_mavlink_as_in_process(&quiet, (6, 20), &axes, "paper-quiet", (1.05, 0.005));
    // And the agents held as often: the report's adjustments are theirs (before, every step
    // flown on a setpoint counted as one: 600 a minute against 520).
    let adjustments = |s: &serde_json::Value| s["adjustments_per_uav_minute"].as_f64().expect("adjustments");
    let (a, b) = (adjustments(&net), adjustments(&inproc));
    assert!((a - b).abs() <= 0.05 * b, "{a} adjustments a minute over MAVLink against {b} in process");
}

#[test]
fn agents_over_mavlink_refuse_a_vehicle_that_autopilot_targets_do_not_fly() {
    let o = Command::new(env!("CARGO_BIN_EXE_proxform"))
        .args(["run", "--scenario", "fixed-wing-v", "--distributed", "--clock", "realtime", "--agents-mavlink"])
        .args(["--mavlink-port", "30000"])
        .args(["--no-figures", "-q", "--out"])
        .arg(std::env::temp_dir().join(format!("proxform-mavlink-refused-{}", std::process::id())))
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("fly a multirotor or the kinematic vehicle"), "{stderr}");
}

#[test]
fn agents_need_no_world_sensing_their_autopilot_and_the_radio_suffice() {
    let _flight = one_flight();
    // `--agents-sensing autopilot`: each agent's updates are its autopilot's states on its own
    // clock and its neighbours what the other agents broadcast (every UAV broadcasts), as on a
    // companion computer with no world; the world's sensing goes unused. The formation holds
    // within its allowable errors.
    let dir = std::env::temp_dir().join(format!("proxform-mavlink-noworld-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a folder");
    let file = dir.join("v6.toml");
    std::fs::write(
        &file,
        "duration_s = 15.0\n[vehicle]\nmodel = \"multirotor\"\n[formation.shape]\nkind = \"v\"\nuavs = 6\n\
         spacing_m = 8.0\nangle_deg = 30.0\n[path]\nkind = \"waypoints\"\nspeed_kmh = 18.0\n\
         points_m = [[100.0, 0.0, 0.0], [100.0, 100.0, 0.0]]\nturn_radius_m = 20.0\n[radio]\nbroadcast_all = true\n",
    )
    .expect("written");
    let base = free_ports_for(6);
    let world = Command::new(env!("CARGO_BIN_EXE_proxform"))
        .arg("run")
        .arg(&file)
        .args(["--distributed", "--clock", "realtime", "--agents-mavlink", "--agents-sensing", "autopilot"])
        .args(["--mavlink-port", &base.to_string(), "--no-figures", "--no-trajectories", "-q", "--out"])
        .arg(dir.join("out"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("proxform runs");
    let stderr = String::from_utf8_lossy(&world.wait_with_output_bounded(Duration::from_secs(120))).to_string();
    let agents: Vec<&str> = stderr.lines().filter(|l| l.contains("over MAVLink:")).collect();
    assert_eq!(agents.len(), 5, "{stderr}");
    for l in &agents {
        let sent: u64 = l
            .split("MAVLink: ")
            .nth(1)
            .and_then(|r| r.split(' ').next())
            .and_then(|n| n.parse().ok())
            .expect("setpoints");
        assert!(sent >= 130, "decided about once a period (150): {l}");
        assert!(l.contains("sensing from autopilot") && !l.contains("(0 updates of a world"), "{l}");
    }
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/summary.json")).expect("summary")).expect("json");
    assert_eq!(s["pass_fraction"].as_f64(), Some(1.0), "{stderr}");
    // Without every UAV broadcasting, an agent would hear nobody: refused before anything starts.
    let plain = dir.join("plain.toml");
    let text = std::fs::read_to_string(&file).expect("read").replace("broadcast_all = true", "broadcast_all = false");
    std::fs::write(&plain, text).expect("written");
    let o = Command::new(env!("CARGO_BIN_EXE_proxform"))
        .arg("run")
        .arg(&plain)
        .args(["--distributed", "--clock", "realtime", "--agents-mavlink", "--agents-sensing", "autopilot"])
        .args(["--mavlink-port", &base.to_string(), "--no-figures", "-q", "--out"])
        .arg(dir.join("plain"))
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("radio.broadcast_all = true"), "{err}");
    let _ = std::fs::remove_dir_all(dir);
}
