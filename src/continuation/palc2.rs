//! Two-parameter curves of codimension-one points by pseudo-arclength continuation of the
//! minimally augmented system, so a curve passes turning points in either parameter.
//!
//! Unknowns u = (β, ω, λ₁, λ₂) (λ₁ "free", λ₂ "along", e.g. f and Θ). Equations
//!
//! ```text
//!   Pᵏ(x; λ₁, λ₂) − x − (s, 0) = 0,   g(x, λ₁, λ₂) = 0,   t·(W u − v_pred) = 0,
//! ```
//!
//! with g the bordered test function of A = M − σI ([`super::minaug`]; det M − 1 for a
//! Neimark–Sacker curve), W = diag(1, w_ω, 1, 1) and t the unit tangent in scaled variables. The
//! first two rows of the Newton matrix are the map's Jacobians; the row of g is a forward difference
//! (g is built from M, so its exact derivative would need second-order sensitivities): this makes
//! Newton converge linearly at rate ~1e-5, while the solution is as accurate as the residual. The
//! bordering vectors are reset to the left and right null vectors at every accepted point. The
//! tangent solves [J W⁻¹; t_prevᵀ] t = e₄. Step control as in [`super::palc`]. Codimension-two points
//! ([`super::codim2`]) are located between two points by an Illinois secant on the scaled arclength,
//! each trial point corrected on the hyperplane t_a·(W u − W u_a) = σ; a bracket whose test function
//! does not fall below 1e-3 of its end values is a jump (a nonsmooth point), not a zero, and is
//! dropped.
//!
//! Curves of nonsmooth points use the same solver with another scalar equation g: the grazing
//! margin of the one-sided flow ([`continue_grazing_curve`], the onset of sticking) and the edge
//! margin a − σ r_s of a tracked arrival on Σ on the real map ([`continue_event_edge_curve`], the
//! end of sticking).

use super::codim2::{test_functions, Codim2Kind, Codim2Point, CurveLocal};
use super::minaug::{
    arrival_edge, bordered_test, critical_multiplier, grazing_margin, linearise_map,
    nearest_edge_arrival, unit, MapLinearisation,
};
use super::options::{check_accuracy, check_range, check_steps};
use super::two_param::{check_curve_args, lock_loss_starts, Curve, CurvePoint, CurveStop};
use super::SpecialKind;
use crate::error::{Error, Result};
use crate::integrator::FlowMethod;
use crate::model::{OneSided, Parameter, Parametrised};
use crate::numerics::{newton, Illinois, Linearisation, NewtonOptions};
use crate::orbits::{OrbitSpec, ShootingOptions};
use nalgebra::{Matrix4, Vector4};
use serde::{Deserialize, Serialize};

/// Options of a two-parameter pseudo-arclength continuation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CurveOptions {
    /// Initial step in scaled arclength; its sign sets the initial direction in the along parameter.
    pub ds: f64,
    /// Smallest step before giving up.
    pub ds_min: f64,
    /// Largest step.
    pub ds_max: f64,
    /// Largest number of steps.
    pub max_steps: usize,
    /// Range of the free parameter: the curve stops on its bounds.
    pub free_range: (f64, f64),
    /// Range of the along parameter.
    pub along_range: (f64, f64),
    /// Weight of ω in the arclength norm.
    pub omega_weight: f64,
    /// Shooting options; the corrector converges to `shooting.newton_tol`.
    pub shooting: ShootingOptions,
    /// Detect and locate codimension-two points.
    pub detect: bool,
    /// Width of the final bracket (scaled arclength) of a located codimension-two point.
    pub locate_tol: f64,
    /// Stop when the spectral radius of the orbit's map exceeds this (single shooting loses about
    /// log₁₀|μ| digits); unlimited by default.
    #[serde(default = "unlimited")]
    pub max_multiplier: f64,
}

fn unlimited() -> f64 {
    f64::INFINITY
}

