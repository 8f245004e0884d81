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
    let f = crate::files::create_output(path)?;
    serde_json::to_writer_pretty(BufWriter::new(f), summary).with_context(|| format!("cannot write {}", path.display()))
}

/// Which optional column groups `runs.csv` has: those of the parts the batch's first run has
/// (every run of a scenario has them alike), and the transitions' when any run has them.
#[derive(Debug, Clone, Copy, Default)]
pub struct RunColumns {
    faults: bool,
    forming: bool,
    transitions: bool,
    flown: bool,
    isolation: bool,
    uncontrolled: bool,
}

impl RunColumns {
    /// The columns of a batch whose first run is `first` and whose summary is `summary`:
    /// `transitions` when some run changed formation, `uncontrolled_s` when in some run a
    /// follower flew without its agent.
    pub fn of(first: &RunSummary, summary: Option<&proxform_sim::Summary>) -> Self {
        Self {
            faults: first.sensor_faults.is_some(),
            forming: first.forming.is_some(),
            transitions: summary.is_some_and(|s| s.transitions.is_some()),
            flown: first.flown.is_some(),
            isolation: first.isolation.is_some(),
            uncontrolled: summary.is_some_and(|s| s.uncontrolled.is_some()),
        }
    }
}

/// `runs.csv`, one row per run in run order: the figures a paper tabulates or plots across
/// seeds, written as the rows come (a batch of any size in bounded memory).
pub struct RunsCsv {
    path: std::path::PathBuf,
    w: csv::Writer<BufWriter<File>>,
    seed: u64,
    columns: RunColumns,
}

impl RunsCsv {
    /// Creates the file and writes its header.
    pub fn create(path: &Path, seed: u64, columns: RunColumns) -> Result<Self> {
        let f = crate::files::create_output(path)?;
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
        let c = columns;
        if c.faults {
            header.extend(["healthy_pass", "rejoin_s"].map(String::from));
        }
        if c.forming {
            header.extend(["time_to_form_s", "transient_error_ratio", "settled_error_ratio"].map(String::from));
        }
        if c.transitions {
            header.extend(["transition_s", "transition_error_ratio", "transition_closest_m"].map(String::from));
        }
        if c.flown {
            header.extend(["path_length_m_per_uav", "delta_v_mps_per_uav", "work_j_per_kg_per_uav"].map(String::from));
        }
        if c.isolation {
            header.extend(
                ["isolating_s_per_uav", "isolated_per_uav_s", "own_suspect_s_per_uav", "own_suspect_episodes"]
                    .map(String::from),
            );
        }
        if c.uncontrolled {
            header.push("uncontrolled_s".into());
        }
        w.write_record(&header).with_context(|| format!("cannot write {}", path.display()))?;
        Ok(Self { path: path.into(), w, seed, columns })
    }

    /// Writes the next run's row (errors in the report's units: metres, and degrees for the
    /// attitudes).
    pub fn write(&mut self, r: &RunSummary) -> Result<()> {
        let c = self.columns;
        let mut rec =
            vec![self.seed.to_string(), r.run.to_string(), u8::from(r.pass).to_string(), r.judged_steps.to_string()];
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
        if let (true, Some(f)) = (c.faults, r.sensor_faults) {
            rec.extend([u8::from(f.healthy_pass).to_string(), format!("{:.3}", f.rejoin_s)]);
        }
        if let (true, Some(f)) = (c.forming, r.forming) {
            rec.extend([
                format!("{:.3}", f.time_to_form_s),
                format!("{:.4}", f.transient_error_ratio),
                f.settled_error_ratio.map_or_else(String::new, |v| format!("{v:.4}")),
            ]);
        }
        if c.transitions {
            // Slots re-assigned in flight change the formation in some runs only.
            rec.extend(match r.transitions {
                Some(t) => [
                    format!("{:.3}", t.transition_s),
                    format!("{:.4}", t.transient_error_ratio),
                    format!("{:.3}", t.closest_m),
                ],
                None => [String::new(), String::new(), String::new()],
            });
        }
        if let (true, Some(f)) = (c.flown, r.flown) {
            rec.extend([
                format!("{:.1}", f.path_length_m_per_uav),
                format!("{:.2}", f.delta_v_mps_per_uav),
                format!("{:.1}", f.work_j_per_kg_per_uav),
            ]);
        }
        if let (true, Some(i)) = (c.isolation, r.isolation) {
            rec.extend([
                format!("{:.3}", i.isolating_s_per_uav),
                format!("{:.6}", i.isolated_per_uav_s),
                format!("{:.3}", i.own_suspect_s_per_uav),
                i.own_suspect_episodes.to_string(),
            ]);
        }
        if c.uncontrolled {
            rec.push(format!("{:.1}", r.uncontrolled_s));
        }
        self.w.write_record(&rec).with_context(|| format!("cannot write {}", self.path.display()))
    }

    /// Flushes the file.
    pub fn finish(mut self) -> Result<()> {
        self.w.flush().with_context(|| format!("cannot write {}", self.path.display()))
    }
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
        let f = crate::files::create_output(path)?;
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
