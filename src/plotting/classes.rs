//! The class layer of a map (paper Figs. 7b and 8): a categorical layer over the RMS_δ colours
//! that stays readable at any grid density. Class markers are drawn one per block of cells, the
//! block as small as the glyph allows (one cell where cells are wide and tall enough), and only
//! where every cell of the block has the same class; lines separate neighbouring cells of
//! different classes, so every class region is outlined whatever the density.

use crate::sweep::PointRecord;
use std::ops::Range;

/// Which class the markers of a map show.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Markers {
    /// The paper's flowchart: circle chaos, cross T/2, dash T.
    Paper,
    /// The rigorous class: circle chaos/QP, cross symmetric, dash asymmetric periodic, square
    /// unresolved.
    Rigorous,
    /// No class layer.
    None,
}

/// The glyph of a class.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Glyph {
    /// ○
    Circle,
    /// ×
    Cross,
    /// —
    Dash,
    /// □
    Square,
}

impl Markers {
    /// The glyph of a point's class (None for [`Markers::None`]).
    pub fn glyph(self, p: &PointRecord) -> Option<Glyph> {
        match self {
            Markers::None => None,
            Markers::Paper => Some(match p.paper_class.as_str() {
                "chaos" => Glyph::Circle,
                "T/2" => Glyph::Cross,
                _ => Glyph::Dash,
            }),
            Markers::Rigorous => Some(if p.class == "chaos" || p.class == "QP" {
                Glyph::Circle
            } else if p.symmetric {
                Glyph::Cross
            } else if p.half_periods > 0 {
                Glyph::Dash
            } else {
                Glyph::Square
            }),
        }
    }

    /// What each glyph means.
    pub fn key(self) -> &'static str {
        match self {
            Markers::Paper => "paper classes: ○ chaos, × T/2, — T",
            Markers::Rigorous => {
                "rigorous classes: ○ chaos/QP, × symmetric, — asymmetric periodic, □ unresolved"
            }
            Markers::None => "",
        }
    }
}

/// The pixels a marker needs: its 8 px glyph and a 4 px gap to the next one.
pub const GLYPH_PX: f64 = 12.0;

/// Cells per marker along an axis whose narrowest cell is `cell_px` pixels wide: the fewest
/// cells that give a marker [`GLYPH_PX`].
pub fn cells_per_marker(cell_px: f64) -> usize {
    if cell_px >= GLYPH_PX {
        1
    } else {
        (GLYPH_PX / cell_px.max(1e-3)).ceil() as usize
    }
}

/// The classes of a grid: a glyph per cell (row-major), None where a cell has no point.
#[derive(Debug, Clone)]
pub struct ClassGrid {
    /// Rows and columns.
    pub shape: (usize, usize),
    /// Glyph of cell (row, col) at `row * cols + col`.
    pub cells: Vec<Option<Glyph>>,
}

/// A block of cells of one class, marked once.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Block {
    /// Its rows.
    pub rows: Range<usize>,
    /// Its columns.
    pub cols: Range<usize>,
    /// The class of every cell in it.
    pub glyph: Glyph,
}

/// A side shared by two cells of different classes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Border {
    /// Between cells (row, col − 1) and (row, col): the column edge `col` over row `row`.
    Vertical {
        /// The row.
        row: usize,
        /// The column edge (the left side of cell `col`).
        col: usize,
    },
    /// Between cells (row − 1, col) and (row, col): the row edge `row` under column `col`.
    Horizontal {
        /// The row edge (the lower side of cell `row`).
        row: usize,
        /// The column.
        col: usize,
    },
}

impl ClassGrid {
    /// The glyphs of `points` (rows × cols) by `markers`.
    pub fn new(points: &[PointRecord], shape: (usize, usize), markers: Markers) -> Self {
        let mut cells = vec![None; shape.0 * shape.1];
        for p in points.iter().filter(|p| p.row < shape.0 && p.col < shape.1) {
            cells[p.row * shape.1 + p.col] = markers.glyph(p);
        }
        Self { shape, cells }
    }

    fn at(&self, r: usize, c: usize) -> Option<Glyph> {
        self.cells[r * self.shape.1 + c]
    }