impl Default for CurveOptions {
    fn default() -> Self {
        Self {
            ds: 0.5,
            ds_min: 1e-6,
            ds_max: 1.0,
            max_steps: 400,
            free_range: (f64::NEG_INFINITY, f64::INFINITY),
            along_range: (f64::NEG_INFINITY, f64::INFINITY),
            omega_weight: 0.1,
            shooting: ShootingOptions::default(),
            detect: true,
            locate_tol: 1e-9,
            max_multiplier: f64::INFINITY,
        }
    }
}

impl CurveOptions {
    /// Checks steps, ranges and tolerances (the checks of [`super::ContinuationOptions`]).
    pub fn validate(&self) -> Result<()> {
        check_steps(self.ds, self.ds_min, self.ds_max, self.max_steps)?;
        check_range("free_range", self.free_range)?;
        check_range("along_range", self.along_range)?;
        check_accuracy(&self.shooting, self.locate_tol, self.omega_weight)?;
        if self.max_multiplier.is_nan() || self.max_multiplier <= 1.0 {
            return Err(Error::InvalidParameter {
                name: "max_multiplier",
                value: self.max_multiplier,
                reason: "must be > 1",
            });
        }
        Ok(())
    }
}

/// A solved point of the augmented system, with what the next step and the test functions need.
#[derive(Debug, Clone)]
struct Node {
    u: Vector4<f64>,
    lin: MapLinearisation,
    g: f64,
    v: [f64; 2],
    w: [f64; 2],
    /// ∇g (unscaled variables).
    grad: Vector4<f64>,
    /// Unit tangent in scaled variables.
    tangent: Vector4<f64>,
    iterations: usize,
    step: f64,
    /// Time of the tracked arrival on Σ (event-edge curves only).
    event_time: f64,
}

/// The scalar equation that makes the orbit special.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Test {
    /// The bordered test function of M − σI.
    Bordered(f64),
    /// det M − 1 (Neimark–Sacker).
    UnitDeterminant,
    /// The smallest side·ω over the (one-sided) orbit: zero where it grazes Σ.
    Grazing(f64),
    /// a − σ r_s at the tracked arrival on Σ: zero where the arrival lies on the edge σ of the stick
    /// region (a stick phase starts or ends, a crossing appears).
    ArrivalEdge {
        /// The edge: a = σ r_s.
        sigma: f64,
        /// The side the tracked arrival comes from.
        side: f64,
    },
}

/// The augmented system of one curve.
struct System<'a, S: Parametrised, M> {
    method: &'a M,
    sys: &'a S,
    spec: OrbitSpec,
    kind: SpecialKind,
    params: [S::Param; 2],
    test: Test,
    b: [f64; 2],
    c: [f64; 2],
    opts: CurveOptions,
    /// Time of the tracked arrival on Σ (event-edge curves), updated at every accepted point.
    t_ref: f64,
}

