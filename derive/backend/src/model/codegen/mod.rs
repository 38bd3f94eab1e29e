//! The code `#[derive(Model)]` generates from checked declarations: the struct of the
//! equations' variables, and `impl Variables` (the state vector, the description, the dispatch by
//! value reference), followed by the checks the compiler makes of the description.

mod access;
mod asserts;
mod description;
mod equations;
mod states;
mod values;

use super::decl::Var;
use super::model_attr::ModelAttr;
use equations::Equations;
use proc_macro2::TokenStream;
use quote::quote;
use syn::{DeriveInput, Error, FieldsNamed, Ident, Result};

/// The generated code of `input` (whose named fields are `fields`): its variables `vars`, the
/// other fields `others` (`internal`: each as "name: type"), its `#[fmu]` attribute `model`.
/// It may panic on declarations the checks reject (the caller catches that).
pub(crate) fn generate(
    input: &DeriveInput,
    fields: &FieldsNamed,
    model: &ModelAttr,
    vars: &[Var],
    others: &[Ident],
    internal: &[String],
) -> Result<TokenStream> {
    let rt = crate::runtime_path();
    let meta = crate::metadata::read().map_err(|e| Error::new(input.ident.span(), e))?;
    let ident = &input.ident;
    let Equations {
        continuous_struct,
        continuous_items,
        state_items,
    } = equations::equations(&rt, input, vars);
    let (offers_me, offers_cs) = match model.interfaces {
        Some((me, cs, _)) => (me, cs),
        None => (true, true),
    };
    let model_fmi3_only = model.fmi3_only.is_some();
    let offers_se = model.scheduled_execution.is_some();
    let description = description::model_description(&rt, input, model, vars, internal, &meta);
    let access_items = access::access_items(&rt, fields, vars, others);
    let checks = asserts::compile_time_checks(&rt, ident, vars, model, &meta);
    Ok(quote! {
        #continuous_struct

        #[allow(unused_mut, unused_assignments, clippy::identity_op)]
        impl #rt::Variables for #ident {
            #continuous_items
            const MODEL_EXCHANGE: bool = #offers_me;
            const FMI3_ONLY: bool = #model_fmi3_only;
            const CO_SIMULATION: bool = #offers_cs;
            const SCHEDULED_EXECUTION: bool = #offers_se;

            #state_items

            const DESCRIPTION: #rt::description::ModelDescription = #description;

            #access_items
        }

        #checks
    })
}
