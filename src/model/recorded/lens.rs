//! The recorded gear as a continuable system: [`RecordedModel`] drives the force law of
//! [`RecordedGear`] uniformly, α = α₀ + 2π f t, and names every parameter the diagnosis can find
//! ([`RecordedParam`], the lens of [`Parametrised`]).
//!
//! **Columns.** The lens names 24 parameters but a map's parameter Jacobian holds at most
//! [`MAX_PARAMS`] columns. A model therefore carries an *active set* of at most that many
//! parameters ([`RecordedModel::with_columns`]; by default f, g, Δ, ζ, η): the jet computes the
//! analytic derivative of every parameter ([`RecordedModel::param_forces`]) and hands out the
//! active ones, so [`Parametrised::column`] is `Some` exactly for the active parameters. A
//! command that continues a parameter activates it first ([`RecordedModel::with_column`]).
//! [`crate::model::Gear`] and its hot path are untouched.
//!
//! The derivatives are those of the equation of the parent module: with the input magnet at
//! α_in = α + ε + χ τ_in(α_in, β), dα_in/dα = dα_in/dε = κ = 1/(1 − χ ∂τ_in/∂α_in),
//! dα_in/dχ = τ_in κ and dα_in/dc = χ κ ∂τ_in/∂c for a coupling coefficient c, so that
//! ∂a/∂p = ∂a/∂p|_{α_in} + (∂a/∂α_in) dα_in/dp; g and Δ enter as c_sc = −g, c_cs = gΔ.

use super::{drag, load_shape_alpha, Coefficients, Geometry, InputBend, RecordedGear};
use super::{ExtraTerm, DRAG_REFERENCE_SPEED, STRIBECK_POWER};
use crate::error::{finite, non_negative, positive, Error, Result};
use crate::model::params::{Column, Parameter, Parametrised};
use crate::model::{DrivenOscillator, Forces, ForcesJet, HalfPeriodSymmetry, MAX_PARAMS};
use crate::numerics::trig::sin_cos;
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};

/// A parameter of the recorded gear (every term the diagnosis can find; per unit inertia).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RecordedParam {
    /// Drive frequency f, Hz (α = α₀ + 2π f t).
    F,
    /// Coupling g = −c_sc, s⁻².
    G,
    /// Shaft index Δ = c_cs/g.
    Delta,
    /// Coupling coefficient c_cc of cos α cos β, s⁻².
    CouplingCc,
    /// Coupling coefficient c_ss of sin α sin β, s⁻².
    CouplingSs,
    /// Viscous damping ζ, s⁻¹.
    Zeta,
    /// Dry friction η, s⁻².
    Eta,
    /// Static torque A of A sin β, s⁻².
    StaticA,
    /// Static torque B of B cos β, s⁻².
    StaticB,
    /// Static torque A₂ of A₂ sin 2β, s⁻².
    StaticA2,
    /// Static torque B₂ of B₂ cos 2β, s⁻².
    StaticB2,
    /// Static torque A₃ of A₃ sin 3β, s⁻².
    StaticA3,
    /// Static torque B₃ of B₃ cos 3β, s⁻².
    StaticB3,
    /// Drag q of −q (|β̇|/V)^p sgn β̇ (the drag at V = 4 rad/s), s⁻².
    DragQ,
    /// Drag exponent p, in [0.5, 4].
    DragP,
    /// Corotating drag c_r of −c_r (β̇ − α̇), s⁻¹.
    CorotatingDrag,
    /// Load-dependent dry friction η_L, s⁻² per unit bearing load.
    LoadFriction,
    /// Vertical weight ρ_z in the bearing load, units of F₀ (no column).
    LoadWeightVertical,
    /// Side weight ρ_n in the bearing load, units of F₀ (no column).
    LoadWeightSide,
    /// Breakaway excess η_Δs of the static over the sliding friction, s⁻².
    StaticExcess,
    /// Stribeck width w, rad/s.
    StribeckWidth,
    /// Stribeck shape δ, in [0.5, 4].
    StribeckPower,
    /// Input compliance χ, s².
    Compliance,
    /// Drive offset ε of the input magnet from the recorded input angle, rad.
    DriveOffset,
}

