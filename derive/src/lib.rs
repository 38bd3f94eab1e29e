//! The declaration macros of rustfmu: `#[derive(Model)]` and `#[derive(FmuEnum)]`.
//!
//! Use them through the `rustfmu` crate (`use rustfmu::prelude::*`); their attributes are
//! documented there and in `docs/declarations.md`. Every mistake the standard's rules can catch
//! from the declarations alone is a compile error pointing at the field: duplicate names or
//! value references, illegal causality × variability × initial combinations, `depends` naming a
//! non-input, an undeclared unit, a start value where the standard forbids one.
//!
//! This crate is only the entry points: the logic (parsing, checks, code generation) is the
//! library `rustfmu-derive-backend` (`derive/backend/`), on `proc_macro2` token streams and
//! unit-tested there.

use proc_macro::TokenStream;

/// Declares a model's variables on its fields; see the `rustfmu` crate documentation.
#[proc_macro_derive(Model, attributes(fmu, variable))]
pub fn derive_model(input: TokenStream) -> TokenStream {
    rustfmu_derive_backend::derive_model(input.into()).into()
}

/// Makes a fieldless enum an FMI Enumeration type; see the `rustfmu` crate documentation.
#[proc_macro_derive(FmuEnum, attributes(fmu))]
pub fn derive_fmu_enum(input: TokenStream) -> TokenStream {
    rustfmu_derive_backend::derive_fmu_enum(input.into()).into()
}
