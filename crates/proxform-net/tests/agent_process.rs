//! The `proxform-agent` process against a hand-driven world on loopback (multicast scouting
//! off): it announces itself, survives what a broken or hostile sender puts on its keys, answers
//! a valid update with the decision the core's agent makes, and exits when the world ends the
//! batch. Every process started here is ended by its id.

use std::process::{Child, Command};
use std::time::{Duration, Instant};

use proxform_core::state::State9;
use proxform_core::{Observation, ObservationSource, UavId};
use proxform_net::keys::Swarm;
use proxform_net::transport::{free_loopback_endpoint, Received, Role, Session};
use proxform_net::wire::codec::encode;
use proxform_net::wire::{ClockMode, ClockMsg, Message, Phase, Presence, SenseMsg};
use proxform_scenario::builtin::paper;

struct Reap(Child);

impl Drop for Reap {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn sense(uav: u32, k: u64, own: State9, heard: Vec<Observation>) -> SenseMsg {
    SenseMsg { uav, run: 0, phase: Phase::Fly, k, t_s: k as f64 * 0.1, own, heard }
}

#[test]
fn the_agent_answers_valid_updates_survives_garbage_and_exits_at_the_end() {
    let sc = paper();
    let endpoint = free_loopback_endpoint().expect("a free port");
    let world = Session::open(&Role::Router { listen: vec![endpoint.clone()], secured: None }).expect("a router");
    let swarm = Swarm::new(&format!("agent-test-{}", std::process::id())).expect("a name");
    let inbox = world.inbox(&[swarm.command(2), swarm.member(2)]).expect("subscriptions");
    let mut agent = Reap(
        Command::new(env!("CARGO_BIN_EXE_proxform-agent"))
            .args(["--scenario", "paper", "--uav", "2", "--swarm", swarm.name(), "--connect", &endpoint])
            .args(["--idle-exit-s", "20"])
            .spawn()
            .expect("proxform-agent starts"),
    );
    let wait_for = |want: &dyn Fn(&Message) -> bool| {
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(20) {
            if let Some(Received::Message(_, m)) = inbox.recv_timeout(Duration::from_millis(100)) {
                if want(&m) {
                    return Some(m);
                }
            }
        }
        None
    };
    assert!(
        wait_for(&|m| matches!(m, Message::Member(x) if x.uav == 2 && x.presence == Presence::Alive)).is_some(),
        "the agent announces itself"
    );
    let sense_key = swarm.sense(2);
    let put = |bytes: Vec<u8>| world.inner_put(&sense_key, bytes);
    // Garbage, another version, a truncated update, a non-finite own state, observations of
    // unknown UAVs and of itself: nothing to answer, nothing to crash on.
    let nav = sc.initial()[0];
    let own = sc.initial()[1];
    let mut bad_own = own;
    bad_own[3] = f64::NAN;
    let valid = encode(&Message::Sense(sense(2, 1, own, vec![])));
    put(b"not a proxform message".to_vec());
    put([&b"PXF\x07"[..], &valid[4..]].concat());
    put(valid[..valid.len() - 3].to_vec());
    put(encode(&Message::Sense(sense(2, 1, bad_own, vec![]))));
    put(encode(&Message::Sense(sense(9, 1, own, vec![]))));
    let odd = |id| Observation { id: UavId(id), state: nav, age_s: 0.0, source: ObservationSource::Onboard };
    // A valid update with the navigator, an unknown UAV (id 40) and itself (id 1) in it.
    put(encode(&Message::Sense(sense(2, 2, own, vec![odd(0), odd(40), odd(1)]))));
    let answer = wait_for(&|m| matches!(m, Message::Command(c) if c.uav == 2));
    let Some(Message::Command(c)) = answer else { panic!("no decision came") };
    assert_eq!((c.k, c.run), (2, 0), "only the valid update is answered");
    // The core's agent, given the same update (the invalid observations dropped), decides the same.
    let mut reference = sc.agent(UavId(1));
    reference.forget_own_estimate();
    let expected = reference.step(0.2, &own, &[odd(0)]);
    // (Its gap to its place is the agent's own: not on the wire.)
    assert_eq!(c.decision, proxform_core::Decision { gap_sq: 0.0, ..expected });
    // The end of the batch: the agent leaves and exits cleanly.
    let end = ClockMsg { mode: ClockMode::Lockstep, run: 0, k: 0, t_s: 0.0, dt_s: 0.1, epoch_ns: 0, end: true };
    world.put(&swarm.clock(), &Message::Clock(end)).expect("sent");
    let start = Instant::now();
    let status = loop {
        if let Some(s) = agent.0.try_wait().expect("wait") {
            break s;
        }
        assert!(start.elapsed() < Duration::from_secs(10), "the agent did not exit at the end");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert!(status.success(), "{status}");
}
