//! Figures of continuation results, read from the one result type [`Branch`] (and [`Curve`]):
//! branch diagrams in the style of the paper's Fig. 9 and 10 (stable solid, unstable dashed, special
//! points marked), multipliers in the complex plane, and two-parameter boundaries.

use super::{plot_err, Figure};
use crate::continuation::two_param::Curve;
use crate::continuation::{Branch, SpecialKind};
use crate::error::Result;
use crate::model::{Gear, Parameter, Parametrised};
use plotters::coord::Shift;
use plotters::prelude::*;

/// What a branch diagram shows on the y axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Quantity {
    /// β on the section at t = 0 (drive angle α = 0), degrees in [0, 360): for the lock at Θ = 0
    /// this is the lock angle δ = β − α.
    #[default]
    BetaDeg,
    /// ω on the section, rad/s.
    Omega,
    /// α − β at t = 0 with the physical β, degrees in [0, 360): the angle the paper's Figs. 9–10
    /// plot (see [`super::atlas::paper_figure_delta_deg`]); the Θ = 0 lock branch is then the
    /// paper's eq. `delta_lock`.
    PaperFigureDelta,
}

/// A branch diagram of one or more branches: stable parts solid, unstable dashed, special points
/// marked by a shape per type and listed with their parameter values beside the plot.
#[derive(Debug, Clone)]
pub struct BranchDiagram<S: Parametrised = Gear> {
    /// Title.
    pub title: String,
    /// The branches (same continuation parameter).
    pub branches: Vec<Branch<S>>,
    /// Legend label of each branch (missing ones: [`branch_label`]).
    pub labels: Vec<String>,
    /// The y quantity.
    pub quantity: Quantity,
    /// Show angles in the paper's convention (β + 180°).
    pub paper_convention: bool,
}

fn kind_color(k: SpecialKind) -> RGBColor {
    match k {
        SpecialKind::Fold => RGBColor(200, 0, 0),
        SpecialKind::Flip => RGBColor(0, 120, 0),
        SpecialKind::SymmetryBreaking => RGBColor(0, 0, 200),
        SpecialKind::NeimarkSacker => RGBColor(160, 0, 160),
        SpecialKind::Nonsmooth => RGBColor(230, 140, 0),
    }
}

/// The marker of a special point of kind `k` at pixel offset (0, 0).
fn kind_marker<DB: DrawingBackend>(
    k: SpecialKind,
    at: (i32, i32),
) -> DynElement<'static, DB, (i32, i32)> {
    let c = kind_color(k);
    let st = ShapeStyle::from(c).stroke_width(2);
    match k {
        SpecialKind::Fold => TriangleMarker::new(at, 7, c.filled()).into_dyn(),
        SpecialKind::Flip => Cross::new(at, 6, st).into_dyn(),
        SpecialKind::SymmetryBreaking => {
            Rectangle::new([(at.0 - 5, at.1 - 5), (at.0 + 5, at.1 + 5)], st).into_dyn()
        }
        SpecialKind::NeimarkSacker => Circle::new(at, 6, st).into_dyn(),
        SpecialKind::Nonsmooth => Circle::new(at, 4, c.filled()).into_dyn(),
    }
}

impl<S: Parametrised> Default for BranchDiagram<S> {
    fn default() -> Self {
        Self {
            title: String::new(),
            branches: Vec::new(),
            labels: Vec::new(),
            quantity: Quantity::default(),
            paper_convention: false,
        }
    }
}

/// A legend label of a branch from its orbit specification: "symmetric (G, p = 1)",
/// "period 2 (P_T², p = 2)".
pub fn branch_label<S: Parametrised>(b: &Branch<S>) -> String {
    let k = b.spec.iterations;
    let p = b.spec.winding;
    match b.spec.section {
        crate::maps::Section::HalfPeriod if k == 1 => format!("symmetric (G, p = {p})"),
        crate::maps::Section::HalfPeriod => format!("symmetric, {k}T/2 (G^{k}, p = {p})"),
        crate::maps::Section::Stroboscopic if k == 1 => format!("period T (P_T, p = {p})"),
        crate::maps::Section::Stroboscopic => format!("period {k}T (P_T^{k}, p = {p})"),
    }
}

