//! Sweep axes addressed through the parameter lens ([`Parametrised`]): an axis is a parameter
//! name the system declares ([`Parameter::name`]) and its values. [`parse_axis`] reads
//! `name:start:stop:step` or `name:start:stop:n:log` for any lens; [`Axis`] is the gear's axis,
//! whose parameter [`SweepParam`] is a name of the gear's lens ([`GearParam`]) or the built gear's
//! inertia I.

use crate::error::{positive, Error, Result};
use crate::model::gear::shaft_index;
use crate::model::{Gear, GearParam, GearParams, Parameter, Parametrised};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// What an axis of the gear's sweep varies: a parameter of the gear's lens ([`GearParam`]: `f`,
/// `g`, `zeta`, `eta`, `delta`, `theta`), or the output inertia I of the built gear ([`GearParams`],
/// `inertia`), which reaches the reduced gear through the lens's g = c/I. The names are the lens's
/// names; `theta_deg` is read as `theta`, and a Θ axis is written `theta_deg` in checkpoints and
/// CSV headers, as before the lens existed.
///
/// Unlike the lens's Θ (read back in [0°, 90°]), a sweep's Θ may be signed (Fig. 8: −90° to 90°):
/// it is set through Δ = 1 − 3 sin²Θ, which is even in Θ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SweepParam {
    /// A parameter of the gear's lens.
    Lens(GearParam),
    /// Output inertia I, kg m² (g = c/I with c of the spec's [`GearParams`]).
    Inertia,
}

#[allow(non_upper_case_globals)]
impl SweepParam {
    /// Parallel shaft angle Θ = Φ, degrees (signed).
    pub const ThetaDeg: Self = Self::Lens(GearParam::ThetaDeg);
    /// Drive frequency f, Hz.
    pub const F: Self = Self::Lens(GearParam::F);
    /// Viscous damping ζ, 1/s.
    pub const Zeta: Self = Self::Lens(GearParam::Zeta);
    /// Dry friction η, 1/s².
    pub const Eta: Self = Self::Lens(GearParam::Eta);
}

impl From<GearParam> for SweepParam {
    fn from(p: GearParam) -> Self {
        Self::Lens(p)
    }
}

impl Parameter for SweepParam {
    const ALL: &'static [Self] = &[
        Self::ThetaDeg,
        Self::F,
        Self::Zeta,
        Self::Eta,
        Self::Lens(GearParam::G),
        Self::Lens(GearParam::Delta),
        Self::Inertia,
    ];
    fn name(self) -> &'static str {
        match self {
            Self::Lens(p) => p.name(),
            Self::Inertia => "inertia",
        }
    }
    fn unit(self) -> &'static str {
        match self {
            Self::Lens(p) => p.unit(),
            Self::Inertia => "kg m²",
        }
    }
    fn symbol(self) -> &'static str {
        match self {
            Self::Lens(p) => p.symbol(),
            Self::Inertia => "I",
        }
    }
    /// A lens name, `inertia`, or `theta_deg` (the column name of Θ).
    fn from_name(s: &str) -> Result<Self> {
        match s {
            "theta_deg" => Ok(Self::ThetaDeg),
            "inertia" => Ok(Self::Inertia),
            _ => GearParam::from_name(s)
                .map(Self::Lens)
                .map_err(|e| match e {
                    Error::UnknownParameter { name, expected } => Error::UnknownParameter {
                        name,
                        expected: format!("{expected}, inertia"),
                    },
                    e => e,
                }),
        }
    }
}

impl SweepParam {
    /// Parses a name ([`Parameter::from_name`]).
    pub fn parse(s: &str) -> Result<Self> {
        Self::from_name(s)
    }

    /// Column name in outputs and checkpoints: the lens name with its unit where the unit is not
    /// implied (`theta_deg`, `f_hz`).
    pub fn column_name(self) -> &'static str {
        match self {
            Self::ThetaDeg => "theta_deg",
            Self::F => "f_hz",
            p => p.name(),
        }
    }

    /// `gear` with this parameter set to `value`, through the gear's lens; `params` is the built
    /// gear the reduced one comes from (for I: g = c/I).
    pub fn apply(self, gear: &Gear, params: &GearParams, value: f64) -> Result<Gear> {
        match self {
            Self::ThetaDeg => {
                let t = crate::error::finite("theta_deg", value)?.to_radians();
                gear.with_param(GearParam::Delta, shaft_index(t, t))
            }
            Self::Lens(p) => gear.with_param(p, value),
            Self::Inertia => gear.with_param(
                GearParam::G,
                params.coupling() / positive("inertia", value)?,
            ),
        }
    }
}

