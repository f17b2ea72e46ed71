//! The atlas figures: the RMS_δ colour map with its class layer ([`super::classes`]; paper
//! Figs. 7b, 8), polar δ diagrams (Fig. 6), trajectories β(α) over the field energy of eq.
//! `field_energy` (insets of Figs. 9–10), each colour scale with its bar ([`super::colour`]).
//! δ over α with its harmonic fit (Fig. 5), orbit diagrams and Lyapunov exponents against f are
//! [`super::LinePlot`]s built by [`fit_plot`], [`orbit_diagram`] and [`lyapunov_plot`].

use super::classes::{cells_per_marker, legend, Border, ClassGrid, Glyph};
use super::colour::{diverging, sequential, ColourScale};
use super::{plot_err, Figure, LinePlot, Series};
use crate::analysis::classify::WindowSample;
use crate::analysis::HarmonicFit;
use crate::error::Result;
use crate::model::Parameter;
use crate::sweep::{PointRecord, SweepResult};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::f64::consts::TAU;

pub use super::classes::Markers;

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

impl RmsMap {
    /// The colour scale of RMS_δ.
    fn scale(&self) -> ColourScale<'static> {
        ColourScale {
            range: (0.0, self.vmax),
            colour: sequential,
            label: "RMS_δ [deg]",
        }
    }

    /// The cells in their RMS_δ colours, then the class layer; returns the cells per marker
    /// (rows, columns; (1, 1) without a class layer).
    fn draw_map<DB: DrawingBackend, X: Ranged<ValueType = f64>>(
        &self,
        chart: &mut ChartContext<'_, DB, Cartesian2d<X, RangedCoordf64>>,
        (ex, ey): (&[f64], &[f64]),
    ) -> Result<(usize, usize)> {
        let scale = self.scale();
        chart
            .draw_series(self.points.iter().map(|p| {
                Rectangle::new(
                    [(ex[p.col], ey[p.row]), (ex[p.col + 1], ey[p.row + 1])],
                    scale.of(p.rms_delta_deg).filled(),
                )
            }))
            .map_err(plot_err)?;
        if self.markers == Markers::None {
            return Ok((1, 1));
        }
        self.draw_classes(chart, (ex, ey))
    }

    /// The class layer ([`super::classes`]): borders between cells of different classes, then
    /// a marker per block of one class; returns the cells per marker (rows, columns).
    fn draw_classes<DB: DrawingBackend, X: Ranged<ValueType = f64>>(
        &self,
        chart: &mut ChartContext<'_, DB, Cartesian2d<X, RangedCoordf64>>,
        (ex, ey): (&[f64], &[f64]),
    ) -> Result<(usize, usize)> {
        let grid = ClassGrid::new(
            &self.points,
            (self.rows.len(), self.cols.len()),
            self.markers,
        );
        let per = cells_in_glyph(chart, (ex, ey));
        let line = ShapeStyle::from(&BLACK).stroke_width(2);
        chart
            .draw_series(grid.borders().into_iter().map(|b| {
                let ends = match b {
                    Border::Vertical { row, col } => [(ex[col], ey[row]), (ex[col], ey[row + 1])],
                    Border::Horizontal { row, col } => [(ex[col], ey[row]), (ex[col + 1], ey[row])],
                };
                PathElement::new(ends.to_vec(), line)
            }))
            .map_err(plot_err)?;
        let mid = |a: f64, b: f64, log: bool| if log { (a * b).sqrt() } else { 0.5 * (a + b) };
        for b in grid.uniform_blocks(per) {
            let at = (
                mid(ex[b.cols.start], ex[b.cols.end], self.log_x),
                mid(ey[b.rows.start], ey[b.rows.end], false),
            );
            draw_glyph(chart, at, b.glyph)?;
        }
        Ok(per)
    }
}

/// Cells per marker (rows, columns) of a map with cell edges `ex`, `ey` on `chart`
/// ([`cells_per_marker`] of the narrowest cell in pixels).
fn cells_in_glyph<DB: DrawingBackend, X: Ranged<ValueType = f64>>(
    chart: &ChartContext<'_, DB, Cartesian2d<X, RangedCoordf64>>,
    (ex, ey): (&[f64], &[f64]),
) -> (usize, usize) {
    let narrowest = |px: Vec<i32>| {
        px.windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .min()
            .unwrap_or(0) as f64
    };
    let xs = ex.iter().map(|&x| chart.backend_coord(&(x, ey[0])).0);
    let ys = ey.iter().map(|&y| chart.backend_coord(&(ex[0], y)).1);
    (
        cells_per_marker(narrowest(ys.collect())),
        cells_per_marker(narrowest(xs.collect())),
    )
}

