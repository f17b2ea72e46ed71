//! Event-driven Filippov integration with an embedded Runge–Kutta pair ([`Tableau`]), its
//! continuous extension, and saltation matrices — shared by the DP5 and DOP853 methods.
//!
//! The augmented state is y = (β, ω, Z) with Z = ∂(β, ω)/∂(β₀, ω₀, p) stored column by column.
//! On a slip piece of side s, Ż = DF_s Z + [0 | ∂F_s/∂p] (variational equation), integrated with the
//! same Runge–Kutta stages as the state ("internal differentiation"); the local error is controlled on
//! (β, ω) and, separately, on Z. Crossings of Σ = {ω = 0} are located on the continuous extension;
//! at each event the saltation matrix S = I + (F₊ − F₋)∇hᵀ/(∇h·F₋) multiplies Z: diag(1, a₊/a₋) at a
//! crossing, diag(1, 0) at stick entry, I at a release with r_s = r (numerics.md). Stick phases are
//! solved directly (the release time is a root of |a(t, β)| − r_s, no integration while stuck).
//! A step rejected across the kink of a friction floored at zero
//! ([`DrivenOscillator::friction_floor`]) is tried again on the branch of its start; the switch is
//! located on the continuous extension, and the step taken again to it (saltation I: the field is
//! continuous).

use super::augmented::{augmented_rhs_law, param_col, z_beta, z_omega, Layout, NMAX};
use super::bernstein;
use super::tableau::{nested, ErrorEstimate, Pair, Tableau, Touch, DMAX, SMAX};
use super::{
    check_interval, Event, EventKind, Flow, FlowOptions, Mode, Sample, Sensitivity, Stats,
};
use crate::error::{Error, Result};
use crate::model::{release_function, DrivenOscillator};
use crate::numerics::Illinois;
use nalgebra::Matrix2;

/// Largest number of coefficients r of the continuous extension.
const RMAX: usize = 4 + DMAX;

/// Integrates `sys` from (t₀, x₀) to t₁ with the pair `P`, searching the continuous extension of
/// each step that may reach Σ for the first point with s·ω ≤ 0 as [`Pair::TOUCH`] says (probes at
/// fixed points, or exactly: catches short slips that start and end inside one step).
///
/// The solver is compiled for each augmented dimension separately (2: the state alone, 6: with
/// the 2×2 state Jacobian, [`NMAX`]: with parameter columns), so the stage combinations of the
/// common cases run over fixed-size arrays with the tableau's coefficients known at compile time.
pub(super) fn integrate<P: Pair, S: DrivenOscillator + ?Sized>(
    sys: &S,
    t0: f64,
    x0: [f64; 2],
    t1: f64,
    opts: &FlowOptions,
) -> Result<Flow> {
    check_interval(t0, x0, t1)?;
    opts.validate()?;
    match opts.sensitivity {
        Sensitivity::None => Solver::<S, P, 2>::new(sys, opts).run(t0, x0, t1),
        Sensitivity::State => Solver::<S, P, 6>::new(sys, opts).run(t0, x0, t1),
        Sensitivity::StateAndParams => Solver::<S, P, NMAX>::new(sys, opts).run(t0, x0, t1),
    }
}

/// Coefficients r₀ … r_{m−1} of the continuous extension of component `i` (module doc of
/// `tableau.rs`); `m` = 4 + rows of d.
#[inline(always)]
fn dense_coeffs<const N: usize>(
    tab: &Tableau,
    i: usize,
    y: &[f64; N],
    yn: &[f64; N],
    k: &[[f64; N]; SMAX],
    hs: f64,
) -> [f64; RMAX] {
    let ydiff = yn[i] - y[i];
    let bspl = hs * k[0][i] - ydiff;
    let mut r = [0.0; RMAX];
    r[0] = y[i];
    r[1] = ydiff;
    r[2] = bspl;
    r[3] = ydiff - hs * k[tab.fsal()][i] - bspl;
    for (row, d) in tab.d.iter().take(tab.dense_rows).enumerate() {
        let mut acc = 0.0;
        for (j, &dj) in d.iter().enumerate().take(tab.total()) {
            if dj != 0.0 {
                acc += dj * k[j][i];
            }
        }
        r[4 + row] = hs * acc;
    }
    r
}

/// y₀ + h Σⱼ wⱼ kⱼ over the first `M` components (the rest zero) and the stages j with a
/// non-zero weight among the first `stages`: a stage argument (w = row i of a) or the solution
/// (w = b). Each component sums over j in ascending order.
#[inline(always)]
fn combine<const N: usize, const M: usize>(
    w: &[f64; SMAX],
    stages: usize,
    y: &[f64; N],
    k: &[[f64; N]; SMAX],
    hs: f64,
) -> [f64; N] {
    let mut acc = [0.0; M];
    for (kj, &wj) in k.iter().zip(w).take(stages) {
        if wj != 0.0 {
            for c in 0..M {
                acc[c] += wj * kj[c];
            }
        }
    }
    let mut out = [0.0; N];
    for c in 0..M {
        out[c] = y[c] + hs * acc[c];
    }
    out
}

/// Σⱼ wⱼ kⱼ over the stages j with a non-zero weight up to the first-same-as-last one (error
/// estimates).
#[inline(always)]
fn weighted_sum<const N: usize>(w: &[f64; SMAX], stages: usize, k: &[[f64; N]; SMAX]) -> [f64; N] {
    let mut acc = [0.0; N];
    for (kj, &wj) in k.iter().zip(w).take(stages) {
        if wj != 0.0 {
            for c in 0..N {
                acc[c] += wj * kj[c];
            }
        }
    }
    acc
}