impl<S: Parametrised> BranchDiagram<S> {
    fn y(&self, x: [f64; 2]) -> f64 {
        match self.quantity {
            Quantity::BetaDeg => {
                let off = if self.paper_convention { 180.0 } else { 0.0 };
                (x[0].to_degrees() + off).rem_euclid(360.0)
            }
            Quantity::Omega => x[1],
            Quantity::PaperFigureDelta => (-x[0].to_degrees()).rem_euclid(360.0),
        }
    }

    fn y_label(&self) -> &'static str {
        match (self.quantity, self.paper_convention) {
            (Quantity::BetaDeg, false) => "β at t = 0 (α = 0), physical convention [deg]",
            (Quantity::BetaDeg, true) => "β at t = 0 (α = 0), paper convention [deg]",
            (Quantity::Omega, _) => "ω at t = 0 [rad/s]",
            (Quantity::PaperFigureDelta, _) => "α − β at t = 0 [deg] (as plotted in the paper)",
        }
    }
}

fn range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    super::finite_range(v, false).unwrap_or((0.0, 1.0))
}

/// A special point as drawn: kind, parameter, y value; its number in the list is its index + 1.
#[derive(Debug, Clone, Copy)]
struct Mark {
    kind: SpecialKind,
    param: f64,
    y: f64,
}

/// Draws a run of points of one stability, solid (stable) or dashed (unstable).
fn draw_run<DB: DrawingBackend, CT: CoordTranslate<From = (f64, f64)>>(
    chart: &mut ChartContext<'_, DB, CT>,
    run: &[(f64, f64)],
    stable: bool,
    col: RGBAColor,
) -> Result<()> {
    if run.len() < 2 {
        return Ok(());
    }
    if stable {
        chart
            .draw_series(LineSeries::new(run.to_vec(), col.stroke_width(2)))
            .map_err(plot_err)?;
    } else {
        chart
            .draw_series(DashedLineSeries::new(
                run.to_vec(),
                6,
                4,
                col.stroke_width(2),
            ))
            .map_err(plot_err)?;
    }
    Ok(())
}

impl<S: Parametrised> BranchDiagram<S> {
    /// The distinct legend labels, and for each branch the index of its label (its colour):
    /// branches of one kind (e.g. several runs of the automatic diagram) share one entry.
    fn label_groups(&self) -> (Vec<String>, Vec<usize>) {
        let mut labels: Vec<String> = Vec::new();
        let idx = self
            .branches
            .iter()
            .enumerate()
            .map(|(bi, b)| {
                let l = self
                    .labels
                    .get(bi)
                    .cloned()
                    .unwrap_or_else(|| branch_label(b));
                labels.iter().position(|k| *k == l).unwrap_or_else(|| {
                    labels.push(l);
                    labels.len() - 1
                })
            })
            .collect();
        (labels, idx)
    }

    /// The special points of all branches, each once (the same point found on several runs is
    /// drawn and listed once), in order of the parameter.
    fn marks(&self, x_span: f64, y_span: f64) -> Vec<Mark> {
        let mut v: Vec<Mark> = Vec::new();
        for s in self.branches.iter().flat_map(|b| b.specials.iter()) {
            let m = Mark {
                kind: s.kind,
                param: s.param,
                y: self.y(s.x),
            };
            let dup = v.iter().any(|o| {
                o.kind == m.kind
                    && (o.param - m.param).abs() <= 1e-4 * x_span
                    && (o.y - m.y).abs() <= 1e-3 * y_span
            });
            if !dup {
                v.push(m);
            }
        }
        v.sort_by(|a, b| a.param.total_cmp(&b.param));
        v
    }

    /// Height of the side panel's content: the legend, then one row per special point.
    fn panel_height(&self) -> u32 {
        let (labels, _) = self.label_groups();
        let n = self.marks(1.0, 1.0).len();
        (60 + 20 * labels.len() + 30 + 17 * n) as u32
    }

