//! A MAVLink link over UDP: where it goes (`udpin:HOST:PORT` listens there and answers whoever
//! spoke last, as an offboard program listens for PX4's 14540; once it is told which system it
//! talks to, the address that system's frames come from, moving to another address only after
//! the one it answers has sent none of them for [`PEER_SILENT`]; `udpout:HOST:PORT` sends there),
//! and the frames of each datagram checked before anything reads them: MAVLink 2 and 1 frames
//! of the common dialect whose checksum (with the message's CRC extra) holds are decoded; the
//! rest are counted by kind ([`LinkStats`]) and dropped. Messages go out as MAVLink 2.

use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::time::{Duration, Instant};

use mavlink::dialects::common::MavMessage;
use mavlink::{MavHeader, Message as _};

/// How long the address an `udpin` link answers must have sent no frame of its system before
/// another address sending as that system takes its place (an autopilot, or a router, that
/// came back on another port). Frames of the system from elsewhere meanwhile (MAVLink 2 here is
/// unsigned: anyone can write any system id) are read but do not redirect the link.
pub const PEER_SILENT: Duration = Duration::from_secs(1);

/// A link that cannot be opened.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The endpoint is not `udpin:HOST:PORT` or `udpout:HOST:PORT`.
    #[error(
        "MAVLink endpoint \"{0}\": expected udpin:HOST:PORT (listen) or udpout:HOST:PORT (send to), a host that \
         resolves and a port from 1 to 65535"
    )]
    Endpoint(String),
    /// The socket failed.
    #[error("MAVLink endpoint {endpoint}: {problem}")]
    Io {
        /// The endpoint.
        endpoint: String,
        /// What the system said (in the message, not as a cause: it would print twice).
        problem: std::io::Error,
    },
}

/// Where a link goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Endpoint {
    /// Listen on this address; answer the address heard last.
    In(SocketAddr),
    /// Send to this address (from a port of the system's choosing).
    Out(SocketAddr),
}

impl std::str::FromStr for Endpoint {
    type Err = LinkError;

    fn from_str(s: &str) -> Result<Self, LinkError> {
        let bad = || LinkError::Endpoint(s.chars().filter(|c| !c.is_control()).take(120).collect());
        let (kind, addr) = s.split_once(':').ok_or_else(bad)?;
        // `udpin://HOST:PORT`, as MAVSDK writes it, too.
        let addr = addr.strip_prefix("//").unwrap_or(addr);
        let addr = addr.to_socket_addrs().map_err(|_| bad())?.next().ok_or_else(bad)?;
        // Port 0 would be one the system picks, where no autopilot sends or listens.
        if addr.port() == 0 {
            return Err(bad());
        }
        match kind {
            "udpin" => Ok(Self::In(addr)),
            "udpout" => Ok(Self::Out(addr)),
            _ => Err(bad()),
        }
    }
}

/// What a link received that it did not decode.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// Frames decoded.
    pub decoded: u64,
    /// Frames whose checksum did not hold.
    pub bad_crc: u64,
    /// Frames of messages outside the common dialect.
    pub unknown: u64,
    /// Bytes that were no frame (garbage, a frame cut short, flags this link does not read).
    pub malformed: u64,
}

/// The frames of `datagram` that hold, decoded into `out` (appended); the rest counted.
pub fn decode(datagram: &[u8], stats: &mut LinkStats, out: &mut Vec<(MavHeader, MavMessage)>) {
    let mut b = datagram;
    while !b.is_empty() {
        let (version, header_len) = match b[0] {
            0xFD => (mavlink::MavlinkVersion::V2, 10),
            0xFE => (mavlink::MavlinkVersion::V1, 6),
            _ => {
                stats.malformed += 1;
                return;
            }
        };
        if b.len() < header_len + 2 {
            stats.malformed += 1;
            return;
        }
        let len = usize::from(b[1]);
        let (signed, sequence, system, component, id) = match version {
            mavlink::MavlinkVersion::V2 => {
                // Incompatibility flags: only "signed" (0x01) is MAVLink 2 as published.
                if b[2] & !0x01 != 0 {
                    stats.malformed += 1;
                    return;
                }
                (b[2] & 0x01 != 0, b[4], b[5], b[6], u32::from_le_bytes([b[7], b[8], b[9], 0]))
            }
            mavlink::MavlinkVersion::V1 => (false, b[2], b[3], b[4], u32::from(b[5])),
        };
        let total = header_len + len + 2 + if signed { 13 } else { 0 };
        if b.len() < total {
            stats.malformed += 1;
            return;
        }
        let frame = &b[..total];
        b = &b[total..];
        let payload = &frame[header_len..header_len + len];
        let crc = u16::from_le_bytes([frame[header_len + len], frame[header_len + len + 1]]);
        let Some(extra) = known_extra_crc(id) else {
            stats.unknown += 1;
            continue;
        };
        if mavlink::calculate_crc(&frame[1..header_len + len], extra) != crc {
            stats.bad_crc += 1;
            continue;
        }
        match MavMessage::parse(version, id, payload) {
            Ok(m) => {
                stats.decoded += 1;
                out.push((MavHeader { system_id: u32::from(system), component_id: component, sequence }, m));
            }
            Err(_) => stats.malformed += 1,
        }
    }
}

