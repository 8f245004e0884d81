//! Output files: `summary.json` and `trajectories.csv`. Units: SI and radians in the CSV's
//! state columns, errors in m and degrees (the report units).

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use anyhow::{Context, Result};
use proxform_sim::{Summary, Trajectory};

/// Writes the batch summary as pretty JSON.
pub fn write_summary(path: &Path, summary: &Summary) -> Result<()> {
    let f = File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    serde_json::to_writer_pretty(BufWriter::new(f), summary).with_context(|| format!("cannot write {}", path.display()))
}

/// Writes one row per UAV per step.
pub fn write_trajectories(path: &Path, traj: &Trajectory) -> Result<()> {
    let f = File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut w = csv::Writer::from_writer(BufWriter::new(f));
    w.write_record([
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
    let mut rec: Vec<String> = Vec::with_capacity(20);
    for r in &traj.rows {
        rec.clear();
        rec.push(format!("{:.1}", r.t));
        rec.push((r.uav + 1).to_string());
        rec.extend(r.state.iter().map(|v| format!("{v:.6}")));
        rec.extend(r.error[..3].iter().map(|v| format!("{v:.6}")));
        rec.extend(r.error[3..].iter().map(|v| format!("{:.6}", v.to_degrees())));
        rec.push(u8::from(r.in_envelope).to_string());
        rec.push(u8::from(r.within_allowable).to_string());
        rec.push(r.outcome.to_string());
        w.write_record(&rec)?;
    }
    w.flush().with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}
