//! The atlas figures: the RMS_δ colour map with class markers (paper Figs. 7b, 8), polar δ
//! diagrams (Fig. 6), trajectories β(α) over the field-energy landscape (insets of Figs. 9–10).
//! δ over α with its harmonic fit (Fig. 5), orbit diagrams and Lyapunov exponents against f are
//! [`super::LinePlot`]s built by [`fit_plot`], [`orbit_diagram`] and [`lyapunov_plot`].

use super::{plot_err, Figure, LinePlot, Series};
use crate::analysis::classify::WindowSample;
use crate::analysis::HarmonicFit;
use crate::error::Result;
use crate::model::Parameter;
use crate::sweep::{PointRecord, SweepResult};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::f64::consts::TAU;

/// Colour of a value in [0, 1] (a blue–white–red scale: valleys blue, hills red as in the paper).
fn diverging(v: f64) -> RGBColor {
    let v = v.clamp(0.0, 1.0);
    let lerp = |a: f64, b: f64, t: f64| (a + (b - a) * t).round() as u8;
    if v < 0.5 {
        let t = v / 0.5;
        RGBColor(
            lerp(40.0, 245.0, t),
            lerp(70.0, 245.0, t),
            lerp(200.0, 245.0, t),
        )
    } else {
        let t = (v - 0.5) / 0.5;
        RGBColor(
            lerp(245.0, 200.0, t),
            lerp(245.0, 30.0, t),
            lerp(245.0, 30.0, t),
        )
    }
}

/// Sequential colour scale for RMS_δ (dark blue → yellow → red).
fn sequential(v: f64) -> RGBColor {
    let v = v.clamp(0.0, 1.0);
    let stops = [
        (0.0, (20.0, 30.0, 110.0)),
        (0.35, (40.0, 150.0, 200.0)),
        (0.65, (250.0, 220.0, 60.0)),
        (1.0, (200.0, 20.0, 20.0)),
    ];
    for w in stops.windows(2) {
        let ((a, ca), (b, cb)) = (w[0], w[1]);
        if v <= b {
            let t = (v - a) / (b - a);
            let l = |x: f64, y: f64| (x + (y - x) * t).round() as u8;
            return RGBColor(l(ca.0, cb.0), l(ca.1, cb.1), l(ca.2, cb.2));
        }
    }
    RGBColor(200, 20, 20)
}

/// Which class the markers of an [`RmsMap`] show.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Markers {
    /// The paper's flowchart: circle chaos, cross T/2, dash T.
    Paper,
    /// The rigorous class: circle chaos/QP, cross symmetric, dash asymmetric periodic, square
    /// unresolved.
    Rigorous,
    /// No markers.
    None,
}

/// The RMS_δ colour map over a sweep (rows on y, columns on x), with class markers.
#[derive(Debug, Clone)]
pub struct RmsMap {
    /// Title.
    pub title: String,
    /// Row values (y), ascending or not.
    pub rows: Vec<f64>,
    /// Column values (x).
    pub cols: Vec<f64>,
    /// Row axis label.
    pub row_label: String,
    /// Column axis label.
    pub col_label: String,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// The points (row-major, rows × cols).
    pub points: Vec<PointRecord>,
    /// Colour scale maximum, degrees.
    pub vmax: f64,
    /// Markers to draw.
    pub markers: Markers,
}

impl RmsMap {
    /// The map of a finished sweep (markers: the paper's classes; log x for a wide f axis).
    pub fn from_sweep(res: &SweepResult) -> Self {
        let cols = res.spec.cols.values.clone();
        let (lo, hi) = cols
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        Self {
            title: format!("RMS_δ, {:?} protocol", res.spec.protocol),
            rows: res.spec.rows.values.clone(),
            cols,
            row_label: res.spec.rows.param.label(),
            col_label: res.spec.cols.param.label(),
            log_x: lo > 0.0 && hi / lo > 20.0,
            points: res.points().cloned().collect(),
            vmax: 60.0,
            markers: Markers::Paper,
        }
    }
}

