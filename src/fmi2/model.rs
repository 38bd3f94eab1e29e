//! What a model provides to the FMI 2.0 runtime. No C types, no pointers, no FMI calls:
//! a model is plain Rust, and the runtime turns it into an FMU.

use super::variables::VariableSet;
use serde::{Serialize, de::DeserializeOwned};

/// `<DefaultExperiment>` of the model description.
#[derive(Debug, Clone, Copy)]
pub struct DefaultExperiment {
    pub start_time: f64,
    pub stop_time: f64,
    pub step_size: f64,
}

/// Fixed facts about a model: its names and its documentation.
#[derive(Debug, Clone, Copy)]
pub struct ModelInfo {
    /// `modelName` and `modelIdentifier`: the binary is `<identifier>.so`.
    pub identifier: &'static str,
    pub description: &'static str,
    pub author: &'static str,
    pub version: &'static str,
    pub default_experiment: Option<DefaultExperiment>,
    /// HTML fragment for `documentation/index.html`: the equations and their sources.
    pub documentation_html: &'static str,
}

/// Why a step could not be taken. The runtime logs the message and answers `fmi2Discard`;
/// the model's variables hold the last consistent state at `reached_time`.
#[derive(Debug, Clone, PartialEq)]
pub struct StepFailure {
    pub reached_time: f64,
    pub message: String,
}

/// A co-simulation model. The runtime owns the FMI state machine, argument checks, logging,
/// FMU state and the C ABI; the model only computes.
pub trait CoSimModel: Clone + Serialize + DeserializeOwned + Send + 'static {
    type Vars: VariableSet;
    const INFO: ModelInfo;

    /// A model with every variable at its start value.
    fn new() -> Self;
    fn vars(&self) -> &Self::Vars;
    fn vars_mut(&mut self) -> &mut Self::Vars;

    /// Checks one value for the variable `decl` before it is stored (the runtime has already
    /// checked type, finiteness, declared min/max and whether it may be set now). `Err` says what
    /// is wrong; the value is then refused and the runtime logs it with the variable's name.
    fn check(&self, _decl: &super::variables::VarDecl, _value: super::variables::Value) -> Result<(), String> {
        Ok(())
    }

    /// Leaves initialization mode: derive the internal state and every calculated variable
    /// from the start values and parameters. `tolerance` is the importer's relative tolerance
    /// from `fmi2SetupExperiment`, when it defined one.
    fn initialize(&mut self, start_time: f64, tolerance: Option<f64>) -> Result<(), String>;

    /// A tunable parameter was set between steps; recompute what depends on it.
    fn parameters_changed(&mut self) -> Result<(), String> {
        Ok(())
    }

    /// Advances from `t` to `t + h` with the inputs as they are now.
    /// On failure the model leaves a consistent state at [`StepFailure::reached_time`].
    fn do_step(&mut self, t: f64, h: f64) -> Result<(), StepFailure>;
}
