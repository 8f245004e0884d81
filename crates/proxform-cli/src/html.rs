//! `report.html`: one self-contained page of an output folder (`proxform report DIR`, and
//! beside every run's outputs): the summary and per-UAV tables, the conditions flown (wind,
//! noise, losses, faults, tolerances), each follower's errors over time within the allowable
//! bands, their distribution over the runs, and a 3-D replay of the first run (play, pause,
//! scrub, speed, orbit; UAV ids, formation links, trails, the navigator's planned path, close
//! pairs and faults in time). The page's code is the project's own (`assets/report.js`,
//! `assets/report.css`), inlined with the data: it opens from disk and fetches nothing.
//!
//! Its size is bounded whatever the flight (about 5 MB at most): at most [`MAX_REPLAY_FRAMES`]
//! replay frames and [`MAX_REPLAY_VALUES`] positions in all, [`MAX_SERIES_POINTS`] points of
//! the error series of at most [`MAX_SERIES_UAVS`] UAVs, [`HIST_BINS`] bins per distribution;
//! the files are read as streams.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use proxform_scenario::faults::Fault;
use proxform_scenario::Scenario;
use serde_json::{json, Value};

/// The page's file name in an output folder.
pub const REPORT_FILE: &str = "report.html";
/// Most frames of the replay.
pub const MAX_REPLAY_FRAMES: usize = 1500;
/// Most UAV positions of the replay in all (frames × UAVs).
pub const MAX_REPLAY_VALUES: usize = 100_000;
/// Most points of an error series.
pub const MAX_SERIES_POINTS: usize = 500;
/// Most UAVs whose errors over time are drawn (the first ones recorded).
pub const MAX_SERIES_UAVS: usize = 48;
/// Bins of a distribution over the runs.
pub const HIST_BINS: usize = 30;

const TEMPLATE: &str = include_str!("../assets/report.html");
const SCRIPT: &str = include_str!("../assets/report.js");
const STYLE: &str = include_str!("../assets/report.css");

/// The error axes as `summary.json` and `runs.csv` name them, and as the page shows them.
const AXES: [(&str, &str, &str); 6] = [
    ("x_m", "max_err_x_m", "x (m)"),
    ("y_m", "max_err_y_m", "y (m)"),
    ("z_m", "max_err_z_m", "z (m)"),
    ("alpha_deg", "max_err_alpha_deg", "α (°)"),
    ("beta_deg", "max_err_beta_deg", "β (°)"),
    ("gamma_deg", "max_err_gamma_deg", "γ (°)"),
];

/// Writes `report.html` for the output folder `dir`, of `scenario` when given, else of the
/// folder's `scenario.toml` when it has one (without it, the page has no planned path,
/// links or faults).
pub fn write(dir: &Path, scenario: Option<&Scenario>) -> Result<PathBuf> {
    let loaded;
    let scenario = match scenario {
        Some(s) => Some(s),
        None => {
            let path = dir.join(crate::provenance::SCENARIO_FILE);
            loaded = match path.is_file() {
                true => {
                    let (spec, source) = crate::scenarios::load_spec(&path)?;
                    Some(crate::scenarios::check(spec, &source)?)
                }
                false => None,
            };
            loaded.as_ref()
        }
    };
    let data = data(dir, scenario)?;
    let path = dir.join(REPORT_FILE);
    let page = page(&data);
    std::io::Write::write_all(&mut crate::files::create_output(&path)?, page.as_bytes())
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}

/// Text safe inside HTML.
fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '&' => out.push_str("&amp;"),
            '"' => out.push_str("&quot;"),
            c if c.is_control() => out.push('\u{fffd}'),
            c => out.push(c),
        }
    }
    out
}

/// The page: the template with its style, script and data inlined. The data's JSON cannot end
/// its script element (`<` is written `\u003c`).
fn page(data: &Value) -> String {
    let json = data.to_string().replace('<', "\\u003c");
    // (Braces too: the title is placed first, and must hold no placeholder of the others.)
    let title = escape(data["name"].as_str().unwrap_or("proxform")).replace('{', "&#123;").replace('}', "&#125;");
    TEMPLATE
        .replace("{{TITLE}}", &title)
        .replace("/*{{STYLE}}*/", STYLE)
        .replace("/*{{SCRIPT}}*/", &SCRIPT.replace("</", "<\\/"))
        .replace("{{DATA}}", &json)
}

