//! The printed report: per-follower errors against the allowable ones, and the batch summary.

use std::io::{self, Write};
use std::time::Duration;

use proxform_scenario::faults::Fault;
use proxform_scenario::Scenario;
use proxform_sim::Summary;

const AXES: [&str; 6] = ["x m", "y m", "z m", "α °", "β °", "γ °"];

/// The followers whose rows the table shows (indices into the summary's per-UAV detail, in
/// id order): all of them up to [`MAX_ROWS`]; beyond, the [`MAX_ROWS`] farthest out of their
/// allowable errors over the batch (the largest of their worst errors over the allowable ones,
/// the axis that decides a verdict; those not flown last), so that a deep formation's rear
/// ranks show; the followers that failed in some run come before all others, so that a FAIL
/// is never hidden.
fn rows_shown(s: &proxform_sim::Summary) -> Vec<usize> {
    let allow = s.allowable_error.as_array();
    let ratio: Vec<f64> = (0..s.per_uav.len())
        .map(|f| {
            if s.per_uav_runs_flown[f] == 0 {
                return f64::NEG_INFINITY;
            }
            let w = s.per_uav_worst[f].as_array();
            (0..6).map(|k| w[k] / allow[k]).fold(0.0, f64::max)
        })
        .collect();
    let failed: Vec<bool> = s.per_uav_runs_passed.iter().zip(&s.per_uav_runs_flown).map(|(p, f)| p < f).collect();
    worst_rows(&failed, &ratio, MAX_ROWS)
}

/// Of the rows with `failed` and error `ratio`, the `max` to show, in row order: every one up
/// to `max`; beyond, those that failed first (a scattered start's forming errors outweigh the
/// error of the one that did not form), then the largest ratios.
fn worst_rows(failed: &[bool], ratio: &[f64], max: usize) -> Vec<usize> {
    let n = ratio.len();
    if n <= max {
        return (0..n).collect();
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| failed[b].cmp(&failed[a]).then(ratio[b].total_cmp(&ratio[a])).then(a.cmp(&b)));
    order.truncate(max);
    order.sort_unstable();
    order
}