/// Number of [`RecordedParam`]s.
const N: usize = 24;

impl Parameter for RecordedParam {
    const ALL: &'static [Self] = &[
        Self::F,
        Self::G,
        Self::Delta,
        Self::CouplingCc,
        Self::CouplingSs,
        Self::Zeta,
        Self::Eta,
        Self::StaticA,
        Self::StaticB,
        Self::StaticA2,
        Self::StaticB2,
        Self::StaticA3,
        Self::StaticB3,
        Self::DragQ,
        Self::DragP,
        Self::CorotatingDrag,
        Self::LoadFriction,
        Self::LoadWeightVertical,
        Self::LoadWeightSide,
        Self::StaticExcess,
        Self::StribeckWidth,
        Self::StribeckPower,
        Self::Compliance,
        Self::DriveOffset,
    ];
    fn name(self) -> &'static str {
        use RecordedParam::*;
        match self {
            F => "f",
            G => "g",
            Delta => "delta",
            CouplingCc => "coupling_cc",
            CouplingSs => "coupling_ss",
            Zeta => "zeta",
            Eta => "eta",
            StaticA => "static_a",
            StaticB => "static_b",
            StaticA2 => "static_a2",
            StaticB2 => "static_b2",
            StaticA3 => "static_a3",
            StaticB3 => "static_b3",
            DragQ => "drag_q",
            DragP => "drag_p",
            CorotatingDrag => "corotating_drag",
            LoadFriction => "load_friction",
            LoadWeightVertical => "load_weight_vertical",
            LoadWeightSide => "load_weight_side",
            StaticExcess => "static_excess",
            StribeckWidth => "stribeck_width",
            StribeckPower => "stribeck_power",
            Compliance => "compliance",
            DriveOffset => "drive_offset",
        }
    }
    fn symbol(self) -> &'static str {
        use RecordedParam::*;
        match self {
            Delta => "Δ",
            Zeta => "ζ",
            Eta => "η",
            DragP => "p",
            StaticExcess => "η_Δs",
            Compliance => "χ",
            DriveOffset => "ε",
            p => p.name(),
        }
    }
    fn unit(self) -> &'static str {
        use RecordedParam::*;
        match self {
            F => "Hz",
            Zeta | CorotatingDrag => "1/s",
            Delta | DragP | StribeckPower | LoadWeightVertical | LoadWeightSide => "",
            StribeckWidth => "rad/s",
            Compliance => "s²",
            DriveOffset => "rad",
            _ => "1/s²",
        }
    }
}

/// The recorded gear driven at frequency f: a [`DrivenOscillator`] and [`Parametrised`] over every
/// [`RecordedParam`] (module docs: the active set of Jacobian columns).
#[derive(Debug, Clone, PartialEq)]
pub struct RecordedModel {
    gear: RecordedGear,
    f: f64,
    active: Vec<RecordedParam>,
}

/// The default active set of columns: the base model's parameters.
const DEFAULT_ACTIVE: [RecordedParam; 5] = [
    RecordedParam::F,
    RecordedParam::G,
    RecordedParam::Delta,
    RecordedParam::Zeta,
    RecordedParam::Eta,
];

