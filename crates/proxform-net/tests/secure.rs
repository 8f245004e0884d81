//! Authenticated links on loopback: a world serving a swarm over mutual TLS with the swarm's
//! access rules (`proxform_net::access`), and peers that try what a rogue would: connecting
//! without a certificate or with another authority's, and, with UAV 2's certificate, publishing
//! UAV 3's command, state, sense and membership, or the world's clock. What the world receives
//! is checked message by message: only UAV 2's own keys get through.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use proxform_net::access::{acl_json5, Party};
use proxform_net::credentials::{SwarmCredentials, Validity};
use proxform_net::keys::Swarm;
use proxform_net::transport::{free_loopback_endpoint, Received, Role, Secured, Session, Tls};
use proxform_net::wire::{MemberMsg, Message, Presence};

/// Writes a swarm's credentials for UAVs 1 to `uavs` into a fresh folder.
fn credentials(name: &str, uavs: u32) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("proxform-secure-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("a folder");
    let today = 20_000; // 2024-10-04: certificates valid for 20 years from then
    let c = SwarmCredentials::generate("test", uavs, 0, &[], Validity { from_day: today, days: 7300 }).expect("made");
    std::fs::write(dir.join("ca.pem"), &c.ca_pem).expect("write");
    for i in &c.issued {
        std::fs::write(dir.join(format!("{}.pem", i.party.file_stem())), &i.cert_pem).expect("write");
        std::fs::write(dir.join(format!("{}.key", i.party.file_stem())), &i.key_pem).expect("write");
    }
    dir
}

fn client(endpoint: &str, tls: Option<Tls>) -> Result<Session, String> {
    Session::open(&Role::Client { connect: vec![endpoint.into()], wait_for_router: Duration::from_secs(2), tls })
        .map_err(|e| e.to_string())
}

fn world(dir: &Path, swarm: &Swarm) -> (Session, String) {
    let secured = Secured { tls: Tls::in_folder(dir, Party::World), acl_json5: acl_json5(swarm, 4, 1) };
    for _ in 0..10 {
        let e = free_loopback_endpoint().expect("a port").replacen("tcp/", "tls/", 1);
        if let Ok(s) = Session::open(&Role::Router { listen: vec![e.clone()], secured: Some(secured.clone()) }) {
            return (s, e);
        }
    }
    panic!("no router could listen");
}

#[test]
fn only_certified_peers_connect_and_each_publishes_its_own_uavs_keys_only() {
    let dir = credentials("own", 4);
    let swarm = Swarm::new(&format!("secure-{}", std::process::id())).expect("a name");
    let (world, endpoint) = world(&dir, &swarm);
    let inbox = world.inbox(&[format!("proxform/v1/{}/**", swarm.name())]).expect("subscribed");

    // No certificate, or one of another swarm's authority: the handshake fails.
    assert!(client(&endpoint, None).is_err(), "a peer without a certificate connected");
    let other = credentials("other", 4);
    assert!(
        client(&endpoint, Some(Tls::in_folder(&other, Party::Uav(2)))).is_err(),
        "another authority's peer connected"
    );
    // A certified peer connects; so does a plain TCP client to nothing (the port speaks TLS).
    let tcp = endpoint.replacen("tls/", "tcp/", 1);
    assert!(client(&tcp, None).is_err(), "a plain TCP peer joined a TLS router");

    let uav2 = client(&endpoint, Some(Tls::in_folder(&dir, Party::Uav(2)))).expect("UAV 2's agent connects");
    let observer = client(&endpoint, Some(Tls::in_folder(&dir, Party::Observer))).expect("an observer connects");
    // The UAV 3 agent's view: it must never receive the forged clock.
    let uav3 = client(&endpoint, Some(Tls::in_folder(&dir, Party::Uav(3)))).expect("UAV 3's agent connects");
    let uav3_inbox = uav3.inbox(&[swarm.clock(), swarm.command(3)]).expect("subscribed");
    std::thread::sleep(Duration::from_millis(300));

    let forged = [swarm.command(3), swarm.state(3), swarm.sense(3), swarm.member(3), swarm.clock(), swarm.sense(2)];
    for key in &forged {
        uav2.inner_put(key, vec![1, 2, 3]);
    }
    for key in [swarm.command(2), swarm.state(2)] {
        observer.inner_put(&key, vec![4, 5, 6]);
    }
    // On its own key, a message naming UAV 3 (UAV 3 leaving): delivered, but never as UAV 3's.
    let leaving = Message::Member(MemberMsg { uav: 3, presence: Presence::Leaving, pid: 1, digest: 0 });
    uav2.put(&swarm.member(2), &leaving).expect("put");
    // What UAV 2 may send, last: once it has arrived, everything sent before it on the same link
    // has been delivered or dropped.
    let own = [swarm.state(2), swarm.member(2), swarm.command(2)];
    for key in &own {
        uav2.inner_put(key, vec![7, 8, 9]);
    }
    let mut got = Vec::new();
    let mut misplaced = Vec::new();
    let start = Instant::now();
    let mut settled = None;
    while start.elapsed() < Duration::from_secs(10)
        && settled.is_none_or(|t: Instant| t.elapsed() < Duration::from_millis(300))
    {
        match inbox.recv_timeout(Duration::from_millis(50)) {
            Some(Received::Garbage(key, _) | Received::Message(key, _)) => got.push(key),
            Some(Received::Misplaced(key, m)) => misplaced.push((key, m)),
            None => {}
        }
        if settled.is_none() && got.len() >= own.len() {
            settled = Some(Instant::now());
        }
    }
    assert_eq!(got, own, "the world received exactly UAV 2's own keys");
    assert_eq!(misplaced, [(swarm.member(2), leaving)], "UAV 3's leaving, said by UAV 2, taken as UAV 3's");
    assert!(uav3_inbox.try_recv().is_none(), "UAV 3 received a forged clock or command");

    // The world's own clock reaches the agents.
    world.inner_put(&swarm.clock(), vec![0]);
    let start = Instant::now();
    let mut heard = false;
    while !heard && start.elapsed() < Duration::from_secs(5) {
        heard = uav3_inbox.recv_timeout(Duration::from_millis(50)).is_some();
    }
    assert!(heard, "the world's clock did not reach UAV 3's agent");
    for s in [uav2, observer, uav3, world] {
        s.close();
    }
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&other);
}

