//! Figures mirroring the paper's Figures 4-10, as PNG and SVG.
//!
//! Figures 4-9: for one parameter (x, y, z, α, β, γ), (a) the recorded UAVs' values over time
//! and (b) the followers' errors relative to the navigator with the allowable band. Each UAV is
//! drawn over the steps it flew (a removed UAV's line stops, a joining one's starts); a large
//! swarm shows the UAVs its trajectory recorded (the first ones), without a legend beyond a
//! dozen. Figure 10:
//! (a) the 3-D tracks, (b) the attitude overview. The PNG text uses DejaVu Sans, embedded in
//! the binary so no system font library is needed.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use anyhow::{anyhow, Result};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::{CoordTranslate, Shift};
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use proxform_scenario::Scenario;
use proxform_sim::Trajectory;

/// One method's curve: its name and (x, median, p95) points.
type Curve = (String, Vec<(f64, f64, f64)>);
/// One method's pass fractions: its name and (x, pass fraction, interval low, high) points.
type PassLine = (String, Vec<(f64, f64, f64, f64)>);

const FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// How a run's figures are drawn (`--figure-size`, `--figure-dpi`): their size in pixels at
/// 100 DPI, and their scale (DPI / 100), by which a PNG's pixels, text, lines and margins
/// grow (an SVG keeps the size: it scales itself).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Look {
    /// Width and height (px at 100 DPI).
    pub size: (u32, u32),
    /// DPI / 100.
    pub scale: f64,
}

impl Default for Look {
    fn default() -> Self {
        Self { size: (1000, 760), scale: 1.0 }
    }
}

impl Look {
    /// The most pixels a PNG may have.
    pub const MAX_PIXELS: f64 = 1e8;

    /// `v` px at 100 DPI, at this scale.
    fn px(&self, v: u32) -> u32 {
        ((f64::from(v) * self.scale).round() as u32).max(1)
    }

    fn font(&self, v: u32) -> (&'static str, u32) {
        ("sans-serif", self.px(v))
    }

    /// The PNG's size in pixels.
    fn pixels(&self) -> (u32, u32) {
        (self.px(self.size.0), self.px(self.size.1))
    }

    /// The same figure as SVG (unscaled: it scales itself).
    fn for_svg(&self) -> Self {
        Self { scale: 1.0, ..*self }
    }
}

/// A tick's label: the shortest decimal that says it (30, not 30.0; 0, not -0.0).
fn tick(v: &f64) -> String {
    if v.abs() < 1e-9 {
        return "0".into();
    }
    if v.abs() >= 1e6 || v.abs() < 1e-4 {
        return format!("{v:.2e}");
    }
    let s = format!("{v:.6}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// The mesh of a time or plan chart: tick labels without trailing zeros, axes described.
fn mesh<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    look: &Look,
    (x_desc, y_desc): (&str, &str),
) -> Result<()> {
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .label_style(look.font(12))
        .axis_desc_style(look.font(14))
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .draw()
        .map_err(plot_err)
}

/// The legend of `entries` (name, colour) in a strip at the right of `area`, outside the data;
/// the rest of `area`, for the chart (all of it when there is no legend).
fn legend_strip<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, RGBColor)],
    look: &Look,
) -> Result<DrawingArea<DB, Shift>> {
    if entries.is_empty() {
        return Ok(area.clone());
    }
    let longest = entries.iter().map(|e| e.0.chars().count()).max().unwrap_or(0) as u32;
    let width = look.px(44 + 8 * longest);
    let (w, _) = area.dim_in_pixel();
    let (plot, side) = area.split_horizontally(w.saturating_sub(width));
    let at = |v: u32| look.px(v) as i32;
    for (k, (name, color)) in entries.iter().enumerate() {
        let y = at(50 + 20 * k as u32);
        side.draw(&PathElement::new(vec![(at(6), y), (at(28), y)], color.stroke_width(look.px(3))))
            .map_err(plot_err)?;
        side.draw(&Text::new(name.clone(), (at(34), y - at(7)), look.font(13))).map_err(plot_err)?;
    }
    Ok(plot)
}

/// The legend entries of `uavs`' lines (none beyond a dozen UAVs).
fn uav_entries(s: &Series, uavs: impl Iterator<Item = usize>) -> Vec<(String, RGBColor)> {
    if !s.legend() {
        return Vec::new();
    }
    uavs.map(|u| (format!("UAV{}", u + 1), PALETTE[u % PALETTE.len()])).collect()
}
const PALETTE: [RGBColor; 12] = [
    RGBColor(0, 0, 0),
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(174, 199, 232),
];

