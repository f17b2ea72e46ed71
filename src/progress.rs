//! One observer mechanism for every long computation — continuation, sweeps, diagnosis: the
//! computation reports [`Event`]s to an [`Observer`], and progress bars, logs or checkpoint
//! messages live in observers, outside the numerics (argmin's observers).
//!
//! Observers take `&self` and are `Sync`, because sweeps report from worker threads; any
//! `Fn(&Event) + Sync` closure is an observer.
//!
//! ```
//! use gearbif::progress::{Event, Observer};
//! use std::sync::atomic::{AtomicUsize, Ordering};
//! let points = AtomicUsize::new(0);
//! let count = |e: &Event| {
//!     if let Event::BranchPoint { .. } = e {
//!         points.fetch_add(1, Ordering::Relaxed);
//!     }
//! };
//! count.observe(&Event::BranchPoint { index: 1, param: 2.0, stable: true, ds: 0.1 });
//! assert_eq!(points.load(Ordering::Relaxed), 1);
//! ```

use std::path::Path;

/// Something a long computation reports.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Event<'a> {
    /// The computation starts: `total` units of work if known, `done` of them already finished
    /// (e.g. loaded from checkpoints).
    Started {
        /// Units of work in all.
        total: Option<usize>,
        /// Units already done.
        done: usize,
    },
    /// A named stage begins.
    Stage(&'a str),
    /// A continuation accepted a point.
    BranchPoint {
        /// Index of the point on the branch.
        index: usize,
        /// Its parameter value.
        param: f64,
        /// Whether the orbit is stable.
        stable: bool,
        /// The next arclength step.
        ds: f64,
    },
    /// A sweep point finished.
    SweepPoint {
        /// Row index.
        row: usize,
        /// Column index.
        col: usize,
    },
    /// A sweep row finished and was checkpointed (to `path`, if checkpointing).
    RowDone {
        /// Row index.
        row: usize,
        /// The checkpoint file.
        path: Option<&'a Path>,
    },
}

/// Receives the [`Event`]s of a computation.
pub trait Observer: Sync {
    /// Called for each event, possibly from several threads.
    fn observe(&self, event: &Event<'_>);
    /// True once the computation should stop (e.g. the user pressed Ctrl-C): sweeps check it
    /// before each point and end with [`crate::Error::Stopped`]. Never, by default.
    fn stopped(&self) -> bool {
        false
    }
}

/// An observer that ignores the events and stops the computation once its flag is set (by a
/// signal handler or another thread).
#[derive(Debug, Clone, Copy)]
pub struct StopFlag<'a>(pub &'a std::sync::atomic::AtomicBool);

impl Observer for StopFlag<'_> {
    fn observe(&self, _: &Event<'_>) {}
    fn stopped(&self) -> bool {
        self.0.load(std::sync::atomic::Ordering::Relaxed)
    }
}

impl<F: Fn(&Event<'_>) + Sync> Observer for F {
    fn observe(&self, event: &Event<'_>) {
        self(event)
    }
}

/// Reports one line of a computation's log as [`Event::Stage`] (the diagnosis and the campaigns
/// report their steps this way).
pub fn stage(obs: &dyn Observer, line: &str) {
    obs.observe(&Event::Stage(line));
}

/// An observer that passes the [`Event::Stage`] lines to `f` and ignores the rest:
/// `lines(|s| eprintln!("{s}"))`.
pub fn lines<F: Fn(&str) + Sync>(f: F) -> impl Observer {
    move |e: &Event<'_>| {
        if let Event::Stage(s) = e {
            f(s)
        }
    }
}

/// An observer that ignores everything.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Observer for Silent {
    fn observe(&self, _: &Event<'_>) {}
}