impl Serialize for SweepParam {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let name = match *self {
            Self::ThetaDeg => "theta_deg",
            p => p.name(),
        };
        s.serialize_str(name)
    }
}

impl<'de> Deserialize<'de> for SweepParam {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        Self::from_name(&s).map_err(serde::de::Error::custom)
    }
}

/// Largest number of points of one sweep axis, linear or log (and of a whole sweep grid, see
/// [`GRID_POINTS_MAX`]).
pub const AXIS_POINTS_MAX: usize = 10_000_000;

/// Largest number of points of a whole sweep grid (rows × columns).
pub const GRID_POINTS_MAX: usize = 10_000_000;

/// The values `start, start + step, …` up to `stop` (inclusive within step/1000), computed as
/// start + i·step (no accumulated rounding); `what` names the axis in errors.
pub fn range_values(what: &str, start: f64, stop: f64, step: f64) -> Result<Vec<f64>> {
    if ![start, stop, step].iter().all(|v| v.is_finite()) {
        return Err(Error::option(
            format!("axis {what}"),
            format!(
                "start {}, stop {} and step {} must be finite",
                crate::error::show(start),
                crate::error::show(stop),
                crate::error::show(step)
            ),
        ));
    }
    if step == 0.0 || (stop - start) / step < 0.0 {
        return Err(Error::option(
            format!("axis {what}"),
            format!("step {step} does not lead from {start} to {stop}"),
        ));
    }
    // counted as a float first: (stop − start)/step may pass every integer type
    let nf = ((stop - start) / step + 1e-3).floor() + 1.0;
    if nf.is_nan() || nf > AXIS_POINTS_MAX as f64 {
        return Err(Error::shape(
            format!("points of axis {what}"),
            "at most 1e7",
            nf.min(usize::MAX as f64) as usize,
        ));
    }
    let n = nf as usize;
    Ok((0..n).map(|i| start + i as f64 * step).collect())
}

/// `n` log-spaced values from `start` to `stop` (both > 0); `what` names the axis in errors.
pub fn log_values(what: &str, start: f64, stop: f64, n: usize) -> Result<Vec<f64>> {
    positive("start", start)?;
    positive("stop", stop)?;
    if n < 2 {
        return Err(Error::shape(
            format!("points of log axis {what}"),
            ">= 2",
            n,
        ));
    }
    if n > AXIS_POINTS_MAX {
        return Err(Error::shape(
            format!("points of log axis {what}"),
            "at most 1e7",
            n,
        ));
    }
    let (a, b) = (start.ln(), stop.ln());
    Ok((0..n)
        .map(|i| (a + (b - a) * i as f64 / (n - 1) as f64).exp())
        .collect())
}

/// Parses an axis of any lens: `name:start:stop:step` or `name:start:stop:n:log`, the name one of
/// the system's [`Parameter::name`]s (e.g. `theta:-90:90:5`, `f:0.5:50:40:log`, `mu:0.1:0.5:0.1`
/// for the Coulomb oscillator).
pub fn parse_axis<P: Parameter>(s: &str) -> Result<(P, Vec<f64>)> {
    let parts: Vec<&str> = s.split(':').collect();
    let num = |x: &str| -> Result<f64> {
        x.trim()
            .parse::<f64>()
            .map_err(|_| Error::option(format!("axis `{s}`"), format!("`{x}` is not a number")))
    };
    match parts.as_slice() {
        [p, a, b, st] => {
            let p = P::from_name(p)?;
            Ok((p, range_values(p.name(), num(a)?, num(b)?, num(st)?)?))
        }
        [p, a, b, n, "log"] => {
            let n = num(n)?;
            if n.fract() != 0.0 || n < 2.0 {
                return Err(Error::option(
                    format!("axis `{s}`"),
                    "the count of a log axis must be an integer >= 2",
                ));
            }
            if n > AXIS_POINTS_MAX as f64 {
                return Err(Error::option(
                    format!("axis `{s}`"),
                    format!(
                        "{} points: a log axis has at most 1e7",
                        crate::error::show(n)
                    ),
                ));
            }
            let p = P::from_name(p)?;
            Ok((p, log_values(p.name(), num(a)?, num(b)?, n as usize)?))
        }
        _ => Err(Error::option(
            format!("axis `{s}`"),
            "expected param:start:stop:step or param:start:stop:n:log",
        )),
    }
}