/// One class marker at `at` (8 px: circle, cross, dash or square).
fn draw_glyph<DB: DrawingBackend, X: Ranged<ValueType = f64>>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, RangedCoordf64>>,
    at: (f64, f64),
    glyph: Glyph,
) -> Result<()> {
    let st = ShapeStyle::from(&BLACK).stroke_width(1);
    let drawn = match glyph {
        Glyph::Circle => chart.draw_series(std::iter::once(Circle::new(at, 4, st))),
        Glyph::Cross => chart.draw_series(std::iter::once(Cross::new(at, 4, st))),
        Glyph::Dash => chart.draw_series(std::iter::once(
            EmptyElement::at(at) + PathElement::new(vec![(-4, 0), (4, 0)], st),
        )),
        Glyph::Square => chart.draw_series(std::iter::once(
            EmptyElement::at(at) + Rectangle::new([(-3, -3), (3, 3)], st),
        )),
    };
    drawn.map(|_| ()).map_err(plot_err)
}

impl Figure for RmsMap {
    fn size(&self) -> (u32, u32) {
        (1000, 690)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (body, foot) = root.split_vertically(650);
        let (main, bar) = body.split_horizontally(880);
        let ex = edges(&self.cols, self.log_x);
        let ey = edges(&self.rows, false);
        let (x0, x1) = (ex[0].min(ex[ex.len() - 1]), ex[0].max(ex[ex.len() - 1]));
        let (y0, y1) = (ey[0].min(ey[ey.len() - 1]), ey[0].max(ey[ey.len() - 1]));
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
                self.draw_map(&mut chart, (&ex, &ey))?
            }};
        }
        let mut b = ChartBuilder::on(&main);
        b.caption(&self.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(60);
        let per = if self.log_x {
            body!(b
                .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
                .map_err(plot_err)?)
        } else {
            body!(b.build_cartesian_2d(x0..x1, y0..y1).map_err(plot_err)?)
        };
        self.scale().draw_bar(&bar, (40, 57))?;
        if self.markers != Markers::None {
            for (k, text) in legend(self.markers, per).iter().enumerate() {
                foot.draw(&Text::new(
                    text.as_str(),
                    (72, 18 * k as i32),
                    ("sans-serif", 14).into_font(),
                ))
                .map_err(plot_err)?;
            }
        }
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

/// A trajectory β(α) (mod 360°) over the field energy E(α, β) of eq. `field_energy` (paper
/// Figs. 9–10 insets), with the energy's colour bar in mJ.
#[derive(Debug, Clone)]
pub struct Landscape {
    /// Title.
    pub title: String,
    /// Shaft index Δ.
    pub delta: f64,
    /// Coupling energy scale c = μ₀ m₁ m₂ / (4π r³), J (`GearParams::coupling`).
    pub coupling_j: f64,
    /// Sign convention of β (Paper: β shifted by 180°).
    pub convention: crate::model::Convention,
    /// The trajectory.
    pub samples: Vec<WindowSample>,
}

impl Landscape {
    /// Label of the colour bar.
    pub const ENERGY_LABEL: &'static str = "field energy E(α, β) [mJ]";

    /// The energy's colour scale: ±c max(1, |Δ|) in mJ, the range of E.
    fn scale(&self) -> ColourScale<'static> {
        let m = 1e3 * self.coupling_j * 1f64.max(self.delta.abs());
        ColourScale {
            range: (-m, m),
            colour: diverging,
            label: Self::ENERGY_LABEL,
        }
    }

    /// The cells of the background's grid per axis.
    const GRID: usize = 72;

    /// E(α, β) = c (sin α sin β + Δ cos α cos β) in mJ at the centre of cell (i, j) of the
    /// background (α of column i, β of row j in the figure's convention, taken back to the
    /// physical one).
    fn energy_mj(&self, (i, j): (usize, usize)) -> f64 {
        let d = 360.0 / Self::GRID as f64;
        let a = ((i as f64 + 0.5) * d).to_radians();
        let b = ((j as f64 + 0.5) * d).to_radians() - self.convention.beta_offset();
        1e3 * self.coupling_j * crate::model::gear::energy_bracket(self.delta, a, b)
    }

    /// The background: [`Landscape::energy_mj`] on its grid, in the energy's colours.
    fn energy_cells(&self) -> Vec<Rectangle<(f64, f64)>> {
        let (n, scale) = (Self::GRID, self.scale());
        let d = 360.0 / n as f64;
        let mut cells = Vec::with_capacity(n * n);
        for i in 0..n {
            for j in 0..n {
                let (x, y) = (i as f64 * d, j as f64 * d);
                cells.push(Rectangle::new(
                    [(x, y), (x + d, y + d)],
                    scale.of(self.energy_mj((i, j))).filled(),
                ));
            }
        }
        cells
    }
}

