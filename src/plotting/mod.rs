//! Figures (feature `plot`): SVG and PNG through plotters, with a font shipped in the crate so a
//! fresh machine needs no system font libraries.
//!
//! A figure implements [`Figure`]; [`save`] picks the backend from the file extension (`.svg` or
//! `.png`) and writes atomically (to a temporary file, then renamed).

pub mod atlas;
pub mod branch;
pub mod campaign;
pub mod diagnosis;

use crate::error::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Registers the shipped font (DejaVu Sans) as "sans-serif"; called by [`save`], idempotent.
pub fn init_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        for style in [
            FontStyle::Normal,
            FontStyle::Bold,
            FontStyle::Italic,
            FontStyle::Oblique,
        ] {
            // the font is valid (shipped with the crate); failure would be a build defect
            let _ = plotters::style::register_font("sans-serif", style, FONT);
        }
    });
}

/// Something that can draw itself on any plotters backend.
pub trait Figure {
    /// Pixel size (width, height).
    fn size(&self) -> (u32, u32) {
        (900, 600)
    }
    /// Draws onto the root area.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>;
}

/// Converts any plotters error into a crate error.
pub fn plot_err<E: std::fmt::Display>(e: E) -> Error {
    Error::Io(format!("plotting failed: {e}"))
}

/// Saves a figure as SVG or PNG (by the extension of `path`), atomically.
pub fn save(fig: &impl Figure, path: impl AsRef<Path>) -> Result<()> {
    init_fonts();
    let path = path.as_ref();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    let size = fig.size();
    match ext.as_str() {
        "svg" => {
            let mut s = String::new();
            {
                let root = SVGBackend::with_string(&mut s, size).into_drawing_area();
                root.fill(&WHITE).map_err(plot_err)?;
                fig.draw(&root)?;
                root.present().map_err(plot_err)?;
            }
            crate::io::write_atomic(path, s.as_bytes())
        }
        "png" => {
            let dir = path
                .parent()
                .filter(|p| !p.as_os_str().is_empty())
                .unwrap_or(Path::new("."));
            std::fs::create_dir_all(dir).map_err(|e| Error::file("create", dir, e))?;
            let tmp = dir.join(format!(".tmp-{}-{}.png", std::process::id(), unique()));
            {
                let root = BitMapBackend::new(&tmp, size).into_drawing_area();
                root.fill(&WHITE).map_err(plot_err)?;
                fig.draw(&root)?;
                root.present().map_err(plot_err)?;
            }
            std::fs::rename(&tmp, path).map_err(|e| {
                let _ = std::fs::remove_file(&tmp);
                Error::file("move into place", path, e)
            })
        }
        _ => Err(Error::InvalidInput(format!(
            "figure path {} must end in .svg or .png",
            path.display()
        ))),
    }
}

fn unique() -> u64 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static N: AtomicU64 = AtomicU64::new(0);
    N.fetch_add(1, Ordering::Relaxed)
}

/// A simple line/scatter figure of several series, used by the CLI and as the building block of
/// the paper's figures.
#[derive(Debug, Clone, Default)]
pub struct LinePlot {
    /// Title.
    pub title: String,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// The series.
    pub series: Vec<Series>,
}

/// One series of a [`LinePlot`].
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Points.
    pub points: Vec<(f64, f64)>,
    /// Draw markers instead of a line.
    pub markers: bool,
    /// Palette index.
    pub color: usize,
}

fn finite_range(v: impl Iterator<Item = f64>, log: bool) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for x in v {
        if x.is_finite() && (!log || x > 0.0) {
            lo = lo.min(x);
            hi = hi.max(x);
        }
    }
    if lo > hi {
        return None;
    }
    if lo == hi {
        let d = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
        return Some((lo - d, hi + d));
    }
    if log {
        Some((lo / 1.2, hi * 1.2))
    } else {
        let d = 0.05 * (hi - lo);
        Some((lo - d, hi + d))
    }
}

impl Figure for LinePlot {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let pts = || self.series.iter().flat_map(|s| s.points.iter().copied());
        let (x0, x1) = finite_range(pts().map(|p| p.0), self.log_x).unwrap_or((0.0, 1.0));
        let (y0, y1) = finite_range(pts().map(|p| p.1), self.log_y).unwrap_or((0.0, 1.0));
        let mut b = ChartBuilder::on(root);
        b.caption(&self.title, ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70);
        macro_rules! body {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(self.x_label.as_str())
                    .y_desc(self.y_label.as_str())
                    .label_style(("sans-serif", 14))
                    .draw()
                    .map_err(plot_err)?;
                for s in &self.series {
                    let c = Palette99::pick(s.color).to_rgba();
                    let data = s
                        .points
                        .iter()
                        .copied()
                        .filter(|p| p.0.is_finite() && p.1.is_finite());
                    let anno = if s.markers {
                        chart
                            .draw_series(data.map(|p| Circle::new(p, 3, c.filled())))
                            .map_err(plot_err)?
                    } else {
                        chart
                            .draw_series(LineSeries::new(data, c.stroke_width(2)))
                            .map_err(plot_err)?
                    };
                    if !s.label.is_empty() {
                        anno.label(s.label.as_str()).legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(3))
                        });
                    }
                }
                if self.series.iter().any(|s| !s.label.is_empty()) {
                    chart
                        .configure_series_labels()
                        .background_style(WHITE.mix(0.8))
                        .border_style(BLACK)
                        .label_font(("sans-serif", 14))
                        .draw()
                        .map_err(plot_err)?;
                }
            }};
        }
        match (self.log_x, self.log_y) {
            (false, false) => body!(b.build_cartesian_2d(x0..x1, y0..y1).map_err(plot_err)?),
            (true, false) => body!(b
                .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
                .map_err(plot_err)?),
            (false, true) => body!(b
                .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                .map_err(plot_err)?),
            (true, true) => body!(b
                .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
                .map_err(plot_err)?),
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn saves_svg_and_png() {
        let dir = std::env::temp_dir().join(format!("gearbif-plot-{}", std::process::id()));
        let fig = LinePlot {
            title: "test".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            log_x: true,
            series: vec![Series {
                label: "sin".into(),
                points: (1..100)
                    .map(|i| (i as f64, (i as f64 * 0.1).sin()))
                    .collect(),
                markers: false,
                color: 0,
            }],
            ..Default::default()
        };
        save(&fig, dir.join("a.svg")).unwrap();
        save(&fig, dir.join("a.png")).unwrap();
        assert!(std::fs::read_to_string(dir.join("a.svg"))
            .unwrap()
            .contains("<svg"));
        assert!(std::fs::metadata(dir.join("a.png")).unwrap().len() > 1000);
        assert!(save(&fig, dir.join("a.jpg")).is_err());
        std::fs::remove_dir_all(dir).ok();
    }
}
