//! Bytes of the wire messages (schema [`super::VERSION`]): an 8-byte header — `PXF`, the
//! version, the kind, three zero bytes — then the body, little-endian, fixed layouts (see
//! `docs/wire.md`). Floating-point numbers travel as their IEEE-754 bits, so a state arrives
//! exactly as it was sent. Decoding checks everything a hostile or broken sender could get
//! wrong (length, magic, version, kind, counts, enumerations) and never panics.

use proxform_core::state::{Input, State9, P};
use proxform_core::{Decision, Observation, ObservationSource, Outcome, Setpoint, UavId};

use super::{
    outcome_code, ClockMode, ClockMsg, CommandMsg, MemberMsg, Message, Phase, Presence, SenseMsg, StateMsg,
    MAX_OBSERVATIONS, VERSION,
};

/// The first three bytes of every message.
pub const MAGIC: [u8; 3] = *b"PXF";
/// Header length (bytes).
pub const HEADER: usize = 8;
/// Bytes of one observation in a sense message.
pub const OBSERVATION_BYTES: usize = 4 + 1 + 3 + 8 + 8 * P;

/// Message kinds (byte 4 of the header).
pub mod kind {
    /// [`super::StateMsg`].
    pub const STATE: u8 = 1;
    /// [`super::SenseMsg`].
    pub const SENSE: u8 = 2;
    /// [`super::CommandMsg`].
    pub const COMMAND: u8 = 3;
    /// [`super::ClockMsg`].
    pub const CLOCK: u8 = 4;
    /// [`super::MemberMsg`].
    pub const MEMBER: u8 = 5;
}

/// Why bytes are not a message.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// Fewer bytes than the layout needs.
    #[error("message too short: {got} bytes, {need} needed")]
    TooShort {
        /// Bytes received.
        got: usize,
        /// Bytes needed.
        need: usize,
    },
    /// Bytes after the message's end.
    #[error("message too long: {got} bytes, {expected} expected")]
    TooLong {
        /// Bytes received.
        got: usize,
        /// Bytes expected.
        expected: usize,
    },
    /// Not a proxform message.
    #[error("not a proxform message (no PXF header)")]
    Magic,
    /// Another schema version.
    #[error("schema version {0}, this build reads version {VERSION}")]
    Version(u8),
    /// An unknown message kind.
    #[error("unknown message kind {0}")]
    Kind(u8),
    /// A field outside its range (an enumeration's code, a count, a UAV number).
    #[error("{field}: {value} is out of range")]
    Field {
        /// The field.
        field: &'static str,
        /// Its value.
        value: u64,
    },
    /// On a sealed flight, a message without its flight's tag ([`crate::seal`]): from a
    /// process that does not have the key, or altered on the way.
    #[error("not sealed with this flight's key")]
    Unsealed,
}

struct Writer(Vec<u8>);