struct Solver<'a, S: ?Sized, P, const N: usize> {
    sys: &'a S,
    opts: &'a FlowOptions,
    /// Which Jacobian columns are propagated (constant for N = 2 and 6: see [`Self::layout`]).
    layout: Layout,
    stats: Stats,
    events: Vec<Event>,
    samples: Vec<Sample>,
    /// ∂(β, ω)/∂(β₀, ω₀) at each sample (only with a sensitivity).
    sample_jacobians: Vec<Matrix2<f64>>,
    next_sample: usize,
    /// The branch of a floored friction held over the current step
    /// ([`DrivenOscillator::friction_floor`]): `Some(true)` floored, `Some(false)` not, `None`
    /// when the system has no floor.
    held: Option<bool>,
    pair: std::marker::PhantomData<P>,
}

/// Step-size controller state (PI control as in Hairer's DOPRI5/DOP853).
struct Controller {
    /// ln of the previous accepted step's error norm (at least 1e-4).
    ln_facold: f64,
    last_rejected: bool,
}

impl<'a, S: DrivenOscillator + ?Sized, P: Pair, const N: usize> Solver<'a, S, P, N> {
    /// The pair's tableau.
    const TAB: &'static Tableau = &P::TAB;

    fn new(sys: &'a S, opts: &'a FlowOptions) -> Self {
        let layout = Layout::new(sys, opts.sensitivity);
        debug_assert!(layout.dim() <= N);
        Self {
            sys,
            opts,
            layout,
            stats: Stats::default(),
            events: Vec::new(),
            samples: Vec::with_capacity(opts.sample_times.len()),
            sample_jacobians: Vec::new(),
            next_sample: 0,
            held: None,
            pair: std::marker::PhantomData,
        }
    }

    /// The layout; a compile-time constant for the state alone (N = 2) and the state Jacobian
    /// (N = 6), so the right-hand side of those is specialised.
    #[inline(always)]
    fn layout(&self) -> Layout {
        match N {
            2 => Layout::STATE,
            6 => Layout {
                ncols: 2,
                with_params: false,
            },
            _ => self.layout,
        }
    }

    /// Number of components carried (N, or the layout's dimension for the parameter columns).
    #[inline(always)]
    fn dim(&self) -> usize {
        if N <= 6 {
            N
        } else {
            self.layout.dim()
        }
    }

    #[inline(always)]
    fn rhs<const H: bool>(
        &mut self,
        layout: Layout,
        t: f64,
        y: &[f64; N],
        s: f64,
        out: &mut [f64; N],
    ) {
        self.stats.rhs_evals += 1;
        // `H`: on the held branch of a floored friction (a compile-time switch: reading the
        // branch at run time in every evaluation cost 17–20 % of a diagnosis's CPU, docs/performance.md)
        let held = if H { self.held } else { None };
        augmented_rhs_law(self.sys, layout, t, y, s, 0.0, held, out);
    }

    /// [`Self::rhs`] on the held branch when there is one.
    fn rhs_any(&mut self, layout: Layout, t: f64, y: &[f64; N], s: f64, out: &mut [f64; N]) {
        if self.held.is_some() {
            self.rhs::<true>(layout, t, y, s, out);
        } else {
            self.rhs::<false>(layout, t, y, s, out);
        }
    }

    fn record_event(&mut self, t: f64, beta: f64, kind: EventKind) {
        self.stats.events += 1;
        if self.opts.record_events {
            self.events.push(Event { t, beta, kind });
        }
    }

    /// Records the samples in (.., t] of a constant state `y` (stick phases: ω = 0, and the
    /// Jacobian columns, after the stick-entry saltation, constant too).
    fn samples_constant(&mut self, t: f64, y: &[f64; N]) {
        while let Some(&ts) = self.opts.sample_times.get(self.next_sample) {
            if ts > t {
                break;
            }
            self.samples.push(Sample {
                t: ts,
                beta: y[0],
                omega: 0.0,
            });
            if let Some(jx) = self.layout.state_jacobian(y) {
                self.sample_jacobians.push(jx);
            }
            self.next_sample += 1;
        }
    }

    /// The stages after the first-same-as-last one that only the continuous extension uses,
    /// over the first M components: the state alone (M = 2) or everything (M = N).
    fn dense_stages<const M: usize, const H: bool>(
        &mut self,
        layout: Layout,
        t: f64,
        hs: f64,
        y: &[f64; N],
        s: f64,
        k: &mut [[f64; N]; SMAX],
    ) {
        let tab = Self::TAB;
        for i in tab.fsal() + 1..tab.total() {
            let ys = combine::<N, M>(&tab.a[i], i, y, k, hs);
            self.rhs::<H>(layout, t + tab.c[i] * hs, &ys, s, &mut k[i]);
        }
    }

