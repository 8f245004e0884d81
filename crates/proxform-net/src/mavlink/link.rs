//! A MAVLink link over UDP: where it goes (`udpin:HOST:PORT` listens there and answers whoever
//! spoke last, as an offboard program listens for PX4's 14540; once it is told which system it
//! talks to, the address that system's frames come from, moving to another address only after
//! the one it answers has sent none of them for [`PEER_SILENT`]; `udpout:HOST:PORT` sends there),
//! and the frames of each datagram checked before anything reads them: MAVLink 2 and 1 frames
//! of the common dialect whose checksum (with the message's CRC extra) holds are decoded; the
//! rest are counted by kind ([`LinkStats`]) and dropped. `serial:PATH[:BAUD]` is a serial line
//! to a flight controller ([`super::serial`], Linux; 57 600 baud unless told): point to point,
//! every frame from its one other end, the byte stream cut into frames that hold (after bytes
//! that are no frame, or a frame whose checksum fails, at the next start marker). Messages go
//! out as MAVLink 2.

use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::time::{Duration, Instant};

use mavlink::dialects::common::MavMessage;
use mavlink::{MavHeader, Message as _};

use super::serial::{SerialLine, BAUDS};

/// A serial line's baud rate when the endpoint does not say (MAVProxy's default; PX4's
/// companion port is often set to 921 600).
pub const DEFAULT_BAUD: u32 = 57_600;

/// How long the address an `udpin` link answers must have sent no frame of its system before
/// another address sending as that system takes its place (an autopilot, or a router, that
/// came back on another port). Frames of the system from elsewhere meanwhile (MAVLink 2 here is
/// unsigned: anyone can write any system id) are read but do not redirect the link.
pub const PEER_SILENT: Duration = Duration::from_secs(1);

/// A link that cannot be opened.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The endpoint is not `udpin:HOST:PORT`, `udpout:HOST:PORT` or `serial:PATH[:BAUD]`.
    #[error(
        "MAVLink endpoint \"{0}\": expected udpin:HOST:PORT (listen) or udpout:HOST:PORT (send to), a host that \
         resolves and a port from 1 to 65535, or serial:PATH[:BAUD] (a serial line; baud one of {BAUDS:?}, \
         57600 unless given)"
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
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Endpoint {
    /// Listen on this address; answer the address heard last.
    In(SocketAddr),
    /// Send to this address (from a port of the system's choosing).
    Out(SocketAddr),
    /// A serial line: the device and its baud rate.
    Serial {
        /// The device (`/dev/ttyAMA0`, `/dev/ttyUSB0`, ...).
        path: String,
        /// Bits per second, one of the standard rates.
        baud: u32,
    },
}

impl std::str::FromStr for Endpoint {
    type Err = LinkError;

