//! A sweep: the cells of a grid over scenario keys (every combination of the values given
//! for each key, the first key varying slowest) and the row of the sweep's table that each
//! cell's batch summary makes, shared by `proxform sweep` and `proxform.sweep`.

use crate::batch::runs::Summary;

/// Most cells a sweep may have (a grid larger than this is a cluster job of sweeps).
pub const MAX_CELLS: usize = 10_000;

/// Every combination of `axes` ((key, values) each), the first key varying slowest: one
/// cell per combination, as (key, value) pairs in the axes' order.
pub fn cells(axes: &[(String, Vec<String>)]) -> Vec<Vec<(&str, &str)>> {
    let mut out: Vec<Vec<(&str, &str)>> = vec![Vec::new()];
    for (key, values) in axes {
        let mut next = Vec::with_capacity(out.len() * values.len());
        for cell in &out {
            for v in values {
                let mut c = cell.clone();
                c.push((key.as_str(), v.as_str()));
                next.push(c);
            }
        }
        out = next;
    }
    out
}

/// The columns of a sweep's row: (name, value) of a cell's summary, None where the summary
/// has no such part (no faults, no forming).
pub fn row(s: &Summary) -> Vec<(&'static str, Option<f64>)> {
    let w = s.worst_abs_error;
    let p = s.p99_abs_error;
    let mut r = vec![
        ("runs", Some(s.runs as f64)),
        ("pass_fraction", Some(s.pass_fraction)),
        ("worst_err_x_m", Some(w.x_m)),
        ("worst_err_y_m", Some(w.y_m)),
        ("worst_err_z_m", Some(w.z_m)),
        ("worst_err_alpha_deg", Some(w.alpha_deg)),
        ("worst_err_beta_deg", Some(w.beta_deg)),
        ("worst_err_gamma_deg", Some(w.gamma_deg)),
        ("p99_err_x_m", Some(p.x_m)),
        ("p99_err_y_m", Some(p.y_m)),
        ("p99_err_z_m", Some(p.z_m)),
        ("min_separation_m", Some(s.min_separation_m)),
        ("unsafe_runs", Some(s.unsafe_runs as f64)),
        ("off_path_runs", Some(s.off_path_runs as f64)),
        ("adjustments_per_uav_minute", Some(s.adjustments_per_uav_minute)),
        ("held_fraction", Some(s.swarm.held_fraction)),
        ("within_allowable_fraction", Some(s.swarm.within_allowable_fraction)),
        ("control_effort", Some(s.swarm.control_effort)),
        ("radio_used_per_uav_s", Some(s.swarm.radio_used_per_uav_s)),
    ];
    r.push(("healthy_pass_fraction", s.sensor_faults.as_ref().map(|f| f.healthy_pass_fraction)));
    r.push(("formed_fraction", s.forming.as_ref().map(|f| f.formed_fraction)));
    r.push(("time_to_form_s_median", s.forming.as_ref().map(|f| f.time_to_form_s_median)));
    r.push(("transitions_completed_fraction", s.transitions.as_ref().map(|t| t.completed_fraction)));
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_is_every_combination_first_key_slowest() {
        let axes = vec![
            ("a".to_string(), vec!["1".into(), "2".into()]),
            ("b".to_string(), vec!["x".into(), "y".into(), "z".into()]),
        ];
        let c = cells(&axes);
        assert_eq!(c.len(), 6);
        assert_eq!(c[0], vec![("a", "1"), ("b", "x")]);
        assert_eq!(c[2], vec![("a", "1"), ("b", "z")]);
        assert_eq!(c[3], vec![("a", "2"), ("b", "x")]);
        assert_eq!(cells(&[]).len(), 1);
    }
}
