//! The standard's state machines as tables: the states of FMI 2.0 and 3.0 (co-simulation and
//! model exchange) and, for every state-dependent function, the states it is allowed in, in each
//! version. [`super::instance::Instance::check_state`] is the one place that enforces them.
#![allow(non_upper_case_globals)]

use super::{Terms, Version};
use serde::{Deserialize, Serialize};

listed_enum! {
    /// The states of the state machines, named as in FMI 2.0 (co-simulation, section 4.2.4; model
    /// exchange, section 3.2.3: `EventMode`, `ContinuousTimeMode`); FMI 3.0 calls `StepComplete`
    /// Step Mode and `StepFailed` Step Discarded, and has no `StepCanceled` (each layer's
    /// [`Terms::states`] say the names). An instance is in the states of the interface it was
    /// instantiated for. `StepInProgress` does not occur: every step here is synchronous.
    #[derive(Serialize, Deserialize)]
    pub enum State {
        Instantiated,
        InitializationMode,
        StepComplete,
        StepFailed,
        StepCanceled,
        Terminated,
        Error,
        Fatal,
        EventMode,
        ContinuousTimeMode,
        /// FMI 3.0: structural parameters are set (from Instantiated, back to it).
        ConfigurationMode,
        /// FMI 3.0: tunable structural parameters are set (from Step Mode or, in model
        /// exchange, Event Mode, back to it).
        ReconfigurationMode,
        /// FMI 3.0 Scheduled Execution: between the activations of model partitions
        /// (fmi3ActivateModelPartition), after fmi3ExitInitializationMode.
        ClockActivationMode,
        /// FMI 3.0 Scheduled Execution: while the importer's clockUpdate callback runs (a
        /// partition ticked an output clock or gave a countdown clock its interval); the
        /// importer reads the clocks, intervals and outputs from inside it.
        ClockUpdateMode,
    }
}

impl State {
    /// The core's name of the state: FMI 2.0's (each layer's [`Terms`] says its own).
    pub const fn name(self) -> &'static str {
        match self {
            State::Instantiated => "Instantiated",
            State::InitializationMode => "InitializationMode",
            State::StepComplete => "StepComplete",
            State::StepFailed => "StepFailed",
            State::StepCanceled => "StepCanceled",
            State::Terminated => "Terminated",
            State::Error => "Error",
            State::Fatal => "Fatal",
            State::EventMode => "EventMode",
            State::ContinuousTimeMode => "ContinuousTimeMode",
            State::ConfigurationMode => "ConfigurationMode",
            State::ReconfigurationMode => "ReconfigurationMode",
            State::ClockActivationMode => "ClockActivationMode",
            State::ClockUpdateMode => "ClockUpdateMode",
        }
    }
}

const fn bit(s: State) -> u16 {
    1 << s as u8
}
const INSTANTIATED: u16 = bit(State::Instantiated);
const INIT: u16 = bit(State::InitializationMode);
const STEP_COMPLETE: u16 = bit(State::StepComplete);
const STEP_FAILED: u16 = bit(State::StepFailed);
const STEP_CANCELED: u16 = bit(State::StepCanceled);
const TERMINATED: u16 = bit(State::Terminated);
const ERROR: u16 = bit(State::Error);
const FATAL: u16 = bit(State::Fatal);
const EVENT: u16 = bit(State::EventMode);
const CONTINUOUS: u16 = bit(State::ContinuousTimeMode);
const CONFIGURATION: u16 = bit(State::ConfigurationMode);
const RECONFIGURATION: u16 = bit(State::ReconfigurationMode);
const CLOCK_ACTIVATION: u16 = bit(State::ClockActivationMode);
const CLOCK_UPDATE: u16 = bit(State::ClockUpdateMode);
const ANY_BUT_FATAL: u16 = INSTANTIATED
    | INIT
    | STEP_COMPLETE
    | STEP_FAILED
    | STEP_CANCELED
    | TERMINATED
    | ERROR
    | EVENT
    | CONTINUOUS
    | CONFIGURATION
    | RECONFIGURATION
    | CLOCK_ACTIVATION
    | CLOCK_UPDATE;