/// Cell edges around sorted-by-index centres (midpoints; ends mirrored).
fn edges(c: &[f64], log: bool) -> Vec<f64> {
    let tr = |v: f64| if log { v.ln() } else { v };
    let inv = |v: f64| if log { v.exp() } else { v };
    let n = c.len();
    if n == 1 {
        let w = if log { 0.1 } else { 0.5 * c[0].abs().max(1.0) };
        return vec![inv(tr(c[0]) - w), inv(tr(c[0]) + w)];
    }
    let mut e = Vec::with_capacity(n + 1);
    e.push(inv(tr(c[0]) - 0.5 * (tr(c[1]) - tr(c[0]))));
    for i in 0..n - 1 {
        e.push(inv(0.5 * (tr(c[i]) + tr(c[i + 1]))));
    }
    e.push(inv(tr(c[n - 1]) + 0.5 * (tr(c[n - 1]) - tr(c[n - 2]))));
    e
}

impl Figure for RmsMap {
    fn size(&self) -> (u32, u32) {
        (1000, 650)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (main, bar) = root.split_horizontally(880);
        let ex = edges(&self.cols, self.log_x);
        let ey = edges(&self.rows, false);
        let (x0, x1) = (ex[0].min(ex[ex.len() - 1]), ex[0].max(ex[ex.len() - 1]));
        let (y0, y1) = (ey[0].min(ey[ey.len() - 1]), ey[0].max(ey[ey.len() - 1]));
        let nc = self.cols.len();
        let draw_markers = self.markers != Markers::None && nc * self.rows.len() <= 4000;
        macro_rules! body {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .disable_mesh()
                    .x_desc(self.col_label.as_str())
                    .y_desc(self.row_label.as_str())
                    .label_style(("sans-serif", 14))
                    .draw()
                    .map_err(plot_err)?;
                chart
                    .draw_series(self.points.iter().map(|p| {
                        let c = sequential(p.rms_delta_deg / self.vmax);
                        Rectangle::new(
                            [(ex[p.col], ey[p.row]), (ex[p.col + 1], ey[p.row + 1])],
                            c.filled(),
                        )
                    }))
                    .map_err(plot_err)?;
                if draw_markers {
                    for p in &self.points {
                        let at = (self.cols[p.col], self.rows[p.row]);
                        let kind = match self.markers {
                            Markers::Paper => match p.paper_class.as_str() {
                                "chaos" => 0,
                                "T/2" => 1,
                                _ => 2,
                            },
                            _ => {
                                if p.class == "chaos" || p.class == "QP" {
                                    0
                                } else if p.symmetric {
                                    1
                                } else if p.half_periods > 0 {
                                    2
                                } else {
                                    3
                                }
                            }
                        };
                        let st = ShapeStyle::from(&BLACK).stroke_width(1);
                        match kind {
                            0 => {
                                chart
                                    .draw_series(std::iter::once(Circle::new(at, 4, st)))
                                    .map_err(plot_err)?;
                            }
                            1 => {
                                chart
                                    .draw_series(std::iter::once(Cross::new(at, 4, st)))
                                    .map_err(plot_err)?;
                            }
                            2 => {
                                chart
                                    .draw_series(std::iter::once(
                                        EmptyElement::at(at)
                                            + PathElement::new(vec![(-4, 0), (4, 0)], st),
                                    ))
                                    .map_err(plot_err)?;
                            }
                            _ => {
                                chart
                                    .draw_series(std::iter::once(
                                        EmptyElement::at(at)
                                            + plotters::element::Rectangle::new(
                                                [(-3, -3), (3, 3)],
                                                st,
                                            ),
                                    ))
                                    .map_err(plot_err)?;
                            }
                        }
                    }
                }
            }};
        }
        let mut b = ChartBuilder::on(&main);
        b.caption(&self.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(60);
        if self.log_x {
            body!(b
                .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
                .map_err(plot_err)?);
        } else {
            body!(b.build_cartesian_2d(x0..x1, y0..y1).map_err(plot_err)?);
        }
        // colour bar
        let mut cb = ChartBuilder::on(&bar);
        cb.margin_top(40)
            .margin_bottom(57)
            .margin_right(10)
            .y_label_area_size(45)
            .caption("RMS_δ [°]", ("sans-serif", 14));
        let mut c = cb
            .build_cartesian_2d(0.0..1.0, 0.0..self.vmax)
            .map_err(plot_err)?;
        c.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(plot_err)?;
        let n = 100;
        c.draw_series((0..n).map(|i| {
            let a = self.vmax * i as f64 / n as f64;
            let b2 = self.vmax * (i + 1) as f64 / n as f64;
            Rectangle::new([(0.0, a), (1.0, b2)], sequential(a / self.vmax).filled())
        }))
        .map_err(plot_err)?;
        Ok(())
    }
}

