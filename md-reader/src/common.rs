//! What FMI 2.0 and FMI 3.0 descriptions share: a variable's causality, variability and
//! initial (re-exported from `fmi-standard`), and the default experiment.

use crate::Version;

/// `causality`, `variability` and `initial` of a variable: the types of `fmi-standard`, where
/// the standard's rules on them (legal combinations, the default `initial`) are written once.
/// `Causality::StructuralParameter` is FMI 3.0's only.
pub use fmi_standard::{Causality, Initial, Variability};

/// `<DefaultExperiment>`: each attribute as written (a report shows it unchanged), and as a
/// number by the method of the same name.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct DefaultExperiment {
    pub start_time: Option<String>,
    pub stop_time: Option<String>,
    pub tolerance: Option<String>,
    pub step_size: Option<String>,
}

fn number(text: &Option<String>) -> Option<f64> {
    text.as_deref().and_then(|v| v.trim().parse().ok())
}

impl DefaultExperiment {
    pub(crate) fn read(e: &crate::read::Element) -> DefaultExperiment {
        DefaultExperiment {
            start_time: e.string("startTime"),
            stop_time: e.string("stopTime"),
            tolerance: e.string("tolerance"),
            step_size: e.string("stepSize"),
        }
    }

    pub fn start_time(&self) -> Option<f64> {
        number(&self.start_time)
    }

    pub fn stop_time(&self) -> Option<f64> {
        number(&self.stop_time)
    }

    pub fn tolerance(&self) -> Option<f64> {
        number(&self.tolerance)
    }

    pub fn step_size(&self) -> Option<f64> {
        number(&self.step_size)
    }
}

/// Reads a variable's `causality`, `variability` and `initial` (defaults: local, and the
/// version's default variability), with an error that names the variable.
pub(crate) fn kind(
    e: &crate::read::Element,
    name: &str,
    version: Version,
    default_variability: Variability,
) -> Result<(Causality, Variability, Option<Initial>), String> {
    let causality = match e.attr("causality") {
        None => Causality::Local,
        Some(c) => Causality::from_name(c)
            .filter(|c| c.in_fmi2() || version == Version::Fmi3)
            .ok_or_else(|| format!("variable '{name}': unknown causality '{c}'"))?,
    };
    let variability = match e.attr("variability") {
        None => default_variability,
        Some(v) => Variability::from_name(v).ok_or_else(|| format!("variable '{name}': unknown variability '{v}'"))?,
    };
    let initial = match e.attr("initial") {
        None => None,
        Some(i) => Some(Initial::from_name(i).ok_or_else(|| format!("variable '{name}': unknown initial '{i}'"))?),
    };
    Ok((causality, variability, initial))
}