/// One of the six error axes: its state column, label, unit and scale to report units.
struct Axis {
    figure: &'static str,
    state: usize,
    error: usize,
    name: &'static str,
    unit: &'static str,
    degrees: bool,
}

const AXES: [Axis; 6] = [
    Axis { figure: "fig4_x", state: 0, error: 0, name: "x", unit: "m", degrees: false },
    Axis { figure: "fig5_y", state: 1, error: 1, name: "y", unit: "m", degrees: false },
    Axis { figure: "fig6_z", state: 2, error: 2, name: "z", unit: "m", degrees: false },
    Axis { figure: "fig7_alpha", state: 6, error: 3, name: "α (pitch)", unit: "deg", degrees: true },
    Axis { figure: "fig8_beta", state: 7, error: 4, name: "β (yaw)", unit: "deg", degrees: true },
    Axis { figure: "fig9_gamma", state: 8, error: 5, name: "γ (roll)", unit: "deg", degrees: true },
];

fn plot_err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("cannot draw figure: {e:?}")
}

/// Makes the embedded font the "sans-serif" of the PNG backend (once per process).
fn register_embedded_font() -> Result<()> {
    static FONT_OK: OnceLock<bool> = OnceLock::new();
    if *FONT_OK.get_or_init(|| register_font("sans-serif", FontStyle::Normal, FONT).is_ok()) {
        Ok(())
    } else {
        Err(anyhow!("the embedded font could not be loaded"))
    }
}

/// Per-UAV time series extracted from a trajectory.
struct Series {
    /// UAVs recorded (the first `n` of the scenario).
    n: usize,
    /// UAVs in the scenario.
    total: usize,
    /// Time span of the trajectory (s).
    t0: f64,
    t1: f64,
    /// Time step of the trajectory (s).
    dt: f64,
    /// `rows[uav]` = (t, state, error) at each step the UAV flew.
    rows: Vec<Vec<Sample>>,
}

/// One recorded step of one UAV: time, state and formation error.
type Sample = (f64, [f64; 9], [f64; 6]);

impl Series {
    fn new(traj: &Trajectory, total: usize) -> Self {
        let n = traj.rows.iter().map(|r| r.uav as usize + 1).max().unwrap_or(0).min(total);
        let mut rows = vec![Vec::new(); n];
        let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
        for r in &traj.rows {
            let u = r.uav as usize;
            if u < n {
                let mut s = [0.0; 9];
                s.copy_from_slice(r.state.as_slice());
                rows[u].push((r.t, s, r.error));
                t0 = t0.min(r.t);
                t1 = t1.max(r.t);
            }
        }
        if t0 > t1 {
            (t0, t1) = (0.0, 1.0);
        }
        let dt = rows.iter().find(|r| r.len() >= 2).map_or(1.0, |r| (r[1].0 - r[0].0).max(1e-9));
        Self { n, total, t0, t1, dt, rows }
    }

    fn value(sample: &Sample, axis: &Axis) -> f64 {
        to_report(sample.1[axis.state], axis)
    }

    fn error(sample: &Sample, axis: &Axis) -> f64 {
        to_report(sample.2[axis.error], axis)
    }

    /// "the 6 UAVs", or "the first 64 of 10000 UAVs" for a sampled swarm.
    fn which(&self) -> String {
        if self.n < self.total {
            format!("the first {} of {} UAVs", self.n, self.total)
        } else {
            format!("the {} UAVs", self.n)
        }
    }

    /// Legends are drawn for a dozen UAVs at most.
    fn legend(&self) -> bool {
        self.n <= PALETTE.len()
    }
}

fn to_report(v: f64, axis: &Axis) -> f64 {
    if axis.degrees {
        v.to_degrees()
    } else {
        v
    }
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-6);
    (lo - pad, hi + pad)
}