/// Polar diagrams of δ over α (paper Fig. 6): one panel per frequency, radius δ mod 360° (in
/// degrees, rings every 90° labelled), azimuth α (0° to the right, counter-clockwise).
#[derive(Debug, Clone)]
pub struct PolarDelta {
    /// Panels: (title, samples).
    pub panels: Vec<(String, Vec<WindowSample>)>,
}

impl PolarDelta {
    const COLS: usize = 4;
    const PANEL: (u32, u32) = (320, 350);
}

impl Figure for PolarDelta {
    fn size(&self) -> (u32, u32) {
        let n = self.panels.len().max(1);
        let cols = n.min(Self::COLS);
        let rows = n.div_ceil(cols);
        (
            Self::PANEL.0 * cols as u32,
            Self::PANEL.1 * rows as u32 + 30,
        )
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let n = self.panels.len().max(1);
        let cols = n.min(Self::COLS);
        let rows = n.div_ceil(cols);
        let (head, body) = root.split_vertically(30);
        head.draw(&Text::new(
            "radius: δ mod 360° (rings at 90°, 180°, 270°, 360°); azimuth: α (0° right, 90° up)",
            (10, 8),
            ("sans-serif", 15).into_font(),
        ))
        .map_err(plot_err)?;
        let areas = body.split_evenly((rows, cols));
        let grey = RGBColor(170, 170, 170);
        for ((title, s), area) in self.panels.iter().zip(areas.iter()) {
            let inner = area.titled(title, ("sans-serif", 16)).map_err(plot_err)?;
            let (w, h) = inner.dim_in_pixel();
            // equal scales in x and y: the panel's aspect sets the x range
            let r = 400.0;
            let rx = r * w as f64 / h.max(1) as f64;
            let mut ch = ChartBuilder::on(&inner)
                .margin(4)
                .build_cartesian_2d(-rx..rx, -r..r)
                .map_err(plot_err)?;
            for ring in [90.0, 180.0, 270.0, 360.0] {
                ch.draw_series(std::iter::once(PathElement::new(
                    (0..=120)
                        .map(|k| {
                            let a = TAU * k as f64 / 120.0;
                            (ring * a.cos(), ring * a.sin())
                        })
                        .collect::<Vec<_>>(),
                    grey,
                )))
                .map_err(plot_err)?;
                ch.draw_series(std::iter::once(Text::new(
                    format!("{ring:.0}°"),
                    (ring * 0.70, -ring * 0.70),
                    ("sans-serif", 11).into_font().color(&RGBColor(90, 90, 90)),
                )))
                .map_err(plot_err)?;
            }
            for (a, b) in [((-370.0, 0.0), (370.0, 0.0)), ((0.0, -370.0), (0.0, 370.0))] {
                ch.draw_series(std::iter::once(PathElement::new(vec![a, b], grey)))
                    .map_err(plot_err)?;
            }
            ch.draw_series(std::iter::once(Text::new(
                "α = 0°",
                (300.0, 12.0),
                ("sans-serif", 11).into_font().color(&RGBColor(90, 90, 90)),
            )))
            .map_err(plot_err)?;
            let pts: Vec<(f64, f64)> = s
                .iter()
                .map(|w| {
                    let r = w.delta_deg.rem_euclid(360.0);
                    (r * w.alpha.cos(), r * w.alpha.sin())
                })
                .collect();
            ch.draw_series(
                pts.iter()
                    .map(|&p| Circle::new(p, 2, RGBColor(200, 30, 30).filled())),
            )
            .map_err(plot_err)?;
        }
        Ok(())
    }
}

