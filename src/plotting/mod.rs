//! Figures (feature `plot`): SVG and PNG through plotters, with a font shipped in the crate so a
//! fresh machine needs no system font libraries.
//!
//! A figure implements [`Figure`]; [`save`] picks the backend from the file extension (`.svg` or
//! `.png`) and writes atomically (to a temporary file, then renamed).

pub mod atlas;
pub mod basins;
pub mod branch;
pub mod campaign;
pub mod classes;
pub mod colour;
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
        "svg" => crate::io::write_atomic(path, to_svg(fig)?.as_bytes()),
        "png" => {
            let dir = path
                .parent()
                .filter(|p| !p.as_os_str().is_empty())
                .unwrap_or(Path::new("."));
            std::fs::create_dir_all(dir).map_err(|e| Error::file("create", dir, e))?;
            let tmp = dir.join(format!(".tmp-{}-{}.png", std::process::id(), unique()));
            let written = draw_png(fig, &tmp, size).and_then(|()| {
                crate::io::full_disk::after_external_write(&tmp)
                    .map_err(|e| Error::file("write", &tmp, e))
            });
            let moved = written.and_then(|()| {
                std::fs::rename(&tmp, path).map_err(|e| Error::file("move into place", path, e))
            });
            if moved.is_err() {
                let _ = std::fs::remove_file(&tmp);
            }
            moved
        }
        _ => Err(Error::option(
            format!("figure path {}", path.display()),
            "must end in .svg or .png",
        )),
    }
}

/// The SVG text of a figure.
pub fn to_svg(fig: &impl Figure) -> Result<String> {
    init_fonts();
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, fig.size()).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        fig.draw(&root)?;
        root.present().map_err(plot_err)?;
    }
    Ok(s)
}

/// Draws `fig` into the PNG file `path` (the backend writes it on `present`).
fn draw_png(fig: &impl Figure, path: &Path, size: (u32, u32)) -> Result<()> {
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(plot_err)?;
    fig.draw(&root)?;
    root.present().map_err(plot_err)
}

fn unique() -> u64 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static N: AtomicU64 = AtomicU64::new(0);
    N.fetch_add(1, Ordering::Relaxed)
}

/// Shape of the markers of a marker [`Series`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarkerShape {
    /// Filled circle (radius 3 px).
    FilledCircle,
    /// Open square (7 px wide, drawn on top): stays visible around a filled circle at the same point.
    OpenSquare,
    /// Filled triangle.
    Triangle,
    /// Cross.
    Cross,
}

impl MarkerShape {
    /// The default shape of the `k`-th marker series of a plot.
    pub fn nth(k: usize) -> Self {
        [
            Self::FilledCircle,
            Self::OpenSquare,
            Self::Triangle,
            Self::Cross,
        ][k % 4]
    }
}

/// A simple line/scatter figure of several series, used by the CLI and as the building block of
/// the paper's figures. The legend is put into the corner of the plot with the fewest data points;
/// if every corner holds data, the y range is extended so that the legend sits above the data.
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
    /// Logarithmic y axis (points with y ≤ 0 are left out).
    pub log_y: bool,
    /// The series.
    pub series: Vec<Series>,
    /// Marker shape of the k-th marker series (by order among the series with `markers`);
    /// [`MarkerShape::nth`] where missing.
    pub marker_shapes: Vec<MarkerShape>,
    /// Shaded bands, drawn below the series (a confidence band about a curve).
    pub bands: Vec<Band>,
}