impl Writer {
    fn new(kind: u8, body: usize) -> Self {
        let mut v = Vec::with_capacity(HEADER + body);
        v.extend_from_slice(&MAGIC);
        v.extend_from_slice(&[VERSION, kind, 0, 0, 0]);
        Self(v)
    }
    fn u8(&mut self, x: u8) {
        self.0.push(x);
    }
    fn pad(&mut self, n: usize) {
        self.0.extend(std::iter::repeat_n(0, n));
    }
    fn u16(&mut self, x: u16) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn u32(&mut self, x: u32) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn u64(&mut self, x: u64) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn f64(&mut self, x: f64) {
        self.0.extend_from_slice(&x.to_bits().to_le_bytes());
    }
    fn state(&mut self, s: &State9) {
        for v in s.iter() {
            self.f64(*v);
        }
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], DecodeError> {
        let end = self.at + N;
        let slice = self.bytes.get(self.at..end).ok_or(DecodeError::TooShort { got: self.bytes.len(), need: end })?;
        self.at = end;
        let mut out = [0u8; N];
        out.copy_from_slice(slice);
        Ok(out)
    }
    fn u8(&mut self) -> Result<u8, DecodeError> {
        Ok(self.take::<1>()?[0])
    }
    fn skip(&mut self, n: usize) -> Result<(), DecodeError> {
        let end = self.at + n;
        if end > self.bytes.len() {
            return Err(DecodeError::TooShort { got: self.bytes.len(), need: end });
        }
        self.at = end;
        Ok(())
    }
    fn u16(&mut self) -> Result<u16, DecodeError> {
        Ok(u16::from_le_bytes(self.take()?))
    }
    fn u32(&mut self) -> Result<u32, DecodeError> {
        Ok(u32::from_le_bytes(self.take()?))
    }
    fn u64(&mut self) -> Result<u64, DecodeError> {
        Ok(u64::from_le_bytes(self.take()?))
    }
    fn f64(&mut self) -> Result<f64, DecodeError> {
        Ok(f64::from_bits(self.u64()?))
    }
    fn state(&mut self) -> Result<State9, DecodeError> {
        let mut s = State9::zeros();
        for k in 0..P {
            s[k] = self.f64()?;
        }
        Ok(s)
    }
    /// A UAV number (from 1) as an id (from 0).
    fn uav(&mut self, field: &'static str) -> Result<u32, DecodeError> {
        match self.u32()? {
            0 => Err(DecodeError::Field { field, value: 0 }),
            n => Ok(n),
        }
    }
    fn end(&self) -> Result<(), DecodeError> {
        match self.at == self.bytes.len() {
            true => Ok(()),
            false => Err(DecodeError::TooLong { got: self.bytes.len(), expected: self.at }),
        }
    }
}

/// The message as bytes.
pub fn encode(m: &Message) -> Vec<u8> {
    match m {
        Message::State(s) => {
            let mut w = Writer::new(kind::STATE, 100);
            w.u32(s.uav);
            w.u64(s.k);
            w.f64(s.t_s);
            w.state(&s.state);
            w.u8(u8::from(s.rejoining));
            w.pad(7);
            w.0
        }
        Message::Sense(s) => {
            let mut w = Writer::new(kind::SENSE, 104 + s.heard.len() * OBSERVATION_BYTES);
            w.u32(s.uav);
            w.u32(s.run);
            w.u8(match s.phase {
                Phase::Warm => 0,
                Phase::Fly => 1,
            });
            w.pad(3);
            w.u32(s.heard.len() as u32);
            w.u64(s.k);
            w.f64(s.t_s);
            w.state(&s.own);
            for o in &s.heard {
                w.u32(o.id.0 + 1);
                w.u8(match o.source {
                    ObservationSource::Onboard => 0,
                    ObservationSource::Radio => 1,
                    ObservationSource::Close => 2,
                    ObservationSource::Relayed => 3,
                });
                w.pad(3);
                w.f64(o.age_s);
                w.state(&o.state);
            }
            w.0
        }
        Message::Command(c) => {
            let mut w = Writer::new(kind::COMMAND, 144);
            let d = &c.decision;
            w.u32(c.uav);
            w.u32(c.run);
            w.u64(c.k);
            w.f64(c.t_s);
            w.f64(c.age_s);
            w.u8(outcome_code(&d.outcome));
            w.u8(u8::from(d.own_suspect));
            w.u16(d.isolated);
            w.u16(d.occupied_areas);
            w.u16(d.main_refs);
            w.f64(match d.outcome {
                Outcome::Adjusted { normalised_sq } => normalised_sq,
                _ => 0.0,
            });
            for u in d.input.iter() {
                w.f64(*u);
            }
            w.u8(u8::from(d.setpoint.is_some()));
            w.pad(7);
            let sp = d.setpoint.unwrap_or(Setpoint { velocity_mps: [0.0; 3], yaw_rad: 0.0 });
            for v in sp.velocity_mps {
                w.f64(v);
            }
            w.f64(sp.yaw_rad);
            w.u64(c.digest);
            w.0
        }
        Message::Clock(c) => {
            let mut w = Writer::new(kind::CLOCK, 40);
            w.u8(match c.mode {
                ClockMode::Lockstep => 0,
                ClockMode::RealTime => 1,
            });
            w.u8(u8::from(c.end));
            w.pad(2);
            w.u32(c.run);
            w.u64(c.k);
            w.f64(c.t_s);
            w.f64(c.dt_s);
            w.u64(c.epoch_ns);
            w.0
        }
        Message::Member(m) => {
            let mut w = Writer::new(kind::MEMBER, 20);
            w.u32(m.uav);
            w.u8(match m.presence {
                Presence::Alive => 0,
                Presence::Leaving => 1,
            });
            w.pad(3);
            w.u32(m.pid);
            w.u64(m.digest);
            w.0
        }
    }
}

