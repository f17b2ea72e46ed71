//! Two-parameter sweeps ("the atlas") with the paper's protocols, run as a resumable state
//! machine: rows are computed in parallel (feature `parallel`, one row per task; the semi-static
//! protocol is sequential along a row), every finished row is checkpointed atomically as one JSON
//! file, and a restarted sweep loads the finished rows and computes only the missing ones. Each
//! row depends only on the spec, so a resumed sweep ends bit-identical to an uninterrupted one.
//!
//! Progress and checkpoint reporting are observers ([`crate::progress::Observer`]), outside the
//! numerics. The row computation is generic ([`sweep_row`], [`sweep_grid`]: any system with a
//! parameter lens, any integrator, axes named by the lens's names, [`parse_axis`]); [`SweepSpec`]
//! and [`SweepRunner`] are the gear's instance, with the paper's protocols and checkpoints, whose
//! axes ([`SweepParam`]) are the gear's lens names plus the built gear's inertia.
//!
//! Protocols:
//! - [`Protocol::Fresh`] (Fig. 7b): every point starts from the same initial state.
//! - [`Protocol::SemiStatic`] (Fig. 8): along a row the state at the end of one point is the start
//!   of the next (the drive phase is the same at both, α ≡ α₀ mod 2π).

use crate::analysis::classify::{classify_point, ClassifyOptions, Dynamics, PointResult};
use crate::error::{Error, Result};
use crate::integrator::{EventDriven, EventDriven853, FixedStep, FlowMethod, DEFAULT_METHOD};
use crate::model::{Convention, Gear, GearParam, GearParams};
use crate::model::{DrivenOscillator, Parametrised};
pub use crate::progress::{Event, Observer, Silent};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

mod axis;
mod shard;
pub use axis::{log_values, parse_axis, range_values, Axis, SweepParam};
pub use shard::{merge_shards, spec_hash, Shard, ShardStatus};

/// How successive points of a row start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Protocol {
    /// Every point from the spec's initial state (paper Fig. 7b).
    #[default]
    Fresh,
    /// The end state of one point is the start of the next along a row (paper Fig. 8).
    SemiStatic,
}

/// Which integrator simulates the points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// The exact event-driven Filippov integrator (Dormand–Prince 5(4)).
    EventDriven,
    /// The same with Dormand–Prince 8(5,3) (faster at every tolerance; the default).
    #[default]
    EventDriven853,
    /// The paper's fixed-step RK4 with 50 steps per period (no rigorous classification).
    FixedStep,
}

/// A sweep: the gear, the two axes, the protocol, the initial state and the per-point options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepSpec {
    /// The gear (fields not swept keep these values).
    pub gear: GearParams,
    /// Drive frequency if f is not swept, Hz.
    pub f: f64,
    /// Rows (computed in parallel).
    pub rows: Axis,
    /// Columns (sequential along a row; the semi-static protocol carries the state along them).
    pub cols: Axis,
    /// The protocol.
    pub protocol: Protocol,
    /// Drive phase α₀ at t = 0, degrees.
    pub alpha0_deg: f64,
    /// Initial output angle β₀, degrees, in `convention`.
    pub beta0_deg: f64,
    /// Convention of β₀ and of the reported angles.
    pub convention: Convention,
    /// The integrator.
    pub method: Method,
    /// Per-point options.
    pub classify: ClassifyOptions,
}

impl SweepSpec {
    /// The paper's Fig. 8 protocol (Θ from −90° to 90° in 5°, f from 0.1 to 100 Hz in 0.02 Hz
    /// as in the caption, semi-static, 1000 settling turns, start α = 0°, β = 180° paper
    /// convention).
    pub fn paper_fig8() -> Result<Self> {
        Ok(Self {
            gear: GearParams::paper(),
            f: 1.0,
            rows: Axis::range(GearParam::ThetaDeg, -90.0, 90.0, 5.0)?,
            cols: Axis::range(GearParam::F, 0.1, 100.0, 0.02)?,
            protocol: Protocol::SemiStatic,
            alpha0_deg: 0.0,
            beta0_deg: 180.0,
            convention: Convention::Paper,
            method: Method::EventDriven853,
            classify: ClassifyOptions {
                settle_turns: 1000,
                ..ClassifyOptions::default()
            },
        })
    }