    /// One Runge–Kutta step of size `hs` from (t, y) on side `s`: the main stages, the solution
    /// y₁ (written to `yn`) and the scaled error norm. Also returns min s·ω over the stage
    /// arguments and max |ω̇| over the stages, for the test whether the step can reach Σ.
    fn step<const H: bool>(
        &mut self,
        t: f64,
        hs: f64,
        y: &[f64; N],
        s: f64,
        k: &mut [[f64; N]; SMAX],
        yn: &mut [f64; N],
    ) -> StepInfo {
        let tab = Self::TAB;
        let layout = self.layout();
        let mut wmin = s * y[1];
        let mut dmax = k[0][1].abs();
        let mut ys = [0.0; N];
        for i in 1..tab.stages {
            ys = combine::<N, N>(&tab.a[i], i, y, k, hs);
            wmin = wmin.min(s * ys[1]);
            self.rhs::<H>(layout, t + tab.c[i] * hs, &ys, s, &mut k[i]);
            dmax = dmax.max(k[i][1].abs());
        }
        if tab.last_stage_is_solution {
            *yn = ys;
        } else {
            *yn = combine::<N, N>(&tab.b, tab.stages, y, k, hs);
        }
        wmin = wmin.min(s * yn[1]);
        let err = self.error_norm(hs, y, yn, k);
        StepInfo { err, wmin, dmax }
    }

    /// Scaled local error: RMS over the state (β, ω) and, separately, over the Jacobian columns;
    /// the larger counts. Controlling the variational part too matters: on an exactly
    /// representable orbit (the locked state) the state error vanishes while the variational
    /// equation oscillates at √g and would be left unresolved.
    fn error_norm(&self, hs: f64, y: &[f64; N], yn: &[f64; N], k: &[[f64; N]; SMAX]) -> f64 {
        let tab = Self::TAB;
        let n = self.dim();
        let main = weighted_sum(&tab.e, tab.fsal() + 1, k);
        let low = match &tab.estimate {
            ErrorEstimate::Dop853 { e3 } => weighted_sum(e3, tab.fsal() + 1, k),
            ErrorEstimate::Single => [0.0; N],
        };
        // [state, Jacobian] sums of the main and (DOP853) the 3rd-order estimate
        let mut e_main = [0.0; 2];
        let mut e_low = [0.0; 2];
        for i in 0..n {
            let scale = if i == 0 {
                // β lives on the lift: measure its error in radians, not relative to windings
                self.opts.atol + self.opts.rtol
            } else {
                self.opts.atol + self.opts.rtol * y[i].abs().max(yn[i].abs())
            };
            let part = usize::from(i >= 2);
            e_main[part] += (main[i] / scale).powi(2);
            if let ErrorEstimate::Dop853 { .. } = &tab.estimate {
                e_low[part] += (low[i] / scale).powi(2);
            }
        }
        let norm = |part: usize, count: f64| -> f64 {
            match tab.estimate {
                ErrorEstimate::Single => hs * (e_main[part] / count).sqrt(),
                ErrorEstimate::Dop853 { .. } => {
                    let mut deno = e_main[part] + 0.01 * e_low[part];
                    if deno <= 0.0 {
                        deno = 1.0;
                    }
                    hs * e_main[part] * (1.0 / (deno * count)).sqrt()
                }
            }
        };
        let mut err = norm(0, 2.0);
        if n > 2 {
            err = err.max(norm(1, (n - 2) as f64));
        }
        err
    }

