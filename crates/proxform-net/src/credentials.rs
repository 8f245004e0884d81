//! A swarm's certificates: its own authority (a CA made for the swarm alone) and, signed by it,
//! one certificate and private key per party ([`Party`]): the world's (a server and a client,
//! valid for the host names and addresses it is reached at), each UAV agent's and an
//! observer's. Each party's common name is what the world's access rules ([`crate::access`])
//! match. Text only (PEM): writing the files is the caller's.

use crate::access::Party;

/// A certificate and its private key, in PEM.
#[derive(Debug, Clone)]
pub struct Issued {
    /// Whose it is.
    pub party: Party,
    /// The certificate (PEM).
    pub cert_pem: String,
    /// Its private key (PKCS#8 PEM): secret, for that party alone.
    pub key_pem: String,
}

/// A swarm's authority and the certificates it issued.
#[derive(Debug, Clone)]
pub struct SwarmCredentials {
    /// The authority's certificate (PEM): every party trusts it.
    pub ca_pem: String,
    /// The authority's private key (PEM): keep it offline; it issues certificates.
    pub ca_key_pem: String,
    /// The world's, every UAV agent's (but the navigator's) and an observer's.
    pub issued: Vec<Issued>,
}

/// Certificates could not be made.
#[derive(Debug, thiserror::Error)]
pub enum CredentialError {
    /// A host name that cannot be a certificate's subject name.
    #[error("host {0:?}: not a DNS name or an IP address")]
    Host(String),
    /// What the certificate library refused.
    #[error("cannot make certificates: {0}")]
    Make(String),
}

/// The validity of the certificates: from `from_day` to `from_day + days` (days since
/// 1970-01-01, UTC).
#[derive(Debug, Clone, Copy)]
pub struct Validity {
    /// First day.
    pub from_day: i64,
    /// Length in days.
    pub days: u32,
}

/// (year, month, day) of a day counted from 1970-01-01 (the proleptic Gregorian calendar).
fn civil_from_days(z: i64) -> (i32, u8, u8) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u8;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u8;
    let y = (yoe + era * 400 + i64::from(m <= 2)) as i32;
    (y, m, d)
}

/// An IP address, or a DNS name: labels of 1 to 63 letters, digits and '-' (not at either
/// end), joined by dots, 253 characters at most.
fn valid_host(h: &str) -> bool {
    if h.parse::<std::net::IpAddr>().is_ok() {
        return true;
    }
    (1..=253).contains(&h.len())
        && h.split('.').all(|l| {
            (1..=63).contains(&l.len())
                && l.chars().all(|c| c.is_ascii_alphanumeric() || c == '-')
                && !l.starts_with('-')
                && !l.ends_with('-')
        })
}

fn make(e: rcgen::Error) -> CredentialError {
    CredentialError::Make(e.to_string())
}

impl SwarmCredentials {
    /// A new authority for `swarm` and certificates for the world (reached at `hosts`, besides
    /// `localhost` and 127.0.0.1), UAVs 1 to `uavs` but `navigator`, and one observer.
    pub fn generate(
        swarm: &str,
        uavs: u32,
        navigator: u32,
        hosts: &[String],
        validity: Validity,
    ) -> Result<Self, CredentialError> {
        use rcgen::{
            BasicConstraints, CertificateParams, DistinguishedName, DnType, ExtendedKeyUsagePurpose, IsCa, Issuer,
            KeyPair, KeyUsagePurpose,
        };
        if let Some(bad) = hosts.iter().find(|h| !valid_host(h)) {
            return Err(CredentialError::Host(bad.clone()));
        }
        let (y0, m0, d0) = civil_from_days(validity.from_day);
        let (y1, m1, d1) = civil_from_days(validity.from_day + i64::from(validity.days));
        let dated = |mut p: CertificateParams| {
            p.not_before = rcgen::date_time_ymd(y0, m0, d0);
            p.not_after = rcgen::date_time_ymd(y1, m1, d1);
            p
        };
        let mut ca = dated(CertificateParams::new(Vec::<String>::new()).map_err(make)?);
        let mut dn = DistinguishedName::new();
        dn.push(DnType::CommonName, format!("proxform swarm {swarm} authority"));
        ca.distinguished_name = dn;
        ca.is_ca = IsCa::Ca(BasicConstraints::Constrained(0));
        ca.key_usages = vec![KeyUsagePurpose::KeyCertSign, KeyUsagePurpose::CrlSign, KeyUsagePurpose::DigitalSignature];
        let ca_key = KeyPair::generate().map_err(make)?;
        let ca_cert = ca.self_signed(&ca_key).map_err(make)?;
        let ca_key_pem = ca_key.serialize_pem();
        let issuer = Issuer::new(ca, ca_key);

        let mut parties = vec![Party::World];
        parties.extend((1..=uavs).filter(|n| *n != navigator).map(Party::Uav));
        parties.push(Party::Observer);
        let mut issued = Vec::with_capacity(parties.len());
        for party in parties {
            let names: Vec<String> = match party {
                Party::World => {
                    let mut v = vec!["localhost".to_string(), "127.0.0.1".into(), "::1".into()];
                    v.extend(hosts.iter().cloned());
                    v
                }
                _ => vec![party.common_name()],
            };
            let mut p = dated(CertificateParams::new(names).map_err(make)?);
            let mut dn = DistinguishedName::new();
            dn.push(DnType::CommonName, party.common_name());
            p.distinguished_name = dn;
            p.key_usages = vec![KeyUsagePurpose::DigitalSignature];
            p.extended_key_usages = match party {
                Party::World => vec![ExtendedKeyUsagePurpose::ServerAuth, ExtendedKeyUsagePurpose::ClientAuth],
                _ => vec![ExtendedKeyUsagePurpose::ClientAuth],
            };
            let key = KeyPair::generate().map_err(make)?;
            let cert = p.signed_by(&key, &issuer).map_err(make)?;
            issued.push(Issued { party, cert_pem: cert.pem(), key_pem: key.serialize_pem() });
        }
        Ok(Self { ca_pem: ca_cert.pem(), ca_key_pem, issued })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn days_are_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(20_454), (2026, 1, 1));
        assert_eq!(civil_from_days(20_454 + 31 + 28), (2026, 3, 1));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
    }

    #[test]
    fn every_party_but_the_navigator_gets_its_own_certificate() {
        let c = SwarmCredentials::generate(
            "lab",
            4,
            1,
            &["uav-host.local".into()],
            Validity { from_day: 20_000, days: 30 },
        )
        .expect("made");
        let names: Vec<String> = c.issued.iter().map(|i| i.party.common_name()).collect();
        assert_eq!(names, ["world", "uav-2", "uav-3", "uav-4", "observer"]);
        assert!(c.ca_pem.starts_with("-----BEGIN CERTIFICATE-----"));
        assert!(c.issued.iter().all(|i| i.key_pem.contains("PRIVATE KEY")));
        let keys: std::collections::HashSet<&str> = c.issued.iter().map(|i| i.key_pem.as_str()).collect();
        assert_eq!(keys.len(), c.issued.len(), "a key per party");
        let bad = SwarmCredentials::generate("lab", 2, 1, &["not a host!".into()], Validity { from_day: 0, days: 1 });
        assert!(matches!(bad, Err(CredentialError::Host(h)) if h == "not a host!"));
    }
}