impl<S: Parametrised, M: FlowMethod<S>> System<'_, S, M> {
    fn weights(&self) -> Vector4<f64> {
        Vector4::new(1.0, self.opts.omega_weight, 1.0, 1.0)
    }

    /// The map's linearisation and the test function (g, v, w) at u.
    #[allow(clippy::type_complexity)]
    fn eval(&self, u: &Vector4<f64>) -> Result<(MapLinearisation, f64, [f64; 2], [f64; 2], f64)> {
        let sys = self
            .sys
            .with_param(self.params[0], u[2])?
            .with_param(self.params[1], u[3])?;
        let lin = linearise_map(
            self.method,
            &sys,
            &self.spec,
            [u[0], u[1]],
            &self.params,
            &self.opts.shooting,
        )?;
        let (g, v, w) = match self.test {
            Test::Bordered(s) => {
                let t = bordered_test(&lin.jac, s, self.b, self.c)?;
                (t.g, t.v, t.w)
            }
            Test::UnitDeterminant => (lin.floquet().ns_test(), [0.0; 2], [0.0; 2]),
            Test::Grazing(side) => {
                let x = [u[0], u[1]];
                let tol = self.opts.shooting.tol;
                let g = grazing_margin(self.method, &sys, &self.spec, x, side, tol)?;
                (g, [0.0; 2], [0.0; 2])
            }
            Test::ArrivalEdge { sigma, side } => {
                let x = [u[0], u[1]];
                let tol = self.opts.shooting.tol;
                let edge = (sigma, side, self.t_ref);
                let e = arrival_edge(self.method, &sys, &self.spec, x, edge, tol)?;
                return Ok((lin, e.margin, [0.0; 2], [0.0; 2], e.t));
            }
        };
        Ok((lin, g, v, w, f64::NAN))
    }

    /// The Newton matrix rows of F and g at u (∇g by forward differences) and the point data.
    fn rows(&self, u: &Vector4<f64>) -> Result<(Vector4<f64>, Matrix4<f64>, Node)> {
        let (lin, g, v, w, event_time) = self.eval(u)?;
        let hs = [
            1e-6,
            1e-6 * u[1].abs().max(1.0),
            1e-6 * u[2].abs().max(1.0),
            1e-6 * u[3].abs().max(1.0),
        ];
        let mut grad = Vector4::zeros();
        for j in 0..4 {
            let mut up = *u;
            up[j] += hs[j];
            grad[j] = (self.eval(&up)?.1 - g) / hs[j];
        }
        let mut jm = Matrix4::zeros();
        for i in 0..2 {
            jm[(i, 0)] = lin.jac[(i, 0)] - if i == 0 { 1.0 } else { 0.0 };
            jm[(i, 1)] = lin.jac[(i, 1)] - if i == 1 { 1.0 } else { 0.0 };
            jm[(i, 2)] = lin.columns[0][i];
            jm[(i, 3)] = lin.columns[1][i];
        }
        jm.set_row(2, &grad.transpose());
        let r = Vector4::new(lin.residual[0], lin.residual[1], g, 0.0);
        let node = Node {
            u: *u,
            lin,
            g,
            v,
            w,
            grad,
            tangent: Vector4::zeros(),
            iterations: 0,
            step: 0.0,
            event_time,
        };
        Ok((r, jm, node))
    }

    /// Newton on {F = 0, g = 0, n·(W u − v_ref) = c} from `u0`, then the tangent oriented along
    /// `orient` (scaled).
    fn correct(
        &self,
        u0: Vector4<f64>,
        n: Vector4<f64>,
        v_ref: Vector4<f64>,
        c: f64,
        orient: Vector4<f64>,
    ) -> Result<Node> {
        let wts = self.weights();
        let border = n.component_mul(&wts);
        let nopts = NewtonOptions::new(self.opts.shooting.newton_tol, self.opts.shooting.max_iter);
        let mut last_step = 0.0;
        let sol = newton(
            u0,
            &nopts,
            |u| {
                let (mut r, mut jm, node) = self.rows(u)?;
                r[3] = n.dot(&(u.component_mul(&wts) - v_ref)) - c;
                jm.set_row(3, &border.transpose());
                Ok(Linearisation {
                    residual: r,
                    jacobian: jm,
                    data: node,
                })
            },
            |_, du| {
                last_step = du.norm();
                1.0
            },
            &format!("augmented {} curve corrector", self.kind.label()),
        )?;
        let mut node = sol.at.data;
        node.iterations = sol.iterations;
        node.step = last_step;
        node.tangent = self.tangent(&node, &orient)?;
        Ok(node)
    }

    /// Unit tangent (scaled variables) at `node`, oriented along `prev`.
    fn tangent(&self, node: &Node, prev: &Vector4<f64>) -> Result<Vector4<f64>> {
        let wts = self.weights();
        let mut a = Matrix4::zeros();
        for i in 0..2 {
            for j in 0..4 {
                let d = if i == j { 1.0 } else { 0.0 };
                let col = if j < 2 {
                    node.lin.jac[(i, j)] - d
                } else {
                    node.lin.columns[j - 2][i]
                };
                a[(i, j)] = col / wts[j];
            }
        }
        for j in 0..4 {
            a[(2, j)] = node.grad[j] / wts[j];
            a[(3, j)] = prev[j];
        }
        let t = a
            .lu()
            .solve(&Vector4::new(0.0, 0.0, 0.0, 1.0))
            .filter(|t| t.iter().all(|z| z.is_finite()) && t.norm() > 0.0)
            .ok_or(Error::SingularMatrix {
                what: "bordered matrix: cannot compute the tangent",
            })?
            .normalize();
        Ok(if t.dot(prev) < 0.0 { -t } else { t })
    }

    /// The first node: corrected from (`x0`, `free0`) with the along parameter held at its value
    /// in the system.
    fn first_node(&self, x0: [f64; 2], free0: f64) -> Result<Node> {
        let along0 = self.sys.param(self.params[1]);
        let e4 = Vector4::new(0.0, 0.0, 0.0, 1.0);
        let u0 = Vector4::new(x0[0], x0[1], free0, along0);
        let orient = e4 * self.opts.ds.signum();
        self.correct(u0, e4, e4 * along0, 0.0, orient)
            .map_err(|e| self.start_failed(e, free0))
    }

    /// The error of a start guess from which the corrector does not reach the curve: a Newton
    /// iterate outside a parameter's domain is named as a bad start, not as a bad input value.
    fn start_failed(&self, e: Error, free0: f64) -> Error {
        let free = self.params[0].name();
        let why = match e {
            Error::InvalidParameter {
                name,
                value,
                reason,
            } => format!(
                "the corrector left the domain of the parameters ({name} = {value:.6e} {reason})"
            ),
            Error::NewtonFailed { .. } => e.to_string(),
            other => return other,
        };
        Error::NoStartOrbit {
            param: free,
            value: free0,
            reason: format!(
                "no {} point near the start guess: {why}; start nearer the point (`locate` \
                 finds it from a guess of the state and {free})",
                self.kind.label()
            ),
        }
    }

    /// Resets the bordering vectors to the null vectors at `node` (a no-op for NS curves).
    fn rebord(&mut self, node: &Node) {
        if matches!(self.test, Test::ArrivalEdge { .. }) {
            self.t_ref = node.event_time;
        }
        if matches!(self.test, Test::Bordered(_)) {
            self.b = unit(node.w);
            self.c = unit(node.v);
        }
    }

    fn point(&self, n: &Node) -> CurvePoint {
        CurvePoint {
            along: n.u[3],
            free: n.u[2],
            x: [n.u[0], n.u[1]],
            floquet: n.lin.floquet(),
            events: n.lin.events,
            test_value: n.g,
            precision: n.step + self.opts.shooting.newton_tol,
            newton_iterations: n.iterations,
        }
    }

    fn tests(&self, n: &Node) -> Vec<(Codim2Kind, f64)> {
        let fq = n.lin.floquet();
        test_functions(
            self.kind,
            &CurveLocal {
                floquet: &fq,
                v: n.v,
                grad_x: [n.grad[0], n.grad[1]],
                tangent_lambda: [n.tangent[2], n.tangent[3]],
            },
        )
    }
}