    /// Integrates from (t₀, x₀) to t₁: adaptive steps on the slip side of the current mode,
    /// each that may reach Σ (or holds a sample) resolved on its continuous extension, with the
    /// event handling at Σ and the stick phases solved directly.
    fn run(mut self, t0: f64, x0: [f64; 2], t1: f64) -> Result<Flow> {
        let tab = Self::TAB;
        let period = self.sys.period();
        let hmax = self.opts.max_step_fraction * period;
        let (mut y, mut mode) = self.start(t0, x0);
        let mut t = t0;
        let mut h = (period / 100.0)
            .min(hmax)
            .min((t1 - t0).max(f64::MIN_POSITIVE));
        let mut k = [[0.0; N]; SMAX];
        let mut fsal = false;
        let mut ctl = Controller {
            ln_facold: 1e-4_f64.ln(),
            last_rejected: false,
        };
        let mut guard = ZenoGuard::new(period);
        // the step being tried ends where a floored friction switches; switches at the very
        // start of a step in a row (a branch taken at ρ ≈ 0 the wrong way)
        let (mut to_switch, mut flips) = (false, 0usize);

        while t < t1 {
            if self.stats.steps + self.stats.rejected > self.opts.max_steps {
                return Err(Error::StepBudget {
                    t,
                    max_steps: self.opts.max_steps,
                });
            }
            if mode == Mode::Stick {
                let Some((tr, s)) = self.stick_phase(t, &mut y, t1, guard.degenerate()) else {
                    t = t1;
                    break;
                };
                guard.record(
                    tr,
                    "events repeat without progress (stick/slip chattering at a degenerate point)",
                )?;
                t = tr;
                mode = Mode::from_side(s);
                fsal = false;
                self.held = None;
                continue;
            }

            let s = mode.side();
            if !fsal {
                self.rhs_any(self.layout(), t, &y, s, &mut k[0]);
                fsal = true;
            }
            let tn = step_end(t, h, hmax, t1)?;
            let hs = tn - t;
            let mut yn = [0.0; N];
            let info = if self.held.is_some() {
                self.step::<true>(t, hs, &y, s, &mut k, &mut yn)
            } else {
                self.step::<false>(t, hs, &y, s, &mut k, &mut yn)
            };
            let hnew = match self.judge(&mut ctl, info.err, &yn, t, hs, period)? {
                Verdict::Accept(hnew) => hnew,
                Verdict::Retry(hretry) => {
                    to_switch = false;
                    // a rejected step across a switch of a floored friction is tried again at
                    // its size on the branch of its start (the forces there are the same, and
                    // so is the first stage)
                    if self.held.is_none() {
                        if let Some(floored) = self.straddled_floor(t, &y, tn, &yn) {
                            self.held = Some(floored);
                            // (the same forces at the start, but the first stage's derivatives
                            // differ there when ρ = 0 exactly)
                            fsal = false;
                            continue;
                        }
                    }
                    h = hretry;
                    continue;
                }
            };
            if !tab.last_stage_is_solution {
                self.rhs_any(self.layout(), tn, &yn, s, &mut k[tab.fsal()]);
            }
            // On a held branch: does the floor switch inside the step? Then the step is taken
            // again to the switch (the held branch is smooth up to it), and the forces are
            // released from the branch there; a switch at the very start means the branch was
            // taken the wrong way at ρ ≈ 0: it changes at once and the step is taken again.
            let at_switch = std::mem::take(&mut to_switch);
            if let (Some(floored), false) = (self.held, at_switch) {
                if let Some(th) = self.floor_switch(t, hs, &y, &yn, s, &mut k, floored) {
                    self.stats.rejected += 1;
                    if th > FLOOR_SWITCH_AT_START && t + th * hs > t {
                        h = th * hs;
                        to_switch = true;
                        continue;
                    }
                    if flips < 2 {
                        flips += 1;
                        self.held = Some(!floored);
                        fsal = false;
                        continue;
                    }
                }
            }
            flips = 0;
            self.stats.steps += 1;
            let held = self.held;

            // Can ω reach 0 inside the step? The continuous extension (with the extra dense
            // stages of a high-order pair) is formed and probed only when s·ω over the stage
            // arguments and the end points is not larger than g·h·max|ω̇| over the stages, g the
            // largest gap between the sorted nodes (between two points where s·ω ≥ w, a function
            // with |ω̇| ≤ M stays above w − M g h/2: the bound with a factor 2 of margin on M), or
            // when a sample falls inside the step.
            let sample_inside = self
                .opts
                .sample_times
                .get(self.next_sample)
                .is_some_and(|&ts| ts <= tn);
            let near_sigma = info.wmin <= tab.node_gap * hs * info.dmax;
            if near_sigma || sample_inside {
                // on the held branch if the step was taken on it
                let dense_step = if held.is_some() {
                    Self::dense_step::<true>
                } else {
                    Self::dense_step::<false>
                };
                let crossing = dense_step(
                    &mut self,
                    t,
                    hs,
                    tn,
                    &y,
                    &yn,
                    s,
                    &mut k,
                    near_sigma,
                    sample_inside,
                );
                if let Some((tc, mut yc)) = crossing {
                    self.held = None;
                    guard.record(
                        tc,
                        "events repeat without progress (degenerate contact with ω = 0)",
                    )?;
                    mode = self.handle_arrival(tc, &mut yc, s, guard.degenerate());
                    y = yc;
                    t = tc;
                    fsal = false;
                    h = hnew.max(hs * 0.5);
                    continue;
                }
            }

            // no event: accept the whole step. A step to a switch hands over to the other
            // branch for one step (at the switch ρ is 0 up to the local error, and the forces
            // as they are would take their derivatives from either side by rounding); any other
            // step on a held branch to the forces as they are. The first stage is evaluated
            // again after a held step (it holds the derivatives of the branch left behind, or,
            // after two flips in a row, of a branch taken past its switch).
            self.held = match held {
                Some(floored) if at_switch => Some(!floored),
                _ => None,
            };
            y = yn;
            k[0] = k[tab.fsal()];
            t = tn;
            h = hnew;
            if held.is_some() {
                fsal = false;
            }
        }
        Ok(self.finish(t, y, mode))
    }

    /// The start at (t₀, x₀): skips the samples before t₀ and returns the augmented state (the
    /// Jacobian columns from [`Layout::init`]) and the initial mode; a start that sticks has
    /// ω = 0 and the stick-entry saltation applied.
    fn start(&mut self, t0: f64, x0: [f64; 2]) -> ([f64; N], Mode) {
        let mut y = [0.0; N];
        self.layout.init(x0, &mut y);
        self.next_sample += self.opts.sample_times[self.next_sample..]
            .iter()
            .take_while(|&&ts| ts < t0)
            .count();
        let mode = super::initial_mode(self.sys, t0, x0);
        if mode == Mode::Stick {
            y[1] = 0.0;
            self.stick_saltation(&mut y);
        }
        (y, mode)
    }

    /// Accepts or rejects the step of size `hs` from t with error norm `err` and solution `yn`:
    /// a non-finite result is retried at a tenth of the step, an error norm above 1 at the
    /// controller's smaller step ([`Self::propose`] gives the next step of an accepted one);
    /// an error when the step underflows.
    fn judge(
        &mut self,
        ctl: &mut Controller,
        err: f64,
        yn: &[f64; N],
        t: f64,
        hs: f64,
        period: f64,
    ) -> Result<Verdict> {
        let tab = Self::TAB;
        if !err.is_finite() || !yn[0].is_finite() || !yn[1].is_finite() {
            if hs < 1e-14 * period {
                return Err(Error::Integration {
                    t,
                    reason: "non-finite state".into(),
                });
            }
            self.stats.rejected += 1;
            ctl.last_rejected = true;
            return Ok(Verdict::Retry(hs * 0.1));
        }
        let Some(hnew) = self.propose(ctl, err, hs) else {
            let h = hs / (tab.pow_expo(err) / 0.9).min(tab.fac_max);
            self.stats.rejected += 1;
            if h < 1e-15 * period.max(t.abs()) {
                return Err(Error::Integration {
                    t,
                    reason: format!("step size underflow (h = {h:e})"),
                });
            }
            return Ok(Verdict::Retry(h));
        };
        Ok(Verdict::Accept(hnew))
    }