impl RecordedModel {
    /// The gear with coefficients `c` and geometry `geo` driven at `f` Hz (α₀ = 0). The drag is
    /// normalised to its family form (a quadratic drag q β̇|β̇| becomes q V² (|β̇|/V)² sgn β̇,
    /// the same forces bit for bit), the Stribeck shape to its value; the drive offset's growth
    /// per turn is not part of a driven model and must be 0.
    pub fn new(c: Coefficients, geo: Geometry, f: f64) -> Result<Self> {
        positive("f", f)?;
        let mut c = c;
        if c.drag_exponent.is_none() {
            c.quad *= DRAG_REFERENCE_SPEED * DRAG_REFERENCE_SPEED;
            c.drag_exponent = Some(2.0);
        }
        c.stribeck_power.get_or_insert(STRIBECK_POWER);
        if c.alpha_offset_per_turn != 0.0 {
            return Err(Error::InvalidParameter {
                name: "drive_offset_per_turn",
                value: c.alpha_offset_per_turn,
                reason: "a driven model has a fixed drive offset",
            });
        }
        let m = Self {
            gear: RecordedGear {
                c,
                geo,
                alpha0: 0.0,
                alpha_rate: TAU * f,
                bend: InputBend::default(),
            },
            f,
            active: DEFAULT_ACTIVE.to_vec(),
        };
        for &p in RecordedParam::ALL {
            m.with_param(p, m.param(p))?;
        }
        Ok(m)
    }

    /// The base model of model.md (β̈ = −ζβ̇ − η sgn β̇ + g(−sin α cos β + Δ cos α sin β),
    /// physical sign) at `f` Hz.
    pub fn base(g: f64, delta: f64, zeta: f64, eta: f64, f: f64) -> Result<Self> {
        Self::new(
            Coefficients::base(g, delta, zeta, eta),
            Geometry::new(0.0, 0.0),
            f,
        )
    }

    /// The coefficients (drag and Stribeck shape normalised, see [`Self::new`]).
    pub fn coefficients(&self) -> &Coefficients {
        &self.gear.c
    }

    /// The shaft geometry.
    pub fn geometry(&self) -> &Geometry {
        &self.gear.geo
    }

    /// The force law as simulated (α = α₀ + 2π f t).
    pub fn gear(&self) -> &RecordedGear {
        &self.gear
    }

    /// A copy with drive phase α₀ at t = 0.
    pub fn with_alpha0(mut self, alpha0: f64) -> Result<Self> {
        self.gear.alpha0 = finite("alpha0", alpha0)?;
        Ok(self)
    }

    /// The active parameters (the Jacobian columns, in order).
    pub fn columns(&self) -> &[RecordedParam] {
        &self.active
    }

    /// A copy whose Jacobian columns are `params` (distinct, at most [`MAX_PARAMS`]).
    pub fn with_columns(mut self, params: &[RecordedParam]) -> Result<Self> {
        let distinct = params
            .iter()
            .enumerate()
            .all(|(i, p)| !params[..i].contains(p));
        if params.len() > MAX_PARAMS || !distinct {
            return Err(Error::option(
                "columns",
                format!("at most {MAX_PARAMS} distinct parameters, got {params:?}"),
            ));
        }
        if let Some(p) = params.iter().find(|p| no_column(**p)) {
            return Err(Error::NoParameterColumn { name: p.name() });
        }
        self.active = params.to_vec();
        Ok(self)
    }

    /// A copy with `p` among the columns (put first; the last default column gives way when
    /// the set is full).
    pub fn with_column(self, p: RecordedParam) -> Result<Self> {
        if self.active.contains(&p) {
            return Ok(self);
        }
        let mut cols = vec![p];
        cols.extend(self.active.iter().copied().take(MAX_PARAMS - 1));
        self.with_columns(&cols)
    }

    /// Whether the half-period symmetry (α, β) → (α + π, β + π) holds: no static torque of odd
    /// order and no sparse-search term cos/sin(kα + lβ) with k + l odd.
    fn symmetric(&self) -> bool {
        let c = &self.gear.c;
        let odd_torque = c.st_a != 0.0 || c.st_b != 0.0 || c.st_harmonics[1] != (0.0, 0.0);
        let odd_extra = c.extra.iter().any(|&(t, th)| {
            th != 0.0
                && match t {
                    ExtraTerm::Trig { k, l, .. }
                    | ExtraTerm::VelTrig { k, l, .. }
                    | ExtraTerm::FricTrig { k, l, .. } => (k as i32 + l as i32) % 2 != 0,
                    ExtraTerm::Unused => false,
                }
        });
        !odd_torque && !odd_extra
    }
}

