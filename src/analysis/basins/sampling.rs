//! Basin fractions from uniform random samples of a region, with their binomial standard error.
//!
//! With n independent uniform samples of which k end on attractor A, the fraction of the region in
//! the basin of A is estimated by p̂ = k/n with standard error σ = √(p̂(1 − p̂)/n) (binomial). The
//! basin stability of A (Menck et al., Nature Physics 2013) is this fraction for the region of
//! perturbations considered.

use super::attractor::AttractorSet;
use super::grid::{run_rows, Region};
use super::recognise::recognise;
use super::BasinOptions;
use crate::error::{Error, Result};
use crate::model::DrivenOscillator;
use crate::progress::{Event, Observer};
use serde::{Deserialize, Serialize};

/// The basin fraction of one attractor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Fraction {
    /// Attractor index.
    pub attractor: usize,
    /// Samples that ended on it.
    pub count: usize,
    /// p̂ = count / n.
    pub fraction: f64,
    /// √(p̂(1 − p̂)/n).
    pub sigma: f64,
}

/// Basin fractions of a region.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fractions {
    /// The region sampled.
    pub region: Region,
    /// Samples drawn.
    pub samples: usize,
    /// The seed of the random source.
    pub seed: u64,
    /// Per attractor found (index order of the set).
    pub fractions: Vec<Fraction>,
    /// Samples whose integration failed.
    pub failed: usize,
    /// The attractor index of each sample, in the order drawn (`None`: failed).
    pub labels: Vec<Option<usize>>,
}

impl Fractions {
    /// Renumbers the attractors with `new_of` (from [`AttractorSet::finish`]).
    pub fn relabel(&mut self, new_of: &[usize]) {
        for l in self.labels.iter_mut().flatten() {
            *l = new_of[*l];
        }
        self.fractions = tally(&self.labels, new_of.len());
    }

    /// The basin stability of attractor `a`: its fraction with σ (0 ± 0 if never reached).
    pub fn stability(&self, a: usize) -> (f64, f64) {
        self.fractions
            .iter()
            .find(|f| f.attractor == a)
            .map(|f| (f.fraction, f.sigma))
            .unwrap_or((0.0, 0.0))
    }
}

/// Counts, fractions and binomial σ of `labels` over `n_attractors`.
pub fn tally(labels: &[Option<usize>], n_attractors: usize) -> Vec<Fraction> {
    let n = labels.len().max(1) as f64;
    let mut counts = vec![0usize; n_attractors];
    for l in labels.iter().flatten() {
        if *l < n_attractors {
            counts[*l] += 1;
        }
    }
    counts
        .iter()
        .enumerate()
        .map(|(attractor, &count)| {
            let p = count as f64 / n;
            Fraction {
                attractor,
                count,
                fraction: p,
                sigma: (p * (1.0 - p) / n).sqrt(),
            }
        })
        .collect()
}

/// The `i`-th uniform sample of `region` for `seed`: a SplitMix64 hash of (seed, i), so every
/// sample is independent of the order and the threads that compute them.
pub fn sample(region: &Region, seed: u64, i: u64) -> [f64; 2] {
    let u = unit(splitmix(seed ^ splitmix(2 * i)));
    let v = unit(splitmix(seed ^ splitmix(2 * i + 1)));
    region.at(u, v)
}

fn splitmix(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn unit(x: u64) -> f64 {
    (x >> 11) as f64 / (1u64 << 53) as f64
}

/// Basin fractions of `region` from `n` uniform samples drawn with `seed`, the attractors found in
/// or added to `set`. Reports [`Event::Started`] and [`Event::SweepPoint`] per sample (row 0).
pub fn basin_fractions<S: DrivenOscillator + ?Sized>(
    sys: &S,
    set: &AttractorSet,
    region: Region,
    n: usize,
    seed: u64,
    opts: &BasinOptions,
    observer: &dyn Observer,
) -> Result<Fractions> {
    opts.validate()?;
    region.validate()?;
    if n == 0 {
        return Err(Error::shape("basin samples", ">= 1", 0));
    }
    observer.observe(&Event::Started {
        total: Some(n),
        done: 0,
    });
    let work = |i: usize| -> Result<Option<usize>> {
        if observer.stopped() {
            return Err(Error::Stopped {
                what: "basin sampling",
            });
        }
        let o = recognise(sys, set, sample(&region, seed, i as u64), opts);
        observer.observe(&Event::SweepPoint { row: 0, col: i });
        Ok(o.index())
    };
    let labels = run_rows(n, work).into_iter().collect::<Result<Vec<_>>>()?;
    Ok(Fractions {
        region,
        samples: n,
        seed,
        fractions: tally(&labels, set.len()),
        failed: labels.iter().filter(|l| l.is_none()).count(),
        labels,
    })
}
