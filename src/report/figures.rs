//! The report's figures (feature `plot`), drawn from its data ([`super::compute::ReportData`]):
//! the lock branch with the Θ = 0 hysteresis loop (as the paper's Fig. 10a), the classification
//! map with both kinds of class markers, f_c(Θ) and the Θ = 25° branches. Files go to
//! `DIR/figures`; each function returns the (file, alt text) pairs relative to `DIR`.

use super::compute::{Bifurcations, ReportData, BIFURCATION_THETA_DEG};
use crate::error::Result;
use crate::plotting::atlas::{hysteresis_lock_plot, Markers, RmsMap};
use crate::plotting::branch::{BoundaryPlot, BranchDiagram};
use crate::plotting::{save, Figure};
use std::path::Path;

/// Figure links (file relative to the report folder, alt text).
pub type Links = Vec<(String, String)>;

/// The figures of every section.
#[derive(Debug, Clone, Default)]
pub struct FigureSet {
    /// Of the lock-branch section.
    pub lock_branch: Links,
    /// Of the bifurcations section.
    pub bifurcations: Links,
    /// Failures of the bifurcations section's figures (kept, not returned as errors).
    pub bifurcation_errors: Vec<String>,
    /// Of the map section.
    pub map: Links,
}

fn save_pair(fig: &impl Figure, dir: &Path, stem: &str, alt: &str, out: &mut Links) -> Result<()> {
    save(fig, dir.join(format!("{stem}.svg")))?;
    save(fig, dir.join(format!("{stem}.png")))?;
    out.push((format!("figures/{stem}.png"), alt.into()));
    Ok(())
}

/// The lock branch and the Θ = 0 loop (`lock_branch.png`).
pub fn lock_branch(d: &ReportData, dir: &Path) -> Result<Links> {
    let mut out = Links::new();
    let fig = hysteresis_lock_plot(&d.hysteresis, &d.gear.with_parallel_shafts_deg(0.0))?;
    save_pair(
        &fig,
        dir,
        "lock_branch",
        "lock branch and hysteresis",
        &mut out,
    )?;
    Ok(out)
}

/// The map with the paper's and the rigorous classes (`map_paper.png`, `map_rigorous.png`).
pub fn map(d: &ReportData, dir: &Path) -> Result<Links> {
    let mut out = Links::new();
    let mut fig = RmsMap::from_sweep(&d.map);
    fig.title = "RMS_δ with the paper's classes".into();
    save_pair(&fig, dir, "map_paper", "map, paper classes", &mut out)?;
    fig.markers = Markers::Rigorous;
    fig.title = "RMS_δ with the rigorous classes".into();
    save_pair(&fig, dir, "map_rigorous", "map, rigorous classes", &mut out)?;
    Ok(out)
}

/// f_c(Θ) (`fc_theta.png`) and the Θ = 25° branches (`theta25_branches.png`).
pub fn bifurcations(d: &ReportData, b: &Bifurcations, dir: &Path) -> Result<Links> {
    let mut out = Links::new();
    if let Ok(curves) = &b.boundary.curves {
        let mut marks = Vec::new();
        if let Some(fc) = d.gear.lock_loss_frequency() {
            let th_rev = (2.0f64 / 3.0).sqrt().asin().to_degrees();
            marks.push(("analytic f_c at Δ = ±1".to_string(), 0.0, fc));
            marks.push(("analytic f_c at Δ = ±1".to_string(), th_rev, fc));
        }
        let fig = BoundaryPlot {
            title: "lock-loss boundary f_c(Θ) (fold of the lock)".into(),
            curves: curves.clone(),
            marks,
            ..Default::default()
        };
        save_pair(&fig, dir, "fc_theta", "lock-loss boundary f_c(Θ)", &mut out)?;
    }
    if !b.theta25.branches.is_empty() {
        let fig = BranchDiagram {
            title: format!("Θ = {BIFURCATION_THETA_DEG}°: symmetric and asymmetric orbits"),
            branches: b.theta25.branches.clone(),
            ..Default::default()
        };
        save_pair(&fig, dir, "theta25_branches", "Θ = 25° branches", &mut out)?;
    }
    Ok(out)
}

/// Draws every figure into `dir`; a failure of the bifurcation figures is kept in the set.
pub fn draw(d: &ReportData, dir: &Path) -> Result<FigureSet> {
    let mut set = FigureSet {
        lock_branch: lock_branch(d, dir)?,
        map: map(d, dir)?,
        ..Default::default()
    };
    if let Some(b) = &d.bifurcations {
        match bifurcations(d, b, dir) {
            Ok(l) => set.bifurcations = l,
            Err(e) => set.bifurcation_errors.push(e.to_string()),
        }
    }
    Ok(set)
}
