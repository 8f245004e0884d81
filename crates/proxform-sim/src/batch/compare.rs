//! Running a comparison: methods × conditions × seeds, every cell seeing the same
//! disturbances, rows in (method, condition, seed) order whatever the thread count. The file
//! format and its checks are [`proxform_scenario::comparison`].

use std::sync::atomic::{AtomicBool, Ordering};

use proxform_core::RadioNeed;
use proxform_scenario::comparison::{CompareError, Comparison, Condition, MethodEntry};
use proxform_scenario::Scenario;
use rayon::prelude::*;

use super::runs::run_one;
use crate::measure::stats::quantile;
use crate::world::options::RunOptions;

/// One run of a comparison (a CSV row).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CompareRow {
    /// The method's name.
    pub method: String,
    /// The condition's name.
    pub condition: String,
    /// Run index (the seed stream of the base seed).
    pub run: u64,
    /// Every follower within every allowable error for the whole flight.
    pub pass: bool,
    /// Largest position error over the followers and the flight (m, the largest axis).
    pub max_error_m: f64,
    /// Largest error over the allowable error, any axis (≤ 1 passes).
    pub max_error_ratio: f64,
    /// Largest |error| per axis: x, y, z (m).
    pub max_x_m: f64,
    /// See `max_x_m`.
    pub max_y_m: f64,
    /// See `max_x_m`.
    pub max_z_m: f64,
    /// Largest |error| per attitude axis: α, β, γ (degrees).
    pub max_alpha_deg: f64,
    /// See `max_alpha_deg`.
    pub max_beta_deg: f64,
    /// See `max_alpha_deg`.
    pub max_gamma_deg: f64,
    /// RMS position error over the three axes (m).
    pub rms_error_m: f64,
    /// Smallest separation (m).
    pub min_separation_m: f64,
    /// Adjustments per follower per minute.
    pub adjustments_per_uav_min: f64,
    /// Radio messages used (received from UAVs not perceived onboard) per UAV per minute.
    pub messages_per_uav_min: f64,
    /// Mean control effort (inputs over their per-step limits, RSS).
    pub control_effort: f64,
    /// Seconds per follower flown with nothing perceived.
    pub alone_s_per_uav: f64,
}

/// The condition as it reaches `method`: for a method that uses no radio, in a base scenario
/// where nobody broadcasts, the radio's loss, delay and blackout change nothing, and are
/// dropped so that such cells share their runs (bit-identical either way).
pub fn effective(c: &Condition, method: &MethodEntry, base: &Scenario) -> Condition {
    let deaf = method.method.radio_need() == RadioNeed::None
        && !method.broadcast
        && base.beacons().is_empty()
        && !base.radio().broadcast_all;
    if deaf {
        Condition { name: String::new(), radio_loss: 0.0, radio_delay_s: 0.0, blackout: false, ..c.clone() }
    } else {
        Condition { name: String::new(), ..c.clone() }
    }
}

/// Runs every (method, condition, seed) on the current rayon pool, calling `progress` after
/// each run. Rows are in (method, condition, seed) order. Cells that [`effective`] makes equal
/// are run once.
pub fn run_comparison(cmp: &Comparison, progress: &(dyn Fn() + Sync)) -> Result<Vec<CompareRow>, CompareError> {
    let never = AtomicBool::new(false);
    Ok(run_comparison_stoppable(cmp, progress, &never)?.expect("a comparison nobody stops runs to its end"))
}

