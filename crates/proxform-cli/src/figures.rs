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
use plotters::chart::SeriesAnno;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::{CoordTranslate, Shift};
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use proxform_scenario::Scenario;
use proxform_sim::Trajectory;

/// One method's curve: its name and (x, median, p95) points.
type Curve = (String, Vec<(f64, f64, f64)>);

const FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
const SIZE: (u32, u32) = (1000, 760);
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
    allowable: f64,
    nav: usize,
) -> Result<()> {
    root.fill(&WHITE).map_err(plot_err)?;
    let (top, bottom) = root.split_vertically(SIZE.1 / 2);
    let (t0, t1) = (s.t0, s.t1);
    // (a) values
    let (lo, hi) = range(s.rows.iter().flatten().map(|r| Series::value(r, axis)));
    let mut chart = ChartBuilder::on(&top)
        .caption(format!("(a) {} of {}", axis.name, s.which()), ("sans-serif", 22))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(70)
        .build_cartesian_2d(t0..t1, lo..hi)
        .map_err(plot_err)?;
    chart.configure_mesh().x_desc("t (s)").y_desc(format!("{} ({})", axis.name, axis.unit)).draw().map_err(plot_err)?;
    uav_lines(&mut chart, s, 0..s.n, |r| Series::value(r, axis), 2, SeriesLabelPosition::UpperLeft)?;
    // (b) errors with the allowable band
    let followers: Vec<usize> = (0..s.n).filter(|&u| u != nav).collect();
    let (elo, ehi) = range(followers.iter().flat_map(|&u| s.rows[u].iter()).map(|r| Series::error(r, axis)));
    let bound = allowable * 1.15;
    let mut chart = ChartBuilder::on(&bottom)
        .caption(
            format!("(b) {} error relative to UAV{}, allowable ±{allowable}", axis.name, nav + 1),
            ("sans-serif", 22),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(70)
        .build_cartesian_2d(t0..t1, elo.min(-bound)..ehi.max(bound))
        .map_err(plot_err)?;
    chart.configure_mesh().x_desc("t (s)").y_desc(format!("error ({})", axis.unit)).draw().map_err(plot_err)?;
    for sign in [-1.0, 1.0] {
        chart
            .draw_series(DashedLineSeries::new(
                [(t0, sign * allowable), (t1, sign * allowable)],
                8,
                5,
                RED.stroke_width(2),
            ))
            .map_err(plot_err)?;
    }
    uav_lines(&mut chart, s, followers.iter().copied(), |r| Series::error(r, axis), 1, SeriesLabelPosition::LowerLeft)?;
    root.present().map_err(plot_err)
}

/// One line per UAV over the steps it flew, and the legend (for a dozen UAVs at most).
fn uav_lines<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    s: &Series,
    uavs: impl Iterator<Item = usize>,
    value: impl Fn(&Sample) -> f64,
    width: u32,
    legend: SeriesLabelPosition,
) -> Result<()> {
    for u in uavs {
        let color = PALETTE[u % PALETTE.len()];
        let drawn = chart
            .draw_series(LineSeries::new(s.rows[u].iter().map(|r| (r.0, value(r))), color.stroke_width(width)))
            .map_err(plot_err)?;
        if s.legend() {
            label_uav(drawn, u, color);
        }
    }
    if !s.legend() {
        return Ok(());
    }
    legend_box(chart, legend)
}

/// Names UAV `u`'s line in the legend.
fn label_uav<DB: DrawingBackend>(line: &mut SeriesAnno<'_, DB>, u: usize, color: RGBColor) {
    line.label(format!("UAV{}", u + 1))
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
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

fn tracks_figure<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, s: &Series) -> Result<()> {
    root.fill(&WHITE).map_err(plot_err)?;
    let coord = |i: usize| range(s.rows.iter().flatten().map(|r| r.1[i]));
    let (x, y, z) = (coord(0), coord(1), coord(2));
    let mut chart = ChartBuilder::on(root)
        .caption("Formation tracks (x, y, z in m)", ("sans-serif", 24))
        .margin(20)
        .build_cartesian_3d(x.0..x.1, z.0..z.1, y.0..y.1)
        .map_err(plot_err)?;
    chart.with_projection(|mut p| {
        p.pitch = 0.35;
        p.yaw = 0.7;
        p.scale = 0.85;
        p.into_matrix()
    });
    chart.configure_axes().draw().map_err(plot_err)?;
    for u in 0..s.n {
        let color = PALETTE[u % PALETTE.len()];
        let drawn = chart
            .draw_series(LineSeries::new(s.rows[u].iter().map(|r| (r.1[0], r.1[2], r.1[1])), color.stroke_width(2)))
            .map_err(plot_err)?;
        if s.legend() {
            label_uav(drawn, u, color);
        }
    }
    if s.legend() {
        legend_box(&mut chart, SeriesLabelPosition::MiddleRight)?;
    }
    root.present().map_err(plot_err)
}

