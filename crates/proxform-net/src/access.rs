//! Who may do what on a swarm's network: the parties of a swarm (the world, each UAV's agent,
//! observers), the names their certificates carry, and the access rules the world's router
//! enforces on everything that reaches it over an authenticated (mutual TLS) link.
//!
//! The world is the router every agent connects to, so it sees every message first. It accepts
//! from a peer whose certificate names UAV N only what UAV N's agent sends (its state, its
//! command, its membership, its liveliness token) and subscriptions under the swarm's prefix;
//! from an observer only subscriptions; from anyone else nothing. A peer without a certificate
//! of the swarm's authority never completes the TLS handshake. What the world itself publishes
//! (clock, senses, the navigator's state) is local to it and goes out to every party.

use crate::keys::Swarm;

/// One party of a swarm, as its certificate's common name says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Party {
    /// The world (the router): serves the clock, the senses and the navigator.
    World,
    /// UAV N's agent (N from 1).
    Uav(u32),
    /// A program that reads the swarm's traffic and publishes nothing (a viewer, a logger).
    Observer,
}

impl Party {
    /// The certificate's common name: `world`, `uav-N` or `observer`.
    pub fn common_name(&self) -> String {
        match self {
            Party::World => "world".into(),
            Party::Uav(n) => format!("uav-{n}"),
            Party::Observer => "observer".into(),
        }
    }

    /// The file stem of its certificate and key (`uav-3` → `uav-3.pem`, `uav-3.key`).
    pub fn file_stem(&self) -> String {
        self.common_name()
    }
}

/// Every message kind Zenoh's access control knows, for the rule that lets the world's own
/// traffic out.
const ALL_MESSAGES: &str = "\"put\", \"delete\", \"declare_subscriber\", \"query\", \"declare_queryable\", \"reply\", \
                            \"liveliness_token\", \"declare_liveliness_subscriber\", \"liveliness_query\"";

/// What reading a swarm takes: subscriptions and liveliness queries.
const READ_MESSAGES: &str = "\"declare_subscriber\", \"declare_liveliness_subscriber\", \"liveliness_query\"";

/// The Zenoh `access_control` section (JSON5) of a world serving `swarm` with UAVs 1 to
/// `uavs` whose navigator is `navigator`: deny by default; everything under the swarm's prefix
/// may go out; each UAV's agent (`uav-N`, not the navigator's, which the world flies) may send
/// its own state, command, membership and liveliness token and subscribe to the swarm; an
/// `observer` may subscribe.
pub fn acl_json5(swarm: &Swarm, uavs: u32, navigator: u32) -> String {
    let base = format!("proxform/v1/{}", swarm.name());
    let mut rules = vec![
        format!(
            "{{ id: \"out\", messages: [{ALL_MESSAGES}], flows: [\"egress\"], permission: \"allow\", \
             key_exprs: [\"{base}/**\"] }}"
        ),
        format!(
            "{{ id: \"read\", messages: [{READ_MESSAGES}], flows: [\"ingress\"], permission: \"allow\", \
             key_exprs: [\"{base}/**\"] }}"
        ),
    ];
    let mut subjects =
        vec!["{ id: \"anyone\" }".to_string(), "{ id: \"observer\", cert_common_names: [\"observer\"] }".into()];
    let mut policies = vec![
        "{ id: \"out\", rules: [\"out\"], subjects: [\"anyone\"] }".to_string(),
        "{ id: \"observers\", rules: [\"read\"], subjects: [\"observer\"] }".into(),
    ];
    let mut readers = Vec::new();
    for n in (1..=uavs).filter(|n| *n != navigator) {
        let cn = Party::Uav(n).common_name();
        rules.push(format!(
            "{{ id: \"own-{n}\", messages: [\"put\", \"liveliness_token\"], flows: [\"ingress\"], permission: \
             \"allow\", key_exprs: [\"{base}/uav/{n}/state\", \"{base}/uav/{n}/cmd\", \"{base}/member/{n}\", \
             \"{base}/alive/{n}\"] }}"
        ));
        subjects.push(format!("{{ id: \"{cn}\", cert_common_names: [\"{cn}\"] }}"));
        policies.push(format!("{{ id: \"own-{n}\", rules: [\"own-{n}\"], subjects: [\"{cn}\"] }}"));
        readers.push(format!("\"{cn}\""));
    }
    if !readers.is_empty() {
        policies.push(format!("{{ id: \"agents\", rules: [\"read\"], subjects: [{}] }}", readers.join(", ")));
    }
    format!(
        "{{ enabled: true, default_permission: \"deny\", rules: [{}], subjects: [{}], policies: [{}] }}",
        rules.join(", "),
        subjects.join(", "),
        policies.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rules_name_each_uav_its_own_keys_only() {
        let s = Swarm::new("lab").expect("name");
        let acl = acl_json5(&s, 4, 1);
        assert!(acl.contains("default_permission: \"deny\""));
        assert!(acl.contains("\"proxform/v1/lab/uav/3/cmd\""));
        assert!(!acl.contains("uav/1/cmd"), "the navigator has no agent: {acl}");
        // Nobody is allowed the clock or the senses on the way in.
        let own: Vec<&str> = acl.split("id: \"own-").skip(1).collect();
        assert_eq!(own.len(), 6, "three rules and three policies");
        for r in own {
            assert!(!r.contains("/clock") && !r.contains("/sense"), "{r}");
        }
        assert_eq!(Party::Uav(12).common_name(), "uav-12");
    }
}
