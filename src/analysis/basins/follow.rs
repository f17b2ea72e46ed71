//! Global continuation: the attractors and their basin fractions followed over a list of parameter
//! values. At each value the attractors are found afresh from random samples
//! ([`super::basin_fractions`]); an attractor continues a *track* of the previous value when both
//! have the same label (class and period) and rotation number and the distance of their cycles
//! (the least [`super::SectionMetric`] distance between their points) is below
//! [`FollowOptions::match_distance`], nearest pairs first. An attractor matched to no track starts
//! one (a birth); a track not continued ends (a death).

use super::attractor::{Attractor, AttractorSet};
use super::grid::Region;
use super::metric::SectionMetric;
use super::sampling::{basin_fractions, Fraction};
use super::BasinOptions;
use crate::error::Result;
use crate::model::Parametrised;
use crate::progress::Observer;
use serde::{Deserialize, Serialize};

/// Options of the global continuation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FollowOptions {
    /// Random samples per parameter value.
    pub samples: usize,
    /// Seed of the samples (the same starts at every value).
    pub seed: u64,
    /// Largest distance of two cycles on one track.
    pub match_distance: f64,
}

/// The attractors at one parameter value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FollowStep {
    /// The parameter value.
    pub value: f64,
    /// The attractors, in the order of [`AttractorSet::finish`].
    pub attractors: Vec<Attractor>,
    /// Their basin fractions with σ.
    pub fractions: Vec<Fraction>,
    /// The track of each attractor.
    pub tracks: Vec<usize>,
}

/// A birth or a death of a track between two parameter values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum TrackEvent {
    /// Track `track` appears between `from` and `to` (the value where it is first seen).
    Birth {
        /// The track.
        track: usize,
        /// Last value without it.
        from: f64,
        /// First value with it.
        to: f64,
    },
    /// Track `track` ends between `from` (last value with it) and `to`.
    Death {
        /// The track.
        track: usize,
        /// Last value with it.
        from: f64,
        /// First value without it.
        to: f64,
    },
}

/// The global continuation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Follow {
    /// The name of the parameter.
    pub param: String,
    /// One step per value.
    pub steps: Vec<FollowStep>,
    /// Births and deaths, in order.
    pub events: Vec<TrackEvent>,
    /// Number of tracks.
    pub tracks: usize,
}

/// Follows the attractors of `sys` over `values` of `param` (module docs).
pub fn follow_attractors<S: Parametrised>(
    sys: &S,
    param: S::Param,
    values: &[f64],
    region: Region,
    fopts: &FollowOptions,
    opts: &BasinOptions,
    observer: &dyn Observer,
) -> Result<Follow> {
    let mut out = Follow {
        param: crate::model::Parameter::name(param).to_string(),
        steps: Vec::new(),
        events: Vec::new(),
        tracks: 0,
    };
    for &v in values {
        let s = sys.with_param(param, v)?;
        let set = AttractorSet::new(&s);
        let mut fr = basin_fractions(&s, &set, region, fopts.samples, fopts.seed, opts, observer)?;
        let metric = set.metric;
        let (attractors, new_of) = set.finish();
        fr.relabel(&new_of);
        let tracks = match out.steps.last() {
            Some(prev) => match_tracks(&metric, prev, &attractors, fopts, &mut out.tracks),
            None => {
                out.tracks = attractors.len();
                (0..attractors.len()).collect()
            }
        };
        if let Some(prev) = out.steps.last() {
            out.events.extend(events(prev, &tracks, v));
        }
        out.steps.push(FollowStep {
            value: v,
            attractors,
            fractions: fr.fractions,
            tracks,
        });
    }
    Ok(out)
}

/// The track of each attractor of `next`: that of the nearest matching attractor of `prev`, or a
/// new one.
fn match_tracks(
    metric: &SectionMetric,
    prev: &FollowStep,
    next: &[Attractor],
    fopts: &FollowOptions,
    n_tracks: &mut usize,
) -> Vec<usize> {
    let mut pairs = Vec::new();
    for (i, a) in prev.attractors.iter().enumerate() {
        for (j, b) in next.iter().enumerate() {
            let same = a.label == b.label && (a.rotation_number - b.rotation_number).abs() < 0.05;
            let d = b
                .points
                .iter()
                .map(|y| metric.distance_to(*y, &a.points))
                .fold(f64::INFINITY, f64::min);
            if same && d < fopts.match_distance {
                pairs.push((d, i, j));
            }
        }
    }
    pairs.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut track = vec![None; next.len()];
    let mut used = vec![false; prev.attractors.len()];
    for (_, i, j) in pairs {
        if !used[i] && track[j].is_none() {
            used[i] = true;
            track[j] = Some(prev.tracks[i]);
        }
    }
    track
        .into_iter()
        .map(|t| {
            t.unwrap_or_else(|| {
                *n_tracks += 1;
                *n_tracks - 1
            })
        })
        .collect()
}

/// Births (tracks of `tracks` not in `prev`) and deaths (tracks of `prev` not in `tracks`).
fn events(prev: &FollowStep, tracks: &[usize], v: f64) -> Vec<TrackEvent> {
    let births = tracks
        .iter()
        .filter(|t| !prev.tracks.contains(t))
        .map(|&track| TrackEvent::Birth {
            track,
            from: prev.value,
            to: v,
        });
    let deaths = prev
        .tracks
        .iter()
        .filter(|t| !tracks.contains(t))
        .map(|&track| TrackEvent::Death {
            track,
            from: prev.value,
            to: v,
        });
    births.chain(deaths).collect()
}