/// Continues the curve of `kind` points of the problem `spec` of `sys` in the two parameters
/// `free` (λ₁) and `along` (λ₂), from near (x0, λ₁ = `free0`) at λ₂ = its value in `sys`, with the
/// flow computed by `method`. The first point is corrected with λ₂ fixed.
#[allow(clippy::too_many_arguments)]
pub fn continue_curve<S: Parametrised, M: FlowMethod<S>>(
    method: &M,
    sys: &S,
    spec: &OrbitSpec,
    kind: SpecialKind,
    free: S::Param,
    along: S::Param,
    x0: [f64; 2],
    free0: f64,
    opts: &CurveOptions,
) -> Result<Curve<S>> {
    opts.validate()?;
    check_curve_args(free, along, x0, free0)?;
    let test = match kind {
        SpecialKind::NeimarkSacker => Test::UnitDeterminant,
        k => Test::Bordered(critical_multiplier(k)?),
    };
    let along0 = sys.param(along);
    let mut s = System {
        method,
        sys,
        spec: *spec,
        kind,
        params: [free, along],
        test,
        b: [1.0, 0.0],
        c: [1.0, 0.0],
        opts: *opts,
        t_ref: f64::NAN,
    };
    // bordering vectors from the multiplier nearest σ at the start
    if let Test::Bordered(sg) = test {
        let (lin, ..) = s.eval(&Vector4::new(x0[0], x0[1], free0, along0))?;
        let m = lin.jac - sg * nalgebra::Matrix2::identity();
        let svd = m.svd(true, true);
        let k = if svd.singular_values[0] < svd.singular_values[1] {
            0
        } else {
            1
        };
        let (uu, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
        s.b = [uu[(0, k)], uu[(1, k)]];
        s.c = [vt[(k, 0)], vt[(k, 1)]];
    }
    let first = s.first_node(x0, free0)?;
    s.rebord(&first);
    walk(&mut s, first)
}

/// The augmented system of a grazing curve of `sys`: the one-sided flow of `side`.
fn grazing_system<'a, S: Parametrised, M>(
    method: &'a M,
    one_sided: &'a OneSided<S>,
    spec: &OrbitSpec,
    params: [S::Param; 2],
    opts: &CurveOptions,
) -> System<'a, OneSided<S>, M> {
    System {
        method,
        sys: one_sided,
        spec: *spec,
        kind: SpecialKind::Nonsmooth,
        params,
        test: Test::Grazing(one_sided.side()),
        b: [1.0, 0.0],
        c: [1.0, 0.0],
        opts: *opts,
        t_ref: f64::NAN,
    }
}