/// Parameters without an analytic column (they can be swept, not continued).
fn no_column(p: RecordedParam) -> bool {
    matches!(
        p,
        RecordedParam::LoadWeightVertical | RecordedParam::LoadWeightSide
    )
}

/// Where the friction's columns are evaluated: the time, the recorded input angle and β, with
/// their sines and cosines.
#[derive(Debug, Clone, Copy)]
struct FrictionPoint {
    t: f64,
    alpha: f64,
    sc_alpha: (f64, f64),
    beta: f64,
    sc_beta: (f64, f64),
}

/// The derivatives ∂a/∂p and ∂r/∂p of every [`RecordedParam`] at one point (indexed by
/// `p as usize`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamForces {
    /// ∂a/∂p.
    pub a: [f64; N],
    /// ∂r/∂p.
    pub r: [f64; N],
}

impl RecordedModel {
    /// ∂a/∂p and ∂r/∂p for every parameter at (t, β, ω), on the branch `held` of the friction's
    /// floor (`None`: floored at 0 where ρ < 0; see the parent module). Eqs. of the module docs.
    pub fn param_forces(&self, t: f64, beta: f64, omega: f64, held: Option<bool>) -> ParamForces {
        use RecordedParam as P;
        let gear = &self.gear;
        let c = &gear.c;
        let mut d = ParamForces {
            a: [0.0; N],
            r: [0.0; N],
        };
        let al = gear.alpha(t);
        let (sc_alpha, sc_beta) = (sin_cos(al), sin_cos(beta));
        let (_, _, (sa, ca)) = gear.input_angle_sc(al, sc_alpha, sc_beta);
        let (sb, cb) = sc_beta;
        let (_, _, _, a_alpha) = gear.smooth_at((sa, ca), (beta, sc_beta), omega);
        // the input magnet's response: κ, τ_in and ∂τ_in/∂c
        let tau = c.c_sc * ca * sb + c.c_cs * sa * cb - c.c_cc * sa * sb - c.c_ss * ca * cb;
        let tau_a = -c.c_sc * sa * sb + c.c_cs * ca * cb - c.c_cc * ca * sb + c.c_ss * sa * cb;
        let kappa = 1.0 / (1.0 - c.compliance * tau_a);
        let via = a_alpha * c.compliance * kappa;
        let coupling = [
            sa * cb + via * ca * sb,
            ca * sb + via * sa * cb,
            ca * cb - via * sa * sb,
            sa * sb - via * ca * cb,
        ];
        let g = -c.c_sc;
        d.a[P::G as usize] = -coupling[0] + c.c_cs / g * coupling[1];
        d.a[P::Delta as usize] = g * coupling[1];
        d.a[P::CouplingCc as usize] = coupling[2];
        d.a[P::CouplingSs as usize] = coupling[3];
        d.a[P::F as usize] = a_alpha * kappa * TAU * t + c.corot * TAU;
        d.a[P::Compliance as usize] = a_alpha * tau * kappa;
        d.a[P::DriveOffset as usize] = a_alpha * kappa;
        d.a[P::Zeta as usize] = -omega;
        d.a[P::CorotatingDrag as usize] = -(omega - gear.alpha_rate);
        self.torque_columns(&mut d, sc_beta);
        self.drag_columns(&mut d, omega);
        let at = FrictionPoint {
            t,
            alpha: al,
            sc_alpha,
            beta,
            sc_beta,
        };
        self.friction_columns(&mut d, &at, held);
        self.stribeck_columns(&mut d, omega);
        d
    }