    /// An accepted step from (t, y) to (tn, yn), hs = tn − t, on side `s` that may reach Σ
    /// (`near_sigma`) or holds a sample (`sample_inside`), on its continuous extension: the first
    /// point with s·ω ≤ 0 ([`Self::find_crossing`]) if `near_sigma`; with one at tc, the samples before tc
    /// and (tc, y(tc)) with the Jacobian columns interpolated and ω = 0 (the arrival is not yet
    /// handled); without, the samples in (t, tn] and `None`.
    #[allow(clippy::too_many_arguments)]
    fn dense_step<const H: bool>(
        &mut self,
        t: f64,
        hs: f64,
        tn: f64,
        y: &[f64; N],
        yn: &[f64; N],
        s: f64,
        k: &mut [[f64; N]; SMAX],
        near_sigma: bool,
        sample_inside: bool,
    ) -> Option<(f64, [f64; N])> {
        let tab = Self::TAB;
        // the Jacobian columns at samples need the extra dense stages over every component
        let jac_at_samples = self.layout().ncols > 0 && sample_inside;
        if tab.dense_extra > 0 {
            if jac_at_samples {
                self.dense_stages::<N, H>(self.layout(), t, hs, y, s, k);
            } else {
                self.dense_stages::<2, H>(Layout::STATE, t, hs, y, s, k);
            }
        }
        let state_coeffs = [
            dense_coeffs(tab, 0, y, yn, k, hs),
            dense_coeffs(tab, 1, y, yn, k, hs),
        ];
        let m = 4 + tab.dense_rows;
        let dense_state = |i: usize, th: f64| -> f64 { nested(&state_coeffs[i][..m], th) };
        // ∂(β, ω)/∂(β₀, ω₀) on the continuous extension (the state columns: components 2..6)
        let layout = self.layout;
        let jac_coeffs: Option<[[f64; RMAX]; 6]> = jac_at_samples.then(|| {
            std::array::from_fn(|i| {
                if i < 2 {
                    [0.0; RMAX]
                } else {
                    dense_coeffs(tab, i, y, yn, k, hs)
                }
            })
        });
        let dense_jac = jac_coeffs.as_ref().map(|c| {
            move |th: f64| -> Option<Matrix2<f64>> {
                let z: [f64; 6] = std::array::from_fn(|i| nested(&c[i][..m], th));
                layout.state_jacobian(&z)
            }
        });

        let root = if near_sigma {
            self.find_crossing(s, y, yn, &state_coeffs[1][..m], &dense_state)
        } else {
            None
        };
        let Some(thc) = root else {
            self.samples_dense(t, hs, tn, &dense_state, dense_jac.as_ref(), true);
            return None;
        };
        let tc = t + thc * hs;
        // samples strictly before the event from the continuous extension
        self.samples_dense(t, hs, tc, &dense_state, dense_jac.as_ref(), false);
        if tab.dense_extra > 0 && self.layout().ncols > 0 && !jac_at_samples {
            self.dense_stages::<N, H>(self.layout(), t, hs, y, s, k);
        }
        let mut yc = [0.0; N];
        yc[0] = dense_state(0, thc);
        for (i, v) in yc.iter_mut().enumerate().take(self.dim()).skip(2) {
            *v = nested(&dense_coeffs(tab, i, y, yn, k, hs)[..m], thc);
        }
        yc[1] = 0.0;
        Some((tc, yc))
    }

    /// The flow at the end (t, y) in `mode`: the samples left while stuck, the Jacobians, the
    /// events, samples and counts.
    fn finish(mut self, t: f64, y: [f64; N], mode: Mode) -> Flow {
        if self.next_sample < self.opts.sample_times.len() && mode == Mode::Stick {
            self.samples_constant(t, &y);
        }
        let (jac_x, jac_p) = self.layout.jacobians(&y);
        Flow {
            t,
            x: [y[0], y[1]],
            mode,
            jac_x,
            jac_p,
            events: self.events,
            samples: self.samples,
            sample_jacobians: self.sample_jacobians,
            stats: self.stats,
        }
    }

    /// Step-size proposal after an error norm `err` for step `hs` (PI control as in Hairer's
    /// codes): `None` if the step is rejected, else the next step size.
    fn propose(&self, ctl: &mut Controller, err: f64, hs: f64) -> Option<f64> {
        let tab = Self::TAB;
        if err > 1.0 {
            ctl.last_rejected = true;
            return None;
        }
        // fac = err^expo / facold^β as one exponential (two powers cost twice as much)
        let ln_err = err.ln();
        let mut fac = (tab.expo * ln_err - tab.beta * ctl.ln_facold).exp();
        fac = (fac / 0.9).clamp(tab.fac_min, tab.fac_max);
        let mut hnew = hs / fac;
        ctl.ln_facold = ln_err.max(1e-4_f64.ln());
        if ctl.last_rejected {
            hnew = hnew.min(hs);
        }
        ctl.last_rejected = false;
        Some(hnew)
    }