/// A trajectory β(α) (mod 360°) over the field energy E(α, β) (paper Figs. 9–10 insets).
#[derive(Debug, Clone)]
pub struct Landscape {
    /// Title.
    pub title: String,
    /// Shaft index Δ.
    pub delta: f64,
    /// Sign convention of β (Paper: β shifted by 180°).
    pub convention: crate::model::Convention,
    /// The trajectory.
    pub samples: Vec<WindowSample>,
}

impl Figure for Landscape {
    fn size(&self) -> (u32, u32) {
        (620, 560)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let mut ch = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(0.0..360.0, 0.0..360.0)
            .map_err(plot_err)?;
        ch.configure_mesh()
            .disable_mesh()
            .x_desc("α [deg]")
            .y_desc(match self.convention {
                crate::model::Convention::Physical => "β [deg] (physical convention)",
                crate::model::Convention::Paper => "β [deg] (paper convention: physical + 180°)",
            })
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(plot_err)?;
        let n = 72;
        let off = self.convention.beta_offset();
        let d = 360.0 / n as f64;
        let mut cells = Vec::with_capacity(n * n);
        for i in 0..n {
            for j in 0..n {
                let a = ((i as f64 + 0.5) * d).to_radians();
                let b = ((j as f64 + 0.5) * d).to_radians() - off;
                // E/c = sin α sin β + Δ cos α cos β, in [−max(1,|Δ|), max(1,|Δ|)]
                let e = crate::model::gear::energy_bracket(self.delta, a, b);
                let m = 1f64.max(self.delta.abs());
                cells.push(Rectangle::new(
                    [
                        (i as f64 * d, j as f64 * d),
                        ((i + 1) as f64 * d, (j + 1) as f64 * d),
                    ],
                    diverging(0.5 + 0.5 * e / m).filled(),
                ));
            }
        }
        ch.draw_series(cells).map_err(plot_err)?;
        ch.draw_series(self.samples.iter().map(|w| {
            Circle::new(
                (
                    w.alpha.to_degrees().rem_euclid(360.0),
                    w.beta.to_degrees().rem_euclid(360.0),
                ),
                2,
                RGBColor(240, 200, 0).filled(),
            )
        }))
        .map_err(plot_err)?;
        Ok(())
    }
}

/// δ over α (mod 360°) with the harmonic fit (paper Fig. 5), δ shown within ±180° of its mean (a
/// slip wraps); `y_label` names δ's convention.
pub fn fit_plot(
    title: &str,
    y_label: &str,
    samples: &[WindowSample],
    fit: &HarmonicFit,
) -> LinePlot {
    // δ of a window with slips runs over many turns: shown within ±180° of its mean, so that a
    // slip is a wrap and not a line off the page (the fit is drawn as fitted)
    let mean = samples.iter().map(|w| w.delta_deg).sum::<f64>() / samples.len().max(1) as f64;
    let data = samples
        .iter()
        .map(|w| {
            let d = mean + (w.delta_deg - mean + 180.0).rem_euclid(360.0) - 180.0;
            (w.alpha.to_degrees().rem_euclid(360.0), d)
        })
        .collect();
    let curve = (0..=360)
        .map(|k| (k as f64, fit.eval((k as f64).to_radians())))
        .collect();
    LinePlot {
        title: title.into(),
        x_label: "α mod 360 [deg]".into(),
        y_label: y_label.into(),
        series: vec![
            Series {
                label: "simulation (last 10 turns)".into(),
                points: data,
                markers: true,
                color: 0,
            },
            Series {
                label: "7-harmonic fit".into(),
                points: curve,
                markers: false,
                color: 1,
            },
        ],
        ..Default::default()
    }
}

/// An orbit diagram: section points β mod 360° against the swept frequency.
pub fn orbit_diagram(title: &str, points: &[(f64, f64)], log_x: bool) -> LinePlot {
    LinePlot {
        title: title.into(),
        x_label: "f [Hz]".into(),
        y_label: "β at t = kT/2, reduced by the symmetry (physical) [deg]".into(),
        log_x,
        series: vec![Series {
            label: String::new(),
            points: points.to_vec(),
            markers: true,
            color: 0,
        }],
        ..Default::default()
    }
}

