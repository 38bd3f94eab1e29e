//! The FMI-version-neutral core of the runtime, generic over the model: not part of the
//! documented API.
//!
//! Layers, with arrows pointing one way: a model ([`crate::Model`], declared with
//! `#[derive(Model)]`) knows nothing of FMI; [`instance`] runs the standard's state machine
//! around it (the tables of both versions in [`machine`]), checks every argument, and keeps the
//! FMU state ([`state`], [`snapshots`]); [`guard`] is what every C entry point runs through
//! (NULL checks, re-entrancy, `catch_unwind`), and [`shared`] the entry points whose bodies are
//! the same in both versions. The C layers, [`crate::fmi2`] and [`crate::fmi3`], convert the
//! importer's pointers and say their own words: each gives the core its [`Terms`] (its function
//! names, its state names, what it calls the instantiation token), and the core words every
//! message in them. Nothing here rewrites a message after the fact.

/// An enum of unit variants with its `COUNT` and its `ALL` (in declaration order, so that
/// `ALL[x as usize] == x`), from one list.
macro_rules! listed_enum {
    ($(#[$meta:meta])* $vis:vis enum $name:ident { $($(#[$vmeta:meta])* $variant:ident,)* }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        #[repr(u8)]
        $vis enum $name { $($(#[$vmeta])* $variant,)* }

        impl $name {
            pub const ALL: &'static [$name] = &[$($name::$variant,)*];
            pub const COUNT: usize = $name::ALL.len();
        }
    };
}

mod exports;
pub mod guard;
mod initial_derivatives;
pub mod instance;
pub mod logging;
pub mod machine;
pub mod resources;
pub mod shared;
pub mod snapshots;
pub mod state;
pub mod structural;
mod trampolines;

/// What every function returns: `fmi2Status` and `fmi3Status` have the same C type and the
/// same values for the five statuses (`fmi2Pending` has no use here: every step is
/// synchronous), so the core answers in FMI 3.0's and the C layers pass them on unchanged; each
/// layer asserts the equality at compile time.
pub use crate::fmi3::abi::{
    fmi3Discard as DISCARD, fmi3Error as ERROR, fmi3Fatal as FATAL, fmi3OK as OK, fmi3Status as Status,
    fmi3Warning as WARNING,
};

/// The FMI version an instance was instantiated through (the discriminant: the column of
/// `c_names`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Version {
    Fmi2 = 0,
    Fmi3 = 1,
}

listed_enum! {
    /// The functions the core names in its messages besides the one being called (which the C
    /// layer passes). Each version's [`Terms`] gives their names.
    pub enum Function {
        SetDebugLogging,
        /// 2.0's fmi2SetupExperiment; in 3.0 the experiment comes with
        /// fmi3EnterInitializationMode.
        SetupExperiment,
        EnterInitializationMode,
        ExitInitializationMode,
        Terminate,
        Reset,
        FreeInstance,
        GetString,
        SetString,
        DoStep,
        EnterEventMode,
        NewDiscreteStates,
        EnterContinuousTimeMode,
        CompletedIntegratorStep,
        SetTime,
        SetContinuousStates,
        GetContinuousStates,
        GetDerivatives,
        GetNominalsOfContinuousStates,
        GetEventIndicators,
        GetDirectionalDerivative,
        GetFmuState,
        SetFmuState,
        FreeFmuState,
        SerializedFmuStateSize,
        SerializeFmuState,
        DeserializeFmuState,
    }
}

/// How one FMI version says what the core speaks of: given by each C layer
/// (`crate::fmi2::TERMS`, `crate::fmi3::TERMS`), held by each instance. Tables, so that naming a
/// function costs one load (the core names the function it serves on every call, for the
/// message it may have to write).
#[derive(Debug)]
pub struct Terms {
    pub version: Version,
    /// Each [`Function`]'s name in this version, by `Function as usize` (`fmi2GetDerivatives`,
    /// `fmi3GetContinuousStateDerivatives`).
    pub functions: [&'static str; Function::COUNT],
    /// Each [`machine::State`]'s name in this version's state machine, by `State as usize`
    /// (2.0's `StepComplete` is 3.0's `StepMode`).
    pub states: [&'static str; machine::State::COUNT],
    /// What the modelDescription's identity of a build is called: `GUID` in 2.0,
    /// `instantiationToken` in 3.0.
    pub token: &'static str,
    /// The name of the FMU state handle's argument: `FMUstate` in 2.0, `FMUState` in 3.0.
    pub fmu_state: &'static str,
}

/// Each [`Function`]'s C name in FMI 2.0 and in FMI 3.0, side by side.
#[rustfmt::skip] // a table: one function a line
const fn c_names(f: Function) -> [&'static str; 2] {
    match f {
        Function::SetDebugLogging => ["fmi2SetDebugLogging", "fmi3SetDebugLogging"],
        // FMI 3.0 has no fmi3SetupExperiment: the experiment comes with fmi3EnterInitializationMode.
        Function::SetupExperiment => ["fmi2SetupExperiment", "fmi3EnterInitializationMode"],
        Function::EnterInitializationMode => ["fmi2EnterInitializationMode", "fmi3EnterInitializationMode"],
        Function::ExitInitializationMode => ["fmi2ExitInitializationMode", "fmi3ExitInitializationMode"],
        Function::Terminate => ["fmi2Terminate", "fmi3Terminate"],
        Function::Reset => ["fmi2Reset", "fmi3Reset"],
        Function::FreeInstance => ["fmi2FreeInstance", "fmi3FreeInstance"],
        Function::GetString => ["fmi2GetString", "fmi3GetString"],
        Function::SetString => ["fmi2SetString", "fmi3SetString"],
        Function::DoStep => ["fmi2DoStep", "fmi3DoStep"],
        Function::EnterEventMode => ["fmi2EnterEventMode", "fmi3EnterEventMode"],
        Function::NewDiscreteStates => ["fmi2NewDiscreteStates", "fmi3UpdateDiscreteStates"],
        Function::EnterContinuousTimeMode => ["fmi2EnterContinuousTimeMode", "fmi3EnterContinuousTimeMode"],
        Function::CompletedIntegratorStep => ["fmi2CompletedIntegratorStep", "fmi3CompletedIntegratorStep"],
        Function::SetTime => ["fmi2SetTime", "fmi3SetTime"],
        Function::SetContinuousStates => ["fmi2SetContinuousStates", "fmi3SetContinuousStates"],
        Function::GetContinuousStates => ["fmi2GetContinuousStates", "fmi3GetContinuousStates"],
        Function::GetDerivatives => ["fmi2GetDerivatives", "fmi3GetContinuousStateDerivatives"],
        Function::GetNominalsOfContinuousStates => ["fmi2GetNominalsOfContinuousStates", "fmi3GetNominalsOfContinuousStates"],
        Function::GetEventIndicators => ["fmi2GetEventIndicators", "fmi3GetEventIndicators"],
        Function::GetDirectionalDerivative => ["fmi2GetDirectionalDerivative", "fmi3GetDirectionalDerivative"],
        Function::GetFmuState => ["fmi2GetFMUstate", "fmi3GetFMUState"],
        Function::SetFmuState => ["fmi2SetFMUstate", "fmi3SetFMUState"],
        Function::FreeFmuState => ["fmi2FreeFMUstate", "fmi3FreeFMUState"],
        Function::SerializedFmuStateSize => ["fmi2SerializedFMUstateSize", "fmi3SerializedFMUStateSize"],
        Function::SerializeFmuState => ["fmi2SerializeFMUstate", "fmi3SerializeFMUState"],
        Function::DeserializeFmuState => ["fmi2DeSerializeFMUstate", "fmi3DeserializeFMUState"],
    }
}

impl Terms {
    /// The terms of `version`: the functions' names of `c_names`, the state names of the core
    /// (FMI 2.0's) but for `renamed` states, what the version calls the token and the FMU state.
    pub const fn of(
        version: Version,
        token: &'static str,
        fmu_state: &'static str,
        renamed: &[(machine::State, &'static str)],
    ) -> Terms {
        let mut functions = [""; Function::COUNT];
        let mut i = 0;
        while i < Function::COUNT {
            functions[i] = c_names(Function::ALL[i])[version as usize];
            i += 1;
        }
        let mut states = [""; machine::State::COUNT];
        let mut i = 0;
        while i < machine::State::COUNT {
            states[i] = machine::State::ALL[i].name();
            i += 1;
        }
        let mut i = 0;
        while i < renamed.len() {
            states[renamed[i].0 as usize] = renamed[i].1;
            i += 1;
        }
        Terms {
            version,
            functions,
            states,
            token,
            fmu_state,
        }
    }

    #[inline]
    pub fn name(&self, f: Function) -> &'static str {
        self.functions[f as usize]
    }

    #[inline]
    pub fn state_name(&self, s: machine::State) -> &'static str {
        self.states[s as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tables_list_every_function_and_state_at_its_own_index() {
        for (i, f) in Function::ALL.iter().enumerate() {
            assert_eq!(*f as usize, i, "{f:?}");
        }
        for (i, s) in machine::State::ALL.iter().enumerate() {
            assert_eq!(*s as usize, i, "{s:?}");
        }
        for terms in [&crate::fmi2::TERMS, &crate::fmi3::TERMS] {
            assert!(terms.functions.iter().chain(&terms.states).all(|n| !n.is_empty()));
        }
    }
}