    /// Draws the side panel: the branch legend, then the numbered special points.
    fn draw_panel<DB: DrawingBackend>(
        &self,
        side: &DrawingArea<DB, Shift>,
        labels: &[String],
        marks: &[Mark],
        pname: &str,
    ) -> Result<()> {
        let font = ("sans-serif", 14).into_font();
        let small = ("sans-serif", 13).into_font();
        let mut y = 20;
        side.draw(&Text::new(
            "solid: stable, dashed: unstable",
            (5, y),
            font.clone(),
        ))
        .map_err(plot_err)?;
        y += 25;
        for (li, l) in labels.iter().enumerate() {
            let col = Palette99::pick(li).to_rgba();
            side.draw(&PathElement::new(
                vec![(8, y + 7), (30, y + 7)],
                col.stroke_width(3),
            ))
            .map_err(plot_err)?;
            side.draw(&Text::new(l.as_str(), (36, y), font.clone()))
                .map_err(plot_err)?;
            y += 20;
        }
        if marks.is_empty() {
            return Ok(());
        }
        y += 10;
        side.draw(&Text::new("special points", (5, y), font.clone()))
            .map_err(plot_err)?;
        y += 20;
        for (i, m) in marks.iter().enumerate() {
            side.draw(&Text::new(format!("{:>2}", i + 1), (5, y), small.clone()))
                .map_err(plot_err)?;
            side.draw(&(EmptyElement::at((38, y + 7)) + kind_marker::<DB>(m.kind, (0, 0))))
                .map_err(plot_err)?;
            side.draw(&Text::new(
                format!("{} {pname} = {:.4}", m.kind.label(), m.param),
                (52, y),
                small.clone(),
            ))
            .map_err(plot_err)?;
            y += 17;
        }
        Ok(())
    }
}

impl<S: Parametrised> Figure for BranchDiagram<S> {
    fn size(&self) -> (u32, u32) {
        (1150, self.panel_height().max(640))
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        root.fill(&WHITE).map_err(plot_err)?;
        let (main, side) = root.split_horizontally(850);
        let pts = || self.branches.iter().flat_map(|b| b.points.iter());
        let (x0, x1) = range(pts().map(|p| p.param));
        let (y0, y1) = range(pts().map(|p| self.y(p.x)));
        let (pname, xlabel) = self
            .branches
            .first()
            .map(|b| (b.param.name(), b.param.label()))
            .unwrap_or(("parameter", "parameter".into()));
        let mut chart = ChartBuilder::on(&main)
            .caption(&self.title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc(xlabel)
            .y_desc(self.y_label())
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 15))
            .draw()
            .map_err(plot_err)?;
        let (labels, color_of) = self.label_groups();
        for (bi, b) in self.branches.iter().enumerate() {
            let col = Palette99::pick(color_of[bi]).to_rgba();
            // runs of equal stability; break runs where β wraps around
            let mut run: Vec<(f64, f64)> = Vec::new();
            let mut stable = b.points.first().map(|p| p.stable).unwrap_or(true);
            for p in &b.points {
                let q = (p.param, self.y(p.x));
                let wrap = run
                    .last()
                    .map(|l| (l.1 - q.1).abs() > 180.0 && self.quantity != Quantity::Omega)
                    .unwrap_or(false);
                if wrap {
                    draw_run(&mut chart, &run, stable, col)?;
                    run.clear();
                }
                if p.stable != stable {
                    run.push(q);
                    draw_run(&mut chart, &run, stable, col)?;
                    run = vec![q];
                    stable = p.stable;
                }
                run.push(q);
            }
            draw_run(&mut chart, &run, stable, col)?;
        }
        let marks = self.marks(x1 - x0, y1 - y0);
        chart
            .draw_series(
                marks
                    .iter()
                    .map(|m| EmptyElement::at((m.param, m.y)) + kind_marker::<DB>(m.kind, (0, 0))),
            )
            .map_err(plot_err)?;
        // the numbers next to the markers, placed so that none covers another or a marker
        let anchors: Vec<(i32, i32)> = marks
            .iter()
            .map(|m| chart.backend_coord(&(m.param, m.y)))
            .collect();
        let sizes: Vec<(i32, i32)> = (1..=marks.len())
            .map(|k| (8 * k.to_string().len() as i32, 12))
            .collect();
        let area = chart.plotting_area().get_pixel_range();
        let bounds = (area.0.start, area.1.start, area.0.end, area.1.end);
        let placed = super::place_labels(&anchors, &sizes, bounds);
        for (k, (&(px, py), m)) in placed.iter().zip(&marks).enumerate() {
            let c = kind_color(m.kind);
            main.draw(&Text::new(
                (k + 1).to_string(),
                (px, py),
                ("sans-serif", 13).into_font().color(&c),
            ))
            .map_err(plot_err)?;
        }
        // the legend and the list of special points sit in the side panel, not over the data
        self.draw_panel(&side, &labels, &marks, pname)
    }
}