fn axis_figure<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    s: &Series,
    axis: &Axis,
    (allowable, nav): (f64, usize),
    look: &Look,
) -> Result<()> {
    root.fill(&WHITE).map_err(plot_err)?;
    let plot = legend_strip(root, &uav_entries(s, 0..s.n), look)?;
    let (top, bottom) = plot.split_vertically(plot.dim_in_pixel().1 / 2);
    let (t0, t1) = (s.t0, s.t1);
    // (a) values
    let (lo, hi) = range(s.rows.iter().flatten().map(|r| Series::value(r, axis)));
    let mut chart = ChartBuilder::on(&top)
        .caption(format!("(a) {} of {}", axis.name, s.which()), look.font(22))
        .margin(look.px(10))
        .margin_right(look.px(28))
        .x_label_area_size(look.px(40))
        .y_label_area_size(look.px(72))
        .build_cartesian_2d(t0..t1, lo..hi)
        .map_err(plot_err)?;
    mesh(&mut chart, look, ("t (s)", &format!("{} ({})", axis.name, axis.unit)))?;
    uav_lines(&mut chart, s, 0..s.n, |r| Series::value(r, axis), look.px(2))?;
    // (b) errors with the allowable band
    let followers: Vec<usize> = (0..s.n).filter(|&u| u != nav).collect();
    let (elo, ehi) = range(followers.iter().flat_map(|&u| s.rows[u].iter()).map(|r| Series::error(r, axis)));
    let bound = allowable * 1.15;
    let mut chart = ChartBuilder::on(&bottom)
        .caption(
            format!("(b) {} error relative to UAV{}, allowable ±{} (dashed)", axis.name, nav + 1, tick(&allowable)),
            look.font(22),
        )
        .margin(look.px(10))
        .margin_right(look.px(28))
        .x_label_area_size(look.px(40))
        .y_label_area_size(look.px(72))
        .build_cartesian_2d(t0..t1, elo.min(-bound)..ehi.max(bound))
        .map_err(plot_err)?;
    mesh(&mut chart, look, ("t (s)", &format!("error ({})", axis.unit)))?;
    for sign in [-1.0, 1.0] {
        chart
            .draw_series(DashedLineSeries::new(
                [(t0, sign * allowable), (t1, sign * allowable)],
                look.px(8),
                look.px(5),
                RED.stroke_width(look.px(2)),
            ))
            .map_err(plot_err)?;
    }
    uav_lines(&mut chart, s, followers.iter().copied(), |r| Series::error(r, axis), look.px(1))?;
    root.present().map_err(plot_err)
}

/// One line per UAV over the steps it flew.
fn uav_lines<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    s: &Series,
    uavs: impl Iterator<Item = usize>,
    value: impl Fn(&Sample) -> f64,
    width: u32,
) -> Result<()> {
    for u in uavs {
        let color = PALETTE[u % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(s.rows[u].iter().map(|r| (r.0, value(r))), color.stroke_width(width)))
            .map_err(plot_err)?;
    }
    Ok(())
}

/// Draws the legend of the labelled series at `position`.
fn legend_box<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<()> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(position)
        .draw()
        .map_err(plot_err)
}

fn tracks_figure<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, s: &Series, look: &Look) -> Result<()> {
    root.fill(&WHITE).map_err(plot_err)?;
    let plot = legend_strip(root, &uav_entries(s, 0..s.n), look)?;
    let coord = |i: usize| range(s.rows.iter().flatten().map(|r| r.1[i]));
    let (x, y, z) = (coord(0), coord(1), coord(2));
    let mut chart = ChartBuilder::on(&plot)
        .caption("Formation tracks (m)", look.font(24))
        .margin(look.px(20))
        .build_cartesian_3d(x.0..x.1, z.0..z.1, y.0..y.1)
        .map_err(plot_err)?;
    chart.with_projection(|mut p| {
        p.pitch = 0.35;
        p.yaw = 0.7;
        p.scale = 0.8;
        p.into_matrix()
    });
    chart
        .configure_axes()
        .label_style(look.font(12))
        .x_formatter(&tick)
        .y_formatter(&tick)
        .z_formatter(&tick)
        .draw()
        .map_err(plot_err)?;
    // The axes' titles at their far ends (the chart is x forward, z up, y across).
    let titles = [("y (m)", (x.1, z.0, y.0)), ("z (m)", (x.0, z.1, y.0)), ("x (m)", (x.0, z.0, y.1))];
    chart
        .draw_series(
            titles.iter().map(|(t, at)| Text::new(t.to_string(), *at, look.font(15).into_font().color(&BLACK))),
        )
        .map_err(plot_err)?;
    for u in 0..s.n {
        let color = PALETTE[u % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(
                s.rows[u].iter().map(|r| (r.1[0], r.1[2], r.1[1])),
                color.stroke_width(look.px(2)),
            ))
            .map_err(plot_err)?;
    }
    root.present().map_err(plot_err)
}