    /// The paper's Fig. 7b protocol on the given axes: fresh start at α = 90°, β = 270° (paper
    /// convention), 90 settling turns and 10 recorded.
    pub fn paper_fig7(rows: Axis, cols: Axis) -> Self {
        Self {
            gear: GearParams::paper(),
            f: 1.0,
            rows,
            cols,
            protocol: Protocol::Fresh,
            alpha0_deg: 90.0,
            beta0_deg: 270.0,
            convention: Convention::Paper,
            method: Method::EventDriven853,
            classify: ClassifyOptions::paper(),
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.rows.values.len() * self.cols.values.len()
    }

    /// True if an axis is empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Validates the spec.
    pub fn validate(&self) -> Result<()> {
        self.gear.validate()?;
        crate::error::positive("f", self.f)?;
        crate::error::finite("alpha0_deg", self.alpha0_deg)?;
        crate::error::finite("beta0_deg", self.beta0_deg)?;
        self.classify.validate()?;
        if self.rows.param == self.cols.param {
            return Err(Error::inconsistent(
                "rows, cols",
                "the two sweep axes must be different parameters",
            ));
        }
        if self.is_empty() {
            return Err(Error::shape("points of the sweep", ">= 1", 0));
        }
        let (nr, nc) = (self.rows.values.len(), self.cols.values.len());
        if nr.checked_mul(nc).is_none_or(|n| n > axis::GRID_POINTS_MAX) {
            return Err(Error::shape(
                format!("points of the sweep ({nr} rows × {nc} columns)"),
                "at most 1e7",
                nr.saturating_mul(nc),
            ));
        }
        for ax in [&self.rows, &self.cols] {
            for &v in &ax.values {
                crate::error::finite("axis value", v)?;
            }
        }
        Ok(())
    }

    /// True if `r` is row `i` of this spec: its index, its value and every column's value.
    fn row_matches(&self, i: usize, r: &RowResult) -> bool {
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits();
        r.row == i
            && self
                .rows
                .values
                .get(i)
                .is_some_and(|&v| same(v, r.row_value))
            && r.points.len() == self.cols.values.len()
            && r.points
                .iter()
                .zip(&self.cols.values)
                .enumerate()
                .all(|(j, (p, &c))| {
                    p.row == i
                        && p.col == j
                        && same(p.row_value, r.row_value)
                        && same(p.col_value, c)
                })
    }

    /// The gear at a grid point: the spec's gear with the two axes set through the gear's lens
    /// ([`SweepParam::apply`]).
    pub fn gear_at(&self, row_value: f64, col_value: f64) -> Result<Gear> {
        let mut g = self.gear.driven(self.f)?;
        for (param, v) in [(self.rows.param, row_value), (self.cols.param, col_value)] {
            g = param.apply(&g, &self.gear, v)?;
        }
        g.with_convention(self.convention)
            .with_alpha0(self.alpha0_deg.to_radians())
    }

    /// [`sweep_row`] of row `row` (value `rv`) with `method` and `opts`.
    fn row_with<M: FlowMethod<Gear>>(
        &self,
        method: &M,
        rv: f64,
        opts: &ClassifyOptions,
        row: usize,
        observer: &dyn Observer,
    ) -> Result<Vec<(Gear, PointResult)>> {
        let x_start = [self.beta0_deg.to_radians(), 0.0];
        let at = |cv: f64| self.gear_at(rv, cv);
        sweep_row(
            method,
            at,
            &self.cols.values,
            x_start,
            self.protocol,
            opts,
            row,
            observer,
        )
    }

    /// True if rows `i` and `j` simulate the same system at every column. A row depends only on
    /// its systems and the rest of the spec, so such rows have equal results: the gear depends on
    /// Θ only through Δ = 1 − 3 sin²Θ (even in Θ, bit for bit), so the rows ±Θ of Fig. 8 are twins.
    pub fn same_systems(&self, i: usize, j: usize) -> bool {
        let (Some(&a), Some(&b)) = (self.rows.values.get(i), self.rows.values.get(j)) else {
            return false;
        };
        self.cols
            .values
            .iter()
            .all(|&c| matches!((self.gear_at(a, c), self.gear_at(b, c)), (Ok(x), Ok(y)) if x == y))
    }

    /// Row `row` as a copy of `twin`'s result (rows with [`Self::same_systems`]).
    fn copy_row(&self, twin: &RowResult, row: usize) -> RowResult {
        let rv = self.rows.values[row];
        let points = twin
            .points
            .iter()
            .map(|p| PointRecord {
                row,
                row_value: rv,
                ..p.clone()
            })
            .collect();
        RowResult {
            row,
            row_value: rv,
            points,
        }
    }

    /// Computes one row (sequential along the columns).
    pub fn compute_row(&self, row: usize, observer: &dyn Observer) -> Result<RowResult> {
        let rv = *self.rows.values.get(row).ok_or_else(|| {
            Error::shape("row index", format!("< {}", self.rows.values.len()), row)
        })?;
        let results = match self.method {
            Method::EventDriven => {
                self.row_with(&EventDriven, rv, &self.classify, row, observer)?
            }
            Method::EventDriven853 => {
                self.row_with(&EventDriven853, rv, &self.classify, row, observer)?
            }
            Method::FixedStep => {
                let fixed_opts = ClassifyOptions {
                    rigorous: false,
                    ..self.classify.clone()
                };
                self.row_with(&FixedStep::default(), rv, &fixed_opts, row, observer)?
            }
        };
        let cols = &self.cols.values;
        let points = results
            .iter()
            .zip(cols)
            .enumerate()
            .map(|(col, ((gear, res), &cv))| PointRecord::new(row, col, rv, cv, gear, res))
            .collect();
        Ok(RowResult {
            row,
            row_value: rv,
            points,
        })
    }
}

/// One row of a sweep of any system: classifies the attractor at each value of `cols` (in order)
/// with [`classify_point`], the system built by `system_at`; with [`Protocol::SemiStatic`] the end
/// state of one point starts the next (settling [`ClassifyOptions::settle_after_nonperiodic`] turns
/// after a non-periodic point, if set), with [`Protocol::Fresh`] every point starts at `x_start`.
/// Reports [`Event::SweepPoint`] { row, col } after each point.
#[allow(clippy::too_many_arguments)]
pub fn sweep_row<S, M, F>(
    method: &M,
    system_at: F,
    cols: &[f64],
    x_start: [f64; 2],
    protocol: Protocol,
    opts: &ClassifyOptions,
    row: usize,
    observer: &dyn Observer,
) -> Result<Vec<(S, PointResult)>>
where
    S: DrivenOscillator,
    M: FlowMethod<S> + ?Sized,
    F: Fn(f64) -> Result<S>,
{
    let mut x = x_start;
    let mut out: Vec<(S, PointResult)> = Vec::with_capacity(cols.len());
    for (col, &cv) in cols.iter().enumerate() {
        if observer.stopped() {
            return Err(Error::Stopped { what: "the sweep" });
        }
        let sys = system_at(cv)?;
        let quick = match protocol {
            Protocol::Fresh => {
                x = x_start;
                None
            }
            Protocol::SemiStatic => opts.after(out.last().map(|(_, r)| r)),
        };
        let res = classify_point(&sys, x, method, quick.as_ref().unwrap_or(opts))?;
        x = res.end_state;
        out.push((sys, res));
        observer.observe(&Event::SweepPoint { row, col });
    }
    Ok(out)
}

/// A two-parameter sweep of any [`Parametrised`] system: `rows.0` takes the values `rows.1`, and
/// along each row (one task per row with the `parallel` feature) `cols.0` takes the values
/// `cols.1` ([`sweep_row`]). Returns the results row by row. The gear's resumable, checkpointed
/// sweep is [`SweepRunner`].
#[allow(clippy::too_many_arguments)]
pub fn sweep_grid<S, M>(
    method: &M,
    base: &S,
    rows: (S::Param, &[f64]),
    cols: (S::Param, &[f64]),
    x_start: [f64; 2],
    protocol: Protocol,
    opts: &ClassifyOptions,
    observer: &dyn Observer,
) -> Result<Vec<Vec<(S, PointResult)>>>
where
    S: Parametrised,
    M: FlowMethod<S> + ?Sized,
{
    opts.validate()?;
    if rows.0 == cols.0 {
        return Err(Error::inconsistent(
            "rows, cols",
            "the two sweep axes must be different parameters",
        ));
    }
    observer.observe(&Event::Started {
        total: Some(rows.1.len() * cols.1.len()),
        done: 0,
    });
    let row = |i: usize| -> Result<Vec<(S, PointResult)>> {
        let sys = base.with_param(rows.0, rows.1[i])?;
        let at = |v: f64| sys.with_param(cols.0, v);
        sweep_row(method, at, cols.1, x_start, protocol, opts, i, observer)
    };
    #[cfg(feature = "parallel")]
    let out: Vec<Result<Vec<(S, PointResult)>>> = {
        use rayon::prelude::*;
        (0..rows.1.len()).into_par_iter().map(row).collect()
    };
    #[cfg(not(feature = "parallel"))]
    let out: Vec<Result<Vec<(S, PointResult)>>> = (0..rows.1.len()).map(row).collect();
    out.into_iter().collect()
}

/// One point of a sweep, flat (one CSV line).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PointRecord {
    /// Row index.
    pub row: usize,
    /// Column index.
    pub col: usize,
    /// Row parameter value.
    pub row_value: f64,
    /// Column parameter value.
    pub col_value: f64,
    /// Drive frequency, Hz.
    pub f_hz: f64,
    /// Shaft orientation index Δ.
    pub delta: f64,
    /// Standard deviation of δ over the window, degrees (RMS_δ of Figs. 7–8).
    pub rms_delta_deg: f64,
    /// RMS of the 7-harmonic fit residual, degrees (eq. `rms`).
    pub rms_fit_deg: f64,
    /// THD_F, standard definition (may be +∞ → JSON null).
    pub thd: Option<f64>,
    /// THD_F, as printed (denominator a₁² + b₁²).
    pub thd_printed: Option<f64>,
    /// Mean δ, degrees.
    pub delta_avg_deg: f64,
    /// DFT amplitude of δ at the drive frequency, degrees.
    pub delta_fund_deg: f64,
    /// Net output rotation frequency over the window, Hz.
    pub net_rotation_hz: f64,
    /// The paper's class: chaos, T/2, T.
    pub paper_class: String,
    /// The rigorous class: T/2, T, 3T, 3T/2, QP, chaos, ? (empty if not computed).
    pub class: String,
    /// Minimal period in half periods (0 if not periodic).
    pub half_periods: usize,
    /// Symmetric periodic orbit.
    pub symmetric: bool,
    /// Rotation number per drive period.
    pub rotation_number: Option<f64>,
    /// Locked (|rotation number| = 1).
    pub locked: Option<bool>,
    /// Largest Lyapunov exponent per drive period (null: −∞ or not computed).
    pub lyapunov: Option<f64>,
    /// Do the classes agree?
    pub agree: Option<bool>,
    /// Final β (mod 2π), rad.
    pub beta_end: f64,
    /// Final ω, rad/s.
    pub omega_end: f64,
}