/// The functions whose legality depends on the state, with the states each is allowed in,
/// from the standard's tables in sections 3.2.3 and 4.2.4 (as the Reference-FMUs encode them).
/// The co-simulation functions are allowed in co-simulation states only, the model-exchange
/// ones in model-exchange states only, so each interface refuses the other's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Call {
    SetDebugLogging,
    FreeInstance,
    SetupExperiment,
    EnterInitializationMode,
    ExitInitializationMode,
    Terminate,
    Reset,
    GetValues,
    /// fmi2SetReal.
    SetValues,
    /// fmi2SetInteger, fmi2SetBoolean, fmi2SetString: not in continuous-time mode.
    SetDiscreteValues,
    FmuState,
    GetDirectionalDerivative,
    SetRealInputDerivatives,
    GetRealOutputDerivatives,
    DoStep,
    CancelStep,
    GetStatus,
    EnterEventMode,
    NewDiscreteStates,
    EnterContinuousTimeMode,
    CompletedIntegratorStep,
    SetTime,
    SetContinuousStates,
    GetEventIndicators,
    GetContinuousStates,
    GetDerivatives,
    GetNominalsOfContinuousStates,
    /// FMI 3.0 only: fmi3GetNumberOfContinuousStates, fmi3GetNumberOfEventIndicators.
    GetNumberOf,
    /// FMI 3.0 only: fmi3EvaluateDiscreteStates.
    EvaluateDiscreteStates,
    /// FMI 3.0 only: fmi3EnterStepMode (co-simulation with event mode; the instance checks that
    /// it was made with eventModeUsed).
    EnterStepMode,
    /// FMI 3.0 only: fmi3SetClock (Event Mode).
    SetClock,
    /// FMI 3.0 only: fmi3GetClock.
    GetClock,
    /// FMI 3.0 only: fmi3GetIntervalDecimal, fmi3GetShiftDecimal (Initialization and Event Mode).
    GetInterval,
    /// FMI 3.0 only: fmi3SetIntervalDecimal (Initialization Mode; a tunable clock's also in
    /// Event Mode: the instance checks).
    SetInterval,
    /// FMI 3.0 only: fmi3SetShiftDecimal (Initialization Mode).
    SetShift,
    /// FMI 3.0 only: fmi3EnterConfigurationMode (Instantiated; Step Mode; model exchange's
    /// Event Mode).
    EnterConfigurationMode,
    /// FMI 3.0 only: fmi3ExitConfigurationMode.
    ExitConfigurationMode,
    /// FMI 3.0 Scheduled Execution only: fmi3ActivateModelPartition (Clock Activation Mode).
    ActivateModelPartition,
}