#[test]
fn a_flood_fills_an_inbox_to_its_bound_and_no_further() {
    // A peer publishes 8 MiB faster than anyone reads: an inbox bounded to 1 MiB keeps at most
    // that, counts what it dropped, and takes messages again once read.
    let endpoint = proxform_net::transport::free_loopback_endpoint().expect("a port");
    let router = Session::open(&Role::Router { listen: vec![endpoint.clone()], secured: None }).expect("router");
    let inbox = router.inbox_bounded(&["flood/**".to_string()], 1 << 20).expect("subscribed");
    let peer =
        Session::open(&Role::Client { connect: vec![endpoint], wait_for_router: Duration::from_secs(10), tls: None })
            .expect("peer");
    std::thread::sleep(Duration::from_millis(300));
    // In bursts until the inbox has dropped 100 (the sender's own congestion control may drop
    // some of a burst on a busy machine: what reaches the inbox is what is counted).
    let start = Instant::now();
    let mut sent = 0;
    while inbox.dropped() < 100 && start.elapsed() < Duration::from_secs(20) {
        for _ in 0..8 {
            peer.inner_put("flood/x", vec![7u8; 64 << 10]);
        }
        sent += 8;
        std::thread::sleep(Duration::from_millis(5));
    }
    let dropped = inbox.dropped();
    let mut kept = 0;
    while inbox.try_recv().is_some() {
        kept += 1;
    }
    assert!((1..=16).contains(&kept), "{kept} of 64 KiB kept in 1 MiB");
    assert!(dropped >= 100, "{dropped} dropped, {kept} kept of {sent} sent");
    peer.inner_put("flood/x", vec![1, 2, 3]);
    let again = inbox.recv_timeout(Duration::from_secs(5));
    assert!(again.is_some(), "read, the inbox takes messages again");
}

#[test]
fn a_burst_of_messages_someone_waits_for_arrives_whole() {
    // A publisher of updates sends 4 000 updates of ~60 KiB (700 observations: one a batch) as fast
    // as it can, far faster than the link drains its two queued batches: it waits for room,
    // and every one arrives. (Zenoh's default drops a message that finds no room within 1 ms:
    // that lost a lockstep answer on a loaded machine; a telemetry publisher keeps that and
    // here loses about half, idle.)
    use proxform_core::observation::{Observation, ObservationSource};
    use proxform_core::UavId;
    use proxform_net::wire::{Phase, SenseMsg};
    let endpoint = proxform_net::transport::free_loopback_endpoint().expect("a port");
    let router = Session::open(&Role::Router { listen: vec![endpoint.clone()], secured: None }).expect("router");
    let inbox = router.inbox_bounded(&["burst/**".to_string()], 1 << 30).expect("subscribed");
    let peer =
        Session::open(&Role::Client { connect: vec![endpoint], wait_for_router: Duration::from_secs(10), tls: None })
            .expect("peer");
    std::thread::sleep(Duration::from_millis(300));
    let heard: Vec<Observation> = (0..700)
        .map(|i| Observation {
            id: UavId(i),
            state: Default::default(),
            age_s: 0.1,
            source: ObservationSource::Onboard,
        })
        .collect();
    let update = |k: u64| {
        Message::Sense(SenseMsg {
            uav: 2,
            run: 0,
            phase: Phase::Fly,
            k,
            t_s: 0.1 * k as f64,
            own: Default::default(),
            heard: heard.clone(),
        })
    };
    let count = |key: &str, p: proxform_net::transport::Publisher| {
        let n = 4000u64;
        for k in 0..n {
            p.send(&update(k)).expect("sent");
        }
        let (start, mut got) = (Instant::now(), 0u64);
        while start.elapsed() < Duration::from_secs(30) && inbox.recv_timeout(Duration::from_secs(1)).is_some() {
            got += 1;
        }
        eprintln!("{key}: {got} of {n}");
        got
    };
    let telemetry = count("telemetry", peer.telemetry("burst/telemetry").expect("publisher"));
    let waited = count("waited", peer.publisher("burst/waited").expect("publisher"));
    assert_eq!(waited, 4000, "a publisher of updates lost some of a burst (telemetry kept {telemetry})");
}