/// The largest Lyapunov exponent per drive period against f (−∞ values are left out).
pub fn lyapunov_plot(title: &str, points: &[(f64, f64)], log_x: bool) -> LinePlot {
    LinePlot {
        title: title.into(),
        x_label: "f [Hz]".into(),
        y_label: "λ_max [1/drive period]".into(),
        log_x,
        series: vec![
            Series {
                label: "λ_max".into(),
                points: points.to_vec(),
                markers: true,
                color: 0,
            },
            Series {
                label: "λ = 0".into(),
                points: points
                    .first()
                    .zip(points.last())
                    .map(|(a, b)| vec![(a.0, 0.0), (b.0, 0.0)])
                    .unwrap_or_default(),
                markers: false,
                color: 3,
            },
        ],
        ..Default::default()
    }
}

pub use crate::analysis::harmonic::paper_figure_delta_deg;

/// y label of angles shown as [`paper_figure_delta_deg`].
pub const PAPER_FIGURE_DELTA_LABEL: &str = "α − β [deg] (as plotted in the paper)";

/// Points of an up-and-down run as two marker series in the paper's style: open squares for
/// increasing f, filled circles for decreasing f (drawn first, so the squares stay visible
/// around them).
pub fn updown_series(
    up: Vec<(f64, f64)>,
    down: Vec<(f64, f64)>,
) -> (Vec<Series>, Vec<super::MarkerShape>) {
    (
        vec![
            Series {
                label: "f decreasing".into(),
                points: down,
                markers: true,
                color: 3,
            },
            Series {
                label: "f increasing".into(),
                points: up,
                markers: true,
                color: 1,
            },
        ],
        vec![
            super::MarkerShape::FilledCircle,
            super::MarkerShape::OpenSquare,
        ],
    )
}

/// Fig. 10a: δ_avg of the locked points up and down against f at Θ = 0, with the analytic stable
/// and unstable lock branches, as the paper plots them ([`paper_figure_delta_deg`]).
pub fn hysteresis_lock_plot(
    h: &crate::sweep::Hysteresis,
    gear: &crate::model::GearParams,
) -> Result<LinePlot> {
    let mut stable = Vec::new();
    let mut unstable = Vec::new();
    if let Some(fc) = gear.lock_loss_frequency() {
        for k in 0..=400 {
            let f = (fc * k as f64 / 400.0).max(1e-3);
            let g = crate::model::Gear::new(gear.g(), 1.0, gear.zeta, gear.eta, f)?
                .with_convention(crate::model::Convention::Paper);
            if let Ok(b) = g.lock_branch() {
                stable.push((f, paper_figure_delta_deg(b.stable.phase.to_degrees())));
                unstable.push((f, paper_figure_delta_deg(b.unstable.phase.to_degrees())));
            }
        }
        // close the two branches at the fold
        if let Some(&last) = stable.last() {
            unstable.push(last);
        }
    }
    let pts = |v: &[PointRecord]| -> Vec<(f64, f64)> {
        v.iter()
            .filter(|r| r.locked == Some(true))
            .map(|r| (r.f_hz, paper_figure_delta_deg(r.delta_avg_deg)))
            .collect()
    };
    let (mut series, marker_shapes) = updown_series(pts(&h.up), pts(&h.down));
    series.insert(
        0,
        Series {
            label: "analytic unstable".into(),
            points: unstable,
            markers: false,
            color: 7,
        },
    );
    series.insert(
        0,
        Series {
            label: "analytic stable".into(),
            points: stable,
            markers: false,
            color: 0,
        },
    );
    Ok(LinePlot {
        title: "Θ = 0: lock angle δ_avg of the locked points, analytic lock branches".into(),
        x_label: "f [Hz]".into(),
        y_label: PAPER_FIGURE_DELTA_LABEL.into(),
        series,
        marker_shapes,
        ..Default::default()
    })
}