/// Continues the curve of **grazing points** of the problem `spec` of `sys` in (`free`, `along`):
/// orbits on side `side` of Σ = {ω = 0} that touch it, ω = ω̇ = 0 at one instant (for dry
/// friction: the onset of sticking, |a| = r there). The defining system is a regular root problem
/// on the one-sided flow ([`OneSided`], the smooth field of `side` continued across Σ):
///
/// ```text
///   P̃ᵏ(x; λ₁, λ₂) − x − (s, 0) = 0,   g(x; λ₁, λ₂) = min_t side·ω̃(t) = 0,
/// ```
///
/// with P̃ the one-sided map (equal to the true map on the side where the orbit does not touch
/// Σ, and at the grazing point itself) and g the grazing margin ([`grazing_margin`]: a smooth
/// function there, positive before the touch and negative past it, where the true orbit sticks).
/// Continued by the same pseudo-arclength as the other curves, so it passes turning points; the
/// codimension-two points located on it are fold–grazing and flip–grazing points (on G:
/// symmetry-breaking–grazing) and turning points. `method` integrates the one-sided flow.
#[allow(clippy::too_many_arguments)]
pub fn continue_grazing_curve<S: Parametrised, M: FlowMethod<OneSided<S>>>(
    method: &M,
    sys: &S,
    spec: &OrbitSpec,
    side: f64,
    free: S::Param,
    along: S::Param,
    x0: [f64; 2],
    free0: f64,
    opts: &CurveOptions,
) -> Result<Curve<S>> {
    opts.validate()?;
    check_curve_args(free, along, x0, free0)?;
    let os = OneSided::new(sys.clone(), side)?;
    let mut s = grazing_system(method, &os, spec, [free, along], opts);
    let first = s.first_node(x0, free0)?;
    let c = walk(&mut s, first)?;
    Ok(Curve {
        kind: c.kind,
        along: c.along,
        free: c.free,
        spec: c.spec,
        points: c.points,
        stopped: c.stopped,
        codim2: c.codim2,
    })
}