/// The attitude of the formation: for each angle, the navigator's (black, left axis) and each
/// follower's difference from it, its formation error (thin, right axis): the followers' own
/// curves would lie on the navigator's.
fn attitude_figure<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    s: &Series,
    nav: usize,
    look: &Look,
) -> Result<()> {
    root.fill(&WHITE).map_err(plot_err)?;
    let mut entries = uav_entries(s, (0..s.n).filter(|&u| u != nav));
    if nav < s.n {
        entries.insert(0, (format!("UAV{} (navigator)", nav + 1), BLACK));
    }
    let plot = legend_strip(root, &entries, look)?;
    let panels = plot.split_evenly((3, 1));
    let followers: Vec<usize> = (0..s.n).filter(|&u| u != nav).collect();
    for (panel, axis) in panels.iter().zip(&AXES[3..]) {
        let own = if nav < s.n { nav } else { 0 };
        let (lo, hi) = range(s.rows.get(own).into_iter().flatten().map(|r| Series::value(r, axis)));
        let m = followers
            .iter()
            .flat_map(|&u| s.rows[u].iter())
            .map(|r| Series::error(r, axis).abs())
            .fold(0.0, f64::max)
            .max(1e-6)
            * 1.1;
        let mut chart = ChartBuilder::on(panel)
            .caption(
                format!("{}: UAV{} (left) and each follower's error from it (right)", axis.name, own + 1),
                look.font(17),
            )
            .margin(look.px(8))
            .x_label_area_size(look.px(34))
            .y_label_area_size(look.px(64))
            .right_y_label_area_size(look.px(64))
            .build_cartesian_2d(s.t0..s.t1, lo..hi)
            .map_err(plot_err)?
            .set_secondary_coord(s.t0..s.t1, -m..m);
        chart
            .configure_mesh()
            .x_desc("t (s)")
            .y_desc(format!("UAV{} (°)", own + 1))
            .label_style(look.font(12))
            .axis_desc_style(look.font(13))
            .x_label_formatter(&tick)
            .y_label_formatter(&tick)
            .draw()
            .map_err(plot_err)?;
        chart
            .configure_secondary_axes()
            .y_desc("error (°)")
            .label_style(look.font(12))
            .axis_desc_style(look.font(13))
            .y_label_formatter(&tick)
            .draw()
            .map_err(plot_err)?;
        for &u in &followers {
            let color = PALETTE[u % PALETTE.len()];
            chart
                .draw_secondary_series(LineSeries::new(
                    s.rows[u].iter().map(|r| (r.0, Series::error(r, axis))),
                    color.stroke_width(look.px(1)),
                ))
                .map_err(plot_err)?;
        }
        chart
            .draw_series(LineSeries::new(
                s.rows.get(own).into_iter().flatten().map(|r| (r.0, Series::value(r, axis))),
                BLACK.stroke_width(look.px(2)),
            ))
            .map_err(plot_err)?;
    }
    root.present().map_err(plot_err)
}

/// Draws `$figure(area, args.., look)` as `$dir/$name.png` (at the look's scale) and `.svg`,
/// and adds both to `$written`.
macro_rules! png_and_svg {
    ($written:expr, $dir:expr, $name:expr, $look:expr, $figure:ident($($arg:expr),*)) => {{
        let png = $dir.join(format!("{}.png", $name));
        let svg = $dir.join(format!("{}.svg", $name));
        let look: &Look = $look;
        $figure(&BitMapBackend::new(crate::files::fresh(&png)?, look.pixels()).into_drawing_area(), $($arg,)* look)?;
        let flat = look.for_svg();
        $figure(&SVGBackend::new(crate::files::fresh(&svg)?, flat.size).into_drawing_area(), $($arg,)* &flat)?;
        $written.extend([png, svg]);
    }};
}

/// Draws every figure of a run into `dir` as `look` says and returns the files written.
pub fn write_all(dir: &Path, scenario: &Scenario, traj: &Trajectory, look: &Look) -> Result<Vec<PathBuf>> {
    register_embedded_font()?;
    let s = Series::new(traj, scenario.len());
    let nav = scenario.navigator().index();
    let allow = scenario.allowable().as_array();
    let mut written = Vec::new();
    for axis in &AXES {
        let a = if axis.degrees { allow[axis.error].to_degrees() } else { allow[axis.error] };
        let a = (a * 1e6).round() / 1e6;
        png_and_svg!(written, dir, axis.figure, look, axis_figure(&s, axis, (a, nav)));
    }
    png_and_svg!(written, dir, "fig10a_tracks", look, tracks_figure(&s));
    png_and_svg!(written, dir, "fig10b_attitude", look, attitude_figure(&s, nav));
    png_and_svg!(written, dir, "fig10c_plan", look, plan_figure(&s));
    let moves = !scenario.placement().in_slots()
        || !scenario.schedule().is_empty()
        || scenario.reassign_on_loss().is_some()
        || scenario.faults().iter().any(|f| matches!(f, proxform_scenario::faults::Fault::Join { .. }));
    if moves && nav < s.n {
        png_and_svg!(written, dir, "approach_plan", look, approach_figure(&s, nav));
    }
    Ok(written)
}

