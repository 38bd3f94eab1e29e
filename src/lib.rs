//! # rustfmu: FMI 2.0 and FMI 3.0 FMUs from plain Rust models
//!
//! A model is a Rust struct. Its variables are declared on its fields with
//! `#[derive(Model)]`; it implements [`Model`] (initialization, checks) and [`CoSimulation`]
//! (a communication step); one line, [`export_fmu!`], makes the crate's `cdylib` an FMU (FMI 2.0
//! and FMI 3.0 from one binary).
//! `cargo fmu build` (from the `fmu-build` package) packages it.
//!
//! ```ignore
//! use rustfmu::prelude::*;
//!
//! /// A first-order lag: T dy/dt = u - y.
//! #[derive(Model, Clone, Debug, serde::Serialize, serde::Deserialize)]
//! pub struct Lag {
//!     /// Input u
//!     #[variable(vr = 0, input)]
//!     pub u: f64,
//!     /// Output y; its start value is the initial state
//!     #[variable(vr = 1, output, initial = exact, depends = [])]
//!     pub y: f64,
//!     /// Time constant T
//!     #[variable(vr = 2, parameter, tunable, start = 0.1, unit = "s", min > 0.0)]
//!     pub T: f64,
//! }
//!
//! impl Model for Lag {}
//! impl CoSimulation for Lag {
//!     fn do_step(&mut self, _t: f64, h: f64, _ctx: &mut Context) -> Result<(), StepFailure> {
//!         self.y = self.u + (self.y - self.u) * (-h / self.T).exp();
//!         Ok(())
//!     }
//! }
//!
//! rustfmu::export_fmu!(Lag);
//! ```
//!
//! What the runtime does for every model: the FMI 2.0 state machine; all-or-nothing argument
//! checks (unknown value references, NULL arrays, NaN and infinite values, values outside the
//! declared bounds, variables that cannot be set in the current state); no non-finite value
//! under fmi2OK (every Real variable and [`Model::check_internal_state`] after initialization,
//! every step and every parameter change); logging through the importer's logger (always with
//! `"%s"`); versioned, checked FMU state get/set/serialize (only live states this FMU made are
//! accepted, and deserialized content passes the setters' checks); refusal of a call into an
//! instance while another call is inside it; the GUID; `catch_unwind` at every entry point. The declaration attributes are documented in
//! `docs/declarations.md` and on [`macro@Model`].

extern crate self as rustfmu;

mod big_array;
mod clock;
pub mod description;
mod model;
pub mod solver;
mod step;
pub mod testing;
mod value;

pub use big_array::{BigArray, BigMatrix};
pub use clock::Clock;
pub use model::{CoSimulation, Context, Event, EventClock, Model, Real, StateVector, StepFailure, StepView, Variables};
pub use num_dual;
pub use rustfmu_derive::{FmuEnum, Model};
/// FMI-LS-BUS 1.0.0's CAN bus operations, for the models of network FMUs
/// (`#[fmu(can_network(..))]`): the crate `rustfmu-ls-bus`.
pub use rustfmu_ls_bus as ls_bus;
pub use step::events::{MAX_EVENTS_PER_STEP, MAX_ROUNDS, Round, update_round};
pub use step::standalone::Standalone;
pub use value::{FmiType, FmuEnum, Value};

#[doc(hidden)]
pub mod core;
#[doc(hidden)]
pub mod fmi2;
#[doc(hidden)]
pub mod fmi3;

/// Exports `Model` as an FMU of both FMI versions in one binary: the FMI 2.0 functions
/// ([`export_fmi2!`]) and the FMI 3.0 ones ([`export_fmi3!`]), each with the description of its
/// version embedded. `cargo fmu build` builds the crate once per target and packages that one
/// binary twice, into the FMI 2.0 and the FMI 3.0 `.fmu`: one model, one line, both versions.
/// An importer calls the functions of the version its `modelDescription.xml` names (the two sets
/// share no symbol and no state: each instance belongs to the version that instantiated it).
#[macro_export]
macro_rules! export_fmu {
    ($model:ty) => {
        $crate::export_fmi2!($model);
        $crate::export_fmi3!($model);
    };
}

/// Everything a model file needs.
pub mod prelude {
    pub use crate::description::Variable;
    pub use crate::{Clock, CoSimulation, Context, Event, FmuEnum, Model, Real, StepFailure, Value};
}

/// What the macros expand to; not part of the API.
#[doc(hidden)]
pub mod __private {
    pub use crate::core::shared;
    pub use crate::fmi2::{TERMS as TERMS2, abi, api};
    pub use crate::fmi3::{TERMS as TERMS3, abi as abi3, api as api3};
    pub use serde;
}