/// The grazing point of the problem `spec` of `sys` at the present value of `along` (held fixed):
/// the defining system of [`continue_grazing_curve`] solved for (x, `free`) by Newton from
/// (`x0`, `free0`). Its `precision` is the last Newton step.
#[allow(clippy::too_many_arguments)]
pub fn locate_grazing<S: Parametrised, M: FlowMethod<OneSided<S>>>(
    method: &M,
    sys: &S,
    spec: &OrbitSpec,
    side: f64,
    free: S::Param,
    along: S::Param,
    x0: [f64; 2],
    free0: f64,
    opts: &CurveOptions,
) -> Result<CurvePoint> {
    check_curve_args(free, along, x0, free0)?;
    let os = OneSided::new(sys.clone(), side)?;
    let s = grazing_system(method, &os, spec, [free, along], opts);
    Ok(s.point(&s.first_node(x0, free0)?))
}

/// Continues the curve of points where an **arrival on Σ lies on an edge of the stick region**:
/// the orbit of `spec` reaches ω = 0 at t_e with a(t_e, β_e, 0) = σ r_s(t_e, β_e). Across it the
/// event sequence changes without a touch of Σ: a stick phase starts (arrival from the side −σ:
/// (0, 1) → (1, 1), a crossing appears) or a stick phase shrinks to nothing ((1, 1) → (2, 0)).
/// Defining system on the real map (which is C¹ there: the crossing saltation
/// diag(1, (a − s'r)/(a − s r)) tends to the stick saltation diag(1, 0) at the edge):
///
/// ```text
///   Pᵏ(x; λ₁, λ₂) − x − (s, 0) = 0,   a(t_e, β_e, 0) − σ r_s(t_e, β_e) = 0,
/// ```
///
/// with t_e the arrival from the same side tracked from point to point (the one nearest to the
/// previous point's).
/// The arrival and σ are chosen at the start (the nonsmooth point a one-parameter continuation
/// located, on either side of the edge) as the arrival from a side s nearest to its edge
/// a = −s r_s, so σ = −s ([`nearest_edge_arrival`]: not the tangential return to Σ that follows a
/// crossing, which exists on one side of the edge only). Turning points and fold/flip points of
/// the orbit on the curve are located as on the grazing curves.
#[allow(clippy::too_many_arguments)]
pub fn continue_event_edge_curve<S: Parametrised, M: FlowMethod<S>>(
    method: &M,
    sys: &S,
    spec: &OrbitSpec,
    free: S::Param,
    along: S::Param,
    x0: [f64; 2],
    free0: f64,
    opts: &CurveOptions,
) -> Result<Curve<S>> {
    opts.validate()?;
    check_curve_args(free, along, x0, free0)?;
    let start = sys.with_param(free, free0)?;
    let (sigma, side, t_ref) = nearest_edge_arrival(method, &start, spec, x0, opts.shooting.tol)?;
    let mut s = System {
        method,
        sys,
        spec: *spec,
        kind: SpecialKind::Nonsmooth,
        params: [free, along],
        test: Test::ArrivalEdge { sigma, side },
        b: [1.0, 0.0],
        c: [1.0, 0.0],
        opts: *opts,
        t_ref,
    };
    let first = s.first_node(x0, free0)?;
    s.rebord(&first);
    walk(&mut s, first)
}

/// Where a parameter left its range: (which parameter, the bound).
fn out_of_range<S: Parametrised, M>(s: &System<S, M>, u: &Vector4<f64>) -> Option<(usize, f64)> {
    let ranges = [s.opts.free_range, s.opts.along_range];
    (0..2).find_map(|k| {
        let (lo, hi) = ranges[k];
        let z = u[2 + k];
        if z > hi {
            Some((k, hi))
        } else if z < lo {
            Some((k, lo))
        } else {
            None
        }
    })
}