fn fin(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

impl PointRecord {
    /// Flattens a point result.
    pub fn new(row: usize, col: usize, rv: f64, cv: f64, gear: &Gear, r: &PointResult) -> Self {
        let rig = r.rigorous.as_ref();
        let (hp, sym) = match rig.map(|r| &r.dynamics) {
            Some(Dynamics::Periodic {
                half_periods,
                symmetric,
                ..
            }) => (*half_periods, *symmetric),
            _ => (0, false),
        };
        Self {
            row,
            col,
            row_value: rv,
            col_value: cv,
            f_hz: gear.f,
            delta: gear.delta,
            rms_delta_deg: r.paper.rms_delta_deg,
            rms_fit_deg: r.paper.rms_fit_deg,
            thd: fin(r.paper.thd),
            thd_printed: fin(r.paper.thd_printed),
            delta_avg_deg: r.paper.delta_avg_deg,
            delta_fund_deg: r.paper.delta_fund_deg,
            net_rotation_hz: r.net_rotation_hz,
            paper_class: r.paper.class.label().to_string(),
            class: rig.map(|r| r.label.clone()).unwrap_or_default(),
            half_periods: hp,
            symmetric: sym,
            rotation_number: rig.map(|r| r.rotation_number),
            locked: rig.map(|r| r.locked),
            lyapunov: rig.and_then(|r| r.lyapunov.per_period),
            agree: r.agree,
            beta_end: r.end_state[0],
            omega_end: r.end_state[1],
        }
    }
}

/// A finished row.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RowResult {
    /// Row index.
    pub row: usize,
    /// Row parameter value.
    pub row_value: f64,
    /// Its points, in column order.
    pub points: Vec<PointRecord>,
}

