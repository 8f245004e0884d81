//! The transport: a Zenoh session with explicit endpoints and multicast scouting off (nothing
//! is discovered or announced beyond the endpoints given), and typed publishing and receiving
//! of [`crate::wire`] messages. A world runs as a Zenoh router that agents and outside clients
//! connect to; the key expressions are those of [`crate::keys`].

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

use zenoh::qos::CongestionControl;
use zenoh::Wait;

use crate::access::Party;
use crate::seal::FlightKey;
use crate::wire::codec::{self, DecodeError};
use crate::wire::Message;

/// A party's identity on a swarm's authenticated links (PEM files, `proxform keys`): the
/// swarm's authority, which every peer's certificate must be signed by (mutual TLS), and this
/// party's own certificate and private key.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Tls {
    /// The swarm authority's certificate.
    pub ca: PathBuf,
    /// This party's certificate.
    pub cert: PathBuf,
    /// This party's private key.
    pub key: PathBuf,
}

impl Tls {
    /// The files of `party` in a folder written by `proxform keys`: `ca.pem`, `<party>.pem`,
    /// `<party>.key`.
    pub fn in_folder(dir: &Path, party: Party) -> Self {
        let stem = party.file_stem();
        Self { ca: dir.join("ca.pem"), cert: dir.join(format!("{stem}.pem")), key: dir.join(format!("{stem}.key")) }
    }

    /// Checks that each file is there and is what it should be (a PEM certificate, a PEM
    /// private key), so that a missing or damaged file is named before any link is tried (the
    /// TLS library only says that nothing could be trusted, or times out).
    pub fn check(&self) -> Result<(), TransportError> {
        for (path, label) in [(&self.ca, "CERTIFICATE"), (&self.cert, "CERTIFICATE"), (&self.key, "PRIVATE KEY")] {
            let meta =
                std::fs::metadata(path).map_err(|e| TransportError::Config(format!("{}: {e}", path.display())))?;
            if !meta.is_file() || meta.len() > 1 << 20 {
                return Err(TransportError::Config(format!("{}: not a PEM file of at most 1 MiB", path.display())));
            }
            let text = std::fs::read_to_string(path).unwrap_or_default();
            let begin = text.find("-----BEGIN ").map(|i| &text[i + 11..]);
            let pem = begin.is_some_and(|b| b.split("-----").next().is_some_and(|l| l.ends_with(label)))
                && text.contains("-----END ");
            if !pem {
                let what = if label == "CERTIFICATE" { "certificate" } else { "private key" };
                return Err(TransportError::Config(format!(
                    "{}: not a PEM {what} (make the swarm's credentials with `proxform keys`)",
                    path.display()
                )));
            }
        }
        Ok(())
    }
}

/// A router's authenticated links and the access rules it enforces on them
/// ([`crate::access::acl_json5`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Secured {
    /// The router's identity (the world's).
    pub tls: Tls,
    /// The `access_control` section (JSON5).
    pub acl_json5: String,
}

/// How a process joins the network.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Role {
    /// A router listening on these endpoints (such as `tcp/127.0.0.1:7447`, or `tls/...` when
    /// secured); others connect to it. The world runs as one.
    Router {
        /// Endpoints to listen on.
        listen: Vec<String>,
        /// Mutual TLS and access rules (None: plain links, for loopback).
        secured: Option<Secured>,
    },
    /// A client of a router at one of these endpoints. Agents and outside programs run as one.
    Client {
        /// Endpoints to connect to.
        connect: Vec<String>,
        /// How long to wait for the router at start.
        wait_for_router: Duration,
        /// This party's identity for a `tls/` endpoint.
        tls: Option<Tls>,
    },
}

/// A transport that could not be set up or used.
#[derive(Debug, thiserror::Error)]
pub enum TransportError {
    /// The configuration was refused (a malformed endpoint, say).
    #[error("network configuration: {0}")]
    Config(String),
    /// The session could not be opened (nothing listening, a port in use).
    #[error("cannot open the network session: {0}")]
    Open(String),
    /// A declaration or a publication failed.
    #[error("network: {0}")]
    Io(String),
}