/// A chart seen from above on `root`, captioned, over the ranges of x and y with equal scales
/// (the narrower range widened around its centre), its axes described.
fn plan_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    (caption, font): (&str, u32),
    (x, y): ((f64, f64), (f64, f64)),
    (x_desc, y_desc): (&str, &str),
    look: &Look,
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>> {
    let (w, h) = root.dim_in_pixel();
    let aspect = f64::from(w.saturating_sub(look.px(120)).max(1)) / f64::from(h.saturating_sub(look.px(100)).max(1));
    let (wx, wy) = ((x.1 - x.0).max(1e-9), (y.1 - y.0).max(1e-9));
    let (x, y) = if wx / wy > aspect {
        let c = 0.5 * (y.0 + y.1);
        (x, (c - 0.5 * wx / aspect, c + 0.5 * wx / aspect))
    } else {
        let c = 0.5 * (x.0 + x.1);
        ((c - 0.5 * wy * aspect, c + 0.5 * wy * aspect), y)
    };
    let mut chart = ChartBuilder::on(root)
        .caption(caption, look.font(font))
        .margin(look.px(15))
        .margin_right(look.px(28))
        .x_label_area_size(look.px(44))
        .y_label_area_size(look.px(72))
        .build_cartesian_2d(x.0..x.1, y.0..y.1)
        .map_err(plot_err)?;
    mesh(&mut chart, look, (x_desc, y_desc))?;
    Ok(chart)
}

/// The followers' tracks relative to the navigator, seen from above (x forward, y left of
/// the world axes; equal scales): how the formation came together or changed. A hollow
/// circle marks each follower's start, a filled square its end, dots every 10 s.
fn approach_figure<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    s: &Series,
    nav: usize,
    look: &Look,
) -> Result<()> {
    root.fill(&WHITE).map_err(plot_err)?;
    let plot = legend_strip(root, &uav_entries(s, (0..s.n).filter(|&u| u != nav)), look)?;
    // The navigator's position at each recorded step, by step index from the start.
    let step = |t: f64| ((t - s.t0) / s.dt).round() as usize;
    let mut nav_at = vec![None; s.rows[nav].last().map_or(0, |r| step(r.0) + 1)];
    for r in &s.rows[nav] {
        nav_at[step(r.0)] = Some((r.1[0], r.1[1]));
    }
    let relative: Vec<Vec<(f64, f64, f64)>> = (0..s.n)
        .map(|u| {
            if u == nav {
                return Vec::new();
            }
            s.rows[u]
                .iter()
                .filter_map(|r| {
                    let (nx, ny) = nav_at.get(step(r.0)).copied().flatten()?;
                    Some((r.0, r.1[0] - nx, r.1[1] - ny))
                })
                .collect()
        })
        .collect();
    let all = || relative.iter().flatten().chain(std::iter::once(&(0.0, 0.0, 0.0)));
    let mut chart = plan_chart(
        &plot,
        ("Approach relative to the navigator (m): ○ start, ■ end, dots every 10 s", 22),
        (range(all().map(|p| p.1)), range(all().map(|p| p.2))),
        ("x − x_navigator (m)", "y − y_navigator (m)"),
        look,
    )?;
    let every = ((10.0 / s.dt).round() as usize).max(1);
    chart
        .draw_series(std::iter::once(TriangleMarker::new((0.0, 0.0), look.px(7), BLACK.filled())))
        .map_err(plot_err)?;
    for (u, pts) in relative.iter().enumerate() {
        let (Some(first), Some(last)) = (pts.first(), pts.last()) else { continue };
        let color = PALETTE[u % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(pts.iter().map(|p| (p.1, p.2)), color.stroke_width(look.px(1))))
            .map_err(plot_err)?;
        let dots = pts.iter().filter(|p| step(p.0) % every == 0);
        chart.draw_series(dots.map(|p| Circle::new((p.1, p.2), look.px(2), color.filled()))).map_err(plot_err)?;
        chart
            .draw_series(std::iter::once(Circle::new((first.1, first.2), look.px(6), color.stroke_width(look.px(2)))))
            .map_err(plot_err)?;
        let h = look.px(5) as i32;
        let square = EmptyElement::at((last.1, last.2)) + Rectangle::new([(-h, -h), (h, h)], color.filled());
        chart.draw_series(std::iter::once(square)).map_err(plot_err)?;
    }
    root.present().map_err(plot_err)
}