/// Prints the table of one batch.
pub fn print(
    out: &mut impl Write,
    scenario: &Scenario,
    s: &Summary,
    timing: Option<(Duration, usize)>,
) -> io::Result<()> {
    let allow = s.allowable_error.as_array();
    writeln!(
        out,
        "proxform run: scenario '{}' ({} UAVs), {} run(s){} from seed {}{}",
        s.scenario,
        s.uavs,
        s.runs,
        match s.first_run {
            0 => String::new(),
            k => format!(" (runs {k}..={})", k + s.runs.saturating_sub(1)),
        },
        s.seed,
        timing.map_or_else(String::new, |(e, threads)| format!(", {:.2} s on {threads} thread(s)", e.as_secs_f64()))
    )?;
    // What the flight met, and what it was judged by.
    writeln!(out, "conditions: {}", crate::html::conditions(scenario).join("; "))?;
    writeln!(out)?;
    writeln!(out, "Largest |error| relative to the navigator (METHOD §7), over all runs:")?;
    write!(out, "{:<8}", "UAV")?;
    for a in AXES {
        write!(out, "{a:>10}")?;
    }
    writeln!(out, "{:>14}{:>10}", "adjust/run", "result")?;
    write!(out, "{:<8}", "allowed")?;
    for a in allow {
        write!(out, "{:>10}", number(a))?;
    }
    writeln!(out)?;
    let shown = rows_shown(s);
    for &f in &shown {
        let verdict = match (s.per_uav_runs_flown[f], s.per_uav_runs_passed[f]) {
            (0, _) => "not flown",
            (flown, passed) if passed == flown => "PASS",
            _ => "FAIL",
        };
        uav_row(
            out,
            &format!("UAV{}", s.per_uav[f]),
            &s.per_uav_worst[f].as_array(),
            s.per_uav_adjustments[f],
            verdict,
        )?;
    }
    let followers = s.uavs as usize - 1;
    if followers > shown.len() {
        let detail = if s.per_uav.len() < followers {
            format!(" of the first {}, which have their rows in summary.json (per_uav)", s.per_uav.len())
        } else {
            "); each has its row in summary.json (per_uav".to_string()
        };
        let shown_n = shown.len();
        writeln!(
            out,
            "… {} more followers (shown: the {shown_n} farthest out of their allowable errors, on their worst axis{detail})",
            followers - shown_n
        )?;
        let per_run = s.adjustments_per_uav_minute * scenario.duration_s() / 60.0;
        let verdict = if s.pass_fraction == 1.0 { "PASS" } else { "FAIL" };
        uav_row(out, "all", &s.worst_abs_error.as_array(), per_run, verdict)?;
    }
    writeln!(out)?;
    row(out, "p99 over runs", &s.p99_abs_error.as_array())?;
    row(out, "median", &s.median_abs_error.as_array())?;
    row(out, "RMS measured", &s.rms_error.as_array())?;
    row(out, "eq.17 σ", &s.predicted_sigma.as_array())?;
    writeln!(out)?;
    let passed = s.counts.passed;
    writeln!(out, "pass fraction            {} ({passed} of {} runs)", fraction(s.pass_fraction), s.runs)?;
    if s.unjudged_runs > 0 {
        writeln!(
            out,
            "nothing to judge         in {} run(s) no follower flew: those runs do not pass",
            s.unjudged_runs
        )?;
    }
    if s.unsafe_runs > 0 {
        writeln!(
            out,
            "unsafe                   in {} run(s) a pair came closer than the safety distance: those runs do not pass",
            s.unsafe_runs
        )?;
    }
    if let Some(u) = &s.uncontrolled {
        writeln!(
            out,
            "uncontrolled             in {} run(s) a follower flew uncontrolled, without its agent or its commands (up to {} UAV-s in a run, holding its course, a multirotor hovering once its autopilot's failsafe took over): those runs do not pass",
            u.runs,
            number(u.max_s)
        )?;
    }
    if s.off_path_runs > 0 {
        writeln!(
            out,
            "off path                 in {} run(s) the formation left its planned path by more than {} m: those runs do not pass",
            s.off_path_runs,
            number(s.path_bound_m)
        )?;
    }
    writeln!(
        out,
        "path                     the navigator (or the formation's estimate of its slot) at most {} m from the planned path (bound {} m)",
        number(s.path_deviation_m_max),
        number(s.path_bound_m)
    )?;
    if let Some(latest) = s.succession_latest_s {
        writeln!(
            out,
            "succession               in {} run(s) the navigator was lost and a successor led its slot's path (from {} s at the latest)",
            s.succession_runs,
            number(latest)
        )?;
    }
    writeln!(
        out,
        "min separation           {} m (safety distance {} m, {} run(s) closer; true positions)",
        number(s.min_separation_m),
        number(s.safety_distance_m),
        s.unsafe_runs
    )?;
    writeln!(out, "adjustments per UAV-min  {:.1}", s.adjustments_per_uav_minute)?;
    let m = &s.swarm;
    writeln!(
        out,
        "inside envelope          {} % of follower steps held; {} % within the allowable errors",
        percent(m.held_fraction),
        percent(m.within_allowable_fraction)
    )?;
    writeln!(out, "control effort           {:.3} (inputs over their per-step limits, RSS, mean)", m.control_effort)?;
    writeln!(out, "pairs closer than safety {:.2} per run (max {})", m.close_pairs_mean, m.close_pairs_max)?;
    writeln!(
        out,
        "order, connectivity      order mean {:.4}, min {:.4}; largest group connected by onboard sensing ≥ {} %",
        m.order_mean,
        m.order_min,
        percent(m.connectivity_min)
    )?;
    writeln!(
        out,
        "radio                    {:.1} messages sent and {:.1} used per UAV per second",
        m.radio_sent_per_uav_s, m.radio_used_per_uav_s
    )?;
    if m.alone_s_per_uav > 0.0 {
        writeln!(out, "flown alone              {:.2} s per follower (nothing perceived)", m.alone_s_per_uav)?;
    }
    if let Some(f) = &s.sensor_faults {
        let healthy = s.counts.healthy_passed;
        // The navigator has no slot error to come back within: its faults show in the
        // followers' errors alone.
        // A fault lasting to the end of the flight has no return to time.
        let nav = scenario.navigator();
        let (mut navigator, mut followers, mut ends) = (false, false, false);
        for x in scenario.faults() {
            if let Fault::Glitch { uav, at_s, duration_s, .. } | Fault::StuckSensor { uav, at_s, duration_s } = *x {
                navigator |= uav == nav;
                followers |= uav != nav;
                ends |= uav != nav && at_s + duration_s < scenario.duration_s();
            }
        }
        let mut back = Vec::new();
        if followers && !ends {
            back.push("the faulty followers' faults last to the end of the flight (no return to time)".into());
        } else if followers {
            back.push(format!(
                "faulty followers back within them {} s after the fault (median), {} s (p99), {} s (max)",
                number(f.rejoin_s_median),
                number(f.rejoin_s_p99),
                number(f.rejoin_s_max)
            ));
        }
        if navigator {
            back.push("the navigator's own faults show in the followers' errors (it has no slot error)".into());
        }
        writeln!(
            out,
            "sensor faults            the {}followers within the allowable errors in {} ({healthy} of {} runs); {}",
            if followers { "other " } else { "" },
            fraction(f.healthy_pass_fraction),
            s.runs,
            back.join("; ")
        )?;
    }
    if let Some(f) = &s.forming {
        let formed = s.counts.formed;
        writeln!(
            out,
            "forming                  formed (every follower within the allowable errors to the end, or to the first change of formation; a re-assignment while forming carries it on) in {} ({formed} of {} runs), from t = {} s (median), {} s (p99), {} s (max); largest error before forming {}× the allowable{}",
            fraction(f.formed_fraction),
            s.runs,
            number(f.time_to_form_s_median),
            number(f.time_to_form_s_p99),
            number(f.time_to_form_s_max),
            number(f.transient_error_ratio_max),
            f.settled_error_ratio_max
                .map_or_else(String::new, |v| format!("; of the followers that started in their slots {}×", number(v)))
        )?;
        // Formed at all is not formed in time: the criterion's deadline, when there is one.
        if let Some(limit) = scenario.form_within_s() {
            let in_time = s.counts.formed_in_time;
            writeln!(
                out,
                "formed in time           by form_within_s = {} s in {in_time} of {} runs (the others do not pass)",
                number(limit),
                s.runs
            )?;
        }
    }
    if let Some(f) = &s.flown {
        writeln!(
            out,
            "flown per follower       {} m, Δv {} m/s, work {} J/kg (Σ|Δ(½v² + g·z)|), means over runs",
            number(f.path_length_m_per_uav),
            number(f.delta_v_mps_per_uav),
            number(f.work_j_per_kg_per_uav)
        )?;
    }
    if let Some(c) = &s.transitions {
        writeln!(
            out,
            "formation changes        completed (every follower within the allowable errors of the new formation until the next change) in {} of runs; slowest change per run {} s (median), {} s (p99), {} s (max); largest error during the changes {}× the allowable; closest pair during them {} m",
            fraction(c.completed_fraction),
            number(c.transition_s_median),
            number(c.transition_s_p99),
            number(c.transition_s_max),
            number(c.transient_error_ratio_max),
            number(c.closest_m)
        )?;
    }
    if let Some(i) = &s.isolation {
        writeln!(
            out,
            "isolation                neighbours left out {:.3} s per follower ({:.4} per follower-second); own sensor refused {:.3} s per follower in {} episode(s)",
            i.isolating_s_per_uav, i.isolated_per_uav_s, i.own_suspect_s_per_uav, i.own_suspect_episodes
        )?;
    }
    if let Some((elapsed, _)) = timing {
        let updates = (s.uavs.saturating_sub(1) * s.runs) as f64 * scenario.steps() as f64;
        writeln!(out, "agent-updates per second {:.3e}", updates / elapsed.as_secs_f64().max(1e-9))?;
    }
    Ok(())
}

