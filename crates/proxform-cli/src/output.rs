//! Output files: `summary.json`, `runs.csv` and `trajectories.csv`. Units: SI and radians in
//! the trajectories' state columns, errors in m and degrees (the report units).

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use anyhow::{Context, Result};
use proxform_sim::measure::trajectory::RowSink;
use proxform_sim::{AxisErrors, RunSummary, Summary, TrajectoryRow};

/// Writes the batch summary as pretty JSON.
pub fn write_summary(path: &Path, summary: &Summary) -> Result<()> {
    let f = File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    serde_json::to_writer_pretty(BufWriter::new(f), summary).with_context(|| format!("cannot write {}", path.display()))
}

/// Writes one row per run: the figures a paper tabulates or plots across seeds.
pub fn write_runs(path: &Path, seed: u64, runs: &[RunSummary]) -> Result<()> {
    let f = File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut w = csv::Writer::from_writer(BufWriter::new(f));
    const AXES: [&str; 6] = ["x_m", "y_m", "z_m", "alpha_deg", "beta_deg", "gamma_deg"];
    let mut header: Vec<String> = ["seed", "run", "pass", "judged_steps"].iter().map(|s| s.to_string()).collect();
    header.extend(AXES.iter().map(|a| format!("max_err_{a}")));
    header.extend(AXES.iter().map(|a| format!("rms_err_{a}")));
    header.extend(
        [
            "min_separation_m",
            "close_pairs",
            "adjustments_per_uav_minute",
            "held_fraction",
            "within_allowable_fraction",
            "control_effort",
            "radio_sent_per_uav_s",
            "radio_used_per_uav_s",
            "order_mean",
            "order_min",
            "connectivity_min",
            "alone_s_per_uav",
            "path_deviation_m",
        ]
        .iter()
        .map(|s| s.to_string()),
    );
    // Fault and isolation columns only for the runs that have them.
    let faults = runs.first().is_some_and(|r| r.sensor_faults.is_some());
    let isolation = runs.first().is_some_and(|r| r.isolation.is_some());
    let forming = runs.first().is_some_and(|r| r.forming.is_some());
    let transitions = runs.iter().any(|r| r.transitions.is_some());
    let flown = runs.first().is_some_and(|r| r.flown.is_some());
    if faults {
        header.extend(["healthy_pass", "rejoin_s"].map(String::from));
    }
    if forming {
        header.extend(["time_to_form_s", "transient_error_ratio", "settled_error_ratio"].map(String::from));
    }
    if transitions {
        header.extend(["transition_s", "transition_error_ratio", "transition_closest_m"].map(String::from));
    }
    if flown {
        header.extend(["path_length_m_per_uav", "delta_v_mps_per_uav", "work_j_per_kg_per_uav"].map(String::from));
    }
    if isolation {
        header.extend(
            ["isolating_s_per_uav", "isolated_per_uav_s", "own_suspect_s_per_uav", "own_suspect_episodes"]
                .map(String::from),
        );
    }
    w.write_record(&header)?;
    // Errors in the report's units: metres, and degrees for the attitudes.
    for r in runs {
        let mut rec =
            vec![seed.to_string(), r.run.to_string(), u8::from(r.pass).to_string(), r.judged_steps.to_string()];
        let (max, rms) = (AxisErrors::from_si(r.max_abs_error).as_array(), AxisErrors::from_si(r.rms_error).as_array());
        rec.extend(max.iter().chain(&rms).map(|v| format!("{v:.6}")));
        rec.extend([
            format!("{:.3}", r.min_separation_m),
            r.close_pairs.to_string(),
            format!("{:.3}", r.adjustments_per_uav_minute()),
            format!("{:.6}", r.held_fraction),
            format!("{:.6}", r.within_allowable_fraction),
            format!("{:.6}", r.control_effort),
            format!("{:.3}", r.radio_sent_per_uav_s),
            format!("{:.3}", r.radio_used_per_uav_s),
            format!("{:.6}", r.order_mean),
            format!("{:.6}", r.order_min),
            format!("{:.6}", r.connectivity_min),
            format!("{:.3}", r.alone_s_per_uav),
            format!("{:.6}", r.path_deviation_m),
        ]);
        if let (true, Some(f)) = (faults, r.sensor_faults) {
            rec.extend([u8::from(f.healthy_pass).to_string(), format!("{:.3}", f.rejoin_s)]);
        }
        if let (true, Some(f)) = (forming, r.forming) {
            rec.extend([
                format!("{:.3}", f.time_to_form_s),
                format!("{:.4}", f.transient_error_ratio),
                f.settled_error_ratio.map_or_else(String::new, |v| format!("{v:.4}")),
            ]);
        }
        if transitions {
            // Slots re-assigned in flight change the formation in some runs only.
            rec.extend(match r.transitions {
                Some(c) => [
                    format!("{:.3}", c.transition_s),
                    format!("{:.4}", c.transient_error_ratio),
                    format!("{:.3}", c.closest_m),
                ],
                None => [String::new(), String::new(), String::new()],
            });
        }
        if let (true, Some(f)) = (flown, r.flown) {
            rec.extend([
                format!("{:.1}", f.path_length_m_per_uav),
                format!("{:.2}", f.delta_v_mps_per_uav),
                format!("{:.1}", f.work_j_per_kg_per_uav),
            ]);
        }
        if let (true, Some(i)) = (isolation, r.isolation) {
            rec.extend([
                format!("{:.3}", i.isolating_s_per_uav),
                format!("{:.6}", i.isolated_per_uav_s),
                format!("{:.3}", i.own_suspect_s_per_uav),
                i.own_suspect_episodes.to_string(),
            ]);
        }
        w.write_record(&rec)?;
    }
    w.flush().with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// `trajectories.csv`, written row by row as the flight goes: one row per recorded UAV per
/// step (every step up to 10^6 steps, evenly decimated beyond).
pub struct TrajectoryCsv {
    path: std::path::PathBuf,
    writer: csv::Writer<BufWriter<File>>,
    /// Decimals of the time column: enough for the update period.
    time_decimals: usize,
    record: Vec<String>,
    error: Option<String>,
}

impl TrajectoryCsv {
    /// Creates the file and writes its header; `dt_s` sets the time column's decimals.
    pub fn create(path: &Path, dt_s: f64) -> Result<Self> {
        let f = File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
        let mut writer = csv::Writer::from_writer(BufWriter::new(f));
        writer.write_record([
            "t_s",
            "uav",
            "x_m",
            "y_m",
            "z_m",
            "vx_mps",
            "vy_mps",
            "vz_mps",
            "alpha_rad",
            "beta_rad",
            "gamma_rad",
            "err_x_m",
            "err_y_m",
            "err_z_m",
            "err_alpha_deg",
            "err_beta_deg",
            "err_gamma_deg",
            "in_envelope",
            "within_allowable",
            "outcome",
        ])?;
        let time_decimals = (-dt_s.log10()).ceil().clamp(1.0, 9.0) as usize;
        Ok(Self { path: path.into(), writer, time_decimals, record: Vec::with_capacity(20), error: None })
    }
}

impl RowSink for TrajectoryCsv {
    fn row(&mut self, r: &TrajectoryRow) {
        if self.error.is_some() {
            return;
        }
        let rec = &mut self.record;
        rec.clear();
        rec.push(format!("{:.*}", self.time_decimals, r.t));
        rec.push((r.uav + 1).to_string());
        rec.extend(r.state.iter().map(|v| format!("{v:.6}")));
        rec.extend(r.error[..3].iter().map(|v| format!("{v:.6}")));
        rec.extend(r.error[3..].iter().map(|v| format!("{:.6}", v.to_degrees())));
        rec.push(u8::from(r.in_envelope).to_string());
        rec.push(u8::from(r.within_allowable).to_string());
        rec.push(r.outcome.to_string());
        if let Err(e) = self.writer.write_record(&*rec) {
            self.error = Some(format!("cannot write {}: {e}", self.path.display()));
        }
    }

    fn finish(&mut self) -> std::result::Result<(), String> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.writer.flush().map_err(|e| format!("cannot write {}: {e}", self.path.display()))
    }
}
