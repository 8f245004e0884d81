//! The key expressions of a swarm (schema version 1): everything of swarm `S` lives under
//! `proxform/v1/S/`, so that several swarms share a network and a program subscribes to all of
//! one with `proxform/v1/S/**`.
//!
//! | key | message | from → to |
//! | --- | --- | --- |
//! | `proxform/v1/S/uav/N/state` | [`crate::wire::StateMsg`] | UAV N (its agent; the world for the navigator) → anyone |
//! | `proxform/v1/S/uav/N/sense` | [`crate::wire::SenseMsg`] | the world (or UAV N's sensors) → UAV N's agent |
//! | `proxform/v1/S/uav/N/cmd` | [`crate::wire::CommandMsg`] | UAV N's agent → the world (or its autopilot) |
//! | `proxform/v1/S/clock` | [`crate::wire::ClockMsg`] | the world → everyone |
//! | `proxform/v1/S/member/N` | [`crate::wire::MemberMsg`] | UAV N's agent → the world |
//! | `proxform/v1/S/alive/N` | a Zenoh liveliness token (no payload) | held by UAV N's agent while its session lives |

/// A swarm's name as it appears in keys: letters, digits, `-` and `_`, 1 to 64 characters.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Swarm(String);

/// A swarm name that cannot be part of a key.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("swarm name {0:?}: 1 to 64 letters, digits, '-' or '_'")]
pub struct BadSwarmName(pub String);

impl Swarm {
    /// Checks `name`.
    pub fn new(name: &str) -> Result<Self, BadSwarmName> {
        let ok =
            (1..=64).contains(&name.len()) && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
        match ok {
            true => Ok(Self(name.to_string())),
            false => Err(BadSwarmName(name.to_string())),
        }
    }

    /// The name.
    pub fn name(&self) -> &str {
        &self.0
    }

    fn base(&self) -> String {
        format!("proxform/v1/{}", self.0)
    }

    /// UAV `uav`'s (from 1) broadcast state.
    pub fn state(&self, uav: u32) -> String {
        format!("{}/uav/{uav}/state", self.base())
    }

    /// Every UAV's broadcast state.
    pub fn all_states(&self) -> String {
        format!("{}/uav/*/state", self.base())
    }

    /// What reaches UAV `uav`'s agent.
    pub fn sense(&self, uav: u32) -> String {
        format!("{}/uav/{uav}/sense", self.base())
    }

    /// UAV `uav`'s commands.
    pub fn command(&self, uav: u32) -> String {
        format!("{}/uav/{uav}/cmd", self.base())
    }

    /// Every UAV's commands.
    pub fn all_commands(&self) -> String {
        format!("{}/uav/*/cmd", self.base())
    }

    /// The world's clock.
    pub fn clock(&self) -> String {
        format!("{}/clock", self.base())
    }

    /// UAV `uav`'s membership.
    pub fn member(&self, uav: u32) -> String {
        format!("{}/member/{uav}", self.base())
    }

    /// UAV `uav`'s liveliness token.
    pub fn alive(&self, uav: u32) -> String {
        format!("{}/alive/{uav}", self.base())
    }

    /// Every UAV's liveliness token.
    pub fn all_alive(&self) -> String {
        format!("{}/alive/*", self.base())
    }

    /// Every UAV's membership.
    pub fn all_members(&self) -> String {
        format!("{}/member/*", self.base())
    }
}

/// Whether `m` came on its own key, as the table above says: a State, Sense or Command on its
/// UAV's key, a Member on its UAV's membership key, a Clock on the clock's. A message naming
/// another UAV than its key (a Command for UAV 3 put on UAV 2's key, the one key an
/// authenticated UAV 2 may publish on) is not its UAV's and is never taken as such.
pub fn on_its_key(key: &str, m: &crate::wire::Message) -> bool {
    use crate::wire::Message;
    let (tail, uav) = match m {
        Message::State(s) => ("state", Some(s.uav)),
        Message::Sense(s) => ("sense", Some(s.uav)),
        Message::Command(c) => ("cmd", Some(c.uav)),
        Message::Member(m) => ("member", Some(m.uav)),
        Message::Clock(_) => ("clock", None),
    };
    let mut parts = key.rsplit('/');
    match (tail, uav) {
        ("clock", _) => parts.next() == Some("clock"),
        ("member", Some(n)) => parts.next() == Some(n.to_string().as_str()) && parts.next() == Some("member"),
        (t, Some(n)) => {
            parts.next() == Some(t) && parts.next() == Some(n.to_string().as_str()) && parts.next() == Some("uav")
        }
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_message_is_its_keys_only() {
        use crate::wire::{MemberMsg, Message, Presence};
        let s = Swarm::new("lab").expect("name");
        let member = |uav| Message::Member(MemberMsg { uav, presence: Presence::Leaving, pid: 1, digest: 0 });
        assert!(on_its_key(&s.member(3), &member(3)));
        assert!(!on_its_key(&s.member(2), &member(3)), "UAV 3 leaving, said on UAV 2's key");
        assert!(!on_its_key(&s.member(13), &member(3)));
        assert!(!on_its_key(&s.clock(), &member(3)));
        assert!(!on_its_key(&s.command(3), &member(3)));
    }

    #[test]
    fn names_that_would_escape_their_keys_are_refused() {
        for bad in ["", "a/b", "a*", "$x", "**", "a b", &"x".repeat(65), "ü"] {
            assert!(Swarm::new(bad).is_err(), "{bad:?}");
        }
        let s = Swarm::new("lab-1_a").expect("valid");
        assert_eq!(s.state(3), "proxform/v1/lab-1_a/uav/3/state");
        assert_eq!(s.all_commands(), "proxform/v1/lab-1_a/uav/*/cmd");
        assert_eq!(s.member(12), "proxform/v1/lab-1_a/member/12");
    }
}