/// Multipliers of every point of a branch in the complex plane, with the unit circle; stable
/// points blue, unstable orange.
#[derive(Debug, Clone)]
pub struct MultiplierPlot<S: Parametrised = Gear> {
    /// Title.
    pub title: String,
    /// The branch.
    pub branch: Option<Branch<S>>,
}

impl<S: Parametrised> Default for MultiplierPlot<S> {
    fn default() -> Self {
        Self {
            title: String::new(),
            branch: None,
        }
    }
}

impl<S: Parametrised> Figure for MultiplierPlot<S> {
    fn size(&self) -> (u32, u32) {
        (720, 720)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        root.fill(&WHITE).map_err(plot_err)?;
        let mut r: f64 = 1.2;
        if let Some(b) = &self.branch {
            for p in &b.points {
                r = r.max(1.1 * p.floquet.spectral_radius().min(5.0));
            }
        }
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 18))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(-r..r, -r..r)
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc("Re μ")
            .y_desc("Im μ")
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 15))
            .draw()
            .map_err(plot_err)?;
        chart
            .draw_series(LineSeries::new(
                (0..=200).map(|i| {
                    let t = i as f64 / 200.0 * std::f64::consts::TAU;
                    (t.cos(), t.sin())
                }),
                BLACK.stroke_width(1),
            ))
            .map_err(plot_err)?
            .label("unit circle |μ| = 1")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK));
        let mut frac = Vec::new();
        if let Some(b) = &self.branch {
            for (stable, c, label) in [
                (true, RGBColor(0, 90, 200), "stable orbit"),
                (false, RGBColor(220, 60, 0), "unstable orbit"),
            ] {
                let pts: Vec<(f64, f64)> = b
                    .points
                    .iter()
                    .filter(|p| p.stable == stable)
                    .flat_map(|p| p.floquet.multipliers)
                    .filter(|z| z[0].abs() <= r && z[1].abs() <= r)
                    .map(|z| (z[0], z[1]))
                    .collect();
                frac.extend(
                    pts.iter()
                        .map(|p| ((p.0 + r) / (2.0 * r), (p.1 + r) / (2.0 * r))),
                );
                if pts.is_empty() {
                    continue;
                }
                chart
                    .draw_series(pts.into_iter().map(|p| Circle::new(p, 3, c.filled())))
                    .map_err(plot_err)?
                    .label(label)
                    .legend(move |(x, y)| Circle::new((x + 9, y), 3, c.filled()));
            }
        }
        let (pos, _) = super::legend_corner(&frac, 3, 20, (600, 600));
        super::draw_legend(&mut chart, pos)
    }
}

/// Two-parameter curves (e.g. the lock-loss boundary f_c(Θ)): one colour and one legend entry per
/// distinct label (curves continued from one start in both directions share a label).
#[derive(Debug, Clone)]
pub struct BoundaryPlot<S: Parametrised = Gear> {
    /// Title.
    pub title: String,
    /// The curves.
    pub curves: Vec<(String, Curve<S>)>,
    /// Extra reference points (label, x, y), e.g. analytic values, drawn as black dots and listed
    /// in the legend.
    pub marks: Vec<(String, f64, f64)>,
    /// A logarithmic axis for the free parameter (curves spanning decades, e.g. f from 1 to
    /// 40 Hz); its values must be > 0.
    pub log_y: bool,
}

impl<S: Parametrised> Default for BoundaryPlot<S> {
    fn default() -> Self {
        Self {
            title: String::new(),
            curves: Vec::new(),
            marks: Vec::new(),
            log_y: false,
        }
    }
}

