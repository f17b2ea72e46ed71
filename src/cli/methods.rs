//! Arguments shared by the commands that integrate: the method and its settings, the drive
//! frequency, the initial state.

use super::common::{check_frequency, count, limits, start_state, tolerance, within, GearArgs};
use crate::error::{finite, Error, Result};
use crate::integrator::{EventDriven, EventDriven853, FixedStep, FlowMethod, Taylor};
use crate::model::Gear;
use clap::Args;

/// `--method` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum MethodArg {
    /// Exact event-driven Filippov integration with adaptive Dormand–Prince 5(4) (saltation
    /// matrices).
    Event,
    /// The same event-driven integration with Dormand–Prince 8(5,3): fewer, longer steps, faster
    /// at every tolerance (the default).
    #[default]
    Dop853,
    /// The same event-driven integration by Taylor's method of adaptive order and step (the gear
    /// provides its Taylor coefficients); fewer, cheaper steps than the DOP853 (docs/performance.md,
    /// "Event-driven Taylor method"). With parameter Jacobians the DOP853 is used.
    Taylor,
    /// The paper's fixed-step RK4 with a naive sgn(ω) (`--steps` per period).
    Fixed,
    /// Friction η tanh(ω/ε) as a stiff ODE solved by diffsol ESDIRK3(4) (feature `diffsol-check`).
    Regularised,
}

/// Integration settings.
#[derive(Debug, Clone, Args)]
pub struct MethodArgs {
    /// Integration method (default: dop853, the event-driven Dormand–Prince 8(5,3); `event` is
    /// the event-driven Dormand–Prince 5(4)).
    #[arg(long, value_enum, default_value_t = MethodArg::Dop853)]
    pub method: MethodArg,
    /// Tolerance [dimensionless], in (0, 1): rtol = tol, atol = 1e-3·tol (event and regularised
    /// methods).
    #[arg(long, default_value_t = 1e-9, allow_hyphen_values = true)]
    pub tol: f64,
    /// Steps per drive period for `--method fixed` [1], 1 to 1000000 (the paper uses 50).
    #[arg(long, default_value_t = 50)]
    pub steps: usize,
    /// Regularisation velocity ε for `--method regularised` [rad/s], in (0, 1].
    #[arg(long, default_value_t = 1e-4, allow_hyphen_values = true)]
    pub epsilon: f64,
}

impl MethodArgs {
    /// Validates the settings and returns the chosen method.
    pub fn method(&self) -> Result<Box<dyn FlowMethod<Gear>>> {
        tolerance("tol", self.tol)?;
        match self.method {
            MethodArg::Event => Ok(Box::new(EventDriven)),
            MethodArg::Dop853 => Ok(Box::new(EventDriven853)),
            MethodArg::Taylor => Ok(Box::new(Taylor)),
            MethodArg::Fixed => {
                count("steps", self.steps, 1, limits::TURNS_MAX)?;
                Ok(Box::new(FixedStep {
                    steps_per_period: self.steps,
                }))
            }
            MethodArg::Regularised => {
                within(
                    "epsilon",
                    self.epsilon,
                    f64::MIN_POSITIVE,
                    1.0,
                    "must be in (0, 1] rad/s",
                )?;
                #[cfg(feature = "diffsol-check")]
                {
                    Ok(Box::new(crate::integrator::Regularised::new(self.epsilon)))
                }
                #[cfg(not(feature = "diffsol-check"))]
                {
                    Err(Error::FeatureDisabled {
                        what: "--method regularised",
                        feature: "diffsol-check",
                    })
                }
            }
        }
    }
}

/// The drive frequency and the initial state.
#[derive(Debug, Clone, Args)]
pub struct DriveArgs {
    /// Drive (input) frequency f [Hz], in [1e-3, 1e4].
    #[arg(long, default_value_t = 2.7, allow_hyphen_values = true)]
    pub f: f64,
    /// Initial state "BETA,OMEGA": output angle β [deg] and velocity ω [rad/s] at t = 0, in the
    /// chosen --convention, |β| <= 360°, |ω| <= 1e6 rad/s (default: the locked-input equilibrium
    /// at α = 0, at rest). The states of orbits (`continue`, `locate`, `boundary`: --state-rad)
    /// are in rad.
    #[arg(
        long = "x0-deg",
        value_name = "BETA_DEG,OMEGA",
        allow_hyphen_values = true
    )]
    pub x0: Option<String>,
}

impl DriveArgs {
    /// The driven gear in the chosen convention.
    pub fn gear(&self, g: &GearArgs) -> Result<Gear> {
        let p = g.params()?;
        check_frequency(self.f)?;
        Ok(p.driven(self.f)?.with_convention(g.convention()))
    }

    /// The initial state (β [rad], ω [rad/s]) in the gear's convention.
    pub fn x0(&self, gear: &Gear) -> Result<[f64; 2]> {
        match &self.x0 {
            None => Ok([
                crate::model::gear::equilibrium_angle(gear.delta, gear.alpha0)
                    + gear.convention.beta_offset(),
                0.0,
            ]),
            Some(s) => parse_x0(s),
        }
    }
}

/// Parses "BETA_DEG,OMEGA" into (β [rad], ω [rad/s]).
pub fn parse_x0(s: &str) -> Result<[f64; 2]> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 2 {
        return Err(Error::option(
            "--x0-deg",
            format!("expected BETA_DEG,OMEGA (two numbers), got `{s}`"),
        ));
    }
    let num = |name: &'static str, t: &str| -> Result<f64> {
        let v: f64 = t
            .parse()
            .map_err(|_| Error::option("--x0-deg", format!("`{t}` is not a number")))?;
        finite(name, v)
    };
    let beta = num("x0-deg beta", parts[0])?;
    let omega = num("x0-deg omega", parts[1])?;
    start_state("--x0-deg", beta, omega, true)?;
    Ok([beta.to_radians(), omega])
}