fn attitude_figure<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, s: &Series) -> Result<()> {
    root.fill(&WHITE).map_err(plot_err)?;
    let panels = root.split_evenly((3, 1));
    for (panel, axis) in panels.iter().zip(&AXES[3..]) {
        let (lo, hi) = range(s.rows.iter().flatten().map(|r| Series::value(r, axis)));
        let mut chart = ChartBuilder::on(panel)
            .caption(format!("{} of {}", axis.name, s.which()), ("sans-serif", 18))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(60)
            .build_cartesian_2d(s.t0..s.t1, lo..hi)
            .map_err(plot_err)?;
        chart.configure_mesh().x_desc("t (s)").y_desc("deg").draw().map_err(plot_err)?;
        for u in 0..s.n {
            let color = PALETTE[u % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(
                    s.rows[u].iter().map(|r| (r.0, Series::value(r, axis))),
                    color.stroke_width(1),
                ))
                .map_err(plot_err)?;
        }
    }
    root.present().map_err(plot_err)
}

/// Draws every figure of a run into `dir` and returns the files written.
pub fn write_all(dir: &Path, scenario: &Scenario, traj: &Trajectory) -> Result<Vec<PathBuf>> {
    register_embedded_font()?;
    let s = Series::new(traj, scenario.len());
    let nav = scenario.navigator().index();
    let allow = scenario.allowable().as_array();
    let mut written = Vec::new();
    for axis in &AXES {
        let a = if axis.degrees { allow[axis.error].to_degrees() } else { allow[axis.error] };
        let a = (a * 1e6).round() / 1e6;
        let png = dir.join(format!("{}.png", axis.figure));
        let svg = dir.join(format!("{}.svg", axis.figure));
        axis_figure(&BitMapBackend::new(crate::files::fresh(&png)?, SIZE).into_drawing_area(), &s, axis, a, nav)?;
        axis_figure(&SVGBackend::new(crate::files::fresh(&svg)?, SIZE).into_drawing_area(), &s, axis, a, nav)?;
        written.extend([png, svg]);
    }
    let png = dir.join("fig10a_tracks.png");
    let svg = dir.join("fig10a_tracks.svg");
    tracks_figure(&BitMapBackend::new(crate::files::fresh(&png)?, SIZE).into_drawing_area(), &s)?;
    tracks_figure(&SVGBackend::new(crate::files::fresh(&svg)?, SIZE).into_drawing_area(), &s)?;
    written.extend([png, svg]);
    let png = dir.join("fig10b_attitude.png");
    let svg = dir.join("fig10b_attitude.svg");
    attitude_figure(&BitMapBackend::new(crate::files::fresh(&png)?, SIZE).into_drawing_area(), &s)?;
    attitude_figure(&SVGBackend::new(crate::files::fresh(&svg)?, SIZE).into_drawing_area(), &s)?;
    written.extend([png, svg]);
    let png = dir.join("fig10c_plan.png");
    let svg = dir.join("fig10c_plan.svg");
    plan_figure(&BitMapBackend::new(crate::files::fresh(&png)?, SIZE).into_drawing_area(), &s)?;
    plan_figure(&SVGBackend::new(crate::files::fresh(&svg)?, SIZE).into_drawing_area(), &s)?;
    written.extend([png, svg]);
    let moves = !scenario.placement().in_slots()
        || !scenario.schedule().is_empty()
        || scenario.reassign_on_loss().is_some()
        || scenario.faults().iter().any(|f| matches!(f, proxform_scenario::faults::Fault::Join { .. }));
    if moves && nav < s.n {
        let png = dir.join("approach_plan.png");
        let svg = dir.join("approach_plan.svg");
        approach_figure(&BitMapBackend::new(crate::files::fresh(&png)?, SIZE).into_drawing_area(), &s, nav)?;
        approach_figure(&SVGBackend::new(crate::files::fresh(&svg)?, SIZE).into_drawing_area(), &s, nav)?;
        written.extend([png, svg]);
    }
    Ok(written)
}

/// A chart seen from above on `root` of `SIZE`, captioned (text, font size), over the ranges
/// of x and y with equal scales (the narrower range widened around its centre), its axes
/// described.
fn plan_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    (caption, font): (&str, u32),
    (x, y): ((f64, f64), (f64, f64)),
    (x_desc, y_desc): (&str, &str),
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>> {
    let aspect = f64::from(SIZE.0 - 120) / f64::from(SIZE.1 - 100);
    let (wx, wy) = (x.1 - x.0, y.1 - y.0);
    let (x, y) = if wx / wy > aspect {
        let c = 0.5 * (y.0 + y.1);
        (x, (c - 0.5 * wx / aspect, c + 0.5 * wx / aspect))
    } else {
        let c = 0.5 * (x.0 + x.1);
        ((c - 0.5 * wy * aspect, c + 0.5 * wy * aspect), y)
    };
    let mut chart = ChartBuilder::on(root)
        .caption(caption, ("sans-serif", font))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)
        .map_err(plot_err)?;
    chart.configure_mesh().x_desc(x_desc).y_desc(y_desc).draw().map_err(plot_err)?;
    Ok(chart)
}