impl<S: Parametrised> Figure for BoundaryPlot<S> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        root.fill(&WHITE).map_err(plot_err)?;
        let all = || self.curves.iter().flat_map(|c| c.1.points.iter());
        let (x0, x1) = range(all().map(|p| p.along).chain(self.marks.iter().map(|m| m.1)));
        let ys = || all().map(|p| p.free).chain(self.marks.iter().map(|m| m.2));
        let (y0, y1) = if self.log_y {
            super::finite_range(ys(), true).unwrap_or((0.1, 1.0))
        } else {
            range(ys())
        };
        let (xl, yl) = self
            .curves
            .first()
            .map(|c| (c.1.along.label(), c.1.free.label()))
            .unwrap_or_default();
        let mut labels: Vec<&str> = Vec::new();
        for (l, _) in &self.curves {
            if !labels.contains(&l.as_str()) {
                labels.push(l);
            }
        }
        let mut mark_labels: Vec<&str> = Vec::new();
        for (l, _, _) in &self.marks {
            if !mark_labels.contains(&l.as_str()) {
                mark_labels.push(l);
            }
        }
        // positions as fractions of the axes (of log y on a log axis), for the legend's corner
        let fy = |y: f64| if self.log_y { y.ln() } else { y };
        let frac: Vec<(f64, f64)> = all()
            .map(|p| (p.along, p.free))
            .chain(self.marks.iter().map(|m| (m.1, m.2)))
            .map(|(x, y)| ((x - x0) / (x1 - x0), (fy(y) - fy(y0)) / (fy(y1) - fy(y0))))
            .collect();
        let chars = labels
            .iter()
            .chain(&mark_labels)
            .map(|l| l.chars().count())
            .max()
            .unwrap_or(0);
        let (pos, headroom) =
            super::legend_corner(&frac, labels.len() + mark_labels.len(), chars, (780, 480));
        let y1 = if self.log_y {
            y1 * (y1 / y0).powf(headroom)
        } else {
            y1 + headroom * (y1 - y0)
        };
        let mut b = super::line_frame(root, &self.title);
        macro_rules! body {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(xl)
                    .y_desc(yl)
                    .label_style(("sans-serif", 14))
                    .axis_desc_style(("sans-serif", 15))
                    .draw()
                    .map_err(plot_err)?;
                for (label, c) in &self.curves {
                    let i = labels.iter().position(|l| l == label).unwrap_or(0);
                    // skip the palette's yellow (index 2), unreadable on white
                    let col = Palette99::pick(if i >= 2 { i + 1 } else { i }).to_rgba();
                    let anno = chart
                        .draw_series(LineSeries::new(
                            c.points.iter().map(|p| (p.along, p.free)),
                            col.stroke_width(2),
                        ))
                        .map_err(plot_err)?;
                    // one legend entry per label: on its first curve
                    if self.curves.iter().position(|(l, _)| l == label)
                        == self.curves.iter().position(|x| std::ptr::eq(&x.1, c))
                    {
                        anno.label(label.as_str()).legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 18, y)], col.stroke_width(3))
                        });
                    }
                }
                // one colour per kind of mark: black first, then distinct dark colours
                let mark_colours = [
                    BLACK,
                    RGBColor(200, 30, 30),
                    RGBColor(30, 30, 200),
                    RGBColor(0, 140, 0),
                    RGBColor(160, 0, 160),
                    RGBColor(200, 120, 0),
                ];
                for (k, ml) in mark_labels.iter().enumerate() {
                    let pts: Vec<(f64, f64)> = self
                        .marks
                        .iter()
                        .filter(|m| m.0 == *ml)
                        .map(|m| (m.1, m.2))
                        .collect();
                    let col = mark_colours[k % mark_colours.len()];
                    chart
                        .draw_series(pts.into_iter().map(|p| Circle::new(p, 5, col.filled())))
                        .map_err(plot_err)?
                        .label(*ml)
                        .legend(move |(x, y)| Circle::new((x + 9, y), 5, col.filled()));
                }
                if !self.curves.is_empty() || !self.marks.is_empty() {
                    super::draw_legend(&mut chart, pos)?;
                }
            }};
        }
        if self.log_y {
            body!(b
                .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                .map_err(plot_err)?)
        } else {
            body!(b.build_cartesian_2d(x0..x1, y0..y1).map_err(plot_err)?)
        }
        Ok(())
    }
}