impl Call {
    #[inline]
    pub const fn allowed_in(self) -> u16 {
        match self {
            Call::SetDebugLogging => ANY_BUT_FATAL,
            Call::FreeInstance => ANY_BUT_FATAL | FATAL,
            Call::SetupExperiment => INSTANTIATED,
            Call::EnterInitializationMode => INSTANTIATED,
            Call::ExitInitializationMode => INIT,
            // Not from StepCanceled: after fmi2CancelStep only fmi2Reset and fmi2FreeInstance
            // are meant to follow (the Reference FMUs' mask is StepComplete | StepFailed too).
            Call::Terminate => STEP_COMPLETE | STEP_FAILED | EVENT | CONTINUOUS,
            Call::Reset => ANY_BUT_FATAL,
            Call::GetValues | Call::GetDirectionalDerivative => {
                INIT | STEP_COMPLETE | STEP_FAILED | STEP_CANCELED | TERMINATED | ERROR | EVENT | CONTINUOUS
            }
            // Which variables may be set in which of these states: `Instance::settable`.
            Call::SetValues => INSTANTIATED | INIT | STEP_COMPLETE | EVENT | CONTINUOUS,
            Call::SetDiscreteValues => INSTANTIATED | INIT | STEP_COMPLETE | EVENT,
            Call::FmuState => ANY_BUT_FATAL,
            Call::SetRealInputDerivatives => INSTANTIATED | INIT | STEP_COMPLETE,
            Call::GetRealOutputDerivatives => STEP_COMPLETE | STEP_FAILED | STEP_CANCELED | TERMINATED | ERROR,
            Call::DoStep => STEP_COMPLETE,
            Call::CancelStep => 0,
            Call::GetStatus => STEP_COMPLETE | STEP_FAILED | TERMINATED,
            Call::EnterEventMode => EVENT | CONTINUOUS,
            Call::NewDiscreteStates | Call::EnterContinuousTimeMode => EVENT,
            Call::CompletedIntegratorStep | Call::SetContinuousStates => CONTINUOUS,
            Call::SetTime => EVENT | CONTINUOUS,
            Call::GetEventIndicators | Call::GetContinuousStates => INIT | EVENT | CONTINUOUS | TERMINATED | ERROR,
            Call::GetDerivatives => EVENT | CONTINUOUS | TERMINATED | ERROR,
            Call::GetNominalsOfContinuousStates => INSTANTIATED | EVENT | CONTINUOUS | TERMINATED | ERROR,
            Call::GetNumberOf
            | Call::EvaluateDiscreteStates
            | Call::EnterStepMode
            | Call::SetClock
            | Call::GetClock
            | Call::GetInterval
            | Call::SetInterval
            | Call::SetShift
            | Call::EnterConfigurationMode
            | Call::ExitConfigurationMode
            | Call::ActivateModelPartition => 0,
        }
    }

    /// The FMI 3.0 table (sections 3.2 and 4.2 of FMI 3.0, as the Reference-FMUs encode it) for
    /// the FMUs this runtime makes: co-simulation's event mode (Event Mode ⇄ Step Mode, for
    /// instances made with eventModeUsed: `Instance::check_state`), no clocks, no configuration
    /// mode. `StepComplete` is 3.0's Step Mode, `StepFailed` its Step Discarded. Where 3.0 differs
    /// from 2.0: fmi3EnterEventMode from Continuous-Time Mode (and Step Mode); the model-exchange
    /// evaluations also in Initialization Mode; the nominals not before initialization; the
    /// getters also in Instantiated (FMI 3.0.2: "get variable start values", fmi-standard #2174),
    /// for the variables that have a start value (`Instance::get_values`).
    #[inline]
    pub const fn allowed_in3(self) -> u16 {
        match self {
            // From Step Mode too: co-simulation with event mode (the instance checks that it
            // was made with eventModeUsed).
            Call::EnterEventMode => CONTINUOUS | STEP_COMPLETE,
            Call::GetDerivatives | Call::GetEventIndicators | Call::GetContinuousStates => {
                INIT | EVENT | CONTINUOUS | TERMINATED | ERROR
            }
            Call::GetNominalsOfContinuousStates => INIT | EVENT | CONTINUOUS | TERMINATED | ERROR,
            Call::GetNumberOf => ANY_BUT_FATAL,
            Call::EvaluateDiscreteStates => EVENT,
            Call::EnterStepMode => EVENT,
            // Clocks (FMI 3.0, 2.2.9 and its state tables): input clocks are activated in Event
            // Mode; their intervals and shifts are read in Initialization and Event Mode, set in
            // Initialization Mode (a tunable clock's interval also in Event Mode).
            Call::SetClock => EVENT,
            // In Scheduled Execution also between activations and in the clockUpdate callback.
            Call::GetClock | Call::GetInterval => INIT | EVENT | CLOCK_ACTIVATION | CLOCK_UPDATE,
            Call::SetInterval => INIT | EVENT | CLOCK_ACTIVATION,
            Call::SetShift => INIT,
            // Structural parameters (FMI 3.0, 3.2 and 4.2): Configuration Mode from Instantiated,
            // Reconfiguration Mode from Step Mode (co-simulation) or Event Mode (model exchange:
            // the instance checks the interface); the getters and setters work there (which
            // variables may be set: `Instance::settable`).
            Call::EnterConfigurationMode => INSTANTIATED | STEP_COMPLETE | EVENT,
            // An FMU state is not taken or restored in the middle of a configuration.
            // Nor inside the clockUpdate callback of a partition's activation.
            Call::FmuState => ANY_BUT_FATAL & !(CONFIGURATION | RECONFIGURATION | CLOCK_UPDATE),
            Call::ExitConfigurationMode => CONFIGURATION | RECONFIGURATION,
            Call::GetValues => {
                INSTANTIATED
                    | CONFIGURATION
                    | RECONFIGURATION
                    | CLOCK_ACTIVATION
                    | CLOCK_UPDATE
                    | Call::GetValues.allowed_in()
            }
            Call::SetValues | Call::SetDiscreteValues => {
                CONFIGURATION | RECONFIGURATION | CLOCK_ACTIVATION | self.allowed_in()
            }
            // No fmi3SetupExperiment, fmi3SetRealInputDerivatives, fmi3CancelStep or
            // fmi3GetStatus in FMI 3.0.
            Call::SetupExperiment | Call::SetRealInputDerivatives | Call::CancelStep | Call::GetStatus => 0,
            // Scheduled Execution (FMI 3.0, chapter 5): Clock Activation Mode after
            // initialization; Clock Update Mode while the importer's clockUpdate callback runs
            // (`Instance::check_state` refuses the model-exchange and co-simulation functions to
            // scheduled instances, and fmi3ActivateModelPartition to the others).
            Call::ActivateModelPartition => CLOCK_ACTIVATION,
            Call::Terminate => CLOCK_ACTIVATION | self.allowed_in(),
            Call::Reset => ANY_BUT_FATAL & !CLOCK_UPDATE,
            _ => self.allowed_in(),
        }
    }
}