/// A loopback TCP endpoint on a port that was free a moment ago (`tcp/127.0.0.1:P`), for a
/// router of this machine's own.
pub fn free_loopback_endpoint() -> Result<String, TransportError> {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").map_err(|e| TransportError::Open(e.to_string()))?;
    let port = listener.local_addr().map_err(|e| TransportError::Open(e.to_string()))?.port();
    Ok(format!("tcp/127.0.0.1:{port}"))
}

/// An open session.
pub struct Session {
    inner: zenoh::Session,
    /// The flight's key: every message sent is sealed with it, and only messages sealed with it
    /// are received (None: plain messages both ways).
    seal: Option<Arc<FlightKey>>,
}

impl std::fmt::Debug for Session {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session").field("zid", &self.inner.zid().to_string()).finish()
    }
}

fn config(role: &Role) -> Result<zenoh::Config, TransportError> {
    let mut c = zenoh::Config::default();
    let json = |v: &[String]| format!("[{}]", v.iter().map(|e| format!("{e:?}")).collect::<Vec<_>>().join(","));
    let mut set = |key: &str, value: String| {
        c.insert_json5(key, &value).map_err(|e| TransportError::Config(format!("{key} = {value}: {e}")))
    };
    set("scouting/multicast/enabled", "false".into())?;
    set("scouting/gossip/enabled", "false".into())?;
    let path = |p: &Path| format!("{:?}", p.display().to_string());
    match role {
        Role::Router { listen, secured } => {
            set("mode", "\"router\"".into())?;
            set("listen/endpoints", json(listen))?;
            if let Some(s) = secured {
                set("transport/link/tls/root_ca_certificate", path(&s.tls.ca))?;
                set("transport/link/tls/listen_certificate", path(&s.tls.cert))?;
                set("transport/link/tls/listen_private_key", path(&s.tls.key))?;
                set("transport/link/tls/enable_mtls", "true".into())?;
                set("transport/link/tls/close_link_on_expiration", "true".into())?;
                set("access_control", s.acl_json5.clone())?;
            }
        }
        Role::Client { connect, wait_for_router, tls } => {
            set("mode", "\"client\"".into())?;
            set("connect/endpoints", json(connect))?;
            set("connect/timeout_ms", wait_for_router.as_millis().to_string())?;
            if let Some(t) = tls {
                set("transport/link/tls/root_ca_certificate", path(&t.ca))?;
                set("transport/link/tls/connect_certificate", path(&t.cert))?;
                set("transport/link/tls/connect_private_key", path(&t.key))?;
                set("transport/link/tls/enable_mtls", "true".into())?;
                set("transport/link/tls/verify_name_on_connect", "true".into())?;
                set("transport/link/tls/close_link_on_expiration", "true".into())?;
            }
        }
    }
    Ok(c)
}

impl Session {
    /// Opens a session in `role`.
    pub fn open(role: &Role) -> Result<Self, TransportError> {
        let inner = zenoh::open(config(role)?).wait().map_err(|e| TransportError::Open(e.to_string()))?;
        Ok(Self { inner, seal: None })
    }

    /// The session sealing with `key` what it sends and taking only what `key` sealed
    /// ([`crate::seal`]); None leaves it plain.
    pub fn sealed(mut self, key: Option<FlightKey>) -> Self {
        self.seal = key.map(Arc::new);
        self
    }

    /// Whether it seals.
    pub fn is_sealed(&self) -> bool {
        self.seal.is_some()
    }

    fn bytes(&self, key: &str, m: &Message) -> Vec<u8> {
        match &self.seal {
            Some(k) => k.seal(key, codec::encode(m)),
            None => codec::encode(m),
        }
    }

    /// A publisher of messages that someone waits for (an update, a command, the clock): when
    /// the link's queue is full it waits for room rather than dropping the message (Zenoh's
    /// default drops it after 1 ms, which a loaded machine reaches: a lockstep answer lost).
    pub fn publisher(&self, key: &str) -> Result<Publisher, TransportError> {
        self.publisher_with(key, CongestionControl::Block)
    }

    /// A publisher of telemetry (states broadcast every period): the newest value wins, so a
    /// message the link has no room for is dropped rather than holding the sender.
    pub fn telemetry(&self, key: &str) -> Result<Publisher, TransportError> {
        self.publisher_with(key, CongestionControl::Drop)
    }

