//! A companion computer and a vehicle talking MAVLink over loopback UDP, each on its own
//! thread: the companion finds the vehicle, reads its state in the method's frame, switches it
//! to OFFBOARD (only once setpoints stream) and flies it by velocity; when the vehicle goes
//! silent the safety policy holds within its timeout; setpoints for another system and
//! non-finite ones are refused by the vehicle and counted. Every loop is bounded in time.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use proxform_core::state;
use proxform_net::mavlink::autopilot::{Autopilot, Safety, Verdict};
use proxform_net::mavlink::frame::{Frame, GeoOrigin, Ned};
use proxform_net::mavlink::link::{Endpoint, Link};
use proxform_net::mavlink::modes::{Flavour, Mode};
use proxform_net::mavlink::served::{Refused, Served};

/// A vehicle that flies its setpoint's velocity at 50 Hz (HOLD: stops), on its own thread,
/// until `stop`; returns what it refused and where it ended.
fn vehicle(
    flavour: Flavour,
    link: Link,
    stop: Arc<AtomicBool>,
    silent: Arc<AtomicBool>,
) -> std::thread::JoinHandle<(Refused, Ned)> {
    std::thread::spawn(move || {
        let mut link = link;
        let mut served = Served::new(7, flavour, mavlink::dialects::common::MavType::MAV_TYPE_QUADROTOR);
        let origin = GeoOrigin::from_degrees(47.397742, 8.545594, 488.0);
        let mut ned = Ned { position: [10.0, 20.0, -30.0], velocity: [0.0; 3], attitude: [0.0, 0.0, 0.3] };
        let start = Instant::now();
        let mut last = start;
        let mut beat = start - Duration::from_secs(1);
        while !stop.load(Ordering::Relaxed) && start.elapsed() < Duration::from_secs(20) {
            let now = Instant::now();
            let t = now.duration_since(start).as_secs_f64();
            while let Ok(Some((h, m))) = link.recv(Duration::ZERO) {
                if let Some(reply) = served.handle(&h, &m, t) {
                    let _ = link.send(&reply);
                }
            }
            let dt = now.duration_since(last).as_secs_f64();
            last = now;
            let v = served.setpoint(t).map_or([0.0; 3], |s| s.velocity_ned);
            for k in 0..3 {
                ned.position[k] += v[k] * dt;
            }
            ned.velocity = v;
            if !silent.load(Ordering::Relaxed) {
                if now.duration_since(beat) >= Duration::from_millis(500) {
                    let _ = link.send(&served.heartbeat());
                    for m in served.origin(&origin) {
                        let _ = link.send(&m);
                    }
                    beat = now;
                }
                for m in served.telemetry(t, &ned, &origin) {
                    let _ = link.send(&m);
                }
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        (served.refused, ned)
    })
}

#[test]
fn a_companion_flies_a_vehicle_by_velocity_and_holds_when_it_goes_silent() {
    flies_by_velocity_and_holds(Flavour::Px4);
}

#[test]
fn a_companion_flies_an_ardupilot_vehicle_in_guided_and_holds_in_loiter() {
    // ArduPilot's mode numbers (Copter: GUIDED 4, LOITER 5), told by its HEARTBEAT.
    flies_by_velocity_and_holds(Flavour::ArduPilot);
}

fn flies_by_velocity_and_holds(flavour: Flavour) {
    let mut vehicle_link = Link::open(Endpoint::In(([127, 0, 0, 1], 0).into()), 7, 1).expect("bound");
    let port = vehicle_link.local_addr().expect("address").port();
    let companion = Link::open(format!("udpout:127.0.0.1:{port}").parse().expect("endpoint"), 7, 191).expect("bound");
    let mut ap = Autopilot::new(companion, None);
    // The vehicle answers whoever spoke to it: the companion speaks first.
    ap.heartbeat().expect("sent");
    let first = vehicle_link.recv(Duration::from_secs(2)).expect("io");
    assert!(first.is_some(), "the vehicle heard the companion");
    let (stop, silent) = (Arc::new(AtomicBool::new(false)), Arc::new(AtomicBool::new(false)));
    let handle = vehicle(flavour, vehicle_link, stop.clone(), silent.clone());
    let frame = Frame { origin_ned: [0.0; 3], course_rad: 0.0 };

    // Found, with its state and origin.
    let deadline = Instant::now() + Duration::from_secs(5);
    while (ap.state(&frame, Instant::now()).is_none() || ap.origin().is_none()) && Instant::now() < deadline {
        ap.poll(Duration::from_millis(50)).expect("io");
    }
    assert_eq!(ap.target(), Some(7));
    assert_eq!(ap.flavour(), Some(flavour), "told by the vehicle's HEARTBEAT");
    let (s, age) = ap.state(&frame, Instant::now()).expect("a state");
    assert!(age < Duration::from_millis(500));
    // North 10, east 20, down −30: x 10, y −20 (left of north is west), z 30.
    assert!(
        (s[state::X] - 10.0).abs() < 1e-4 && (s[state::Y] + 20.0).abs() < 1e-4 && (s[state::Z] - 30.0).abs() < 1e-4
    );
    assert!((s[state::BETA] + 0.3).abs() < 1e-6, "yaw 0.3 clockwise is β −0.3");
    assert_eq!(ap.mode(), Some(Mode::Hold));
    assert!(ap.armed());

    // OFFBOARD is refused before setpoints stream, then accepted; the vehicle flies north.
    ap.request(Mode::Offboard).expect("sent");
    let deadline = Instant::now() + Duration::from_secs(3);
    while ap.last_ack.is_none() && Instant::now() < deadline {
        ap.poll(Duration::from_millis(20)).expect("io");
    }
    assert_eq!(ap.last_ack.map(|a| a.1), Some(false), "denied without a setpoint stream");
    let start = Instant::now();
    let mut asked = false;
    while start.elapsed() < Duration::from_secs(3) {
        ap.send_velocity([5.0, 0.0, 0.0], 0.0, 0).expect("sent");
        if !asked && start.elapsed() > Duration::from_millis(200) {
            ap.request(Mode::Offboard).expect("sent");
            asked = true;
        }
        ap.poll(Duration::from_millis(20)).expect("io");
        if ap.mode() == Some(Mode::Offboard) && start.elapsed() > Duration::from_millis(1500) {
            break;
        }
    }
    assert_eq!(ap.mode(), Some(Mode::Offboard));
    let (s2, _) = ap.state(&frame, Instant::now()).expect("a state");
    assert!(s2[state::X] > 13.0, "flew north: x {}", s2[state::X]);
    assert!((s2[state::Y] + 20.0).abs() < 0.5);
    // Non-finite setpoints are not sent at all.
    assert!(!ap.send_velocity([f64::NAN, 0.0, 0.0], 0.0, 0).expect("io"));

    // The vehicle goes silent: within the safety policy's timeout the verdict is HOLD.
    let safety = Safety::default();
    silent.store(true, Ordering::Relaxed);
    let cut = Instant::now();
    let held = loop {
        ap.poll(Duration::from_millis(20)).expect("io");
        let age = ap.state(&frame, Instant::now()).map(|(_, a)| a.as_secs_f64());
        if let Verdict::Hold(why) = safety.verdict(age, Some(0.0)) {
            break Some((cut.elapsed(), why));
        }
        if cut.elapsed() > Duration::from_secs(3) {
            break None;
        }
    };
    let (after, why) = held.expect("held");
    assert!(after.as_secs_f64() <= safety.position_timeout_s + 0.1, "{after:?}");
    assert!(why.contains("stale"), "{why}");
    ap.request(Mode::Hold).expect("sent");
    std::thread::sleep(Duration::from_millis(100));
    stop.store(true, Ordering::Relaxed);
    let (refused, end) = handle.join().expect("the vehicle thread");
    assert_eq!(refused, Refused { foreign: 0, invalid: 0, commands: 1 }, "the one early OFFBOARD");
    assert!(end.velocity == [0.0; 3], "in HOLD it stopped: {end:?}");
}

#[test]
fn a_listening_companion_is_not_redirected_by_another_system_on_its_port() {
    // The companion listens (`udpin`, as beside PX4 SITL); its autopilot (system 7) and another
    // local process (system 66, also claiming to be a PX4) both send to its port. Once the
    // autopilot is known, the companion's setpoints go to the autopilot alone, however often
    // the other one speaks.
    use mavlink::dialects::common::{MavAutopilot, MavMessage, MavType, HEARTBEAT_DATA};
    let companion = Link::open(Endpoint::In(([127, 0, 0, 1], 0).into()), 7, 191).expect("bound");
    let port = companion.local_addr().expect("address").port();
    let to_companion = |system| Link::open(format!("udpout:127.0.0.1:{port}").parse().expect("endpoint"), system, 1);
    let (mut vehicle, mut intruder) = (to_companion(7).expect("bound"), to_companion(66).expect("bound"));
    let mut ap = Autopilot::new(companion, None);
    let beat = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
        mavtype: MavType::MAV_TYPE_QUADROTOR,
        ..Default::default()
    });
    vehicle.send(&beat).expect("sent");
    let deadline = Instant::now() + Duration::from_secs(3);
    while ap.target().is_none() && Instant::now() < deadline {
        ap.poll(Duration::from_millis(20)).expect("io");
    }
    assert_eq!(ap.target(), Some(7));
    let (mut to_vehicle, mut to_intruder) = (0, 0);
    for _ in 0..20 {
        intruder.send(&beat).expect("sent");
        ap.poll(Duration::from_millis(5)).expect("io");
        assert!(ap.send_velocity([1.0, 0.0, 0.0], 0.0, 0).expect("sent"));
        while let Ok(Some(_)) = vehicle.recv(Duration::from_millis(5)) {
            to_vehicle += 1;
        }
        while let Ok(Some(_)) = intruder.recv(Duration::ZERO) {
            to_intruder += 1;
        }
    }
    assert_eq!(to_intruder, 0, "nothing went to the other system");
    assert_eq!(to_vehicle, 20, "every setpoint reached the autopilot");
    assert!(ap.foreign >= 20, "the other system's frames were counted: {}", ap.foreign);
    // Another process writing the autopilot's own system id while the autopilot speaks: its
    // position is not taken, and the setpoints still go to the autopilot.
    use mavlink::dialects::common::LOCAL_POSITION_NED_DATA;
    let frame = Frame { origin_ned: [0.0; 3], course_rad: 0.0 };
    let mut fake = to_companion(7).expect("bound");
    let at = |x| MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA { x, ..Default::default() });
    let (foreign, mut to_fake) = (ap.foreign, 0);
    vehicle.send(&MavMessage::ATTITUDE(Default::default())).expect("sent");
    for _ in 0..10 {
        vehicle.send(&at(5.0)).expect("sent");
        fake.send(&at(999.0)).expect("sent");
        ap.poll(Duration::from_millis(5)).expect("io");
        ap.send_velocity([1.0, 0.0, 0.0], 0.0, 0).expect("sent");
        while let Ok(Some(_)) = fake.recv(Duration::ZERO) {
            to_fake += 1;
        }
    }
    ap.poll(Duration::from_millis(20)).expect("io");
    let (s, _) = ap.state(&frame, Instant::now()).expect("the autopilot's state");
    assert!((s[state::X] - 5.0).abs() < 1e-6, "x {} (the fake said 999)", s[state::X]);
    assert_eq!(to_fake, 0, "nothing went to the fake");
    assert!(ap.foreign >= foreign + 10, "the fake's frames counted as another's: {}", ap.foreign - foreign);
}
