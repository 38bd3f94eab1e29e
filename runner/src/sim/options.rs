//! What a run is asked ([`RunOptions`], [`Scheme`], [`Override`], [`Adaptive`]) and what it
//! gives ([`RunResult`], [`Terminated`], [`Failure`]).

use crate::Error;

/// How a communication point is evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheme {
    /// In dependency order: each instance's inputs from the outputs read just before (the default).
    GaussSeidel,
    /// Every output read, then every input set: a one-step delay at each feedthrough in a loop.
    Jacobi,
}

/// A per-run value for "component.variable", converted to the variable's type.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Override {
    Real(f64),
    Integer(i64),
    Boolean(bool),
    /// Text, as the command line gives it: parsed as the variable's type.
    Text(String),
}

/// One run.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct RunOptions {
    /// s; the run makes n = round(stop_time / step) steps.
    pub stop_time: f64,
    /// Communication step, s.
    pub step: f64,
    /// "component.variable" = value, on top of the system's parameter bindings.
    pub overrides: Vec<(String, Override)>,
    /// "component.variable" to read at every communication point (Real, Integer, Boolean).
    pub record: Vec<String>,
    /// Stop the run after the first communication point where |value| > limit, for a recorded
    /// "component.variable" (a fallen pendulum, a diverged run).
    pub stop_when_above: Vec<(String, f64)>,
    /// Error-controlled communication steps ([`Adaptive`]); `None`: fixed steps of `step`.
    pub adaptive: Option<Adaptive>,
    /// A first-order hold on the connections: see [`Simulation::input_derivatives`](crate::Simulation::input_derivatives).
    pub input_derivatives: bool,
    /// How algebraic loops are solved ([`crate::sim::LoopOptions`]: tolerances, iterations,
    /// finite differences).
    #[serde(default)]
    pub loops: crate::sim::LoopOptions,
}

/// Error-controlled communication steps: each step of h is made once whole and once as two
/// halves from the same FMU states (step doubling); the difference of the connected outputs at
/// its end estimates the coupling error of the halves. A step whose scaled difference
/// max |a - b| / (tolerance (1 + |b|)) exceeds 1 is rejected (every FMU set back to its state at
/// the step's start) and retried shorter; an accepted one keeps the halves' result, and the next
/// step grows or shrinks by 0.9 err^(-1/2) (the local coupling error of a held input is O(h^2)),
/// between 1/5 and 2 times, within [min_step, max_step]. Needs every component to get and set its
/// FMU state and to take variable steps; otherwise the run is made with fixed steps and
/// [`RunResult::note`] says why.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Adaptive {
    pub tolerance: f64,
    /// s (default: the run's `step` / 1000).
    pub min_step: Option<f64>,
    /// s (default: the run's stop time / 10).
    pub max_step: Option<f64>,
    /// The Real variables ("component.variable") whose difference is the estimate; empty: every
    /// connected output.
    pub error_on: Vec<String>,
}

impl RunOptions {
    pub fn new(stop_time: f64, step: f64) -> RunOptions {
        RunOptions {
            stop_time,
            step,
            overrides: Vec::new(),
            record: Vec::new(),
            stop_when_above: Vec::new(),
            adaptive: None,
            input_derivatives: false,
            loops: crate::sim::LoopOptions::default(),
        }
    }
}

/// What a run recorded: one row per communication point.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct RunResult {
    pub names: Vec<String>,
    /// s
    pub time: Vec<f64>,
    /// Row-major, `time.len() × names.len()`.
    pub values: Vec<f64>,
    /// Whether a `stop_when_above` condition ended the run before `stop_time`.
    pub stopped: bool,
    /// fmi2DoStep calls of the run (each is one call per component): the steps made, accepted
    /// or not.
    pub fmu_steps: usize,
    /// Error-controlled steps rejected (and made again shorter).
    pub rejected: usize,
    /// Why an error-controlled run was made with fixed steps, if it was.
    pub note: Option<String>,
    /// What each algebraic loop took (Jacobian kind, solves, Newton iterations), in the order.
    #[serde(default)]
    pub loops: Vec<crate::sim::LoopReport>,
    /// A component asked to end the simulation before the stop time: the run ended there.
    #[serde(default)]
    pub terminated: Option<Terminated>,
}

/// A component asked to end the simulation (FMI 2.0.5 4.2.3: fmi2DoStep answered fmi2Discard
/// and fmi2GetBooleanStatus(fmi2Terminated) fmi2True, "the slave wants to terminate the
/// simulation"; FMI 3.0.2 4.2.1: fmi3DoStep's `terminateSimulation`, "the FMU requests to stop
/// the simulation", or fmi3UpdateDiscreteStates'): the run ended there, as fmusim ends it, with
/// every component terminated (fmi2Terminate / fmi3Terminate). Not a failure.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Terminated {
    pub component: String,
    /// Its last successful time, s.
    pub time: f64,
    /// Who asked, when, and where the rows end.
    pub message: String,
}

impl RunResult {
    /// The recorded values of column `i`.
    pub fn column(&self, i: usize) -> Vec<f64> {
        let m = self.names.len();
        (0..self.time.len()).map(|k| self.values[k * m + i]).collect()
    }
}

/// A run that failed: the error, and what was recorded up to the failure.
#[derive(Debug, Clone)]
pub struct Failure {
    pub error: Error,
    pub partial: RunResult,
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.error.fmt(f)
    }
}

impl From<Error> for Failure {
    fn from(error: Error) -> Failure {
        Failure {
            error,
            partial: RunResult::default(),
        }
    }
}
