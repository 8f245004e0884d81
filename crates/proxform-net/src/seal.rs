//! A flight's key: every message of a sealed flight carries, after its bytes, an HMAC-SHA256
//! tag over the key expression it travels on and those bytes, made with a key of 32 random
//! bytes that the world draws for the flight and gives to its agents only (the agents it
//! launches in their environment, [`ENV`]; agents started elsewhere in a file of their
//! owner's, `--flight-key FILE`). A process without the key can read a sealed flight but not
//! speak in it: whatever it publishes, a forged Command, Clock end, Member or Sense, fails the
//! tag and is counted as garbage, never taken. Replays of a flight's own messages are met by
//! the receivers (an agent steps on each update once; the world takes a command for the step
//! it is at). Mutual TLS (`--tls`) also keeps outsiders from reading; the seal keeps them from
//! writing on plain links (loopback, a trusted network).

use ring::hmac;

/// The environment variable in which a launched agent finds its flight's key (hex).
pub const ENV: &str = "PROXFORM_FLIGHT_KEY";

/// Bytes of the tag after a sealed message.
pub const TAG_BYTES: usize = 32;

/// Why a key could not be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum KeyError {
    /// Not 64 hexadecimal digits.
    #[error("a flight key is 64 hexadecimal digits (32 bytes), found {0} characters that are not")]
    Format(usize),
    /// No randomness from the system.
    #[error("the system gave no random bytes for a flight key")]
    Random,
    /// A key file that cannot be read or written as one.
    #[error("{0}")]
    File(String),
    /// A key anyone could guess (every byte the same).
    #[error("a flight key of one byte repeated is no secret: make one with --flight-key NEW_FILE")]
    Weak,
}

/// The key of [`ENV`] in this process's environment, if it is set.
pub fn from_env() -> Result<Option<FlightKey>, KeyError> {
    match std::env::var(ENV) {
        Ok(hex) => FlightKey::from_hex(&hex).map(Some),
        Err(std::env::VarError::NotPresent) => Ok(None),
        Err(std::env::VarError::NotUnicode(_)) => Err(KeyError::Format(0)),
    }
}

/// The key in file `path`: a regular file (not a link, FIFO or device) of at most 1 KiB.
pub fn read_key_file(path: &std::path::Path) -> Result<FlightKey, KeyError> {
    let io = |e: std::io::Error| KeyError::File(format!("cannot read {}: {e}", path.display()));
    let meta = std::fs::symlink_metadata(path).map_err(io)?;
    if !meta.is_file() || meta.len() > 1024 {
        return Err(KeyError::File(format!("{} is not a key file (a regular file of 64 hex digits)", path.display())));
    }
    // Readable by others, it is not the owner's secret (as ssh refuses such a key).
    use std::os::unix::fs::PermissionsExt;
    let mode = meta.permissions().mode() & 0o777;
    if mode & 0o077 != 0 {
        return Err(KeyError::File(format!(
            "{} can be read by others (mode {mode:o}): a flight key must be its owner's alone (chmod 600 {})",
            path.display(),
            path.display()
        )));
    }
    FlightKey::from_hex(&std::fs::read_to_string(path).map_err(io)?)
}

/// A new key written to `path`, which must not exist (created readable by its owner only,
/// never through a link), or the key already there.
pub fn key_file(path: &std::path::Path) -> Result<FlightKey, KeyError> {
    use std::io::Write;
    use std::os::unix::fs::OpenOptionsExt;
    if std::fs::symlink_metadata(path).is_ok() {
        return read_key_file(path);
    }
    let key = FlightKey::generate()?;
    let io = |e: std::io::Error| KeyError::File(format!("cannot write {}: {e}", path.display()));
    let mut f = std::fs::OpenOptions::new().write(true).create_new(true).mode(0o600).open(path).map_err(io)?;
    writeln!(f, "{}", key.hex()).map_err(io)?;
    Ok(key)
}

/// A flight's key.
#[derive(Clone)]
pub struct FlightKey {
    hex: String,
    key: hmac::Key,
}

impl std::fmt::Debug for FlightKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("FlightKey(…)")
    }
}

impl FlightKey {
    /// A new key of 32 random bytes from the system.
    pub fn generate() -> Result<Self, KeyError> {
        use ring::rand::SecureRandom;
        let mut bytes = [0u8; 32];
        ring::rand::SystemRandom::new().fill(&mut bytes).map_err(|_| KeyError::Random)?;
        Ok(Self::from_bytes(&bytes))
    }

    fn from_bytes(bytes: &[u8; 32]) -> Self {
        let hex = bytes.iter().map(|b| format!("{b:02x}")).collect();
        Self { hex, key: hmac::Key::new(hmac::HMAC_SHA256, bytes) }
    }