/// The tracks seen from above (x right, y up, equal scales), with each UAV's position marked
/// every 10 s so the formation's shape can be read along the way.
fn plan_figure<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, s: &Series, look: &Look) -> Result<()> {
    root.fill(&WHITE).map_err(plot_err)?;
    let plot = legend_strip(root, &uav_entries(s, 0..s.n), look)?;
    let coord = |i: usize| range(s.rows.iter().flatten().map(|r| r.1[i]));
    let mut chart = plan_chart(
        &plot,
        ("Tracks seen from above (m); dots every 10 s", 24),
        (coord(0), coord(1)),
        ("x (m)", "y (m)"),
        look,
    )?;
    let every = ((10.0 / s.dt).round() as usize).max(1);
    for u in 0..s.n {
        let color = PALETTE[u % PALETTE.len()];
        let pts: Vec<(f64, f64)> = s.rows[u].iter().map(|r| (r.1[0], r.1[1])).collect();
        chart.draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(look.px(1)))).map_err(plot_err)?;
        // Dots at the same instants for every UAV (multiples of 10 s from the start).
        let dots = s.rows[u].iter().filter(|r| (((r.0 - s.t0) / s.dt).round() as usize).is_multiple_of(every));
        chart.draw_series(dots.map(|r| Circle::new((r.1[0], r.1[1]), look.px(3), color.filled()))).map_err(plot_err)?;
    }
    root.present().map_err(plot_err)
}

/// Cost per agent-update against swarm size, one curve per (search, threads) configuration.
pub fn bench_plot(dir: &Path, rows: &[(u64, String, usize, f64)]) -> Result<Vec<PathBuf>> {
    register_embedded_font()?;
    let png = dir.join("cost_per_update.png");
    let svg = dir.join("cost_per_update.svg");
    bench_chart(&BitMapBackend::new(crate::files::fresh(&png)?, (900, 600)).into_drawing_area(), rows)?;
    bench_chart(&SVGBackend::new(crate::files::fresh(&svg)?, (900, 600)).into_drawing_area(), rows)?;
    Ok(vec![png, svg])
}

fn bench_chart<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, rows: &[(u64, String, usize, f64)]) -> Result<()> {
    root.fill(&WHITE).map_err(plot_err)?;
    let nmax = rows.iter().map(|r| r.0).max().unwrap_or(100) as f64;
    let ymax = rows.iter().map(|r| r.3).fold(1.0, f64::max);
    let ymin = rows.iter().map(|r| r.3).fold(f64::INFINITY, f64::min).min(ymax);
    let mut chart = ChartBuilder::on(root)
        .caption("Cost per agent-update (swarm scenario)", ("sans-serif", 24))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d((50.0..nmax * 2.0).log_scale(), (ymin * 0.5..ymax * 2.0).log_scale())
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .x_desc("UAVs")
        .y_desc("ns per agent-update")
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_label_formatter(&|v| format!("{v:.0}"))
        .draw()
        .map_err(plot_err)?;
    let mut configs: Vec<(String, usize)> = rows.iter().map(|r| (r.1.clone(), r.2)).collect();
    configs.sort();
    configs.dedup();
    for (k, (search, threads)) in configs.iter().enumerate() {
        let color = PALETTE[(k + 1) % PALETTE.len()];
        let pts: Vec<(f64, f64)> =
            rows.iter().filter(|r| &r.1 == search && r.2 == *threads).map(|r| (r.0 as f64, r.3)).collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(plot_err)?
            .label(format!("{search}, {threads} thread(s)"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled()))).map_err(plot_err)?;
    }
    legend_box(&mut chart, SeriesLabelPosition::UpperLeft)?;
    root.present().map_err(plot_err)
}