impl Call {
    /// `Some(true)`: a model-exchange function; `Some(false)`: a co-simulation one; `None`:
    /// common to both. The states of the two machines overlap (instantiated, initialization,
    /// terminated, error), so the interface is checked besides the state.
    #[inline]
    pub const fn interface(self) -> Option<bool> {
        match self {
            Call::EnterEventMode
            | Call::NewDiscreteStates
            | Call::EnterContinuousTimeMode
            | Call::CompletedIntegratorStep
            | Call::SetTime
            | Call::SetContinuousStates
            | Call::GetEventIndicators
            | Call::GetContinuousStates
            | Call::GetDerivatives
            | Call::GetNominalsOfContinuousStates
            | Call::GetNumberOf
            | Call::EvaluateDiscreteStates => Some(true),
            Call::SetRealInputDerivatives
            | Call::GetRealOutputDerivatives
            | Call::DoStep
            | Call::CancelStep
            | Call::GetStatus
            | Call::EnterStepMode => Some(false),
            _ => None,
        }
    }
}

impl Call {
    /// The states `self` is allowed in, in `version`'s table.
    #[inline]
    pub const fn allowed(self, version: Version) -> u16 {
        match version {
            Version::Fmi2 => self.allowed_in(),
            Version::Fmi3 => self.allowed_in3(),
        }
    }
}

/// Whether `state` is one of the states in `mask`.
#[inline]
pub const fn contains(mask: u16, state: State) -> bool {
    mask & bit(state) != 0
}

/// The states of `mask`, in `terms`' names, for a message.
pub fn state_names(terms: &Terms, mask: u16) -> String {
    const ALL: [State; 14] = [
        State::Instantiated,
        State::InitializationMode,
        State::EventMode,
        State::ContinuousTimeMode,
        State::StepComplete,
        State::StepFailed,
        State::StepCanceled,
        State::ConfigurationMode,
        State::ReconfigurationMode,
        State::ClockActivationMode,
        State::ClockUpdateMode,
        State::Terminated,
        State::Error,
        State::Fatal,
    ];
    let names: Vec<String> = ALL
        .iter()
        .filter(|s| mask & bit(**s) != 0)
        .map(|s| terms.state_name(*s).to_string())
        .collect();
    if names.is_empty() {
        "no state of this FMU".into()
    } else {
        names.join(", ")
    }
}