/// Schema id of `sweep.json` (docs/formats.md).
pub const SCHEMA: &str = "gearbif.sweep/1";

/// The result of a complete sweep: the spec and every row.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepResult {
    /// The spec.
    pub spec: SweepSpec,
    /// Rows in order.
    pub rows: Vec<RowResult>,
}

impl SweepResult {
    /// All points, row-major.
    pub fn points(&self) -> impl Iterator<Item = &PointRecord> {
        self.rows.iter().flat_map(|r| r.points.iter())
    }

    /// CSV text: one line per point, a header naming the two axes.
    pub fn to_csv(&self) -> Result<String> {
        let mut w = csv::Writer::from_writer(Vec::new());
        for p in self.points() {
            w.serialize(p)
                .map_err(|e| Error::format("CSV", "sweep table", e))?;
        }
        let bytes = w
            .into_inner()
            .map_err(|e| Error::format("CSV", "sweep table", e.into_error()))?;
        let mut s = String::from_utf8(bytes).map_err(|e| Error::format("CSV", "sweep table", e))?;
        let header = format!(
            "# rows = {}, cols = {}, protocol = {:?}, method = {:?}\n",
            self.spec.rows.param.column_name(),
            self.spec.cols.param.column_name(),
            self.spec.protocol,
            self.spec.method
        );
        s.insert_str(0, &header);
        Ok(s)
    }