    /// The key from its 64 hexadecimal digits (surrounding white space ignored).
    pub fn from_hex(text: &str) -> Result<Self, KeyError> {
        let t = text.trim();
        let digit = |c: u8| (c as char).to_digit(16);
        if t.len() != 64 || !t.bytes().all(|c| digit(c).is_some()) {
            return Err(KeyError::Format(t.chars().count()));
        }
        let mut bytes = [0u8; 32];
        for (i, pair) in t.as_bytes().chunks(2).enumerate() {
            bytes[i] = (digit(pair[0]).unwrap_or(0) * 16 + digit(pair[1]).unwrap_or(0)) as u8;
        }
        if bytes.iter().all(|b| *b == bytes[0]) {
            return Err(KeyError::Weak);
        }
        Ok(Self::from_bytes(&bytes))
    }

    /// Its 64 hexadecimal digits (for a launched agent's environment, or a key file).
    pub fn hex(&self) -> &str {
        &self.hex
    }

    /// What a tag covers: the key expression (its length first) and the message's bytes.
    fn signed(key_expr: &str, body: &[u8]) -> Vec<u8> {
        let mut signed = Vec::with_capacity(8 + key_expr.len() + body.len());
        signed.extend_from_slice(&(key_expr.len() as u64).to_le_bytes());
        signed.extend_from_slice(key_expr.as_bytes());
        signed.extend_from_slice(body);
        signed
    }

    /// `body` sealed for `key_expr`: the body, then its tag.
    pub fn seal(&self, key_expr: &str, mut body: Vec<u8>) -> Vec<u8> {
        let tag = hmac::sign(&self.key, &Self::signed(key_expr, &body));
        body.extend_from_slice(tag.as_ref());
        body
    }

    /// The body of `bytes` if its tag is this key's for `key_expr` (checked in constant time);
    /// None for anything else (no tag, another key, another key expression, altered bytes).
    pub fn open<'a>(&self, key_expr: &str, bytes: &'a [u8]) -> Option<&'a [u8]> {
        let body_len = bytes.len().checked_sub(TAG_BYTES)?;
        let (body, tag) = bytes.split_at(body_len);
        // `verify` recomputes the tag and compares in constant time.
        hmac::verify(&self.key, &Self::signed(key_expr, body), tag).ok().map(|()| body)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_key_opens_what_it_sealed_on_its_key_expression() {
        let k = FlightKey::generate().expect("random");
        let sealed = k.seal("proxform/v1/s/uav/3/cmd", b"PXF command".to_vec());
        assert_eq!(sealed.len(), 11 + TAG_BYTES);
        assert_eq!(k.open("proxform/v1/s/uav/3/cmd", &sealed), Some(&b"PXF command"[..]));
        // Another key expression, another key, an altered byte, no tag: refused.
        assert_eq!(k.open("proxform/v1/s/uav/2/cmd", &sealed), None);
        let other = FlightKey::generate().expect("random");
        assert_eq!(other.open("proxform/v1/s/uav/3/cmd", &sealed), None);
        let mut altered = sealed.clone();
        altered[4] ^= 1;
        assert_eq!(k.open("proxform/v1/s/uav/3/cmd", &altered), None);
        assert_eq!(k.open("proxform/v1/s/uav/3/cmd", b"PXF command"), None);
        assert_eq!(k.open("proxform/v1/s/uav/3/cmd", b""), None);
        // Its hex gives it back; anything else is refused.
        let again = FlightKey::from_hex(&format!(" {}\n", k.hex())).expect("hex");
        assert_eq!(again.open("proxform/v1/s/uav/3/cmd", &sealed), Some(&b"PXF command"[..]));
        assert_eq!(FlightKey::from_hex("abc").map(|_| ()), Err(KeyError::Format(3)));
        assert!(FlightKey::from_hex(&"g".repeat(64)).is_err());
        assert_eq!(FlightKey::from_hex(&"0".repeat(64)).map(|_| ()), Err(KeyError::Weak));
        assert_ne!(k.hex(), other.hex());
    }

    #[test]
    fn a_key_file_others_can_read_is_refused() {
        use std::os::unix::fs::PermissionsExt;
        let dir = std::env::temp_dir().join(format!("proxform-key-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("a folder");
        let path = dir.join("flight.key");
        let made = key_file(&path).expect("a new key, 0600");
        assert_eq!(read_key_file(&path).map(|k| k.hex().to_string()).ok(), Some(made.hex().to_string()));
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o644)).expect("chmod");
        let e = read_key_file(&path).map(|_| ()).expect_err("world-readable");
        assert!(e.to_string().contains("can be read by others (mode 644)"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