    fn publisher_with(&self, key: &str, congestion: CongestionControl) -> Result<Publisher, TransportError> {
        let inner = self
            .inner
            .declare_publisher(key.to_string())
            .congestion_control(congestion)
            .wait()
            .map_err(|e| TransportError::Io(e.to_string()))?;
        Ok(Publisher { inner, key: key.to_string(), seal: self.seal.clone() })
    }

    /// Puts raw bytes on `key` (for tests of what a broken sender does; a failed put is
    /// ignored).
    pub fn inner_put(&self, key: &str, bytes: Vec<u8>) {
        let _ = self.inner.put(key.to_string(), bytes).wait();
    }

    /// Puts one message on `key` without declaring a publisher (waiting for room on a full
    /// link, as [`Session::publisher`]'s).
    pub fn put(&self, key: &str, m: &Message) -> Result<(), TransportError> {
        self.inner
            .put(key.to_string(), self.bytes(key, m))
            .congestion_control(CongestionControl::Block)
            .wait()
            .map_err(|e| TransportError::Io(e.to_string()))
    }

    /// Closes the session (also done on drop).
    pub fn close(self) {
        let _ = self.inner.close().wait();
    }
}

/// Publishes messages on one key.
pub struct Publisher {
    inner: zenoh::pubsub::Publisher<'static>,
    key: String,
    seal: Option<Arc<FlightKey>>,
}

impl Publisher {
    /// Sends `m` (sealed, on a sealed session).
    pub fn send(&self, m: &Message) -> Result<(), TransportError> {
        let bytes = match &self.seal {
            Some(k) => k.seal(&self.key, codec::encode(m)),
            None => codec::encode(m),
        };
        self.inner.put(bytes).wait().map_err(|e| TransportError::Io(e.to_string()))
    }
}

/// What arrived on a subscription.
#[derive(Debug)]
pub enum Received {
    /// A message, with the key it came on.
    Message(String, Message),
    /// Bytes that are not a message (a foreign or broken sender): reported, not fatal.
    Garbage(String, DecodeError),
    /// A message on a key that is not its own ([`crate::keys::on_its_key`]: a Command for UAV
    /// 3 on UAV 2's key): never delivered as a message, reported.
    Misplaced(String, Message),
}

/// Most bytes of messages an inbox holds before it drops what arrives (a flood, or a reader
/// that stopped): the newest value wins on the wire, so what is dropped is counted, never
/// waited for.
pub const INBOX_MAX_BYTES: usize = 64 << 20;

/// What an inbox holds beside its messages: their bytes now, and how many it dropped.
#[derive(Debug, Default)]
struct Held {
    bytes: AtomicUsize,
    dropped: AtomicU64,
    max_bytes: usize,
}

/// Messages from any number of subscriptions, in arrival order, in one queue of at most
/// [`INBOX_MAX_BYTES`].
pub struct Inbox {
    rx: std::sync::mpsc::Receiver<(usize, Received)>,
    tx: std::sync::mpsc::Sender<(usize, Received)>,
    held: Arc<Held>,
    /// Kept alive: dropping a subscriber undeclares it.
    _subscribers: Vec<zenoh::pubsub::Subscriber<()>>,
}

impl Inbox {
    /// The next message, waiting at most `timeout`; None when nothing came.
    pub fn recv_timeout(&self, timeout: Duration) -> Option<Received> {
        self.rx.recv_timeout(timeout).ok().map(|(n, r)| self.taken(n, r))
    }

    /// The next message if one is waiting.
    pub fn try_recv(&self) -> Option<Received> {
        self.rx.try_recv().ok().map(|(n, r)| self.taken(n, r))
    }

    fn taken(&self, bytes: usize, r: Received) -> Received {
        self.held.bytes.fetch_sub(bytes, Ordering::Relaxed);
        r
    }

    /// Messages dropped because the inbox was full.
    pub fn dropped(&self) -> u64 {
        self.held.dropped.load(Ordering::Relaxed)
    }
}

impl Session {
    /// An inbox receiving every message on `keys` (key expressions: `*` and `**` allowed),
    /// holding at most [`INBOX_MAX_BYTES`].
    pub fn inbox(&self, keys: &[String]) -> Result<Inbox, TransportError> {
        self.inbox_bounded(keys, INBOX_MAX_BYTES)
    }

