//! Peak resident memory of this process, as the kernel reports it.

/// Peak resident set size in bytes (Linux `VmHWM`); None where the kernel does not say.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Formats a byte count in MiB.
pub fn mib(bytes: Option<u64>) -> String {
    bytes.map_or_else(|| "n/a".to_string(), |b| format!("{:.0} MiB", b as f64 / (1024.0 * 1024.0)))
}
