//! Memory: the peak this process reached, as the kernel reports it, and what a flight will
//! need, said before it is taken (refused when the machine does not have it).

use anyhow::{bail, Result};

/// Peak resident set size in bytes (Linux `VmHWM`); None where the kernel does not say.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Memory available to new allocations without swapping (Linux `MemAvailable`), bytes; None
/// where the kernel does not say.
pub fn available_bytes() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Formats a byte count in MiB.
pub fn mib(bytes: Option<u64>) -> String {
    bytes.map_or_else(|| "n/a".to_string(), |b| format!("{:.0} MiB", b as f64 / (1024.0 * 1024.0)))
}

/// Formats a byte count in GiB.
fn gib(bytes: u64) -> String {
    format!("{:.1} GiB", bytes as f64 / (1024.0 * 1024.0 * 1024.0))
}

/// Flights from this size on are announced with their memory before they start.
pub const ANNOUNCE_BYTES: u64 = 4 << 30;

/// A flight's peak resident memory over the engine's own account of its arrays and agents
/// (`proxform_sim::bytes_estimate`), as measured at 10^6 UAVs on a lattice: the reference
/// engine 3 130 MiB against 1 656, the fast one 1 697 against 767 (the measures' per-UAV
/// records, allocator overhead and the warm-up's transients are not in the account).
pub const PEAK_OVER_ACCOUNT: u64 = 2;

/// Checks that `at_once` flights of `scenario` on `engine` fit in `available` bytes (the
/// machine's available memory, when known) before any is built: refused, naming the estimate
/// and what is available, when they do not; announced on standard error from
/// [`ANNOUNCE_BYTES`] on. The estimate is the engine's own (`proxform_sim::bytes_estimate`).
pub fn check_flights(
    scenario: &proxform_scenario::Scenario,
    engine: proxform_sim::EngineKind,
    at_once: usize,
    available: Option<u64>,
) -> Result<()> {
    let one = (proxform_sim::bytes_estimate(scenario, engine) as u64).saturating_mul(PEAK_OVER_ACCOUNT);
    let need = one.saturating_mul(at_once.max(1) as u64);
    let what = match at_once {
        0 | 1 => format!("a flight of {} UAVs on the {} engine", scenario.len(), engine.name()),
        n => format!("{n} flights at once of {} UAVs on the {} engine", scenario.len(), engine.name()),
    };
    if let Some(free) = available.filter(|&free| need > free) {
        let fewer = if at_once > 1 { "fewer --threads, " } else { "" };
        let fast =
            if engine == proxform_sim::EngineKind::Reference { ", or engine = \"fast\" (about half)" } else { "" };
        bail!(
            "{what} needs about {} ({} bytes per UAV), more than the {} this machine has available: {fewer}fewer UAVs{fast}",
            gib(need),
            one / scenario.len().max(1) as u64,
            gib(free)
        );
    }
    if need >= ANNOUNCE_BYTES {
        eprintln!("note: {what} needs about {} of memory", gib(need));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proxform_sim::EngineKind;

    #[test]
    fn a_flight_the_machine_cannot_hold_is_refused_before_it_is_built() {
        let swarm =
            |n| proxform_scenario::Scenario::try_from(proxform_scenario::builtin::swarm_spec(n)).expect("valid");
        let (small, large) = (swarm(1_000), swarm(10_000));
        for engine in [EngineKind::Reference, EngineKind::Fast] {
            // The estimate grows with the swarm, a flight at a time.
            let (a, b) = (proxform_sim::bytes_estimate(&small, engine), proxform_sim::bytes_estimate(&large, engine));
            assert!(b > 9 * a && b < 11 * a, "{engine:?}: {a} {b}");
            let need = 2 * b as u64;
            let e = check_flights(&large, engine, 1, Some(need / 2)).expect_err("more than is available");
            let m = e.to_string();
            assert!(m.contains("10000 UAVs") && m.contains("needs about") && m.contains("available"), "{m}");
            // Two flights at once need twice one.
            assert!(check_flights(&large, engine, 1, Some(need + 1)).is_ok());
            assert!(check_flights(&large, engine, 2, Some(need + 1)).is_err());
            // Where the kernel does not say what is available, nothing is refused.
            assert!(check_flights(&large, engine, 64, None).is_ok());
        }
        // The fast engine holds less than the reference.
        assert!(
            proxform_sim::bytes_estimate(&large, EngineKind::Fast)
                < proxform_sim::bytes_estimate(&large, EngineKind::Reference)
        );
    }
}
