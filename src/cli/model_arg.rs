//! `--model FILE`: run a dynamics command on the recorded gear of a model.json (written by
//! `gearbif diagnose`) instead of the paper's gear built from the gear flags.

use super::common::{ConventionArg, GearArgs};
use super::methods::{MethodArg, MethodArgs};
use crate::error::{Error, Result};
use crate::integrator::{EventDriven, EventDriven853, FixedStep, FlowMethod};
use crate::model::recorded::file::ModelFile;
use crate::model::recorded::{RecordedModel, RecordedParam};
use crate::model::{Convention, Gear, Parametrised};
use clap::Args;
use std::path::PathBuf;

/// The model file argument.
#[derive(Debug, Clone, Args, Default)]
pub struct ModelArgs {
    /// model.json of a diagnosed gear (`gearbif diagnose`): run on that recorded gear, with
    /// every term the diagnosis found (the gear flags and --config are then refused).
    #[arg(long, value_name = "FILE")]
    pub model: Option<PathBuf>,
}

impl ModelArgs {
    /// The recorded gear driven at `f` Hz, or `None` without --model. Refuses the gear flags
    /// (and `--convention paper`) next to --model: the file defines the gear.
    pub fn recorded(&self, gear: &GearArgs, f: f64) -> Result<Option<RecordedModel>> {
        self.file(gear)?.map(|m| m.model(f)).transpose()
    }

    /// The model file, read and checked, or `None` without --model; refuses the gear flags next
    /// to it as [`Self::recorded`] does.
    pub fn file(&self, gear: &GearArgs) -> Result<Option<ModelFile>> {
        let Some(path) = &self.model else {
            return Ok(None);
        };
        let set: Vec<&str> = [
            ("--config", gear.config.is_some()),
            ("--m1", gear.m1.is_some()),
            ("--m2", gear.m2.is_some()),
            ("--r", gear.r.is_some()),
            ("--inertia", gear.inertia.is_some()),
            ("--theta-deg", gear.theta_deg.is_some()),
            ("--phi-deg", gear.phi_deg.is_some()),
            ("--zeta", gear.zeta.is_some()),
            ("--eta", gear.eta.is_some()),
            (
                "--convention paper",
                gear.convention == ConventionArg::Paper,
            ),
        ]
        .into_iter()
        .filter_map(|(flag, on)| on.then_some(flag))
        .collect();
        if !set.is_empty() {
            return Err(Error::inconsistent(
                format!("--model, {}", set.join(", ")),
                "the model file defines the gear (physical sign): drop the gear flags",
            ));
        }
        ModelFile::read(path).map(Some)
    }
}

/// The integration method of `m` for the recorded gear (the regularised and the Taylor method are
/// the paper's gear's only).
pub fn method(m: &MethodArgs) -> Result<Box<dyn FlowMethod<RecordedModel>>> {
    super::common::tolerance("tol", m.tol)?;
    match m.method {
        MethodArg::Event => Ok(Box::new(EventDriven)),
        MethodArg::Dop853 => Ok(Box::new(EventDriven853)),
        MethodArg::Fixed => {
            super::common::count("steps", m.steps, 1, super::common::limits::TURNS_MAX)?;
            Ok(Box::new(FixedStep {
                steps_per_period: m.steps,
            }))
        }
        MethodArg::Regularised => Err(Error::inconsistent(
            "--model, --method regularised",
            "the regularised method runs the paper's gear only",
        )),
        MethodArg::Taylor => Err(Error::inconsistent(
            "--model, --method taylor",
            "the recorded gear has no Taylor coefficients yet: use --method dop853 or event",
        )),
    }
}

/// What a command's summary says of the system: its convention and base parameters, and the
/// model file it came from.
pub struct SystemInfo {
    /// The sign convention (physical for a model file).
    pub convention: Convention,
    /// Drive frequency, Hz.
    pub f: f64,
    /// g, Δ, ζ, η.
    pub base: [f64; 4],
    /// The model file (--model).
    pub model: Option<String>,
}

impl SystemInfo {
    /// Of the paper's gear.
    pub fn of_gear(gear: &Gear) -> Self {
        Self {
            convention: gear.convention,
            f: gear.f,
            base: [gear.g, gear.delta, gear.zeta, gear.eta],
            model: None,
        }
    }

    /// Of a recorded gear read from the file of `args`.
    pub fn of_model(m: &RecordedModel, args: &ModelArgs) -> Self {
        let p = |q| m.param(q);
        Self {
            convention: Convention::Physical,
            f: p(RecordedParam::F),
            base: [
                p(RecordedParam::G),
                p(RecordedParam::Delta),
                p(RecordedParam::Zeta),
                p(RecordedParam::Eta),
            ],
            model: args.model.as_ref().map(|p| p.display().to_string()),
        }
    }
}

/// The initial state "BETA_DEG,OMEGA" of `x0`, or the recorded gear's locked-input equilibrium
/// of its base coupling at α = 0, at rest.
pub fn start(m: &RecordedModel, x0: &Option<String>) -> Result<[f64; 2]> {
    match x0 {
        Some(s) => super::methods::parse_x0(s),
        None => Ok([
            crate::model::gear::equilibrium_angle(m.param(RecordedParam::Delta), 0.0),
            0.0,
        ]),
    }
}