/// Most follower rows printed; larger swarms get a summary row.
const MAX_ROWS: usize = 10;

/// One row of the per-follower table: its largest errors, adjustments per run, and its verdict
/// by the run's criterion (`PASS` in every run it flew, `FAIL`, `not flown`).
fn uav_row(out: &mut impl Write, label: &str, worst: &[f64; 6], adjustments: f64, verdict: &str) -> io::Result<()> {
    write!(out, "{label:<8}")?;
    for e in worst {
        write!(out, "{:>10}", number(*e))?;
    }
    let adjust = if adjustments.abs() < 1e9 { format!("{adjustments:.1}") } else { number(adjustments) };
    writeln!(out, "{adjust:>14}{verdict:>10}")?;
    Ok(())
}

fn row(out: &mut impl Write, label: &str, v: &[f64; 6]) -> io::Result<()> {
    write!(out, "{label:<8}")?;
    if label.len() > 8 {
        writeln!(out)?;
        write!(out, "{:<8}", "")?;
    }
    for e in v {
        write!(out, "{:>10}", number(*e))?;
    }
    writeln!(out)?;
    Ok(())
}

/// A number in at most 9 characters, so that columns stay aligned for any value: three
/// decimals in the usual range, scientific notation far outside it.
pub fn number(v: f64) -> String {
    let a = v.abs();
    if !v.is_finite() {
        if v.is_nan() {
            "—".into()
        } else if v > 0.0 {
            "∞".into()
        } else {
            "−∞".into()
        }
    } else if a == 0.0 || (1e-3..1e5).contains(&a) {
        format!("{v:.3}")
    } else {
        format!("{v:.2e}")
    }
}