    /// The static torque's columns: sin kβ and cos kβ, k = 1, 2, 3.
    fn torque_columns(&self, d: &mut ParamForces, (sb, cb): (f64, f64)) {
        use RecordedParam as P;
        let (s2, c2) = (2.0 * sb * cb, cb * cb - sb * sb);
        let (s3, c3) = (sb * c2 + cb * s2, cb * c2 - sb * s2);
        let cols = [
            (P::StaticA, sb),
            (P::StaticB, cb),
            (P::StaticA2, s2),
            (P::StaticB2, c2),
            (P::StaticA3, s3),
            (P::StaticB3, c3),
        ];
        for (p, v) in cols {
            d.a[p as usize] = v;
        }
    }

    /// The drag's columns: −(|x|)^p sgn x and −q x |x|^(p−1) ln|x|, x = ω/V.
    fn drag_columns(&self, d: &mut ParamForces, omega: f64) {
        use RecordedParam as P;
        let c = &self.gear.c;
        let (shape, _) = drag(c.drag_exponent, omega);
        d.a[P::DragQ as usize] = -shape;
        let x = (omega / DRAG_REFERENCE_SPEED).abs();
        if x > 0.0 {
            d.a[P::DragP as usize] = -c.quad * shape * x.ln();
        }
    }

    /// The dry friction's columns: η, η_L, and the drive frequency's through the friction's
    /// dependence on α (load and friction harmonics), where the floor lets ρ through.
    fn friction_columns(&self, d: &mut ParamForces, at: &FrictionPoint, held: Option<bool>) {
        use RecordedParam as P;
        let FrictionPoint {
            t,
            alpha: al,
            sc_alpha,
            beta,
            sc_beta,
        } = *at;
        let gear = &self.gear;
        let c = &gear.c;
        let (rho, _) = gear.friction(al, (beta, sc_beta), Some(sc_alpha), false);
        let through = match held {
            None => rho > 0.0,
            Some(floored) => !floored,
        };
        if !through {
            return;
        }
        d.r[P::Eta as usize] = 1.0;
        let (lo, hi) = super::Shape::LoadWeight.range();
        let w = c.load_weight.map(|x| x.clamp(lo, hi));
        d.r[P::LoadFriction as usize] = super::load_shape(&gear.geo, al, beta, w, c.load_radial);
        let mut r_alpha = 0.0;
        if c.eta_load != 0.0 {
            r_alpha += c.eta_load * load_shape_alpha(&gear.geo, al, beta, w, c.load_radial);
        }
        for &(term, th) in &c.extra {
            if let ExtraTerm::FricTrig { k, l, sin } = term {
                let (_, dv) = super::angle_harmonic_sc(k, l, sin, sc_alpha, sc_beta);
                r_alpha += th * k as f64 * dv;
            }
        }
        d.r[P::F as usize] = r_alpha * TAU * t;
    }

    /// The Stribeck part's columns: e·E, E = exp(−xᵟ), x = |ω|/w, with ∂/∂e = E (1 at rest:
    /// the static bound η + e, which the release uses), ∂/∂w = e E δ xᵟ/w, ∂/∂δ = −e E xᵟ ln x.
    fn stribeck_columns(&self, d: &mut ParamForces, omega: f64) {
        use RecordedParam as P;
        let c = &self.gear.c;
        if omega == 0.0 {
            d.r[P::StaticExcess as usize] = 1.0;
            return;
        }
        let (w, delta) = (c.stribeck_width, c.stribeck_power.unwrap_or(STRIBECK_POWER));
        if w <= 0.0 {
            return;
        }
        let e = c.eta_static_excess.max(0.0);
        let x = omega.abs() / w;
        let xd = x.powf(delta);
        let big_e = (-xd).exp();
        d.r[P::StaticExcess as usize] = big_e;
        d.r[P::StribeckWidth as usize] = e * big_e * delta * xd / w;
        d.r[P::StribeckPower as usize] = -e * big_e * xd * x.ln();
    }