/// A shaded band of a [`LinePlot`] between two curves on the same abscissae.
#[derive(Debug, Clone)]
pub struct Band {
    /// Legend label.
    pub label: String,
    /// (x, lower, upper).
    pub points: Vec<(f64, f64, f64)>,
    /// Palette index.
    pub color: usize,
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

/// The frame of a line figure: its caption, margin and axis label areas ([`LinePlot`],
/// [`branch::BoundaryPlot`]).
pub(crate) fn line_frame<'a, 'b, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
) -> ChartBuilder<'a, 'b, DB> {
    let mut b = ChartBuilder::on(root);
    b.caption(title, ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(50)
        .y_label_area_size(80);
    b
}

/// The range of the finite values (positive ones for a log axis) with a margin: 5 % of the span
/// (linear) or a factor 1.2 (log); `None` if there are none.
pub(crate) fn finite_range(v: impl Iterator<Item = f64>, log: bool) -> Option<(f64, f64)> {
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

/// Where a legend of `rows` entries, the longest `chars` characters, fits in a plot area of
/// `area` pixels without covering any of the `frac` points (positions as fractions of the axes,
/// x to the right, y upwards): the corner with the fewest points, and the fraction of the height
/// to add above the data when every corner holds some (0 otherwise).
pub fn legend_corner(
    frac: &[(f64, f64)],
    rows: usize,
    chars: usize,
    area: (u32, u32),
) -> (SeriesLabelPosition, f64) {
    let w = ((chars as f64 * 8.0 + 50.0) / area.0 as f64).min(0.9);
    let h = ((rows as f64 * 22.0 + 16.0) / area.1 as f64).min(0.9);
    let count = |x0: f64, y0: f64| {
        frac.iter()
            .filter(|p| p.0 >= x0 && p.0 <= x0 + w && p.1 >= y0 && p.1 <= y0 + h)
            .count()
    };
    let corners = [
        (SeriesLabelPosition::UpperRight, 1.0 - w, 1.0 - h),
        (SeriesLabelPosition::UpperLeft, 0.0, 1.0 - h),
        (SeriesLabelPosition::LowerRight, 1.0 - w, 0.0),
        (SeriesLabelPosition::LowerLeft, 0.0, 0.0),
    ];
    let best = corners
        .into_iter()
        .map(|(pos, x0, y0)| (count(x0, y0), pos))
        .min_by_key(|c| c.0);
    match best {
        Some((0, pos)) => (pos, 0.0),
        _ => (SeriesLabelPosition::UpperRight, h / (1.0 - h)),
    }
}

/// Places text labels of pixel sizes `sizes` (w, h) next to their anchors (pixels) so that no
/// label covers another label or any anchor's marker (a 12 px box), inside `bounds` (x0, y0, x1, y1):
/// a greedy pass over candidate offsets around each anchor, nearest first. Returns the top-left
/// corner of each label; a label that fits nowhere free takes the candidate with the least overlap.
pub fn place_labels(
    anchors: &[(i32, i32)],
    sizes: &[(i32, i32)],
    bounds: (i32, i32, i32, i32),
) -> Vec<(i32, i32)> {
    type Rect = (i32, i32, i32, i32);
    let overlap = |a: &Rect, b: &Rect| {
        let w = (a.2.min(b.2) - a.0.max(b.0)).max(0);
        let h = (a.3.min(b.3) - a.1.max(b.1)).max(0);
        w * h
    };
    let markers: Vec<Rect> = anchors
        .iter()
        .map(|&(x, y)| (x - 6, y - 6, x + 6, y + 6))
        .collect();
    let mut placed: Vec<Rect> = Vec::with_capacity(anchors.len());
    for (&(x, y), &(w, h)) in anchors.iter().zip(sizes) {
        let mut best: Option<(i32, Rect)> = None;
        for r in [1, 2, 3, 5] {
            let (dx, dy) = (8 * r, 7 * r);
            for (ox, oy) in [
                (dx, -dy - h / 2),
                (dx, dy - h / 2),
                (-dx - w, -dy - h / 2),
                (-dx - w, dy - h / 2),
                (-w / 2, -dy - h),
                (-w / 2, dy),
                (dx, -h / 2),
                (-dx - w, -h / 2),
            ] {
                let rect = (x + ox, y + oy, x + ox + w, y + oy + h);
                if rect.0 < bounds.0 || rect.1 < bounds.1 || rect.2 > bounds.2 || rect.3 > bounds.3
                {
                    continue;
                }
                let cost: i32 = placed
                    .iter()
                    .chain(&markers)
                    .map(|o| overlap(&rect, o))
                    .sum();
                if best.is_none_or(|b| cost < b.0) {
                    best = Some((cost, rect));
                }
                if cost == 0 {
                    break;
                }
            }
            if best.is_some_and(|b| b.0 == 0) {
                break;
            }
        }
        let rect = best.map(|b| b.1).unwrap_or((x + 8, y - h, x + 8 + w, y));
        placed.push(rect);
    }
    placed.iter().map(|r| (r.0, r.1)).collect()
}

/// Draws the points of one marker series (and its legend entry if `label` is not empty).
fn draw_markers<'a, DB: DrawingBackend + 'a, CT: CoordTranslate<From = (f64, f64)>>(
    chart: &mut ChartContext<'a, DB, CT>,
    shape: MarkerShape,
    points: Vec<(f64, f64)>,
    c: RGBAColor,
    label: &str,
) -> Result<()> {
    macro_rules! series {
        ($elems:expr, $glyph:expr) => {{
            let anno = chart.draw_series($elems).map_err(plot_err)?;
            if !label.is_empty() {
                anno.label(label).legend($glyph);
            }
        }};
    }
    let it = points.into_iter();
    match shape {
        MarkerShape::FilledCircle => {
            series!(it.map(|p| Circle::new(p, 3, c.filled())), move |(x, y)| {
                Circle::new((x + 9, y), 3, c.filled())
            })
        }
        MarkerShape::OpenSquare => series!(
            it.map(|p| EmptyElement::at(p) + Rectangle::new([(-4, -4), (4, 4)], c.stroke_width(2))),
            move |(x, y)| Rectangle::new([(x + 5, y - 4), (x + 13, y + 4)], c.stroke_width(2))
        ),
        MarkerShape::Triangle => series!(
            it.map(|p| TriangleMarker::new(p, 5, c.filled())),
            move |(x, y)| TriangleMarker::new((x + 9, y), 5, c.filled())
        ),
        MarkerShape::Cross => {
            series!(
                it.map(|p| Cross::new(p, 4, c.stroke_width(2))),
                move |(x, y)| Cross::new((x + 9, y), 4, c.stroke_width(2))
            )
        }
    }
    Ok(())
}

/// Draws a legend at `pos` if any series is labelled.
fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    pos: SeriesLabelPosition,
) -> Result<()> {
    chart
        .configure_series_labels()
        .position(pos)
        .margin(8)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(plot_err)
}

/// Position of a point as fractions of the axes ranges (log or linear).
fn axis_fraction(v: f64, lo: f64, hi: f64, log: bool) -> f64 {
    if log {
        (v.ln() - lo.ln()) / (hi.ln() - lo.ln())
    } else {
        (v - lo) / (hi - lo)
    }
}

impl LinePlot {
    fn visible(&self, p: &(f64, f64)) -> bool {
        p.0.is_finite()
            && p.1.is_finite()
            && (!self.log_x || p.0 > 0.0)
            && (!self.log_y || p.1 > 0.0)
    }
}

impl Figure for LinePlot {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let pts = || {
            self.series
                .iter()
                .flat_map(|s| s.points.iter().copied())
                .chain(
                    self.bands
                        .iter()
                        .flat_map(|b| b.points.iter().flat_map(|&(x, l, u)| [(x, l), (x, u)])),
                )
                .filter(|p| self.visible(p))
        };
        let (x0, x1) = finite_range(pts().map(|p| p.0), self.log_x).unwrap_or((0.0, 1.0));
        let (y0, mut y1) = finite_range(pts().map(|p| p.1), self.log_y).unwrap_or((0.0, 1.0));
        // the legend: the emptiest corner, or room made above the data
        let labelled: Vec<&str> = self
            .series
            .iter()
            .map(|s| s.label.as_str())
            .chain(self.bands.iter().map(|b| b.label.as_str()))
            .filter(|l| !l.is_empty())
            .collect();
        let chars = labelled
            .iter()
            .map(|s| s.chars().count())
            .max()
            .unwrap_or(0);
        let (w, h) = root.dim_in_pixel();
        let frac: Vec<(f64, f64)> = pts()
            .map(|p| {
                (
                    axis_fraction(p.0, x0, x1, self.log_x),
                    axis_fraction(p.1, y0, y1, self.log_y),
                )
            })
            .collect();
        let (pos, headroom) = legend_corner(
            &frac,
            labelled.len(),
            chars,
            (w.saturating_sub(100).max(1), h.saturating_sub(110).max(1)),
        );
        if !labelled.is_empty() && headroom > 0.0 {
            y1 = if self.log_y {
                (y1.ln() + headroom * (y1.ln() - y0.ln())).exp()
            } else {
                y1 + headroom * (y1 - y0)
            };
        }
        let mut b = line_frame(root, &self.title);
        macro_rules! body {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(self.x_label.as_str())
                    .y_desc(self.y_label.as_str())
                    .label_style(("sans-serif", 14))
                    .axis_desc_style(("sans-serif", 15))
                    .draw()
                    .map_err(plot_err)?;
                for band in &self.bands {
                    let c = Palette99::pick(band.color).to_rgba();
                    let mut ring: Vec<(f64, f64)> =
                        band.points.iter().map(|&(x, _, u)| (x, u)).collect();
                    ring.extend(band.points.iter().rev().map(|&(x, l, _)| (x, l)));
                    let fill = c.mix(0.25).filled();
                    let anno = chart
                        .draw_series(std::iter::once(Polygon::new(ring, fill)))
                        .map_err(plot_err)?;
                    if !band.label.is_empty() {
                        anno.label(band.label.as_str()).legend(move |(x, y)| {
                            Rectangle::new([(x, y - 5), (x + 18, y + 5)], c.mix(0.25).filled())
                        });
                    }
                }
                let mut k = 0;
                for s in &self.series {
                    let c = Palette99::pick(s.color).to_rgba();
                    let data: Vec<(f64, f64)> = s
                        .points
                        .iter()
                        .copied()
                        .filter(|p| self.visible(p))
                        .collect();
                    if s.markers {
                        let shape = self
                            .marker_shapes
                            .get(k)
                            .copied()
                            .unwrap_or_else(|| MarkerShape::nth(k));
                        k += 1;
                        draw_markers(&mut chart, shape, data, c, &s.label)?;
                    } else {
                        let anno = chart
                            .draw_series(LineSeries::new(data, c.stroke_width(2)))
                            .map_err(plot_err)?;
                        if !s.label.is_empty() {
                            anno.label(s.label.as_str()).legend(move |(x, y)| {
                                PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(3))
                            });
                        }
                    }
                }
                if !labelled.is_empty() {
                    draw_legend(&mut chart, pos)?;
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
    fn labels_of_a_dense_cluster_do_not_overlap() {
        // twelve markers within 30 px (the period-doubling cascade of a diagram), labels "1".."12"
        let anchors: Vec<(i32, i32)> = (0..12).map(|k| (300 + 3 * k, 200 + 2 * (k % 4))).collect();
        let sizes: Vec<(i32, i32)> = (1..=12)
            .map(|k: i32| (8 * k.to_string().len() as i32, 12))
            .collect();
        let at = place_labels(&anchors, &sizes, (0, 0, 800, 600));
        let rects: Vec<_> = at
            .iter()
            .zip(&sizes)
            .map(|(p, s)| (p.0, p.1, p.0 + s.0, p.1 + s.1))
            .collect();
        for (i, a) in rects.iter().enumerate() {
            assert!(a.0 >= 0 && a.1 >= 0 && a.2 <= 800 && a.3 <= 600);
            for b in &rects[i + 1..] {
                let apart = a.2 <= b.0 || b.2 <= a.0 || a.3 <= b.1 || b.3 <= a.1;
                assert!(apart, "{a:?} overlaps {b:?}");
            }
            for &(x, y) in &anchors {
                let clear = a.2 <= x - 6 || x + 6 <= a.0 || a.3 <= y - 6 || y + 6 <= a.1;
                assert!(clear, "{a:?} covers the marker at ({x}, {y})");
            }
        }
        // and near the plot's edge they stay inside
        let at = place_labels(&[(795, 5)], &[(16, 12)], (0, 0, 800, 600));
        assert!(at[0].0 + 16 <= 800 && at[0].1 >= 0);
    }

    #[test]
    fn legend_goes_to_an_empty_corner_or_above_the_data() {
        // points along the upper edge and in the lower right: the lower left is free
        let mut pts: Vec<(f64, f64)> = (0..=10).map(|i| (i as f64 / 10.0, 0.98)).collect();
        pts.push((0.95, 0.05));
        let (pos, head) = legend_corner(&pts, 2, 10, (800, 500));
        assert!(matches!(pos, SeriesLabelPosition::LowerLeft), "{pos:?}");
        assert_eq!(head, 0.0);
        // every corner taken: room above the data, as large as the legend's share of the height
        pts.push((0.05, 0.05));
        let (pos, head) = legend_corner(&pts, 2, 10, (800, 500));
        assert!(matches!(pos, SeriesLabelPosition::UpperRight), "{pos:?}");
        let h = (2.0 * 22.0 + 16.0) / 500.0;
        assert!((head - h / (1.0 - h)).abs() < 1e-12);
    }

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