    /// Writes `points.csv` and `sweep.json` into `dir`, atomically.
    pub fn write(&self, dir: impl AsRef<Path>) -> Result<()> {
        let dir = dir.as_ref();
        crate::io::write_atomic(dir.join("points.csv"), self.to_csv()?.as_bytes())?;
        crate::io::write_json_atomic(
            dir.join("sweep.json"),
            &crate::io::with_schema(SCHEMA, self),
        )
    }
}

/// Progress of a run.
#[derive(Debug, Clone, PartialEq)]
pub enum SweepOutcome {
    /// All rows are done.
    Complete(Box<SweepResult>),
    /// Stopped early (row limit); the finished rows are in the checkpoint.
    Stopped {
        /// Rows finished (including loaded ones).
        rows_done: usize,
        /// Rows in the sweep.
        rows_total: usize,
    },
}

/// Runs a [`SweepSpec`], optionally with a checkpoint directory, a row limit and an observer.
pub struct SweepRunner<'a> {
    spec: SweepSpec,
    checkpoint: Option<PathBuf>,
    max_new_rows: Option<usize>,
    observer: &'a dyn Observer,
    shard: Option<Shard>,
}

impl<'a> SweepRunner<'a> {
    /// A runner without checkpoints or observer.
    pub fn new(spec: SweepSpec) -> Self {
        Self {
            spec,
            checkpoint: None,
            max_new_rows: None,
            observer: &Silent,
            shard: None,
        }
    }
    /// Checkpoints rows into `dir` (`spec.json` and `rows/row-NNNNN.json`) and resumes from them.
    pub fn checkpoint(mut self, dir: impl Into<PathBuf>) -> Self {
        self.checkpoint = Some(dir.into());
        self
    }
    /// Stops after computing `n` new rows (used to test resumption; a killed run behaves the same).
    pub fn max_new_rows(mut self, n: usize) -> Self {
        self.max_new_rows = Some(n);
        self
    }
    /// Sets the observer.
    pub fn observer(mut self, o: &'a dyn Observer) -> Self {
        self.observer = o;
        self
    }

    fn row_path(dir: &Path, row: usize) -> PathBuf {
        dir.join("rows").join(format!("row-{row:05}.json"))
    }

    /// Whether row `i` is computed by this runner (all rows, or those of its shard).
    fn owns(&self, i: usize) -> bool {
        self.shard.is_none_or(|s| s.contains(i))
    }