/// The comparison's curves: median (solid) and 95th percentile (dashed) of the largest error
/// over its allowable error (any axis; ≤ 1 passes) against radio loss and against radio delay,
/// one colour per method.
pub fn compare_plots(
    dir: &Path,
    cmp: &proxform_scenario::comparison::Comparison,
    cells: &[proxform_sim::compare::CellSummary],
) -> Result<Vec<PathBuf>> {
    register_embedded_font()?;
    let mut written = Vec::new();
    type Pick = fn(&proxform_scenario::comparison::Condition) -> Option<f64>;
    let sweeps: [(&str, &str, Pick); 3] = [
        ("error_vs_loss", "radio loss (%)", |c| c.is_loss_only().then_some(100.0 * c.radio_loss)),
        ("error_vs_delay", "radio delay (s)", |c| c.is_delay_only().then_some(c.radio_delay_s)),
        ("error_vs_channel_loss", "loss on every channel: onboard detections and radio (%)", |c| {
            c.channel_loss().map(|p| 100.0 * p)
        }),
    ];
    for (file, x_desc, pick) in sweeps {
        // (method, [(x, median, p95)])
        let mut curves: Vec<Curve> = Vec::new();
        for m in &cmp.methods {
            let mut pts: Vec<(f64, f64, f64)> = cmp
                .conditions
                .iter()
                .filter_map(|c| {
                    let x = pick(c)?;
                    let cell = cells.iter().find(|s| s.method == m.name && s.condition == c.name)?;
                    Some((x, cell.error_ratio_median, cell.error_ratio_p95))
                })
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            if pts.len() >= 2 {
                curves.push((m.name.clone(), pts));
            }
        }
        if curves.is_empty() {
            continue;
        }
        let title = format!("{}: largest formation error over the allowable error", cmp.base.name());
        let png = dir.join(format!("{file}.png"));
        let svg = dir.join(format!("{file}.svg"));
        sweep_chart(
            &BitMapBackend::new(crate::files::fresh(&png)?, (900, 600)).into_drawing_area(),
            &title,
            x_desc,
            &curves,
        )?;
        sweep_chart(
            &SVGBackend::new(crate::files::fresh(&svg)?, (900, 600)).into_drawing_area(),
            &title,
            x_desc,
            &curves,
        )?;
        written.extend([png, svg]);
    }
    // The pass fraction under each condition, with its 95 % Wilson interval, per method.
    let names: Vec<String> = cmp.conditions.iter().map(|c| c.name.clone()).collect();
    let by_condition: Vec<PassLine> = cmp
        .methods
        .iter()
        .map(|m| {
            let pts = cmp
                .conditions
                .iter()
                .enumerate()
                .filter_map(|(k, c)| {
                    let cell = cells.iter().find(|s| s.method == m.name && s.condition == c.name)?;
                    Some((k as f64, cell.pass_fraction, cell.pass_fraction_lo, cell.pass_fraction_hi))
                })
                .collect();
            (m.name.clone(), pts)
        })
        .collect();
    if !names.is_empty() {
        let title = format!("{}: runs within the allowable errors (95 % Wilson intervals)", cmp.base.name());
        let png = dir.join("pass_by_condition.png");
        let svg = dir.join("pass_by_condition.svg");
        let size = (170 * names.len().min(100) as u32 + 300).clamp(900, 6000);
        condition_chart(
            &BitMapBackend::new(crate::files::fresh(&png)?, (size, 600)).into_drawing_area(),
            &title,
            &names,
            &by_condition,
        )?;
        condition_chart(
            &SVGBackend::new(crate::files::fresh(&svg)?, (size, 600)).into_drawing_area(),
            &title,
            &names,
            &by_condition,
        )?;
        written.extend([png, svg]);
    }
    // The pass fraction against loss on every channel, one line per method.
    let mut lines: Vec<PassLine> = Vec::new();
    for m in &cmp.methods {
        let mut pts: Vec<(f64, f64, f64, f64)> = cmp
            .conditions
            .iter()
            .filter_map(|c| {
                let x = 100.0 * c.channel_loss()?;
                let cell = cells.iter().find(|s| s.method == m.name && s.condition == c.name)?;
                Some((x, cell.pass_fraction, cell.pass_fraction_lo, cell.pass_fraction_hi))
            })
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        if pts.len() >= 2 {
            lines.push((m.name.clone(), pts));
        }
    }
    if !lines.is_empty() {
        let title = format!("{}: runs within the allowable errors", cmp.base.name());
        let x_desc = "loss on every channel: onboard detections and radio (%)";
        let png = dir.join("pass_vs_channel_loss.png");
        let svg = dir.join("pass_vs_channel_loss.svg");
        pass_chart(
            &BitMapBackend::new(crate::files::fresh(&png)?, (900, 600)).into_drawing_area(),
            &title,
            x_desc,
            &lines,
        )?;
        pass_chart(
            &SVGBackend::new(crate::files::fresh(&svg)?, (900, 600)).into_drawing_area(),
            &title,
            x_desc,
            &lines,
        )?;
        written.extend([png, svg]);
    }
    Ok(written)
}

