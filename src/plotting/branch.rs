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
}

/// A branch diagram of one or more branches of any system.
#[derive(Debug, Clone)]
pub struct BranchDiagram<S: Parametrised = Gear> {
    /// Title.
    pub title: String,
    /// The branches (same continuation parameter).
    pub branches: Vec<Branch<S>>,
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

impl<S: Parametrised> Default for BranchDiagram<S> {
    fn default() -> Self {
        Self {
            title: String::new(),
            branches: Vec::new(),
            quantity: Quantity::default(),
            paper_convention: false,
        }
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
        }
    }
}

fn range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for x in v.filter(|x| x.is_finite()) {
        lo = lo.min(x);
        hi = hi.max(x);
    }
    if lo > hi {
        return (0.0, 1.0);
    }
    let d = if hi > lo { 0.05 * (hi - lo) } else { 1.0 };
    (lo - d, hi + d)
}

impl<S: Parametrised> Figure for BranchDiagram<S> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        root.fill(&WHITE).map_err(plot_err)?;
        let pts = || self.branches.iter().flat_map(|b| b.points.iter());
        let (x0, x1) = range(pts().map(|p| p.param));
        let (y0, y1) = range(pts().map(|p| self.y(p.x)));
        let pname = self
            .branches
            .first()
            .map(|b| b.param.label())
            .unwrap_or_else(|| "parameter".into());
        let ylabel = match self.quantity {
            Quantity::BetaDeg => "β at α = 0 [deg]",
            Quantity::Omega => "ω at α = 0 [rad/s]",
        };
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc(pname)
            .y_desc(ylabel)
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(plot_err)?;
        for (bi, b) in self.branches.iter().enumerate() {
            let col = Palette99::pick(bi).to_rgba();
            // runs of equal stability; break runs where β wraps around
            let mut run: Vec<(f64, f64)> = Vec::new();
            let mut stable = b.points.first().map(|p| p.stable).unwrap_or(true);
            let flush = |run: &mut Vec<(f64, f64)>,
                         stable: bool,
                         chart: &mut ChartContext<'_, DB, _>|
             -> Result<()> {
                if run.len() > 1 {
                    if stable {
                        chart
                            .draw_series(LineSeries::new(run.clone(), col.stroke_width(2)))
                            .map_err(plot_err)?;
                    } else {
                        chart
                            .draw_series(DashedLineSeries::new(
                                run.clone(),
                                6,
                                4,
                                col.stroke_width(2),
                            ))
                            .map_err(plot_err)?;
                    }
                }
                let last = run.last().copied();
                run.clear();
                if let Some(l) = last {
                    run.push(l);
                }
                Ok(())
            };
            for p in &b.points {
                let q = (p.param, self.y(p.x));
                let wrap = run
                    .last()
                    .map(|l| (l.1 - q.1).abs() > 180.0 && self.quantity == Quantity::BetaDeg)
                    .unwrap_or(false);
                if wrap {
                    flush(&mut run, stable, &mut chart)?;
                    run.clear();
                }
                if p.stable != stable {
                    run.push(q);
                    flush(&mut run, stable, &mut chart)?;
                    stable = p.stable;
                }
                run.push(q);
            }
            flush(&mut run, stable, &mut chart)?;
            for s in &b.specials {
                let c = kind_color(s.kind);
                let q = (s.param, self.y(s.x));
                chart
                    .draw_series(std::iter::once(TriangleMarker::new(q, 7, c.filled())))
                    .map_err(plot_err)?;
                chart
                    .draw_series(std::iter::once(Text::new(
                        format!("{} {:.4}", s.kind.label(), s.param),
                        (q.0, q.1),
                        ("sans-serif", 12).into_font().color(&c),
                    )))
                    .map_err(plot_err)?;
            }
        }
        Ok(())
    }
}

/// Multipliers of every point of a branch in the complex plane, with the unit circle.
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
        (700, 700)
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
            .caption(&self.title, ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(-r..r, -r..r)
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc("Re μ")
            .y_desc("Im μ")
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
            .map_err(plot_err)?;
        if let Some(b) = &self.branch {
            for p in &b.points {
                let c = if p.stable {
                    RGBColor(0, 90, 200)
                } else {
                    RGBColor(220, 60, 0)
                };
                for z in p.floquet.multipliers {
                    if z[0].abs() <= r && z[1].abs() <= r {
                        chart
                            .draw_series(std::iter::once(Circle::new((z[0], z[1]), 3, c.filled())))
                            .map_err(plot_err)?;
                    }
                }
            }
        }
        Ok(())
    }
}

/// Two-parameter curves (e.g. the lock-loss boundary f_c(Θ)).
#[derive(Debug, Clone)]
pub struct BoundaryPlot<S: Parametrised = Gear> {
    /// Title.
    pub title: String,
    /// The curves.
    pub curves: Vec<(String, Curve<S>)>,
    /// Extra reference points (label, x, y), e.g. analytic values.
    pub marks: Vec<(String, f64, f64)>,
}

impl<S: Parametrised> Default for BoundaryPlot<S> {
    fn default() -> Self {
        Self {
            title: String::new(),
            curves: Vec::new(),
            marks: Vec::new(),
        }
    }
}

impl<S: Parametrised> Figure for BoundaryPlot<S> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        root.fill(&WHITE).map_err(plot_err)?;
        let all = || self.curves.iter().flat_map(|c| c.1.points.iter());
        let (x0, x1) = range(all().map(|p| p.along).chain(self.marks.iter().map(|m| m.1)));
        let (y0, y1) = range(all().map(|p| p.free).chain(self.marks.iter().map(|m| m.2)));
        let (xl, yl) = self
            .curves
            .first()
            .map(|c| (c.1.along.label(), c.1.free.label()))
            .unwrap_or_default();
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc(xl)
            .y_desc(yl)
            .draw()
            .map_err(plot_err)?;
        for (i, (label, c)) in self.curves.iter().enumerate() {
            let col = Palette99::pick(i).to_rgba();
            chart
                .draw_series(LineSeries::new(
                    c.points.iter().map(|p| (p.along, p.free)),
                    col.stroke_width(2),
                ))
                .map_err(plot_err)?
                .label(label.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], col));
        }
        for (label, x, y) in &self.marks {
            chart
                .draw_series(std::iter::once(Circle::new((*x, *y), 5, BLACK.filled())))
                .map_err(plot_err)?;
            chart
                .draw_series(std::iter::once(Text::new(
                    label.clone(),
                    (*x, *y),
                    ("sans-serif", 12).into_font(),
                )))
                .map_err(plot_err)?;
        }
        if !self.curves.is_empty() {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(plot_err)?;
        }
        Ok(())
    }
}