/// A fraction as a percentage that never rounds a shortfall away: 99.98 % is not shown as
/// 100.0, nor 0.02 % as 0.0.
pub fn percent(f: f64) -> String {
    honest(100.0 * f, 100.0, 1)
}

/// A fraction in [0, 1] with four decimals, or more where four would round it to 0 or 1.
pub fn fraction(f: f64) -> String {
    honest(f, 1.0, 4)
}

/// `v` in [0, top] with at least `decimals` decimals, and as many more (up to 8) as it takes
/// not to show a value below `top` as `top` or one above 0 as 0.
fn honest(v: f64, top: f64, decimals: usize) -> String {
    for d in decimals..=8 {
        let s = format!("{v:.d$}");
        let shown: f64 = s.parse().unwrap_or(v);
        if (shown < top || v >= top) && (shown > 0.0 || v <= 0.0) {
            return s;
        }
    }
    format!("{v:.8}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_fit_their_columns_and_rounding_hides_no_failure() {
        for v in [0.0, 0.123456, 1e308, -1e308, 12345.678, 1e-9, f64::INFINITY, f64::NAN, -0.5] {
            assert!(number(v).chars().count() <= 9, "{v}: {}", number(v));
        }
        assert_eq!(percent(0.9998), "99.98");
        assert_eq!(percent(1.0), "100.0");
        assert_eq!(percent(0.0002), "0.02");
        assert_eq!(percent(0.5), "50.0");
        assert_eq!(fraction(0.99999), "0.99999");
        assert_eq!(fraction(1.0), "1.0000");
        assert_eq!(fraction(0.95), "0.9500");
    }

    #[test]
    fn a_follower_that_failed_is_shown_however_small_its_errors() {
        // Twelve rows, the largest errors those of a scattered start's forming; row 7 failed
        // with a smaller worst error (removed before it formed): it is shown, as are the
        // largest of the others.
        let ratio = [50.0, 40.0, 45.0, 30.0, 60.0, 35.0, 55.0, 20.0, 25.0, 70.0, 65.0, 42.0];
        let mut failed = [false; 12];
        failed[7] = true;
        let shown = worst_rows(&failed, &ratio, 10);
        assert!(shown.contains(&7), "{shown:?}");
        assert_eq!(shown.len(), 10);
        assert!(!shown.contains(&8) && !shown.contains(&3), "the two smallest of the others left out: {shown:?}");
        assert_eq!(worst_rows(&[false; 3], &ratio[..3], 10), [0, 1, 2]);
    }
}
