//! Colour scales and the colour bar that every colour-coded figure of the crate draws beside its
//! data: the bar shows the scale from its lowest to its highest value, labelled with the
//! quantity and its unit.

use super::plot_err;
use crate::error::Result;
use plotters::coord::Shift;
use plotters::prelude::*;

/// A blue–white–red scale of a value in [0, 1]: valleys blue, hills red as in the paper's
/// energy landscapes.
pub fn diverging(v: f64) -> RGBColor {
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

/// A sequential scale of a value in [0, 1] (dark blue → yellow → red), for RMS_δ.
pub fn sequential(v: f64) -> RGBColor {
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

/// A colour scale: the value range it spans, the colour of a value mapped to [0, 1], and the
/// bar's label (the quantity and its unit).
pub struct ColourScale<'a> {
    /// Lowest and highest value of the scale (values beyond are drawn in the end colours).
    pub range: (f64, f64),
    /// Colour of (value − lo) / (hi − lo).
    pub colour: fn(f64) -> RGBColor,
    /// Label of the bar: the quantity and its unit.
    pub label: &'a str,
}

impl ColourScale<'_> {
    /// The colour of `v`.
    pub fn of(&self, v: f64) -> RGBColor {
        let (lo, hi) = self.range;
        (self.colour)((v - lo) / (hi - lo))
    }

    /// Draws the bar into `area` (a narrow strip beside the figure's chart), its axis on the
    /// left labelled with [`ColourScale::label`]; `margins` (top, bottom) align it with the chart.
    pub fn draw_bar<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        (top, bottom): (u32, u32),
    ) -> Result<()> {
        let (lo, hi) = self.range;
        let mut c = ChartBuilder::on(area)
            .margin_top(top)
            .margin_bottom(bottom)
            .margin_right(30)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..1.0, lo..hi)
            .map_err(plot_err)?;
        c.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_desc(self.label)
            .axis_desc_style(("sans-serif", 14))
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(plot_err)?;
        let n = 100;
        c.draw_series((0..n).map(|i| {
            let a = lo + (hi - lo) * i as f64 / n as f64;
            let b = lo + (hi - lo) * (i + 1) as f64 / n as f64;
            Rectangle::new([(0.0, a), (1.0, b)], self.of(0.5 * (a + b)).filled())
        }))
        .map_err(plot_err)?;
        Ok(())
    }
}