impl Figure for Landscape {
    fn size(&self) -> (u32, u32) {
        (740, 580)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (body, foot) = root.split_vertically(560);
        let (main, bar) = body.split_horizontally(620);
        let mut ch = ChartBuilder::on(&main)
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
        ch.draw_series(self.energy_cells()).map_err(plot_err)?;
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
        self.scale().draw_bar(&bar, (40, 52))?;
        foot.draw(&Text::new(
            format!(
                "yellow: the attractor's β(α); background: E = c (sin α sin β + Δ cos α cos β), c = {:.1} mJ, Δ = {:.3}",
                1e3 * self.coupling_j,
                self.delta
            ),
            (12, 0),
            ("sans-serif", 13).into_font(),
        ))
        .map_err(plot_err)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plotting::classes::GLYPH_PX;
    use crate::plotting::to_svg;

    fn point(row: usize, col: usize, paper_class: &str) -> PointRecord {
        PointRecord {
            row,
            col,
            row_value: row as f64,
            col_value: col as f64,
            f_hz: 1.0,
            delta: 1.0,
            rms_delta_deg: 10.0,
            rms_fit_deg: 0.0,
            thd: None,
            thd_printed: None,
            delta_avg_deg: 0.0,
            delta_fund_deg: 0.0,
            net_rotation_hz: 0.0,
            paper_class: paper_class.into(),
            class: String::new(),
            half_periods: 0,
            symmetric: false,
            rotation_number: None,
            locked: None,
            lyapunov: None,
            agree: None,
            beta_end: 0.0,
            omega_end: 0.0,
        }
    }

    /// A map of `rows` × `cols` cells on a log f axis, the class of each cell from `class`.
    fn map(rows: usize, cols: usize, class: impl Fn(usize, usize) -> &'static str) -> RmsMap {
        RmsMap {
            title: "test".into(),
            rows: (0..rows).map(|r| 10.0 * r as f64).collect(),
            cols: (0..cols)
                .map(|c| 0.1 * 1000f64.powf(c as f64 / cols as f64))
                .collect(),
            row_label: "Θ [deg]".into(),
            col_label: "f [Hz]".into(),
            log_x: true,
            points: (0..rows * cols)
                .map(|k| point(k / cols, k % cols, class(k / cols, k % cols)))
                .collect(),
            vmax: 60.0,
            markers: Markers::Paper,
        }
    }

    /// The centres (cx, cy) of the circles of an SVG text.
    fn circles(svg: &str) -> Vec<(f64, f64)> {
        let attr = |el: &str, name: &str| -> f64 {
            let i = el.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
            el[i..i + el[i..].find('"').unwrap()].parse().unwrap()
        };
        svg.split("<circle")
            .skip(1)
            .map(|el| (attr(el, "cx"), attr(el, "cy")))
            .collect()
    }

    #[test]
    fn class_markers_never_crowd_closer_than_a_glyph() {
        // wide cells: one marker per cell
        let svg = to_svg(&map(3, 10, |_, _| "chaos")).unwrap();
        assert_eq!(circles(&svg).len(), 30);
        assert!(svg.contains("one marker per cell"));
        // 200 columns of 4 px: the markers thin out to blocks, never closer than a glyph
        let svg = to_svg(&map(3, 200, |_, _| "chaos")).unwrap();
        let c = circles(&svg);
        assert!(c.len() >= 3 && c.len() <= 3 * 200 / 3, "{}", c.len());
        for a in &c {
            for b in &c {
                let d = (a.0 - b.0).hypot(a.1 - b.1);
                assert!(d == 0.0 || d >= GLYPH_PX - 1.0, "{a:?} {b:?}");
            }
        }
        assert!(svg.contains("one marker per block of"));
        // a narrow checkerboard: every block mixed, no marker; the borders are drawn
        let checker = to_svg(&map(
            3,
            200,
            |r, c| if (r + c) % 2 == 0 { "chaos" } else { "T/2" },
        ));
        let checker = checker.unwrap();
        assert!(circles(&checker).is_empty());
        assert!(checker.matches("<polyline").count() >= 3 * 199);
    }

    #[test]
    fn the_inset_background_is_the_field_energy_with_its_colour_bar() {
        // Θ = 0 (Δ = 1): E = c cos(α − β), in the paper's β (physical + 180°) lowest on the
        // diagonal β = α and highest on β = α ± 180°
        let l = Landscape {
            title: "test".into(),
            delta: 1.0,
            coupling_j: 0.0193,
            convention: crate::model::Convention::Paper,
            samples: Vec::new(),
        };
        let (c_mj, scale) = (19.3, l.scale());
        assert_eq!(scale.range, (-c_mj, c_mj));
        for i in [0, 17, 50] {
            assert!((l.energy_mj((i, i)) + c_mj).abs() < 1e-9);
            assert!((l.energy_mj((i, (i + 36) % 72)) - c_mj).abs() < 1e-9);
            // a quarter turn apart: E = 0
            assert!(l.energy_mj((i, (i + 18) % 72)).abs() < 1e-9);
        }
        // valleys blue, hills red
        assert_eq!(scale.of(-c_mj), diverging(0.0));
        assert_eq!(scale.of(c_mj), diverging(1.0));
        assert_eq!(l.energy_cells().len(), 72 * 72);
        let svg = to_svg(&l).unwrap();
        assert!(svg.contains(Landscape::ENERGY_LABEL));
        assert!(svg.contains("c = 19.3 mJ"));
    }
}