    /// A stick phase from t: records its samples and the release event, applies the release
    /// saltation, and returns (release time, side) or `None` if stuck until t₁.
    fn stick_phase(
        &mut self,
        t: f64,
        y: &mut [f64; N],
        t1: f64,
        nudge: bool,
    ) -> Option<(f64, f64)> {
        let sys = self.sys;
        let beta = y[0];
        let from = if nudge { t + 1e-9 * sys.period() } else { t };
        match sys.next_release(from, beta, t1) {
            None => {
                self.samples_constant(t1, y);
                None
            }
            Some(tr) => {
                let tr = tr.max(t);
                self.samples_constant(tr, y);
                let f = sys.forces(tr, beta, 0.0);
                let s = if f.a >= 0.0 { 1.0 } else { -1.0 };
                // the output leaves with a − s r; zero for r_s = r(t, β, 0) (tangential release)
                let jump = f.a - s * f.r;
                if jump != 0.0 && self.layout.ncols > 0 {
                    self.release_saltation(y, tr, jump, s);
                }
                self.record_event(tr, beta, EventKind::Release { to: s as i8 });
                Some((tr, s))
            }
        }
    }

    /// The branch at (t, y) of a floored friction ([`DrivenOscillator::friction_floor`]; `true`:
    /// floored, ρ ≤ 0) when ρ lies on the other side at (tn, yn), else `None` (no floor, or no
    /// switch between the ends).
    #[cold]
    #[inline(never)]
    fn straddled_floor(&self, t: f64, y: &[f64; N], tn: f64, yn: &[f64; N]) -> Option<bool> {
        let r0 = self.sys.friction_floor(t, y[0], y[1])?;
        let r1 = self.sys.friction_floor(tn, yn[0], yn[1])?;
        // from ρ = 0 exactly towards ρ > 0: the unfloored branch
        ((r0 <= 0.0) != (r1 <= 0.0)).then_some(r0 < 0.0)
    }

    /// Where in an accepted step from (t, y) to (tn, yn), hs = tn − t, on side `s` the floor of
    /// the friction switches away from the held branch (`floored`: ρ ≤ 0 held): `None` when ρ at
    /// the step's end is still on it (a step in which ρ leaves the branch and comes back is not
    /// seen); else the first θ ∈ [0, 1] on the continuous extension of the state with ρ on the
    /// other side (probes at eighths of the step, then Illinois regula falsi to the last bits).
    #[allow(clippy::too_many_arguments)]
    #[cold]
    #[inline(never)]
    fn floor_switch(
        &mut self,
        t: f64,
        hs: f64,
        y: &[f64; N],
        yn: &[f64; N],
        s: f64,
        k: &mut [[f64; N]; SMAX],
        floored: bool,
    ) -> Option<f64> {
        let sys = self.sys;
        // positive (or zero) on the held branch, negative beyond the switch
        let held_side = |rho: f64| if floored { -rho } else { rho };
        let switched = |e: f64| if floored { e < 0.0 } else { e <= 0.0 };
        let e_end = held_side(sys.friction_floor(t + hs, yn[0], yn[1])?);
        if !switched(e_end) {
            return None;
        }
        let tab = Self::TAB;
        if tab.dense_extra > 0 {
            self.dense_stages::<2, true>(Layout::STATE, t, hs, y, s, k);
        }
        let m = 4 + tab.dense_rows;
        let coeffs = [
            dense_coeffs(tab, 0, y, yn, k, hs),
            dense_coeffs(tab, 1, y, yn, k, hs),
        ];
        let e = |th: f64| -> f64 {
            let (b, w) = (nested(&coeffs[0][..m], th), nested(&coeffs[1][..m], th));
            sys.friction_floor(t + th * hs, b, w).map_or(0.0, held_side)
        };
        let e_start = e(0.0).max(0.0);
        let (mut lo, mut flo) = (0.0, e_start);
        let (mut hi, mut fhi) = (1.0, e_end);
        for j in 1..FLOOR_PROBES {
            let th = j as f64 / FLOOR_PROBES as f64;
            let ej = e(th);
            if switched(ej) {
                (hi, fhi) = (th, ej);
                break;
            }
            (lo, flo) = (th, ej);
        }
        // (a switch at the start is taken there: no need to resolve it further)
        let signed = |th: f64| {
            let v = e(th);
            if switched(v) {
                v.min(0.0)
            } else {
                v.max(f64::MIN_POSITIVE)
            }
        };
        let root = Illinois::new(lo, flo, hi, fhi.min(0.0), 0.0);
        Some(refine(root, signed, FLOOR_SWITCH_AT_START))
    }