/// The followers' tracks relative to the navigator, seen from above (x forward, y left of
/// the world axes; equal scales): how the formation came together or changed. A hollow
/// circle marks each follower's start, a filled square its end, dots every 10 s.
fn approach_figure<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, s: &Series, nav: usize) -> Result<()> {
    root.fill(&WHITE).map_err(plot_err)?;
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
        root,
        ("Approach relative to the navigator (m): ○ start, ■ end, dots every 10 s", 22),
        (range(all().map(|p| p.1)), range(all().map(|p| p.2))),
        ("x − x_navigator (m)", "y − y_navigator (m)"),
    )?;
    let every = ((10.0 / s.dt).round() as usize).max(1);
    chart.draw_series(std::iter::once(TriangleMarker::new((0.0, 0.0), 7, BLACK.filled()))).map_err(plot_err)?;
    for (u, pts) in relative.iter().enumerate() {
        let (Some(first), Some(last)) = (pts.first(), pts.last()) else { continue };
        let color = PALETTE[u % PALETTE.len()];
        let drawn = chart
            .draw_series(LineSeries::new(pts.iter().map(|p| (p.1, p.2)), color.stroke_width(1)))
            .map_err(plot_err)?;
        if s.legend() {
            label_uav(drawn, u, color);
        }
        let dots = pts.iter().filter(|p| step(p.0) % every == 0);
        chart.draw_series(dots.map(|p| Circle::new((p.1, p.2), 2, color.filled()))).map_err(plot_err)?;
        chart
            .draw_series(std::iter::once(Circle::new((first.1, first.2), 6, color.stroke_width(2))))
            .map_err(plot_err)?;
        let square = EmptyElement::at((last.1, last.2)) + Rectangle::new([(-5, -5), (5, 5)], color.filled());
        chart.draw_series(std::iter::once(square)).map_err(plot_err)?;
    }
    if s.legend() {
        legend_box(&mut chart, SeriesLabelPosition::UpperRight)?;
    }
    root.present().map_err(plot_err)
}

/// The tracks seen from above (x right, y up, equal scales), with each UAV's position marked
/// every 10 s so the formation's shape can be read along the way.
fn plan_figure<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, s: &Series) -> Result<()> {
    root.fill(&WHITE).map_err(plot_err)?;
    let coord = |i: usize| range(s.rows.iter().flatten().map(|r| r.1[i]));
    let mut chart = plan_chart(
        root,
        ("Tracks seen from above (m); dots every 10 s", 24),
        (coord(0), coord(1)),
        ("x (m)", "y (m)"),
    )?;
    let every = ((10.0 / s.dt).round() as usize).max(1);
    for u in 0..s.n {
        let color = PALETTE[u % PALETTE.len()];
        let pts: Vec<(f64, f64)> = s.rows[u].iter().map(|r| (r.1[0], r.1[1])).collect();
        let drawn = chart.draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(1))).map_err(plot_err)?;
        if s.legend() {
            label_uav(drawn, u, color);
        }
        // Dots at the same instants for every UAV (multiples of 10 s from the start).
        let dots = s.rows[u].iter().filter(|r| (((r.0 - s.t0) / s.dt).round() as usize).is_multiple_of(every));
        chart.draw_series(dots.map(|r| Circle::new((r.1[0], r.1[1]), 3, color.filled()))).map_err(plot_err)?;
    }
    if s.legend() {
        legend_box(&mut chart, SeriesLabelPosition::UpperRight)?;
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
    // The pass fraction against loss on every channel, one line per method.
    let mut lines: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for m in &cmp.methods {
        let mut pts: Vec<(f64, f64)> = cmp
            .conditions
            .iter()
            .filter_map(|c| {
                let x = 100.0 * c.channel_loss()?;
                let cell = cells.iter().find(|s| s.method == m.name && s.condition == c.name)?;
                Some((x, cell.pass_fraction))
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

/// Pass fraction (0 to 1) against a sweep, one line per method.
fn pass_chart<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    x_desc: &str,
    lines: &[(String, Vec<(f64, f64)>)],
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
        .y_desc("pass fraction")
        .y_label_formatter(&|v| format!("{v:.1}"))
        .draw()
        .map_err(plot_err)?;
    for (k, (name, pts)) in lines.iter().enumerate() {
        let color = PALETTE[(k + 1) % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(plot_err)?
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled()))).map_err(plot_err)?;
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