/// One axis of the gear's sweep: a parameter and its values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    /// The parameter.
    pub param: SweepParam,
    /// Its values, in sweep order.
    pub values: Vec<f64>,
}

impl Axis {
    /// Values start, start + step, … up to stop ([`range_values`]).
    pub fn range(param: impl Into<SweepParam>, start: f64, stop: f64, step: f64) -> Result<Self> {
        let param = param.into();
        let values = range_values(param.column_name(), start, stop, step)?;
        Ok(Self { param, values })
    }

    /// `n` log-spaced values from `start` to `stop` ([`log_values`]).
    pub fn log(param: impl Into<SweepParam>, start: f64, stop: f64, n: usize) -> Result<Self> {
        let param = param.into();
        let values = log_values(param.column_name(), start, stop, n)?;
        Ok(Self { param, values })
    }

    /// Parses `param:start:stop:step` or `param:start:stop:nlog` with a trailing `log`
    /// (e.g. `theta:-90:90:5`, `f:0.1:100:0.02`, `f:0.5:50:40:log`; [`parse_axis`]).
    pub fn parse(s: &str) -> Result<Self> {
        let (param, values) = parse_axis::<SweepParam>(s)?;
        Ok(Self { param, values })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_the_lens_names_and_files_keep_theta_deg() {
        for p in [GearParam::F, GearParam::Zeta, GearParam::Eta, GearParam::G] {
            assert_eq!(SweepParam::parse(p.name()).unwrap(), SweepParam::Lens(p));
        }
        assert_eq!(SweepParam::parse("theta").unwrap(), SweepParam::ThetaDeg);
        assert_eq!(
            SweepParam::parse("theta_deg").unwrap(),
            SweepParam::ThetaDeg
        );
        let json =
            serde_json::to_string(&[SweepParam::ThetaDeg, SweepParam::F, SweepParam::Inertia])
                .unwrap();
        assert_eq!(json, r#"["theta_deg","f","inertia"]"#);
        let back: Vec<SweepParam> = serde_json::from_str(&json).unwrap();
        assert_eq!(
            back,
            [SweepParam::ThetaDeg, SweepParam::F, SweepParam::Inertia]
        );
        assert!(matches!(
            SweepParam::parse("mass"),
            Err(Error::UnknownParameter { expected, .. }) if expected.ends_with("theta, inertia")
        ));
    }

    #[test]
    fn setting_through_the_lens_equals_building_the_gear() {
        let params = GearParams::paper();
        let base = params.driven(1.0).unwrap();
        for (p, v, built) in [
            (
                SweepParam::ThetaDeg,
                -35.0,
                params.with_parallel_shafts_deg(-35.0).driven(1.0),
            ),
            (
                SweepParam::Inertia,
                8e-5,
                GearParams {
                    inertia: 8e-5,
                    ..params
                }
                .driven(1.0),
            ),
            (
                SweepParam::Zeta,
                0.7,
                GearParams {
                    zeta: 0.7,
                    ..params
                }
                .driven(1.0),
            ),
            (SweepParam::F, 2.5, params.driven(2.5)),
        ] {
            // bit for bit: a checkpoint written before the lens resumes to the same rows
            assert_eq!(p.apply(&base, &params, v).unwrap(), built.unwrap(), "{p:?}");
        }
        assert!(matches!(
            SweepParam::Inertia.apply(&base, &params, -1.0),
            Err(Error::InvalidParameter {
                name: "inertia",
                ..
            })
        ));
    }

    #[test]
    fn bad_axes_are_typed() {
        assert!(matches!(
            Axis::parse("theta:0:1:x"),
            Err(Error::InvalidOption { .. })
        ));
        assert!(matches!(
            Axis::parse("f:1:2:2.5:log"),
            Err(Error::InvalidOption { .. })
        ));
        assert!(matches!(
            Axis::range(GearParam::F, 0.0, 1.0, 1e-9),
            Err(Error::Shape { got, .. }) if got > 10_000_000
        ));
        for big in ["f:1:2:1e13:log", "f:1:2:1e20:log", "f:1:2:10000001:log"] {
            assert!(
                matches!(Axis::parse(big), Err(Error::InvalidOption { .. })),
                "{big}"
            );
        }
        assert!(matches!(
            Axis::log(GearParam::F, 1.0, 2.0, usize::MAX),
            Err(Error::Shape { .. })
        ));
        let (p, v) = parse_axis::<GearParam>("g:10:30:10").unwrap();
        assert_eq!((p, v), (GearParam::G, vec![10.0, 20.0, 30.0]));
    }
}