/// The CRC extra of message `id` if the common dialect has it.
fn known_extra_crc(id: u32) -> Option<u8> {
    MavMessage::default_message_from_id(id).map(|_| MavMessage::extra_crc(id))
}

/// One end of a MAVLink conversation over UDP.
pub struct Link {
    socket: UdpSocket,
    endpoint: Endpoint,
    peer: Option<SocketAddr>,
    /// The system whose frames alone move an `udpin` link's peer, once known.
    peer_system: Option<u8>,
    system_id: u8,
    component_id: u8,
    sequence: u8,
    buf: Vec<u8>,
    /// When the address answered last sent a frame of the system it answers.
    peer_heard: Option<Instant>,
    /// Where the message `recv` returned last came from.
    last_from: Option<SocketAddr>,
    inbox: std::collections::VecDeque<(SocketAddr, MavHeader, MavMessage)>,
    scratch: Vec<(MavHeader, MavMessage)>,
    /// What arrived.
    pub stats: LinkStats,
}

impl Link {
    /// Opens `endpoint`, sending as system `system_id`, component `component_id`.
    pub fn open(endpoint: Endpoint, system_id: u8, component_id: u8) -> Result<Self, LinkError> {
        let io = |problem| LinkError::Io { endpoint: format!("{endpoint:?}"), problem };
        let (socket, peer) = match endpoint {
            Endpoint::In(a) => (UdpSocket::bind(a).map_err(io)?, None),
            Endpoint::Out(a) => {
                let any: SocketAddr =
                    if a.is_ipv4() { ([0, 0, 0, 0], 0).into() } else { (std::net::Ipv6Addr::UNSPECIFIED, 0).into() };
                let local = if a.ip().is_loopback() { SocketAddr::new(a.ip(), 0) } else { any };
                (UdpSocket::bind(local).map_err(io)?, Some(a))
            }
        };
        Ok(Self {
            socket,
            endpoint,
            peer,
            peer_system: None,
            peer_heard: None,
            last_from: None,
            system_id,
            component_id,
            sequence: 0,
            buf: vec![0; 65_536],
            inbox: Default::default(),
            scratch: Vec::new(),
            stats: LinkStats::default(),
        })
    }

    /// The local address (the port an `udpout` link answers on).
    pub fn local_addr(&self) -> std::io::Result<SocketAddr> {
        self.socket.local_addr()
    }

    /// Where messages go: the `udpout` address, or whoever an `udpin` link heard last.
    pub fn peer(&self) -> Option<SocketAddr> {
        self.peer
    }

    /// Answers only system `system` from now on: an `udpin` link's peer moves only to an
    /// address that sent a frame of that system (a frame of any other, decodable or not, does
    /// not redirect what the link sends). None: whoever spoke last.
    pub fn answer_system(&mut self, system: Option<u8>) {
        self.peer_system = system;
    }

    /// Whether the message `recv` returned last came from the address this link sends to (the
    /// `udpout` address: where the program that flies the vehicle listens).
    pub fn from_peer(&self) -> bool {
        self.last_from.is_some() && self.last_from == self.peer
    }