    fn from_str(s: &str) -> Result<Self, LinkError> {
        let bad = || LinkError::Endpoint(s.chars().filter(|c| !c.is_control()).take(120).collect());
        let (kind, addr) = s.split_once(':').ok_or_else(bad)?;
        if kind == "serial" {
            let (path, baud) = match addr.rsplit_once(':') {
                Some((path, baud)) if baud.bytes().all(|b| b.is_ascii_digit()) => {
                    (path, baud.parse::<u32>().map_err(|_| bad())?)
                }
                _ => (addr, DEFAULT_BAUD),
            };
            if path.is_empty() || !BAUDS.contains(&baud) {
                return Err(bad());
            }
            return Ok(Self::Serial { path: path.to_string(), baud });
        }
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

/// What the bytes at the start of a buffer are.
enum Frame {
    /// A frame that holds, `len` bytes long (its message appended to the output).
    Decoded { len: usize },
    /// A whole frame (`len` bytes) of a message outside the common dialect.
    Unknown { len: usize },
    /// A whole frame (`len` bytes) whose checksum does not hold.
    BadCrc { len: usize },
    /// A whole frame (`len` bytes) whose payload does not parse.
    Unparsed { len: usize },
    /// A frame's start whose rest has not arrived.
    Short,
    /// No frame: not a start marker, or flags this link does not read.
    Noise,
}

/// The frame at the start of `b` (not empty), its message appended to `out` if it holds; a
/// whole frame counted in `stats` as decoded, unknown or failing its checksum (what is no
/// frame is counted by the caller, which knows where it ends).
fn frame_at(b: &[u8], stats: &mut LinkStats, out: &mut Vec<(MavHeader, MavMessage)>) -> Frame {
    let (version, header_len) = match b[0] {
        0xFD => (mavlink::MavlinkVersion::V2, 10),
        0xFE => (mavlink::MavlinkVersion::V1, 6),
        _ => return Frame::Noise,
    };
    // MAVLink 2's incompatibility flags: only "signed" (0x01) is MAVLink 2 as published.
    if version == mavlink::MavlinkVersion::V2 && b.len() > 2 && b[2] & !0x01 != 0 {
        return Frame::Noise;
    }
    if b.len() < header_len + 2 {
        return Frame::Short;
    }
    let len = usize::from(b[1]);
    let (signed, sequence, system, component, id) = match version {
        mavlink::MavlinkVersion::V2 => (b[2] & 0x01 != 0, b[4], b[5], b[6], u32::from_le_bytes([b[7], b[8], b[9], 0])),
        mavlink::MavlinkVersion::V1 => (false, b[2], b[3], b[4], u32::from(b[5])),
    };
    let total = header_len + len + 2 + if signed { 13 } else { 0 };
    if b.len() < total {
        return Frame::Short;
    }
    let frame = &b[..total];
    let payload = &frame[header_len..header_len + len];
    let crc = u16::from_le_bytes([frame[header_len + len], frame[header_len + len + 1]]);
    let Some(extra) = known_extra_crc(id) else {
        stats.unknown += 1;
        return Frame::Unknown { len: total };
    };
    if mavlink::calculate_crc(&frame[1..header_len + len], extra) != crc {
        stats.bad_crc += 1;
        return Frame::BadCrc { len: total };
    }
    match MavMessage::parse(version, id, payload) {
        Ok(message) => {
            out.push((MavHeader { system_id: u32::from(system), component_id: component, sequence }, message));
            stats.decoded += 1;
            Frame::Decoded { len: total }
        }
        Err(_) => Frame::Unparsed { len: total },
    }
}

/// The frames of `datagram` that hold, decoded into `out` (appended); the rest counted.
pub fn decode(datagram: &[u8], stats: &mut LinkStats, out: &mut Vec<(MavHeader, MavMessage)>) {
    let mut b = datagram;
    while !b.is_empty() {
        let len = match frame_at(b, stats, out) {
            Frame::Decoded { len } | Frame::Unknown { len } | Frame::BadCrc { len } => len,
            Frame::Unparsed { len } => {
                stats.malformed += 1;
                len
            }
            // A datagram holds whole frames: the rest of it is no frame.
            Frame::Short | Frame::Noise => {
                stats.malformed += 1;
                return;
            }
        };
        b = &b[len..];
    }
}

/// The frames that hold at the start of a byte stream's `pending` bytes, decoded into `out`
/// (appended) and removed with whatever was no frame (counted); a frame's start whose rest
/// has not arrived stays. A frame whose checksum fails may be bytes that only look like one
/// (a start marker inside noise, a frame cut by a lost byte): the stream is read on from the
/// next start marker after its first byte, so a frame hidden in it is not lost. A frame of a
/// message outside the common dialect (an ArduPilot's own) is skipped whole, as MAVLink's
/// parsers do: its checksum cannot be checked, and its payload read as a stream could hold
/// false frames; a frame whose header lost a byte may read as one, and take the next frame
/// with it.
pub fn decode_stream(pending: &mut Vec<u8>, stats: &mut LinkStats, out: &mut Vec<(MavHeader, MavMessage)>) {
    let mut at = 0;
    let mut in_noise = false;
    while at < pending.len() {
        let skip = match frame_at(&pending[at..], stats, out) {
            Frame::Decoded { len } | Frame::Unknown { len } => len,
            Frame::Short => break,
            Frame::BadCrc { .. } => 1,
            Frame::Unparsed { .. } | Frame::Noise => {
                // One count per stretch of noise, as a datagram of noise counts once.
                if !in_noise {
                    stats.malformed += 1;
                }
                in_noise = true;
                let next = pending[at + 1..].iter().position(|&c| c == 0xFD || c == 0xFE);
                at = next.map_or(pending.len(), |n| at + 1 + n);
                continue;
            }
        };
        in_noise = false;
        at += skip;
    }
    pending.drain(..at);
}

/// The CRC extra of message `id` if the common dialect has it.
fn known_extra_crc(id: u32) -> Option<u8> {
    MavMessage::default_message_from_id(id).map(|_| MavMessage::extra_crc(id))
}

/// What a link reads and writes.
enum Io {
    Udp(UdpSocket),
    /// The line and the bytes read from it that are not yet a whole frame.
    Serial(SerialLine, Vec<u8>),
}

/// One end of a MAVLink conversation over UDP or a serial line.
pub struct Link {
    io: Io,
    endpoint: Endpoint,
    peer: Option<SocketAddr>,
    /// The address the system it answers speaks from: for `udpin` also where messages go; for
    /// `udpout`, the `udpout` address or, failing it, where that system's frames come from (a
    /// router or autopilot may answer from another port than the one it listens on).
    source: Option<SocketAddr>,
    /// The system whose frames alone move the link's source (and an `udpin` link's peer), once
    /// known.
    peer_system: Option<u8>,
    system_id: u8,
    component_id: u8,
    sequence: u8,
    buf: Vec<u8>,
    /// When the source last sent a frame of the system it answers.
    peer_heard: Option<Instant>,
    /// Where the message `recv` returned last came from (None: a serial line's other end).
    last_from: Option<SocketAddr>,
    inbox: std::collections::VecDeque<(Option<SocketAddr>, MavHeader, MavMessage)>,
    scratch: Vec<(MavHeader, MavMessage)>,
    /// What arrived.
    pub stats: LinkStats,
}

impl Link {
    /// Opens `endpoint`, sending as system `system_id`, component `component_id`.
    pub fn open(endpoint: Endpoint, system_id: u8, component_id: u8) -> Result<Self, LinkError> {
        let io = |problem| LinkError::Io { endpoint: format!("{endpoint:?}"), problem };
        let (link, peer) = match &endpoint {
            Endpoint::In(a) => (Io::Udp(UdpSocket::bind(a).map_err(io)?), None),
            Endpoint::Out(a) => {
                let any: SocketAddr =
                    if a.is_ipv4() { ([0, 0, 0, 0], 0).into() } else { (std::net::Ipv6Addr::UNSPECIFIED, 0).into() };
                let local = if a.ip().is_loopback() { SocketAddr::new(a.ip(), 0) } else { any };
                (Io::Udp(UdpSocket::bind(local).map_err(io)?), Some(*a))
            }
            Endpoint::Serial { path, baud } => {
                (Io::Serial(SerialLine::open(path, *baud).map_err(io)?, Vec::with_capacity(4096)), None)
            }
        };
        Ok(Self {
            io: link,
            endpoint,
            peer,
            source: None,
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

    /// The local address (the port an `udpout` link answers on); a serial line has none.
    pub fn local_addr(&self) -> std::io::Result<SocketAddr> {
        match &self.io {
            Io::Udp(socket) => socket.local_addr(),
            Io::Serial(..) => Err(std::io::Error::new(std::io::ErrorKind::Unsupported, "a serial line")),
        }
    }

    /// Where messages go: the `udpout` address, or whoever an `udpin` link heard last (None on
    /// a serial line, which goes to its other end).
    pub fn peer(&self) -> Option<SocketAddr> {
        self.peer
    }

    /// Answers only system `system` from now on: an `udpin` link's peer moves only to an
    /// address that sent a frame of that system (a frame of any other, decodable or not, does
    /// not redirect what the link sends). None: whoever spoke last.
    pub fn answer_system(&mut self, system: Option<u8>) {
        self.peer_system = system;
    }

    /// Whether the message `recv` returned last came from the address the system it answers
    /// speaks from (an `udpin` link's peer; an `udpout` link's address, or the one address its
    /// system answers from).
    /// A serial line's frames all come from its other end.
    pub fn from_peer(&self) -> bool {
        match self.io {
            Io::Udp(_) => self.last_from.is_some() && self.last_from == self.source,
            Io::Serial(..) => true,
        }
    }

    /// Sends `m` to the peer (nothing while an `udpin` link has heard nobody).
    pub fn send(&mut self, m: &MavMessage) -> std::io::Result<()> {
        let peer = match (&self.io, self.peer) {
            (Io::Serial(..), _) => None,
            (Io::Udp(_), Some(peer)) => Some(peer),
            (Io::Udp(_), None) => return Ok(()),
        };
        let header = MavHeader {
            system_id: u32::from(self.system_id),
            component_id: self.component_id,
            sequence: self.sequence,
        };
        self.sequence = self.sequence.wrapping_add(1);
        let mut bytes = Vec::with_capacity(64);
        mavlink::write_v2_msg(&mut bytes, header, m).map_err(|e| std::io::Error::other(e.to_string()))?;
        match (&mut self.io, peer) {
            (Io::Udp(socket), Some(peer)) => socket.send_to(&bytes, peer).map(|_| ()),
            (Io::Serial(line, _), _) => line.write(&bytes),
            (Io::Udp(_), None) => Ok(()),
        }
    }

    /// The next message that holds, waiting at most `timeout` (None when nothing came).
    pub fn recv(&mut self, timeout: Duration) -> std::io::Result<Option<(MavHeader, MavMessage)>> {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some((from, h, m)) = self.inbox.pop_front() {
                self.last_from = from;
                return Ok(Some((h, m)));
            }
            let left = deadline.saturating_duration_since(Instant::now());
            let socket = match &mut self.io {
                Io::Udp(socket) => socket,
                Io::Serial(line, pending) => {
                    let n = line.read(&mut self.buf, left)?;
                    pending.extend_from_slice(&self.buf[..n]);
                    self.scratch.clear();
                    decode_stream(pending, &mut self.stats, &mut self.scratch);
                    self.inbox.extend(self.scratch.drain(..).map(|(h, m)| (None, h, m)));
                    if self.inbox.is_empty() && Instant::now() >= deadline {
                        return Ok(None);
                    }
                    continue;
                }
            };
            if left.is_zero() {
                socket.set_nonblocking(true)?;
            } else {
                socket.set_nonblocking(false)?;
                socket.set_read_timeout(Some(left))?;
            }
            let (n, from) = match socket.recv_from(&mut self.buf) {
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
            if self.scratch.iter().any(|(h, _)| answers(h)) {
                let now = Instant::now();
                // Told its system, the link keeps its source while that address speaks as the
                // system; an `udpout` link's own address is its source whenever it speaks.
                let sent_to = matches!(self.endpoint, Endpoint::Out(a) if a == from);
                let keep = !sent_to
                    && self.peer_system.is_some()
                    && self.source.is_some_and(|p| p != from)
                    && self.peer_heard.is_some_and(|t| now.duration_since(t) < PEER_SILENT);
                if !keep {
                    self.source = Some(from);
                    self.peer_heard = Some(now);
                    if matches!(self.endpoint, Endpoint::In(_)) {
                        self.peer = Some(from);
                    }
                }
            }
            self.inbox.extend(self.scratch.drain(..).map(|(h, m)| (Some(from), h, m)));
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

    #[test]
    fn a_byte_stream_is_cut_into_the_frames_that_hold_whatever_comes_between() {
        let pos =
            |x| MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA { x, y: -2.0, z: -30.0, ..Default::default() });
        let mut stream = b"\x00noise\xfd\x09".to_vec(); // noise, with a start marker and a length in it
        stream.extend(frame(&pos(1.0), 3));
        let mut broken = frame(&pos(2.0), 3);
        let last = broken.len() - 1;
        broken[last] ^= 0xff; // its checksum fails
        stream.extend(&broken);
        stream.extend(frame(&pos(3.0), 3));
        // A frame cut short by lost bytes, the next one right behind it.
        let cut = frame(&pos(4.0), 3);
        stream.extend(&cut[..cut.len() - 5]);
        stream.extend(frame(&pos(5.0), 3));
        stream.extend(frame(&MavMessage::HEARTBEAT(HEARTBEAT_DATA::default()), 3));
        // Arriving a few bytes at a time, the last frame's end not yet.
        let whole = stream.len();
        stream.extend(&frame(&pos(6.0), 3)[..20]);
        let (mut stats, mut out, mut pending) = (LinkStats::default(), Vec::new(), Vec::new());
        for chunk in stream.chunks(7) {
            pending.extend_from_slice(chunk);
            decode_stream(&mut pending, &mut stats, &mut out);
            assert!(pending.len() <= 7 + 280, "what is kept is at most a frame and a chunk");
        }
        let xs: Vec<f32> = out
            .iter()
            .filter_map(|(_, m)| match m {
                MavMessage::LOCAL_POSITION_NED(p) => Some(p.x),
                _ => None,
            })
            .collect();
        assert_eq!(xs, vec![1.0, 3.0, 5.0], "every whole frame that holds, in order");
        assert_eq!(out.len(), 4, "and the heartbeat");
        assert_eq!(pending.len(), stream.len() - whole, "the last frame's start waits for its rest");
        assert!(stats.bad_crc >= 2 && stats.malformed >= 1, "{stats:?}");
        pending.extend_from_slice(&frame(&pos(6.0), 3)[20..]);
        decode_stream(&mut pending, &mut stats, &mut out);
        assert!(matches!(out.last(), Some((_, MavMessage::LOCAL_POSITION_NED(p))) if p.x == 6.0));
        assert!(pending.is_empty());
    }

    #[test]
    fn serial_endpoints_parse_with_their_baud_or_say_what_they_expect() {
        let serial = |s: &str| s.parse::<Endpoint>();
        assert_eq!(
            serial("serial:/dev/ttyAMA0:921600").ok(),
            Some(Endpoint::Serial { path: "/dev/ttyAMA0".into(), baud: 921_600 })
        );
        assert_eq!(
            serial("serial:/dev/ttyUSB0").ok(),
            Some(Endpoint::Serial { path: "/dev/ttyUSB0".into(), baud: DEFAULT_BAUD })
        );
        for bad in ["serial:", "serial:/dev/ttyUSB0:12345", "serial:/dev/ttyUSB0:99999999999", "serial::57600"] {
            let e = serial(bad).expect_err(bad).to_string();
            assert!(e.contains("serial:PATH[:BAUD]") && e.contains("921600"), "{e}");
        }
        let missing = Link::open(serial("serial:/nonexistent/tty:57600").expect("parsed"), 1, 191);
        assert!(matches!(missing, Err(LinkError::Io { .. })));
    }

    /// A serial line over a pseudo-terminal: the link on its device, the test as the autopilot
    /// on the other side.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_serial_link_talks_to_the_other_end_of_its_line() {
        use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
        use std::io::{Read, Write};
        use std::os::fd::AsFd;
        let pty = nix::pty::openpty(None, None).expect("a pseudo-terminal");
        let device = nix::unistd::ttyname(&pty.slave).expect("its device");
        let endpoint = format!("serial:{}:921600", device.display()).parse().expect("endpoint");
        let mut companion = Link::open(endpoint, 255, 191).expect("opened");
        let mut autopilot = std::fs::File::from(pty.master);
        assert!(companion.local_addr().is_err() && companion.peer().is_none());
        // The autopilot's frames, in two writes that cut one of them, with noise before.
        let beat = MavMessage::HEARTBEAT(HEARTBEAT_DATA::default());
        let pos = MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA { x: 7.5, ..Default::default() });
        let mut bytes = b"\x55\xaa".to_vec();
        bytes.extend(frame(&beat, 1));
        bytes.extend(frame(&pos, 1));
        let (first, rest) = bytes.split_at(8);
        autopilot.write_all(first).expect("written");
        assert!(companion.recv(Duration::from_millis(100)).expect("io").is_none(), "a frame cut short waits");
        autopilot.write_all(rest).expect("written");
        let got = companion.recv(Duration::from_secs(2)).expect("io").expect("heartbeat");
        assert!(matches!(got.1, MavMessage::HEARTBEAT(_)) && got.0.system_id == 1);
        assert!(companion.from_peer(), "the line's other end");
        let got = companion.recv(Duration::from_secs(2)).expect("io").expect("position");
        assert!(matches!(got.1, MavMessage::LOCAL_POSITION_NED(p) if p.x == 7.5));
        assert_eq!((companion.stats.decoded, companion.stats.malformed), (2, 1));
        // What the companion sends reaches the autopilot whole.
        companion.send(&pos).expect("sent");
        let (mut pending, mut out, mut stats) = (Vec::new(), Vec::new(), LinkStats::default());
        let mut buf = [0u8; 512];
        for _ in 0..20 {
            let mut fds = [PollFd::new(autopilot.as_fd(), PollFlags::POLLIN)];
            if poll(&mut fds, PollTimeout::from(100u16)).expect("poll") > 0 {
                let n = autopilot.read(&mut buf).expect("read");
                pending.extend_from_slice(&buf[..n]);
                decode_stream(&mut pending, &mut stats, &mut out);
            }
            if !out.is_empty() {
                break;
            }
        }
        assert!(matches!(&out[..], [(h, MavMessage::LOCAL_POSITION_NED(p))] if h.system_id == 255 && p.x == 7.5));
    }

    #[test]
    fn an_udpout_link_takes_its_system_from_the_one_address_it_answers_from() {
        // An autopilot (or a router) that listens on one port and answers from another.
        let local = Endpoint::In(([127, 0, 0, 1], 0).into());
        let listens = Link::open(local, 1, 1).expect("bound");
        let port = listens.local_addr().expect("address").port();
        let mut companion =
            Link::open(format!("udpout:127.0.0.1:{port}").parse().expect("endpoint"), 255, 191).expect("bound");
        let to = |system| Link::open(Endpoint::In(([127, 0, 0, 1], 0).into()), system, 1);
        let (mut answers, mut intruder) = (to(1).expect("bound"), to(1).expect("bound"));
        let here = companion.local_addr().expect("address");
        let beat = MavMessage::HEARTBEAT(HEARTBEAT_DATA::default());
        let say = |l: &mut Link, c: &mut Link| {
            l.peer = Some(here);
            l.send(&beat).expect("sent");
            c.recv(Duration::from_secs(2)).expect("io").expect("heard")
        };
        companion.answer_system(Some(1));
        assert_eq!(say(&mut answers, &mut companion).0.system_id, 1);
        assert!(companion.from_peer(), "its system's frames from where it answers");
        // Another address writing the same system id does not take it while it speaks ...
        say(&mut intruder, &mut companion);
        assert!(!companion.from_peer(), "another address claiming system 1");
        say(&mut answers, &mut companion);
        assert!(companion.from_peer());
        assert_eq!(companion.peer(), listens.local_addr().ok(), "an udpout link sends where it was told");
        // ... and once it has been silent for PEER_SILENT, the new address is its system's.
        std::thread::sleep(PEER_SILENT + Duration::from_millis(100));
        say(&mut intruder, &mut companion);
        assert!(companion.from_peer(), "the autopilot went silent");
    }
}