    /// The jet with the active columns filled from [`Self::param_forces`].
    fn jet_with_columns(
        &self,
        mut j: ForcesJet,
        t: f64,
        x: [f64; 2],
        held: Option<bool>,
    ) -> ForcesJet {
        let d = self.param_forces(t, x[0], x[1], held);
        for (k, &p) in self.active.iter().enumerate() {
            j.a_p[k] = d.a[p as usize];
            j.r_p[k] = d.r[p as usize];
        }
        j
    }
}

impl DrivenOscillator for RecordedModel {
    fn period(&self) -> f64 {
        1.0 / self.f
    }
    fn n_params(&self) -> usize {
        self.active.len()
    }
    fn param_name(&self, k: usize) -> &'static str {
        self.active.get(k).map(|p| p.name()).unwrap_or("?")
    }
    fn period_derivative(&self, k: usize) -> f64 {
        if self.active.get(k) == Some(&RecordedParam::F) {
            -1.0 / (self.f * self.f)
        } else {
            0.0
        }
    }
    fn forces(&self, t: f64, beta: f64, omega: f64) -> Forces {
        self.gear.forces(t, beta, omega)
    }
    fn forces_jet(&self, t: f64, beta: f64, omega: f64, params: bool) -> ForcesJet {
        let j = self.gear.forces_jet(t, beta, omega, false);
        if params {
            self.jet_with_columns(j, t, [beta, omega], None)
        } else {
            j
        }
    }
    fn friction_floor(&self, t: f64, beta: f64, omega: f64) -> Option<f64> {
        self.gear.friction_floor(t, beta, omega)
    }
    fn forces_held(&self, t: f64, beta: f64, omega: f64, floored: bool) -> Forces {
        self.gear.forces_held(t, beta, omega, floored)
    }
    fn forces_jet_held(
        &self,
        t: f64,
        beta: f64,
        omega: f64,
        params: bool,
        floored: bool,
    ) -> ForcesJet {
        let j = self.gear.forces_jet_held(t, beta, omega, false, floored);
        if params {
            self.jet_with_columns(j, t, [beta, omega], Some(floored))
        } else {
            j
        }
    }
    fn static_friction(&self, t: f64, beta: f64) -> f64 {
        self.gear.static_friction(t, beta)
    }
    fn half_period_symmetry(&self) -> Option<HalfPeriodSymmetry> {
        self.symmetric().then_some(HalfPeriodSymmetry {
            sign: 1.0,
            shift: PI,
        })
    }
    fn drive_phase(&self, t: f64) -> f64 {
        self.gear.alpha(t)
    }
    /// +1 for Δ ≥ 0 (the output turns with the input), −1 for Δ < 0.
    fn co_rotation(&self) -> f64 {
        if self.param(RecordedParam::Delta) >= 0.0 {
            1.0
        } else {
            -1.0
        }
    }
}

impl Parametrised for RecordedModel {
    type Param = RecordedParam;

    fn param(&self, p: RecordedParam) -> f64 {
        use RecordedParam::*;
        let c = &self.gear.c;
        match p {
            F => self.f,
            G => -c.c_sc,
            Delta => -c.c_cs / c.c_sc,
            CouplingCc => c.c_cc,
            CouplingSs => c.c_ss,
            Zeta => c.zeta,
            Eta => c.eta,
            StaticA => c.st_a,
            StaticB => c.st_b,
            StaticA2 => c.st_harmonics[0].0,
            StaticB2 => c.st_harmonics[0].1,
            StaticA3 => c.st_harmonics[1].0,
            StaticB3 => c.st_harmonics[1].1,
            DragQ => c.quad,
            DragP => c.drag_exponent.unwrap_or(2.0),
            CorotatingDrag => c.corot,
            LoadFriction => c.eta_load,
            LoadWeightVertical => c.load_weight[0],
            LoadWeightSide => c.load_weight[1],
            StaticExcess => c.eta_static_excess,
            StribeckWidth => c.stribeck_width,
            StribeckPower => c.stribeck_power.unwrap_or(STRIBECK_POWER),
            Compliance => c.compliance,
            DriveOffset => c.alpha_offset,
        }
    }