/// Bytes as a message, or why they are not one.
pub fn decode(bytes: &[u8]) -> Result<Message, DecodeError> {
    let mut r = Reader { bytes, at: 0 };
    let head = r.take::<HEADER>()?;
    if head[..3] != MAGIC {
        return Err(DecodeError::Magic);
    }
    if head[3] != VERSION {
        return Err(DecodeError::Version(head[3]));
    }
    let m = match head[4] {
        kind::STATE => {
            let (uav, k, t_s, state) = (r.uav("uav")?, r.u64()?, r.f64()?, r.state()?);
            let rejoining = match r.u8()? {
                0 => false,
                1 => true,
                v => return Err(DecodeError::Field { field: "rejoining", value: v.into() }),
            };
            r.skip(7)?;
            Message::State(StateMsg { uav, k, t_s, state, rejoining })
        }
        kind::SENSE => {
            let uav = r.uav("uav")?;
            let run = r.u32()?;
            let phase = match r.u8()? {
                0 => Phase::Warm,
                1 => Phase::Fly,
                v => return Err(DecodeError::Field { field: "phase", value: v.into() }),
            };
            r.skip(3)?;
            let n = r.u32()? as usize;
            if n > MAX_OBSERVATIONS {
                return Err(DecodeError::Field { field: "observations", value: n as u64 });
            }
            let (k, t_s, own) = (r.u64()?, r.f64()?, r.state()?);
            // The count must match the bytes before anything is allocated for it.
            let expected = r.at + n * OBSERVATION_BYTES;
            if bytes.len() < expected {
                return Err(DecodeError::TooShort { got: bytes.len(), need: expected });
            }
            let mut heard = Vec::with_capacity(n);
            for _ in 0..n {
                let id = UavId(r.uav("observation uav")? - 1);
                let source = match r.u8()? {
                    0 => ObservationSource::Onboard,
                    1 => ObservationSource::Radio,
                    2 => ObservationSource::Close,
                    3 => ObservationSource::Relayed,
                    v => return Err(DecodeError::Field { field: "observation source", value: v.into() }),
                };
                r.skip(3)?;
                let age_s = r.f64()?;
                heard.push(Observation { id, state: r.state()?, age_s, source });
            }
            Message::Sense(SenseMsg { uav, run, phase, k, t_s, own, heard })
        }
        kind::COMMAND => {
            let (uav, run, k, t_s, age_s) = (r.uav("uav")?, r.u32()?, r.u64()?, r.f64()?, r.f64()?);
            let code = r.u8()?;
            let own_suspect = match r.u8()? {
                0 => false,
                1 => true,
                v => return Err(DecodeError::Field { field: "own_suspect", value: v.into() }),
            };
            let isolated = r.u16()?;
            let (occupied_areas, main_refs, normalised_sq) = (r.u16()?, r.u16()?, r.f64()?);
            let outcome = match code {
                0 => Outcome::Held,
                1 => Outcome::Adjusted { normalised_sq },
                2 => Outcome::Alone,
                v => return Err(DecodeError::Field { field: "outcome", value: v.into() }),
            };
            let mut input = Input::zeros();
            for j in 0..input.len() {
                input[j] = r.f64()?;
            }
            let has_setpoint = match r.u8()? {
                0 => false,
                1 => true,
                v => return Err(DecodeError::Field { field: "setpoint flag", value: v.into() }),
            };
            r.skip(7)?;
            let velocity_mps = [r.f64()?, r.f64()?, r.f64()?];
            let yaw_rad = r.f64()?;
            let setpoint = has_setpoint.then_some(Setpoint { velocity_mps, yaw_rad });
            // (How far the UAV was from its place is the agent's own: not on the wire.)
            let decision =
                Decision { outcome, input, occupied_areas, main_refs, isolated, own_suspect, gap_sq: 0.0, setpoint };
            Message::Command(CommandMsg { uav, run, k, t_s, age_s, decision, digest: r.u64()? })
        }
        kind::CLOCK => {
            let mode = match r.u8()? {
                0 => ClockMode::Lockstep,
                1 => ClockMode::RealTime,
                v => return Err(DecodeError::Field { field: "clock mode", value: v.into() }),
            };
            let end = match r.u8()? {
                0 => false,
                1 => true,
                v => return Err(DecodeError::Field { field: "end", value: v.into() }),
            };
            r.skip(2)?;
            Message::Clock(ClockMsg {
                mode,
                end,
                run: r.u32()?,
                k: r.u64()?,
                t_s: r.f64()?,
                dt_s: r.f64()?,
                epoch_ns: r.u64()?,
            })
        }
        kind::MEMBER => {
            let uav = r.uav("uav")?;
            let presence = match r.u8()? {
                0 => Presence::Alive,
                1 => Presence::Leaving,
                v => return Err(DecodeError::Field { field: "presence", value: v.into() }),
            };
            r.skip(3)?;
            Message::Member(MemberMsg { uav, presence, pid: r.u32()?, digest: r.u64()? })
        }
        other => return Err(DecodeError::Kind(other)),
    };
    r.end()?;
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(seed: f64) -> State9 {
        State9::from_fn(|k, _| seed * (k as f64 + 1.0) - 3.0 + 1e-13 * k as f64)
    }

    fn samples() -> Vec<Message> {
        let obs = |id, source| Observation { id: UavId(id), state: state(id as f64 + 0.5), age_s: 0.1, source };
        vec![
            Message::State(StateMsg { uav: 3, k: 17, t_s: 1.7, state: state(1.0), rejoining: true }),
            Message::Sense(SenseMsg {
                uav: 2,
                run: 4,
                phase: Phase::Fly,
                k: 9,
                t_s: 0.9,
                own: state(2.0),
                heard: vec![obs(0, ObservationSource::Onboard), obs(5, ObservationSource::Radio)],
            }),
            Message::Sense(SenseMsg {
                uav: 1,
                run: 4,
                phase: Phase::Fly,
                k: 9,
                t_s: 0.9,
                own: state(3.0),
                heard: vec![obs(4, ObservationSource::Close), obs(6, ObservationSource::Relayed)],
            }),
            Message::Sense(SenseMsg {
                uav: 7,
                run: 0,
                phase: Phase::Warm,
                k: 0,
                t_s: -1.0,
                own: state(-1.0),
                heard: vec![],
            }),
            Message::Command(CommandMsg {
                uav: 5,
                run: 1,
                k: 3,
                t_s: 0.3,
                age_s: 0.0004,
                decision: Decision {
                    outcome: Outcome::Adjusted { normalised_sq: 1.25 },
                    input: Input::from_fn(|j, _| j as f64 * -0.01),
                    occupied_areas: 4,
                    main_refs: 2,
                    isolated: 1,
                    own_suspect: true,
                    gap_sq: 0.0,
                    setpoint: Some(Setpoint { velocity_mps: [20.0, -1.5, 0.25], yaw_rad: -3.0 }),
                },
                digest: 0x0123_4567_89ab_cdef,
            }),
            Message::Command(CommandMsg {
                uav: 5,
                run: 1,
                k: 4,
                t_s: 0.4,
                age_s: 0.0,
                decision: Decision::alone(),
                digest: 0,
            }),
            Message::Clock(ClockMsg {
                mode: ClockMode::RealTime,
                run: 2,
                k: 5,
                t_s: 0.5,
                dt_s: 0.1,
                epoch_ns: 1_700_000_000_000_000_000,
                end: true,
            }),
            Message::Member(MemberMsg { uav: 9, presence: Presence::Leaving, pid: 4242, digest: 0xfeed_beef_0123 }),
        ]
    }

    #[test]
    fn every_message_comes_back_bit_for_bit() {
        for m in samples() {
            let bytes = encode(&m);
            assert_eq!(&bytes[..3], b"PXF");
            assert_eq!(decode(&bytes).as_ref(), Ok(&m));
        }
        // Layouts as docs/wire.md gives them.
        let lens: Vec<usize> = samples().iter().map(|m| encode(m).len()).collect();
        assert_eq!(lens, [108, 112 + 2 * OBSERVATION_BYTES, 112 + 2 * OBSERVATION_BYTES, 112, 152, 152, 48, 28]);
        // NaN payloads and signed zeros survive (bits, not values).
        let odd = Message::State(StateMsg {
            uav: 1,
            k: 0,
            t_s: -0.0,
            state: State9::repeat(f64::from_bits(0x7ff8_dead_beef_0001)),
            rejoining: false,
        });
        match decode(&encode(&odd)) {
            Ok(Message::State(s)) => {
                assert_eq!(s.t_s.to_bits(), (-0.0f64).to_bits());
                assert!(s.state.iter().all(|v| v.to_bits() == 0x7ff8_dead_beef_0001));
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn broken_bytes_are_refused_without_panicking() {
        for m in samples() {
            let bytes = encode(&m);
            // Every truncation, and one byte too many.
            for n in 0..bytes.len() {
                assert!(decode(&bytes[..n]).is_err(), "{n} of {} bytes of {m:?}", bytes.len());
            }
            let mut long = bytes.clone();
            long.push(0);
            assert!(matches!(decode(&long), Err(DecodeError::TooLong { .. })));
            // Every single byte changed: an error or another valid message, never a panic.
            for i in 0..bytes.len() {
                for v in [0u8, 1, 2, 3, 0x7f, 0xff] {
                    let mut b = bytes.clone();
                    b[i] = v;
                    let _ = decode(&b);
                }
            }
        }
        assert_eq!(decode(b"XYZ\x01\x01\0\0\0"), Err(DecodeError::Magic));
        assert_eq!(decode(b"PXF\x02\x01\0\0\0"), Err(DecodeError::Version(2)));
        assert_eq!(decode(b"PXF\x01\x09\0\0\0"), Err(DecodeError::Kind(9)));
        // A sense message that claims more observations than it carries allocates nothing.
        let mut claim = encode(&samples()[2]);
        claim[20..24].copy_from_slice(&(MAX_OBSERVATIONS as u32).to_le_bytes());
        assert!(matches!(decode(&claim), Err(DecodeError::TooShort { .. })));
        claim[20..24].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(decode(&claim), Err(DecodeError::Field { field: "observations", .. })));
        // UAV number 0 does not exist.
        let mut zero = encode(&samples()[0]);
        zero[8..12].copy_from_slice(&0u32.to_le_bytes());
        assert!(matches!(decode(&zero), Err(DecodeError::Field { field: "uav", .. })));
    }
}