    /// Sends `m` to the peer (nothing while an `udpin` link has heard nobody).
    pub fn send(&mut self, m: &MavMessage) -> std::io::Result<()> {
        let Some(peer) = self.peer else { return Ok(()) };
        let header = MavHeader {
            system_id: u32::from(self.system_id),
            component_id: self.component_id,
            sequence: self.sequence,
        };
        self.sequence = self.sequence.wrapping_add(1);
        let mut bytes = Vec::with_capacity(64);
        mavlink::write_v2_msg(&mut bytes, header, m).map_err(|e| std::io::Error::other(e.to_string()))?;
        self.socket.send_to(&bytes, peer).map(|_| ())
    }

    /// The next message that holds, waiting at most `timeout` (None when nothing came).
    pub fn recv(&mut self, timeout: Duration) -> std::io::Result<Option<(MavHeader, MavMessage)>> {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some((from, h, m)) = self.inbox.pop_front() {
                self.last_from = Some(from);
                return Ok(Some((h, m)));
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                self.socket.set_nonblocking(true)?;
            } else {
                self.socket.set_nonblocking(false)?;
                self.socket.set_read_timeout(Some(left))?;
            }
            let (n, from) = match self.socket.recv_from(&mut self.buf) {
                Ok(r) => r,
                Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {
                    return Ok(None)
                }
                // A port nobody listens on yet (ICMP refused): nothing arrived.
                Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => {
                    if Instant::now() >= deadline {
                        return Ok(None);
                    }
                    continue;
                }
                Err(e) => return Err(e),
            };
            self.scratch.clear();
            decode(&self.buf[..n], &mut self.stats, &mut self.scratch);
            let answers = |h: &MavHeader| self.peer_system.is_none_or(|s| h.system_id == u32::from(s));
            if matches!(self.endpoint, Endpoint::In(_)) && self.scratch.iter().any(|(h, _)| answers(h)) {
                let now = Instant::now();
                // Told its system, the link keeps the address it answers while that address
                // speaks as the system.
                let keep = self.peer_system.is_some()
                    && self.peer.is_some_and(|p| p != from)
                    && self.peer_heard.is_some_and(|t| now.duration_since(t) < PEER_SILENT);
                if !keep {
                    self.peer = Some(from);
                    self.peer_heard = Some(now);
                }
            }
            self.inbox.extend(self.scratch.drain(..).map(|(h, m)| (from, h, m)));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mavlink::dialects::common::{HEARTBEAT_DATA, LOCAL_POSITION_NED_DATA};

    fn frame(m: &MavMessage, system: u8) -> Vec<u8> {
        let mut v = Vec::new();
        let h = MavHeader { system_id: u32::from(system), component_id: 1, sequence: 7 };
        mavlink::write_v2_msg(&mut v, h, m).expect("written");
        v
    }

    #[test]
    fn frames_that_hold_are_decoded_and_the_rest_counted() {
        let pos =
            MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA { x: 1.5, y: -2.0, z: -30.0, ..Default::default() });
        let beat = MavMessage::HEARTBEAT(HEARTBEAT_DATA::default());
        let mut datagram = frame(&pos, 3);
        datagram.extend(frame(&beat, 3));
        let (mut stats, mut out) = (LinkStats::default(), Vec::new());
        decode(&datagram, &mut stats, &mut out);
        assert_eq!(out.len(), 2);
        assert_eq!(out[0].0.system_id, 3);
        assert_eq!(out[0].1, pos);
        assert_eq!(stats, LinkStats { decoded: 2, ..Default::default() });
        // A flipped payload byte: the checksum fails and nothing is read.
        let mut bad = frame(&pos, 3);
        bad[12] ^= 0x40;
        out.clear();
        decode(&bad, &mut stats, &mut out);
        assert!(out.is_empty());
        assert_eq!(stats.bad_crc, 1);
        // A message id outside the dialect, a frame cut short, garbage.
        let mut unknown = frame(&pos, 3);
        unknown[7..10].copy_from_slice(&[0xAB, 0xCD, 0x0E]);
        decode(&unknown, &mut stats, &mut out);
        decode(&frame(&pos, 3)[..9], &mut stats, &mut out);
        decode(b"hello", &mut stats, &mut out);
        assert!(out.is_empty());
        assert_eq!((stats.unknown, stats.malformed), (1, 2));
    }

