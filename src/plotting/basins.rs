//! The basin map figure: one colour per attractor over the (β, ω) grid of initial states at t = 0,
//! the attractors' section points in black, and a legend naming each attractor by class, period and
//! rotation number (`gearbif basins`, docs/basins.md).

use super::{plot_err, Figure};
use crate::analysis::basins::{Attractor, BasinMap};
use crate::error::Result;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Colours of attractors 0, 1, … (repeating after 10); cells whose integration failed are grey.
const COLOURS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(255, 215, 0),
];

/// The colour of attractor `k`.
pub fn colour(k: usize) -> RGBColor {
    COLOURS[k % COLOURS.len()]
}

/// A basin map with its attractors.
#[derive(Debug, Clone)]
pub struct BasinFigure<'a> {
    /// Title (system and parameters).
    pub title: String,
    /// The map.
    pub map: &'a BasinMap,
    /// The attractors its labels index, with the fraction of the cells on each (legend).
    pub attractors: &'a [Attractor],
}

impl Figure for BasinFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (1100, 700)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (main, side) = root.split_horizontally(760);
        let r = self.map.region;
        let mut chart = ChartBuilder::on(&main)
            .caption(self.title.as_str(), ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(r.beta.0..r.beta.1, r.omega.0..r.omega.1)
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("β at t = 0 [rad]")
            .y_desc("ω at t = 0 [rad/s]")
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(plot_err)?;
        let (nb, nw) = (self.map.n_beta, self.map.n_omega);
        let db = (r.beta.1 - r.beta.0) / nb as f64;
        let dw = (r.omega.1 - r.omega.0) / nw as f64;
        let cells = (0..nw).flat_map(|row| (0..nb).map(move |col| (row, col)));
        chart
            .draw_series(cells.map(|(row, col)| {
                let c = match self.map.labels[row * nb + col] {
                    Some(k) => colour(k),
                    None => RGBColor(160, 160, 160),
                };
                let x0 = r.beta.0 + col as f64 * db;
                let y0 = r.omega.0 + row as f64 * dw;
                Rectangle::new([(x0, y0), (x0 + db, y0 + dw)], c.filled())
            }))
            .map_err(plot_err)?;
        let inside = |p: &[f64; 2]| {
            p[0] >= r.beta.0 && p[0] <= r.beta.1 && p[1] >= r.omega.0 && p[1] <= r.omega.1
        };
        for a in self.attractors {
            let pts = a.points.iter().filter(|p| inside(p));
            chart
                .draw_series(pts.map(|p| Circle::new((p[0], p[1]), 4, BLACK.filled())))
                .map_err(plot_err)?;
        }
        self.legend(&side)
    }
}

impl BasinFigure<'_> {
    /// The legend: a colour square and the attractor's name and cell fraction per line.
    fn legend<DB: DrawingBackend>(&self, side: &DrawingArea<DB, Shift>) -> Result<()> {
        let frac = self.map.cell_fractions(self.attractors.len());
        let style = ("sans-serif", 14).into_font();
        side.draw(&Text::new(
            "attractors (● section points)",
            (10, 40),
            style.clone(),
        ))
        .map_err(plot_err)?;
        for (k, a) in self.attractors.iter().enumerate() {
            let y = 70 + 24 * k as i32;
            side.draw(&Rectangle::new([(10, y), (26, y + 16)], colour(k).filled()))
                .map_err(plot_err)?;
            let text = format!("{}: {:.1} % of cells", a.legend(k), 100.0 * frac[k]);
            side.draw(&Text::new(text, (34, y), style.clone()))
                .map_err(plot_err)?;
        }
        Ok(())
    }
}
