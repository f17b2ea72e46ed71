//! The campaign figure: detection rate against effect size, one panel per swept effect (with the
//! 90 % goal), and the confusion matrix of verdicts.

use super::colour::ColourScale;
use super::{plot_err, Figure};
use crate::campaign::metrics::Summary;
use crate::error::Result;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Power panels and the confusion matrix of a campaign.
pub struct CampaignFigure<'a> {
    /// The campaign's metrics.
    pub summary: &'a Summary,
}

const COLS: usize = 3;

impl Figure for CampaignFigure<'_> {
    fn size(&self) -> (u32, u32) {
        let rows = self.summary.power.len().div_ceil(COLS).max(1) as u32;
        (1700, (280 * rows).max(620))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (w, _) = root.dim_in_pixel();
        let (left, right) = root.split_horizontally(w * 64 / 100);
        let n = self.summary.power.len();
        let rows = n.div_ceil(COLS).max(1);
        let panels = left.split_evenly((rows, COLS));
        for (p, area) in self.summary.power.iter().zip(panels.iter()) {
            let xs: Vec<f64> = p.points.iter().map(|q| q.size).collect();
            let xmax = xs.iter().copied().fold(0.0, f64::max) * 1.1;
            let unit = if p.unit.is_empty() { "1" } else { &p.unit };
            let mut ch = ChartBuilder::on(area)
                .caption(format!("{} → {}", p.effect, p.expected), ("sans-serif", 15))
                .margin(8)
                .x_label_area_size(34)
                .y_label_area_size(44)
                .build_cartesian_2d(0.0..xmax.max(1e-12), 0.0..1.05)
                .map_err(plot_err)?;
            ch.configure_mesh()
                .x_desc(format!("size [{unit}]"))
                .y_desc("named right")
                .x_labels(5)
                .y_labels(6)
                .label_style(("sans-serif", 12))
                .draw()
                .map_err(plot_err)?;
            ch.draw_series(LineSeries::new(
                [(0.0, 0.9), (xmax, 0.9)],
                ShapeStyle::from(&RGBColor(150, 150, 150)).stroke_width(1),
            ))
            .map_err(plot_err)?;
            let pts: Vec<(f64, f64)> = p
                .points
                .iter()
                .filter_map(|q| q.named_right.rate.map(|r| (q.size, r)))
                .collect();
            ch.draw_series(LineSeries::new(pts.iter().copied(), BLUE.stroke_width(2)))
                .map_err(plot_err)?;
            for q in p.points.iter().filter(|q| q.named_right.n > 0) {
                ch.draw_series(LineSeries::new(
                    [(q.size, q.named_right.lo95), (q.size, q.named_right.hi95)],
                    BLUE.stroke_width(1),
                ))
                .map_err(plot_err)?;
            }
            ch.draw_series(
                pts.iter()
                    .map(|&(x, y)| Circle::new((x, y), 4, BLUE.filled())),
            )
            .map_err(plot_err)?;
        }
        draw_confusion(self.summary, &right)
    }
}

/// Width of the confusion matrix's colour bar, px.
const BAR_W: u32 = 120;

/// The shade of a cell of the confusion matrix: white (none of its row) to blue (all of it).
fn share_colour(frac: f64) -> RGBColor {
    let shade = (255.0 * (1.0 - 0.85 * frac.clamp(0.0, 1.0))) as u8;
    RGBColor(shade, shade, 255)
}

/// The colour scale of the confusion matrix.
const SHARE: ColourScale<'static> = ColourScale {
    range: (0.0, 1.0),
    colour: share_colour,
    label: "fraction of the truth's row",
};

fn draw_confusion<DB: DrawingBackend>(s: &Summary, area: &DrawingArea<DB, Shift>) -> Result<()> {
    let c = &s.confusion;
    let (nr, nc) = (c.rows.len().max(1), c.cols.len().max(1));
    let area = area.margin(10, 10, 10, 10);
    let (w, h) = area.dim_in_pixel();
    let (area, bar) = area.split_horizontally(w.saturating_sub(BAR_W));
    let w = w.saturating_sub(BAR_W);
    let label_w = 190i32;
    let label_h = 150i32;
    let title_h = 30i32;
    let cw = ((w as i32 - label_w) / nc as i32).clamp(8, 70);
    let chh = ((h as i32 - label_h - title_h) / nr as i32).clamp(8, 40);
    area.draw(&Text::new(
        "confusion matrix (rows: truth, columns: verdict)",
        (0, 5),
        ("sans-serif", 15).into_font(),
    ))
    .map_err(plot_err)?;
    for (i, row) in c.rows.iter().enumerate() {
        let total: usize = c.counts[i].iter().sum::<usize>().max(1);
        let y0 = title_h + label_h + i as i32 * chh;
        area.draw(&Text::new(
            shorten(row),
            (4, y0 + chh / 2 - 6),
            ("sans-serif", 12).into_font(),
        ))
        .map_err(plot_err)?;
        for (j, &k) in c.counts[i].iter().enumerate() {
            let x0 = label_w + j as i32 * cw;
            let frac = k as f64 / total as f64;
            area.draw(&Rectangle::new(
                [(x0, y0), (x0 + cw - 1, y0 + chh - 1)],
                SHARE.of(frac).filled(),
            ))
            .map_err(plot_err)?;
            if k > 0 {
                let col = if frac > 0.6 { WHITE } else { BLACK };
                area.draw(&Text::new(
                    k.to_string(),
                    (x0 + cw / 2 - 6, y0 + chh / 2 - 6),
                    ("sans-serif", 12).into_font().color(&col),
                ))
                .map_err(plot_err)?;
            }
        }
    }
    let bottom = title_h + label_h + nr as i32 * chh;
    // the bar beside the matrix, as tall as its rows
    SHARE.draw_bar(
        &bar,
        (
            (title_h + label_h) as u32,
            (h as i32 - bottom).max(0) as u32,
        ),
    )?;
    let note_y = bottom + 24;
    for (k, line) in [
        "cells: counts; colour: fraction of the row (bar)",
        "left panels: fraction named right per size, bars: 95 % interval,",
        "grey line: the 90 % goal",
    ]
    .iter()
    .enumerate()
    {
        area.draw(&Text::new(
            *line,
            (4, note_y + 18 * k as i32),
            ("sans-serif", 12).into_font(),
        ))
        .map_err(plot_err)?;
    }
    for (j, col) in c.cols.iter().enumerate() {
        let x = label_w + j as i32 * cw + cw / 2 - 6;
        let style = ("sans-serif", 12)
            .into_font()
            .transform(FontTransform::Rotate270);
        area.draw(&Text::new(shorten(col), (x, title_h + label_h - 6), style))
            .map_err(plot_err)?;
    }
    Ok(())
}

fn shorten(s: &str) -> String {
    if s.chars().count() > 26 {
        let t: String = s.chars().take(25).collect();
        format!("{t}…")
    } else {
        s.to_string()
    }
}
