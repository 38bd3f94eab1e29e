//! The FMI 2.0 co-simulation runtime, generic over the model.
//!
//! Layers, with arrows pointing one way: a model ([`model::CoSimModel`], declared with
//! [`fmi2_variables!`](crate::fmi2_variables)) knows nothing of FMI; [`instance`] runs the
//! standard's state machine around it; [`api`] is the C boundary; [`export`] puts the symbols in
//! an FMU crate; [`xml`] writes the model description from the same declarations.

pub mod abi;
pub mod api;
pub mod export;
pub mod instance;
pub mod logging;
pub mod model;
pub mod resources;
pub mod state;
pub mod units;
pub mod variables;
pub mod xml;

/// What `fmu-build` needs to know about one FMU crate.
#[derive(Debug, Clone, Copy)]
pub struct FmuEntry {
    pub info: model::ModelInfo,
    /// The cargo package of the thin cdylib crate.
    pub package: &'static str,
    /// Its library name (the `.so` is `lib<lib_name>.so`).
    pub lib_name: &'static str,
    pub variables: &'static [variables::VarDecl],
    pub model_description: fn() -> Result<String, String>,
}

impl FmuEntry {
    pub const fn of<M: model::CoSimModel>(package: &'static str, lib_name: &'static str) -> FmuEntry {
        FmuEntry {
            info: M::INFO,
            package,
            lib_name,
            variables: <M::Vars as variables::VariableSet>::DECLS,
            model_description: xml::model_description::<M>,
        }
    }
}