/// Everything the page shows, as JSON.
fn data(dir: &Path, scenario: Option<&Scenario>) -> Result<Value> {
    let summary_path = dir.join("summary.json");
    let text = crate::files::read_input(&summary_path, "summary")?;
    let summary: Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not a proxform summary", summary_path.display()))?;
    // What the page reads, there and of its kind (else the page would stop half drawn).
    const AXES_OF: [&str; 5] = ["worst_abs_error", "p99_abs_error", "median_abs_error", "rms_error", "allowable_error"];
    const NUMBERS: [&str; 9] = [
        "uavs",
        "runs",
        "seed",
        "pass_fraction",
        "safety_distance_m",
        "min_separation_m",
        "unsafe_runs",
        "off_path_runs",
        "adjustments_per_uav_minute",
    ];
    const LISTS: [&str; 5] =
        ["per_uav", "per_uav_worst", "per_uav_adjustments", "per_uav_runs_flown", "per_uav_runs_passed"];
    let missing =
        |key: &str, what: &str| anyhow::anyhow!("{}: not a proxform summary ({key}: {what})", summary_path.display());
    if !summary.is_object() {
        bail!("{}: not a proxform summary (not a JSON object)", summary_path.display());
    }
    for key in AXES_OF {
        let axes = summary.get(key).ok_or_else(|| missing(key, "missing"))?;
        if AXES.iter().any(|a| axes.get(a.0).is_none()) {
            return Err(missing(key, "not the six axes"));
        }
    }
    for key in NUMBERS {
        if !summary.get(key).is_some_and(|v| v.is_number() || v.is_null()) {
            return Err(missing(key, "not a number"));
        }
    }
    let followers = summary.get("per_uav").and_then(Value::as_array).map_or(0, Vec::len);
    for key in LISTS {
        if summary.get(key).and_then(Value::as_array).map(Vec::len) != Some(followers) {
            return Err(missing(key, "not a list of one entry per follower"));
        }
    }
    if summary["per_uav_worst"].as_array().into_iter().flatten().any(|w| AXES.iter().any(|a| w.get(a.0).is_none())) {
        return Err(missing("per_uav_worst", "not the six axes for every follower"));
    }
    let (version, command) = header(dir);
    let runs = dir.join("runs.csv");
    let hist = if runs.is_file() { histograms(&runs)? } else { Value::Null };
    let traj = dir.join("trajectories.csv");
    let (replay, series) = if traj.is_file() { trajectories(&traj)? } else { (Value::Null, Value::Null) };
    let name = summary["scenario"].as_str().unwrap_or("flight").to_string();
    let mut data = json!({
        "name": name,
        "version": version.unwrap_or_else(crate::provenance::version),
        "command": command,
        "axes": AXES.iter().map(|a| json!({"key": a.0, "label": a.2})).collect::<Vec<_>>(),
        "summary": summary,
        "hist": hist,
        "replay": replay,
        "series": series,
    });
    if let Some(sc) = scenario {
        data["scenario"] = of_scenario(sc, &data["replay"]);
    }
    Ok(data)
}

/// The version and command line from the folder's `scenario.toml` header, if any.
fn header(dir: &Path) -> (Option<String>, Option<String>) {
    let Ok(text) = std::fs::read_to_string(dir.join(crate::provenance::SCENARIO_FILE)) else {
        return (None, None);
    };
    let mut version = None;
    let mut command = None;
    for line in text.lines().take_while(|l| l.starts_with('#')) {
        if let Some(v) =
            line.strip_prefix("# The scenario as ").and_then(|l| l.strip_suffix(" ran it, every default filled in."))
        {
            version = Some(v.to_string());
        }
        if let Some(c) = line.strip_prefix("# Command: ") {
            command = Some(c.to_string());
        }
    }
    (version, command)
}