    /// Loads finished rows from the checkpoint (checking that it belongs to the same spec). A
    /// spec.json that does not parse is refused (the error names the file and line); a row file
    /// that does not parse or does not match the spec is ignored and its row recomputed; temporary
    /// files left by a killed run are removed.
    fn load(&self) -> Result<Vec<Option<RowResult>>> {
        let n = self.spec.rows.values.len();
        let mut rows = vec![None; n];
        let Some(dir) = &self.checkpoint else {
            return Ok(rows);
        };
        let spec_path = dir.join("spec.json");
        if spec_path.exists() {
            let bytes =
                std::fs::read(&spec_path).map_err(|e| Error::file("read", &spec_path, e))?;
            let old: SweepSpec = serde_json::from_slice(&bytes).map_err(|e| Error::Recording {
                file: spec_path.display().to_string(),
                line: (e.line() > 0).then_some(e.line()),
                what: format!("corrupt sweep checkpoint ({e}); delete its folder to start afresh"),
            })?;
            if old != self.spec {
                return Err(Error::checkpoint(
                    dir,
                    "the checkpoint belongs to a different sweep; use another directory",
                ));
            }
            crate::io::remove_stale_temporaries(&dir.join("rows"));
            for (i, slot) in rows.iter_mut().enumerate() {
                if !self.owns(i) {
                    continue;
                }
                let p = Self::row_path(dir, i);
                if p.is_file() {
                    let bytes = std::fs::read(&p).map_err(|e| Error::file("read", &p, e))?;
                    *slot = serde_json::from_slice::<RowResult>(&bytes)
                        .ok()
                        .filter(|r| self.spec.row_matches(i, r));
                }
            }
        } else {
            crate::io::write_json_atomic(&spec_path, &self.spec)?;
        }
        if let Some(shard) = self.shard {
            shard::check_or_write_manifest(dir, &self.spec, shard)?;
        }
        Ok(rows)
    }

    /// Runs (or resumes) the sweep.
    pub fn run(&self) -> Result<SweepOutcome> {
        if self.shard.is_some() {
            return Err(Error::inconsistent(
                "shard",
                "a sharded runner is run with `run_shard`",
            ));
        }
        let rows = self.run_rows()?;
        let rows_done = rows.iter().filter(|r| r.is_some()).count();
        if rows_done < rows.len() {
            return Ok(SweepOutcome::Stopped {
                rows_done,
                rows_total: rows.len(),
            });
        }
        Ok(SweepOutcome::Complete(Box::new(SweepResult {
            spec: self.spec.clone(),
            rows: rows.into_iter().flatten().collect(),
        })))
    }

    /// Runs (or resumes) one shard of the sweep into the checkpoint directory (required); the
    /// shards are combined by [`merge_shards`].
    pub fn run_shard(mut self, shard: Shard) -> Result<ShardStatus> {
        if self.checkpoint.is_none() {
            return Err(Error::inconsistent(
                "shard, checkpoint",
                "a shard needs a checkpoint directory",
            ));
        }
        shard.check_rows(self.spec.rows.values.len())?;
        self.shard = Some(shard);
        let rows = self.run_rows()?;
        let rows_total = shard.rows(rows.len()).count();
        let rows_done = shard
            .rows(rows.len())
            .filter(|&i| rows[i].is_some())
            .count();
        Ok(ShardStatus {
            shard,
            rows_done,
            rows_total,
        })
    }

    /// Loads the finished rows, computes the missing rows this runner owns (up to the row limit),
    /// checkpoints each, and returns every row slot.
    fn run_rows(&self) -> Result<Vec<Option<RowResult>>> {
        self.spec.validate()?;
        let mut rows = self.load()?;
        let ncols = self.spec.cols.values.len();
        let done = rows.iter().filter(|r| r.is_some()).count();
        let owned = (0..rows.len()).filter(|&i| self.owns(i)).count();
        self.observer.observe(&Event::Started {
            total: Some(owned * ncols),
            done: done * ncols,
        });
        // rows owned here that are twins of an earlier owned row are copied, not computed
        let twin: Vec<Option<usize>> = (0..rows.len())
            .map(|i| (0..i).find(|&j| self.owns(i) && self.owns(j) && self.spec.same_systems(i, j)))
            .collect();
        let pending: Vec<usize> = (0..rows.len())
            .filter(|&i| rows[i].is_none() && self.owns(i) && twin[i].is_none())
            .collect();
        let started = AtomicUsize::new(0);
        let limit = self.max_new_rows.unwrap_or(usize::MAX);
        let work = |i: usize| -> Result<Option<RowResult>> {
            if started.fetch_add(1, Ordering::SeqCst) >= limit {
                return Ok(None);
            }
            let r = self.spec.compute_row(i, self.observer)?;
            self.finish_row(&r)?;
            Ok(Some(r))
        };
        #[cfg(feature = "parallel")]
        let new: Vec<Result<Option<RowResult>>> = {
            use rayon::prelude::*;
            pending.par_iter().map(|&i| work(i)).collect()
        };
        #[cfg(not(feature = "parallel"))]
        let new: Vec<Result<Option<RowResult>>> = pending.iter().map(|&i| work(i)).collect();
        for r in new {
            if let Some(row) = r? {
                let i = row.row;
                rows[i] = Some(row);
            }
        }
        for (i, t) in twin.iter().enumerate() {
            if let (None, Some(Some(src))) = (&rows[i], t.map(|j| rows[j].as_ref())) {
                let r = self.spec.copy_row(src, i);
                for col in 0..ncols {
                    self.observer.observe(&Event::SweepPoint { row: i, col });
                }
                self.finish_row(&r)?;
                rows[i] = Some(r);
            }
        }
        Ok(rows)
    }

