//! What FMI 2.0 and FMI 3.0 descriptions share: a variable's causality, variability and
//! initial, and the default experiment.

use crate::Version;
use std::fmt;

/// `causality` of a variable. `StructuralParameter` is FMI 3.0's only.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Causality {
    Parameter,
    CalculatedParameter,
    StructuralParameter,
    Input,
    Output,
    Local,
    Independent,
}

impl Causality {
    /// As the XML writes it, where `version` defines it.
    pub fn parse(s: &str, version: Version) -> Option<Causality> {
        Some(match s {
            "parameter" => Causality::Parameter,
            "calculatedParameter" => Causality::CalculatedParameter,
            "structuralParameter" if version == Version::Fmi3 => Causality::StructuralParameter,
            "input" => Causality::Input,
            "output" => Causality::Output,
            "local" => Causality::Local,
            "independent" => Causality::Independent,
            _ => return None,
        })
    }

    /// As the XML writes it.
    pub fn name(self) -> &'static str {
        match self {
            Causality::Parameter => "parameter",
            Causality::CalculatedParameter => "calculatedParameter",
            Causality::StructuralParameter => "structuralParameter",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Local => "local",
            Causality::Independent => "independent",
        }
    }
}

/// `variability` of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Variability {
    Constant,
    Fixed,
    Tunable,
    Discrete,
    Continuous,
}

impl Variability {
    /// As the XML writes it.
    pub fn parse(s: &str) -> Option<Variability> {
        Some(match s {
            "constant" => Variability::Constant,
            "fixed" => Variability::Fixed,
            "tunable" => Variability::Tunable,
            "discrete" => Variability::Discrete,
            "continuous" => Variability::Continuous,
            _ => return None,
        })
    }

    /// As the XML writes it.
    pub fn name(self) -> &'static str {
        match self {
            Variability::Constant => "constant",
            Variability::Fixed => "fixed",
            Variability::Tunable => "tunable",
            Variability::Discrete => "discrete",
            Variability::Continuous => "continuous",
        }
    }
}

/// `initial` of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Initial {
    Exact,
    Approx,
    Calculated,
}

impl Initial {
    /// As the XML writes it.
    pub fn parse(s: &str) -> Option<Initial> {
        Some(match s {
            "exact" => Initial::Exact,
            "approx" => Initial::Approx,
            "calculated" => Initial::Calculated,
            _ => return None,
        })
    }

    /// As the XML writes it.
    pub fn name(self) -> &'static str {
        match self {
            Initial::Exact => "exact",
            Initial::Approx => "approx",
            Initial::Calculated => "calculated",
        }
    }

    /// The `initial` in force where none is written: the default of the table causality ×
    /// variability (FMI 2.0 section 2.2.7, FMI 3.0 section 2.4.7.4; the two agree on every
    /// combination 2.0 has). `None` where `initial` is not defined (inputs, the independent
    /// variable).
    pub fn default_for(causality: Causality, variability: Variability) -> Option<Initial> {
        match (causality, variability) {
            (Causality::Input | Causality::Independent, _) => None,
            (_, Variability::Constant) => Some(Initial::Exact),
            (Causality::Parameter | Causality::StructuralParameter, _) => Some(Initial::Exact),
            (Causality::CalculatedParameter | Causality::Output | Causality::Local, _) => Some(Initial::Calculated),
        }
    }
}

macro_rules! display_as_written {
    ($($t:ty),*) => {$(
        impl fmt::Display for $t {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.name())
            }
        }
    )*};
}
display_as_written!(Causality, Variability, Initial);

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
        Some(c) => Causality::parse(c, version).ok_or_else(|| format!("variable '{name}': unknown causality '{c}'"))?,
    };
    let variability = match e.attr("variability") {
        None => default_variability,
        Some(v) => Variability::parse(v).ok_or_else(|| format!("variable '{name}': unknown variability '{v}'"))?,
    };
    let initial = match e.attr("initial") {
        None => None,
        Some(i) => Some(Initial::parse(i).ok_or_else(|| format!("variable '{name}': unknown initial '{i}'"))?),
    };
    Ok((causality, variability, initial))
}