/// [`run_comparison`] that another thread can stop (a user's interrupt): once `stop` is set,
/// no new flight starts and the result is `Ok(None)`.
pub fn run_comparison_stoppable(
    cmp: &Comparison,
    progress: &(dyn Fn() + Sync),
    stop: &AtomicBool,
) -> Result<Option<Vec<CompareRow>>, CompareError> {
    let (unique, uses) = plan(cmp);
    let unique: Vec<(usize, Scenario)> = unique
        .into_iter()
        .map(|(mi, ci)| cmp.conditions[ci].scenario(&cmp.base_spec, &cmp.methods[mi]).map(|sc| (mi, sc)))
        .collect::<Result<_, _>>()?;
    let tasks: Vec<(usize, u64)> = (0..unique.len()).flat_map(|k| (0..cmp.seeds).map(move |r| (k, r))).collect();
    // One flight per work item: cells differ in cost by 100× (the horizon QP), and rayon's
    // adaptive splitting would otherwise leave a whole chunk of expensive cells to one thread.
    let Some(runs): Option<Vec<crate::measure::metrics::RunSummary>> = tasks
        .par_iter()
        .with_max_len(1)
        .map(|&(k, r)| {
            if stop.load(Ordering::Relaxed) {
                return None;
            }
            let (s, _) = run_one(&unique[k].1, RunOptions::default(), cmp.seed, r, false);
            progress();
            Some(s)
        })
        .collect::<Option<_>>()
        .filter(|_| !stop.load(Ordering::Relaxed))
    else {
        return Ok(None);
    };
    let seeds = cmp.seeds as usize;
    let allowable = cmp.base.allowable().as_array();
    Ok(Some(
        uses.iter()
            .flat_map(|&(mi, ci, k)| {
                let (m, c) = (&cmp.methods[mi], &cmp.conditions[ci]);
                runs[k * seeds..(k + 1) * seeds].iter().map(move |s| {
                    let e = s.max_abs_error;
                    let ratio = (0..6).map(|a| e[a] / allowable[a]).fold(0.0, f64::max);
                    let per_min = 60.0 / s.duration_s.max(f64::MIN_POSITIVE);
                    CompareRow {
                        method: m.name.clone(),
                        condition: c.name.clone(),
                        run: s.run,
                        pass: s.pass,
                        max_error_m: e[0].max(e[1]).max(e[2]),
                        max_error_ratio: ratio,
                        max_x_m: e[0],
                        max_y_m: e[1],
                        max_z_m: e[2],
                        max_alpha_deg: e[3].to_degrees(),
                        max_beta_deg: e[4].to_degrees(),
                        max_gamma_deg: e[5].to_degrees(),
                        rms_error_m: ((s.rms_error[0].powi(2) + s.rms_error[1].powi(2) + s.rms_error[2].powi(2)) / 3.0)
                            .sqrt(),
                        min_separation_m: s.min_separation_m,
                        adjustments_per_uav_min: s.adjustments as f64 / s.followers.max(1) as f64 * per_min,
                        messages_per_uav_min: s.radio_used_per_uav_s * 60.0,
                        control_effort: s.control_effort,
                        alone_s_per_uav: s.alone_s_per_uav,
                    }
                })
            })
            .collect(),
    ))
}

/// What [`plan`] returns: the distinct cells to fly, as (method, condition) indices of a
/// representative, and for every (method, condition) in order, the distinct cell whose runs it
/// reports, as (method, condition, cell).
type Plan = (Vec<(usize, usize)>, Vec<(usize, usize, usize)>);

/// Which cells to fly and which runs each cell reports.
fn plan(cmp: &Comparison) -> Plan {
    let mut unique: Vec<(usize, usize, Condition)> = Vec::new();
    let mut uses = Vec::new();
    for (mi, m) in cmp.methods.iter().enumerate() {
        for (ci, c) in cmp.conditions.iter().enumerate() {
            let eff = effective(c, m, &cmp.base);
            let k = unique.iter().position(|u| u.0 == mi && u.2 == eff).unwrap_or_else(|| {
                unique.push((mi, ci, eff));
                unique.len() - 1
            });
            uses.push((mi, ci, k));
        }
    }
    (unique.into_iter().map(|(mi, ci, _)| (mi, ci)).collect(), uses)
}

/// Number of distinct cells [`run_comparison`] flies (after sharing, see [`effective`]).
pub fn distinct_cells(cmp: &Comparison) -> usize {
    plan(cmp).0.len()
}

/// Number of flights [`run_comparison`] flies (distinct cells × seeds).
pub fn flights(cmp: &Comparison) -> u64 {
    distinct_cells(cmp) as u64 * cmp.seeds
}

/// Median and 95th percentile of one cell's runs.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CellSummary {
    /// The method's name.
    pub method: String,
    /// The condition's name.
    pub condition: String,
    /// Runs in the cell.
    pub runs: u64,
    /// Fraction of runs that passed.
    pub pass_fraction: f64,
    /// The 95 % Wilson interval of the pass fraction: its low end.
    pub pass_fraction_lo: f64,
    /// Its high end.
    pub pass_fraction_hi: f64,
    /// Median of the largest position error (m).
    pub max_error_m_median: f64,
    /// 95th percentile of the largest position error (m).
    pub max_error_m_p95: f64,
    /// Median of the largest attitude error, any of α, β, γ (degrees).
    pub max_attitude_deg_median: f64,
    /// 95th percentile of the same.
    pub max_attitude_deg_p95: f64,
    /// Median of the largest error over its allowable error (any axis; ≤ 1 passes).
    pub error_ratio_median: f64,
    /// 95th percentile of the same.
    pub error_ratio_p95: f64,
    /// Median of the smallest separation (m).
    pub min_separation_m_median: f64,
    /// 5th percentile of the smallest separation (m): the close end.
    pub min_separation_m_p05: f64,
    /// Median adjustments per follower per minute.
    pub adjustments_per_uav_min: f64,
    /// Median radio messages received per UAV per minute.
    pub messages_per_uav_min: f64,
    /// Median control effort.
    pub control_effort: f64,
}