/// Distributions over the runs of each axis's worst error and the minimum separation, from
/// `runs.csv` (two passes: the range, then the counts).
fn histograms(path: &Path) -> Result<Value> {
    let mut columns: Vec<(&str, &str)> = AXES.iter().map(|a| (a.0, a.1)).collect();
    columns.push(("min_separation_m", "min_separation_m"));
    let read = |pass: &mut dyn FnMut(&[f64])| -> Result<()> {
        let mut r = csv::Reader::from_path(path).with_context(|| format!("cannot read {}", path.display()))?;
        let heads = r.headers().with_context(|| format!("{}: no header", path.display()))?.clone();
        let at: Vec<Option<usize>> = columns.iter().map(|(_, c)| heads.iter().position(|h| h == *c)).collect();
        let mut row = vec![f64::NAN; at.len()];
        for rec in r.records() {
            let rec = rec.with_context(|| format!("cannot read {}", path.display()))?;
            for (v, i) in row.iter_mut().zip(&at) {
                *v = i.and_then(|i| rec.get(i)).and_then(|s| s.parse().ok()).unwrap_or(f64::NAN);
            }
            pass(&row);
        }
        Ok(())
    };
    let mut hi = vec![f64::NEG_INFINITY; columns.len()];
    let mut lo = vec![f64::INFINITY; columns.len()];
    let mut n = 0u64;
    read(&mut |row| {
        n += 1;
        for (j, v) in row.iter().enumerate().filter(|(_, v)| v.is_finite()) {
            hi[j] = hi[j].max(*v);
            lo[j] = lo[j].min(*v);
        }
    })?;
    let mut counts = vec![vec![0u64; HIST_BINS]; columns.len()];
    let width: Vec<f64> =
        lo.iter().zip(&hi).map(|(l, h)| if h > l { (h - l) / HIST_BINS as f64 } else { 1.0 }).collect();
    read(&mut |row| {
        for (j, v) in row.iter().enumerate().filter(|(_, v)| v.is_finite()) {
            let b = (((v - lo[j]) / width[j]) as usize).min(HIST_BINS - 1);
            counts[j][b] += 1;
        }
    })?;
    let mut out = serde_json::Map::new();
    out.insert("runs".into(), json!(n));
    for (j, (key, _)) in columns.iter().enumerate() {
        if hi[j] >= lo[j] {
            out.insert((*key).into(), json!({"lo": lo[j], "width": width[j], "counts": counts[j]}));
        }
    }
    Ok(Value::Object(out))
}