/// The continuation loop from the first node.
fn walk<S: Parametrised, M: FlowMethod<S>>(s: &mut System<S, M>, first: Node) -> Result<Curve<S>> {
    let mut nodes_pts = vec![s.point(&first)];
    let mut codim2 = Vec::new();
    let mut prev = first;
    let mut ds = s.opts.ds.abs();
    let mut stopped = None;
    for _ in 0..s.opts.max_steps {
        let Some(mut next) = step(s, &prev, &mut ds) else {
            stopped = Some(CurveStop::StepTooSmall {
                free: prev.u[2],
                along: prev.u[3],
                ds_min: s.opts.ds_min,
            });
            break;
        };
        let mut bound = None;
        if let Some((k, b)) = out_of_range(s, &next.u) {
            // land on the bound with that parameter fixed
            let frac = (b - prev.u[2 + k]) / (next.u[2 + k] - prev.u[2 + k]);
            let mut e = Vector4::zeros();
            e[2 + k] = 1.0;
            let up = prev.u + frac * (next.u - prev.u);
            match s.correct(up, e, e * b, 0.0, prev.tangent) {
                Ok(n) => next = n,
                Err(err) => {
                    stopped = Some(CurveStop::NotConverged {
                        at: b,
                        error: err.to_string(),
                    });
                    break;
                }
            }
            bound = Some((k, b));
        }
        if s.opts.detect {
            let after = nodes_pts.len() - 1;
            codim2.extend(locate_between(s, &prev, &next, after));
        }
        nodes_pts.push(s.point(&next));
        s.rebord(&next);
        ds = match next.iterations {
            0..=3 => (ds * 1.5).min(s.opts.ds_max),
            4..=6 => ds,
            _ => (ds * 0.6).max(s.opts.ds_min),
        };
        prev = next;
        let radius = prev.lin.floquet().spectral_radius();
        if radius > s.opts.max_multiplier {
            stopped = Some(CurveStop::MultiplierLimit {
                modulus: radius,
                free: prev.u[2],
                along: prev.u[3],
            });
            break;
        }
        if let Some((k, b)) = bound {
            stopped = Some(CurveStop::ParameterBound {
                param: s.params[k].name().to_string(),
                value: b,
            });
            break;
        }
    }
    if stopped.is_none() {
        stopped = Some(CurveStop::MaxSteps {
            steps: s.opts.max_steps,
        });
    }
    Ok(Curve {
        kind: s.kind,
        along: s.params[1],
        free: s.params[0],
        spec: s.spec,
        points: nodes_pts,
        stopped,
        codim2,
    })
}

/// Predicts and corrects one node from `prev`, halving the step on failure, on a correction longer
/// than the step or on a tangent turning by more than 60°; `None` below `ds_min`.
fn step<S: Parametrised, M: FlowMethod<S>>(
    s: &System<S, M>,
    prev: &Node,
    ds: &mut f64,
) -> Option<Node> {
    let wts = s.weights();
    let v0 = prev.u.component_mul(&wts);
    loop {
        let v_pred = v0 + *ds * prev.tangent;
        let u_pred = v_pred.component_div(&wts);
        if let Ok(n) = s.correct(u_pred, prev.tangent, v_pred, 0.0, prev.tangent) {
            let jump = (n.u.component_mul(&wts) - v_pred).norm();
            if n.tangent.dot(&prev.tangent) > 0.5 && jump <= *ds {
                return Some(n);
            }
        }
        *ds *= 0.5;
        if *ds < s.opts.ds_min {
            return None;
        }
    }
}

/// Locates every codimension-two test function that changes sign between `a` and `b`.
fn locate_between<S: Parametrised, M: FlowMethod<S>>(
    s: &System<S, M>,
    a: &Node,
    b: &Node,
    after: usize,
) -> Vec<Codim2Point> {
    let ta = s.tests(a);
    let tb = s.tests(b);
    let mut out = Vec::new();
    for ((kind, fa), (_, fb)) in ta.into_iter().zip(tb) {
        if fa * fb >= 0.0 || fa.is_nan() || fb.is_nan() {
            continue;
        }
        if let Ok(p) = locate_one(s, a, b, kind, fa, fb, after) {
            out.push(p);
        }
    }
    out
}