    /// The first θ ∈ (0, 1] of the step with s·ω(θ) ≤ 0 on the continuous extension (nested
    /// coefficients `coeffs` of ω), bracketed as [`Pair::TOUCH`] says: the first probe with
    /// s·ω ≤ 0, or exactly from the Bernstein form of s·ω (`bernstein.rs`: convex hull and
    /// Descartes' rule, de Casteljau splitting), which also finds a touch of Σ between any two
    /// points of the step; then Illinois regula falsi on the bracket.
    fn find_crossing<F: Fn(usize, f64) -> f64>(
        &self,
        s: f64,
        y: &[f64; N],
        yn: &[f64; N],
        coeffs: &[f64],
        dense: &F,
    ) -> Option<f64> {
        let e = |th: f64| -> f64 { s * dense(1, th) };
        let root = if let Touch::Probes(probes) = P::TOUCH {
            let mut root: Option<(f64, f64)> = None;
            let mut th_prev = 0.0;
            for j in 1..=probes {
                let th = j as f64 / probes as f64;
                let ev = if j == probes { s * yn[1] } else { e(th) };
                if ev <= 0.0 {
                    root = Some((th_prev, th));
                    break;
                }
                th_prev = th;
            }
            root
        } else {
            let (mut b, d) = bernstein::from_nested(coeffs, s);
            // the end coefficients are the end values: the same numbers as the state's
            b[0] = s * y[1];
            b[d] = s * yn[1];
            bernstein::first_zero(&b, d)
        };
        let (lo, hi) = root?;
        // bracket: e(lo) > 0 (or lo = 0, the start), e(hi) ≤ 0; refined by Illinois regula falsi
        let mut flo = if lo == 0.0 { s * y[1] } else { e(lo) };
        let fhi = if hi == 1.0 { s * yn[1] } else { e(hi) };
        if flo <= 0.0 {
            // starts on Σ (just after an event) and the sign is wrong at once
            flo = 0.0;
        }
        Some(refine(Illinois::new(lo, flo, hi, fhi, 0.0), e, 0.0))
    }

    /// Records the requested samples in (t, t_end) (or (t, t_end] when `inclusive`) from the
    /// continuous extension.
    /// With `jac`, also the state Jacobian at each sample from the continuous extension of the
    /// Jacobian columns.
    fn samples_dense<F: Fn(usize, f64) -> f64, J: Fn(f64) -> Option<Matrix2<f64>>>(
        &mut self,
        t: f64,
        hs: f64,
        t_end: f64,
        dense: &F,
        jac: Option<&J>,
        inclusive: bool,
    ) {
        while let Some(&ts) = self.opts.sample_times.get(self.next_sample) {
            if ts > t_end || (!inclusive && ts >= t_end) {
                break;
            }
            let th = ((ts - t) / hs).clamp(0.0, 1.0);
            self.samples.push(Sample {
                t: ts,
                beta: dense(0, th),
                omega: dense(1, th),
            });
            if let Some(j) = jac.and_then(|j| j(th)) {
                self.sample_jacobians.push(j);
            }
            self.next_sample += 1;
        }
    }

    /// Decides what happens when ω reaches 0 from side `s` at time `tc`, applies the saltation
    /// matrix to the Jacobian columns, records the event, and returns the new mode.
    fn handle_arrival(&mut self, tc: f64, y: &mut [f64; N], s: f64, force_stick: bool) -> Mode {
        let beta = y[0];
        match arrival(self.sys, tc, beta, s, force_stick) {
            Arrival::Stick => {
                self.stick_saltation(y);
                self.record_event(tc, beta, EventKind::StickStart);
                Mode::Stick
            }
            Arrival::Graze => {
                self.record_event(tc, beta, EventKind::Graze { side: s as i8 });
                Mode::from_side(s)
            }
            Arrival::Cross { to, ratio } => {
                for c in 0..self.layout.ncols {
                    y[z_omega(c)] *= ratio;
                }
                self.record_event(
                    tc,
                    beta,
                    EventKind::Crossing {
                        from: s as i8,
                        to: to as i8,
                    },
                );
                Mode::from_side(to)
            }
        }
    }

    /// Stick entry: S = diag(1, 0) (the sliding field vanishes).
    fn stick_saltation(&self, y: &mut [f64; N]) {
        for c in 0..self.layout.ncols {
            y[z_omega(c)] = 0.0;
        }
    }

    /// Release with a jump of the acceleration (static friction above sliding friction):
    /// Z₊ = Z₋ − F₊ dt_r/dz, with dt_r/dz = −(G_β Z_β + G_p)/G_t from G(t, β) = |a| − r_s = 0.
    fn release_saltation(&self, y: &mut [f64; N], tr: f64, jump: f64, s: f64) {
        let sys = self.sys;
        let beta = y[0];
        let Some((gt, gb)) = release_gradient(sys, tr, beta) else {
            return;
        };
        let jet = sys.forces_jet(tr, beta, 0.0, self.layout.with_params);
        for c in 0..self.layout.ncols {
            let mut gz = gb * y[z_beta(c)];
            if c >= param_col(0) {
                // ∂G/∂p = sgn(a) ∂a/∂p − ∂r_s/∂p, taking ∂r_s/∂p = ∂r/∂p
                let k = c - param_col(0);
                gz += s * jet.a_p[k] - jet.r_p[k];
            }
            let dt = -gz / gt;
            // F₊ − F₋ = (0, jump)
            y[z_omega(c)] -= jump * dt;
        }
    }
}

/// The end of the next step from t: t + h with h at most `hmax`, or t₁ when that reaches it;
/// an error when the step underflows.
#[inline]
fn step_end(t: f64, h: f64, hmax: f64, t1: f64) -> Result<f64> {
    let hh = h.min(hmax).min(t1 - t);
    let last = hh >= t1 - t;
    let tn = if last { t1 } else { t + hh };
    let hs = tn - t;
    if hs <= 0.0 || !hs.is_finite() {
        return Err(Error::Integration {
            t,
            reason: format!("step size underflow (h = {hs:e})"),
        });
    }
    Ok(tn)
}