/// Pass fraction (0 to 1) under each named condition, with its interval, one colour per
/// method (side by side at each condition); the legend outside.
fn condition_chart<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    names: &[String],
    methods: &[PassLine],
) -> Result<()> {
    root.fill(&WHITE).map_err(plot_err)?;
    let look = Look::default();
    let entries: Vec<(String, RGBColor)> =
        methods.iter().enumerate().map(|(k, m)| (m.0.clone(), PALETTE[(k + 1) % PALETTE.len()])).collect();
    let plot = legend_strip(root, &entries, &look)?;
    let n = names.len() as f64;
    let mut chart = ChartBuilder::on(&plot)
        .caption(title, ("sans-serif", 20))
        .margin(15)
        .margin_right(25)
        .x_label_area_size(60)
        .y_label_area_size(70)
        .build_cartesian_2d(-0.6..n - 0.4, 0.0..1.02)
        .map_err(plot_err)?;
    let label = |v: &f64| {
        let k = v.round();
        match (v - k).abs() < 1e-6 && k >= 0.0 {
            true => names.get(k as usize).cloned().unwrap_or_default(),
            false => String::new(),
        }
    };
    chart
        .configure_mesh()
        .x_desc("condition")
        .y_desc("pass fraction")
        .x_labels(names.len().max(2))
        .x_label_formatter(&label)
        .y_label_formatter(&tick)
        .label_style(("sans-serif", 12))
        .disable_x_mesh()
        .draw()
        .map_err(plot_err)?;
    let width = 0.6 / methods.len().max(1) as f64;
    for (k, (_, pts)) in methods.iter().enumerate() {
        let color = PALETTE[(k + 1) % PALETTE.len()];
        let dx = (k as f64 - 0.5 * (methods.len() as f64 - 1.0)) * width;
        chart
            .draw_series(pts.iter().map(|p| ErrorBar::new_vertical(p.0 + dx, p.2, p.1, p.3, color.stroke_width(2), 8)))
            .map_err(plot_err)?;
        chart.draw_series(pts.iter().map(|p| Circle::new((p.0 + dx, p.1), 4, color.filled()))).map_err(plot_err)?;
    }
    root.present().map_err(plot_err)
}

/// Pass fraction (0 to 1) against a sweep, one line per method, with each point's interval.
fn pass_chart<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    x_desc: &str,
    lines: &[PassLine],
) -> Result<()> {
    root.fill(&WHITE).map_err(plot_err)?;
    let xs = || lines.iter().flat_map(|l| l.1.iter().map(|p| p.0));
    let (x0, x1) = xs().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 24))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1.max(x0 + 1e-9), 0.0..1.02)
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc("pass fraction (95 % Wilson intervals)")
        .y_label_formatter(&tick)
        .draw()
        .map_err(plot_err)?;
    for (k, (name, pts)) in lines.iter().enumerate() {
        let color = PALETTE[(k + 1) % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(pts.iter().map(|p| (p.0, p.1)), color.stroke_width(2)))
            .map_err(plot_err)?
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
        chart.draw_series(pts.iter().map(|p| Circle::new((p.0, p.1), 4, color.filled()))).map_err(plot_err)?;
        chart
            .draw_series(pts.iter().map(|p| ErrorBar::new_vertical(p.0, p.2, p.1, p.3, color.stroke_width(1), 6)))
            .map_err(plot_err)?;
    }
    legend_box(&mut chart, SeriesLabelPosition::LowerLeft)?;
    root.present().map_err(plot_err)
}

fn sweep_chart<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    x_desc: &str,
    curves: &[Curve],
) -> Result<()> {
    let allowable = 1.0;
    root.fill(&WHITE).map_err(plot_err)?;
    let all = || curves.iter().flat_map(|c| c.1.iter());
    let (x0, x1) = all().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let ymax = all().map(|p| p.2).filter(|v| v.is_finite()).fold(allowable, f64::max) * 2.0;
    let ymin = all().map(|p| p.1).filter(|v| v.is_finite() && *v > 0.0).fold(allowable, f64::min) * 0.5;
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 24))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1.max(x0 + 1e-9), (ymin..ymax).log_scale())
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc("largest error / allowable: median —, p95 - -")
        .y_label_formatter(&|v| format!("{v:.3}"))
        .draw()
        .map_err(plot_err)?;
    chart
        .draw_series(DashedLineSeries::new([(x0, allowable), (x1, allowable)], 4, 4, BLACK.stroke_width(1)))
        .map_err(plot_err)?
        .label("allowable error (pass below)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK));
    for (k, (name, pts)) in curves.iter().enumerate() {
        let color = PALETTE[(k + 1) % PALETTE.len()];
        let median: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.1.max(ymin))).collect();
        let p95: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.2.max(ymin))).collect();
        chart
            .draw_series(LineSeries::new(median.clone(), color.stroke_width(2)))
            .map_err(plot_err)?
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
        chart.draw_series(median.iter().map(|&p| Circle::new(p, 4, color.filled()))).map_err(plot_err)?;
        chart.draw_series(DashedLineSeries::new(p95, 6, 4, color.stroke_width(1))).map_err(plot_err)?;
    }
    legend_box(&mut chart, SeriesLabelPosition::UpperLeft)?;
    root.present().map_err(plot_err)
}
