//! The effects a model file lists (docs/diagnosis.md's catalog) as an enum, and for each the
//! parameters of the recorded gear it adds and their value with the effect switched off: the
//! gear without the effect is the same file with those parameters at their off value
//! ([`super::file::ModelFile::scaled`]). The strings are the file's (`effects`), read once by
//! [`Effect::from_name`].

use super::RecordedParam;
use crate::error::{Error, Result};

/// An effect of the catalog.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Effect {
    /// Misaligned shafts: the coupling coefficients c_cc, c_ss.
    CouplingGeometry,
    /// A lab-fixed torque: A_k sin kβ + B_k cos kβ.
    StaticTorque,
    /// Dry friction growing with the bearing load: η_L.
    LoadDependentFriction,
    /// Breakaway above the sliding friction: η_Δs.
    StaticFriction,
    /// Drag relative to the input: c_r.
    CorotatingDrag,
    /// Quadratic drag q (p = 2).
    QuadraticDrag,
    /// Power-law drag q, p.
    PowerLawDrag,
    /// The input magnet's lag χ.
    InputCompliance,
    /// Lost drive steps: the drive offset ε of the fit's reference.
    DriveSteps,
    /// The camera's latency (the measurement model, not the dynamics).
    SensorLatency,
    /// A drift of a parameter over the session (not part of a driven model).
    ParameterDrift,
    /// A parameter depending on the run's conditions (not part of a driven model).
    ConditionDependence,
    /// The sparse search's terms (`extra_terms` of the file).
    Unexplained,
}

impl Effect {
    /// Every effect, in the order of [`super::file::KNOWN_EFFECTS`].
    pub const ALL: [Effect; 13] = [
        Effect::CouplingGeometry,
        Effect::StaticTorque,
        Effect::LoadDependentFriction,
        Effect::StaticFriction,
        Effect::CorotatingDrag,
        Effect::QuadraticDrag,
        Effect::PowerLawDrag,
        Effect::InputCompliance,
        Effect::DriveSteps,
        Effect::SensorLatency,
        Effect::ParameterDrift,
        Effect::ConditionDependence,
        Effect::Unexplained,
    ];

    /// The catalog's identifier.
    pub fn name(self) -> &'static str {
        use Effect::*;
        match self {
            CouplingGeometry => "coupling_geometry",
            StaticTorque => "static_torque",
            LoadDependentFriction => "load_dependent_friction",
            StaticFriction => "static_friction",
            CorotatingDrag => "corotating_drag",
            QuadraticDrag => "quadratic_drag",
            PowerLawDrag => "power_law_drag",
            InputCompliance => "input_compliance",
            DriveSteps => "drive_steps",
            SensorLatency => "sensor_latency",
            ParameterDrift => "parameter_drift",
            ConditionDependence => "condition_dependence",
            Unexplained => "unexplained",
        }
    }

    /// The effect of identifier `s`.
    pub fn from_name(s: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|e| e.name() == s)
            .ok_or_else(|| Error::unknown_name("effect", s, Self::ALL.map(Effect::name)))
    }

    /// The gear's parameters this effect adds, each with its value when the effect is off (the
    /// sparse search's terms of [`Effect::Unexplained`] are not lens parameters: they are the
    /// file's `extra_terms`, off at 0).
    pub fn parameters(self) -> &'static [(RecordedParam, f64)] {
        use RecordedParam as P;
        match self {
            Effect::CouplingGeometry => &[(P::CouplingCc, 0.0), (P::CouplingSs, 0.0)],
            Effect::StaticTorque => &[
                (P::StaticA, 0.0),
                (P::StaticB, 0.0),
                (P::StaticA2, 0.0),
                (P::StaticB2, 0.0),
                (P::StaticA3, 0.0),
                (P::StaticB3, 0.0),
            ],
            Effect::LoadDependentFriction => &[(P::LoadFriction, 0.0)],
            Effect::StaticFriction => &[(P::StaticExcess, 0.0)],
            Effect::CorotatingDrag => &[(P::CorotatingDrag, 0.0)],
            Effect::QuadraticDrag | Effect::PowerLawDrag => &[(P::DragQ, 0.0)],
            Effect::InputCompliance => &[(P::Compliance, 0.0)],
            Effect::DriveSteps => &[(P::DriveOffset, 0.0)],
            Effect::SensorLatency
            | Effect::ParameterDrift
            | Effect::ConditionDependence
            | Effect::Unexplained => &[],
        }
    }

    /// True when the effect is part of the dynamics (it can be switched off in the gear).
    pub fn in_dynamics(self) -> bool {
        !self.parameters().is_empty() || self == Effect::Unexplained
    }

    /// True for the drag family (a law fitted over the recorded speeds).
    pub fn is_drag(self) -> bool {
        matches!(
            self,
            Effect::CorotatingDrag | Effect::QuadraticDrag | Effect::PowerLawDrag
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every identifier a model file may list is an effect, and back.
    #[test]
    fn names_are_the_files() {
        let names: Vec<&str> = Effect::ALL.iter().map(|e| e.name()).collect();
        assert_eq!(names, super::super::file::KNOWN_EFFECTS);
        for e in Effect::ALL {
            assert_eq!(Effect::from_name(e.name()).unwrap(), e);
        }
        assert!(Effect::from_name("gremlins").is_err());
    }
}