    /// The blocks of `per` = (rows, cols) cells, counted from cell (0, 0), whose cells all have
    /// the same class; mixed blocks and blocks with a missing cell are left out.
    pub fn uniform_blocks(&self, per: (usize, usize)) -> Vec<Block> {
        let (nr, nc) = self.shape;
        let (kr, kc) = (per.0.max(1), per.1.max(1));
        let mut out = Vec::new();
        for r0 in (0..nr).step_by(kr) {
            for c0 in (0..nc).step_by(kc) {
                let (rows, cols) = (r0..(r0 + kr).min(nr), c0..(c0 + kc).min(nc));
                let Some(g) = self.at(r0, c0) else { continue };
                let same = rows
                    .clone()
                    .all(|r| cols.clone().all(|c| self.at(r, c) == Some(g)));
                if same {
                    out.push(Block {
                        rows,
                        cols,
                        glyph: g,
                    });
                }
            }
        }
        out
    }

    /// Every side shared by two cells of different classes.
    pub fn borders(&self) -> Vec<Border> {
        let (nr, nc) = self.shape;
        let mut out = Vec::new();
        for r in 0..nr {
            for c in 0..nc {
                if c > 0 && self.at(r, c - 1) != self.at(r, c) {
                    out.push(Border::Vertical { row: r, col: c });
                }
                if r > 0 && self.at(r - 1, c) != self.at(r, c) {
                    out.push(Border::Horizontal { row: r, col: c });
                }
            }
        }
        out
    }
}

/// The two lines under a map that say what its class layer shows: the glyphs, and how many
/// cells a marker stands for (`per`: rows, columns).
pub fn legend(markers: Markers, per: (usize, usize)) -> [String; 2] {
    let each = if per == (1, 1) {
        "one marker per cell".to_string()
    } else {
        format!(
            "one marker per block of {} × {} cells (columns × rows) where all are of one class",
            per.1, per.0
        )
    };
    [
        markers.key().to_string(),
        format!("{each}; black lines: borders between cells of different classes"),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(rows: &[&str]) -> ClassGrid {
        let glyph = |ch| match ch {
            'o' => Some(Glyph::Circle),
            'x' => Some(Glyph::Cross),
            '-' => Some(Glyph::Dash),
            _ => None,
        };
        ClassGrid {
            shape: (rows.len(), rows[0].len()),
            cells: rows.iter().flat_map(|r| r.chars().map(glyph)).collect(),
        }
    }

    #[test]
    fn a_marker_per_cell_only_where_the_cell_holds_the_glyph() {
        assert_eq!(cells_per_marker(12.0), 1);
        assert_eq!(cells_per_marker(40.0), 1);
        // a 100-column grid on 790 px: 7.9 px cells, two per marker
        assert_eq!(cells_per_marker(7.9), 2);
        // the paper's 4996 columns: 0.16 px cells
        assert_eq!(cells_per_marker(0.16), 75);
        assert!(cells_per_marker(0.0) > 1000);
    }

    #[test]
    fn blocks_are_marked_only_where_all_their_cells_agree() {
        let g = grid(&["xxxxoo", "xxxoo-", "xxx.oo"]);
        let b = g.uniform_blocks((1, 2));
        // row 0: xx xx oo; row 1: xx (xo mixed) o- mixed; row 2: xx (x. missing) oo
        let got: Vec<_> = b.iter().map(|b| (b.rows.start, b.cols.start)).collect();
        assert_eq!(got, [(0, 0), (0, 2), (0, 4), (1, 0), (2, 0), (2, 4)]);
        assert!(b.iter().all(|b| b.cols.len() == 2 && b.rows.len() == 1));
        assert_eq!(b[2].glyph, Glyph::Circle);
        // a block at the grid's end is cut to the grid
        let b = g.uniform_blocks((2, 3));
        let got: Vec<_> = b.iter().map(|b| (b.rows.clone(), b.cols.clone())).collect();
        assert_eq!(got, [(0..2, 0..3), (2..3, 0..3)]);
        assert!(b.iter().all(|b| b.glyph == Glyph::Cross));
    }

    #[test]
    fn borders_separate_exactly_the_cells_of_different_classes() {
        let g = grid(&["xxo", "xoo"]);
        let b = g.borders();
        assert_eq!(
            b,
            [
                Border::Vertical { row: 0, col: 2 },
                Border::Vertical { row: 1, col: 1 },
                Border::Horizontal { row: 1, col: 1 },
            ]
        );
        assert!(grid(&["ooo", "ooo"]).borders().is_empty());
    }
}
