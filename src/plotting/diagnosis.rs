//! Figures of a diagnosis: residual fingerprints before/after, recording vs base vs augmented
//! model, κ(α0).

use super::{save, Band, LinePlot, Series};
use crate::error::Result;
use crate::identification::curve::Curve;
use crate::identification::diagnose::Diagnosis;
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

fn binned(
    points: impl Iterator<Item = (f64, f64)>,
    lo: f64,
    hi: f64,
    nb: usize,
) -> Vec<(f64, f64)> {
    let mut s = vec![0.0; nb];
    let mut c = vec![0usize; nb];
    for (x, y) in points {
        if !x.is_finite() || !y.is_finite() {
            continue;
        }
        let k = (((x - lo) / (hi - lo)) * nb as f64).floor();
        if k >= 0.0 && (k as usize) < nb {
            s[k as usize] += y;
            c[k as usize] += 1;
        }
    }
    (0..nb)
        .filter(|&k| c[k] > 0)
        .map(|k| {
            (
                lo + (k as f64 + 0.5) * (hi - lo) / nb as f64,
                s[k] / c[k] as f64,
            )
        })
        .collect()
}

/// (file, x label, x of a fingerprint point, x range).
type Spec<'a> = (
    &'a str,
    &'a str,
    Box<dyn Fn(&(f64, f64, f64, f64, f64)) -> f64>,
    f64,
    f64,
);

/// Writes the figures into `dir`; returns their paths.
pub fn write_figures(d: &Diagnosis, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let fp = &d.fingerprint;
    let vmax = fp.iter().map(|f| f.2.abs()).fold(0.0, f64::max).max(1e-6);
    let specs: Vec<Spec> = vec![
        (
            "fingerprint_beta.svg",
            "output angle β mod 360° [deg]",
            Box::new(|f| f.1.rem_euclid(TAU).to_degrees()),
            0.0,
            360.0,
        ),
        (
            "fingerprint_alpha.svg",
            "input angle α mod 360° [deg]",
            Box::new(|f| f.0.rem_euclid(TAU).to_degrees()),
            0.0,
            360.0,
        ),
        (
            "fingerprint_velocity.svg",
            "output velocity β̇ [rad/s]",
            Box::new(|f| f.2),
            -vmax,
            vmax,
        ),
    ];
    for (name, xl, fx, lo, hi) in specs {
        let before = binned(fp.iter().map(|f| (fx(f), f.3)), lo, hi, 36);
        let after = binned(fp.iter().map(|f| (fx(f), f.4)), lo, hi, 36);
        let plot = LinePlot {
            title: "equation-error residual, binned mean".into(),
            x_label: xl.into(),
            y_label: "residual [rad/s²]".into(),
            series: vec![
                Series {
                    label: "base model".into(),
                    points: before,
                    markers: true,
                    color: 0,
                },
                Series {
                    label: "augmented model".into(),
                    points: after,
                    markers: true,
                    color: 1,
                },
            ],
            ..Default::default()
        };
        let p = dir.join(name);
        save(&plot, &p)?;
        out.push(p);
    }
    // the run the augmented model improves most
    let best = (0..d.runs.len())
        .filter(|&r| !d.base_pred[r].t.is_empty())
        .max_by(|&a, &b| {
            let ia = d.base_pred[a].rms - d.aug_pred[a].rms;
            let ib = d.base_pred[b].rms - d.aug_pred[b].rms;
            ia.total_cmp(&ib)
        });
    if let Some(r) = best {
        let run = &d.runs[r];
        let n = run.t.len().min(400);
        let take = |p: &crate::identification::predict::Prediction| -> Vec<(f64, f64)> {
            p.t.iter()
                .zip(&p.beta)
                .filter(|(t, _)| **t <= run.t[n - 1])
                .map(|(t, b)| (*t, *b))
                .collect()
        };
        let plot = LinePlot {
            title: format!("{}: recording vs short-horizon predictions", d.files[r]),
            x_label: "t [s]".into(),
            y_label: "β [rad]".into(),
            series: vec![
                Series {
                    label: "recording".into(),
                    points: (0..n).map(|i| (run.t[i], run.beta[i])).collect(),
                    markers: true,
                    color: 7,
                },
                Series {
                    label: format!("base (rms {:.4} rad)", d.base_pred[r].rms),
                    points: take(&d.base_pred[r]),
                    markers: false,
                    color: 0,
                },
                Series {
                    label: format!("augmented (rms {:.4} rad)", d.aug_pred[r].rms),
                    points: take(&d.aug_pred[r]),
                    markers: false,
                    color: 1,
                },
            ],
            ..Default::default()
        };
        let p = dir.join("recording_vs_models.svg");
        save(&plot, &p)?;
        out.push(p);
    }
    if let Some(c) = &d.report.curve {
        let p = dir.join("remainder_curve.svg");
        save(&curve_plot(c, d.augmented.eta), &p)?;
        out.push(p);
    }
    if let Some(k) = &d.kappa {
        let pts: Vec<(f64, f64)> = d
            .ringdowns
            .iter()
            .map(|f| (f.alpha0_deg.rem_euclid(360.0), f.kappa.sqrt()))
            .collect();
        let curve: Vec<(f64, f64)> = (0..=180)
            .map(|i| {
                let a = (2.0 * i as f64).to_radians();
                (
                    2.0 * i as f64,
                    (k.g * (a.sin().powi(2) + k.delta_abs.powi(2) * a.cos().powi(2)).sqrt()).sqrt(),
                )
            })
            .collect();
        let plot = LinePlot {
            title: format!(
                "√κ(α0): g = {:.1} ± {:.1} s⁻², |Δ| = {:.3} ± {:.3}",
                k.g, k.g_err, k.delta_abs, k.delta_err
            ),
            x_label: "α0 [deg]".into(),
            y_label: "√κ [1/s]".into(),
            series: vec![
                Series {
                    label: "ring-down fits".into(),
                    points: pts,
                    markers: true,
                    color: 0,
                },
                Series {
                    label: "eq. kappaex".into(),
                    points: curve,
                    markers: false,
                    color: 1,
                },
            ],
            ..Default::default()
        };
        let p = dir.join("kappa_alpha0.svg");
        save(&plot, &p)?;
        out.push(p);
    }
    Ok(out)
}