/// The bracket `root` of a root of `e` on a step's continuous extension (θ ∈ [0, 1]) refined by
/// Illinois regula falsi to the last bits of θ, or until its high end is at most `at_start`;
/// returns the high end (the first point past the root).
pub(super) fn refine(mut root: Illinois, e: impl Fn(f64) -> f64, at_start: f64) -> f64 {
    for _ in 0..200 {
        if root.hi() - root.lo() <= 4.0 * f64::EPSILON * root.hi().max(1e-300)
            || root.hi() <= at_start
        {
            break;
        }
        let Some(mid) = root.next_point() else {
            break;
        };
        root.update(mid, e(mid));
    }
    root.hi()
}

/// Probes per step of the search for a switch of the friction's floor
/// ([`Solver::floor_switch`]): the first probe past the switch brackets it.
const FLOOR_PROBES: usize = 8;

/// A switch of the friction's floor within this fraction of a step from its start is taken at
/// the start: the held branch was the wrong one at ρ ≈ 0, and the step is taken again on the
/// other (its piece on the wrong branch, ≤ 10⁻⁶ of the step, leaves an error in ω of order
/// |ρ̇| (10⁻⁶ h)²).
const FLOOR_SWITCH_AT_START: f64 = 1e-6;

/// Whether a step is accepted, with the next step size, or retried with a smaller one.
enum Verdict {
    /// Accepted; the next step size.
    Accept(f64),
    /// Rejected; the step size to retry with.
    Retry(f64),
}

/// What one step reports besides its solution.
struct StepInfo {
    /// Scaled local error norm.
    err: f64,
    /// Smallest s·ω over the start, the stage arguments and the end.
    wmin: f64,
    /// Largest |ω̇| over the stages.
    dmax: f64,
}

/// Guard against Zeno-like repetition of events without progress: events closer than
/// 10⁻¹³ T to the previous one count as a stall; more than 8 in a row mark the point degenerate
/// (the event handlers then take the degenerate branch), more than 16 are an error.
/// What an arrival on Σ = {ω = 0} from side `s` at (t, β) is under the Filippov convention
/// ([`arrival`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Arrival {
    /// |a| ≤ r_s (or a stick forced at a degenerate point): saltation diag(1, 0).
    Stick,
    /// a points back to side s (a tangency): no switch, saltation I.
    Graze,
    /// A crossing to side `to`: saltation diag(1, `ratio`), ratio = a₊/a₋ with a± = a − s± r.
    Cross {
        /// The new side, ±1.
        to: f64,
        /// a₊/a₋.
        ratio: f64,
    },
}

/// The Filippov rule at an arrival on Σ from side `s` at time `tc` and angle `beta`: stick while
/// |a(tc, β, 0)| ≤ r_s(tc, β) (or when `force_stick`), a graze when a keeps the sign of s, else a
/// crossing with the ratio of the accelerations after and before. Shared by every event-driven
/// method (the Runge–Kutta pairs here, the Taylor method).
pub(super) fn arrival<S: DrivenOscillator + ?Sized>(
    sys: &S,
    tc: f64,
    beta: f64,
    s: f64,
    force_stick: bool,
) -> Arrival {
    let f = sys.forces(tc, beta, 0.0);
    if f.a.abs() <= sys.static_friction(tc, beta) || force_stick {
        return Arrival::Stick;
    }
    let to = if f.a > 0.0 { 1.0 } else { -1.0 };
    if to == s {
        return Arrival::Graze;
    }
    Arrival::Cross {
        to,
        ratio: (f.a - to * f.r) / (f.a - s * f.r),
    }
}

/// (G_t, G_β) of the release function G(t, β) = |a| − r_s at a release (tr, β), by central
/// differences (steps 1e-7 T and 1e-7 rad); `None` where G_t is 0 or not finite (no jump
/// saltation then). The release saltation's dt_r/dz = −G_β Z_β / G_t of every event-driven method.
pub(super) fn release_gradient<S: DrivenOscillator + ?Sized>(
    sys: &S,
    tr: f64,
    beta: f64,
) -> Option<(f64, f64)> {
    let (ht, hb) = (1e-7 * sys.period(), 1e-7);
    let gt =
        (release_function(sys, tr + ht, beta) - release_function(sys, tr - ht, beta)) / (2.0 * ht);
    let gb =
        (release_function(sys, tr, beta + hb) - release_function(sys, tr, beta - hb)) / (2.0 * hb);
    (gt != 0.0 && gt.is_finite()).then_some((gt, gb))
}

pub(super) struct ZenoGuard {
    stalled: usize,
    last_event_t: f64,
    tiny: f64,
}

impl ZenoGuard {
    pub(super) fn new(period: f64) -> Self {
        Self {
            stalled: 0,
            last_event_t: f64::NEG_INFINITY,
            tiny: 1e-13 * period.max(1e-300),
        }
    }

    /// Records an event at `t`; an error with `reason` after more than 16 stalls in a row.
    pub(super) fn record(&mut self, t: f64, reason: &str) -> Result<()> {
        if t - self.last_event_t <= self.tiny {
            self.stalled += 1;
        } else {
            self.stalled = 0;
        }
        if self.stalled > 16 {
            return Err(Error::Integration {
                t,
                reason: reason.into(),
            });
        }
        self.last_event_t = t;
        Ok(())
    }

    /// Whether the current point is degenerate (more than 8 stalls in a row).
    pub(super) fn degenerate(&self) -> bool {
        self.stalled > 8
    }
}