/// The replay and the error series of the first run, from `trajectories.csv` (two passes: its
/// times and UAVs, then the rows kept).
fn trajectories(path: &Path) -> Result<(Value, Value)> {
    let open = || -> Result<(csv::Reader<std::fs::File>, [usize; 12])> {
        let mut r = csv::Reader::from_path(path).with_context(|| format!("cannot read {}", path.display()))?;
        let heads = r.headers().with_context(|| format!("{}: no header", path.display()))?.clone();
        let names = [
            "t_s",
            "uav",
            "x_m",
            "y_m",
            "z_m",
            "err_x_m",
            "err_y_m",
            "err_z_m",
            "err_alpha_deg",
            "err_beta_deg",
            "err_gamma_deg",
            "within_allowable",
        ];
        let mut at = [0; 12];
        for (a, n) in at.iter_mut().zip(names) {
            *a = heads.iter().position(|h| h == n).with_context(|| format!("{}: no column {n}", path.display()))?;
        }
        Ok((r, at))
    };
    let number = |rec: &csv::StringRecord, i: usize| -> Result<f64> {
        let s = rec.get(i).unwrap_or("");
        s.parse().with_context(|| format!("{}: \"{s}\" is not a number", path.display()))
    };
    // Pass 1: the times (rows come in time order) and the UAVs.
    let (mut r, at) = open()?;
    let mut times = 0usize;
    let mut last_t = f64::NAN;
    let mut uavs = std::collections::BTreeSet::new();
    for rec in r.records() {
        let rec = rec.with_context(|| format!("cannot read {}", path.display()))?;
        let t = number(&rec, at[0])?;
        if t != last_t {
            times += 1;
            last_t = t;
        }
        uavs.insert(number(&rec, at[1])? as u32);
    }
    let uavs: Vec<u32> = uavs.into_iter().collect();
    let n = uavs.len().max(1);
    let frames = MAX_REPLAY_FRAMES.min(MAX_REPLAY_VALUES / n).max(2);
    let every = times.div_ceil(frames).max(1);
    let series_every = times.div_ceil(MAX_SERIES_POINTS).max(1);
    let slot = |u: u32| uavs.binary_search(&u).ok();
    // Pass 2: the rows of the frames kept. Absent UAVs (not yet joined, removed) are null.
    let (mut r, at) = open()?;
    let (mut t_replay, mut pos, mut ok) = (Vec::new(), Vec::<Value>::new(), String::new());
    let (mut t_series, mut err) = (Vec::new(), Vec::<Value>::new());
    let mut index = usize::MAX;
    last_t = f64::NAN;
    let (mut keep, mut keep_series) = (false, false);
    for rec in r.records() {
        let rec = rec.with_context(|| format!("cannot read {}", path.display()))?;
        let t = number(&rec, at[0])?;
        if t != last_t {
            last_t = t;
            index = index.wrapping_add(1);
            keep = index % every == 0 || index + 1 == times;
            keep_series = index % series_every == 0 || index + 1 == times;
            if keep {
                t_replay.push(t);
                pos.extend(std::iter::repeat_n(Value::Null, 3 * n));
                ok.extend(std::iter::repeat_n('-', n));
            }
            if keep_series {
                t_series.push(t);
                err.extend(std::iter::repeat_n(Value::Null, 6 * n));
            }
        }
        let Some(j) = slot(number(&rec, at[1])? as u32) else { continue };
        if keep {
            let base = (t_replay.len() - 1) * 3 * n + 3 * j;
            for k in 0..3 {
                pos[base + k] = json!(number(&rec, at[2 + k])?);
            }
            let f = (t_replay.len() - 1) * n + j;
            let within = rec.get(at[11]) == Some("1");
            ok.replace_range(f..f + 1, if within { "1" } else { "0" });
        }
        if keep_series {
            let base = (t_series.len() - 1) * 6 * n + 6 * j;
            for k in 0..6 {
                let v = number(&rec, at[5 + k])?;
                // Four significant digits are what a figure shows.
                err[base + k] = json!(format!("{v:.4e}").parse::<f64>().unwrap_or(v));
            }
        }
    }
    // The error series of the first UAVs recorded only (the replay has them all).
    let shown = n.min(MAX_SERIES_UAVS);
    let err: Vec<Value> = err.chunks(6 * n).flat_map(|frame| frame[..6 * shown].iter().cloned()).collect();
    let replay = json!({"times": t_replay, "uavs": uavs, "pos": pos, "within": ok});
    let series = json!({"times": t_series, "uavs": &uavs[..shown], "err": err, "recorded": uavs.len()});
    Ok((replay, series))
}

/// What the scenario adds: the conditions flown, the tolerances, the navigator, the
/// formation's links, the navigator's planned path over the replay's times, and the faults.
fn of_scenario(sc: &Scenario, replay: &Value) -> Value {
    let allow = sc.allowable().as_array();
    let allowable: Vec<f64> = allow.iter().enumerate().map(|(k, a)| if k < 3 { *a } else { a.to_degrees() }).collect();
    let mut links = Vec::new();
    for (i, deps) in sc.dependencies().iter().enumerate() {
        for (r, _) in deps.refs() {
            links.push([i as u32 + 1, r.0 + 1]);
        }
    }
    let end = replay["times"].as_array().and_then(|t| t.last()).and_then(Value::as_f64).unwrap_or(sc.duration_s());
    let steps = 400usize;
    let path: Vec<[f64; 4]> = (0..=steps)
        .map(|k| {
            let t = end * k as f64 / steps as f64;
            let s = sc.path().state_at(t, [0.0; 3]);
            [t, s[0], s[1], s[2]]
        })
        .collect();
    let events: Vec<Value> = sc
        .faults()
        .iter()
        .map(|f| {
            let (t, what) = match f {
                Fault::Remove { at_s, .. } => (*at_s, "removed".to_string()),
                Fault::Join { at_s, .. } => (*at_s, "joins".to_string()),
                Fault::Glitch { at_s, duration_s, offset_m, .. } => {
                    (*at_s, format!("position glitch {:.1} m for {duration_s} s", offset_m.norm()))
                }
                Fault::StuckSensor { at_s, duration_s, .. } => (*at_s, format!("stuck sensor for {duration_s} s")),
                Fault::RadioBlackout { at_s, duration_s } => (*at_s, format!("radio blackout for {duration_s} s")),
            };
            json!({"t": t, "uav": f.uav().map(|u| u.0 + 1), "what": what})
        })
        .chain(sc.schedule().stages().iter().map(|s| json!({"t": s.at_s, "uav": null, "what": "formation change"})))
        .collect();
    let mut events = events;
    events.sort_by(|a, b| a["t"].as_f64().unwrap_or(0.0).total_cmp(&b["t"].as_f64().unwrap_or(0.0)));
    json!({
        "allowable": allowable,
        "safety_m": sc.safety_distance_m(),
        "navigator": sc.navigator().0 + 1,
        "links": links,
        "path": path,
        "events": events,
        "conditions": conditions(sc),
    })
}