    /// Checkpoints a finished row (if there is a checkpoint) and reports it.
    fn finish_row(&self, r: &RowResult) -> Result<()> {
        let path = match &self.checkpoint {
            Some(dir) => {
                let p = Self::row_path(dir, r.row);
                crate::io::write_json_atomic(&p, r)?;
                Some(p)
            }
            None => None,
        };
        self.observer.observe(&Event::RowDone {
            row: r.row,
            path: path.as_deref(),
        });
        Ok(())
    }
}

/// A hysteresis sweep (Figs. 9–10): f up then down at fixed gear, carrying the state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Hysteresis {
    /// Frequencies of the upward branch (the downward branch visits them in reverse).
    pub f: Vec<f64>,
    /// Points while f increases.
    pub up: Vec<PointRecord>,
    /// Points while f decreases (in decreasing f).
    pub down: Vec<PointRecord>,
}

/// Runs f up through `f_values` (ascending) and back down, semi-static, starting from
/// (α₀, β₀) in `convention`; the paper's protocol for Figs. 9–10.
pub fn hysteresis(
    gear: GearParams,
    f_values: &[f64],
    alpha0_deg: f64,
    beta0_deg: f64,
    convention: Convention,
    opts: &ClassifyOptions,
    observer: &dyn Observer,
) -> Result<Hysteresis> {
    if f_values.is_empty() || f_values.windows(2).any(|w| w[1] <= w[0] || w[1].is_nan()) {
        return Err(Error::option(
            "hysteresis frequencies",
            "need at least one, strictly ascending",
        ));
    }
    let mut x = [beta0_deg.to_radians(), 0.0];
    let mut run = |fs: &mut dyn Iterator<Item = (usize, f64)>| -> Result<Vec<PointRecord>> {
        let mut out = Vec::new();
        for (i, f) in fs {
            let g = gear
                .driven(f)?
                .with_convention(convention)
                .with_alpha0(alpha0_deg.to_radians())?;
            let r = classify_point(&g, x, &DEFAULT_METHOD, opts)?;
            x = r.end_state;
            out.push(PointRecord::new(0, i, gear.theta.to_degrees(), f, &g, &r));
            observer.observe(&Event::SweepPoint { row: 0, col: i });
        }
        Ok(out)
    };
    let up = run(&mut f_values.iter().copied().enumerate())?;
    let down = run(&mut f_values.iter().copied().enumerate().rev())?;
    Ok(Hysteresis {
        f: f_values.to_vec(),
        up,
        down,
    })
}

/// The lock-loss hysteresis at Θ = 0 (paper Fig. 10): [`hysteresis`] of the parallel-shaft gear at
/// Θ = 0 from α₀ = 0°, β₀ = 180° (paper convention), `settle_turns` settling and 10 analysis turns
/// per frequency. `gearbif figure fig10` (1–45 Hz in 1 Hz, 1000 turns) and `gearbif report` run
/// this one function, so their lock-loss and re-lock frequencies and slip rates are the same numbers.
pub fn lock_loss_hysteresis(
    gear: GearParams,
    f_values: &[f64],
    settle_turns: usize,
    observer: &dyn crate::progress::Observer,
) -> Result<Hysteresis> {
    let o = ClassifyOptions {
        settle_turns,
        analysis_turns: 10,
        ..ClassifyOptions::default()
    };
    hysteresis(
        gear.with_parallel_shafts_deg(0.0),
        f_values,
        0.0,
        180.0,
        Convention::Paper,
        &o,
        observer,
    )
}
