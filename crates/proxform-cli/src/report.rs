//! The printed report: per-follower errors against the allowable ones, and the batch summary.

use std::io::{self, Write};
use std::time::Duration;

use proxform_scenario::Scenario;
use proxform_sim::BatchResult;

const AXES: [&str; 6] = ["x m", "y m", "z m", "α °", "β °", "γ °"];

/// Prints the table of one batch.
pub fn print(
    out: &mut impl Write,
    scenario: &Scenario,
    result: &BatchResult,
    elapsed: Duration,
    threads: usize,
) -> io::Result<()> {
    let s = &result.summary;
    let allow = s.allowable_error.as_array();
    writeln!(
        out,
        "proxform run: scenario '{}' ({} UAVs), {} run(s) from seed {}, {:.2} s on {} thread(s)\n",
        s.scenario,
        s.uavs,
        s.runs,
        s.seed,
        elapsed.as_secs_f64(),
        threads
    )?;
    writeln!(out, "Largest |error| relative to the navigator (METHOD §7), over all runs:")?;
    write!(out, "{:<8}", "UAV")?;
    for a in AXES {
        write!(out, "{a:>10}")?;
    }
    writeln!(out, "{:>14}{:>8}", "adjust/run", "result")?;
    write!(out, "{:<8}", "allowed")?;
    for a in allow {
        write!(out, "{a:>10.3}")?;
    }
    writeln!(out)?;
    let shown = s.per_uav.len().min(MAX_ROWS);
    for f in 0..shown {
        uav_row(
            out,
            &format!("UAV{}", s.per_uav[f]),
            &s.per_uav_worst[f].as_array(),
            s.per_uav_adjustments[f],
            &allow,
        )?;
    }
    if s.uavs as usize - 1 > shown {
        writeln!(out, "… {} more followers", s.uavs as usize - 1 - shown)?;
        let per_run = s.adjustments_per_uav_minute * scenario.duration_s() / 60.0;
        uav_row(out, "all", &s.worst_abs_error.as_array(), per_run, &allow)?;
    }
    writeln!(out)?;
    row(out, "p99 over runs", &s.p99_abs_error.as_array())?;
    row(out, "median", &s.median_abs_error.as_array())?;
    row(out, "RMS measured", &s.rms_error.as_array())?;
    row(out, "eq.17 σ", &s.predicted_sigma.as_array())?;
    writeln!(out)?;
    writeln!(
        out,
        "pass fraction            {:.4} ({} of {} runs)",
        s.pass_fraction,
        result.runs.iter().filter(|r| r.pass).count(),
        s.runs
    )?;
    writeln!(
        out,
        "min separation           {:.1} m (safety distance {:.1} m, {} run(s) closer)",
        s.min_separation_m, s.safety_distance_m, s.unsafe_runs
    )?;
    writeln!(out, "adjustments per UAV-min  {:.1}", s.adjustments_per_uav_minute)?;
    let m = &s.swarm;
    writeln!(
        out,
        "inside envelope          {:.1} % of follower steps held; {:.1} % within the allowable errors",
        100.0 * m.held_fraction,
        100.0 * m.within_allowable_fraction
    )?;
    writeln!(out, "control effort           {:.3} (inputs over their per-step limits, RSS, mean)", m.control_effort)?;
    writeln!(out, "pairs closer than safety {:.2} per run (max {})", m.close_pairs_mean, m.close_pairs_max)?;
    writeln!(
        out,
        "order, connectivity      order mean {:.4}, min {:.4}; largest connected group ≥ {:.1} %",
        m.order_mean,
        m.order_min,
        100.0 * m.connectivity_min
    )?;
    writeln!(out, "radio                    {:.1} messages per UAV per second", m.radio_msgs_per_uav_s)?;
    if m.alone_s_per_uav > 0.0 {
        writeln!(out, "flown alone              {:.2} s per follower (nothing perceived)", m.alone_s_per_uav)?;
    }
    let updates = (s.uavs.saturating_sub(1) * s.runs) as f64 * scenario.steps() as f64;
    writeln!(out, "agent-updates per second {:.3e}", updates / elapsed.as_secs_f64().max(1e-9))?;
    Ok(())
}

/// Most follower rows printed; larger swarms get a summary row.
const MAX_ROWS: usize = 10;

fn uav_row(out: &mut impl Write, label: &str, worst: &[f64; 6], adjustments: f64, allow: &[f64; 6]) -> io::Result<()> {
    let ok = worst.iter().zip(allow).all(|(e, a)| e <= a);
    write!(out, "{label:<8}")?;
    for e in worst {
        write!(out, "{e:>10.3}")?;
    }
    writeln!(out, "{:>14.1}{:>8}", adjustments, if ok { "PASS" } else { "FAIL" })?;
    Ok(())
}

fn row(out: &mut impl Write, label: &str, v: &[f64; 6]) -> io::Result<()> {
    write!(out, "{label:<8}")?;
    if label.len() > 8 {
        writeln!(out)?;
        write!(out, "{:<8}", "")?;
    }
    for e in v {
        write!(out, "{e:>10.3}")?;
    }
    writeln!(out)?;
    Ok(())
}