    #[test]
    fn endpoints_parse_or_say_what_they_expect() {
        assert_eq!(
            "udpin:127.0.0.1:14540".parse::<Endpoint>().ok(),
            Some(Endpoint::In(([127, 0, 0, 1], 14540).into()))
        );
        assert!(matches!("udpout://127.0.0.1:14550".parse::<Endpoint>(), Ok(Endpoint::Out(_))));
        for bad in [
            "tcp:1.2.3.4:5",
            "udpin:999.1.1.1:5",
            "udpin:127.0.0.1",
            "serial",
            "udpout:127.0.0.1:99999",
            "udpin:127.0.0.1:0",
        ] {
            let e = bad.parse::<Endpoint>().expect_err(bad);
            assert!(e.to_string().contains("expected udpin:HOST:PORT"), "{e}");
        }
    }

    #[test]
    fn two_links_talk_over_loopback() {
        let mut vehicle = Link::open(Endpoint::In(([127, 0, 0, 1], 0).into()), 2, 1).expect("bound");
        let port = vehicle.local_addr().expect("address").port();
        let mut companion =
            Link::open(format!("udpout:127.0.0.1:{port}").parse().expect("endpoint"), 255, 190).expect("bound");
        companion.send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA::default())).expect("sent");
        let (h, m) = vehicle.recv(Duration::from_secs(2)).expect("io").expect("heard");
        assert_eq!((h.system_id, h.component_id), (255, 190));
        assert!(matches!(m, MavMessage::HEARTBEAT(_)));
        // The listening end answers whoever spoke.
        vehicle.send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA::default())).expect("sent");
        let (h, _) = companion.recv(Duration::from_secs(2)).expect("io").expect("answered");
        assert_eq!(h.system_id, 2);
        assert!(companion.recv(Duration::from_millis(20)).expect("io").is_none());
    }

    #[test]
    fn a_link_told_its_system_is_not_redirected_by_another() {
        let local = Endpoint::In(([127, 0, 0, 1], 0).into());
        let mut companion = Link::open(local, 255, 191).expect("bound");
        let port = companion.local_addr().expect("address").port();
        let to = |system| Link::open(format!("udpout:127.0.0.1:{port}").parse().expect("endpoint"), system, 1);
        let (mut autopilot, mut intruder) = (to(1).expect("bound"), to(66).expect("bound"));
        companion.answer_system(Some(1));
        let beat = MavMessage::HEARTBEAT(HEARTBEAT_DATA::default());
        autopilot.send(&beat).expect("sent");
        assert_eq!(companion.recv(Duration::from_secs(2)).expect("io").expect("heard").0.system_id, 1);
        // Another system speaks (its frames are still read): the link keeps answering system 1.
        intruder.send(&beat).expect("sent");
        assert_eq!(companion.recv(Duration::from_secs(2)).expect("io").expect("heard").0.system_id, 66);
        assert_eq!(companion.peer(), autopilot.local_addr().ok());
        companion.send(&beat).expect("sent");
        assert!(autopilot.recv(Duration::from_secs(2)).expect("io").is_some());
        assert!(intruder.recv(Duration::from_millis(50)).expect("io").is_none());
        // Another address speaking as system 1 (unsigned MAVLink: anyone can) does not take
        // the link while the autopilot speaks; once the autopilot has been silent for
        // PEER_SILENT, a new address of system 1 does (an autopilot back on another port).
        let mut fake = to(1).expect("bound");
        fake.send(&beat).expect("sent");
        assert!(companion.recv(Duration::from_secs(2)).expect("io").is_some());
        assert_eq!(companion.peer(), autopilot.local_addr().ok());
        assert!(!companion.from_peer(), "the fake's frame is not the peer's");
        autopilot.send(&beat).expect("sent");
        assert!(companion.recv(Duration::from_secs(2)).expect("io").is_some());
        assert!(companion.from_peer());
        std::thread::sleep(PEER_SILENT + Duration::from_millis(100));
        fake.send(&beat).expect("sent");
        assert!(companion.recv(Duration::from_secs(2)).expect("io").is_some());
        assert_eq!(companion.peer(), fake.local_addr().ok(), "the autopilot went silent");
        // Told nothing, whoever spoke last.
        companion.answer_system(None);
        intruder.send(&beat).expect("sent");
        assert!(companion.recv(Duration::from_secs(2)).expect("io").is_some());
        assert_eq!(companion.peer(), intruder.local_addr().ok());
    }
}