    /// An inbox holding at most `max_bytes` of messages.
    pub fn inbox_bounded(&self, keys: &[String], max_bytes: usize) -> Result<Inbox, TransportError> {
        let (tx, rx) = std::sync::mpsc::channel();
        let held = Arc::new(Held { max_bytes, ..Held::default() });
        let mut inbox = Inbox { rx, tx, held, _subscribers: Vec::with_capacity(keys.len()) };
        self.subscribe(&mut inbox, keys)?;
        Ok(inbox)
    }

    /// Adds the messages on `keys` to `inbox`.
    pub fn subscribe(&self, inbox: &mut Inbox, keys: &[String]) -> Result<(), TransportError> {
        for key in keys {
            let tx = inbox.tx.clone();
            let held = inbox.held.clone();
            let seal = self.seal.clone();
            let sub = self
                .inner
                .declare_subscriber(key.clone())
                .callback(move |sample| {
                    let key = sample.key_expr().as_str().to_string();
                    let bytes = sample.payload().len() + key.len() + 256;
                    if held.bytes.fetch_add(bytes, Ordering::Relaxed) + bytes > held.max_bytes {
                        held.bytes.fetch_sub(bytes, Ordering::Relaxed);
                        held.dropped.fetch_add(1, Ordering::Relaxed);
                        return;
                    }
                    let payload = sample.payload().to_bytes();
                    let body = match &seal {
                        Some(k) => k.open(&key, &payload).ok_or(DecodeError::Unsealed),
                        None => Ok(&payload[..]),
                    };
                    let received = match body.and_then(codec::decode) {
                        Ok(m) if crate::keys::on_its_key(&key, &m) => Received::Message(key, m),
                        Ok(m) => Received::Misplaced(key, m),
                        Err(e) => Received::Garbage(key, e),
                    };
                    // The inbox is gone only while its owner shuts down.
                    if tx.send((bytes, received)).is_err() {
                        held.bytes.fetch_sub(bytes, Ordering::Relaxed);
                    }
                })
                .wait()
                .map_err(|e| TransportError::Io(e.to_string()))?;
            inbox._subscribers.push(sub);
        }
        Ok(())
    }
}

/// A liveliness token: while it lives (and its session does), subscribers of its key see it
/// alive; when it is dropped, or its process dies and the router loses the connection, they
/// see it gone at once.
pub struct Token {
    _inner: zenoh::liveliness::LivelinessToken,
}

/// A liveliness token appearing or disappearing: its key, and whether it is alive.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Liveliness {
    /// The token's key.
    pub key: String,
    /// Appeared (true) or gone (false).
    pub alive: bool,
}

/// Liveliness changes of the tokens under a key expression, the ones alive at declaration
/// first.
pub struct LivelinessInbox {
    rx: std::sync::mpsc::Receiver<Liveliness>,
    _subscriber: zenoh::pubsub::Subscriber<()>,
}

impl LivelinessInbox {
    /// The next change if one is waiting.
    pub fn try_recv(&self) -> Option<Liveliness> {
        self.rx.try_recv().ok()
    }
}

impl Session {
    /// Declares a liveliness token on `key`.
    pub fn liveliness_token(&self, key: &str) -> Result<Token, TransportError> {
        let inner = self
            .inner
            .liveliness()
            .declare_token(key.to_string())
            .wait()
            .map_err(|e| TransportError::Io(e.to_string()))?;
        Ok(Token { _inner: inner })
    }

    /// Follows the liveliness tokens under `key` (a key expression).
    pub fn liveliness(&self, key: &str) -> Result<LivelinessInbox, TransportError> {
        let (tx, rx) = std::sync::mpsc::channel();
        let sub = self
            .inner
            .liveliness()
            .declare_subscriber(key.to_string())
            .history(true)
            .callback(move |sample| {
                let alive = sample.kind() == zenoh::sample::SampleKind::Put;
                let _ = tx.send(Liveliness { key: sample.key_expr().as_str().to_string(), alive });
            })
            .wait()
            .map_err(|e| TransportError::Io(e.to_string()))?;
        Ok(LivelinessInbox { rx, _subscriber: sub })
    }
}