    fn with_param(&self, p: RecordedParam, v: f64) -> Result<Self> {
        use RecordedParam::*;
        let mut m = self.clone();
        let name = p.name();
        let c = &mut m.gear.c;
        let in_range = |lo: f64, hi: f64| -> Result<f64> {
            if (lo..=hi).contains(&v) {
                Ok(v)
            } else {
                Err(Error::InvalidParameter {
                    name,
                    value: v,
                    reason: "outside the family's range",
                })
            }
        };
        match p {
            F => {
                m.f = positive(name, v)?;
                m.gear.alpha_rate = TAU * v;
            }
            G => {
                let delta = -c.c_cs / c.c_sc;
                c.c_sc = -positive(name, v)?;
                c.c_cs = v * delta;
            }
            Delta => c.c_cs = -c.c_sc * finite(name, v)?,
            CouplingCc => c.c_cc = finite(name, v)?,
            CouplingSs => c.c_ss = finite(name, v)?,
            Zeta => c.zeta = finite(name, v)?,
            Eta => c.eta = finite(name, v)?,
            StaticA => c.st_a = finite(name, v)?,
            StaticB => c.st_b = finite(name, v)?,
            StaticA2 => c.st_harmonics[0].0 = finite(name, v)?,
            StaticB2 => c.st_harmonics[0].1 = finite(name, v)?,
            StaticA3 => c.st_harmonics[1].0 = finite(name, v)?,
            StaticB3 => c.st_harmonics[1].1 = finite(name, v)?,
            DragQ => c.quad = finite(name, v)?,
            DragP => c.drag_exponent = Some(in_range(0.5, 4.0)?),
            CorotatingDrag => c.corot = finite(name, v)?,
            LoadFriction => c.eta_load = finite(name, v)?,
            LoadWeightVertical => c.load_weight[0] = in_range(-50.0, 50.0)?,
            LoadWeightSide => c.load_weight[1] = in_range(-50.0, 50.0)?,
            StaticExcess => c.eta_static_excess = non_negative(name, v)?,
            // 0: the excess at rest only; else within the family's range
            StribeckWidth if v == 0.0 => c.stribeck_width = 0.0,
            StribeckWidth => c.stribeck_width = in_range(1e-3, 20.0)?,
            StribeckPower => c.stribeck_power = Some(in_range(0.5, 4.0)?),
            Compliance => c.compliance = non_negative(name, v)?,
            DriveOffset => c.alpha_offset = finite(name, v)?,
        }
        Ok(m)
    }

    fn column(&self, p: RecordedParam) -> Option<Column> {
        self.active
            .iter()
            .position(|&q| q == p)
            .map(Column::primary)
    }
}

/// In JSON (a branch's `system`): every parameter of the lens by name, the shaft angles and the
/// active columns; the sparse-search terms are the model file's.
impl Serialize for RecordedModel {
    fn serialize<Z: serde::Serializer>(&self, s: Z) -> std::result::Result<Z::Ok, Z::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(RecordedParam::ALL.len() + 3))?;
        for &p in RecordedParam::ALL {
            map.serialize_entry(p.name(), &self.param(p))?;
        }
        map.serialize_entry("theta_deg", &self.gear.geo.theta().to_degrees())?;
        map.serialize_entry("phi_deg", &self.gear.geo.phi().to_degrees())?;
        let cols: Vec<&str> = self.active.iter().map(|p| p.name()).collect();
        map.serialize_entry("columns", &cols)?;
        map.end()
    }
}