/// Illinois secant in the scaled arclength σ from `a` along its tangent for the zero of the test
/// function `kind`.
fn locate_one<S: Parametrised, M: FlowMethod<S>>(
    s: &System<S, M>,
    a: &Node,
    b: &Node,
    kind: Codim2Kind,
    fa: f64,
    fb: f64,
    after: usize,
) -> Result<Codim2Point> {
    let wts = s.weights();
    let va = a.u.component_mul(&wts);
    let sb = a.tangent.dot(&(b.u.component_mul(&wts) - va));
    let sgn = fa.signum();
    let mut r = Illinois::new(0.0, sgn * fa, sb, sgn * fb, 0.05);
    let value = |n: &Node| {
        s.tests(n)
            .into_iter()
            .find(|(k, _)| *k == kind)
            .map(|(_, v)| v)
            .unwrap_or(f64::NAN)
    };
    let mut best: Option<(Node, f64)> = None;
    for _ in 0..40 {
        if (r.hi() - r.lo()).abs() < s.opts.locate_tol {
            break;
        }
        let Some(sig) = r.next_point() else { break };
        let frac = if sb != 0.0 { sig / sb } else { 0.0 };
        let up = a.u + frac * (b.u - a.u);
        let n = s.correct(up, a.tangent, va, sig, a.tangent)?;
        let f = value(&n);
        if !f.is_finite() {
            return Err(Error::NonFiniteTestFunction { kind: kind.label() });
        }
        r.update(sig, sgn * f);
        best = Some((n, f));
    }
    let (n, f) = best.ok_or_else(|| Error::NotFound {
        what: format!(
            "{} point: its bracket is already narrower than the location tolerance",
            kind.label()
        ),
    })?;
    // a sign change across a discontinuity (e.g. where the orbit starts to touch ω = 0) is no zero
    if f.abs() > 1e-3 * fa.abs().max(fb.abs()) {
        return Err(Error::TestFunctionJump {
            kind: kind.label(),
            before: fa,
            after: fb,
            at_bracket: f,
        });
    }
    Ok(Codim2Point {
        kind,
        free: n.u[2],
        along: n.u[3],
        x: [n.u[0], n.u[1]],
        floquet: n.lin.floquet(),
        test_value: f,
        tangent_lambda: [n.tangent[2], n.tangent[3]],
        precision: 0.5 * (r.hi() - r.lo()).abs() + s.opts.shooting.newton_tol,
        after_point: after,
    })
}

/// The lock-loss boundary f_c(Θ) for parallel shafts by pseudo-arclength: the fold curves of the
/// forward lock (p = +1, from Θ = 0) and of the reversed lock (p = −1, from Θ = 54.74°), each started
/// at the analytic f_c, with Θ kept in [0°, 54.74°] and f in `opts.free_range`.
pub fn lock_loss_curves(
    base: &crate::model::Gear,
    opts: &CurveOptions,
) -> Result<Vec<(String, Curve<crate::model::Gear>)>> {
    use crate::model::GearParam;
    let mut out = Vec::new();
    for s in lock_loss_starts(base)? {
        let o = CurveOptions {
            ds: opts.ds.abs() * if s.winding > 0 { 1.0 } else { -1.0 },
            along_range: (0.0, s.theta_rev_deg),
            ..*opts
        };
        let c = continue_curve(
            &crate::integrator::DEFAULT_METHOD,
            &s.gear,
            &s.spec,
            SpecialKind::Fold,
            GearParam::F,
            GearParam::ThetaDeg,
            s.x0,
            s.fc,
            &o,
        )?;
        out.push((s.label, c));
    }
    Ok(out)
}