/// Summarises rows cell by cell, in the order cells first appear.
pub fn summarise(rows: &[CompareRow]) -> Vec<CellSummary> {
    let mut keys: Vec<(&str, &str)> = Vec::new();
    for r in rows {
        if !keys.contains(&(r.method.as_str(), r.condition.as_str())) {
            keys.push((&r.method, &r.condition));
        }
    }
    keys.iter()
        .map(|&(m, c)| {
            let cell: Vec<&CompareRow> = rows.iter().filter(|r| r.method == m && r.condition == c).collect();
            let col = |f: fn(&CompareRow) -> f64| {
                let mut v: Vec<f64> = cell.iter().map(|r| f(r)).collect();
                v.sort_by(f64::total_cmp);
                v
            };
            let err = col(|r| r.max_error_m);
            let sep = col(|r| r.min_separation_m);
            let ratio = col(|r| r.max_error_ratio);
            let attitude = col(|r| r.max_alpha_deg.max(r.max_beta_deg).max(r.max_gamma_deg));
            let passed = cell.iter().filter(|r| r.pass).count() as u64;
            let (lo, hi) = crate::measure::stats::wilson(passed, cell.len() as u64);
            CellSummary {
                method: m.into(),
                condition: c.into(),
                runs: cell.len() as u64,
                pass_fraction: passed as f64 / cell.len().max(1) as f64,
                pass_fraction_lo: lo,
                pass_fraction_hi: hi,
                max_error_m_median: quantile(&err, 0.5),
                max_error_m_p95: quantile(&err, 0.95),
                max_attitude_deg_median: quantile(&attitude, 0.5),
                max_attitude_deg_p95: quantile(&attitude, 0.95),
                error_ratio_median: quantile(&ratio, 0.5),
                error_ratio_p95: quantile(&ratio, 0.95),
                min_separation_m_median: quantile(&sep, 0.5),
                min_separation_m_p05: quantile(&sep, 0.05),
                adjustments_per_uav_min: quantile(&col(|r| r.adjustments_per_uav_min), 0.5),
                messages_per_uav_min: quantile(&col(|r| r.messages_per_uav_min), 0.5),
                control_effort: quantile(&col(|r| r.control_effort), 0.5),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proxform_scenario::builtin::paper_spec;

    /// A comparison of the paper experiment shortened to `duration_s`.
    fn parse(text: &str, duration_s: f64) -> Comparison {
        Comparison::parse(text, "test.toml", |name| match name {
            "paper" => Ok(proxform_scenario::ScenarioSpec { duration_s: Some(duration_s), ..paper_spec() }),
            other => Err(format!("unknown scenario '{other}'")),
        })
        .expect("valid")
    }

    #[test]
    fn rows_do_not_depend_on_the_thread_count() {
        let text = "name = 'x'\nscenario = 'paper'\nseeds = 3\nmethods = ['proximity', 'leader_follower']\n\
                    [[condition]]\nname = 'lossy'\nradio_loss = 0.5\nradio_delay_s = 0.2\n";
        let c = parse(text, 10.0);
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("pool");
        let two = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("pool");
        let a = one.install(|| run_comparison(&c, &|| {})).expect("runs");
        let b = two.install(|| run_comparison(&c, &|| {})).expect("runs");
        assert_eq!(a.len(), 6);
        assert_eq!(a, b);
    }

    #[test]
    fn radio_conditions_are_shared_only_by_methods_without_radio_and_change_nothing_for_them() {
        let text = "name = 'x'\nscenario = 'paper'\nseeds = 2\nmethods = ['proximity', 'leader_follower']\n\
                    [[condition]]\nname = 'ideal'\n[[condition]]\nname = 'lossy'\nradio_loss = 0.9\n";
        let c = parse(text, 20.0);
        // Proximity shares one cell; leader-follower runs both.
        assert_eq!(distinct_cells(&c), 3);
        let rows = run_comparison(&c, &|| {}).expect("runs");
        let cell =
            |m: &str, k: &str| rows.iter().filter(|r| r.method == m && r.condition == k).cloned().collect::<Vec<_>>();
        let lf_ideal = cell("leader_follower", "ideal");
        let lf_lossy = cell("leader_follower", "lossy");
        assert!(lf_lossy[0].max_error_m > lf_ideal[0].max_error_m);
        // Sharing is exact: flying the lossy proximity cell for real gives the same numbers.
        let m = &c.methods[0];
        let sc = c.conditions[1].scenario(&c.base_spec, m).expect("valid");
        let (real, _) = run_one(&sc, RunOptions::default(), c.seed, 0, false);
        let shared = &cell("proximity", "lossy")[0];
        assert_eq!(real.max_abs_error[0].max(real.max_abs_error[1]).max(real.max_abs_error[2]), shared.max_error_m);
        assert_eq!(real.min_separation_m, shared.min_separation_m);
    }
}