/// The curve of what remains ([`Curve`]) with its band ± `band_sigmas` σ, the zero line and, for
/// a friction curve, the final model's constant η (`eta`).
pub fn curve_plot(c: &Curve, eta: f64) -> LinePlot {
    let (name, symbol) = match c.kind.as_str() {
        "friction" => ("dry friction", "η(β)"),
        _ => ("torque", "τ(β)"),
    };
    let closed = |v: &[f64]| -> Vec<(f64, f64)> {
        let mut pts: Vec<(f64, f64)> = c.grid_deg.iter().copied().zip(v.iter().copied()).collect();
        if let Some(&(_, y)) = pts.first() {
            pts.push((360.0, y));
        }
        pts
    };
    let curve = closed(&c.value);
    let mut band: Vec<(f64, f64, f64)> = c
        .value
        .iter()
        .zip(&c.sigma)
        .zip(&c.grid_deg)
        .map(|((v, s), x)| (*x, v - c.band_sigmas * s, v + c.band_sigmas * s))
        .collect();
    if let Some(&(_, l, u)) = band.first() {
        band.push((360.0, l, u));
    }
    let mut series = vec![Series {
        label: format!("{symbol}, {} knots, λ = {:.3e}", c.knots, c.lambda),
        points: curve,
        markers: false,
        color: 1,
    }];
    series.push(Series {
        label: "zero".into(),
        points: vec![(0.0, 0.0), (360.0, 0.0)],
        markers: false,
        color: 7,
    });
    if c.kind == "friction" {
        series.push(Series {
            label: format!("final model's constant η = {eta:.3} s⁻²"),
            points: vec![(0.0, eta), (360.0, eta)],
            markers: false,
            color: 0,
        });
    }
    LinePlot {
        title: format!(
            "{name} curve of what remains: held-out gain {:.0} χ², z = {:.1} (threshold {:.2}){}",
            c.heldout_gain,
            c.z,
            c.z_crit,
            if c.stands { "" } else { ", not significant" }
        ),
        x_label: "output angle β [deg]".into(),
        y_label: format!("{symbol} [s⁻²]"),
        series,
        bands: vec![Band {
            label: format!("± {} σ band", c.band_sigmas),
            points: band,
            color: 1,
        }],
        ..Default::default()
    }
}