/// `v` to four significant digits, without trailing zeros.
fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (3 - v.abs().log10().floor() as i32).clamp(0, 12) as usize;
    let s = format!("{v:.digits$}");
    match s.contains('.') {
        true => s.trim_end_matches('0').trim_end_matches('.').to_string(),
        false => s,
    }
}

/// The disturbances, losses and faults the scenario flies, in words (empty: none).
pub fn conditions(sc: &Scenario) -> Vec<String> {
    let mut out = Vec::new();
    let noise = sc.noise();
    out.push(format!(
        "measurement noise σ {} m, {} m/s, {}°",
        short(noise.position_m),
        short(noise.velocity_mps),
        short(noise.attitude_rad.to_degrees())
    ));
    if sc.actuation_error() > 0.0 {
        out.push(format!("actuation error {} %", short(100.0 * sc.actuation_error())));
    }
    if let Some(b) = sc.gnss_bias() {
        out.push(format!("GNSS bias σ {} m (correlation time {} s)", short(b.sigma_m), short(b.tau_s)));
    }
    if sc.dropout() > 0.0 {
        out.push(format!("observations dropped {} %", short(100.0 * sc.dropout())));
    }
    if sc.relative_sensing() {
        out.push("relative sensing (neighbours in the UAV's own frame)".into());
    }
    let radio = sc.radio();
    match radio.burst {
        // The long-run share lost, then how it comes.
        Some(b) => out.push(format!(
            "radio loss {:.1} % in the long run (bursty: {:.0} % lost in the bad state, {:.1} % of the time{})",
            100.0 * radio.mean_loss(),
            100.0 * b.loss_bad,
            100.0 * b.bad_fraction(),
            if radio.loss > 0.0 { format!("; {:.1} % besides", 100.0 * radio.loss) } else { String::new() }
        )),
        None if radio.loss > 0.0 => out.push(format!("radio loss {:.1} %", 100.0 * radio.loss)),
        None => {}
    }
    if radio.delay_steps > 0 {
        out.push(format!("radio delay {} step(s)", radio.delay_steps));
    }
    let w = sc.wind();
    if w.steady_mps.norm() > 0.0 {
        out.push(format!("steady wind {:.1} km/h", w.steady_mps.norm() * 3.6));
    }
    if let Some(t) = &w.turbulence {
        let severity = format!("{:?}", t.severity).to_lowercase();
        out.push(format!("{severity} Dryden turbulence (at {} m)", short(t.altitude_m)));
    }
    if w.gust.is_some() {
        out.push("a gust".into());
    }
    let net = sc.network();
    if net.loss > 0.0 {
        out.push(format!("network loss {:.1} %", 100.0 * net.loss));
    }
    if net.delay_s > 0.0 {
        out.push(format!("network delay {} s", short(net.delay_s)));
    }
    if !sc.faults().is_empty() {
        out.push(format!("{} fault(s)", sc.faults().len()));
    }
    if !sc.schedule().is_empty() {
        out.push(format!("{} formation change(s)", sc.schedule().stages().len()));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_short() {
        assert_eq!(short(0.049_999_999_999_999_96), "0.05");
        assert_eq!(short(0.02), "0.02");
        assert_eq!(short(1234.5678), "1235");
        assert_eq!(short(0.5729578), "0.573");
        assert_eq!(short(0.0), "0");
    }

    #[test]
    fn the_data_cannot_end_its_script_and_the_title_is_text() {
        let data = json!({"name": "<script>alert(1)</script>\u{7}", "x": "</script><b>"});
        let page = page(&data);
        assert!(!page.contains("<script>alert"), "the title is escaped");
        assert!(!page.contains("</script><b>"), "the data cannot close its element");
        assert!(page.contains("&lt;script&gt;alert(1)&lt;/script&gt;\u{fffd}"));
    }
}
