//! Analysis of simulated responses: the paper's classification (harmonic fit, RMS, THD_F,
//! flowchart; [`harmonic`]), the rigorous classification (period on the Poincaré section modulo the
//! symmetry, rotation number, Lyapunov exponent; [`classify`], [`lyapunov`]), and the σ of a point
//! located on a recorded gear from its model file's covariance ([`uncertainty`]).

pub mod basins;
pub mod classify;
pub mod global_events;
pub mod harmonic;
pub mod lyapunov;
pub mod relock;
pub mod uncertainty;

pub use classify::{
    classify_point, paper_fig6_start, rigorous_classify, ClassifyOptions, Dynamics, PointResult,
    RigorousClass,
};
pub use harmonic::{fit_harmonics, HarmonicFit, PaperClass, PaperMetrics, ThdDefinition};
pub use lyapunov::{LyapunovAccumulator, LyapunovEstimate};
