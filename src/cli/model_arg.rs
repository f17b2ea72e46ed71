//! `--model FILE`: run a dynamics command on the recorded gear of a model.json (written by
//! `gearbif diagnose`) instead of the paper's gear built from the gear flags.

use super::common::{ConventionArg, GearArgs};
use super::methods::{MethodArg, MethodArgs};
use crate::error::{Error, Result};
use crate::integrator::{EventDriven, EventDriven853, FixedStep, FlowMethod};
use crate::model::recorded::file::ModelFile;
use crate::model::recorded::RecordedModel;
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
        ModelFile::read(path)?.model(f).map(Some)
    }
}

/// The integration method of `m` for the recorded gear (the regularised method is the paper's
/// gear's only).
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
    }
}
