//! The basin map: the attractor reached from every cell centre of a (β, ω) grid on the section
//! t ≡ 0 (mod T), computed in parallel (feature `parallel`) with progress per row.

use super::attractor::AttractorSet;
use super::recognise::{recognise, Outcome};
use super::BasinOptions;
use crate::error::{Error, Result};
use crate::model::DrivenOscillator;
use crate::progress::{Event, Observer};
use serde::{Deserialize, Serialize};

/// A rectangle of initial states on the section: β in rad, ω in rad/s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Region {
    /// β range [lo, hi), rad.
    pub beta: (f64, f64),
    /// ω range [lo, hi), rad/s.
    pub omega: (f64, f64),
}

impl Region {
    /// Checks that both ranges are finite and not empty.
    pub fn validate(&self) -> Result<()> {
        for (name, (lo, hi)) in [("beta range", self.beta), ("omega range", self.omega)] {
            if !(lo.is_finite() && hi.is_finite() && hi > lo) {
                return Err(Error::option(
                    name,
                    format!("needs finite lo < hi, got {lo}:{hi}"),
                ));
            }
        }
        Ok(())
    }

    /// The point at fractions (u, v) ∈ [0, 1]² of the ranges.
    pub fn at(&self, u: f64, v: f64) -> [f64; 2] {
        [
            self.beta.0 + u * (self.beta.1 - self.beta.0),
            self.omega.0 + v * (self.omega.1 - self.omega.0),
        ]
    }
}

/// A basin map: `labels[row · n_beta + col]` is the attractor reached from the centre of cell
/// (col, row) (β increasing with col, ω with row), `None` where the integration failed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BasinMap {
    /// The rectangle.
    pub region: Region,
    /// Cells along β.
    pub n_beta: usize,
    /// Cells along ω.
    pub n_omega: usize,
    /// Attractor index per cell, row-major.
    pub labels: Vec<Option<usize>>,
    /// Map applications used per cell, row-major.
    pub steps: Vec<usize>,
}

impl BasinMap {
    /// The centre of cell (col, row).
    pub fn centre(&self, col: usize, row: usize) -> [f64; 2] {
        self.region.at(
            (col as f64 + 0.5) / self.n_beta as f64,
            (row as f64 + 0.5) / self.n_omega as f64,
        )
    }

    /// Renumbers the labels with `new_of` (from [`AttractorSet::finish`]).
    pub fn relabel(&mut self, new_of: &[usize]) {
        for l in self.labels.iter_mut().flatten() {
            *l = new_of[*l];
        }
    }

    /// Fraction of the cells on each of `n` attractors (the grid's estimate of the basin fractions
    /// of the region).
    pub fn cell_fractions(&self, n: usize) -> Vec<f64> {
        let mut c = vec![0usize; n];
        for l in self.labels.iter().flatten() {
            if *l < n {
                c[*l] += 1;
            }
        }
        c.iter()
            .map(|&k| k as f64 / self.labels.len() as f64)
            .collect()
    }
}

/// The basin map of `sys` on an `n_beta` × `n_omega` grid of `region`, the attractors found or
/// added to `set`. Reports [`Event::Started`], then [`Event::SweepPoint`] per cell and [`Event::RowDone`] per row (rows in parallel);
/// ends with [`Error::Stopped`] once the observer asks.
pub fn basin_map<S: DrivenOscillator + ?Sized>(
    sys: &S,
    set: &AttractorSet,
    region: Region,
    n_beta: usize,
    n_omega: usize,
    opts: &BasinOptions,
    observer: &dyn Observer,
) -> Result<BasinMap> {
    opts.validate()?;
    region.validate()?;
    if n_beta == 0 || n_omega == 0 {
        return Err(Error::shape("basin grid cells", ">= 1 per axis", 0));
    }
    let mut map = BasinMap {
        region,
        n_beta,
        n_omega,
        labels: Vec::new(),
        steps: Vec::new(),
    };
    observer.observe(&Event::Started {
        total: Some(n_omega * n_beta),
        done: 0,
    });
    let row = |r: usize| -> Result<Vec<Outcome>> {
        if observer.stopped() {
            return Err(Error::Stopped { what: "basin map" });
        }
        let out = (0..n_beta)
            .map(|c| {
                let o = recognise(sys, set, map.centre(c, r), opts);
                observer.observe(&Event::SweepPoint { row: r, col: c });
                o
            })
            .collect();
        observer.observe(&Event::RowDone { row: r, path: None });
        Ok(out)
    };
    let rows: Vec<Result<Vec<Outcome>>> = run_rows(n_omega, row);
    for r in rows {
        for o in r? {
            map.labels.push(o.index());
            map.steps.push(match o {
                Outcome::Attractor { steps, .. } => steps,
                Outcome::Failed => 0,
            });
        }
    }
    Ok(map)
}

/// `work(i)` for i in 0..n, in parallel with the feature `parallel`.
pub(crate) fn run_rows<T: Send>(n: usize, work: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        (0..n).into_par_iter().map(work).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        (0..n).map(work).collect()
    }
}
