//! `#[derive(Model)]`: reads the struct and its attributes (the attribute grammar, `#[fmu]`,
//! `#[variable]` on each field), checks the declarations against the standard's rules, and
//! generates the typed description, the start values and the get/set dispatch.
//!
//! Each step is a room: `grammar` (one typed grammar for every attribute) below
//! `variable_attr` and `fmu_attr` (the attributes' keys) writing `model_attr` (what `#[fmu]` says), `decl` (the declarations as the rest
//! sees them), `field` (one field's declaration and its own rules), `network` (FMI-LS-BUS network
//! terminals: their terminal, MIME types and rules), `check` (the rules between declarations),
//! `codegen` (the generated code); this file runs them in that order.

mod check;
mod codegen;
pub(crate) mod decl;
mod field;
pub(crate) mod fmu_attr;
mod grammar;
pub(crate) mod model_attr;
mod network;
pub(crate) mod variable_attr;

// The lists the documentation is checked against (`docs_tests.rs`).
#[cfg(test)]
pub(crate) use field::TYPES;
#[cfg(test)]
pub(crate) use fmu_attr::FMU_KEYS;
#[cfg(test)]
pub(crate) use variable_attr::{CLOCK_KEYS, VARIABLE_KEYS};

use proc_macro2::TokenStream;
use quote::quote;
use syn::spanned::Spanned;
use syn::{Data, DeriveInput, Error, Fields, Result};

/// What `#[derive(Model)]` makes of a struct: the generated code (where the declarations parse
/// and the generator gets past them) and the mistake in the declarations, if any.
pub(crate) struct Expansion {
    pub generated: Option<TokenStream>,
    pub error: Option<Error>,
}

/// The derive's output: the generated code, followed by the mistake's `compile_error!` if there
/// is one; or the mistake alone where nothing can be generated.
pub fn expand(input: DeriveInput) -> Result<TokenStream> {
    match expand_parts(input) {
        Expansion {
            generated: Some(generated),
            error: None,
        } => Ok(generated),
        Expansion {
            generated: Some(generated),
            error: Some(problem),
        } => {
            let error = problem.to_compile_error();
            Ok(quote!(#generated #error))
        }
        Expansion {
            error: Some(problem), ..
        } => Err(problem),
        Expansion {
            generated: None,
            error: None,
        } => unreachable!("an expansion has code or an error"),
    }
}

pub(crate) fn expand_parts(input: DeriveInput) -> Expansion {
    expand_checked(input).unwrap_or_else(|e| Expansion {
        generated: None,
        error: Some(e),
    })
}

fn expand_checked(input: DeriveInput) -> Result<Expansion> {
    let Data::Struct(data) = &input.data else {
        return Err(Error::new(input.ident.span(), "#[derive(Model)] is for structs"));
    };
    let Fields::Named(fields) = &data.fields else {
        return Err(Error::new(
            input.ident.span(),
            "#[derive(Model)] needs a struct with named fields",
        ));
    };
    if !input.generics.params.is_empty() {
        return Err(Error::new(
            input.generics.span(),
            "a model struct cannot be generic: an FMU is one concrete model",
        ));
    }
    let model = fmu_attr::parse_model_attr(&input.attrs)?;
    let mut vars = Vec::new();
    let mut others = Vec::new();
    let mut internal = Vec::new();
    for f in &fields.named {
        let attrs: Vec<_> = f.attrs.iter().filter(|a| a.path().is_ident("variable")).collect();
        match attrs.as_slice() {
            [] => {
                let ty = &f.ty;
                internal.push(format!(
                    "{}: {}",
                    f.ident.as_ref().expect("named"),
                    quote!(#ty).to_string().replace(' ', "")
                ));
                others.push(f.ident.clone().expect("named"))
            }
            [a] => vars.push(field::parse_var(f, a)?),
            [_, second, ..] => return Err(Error::new(second.span(), "one #[variable(...)] per field")),
        }
    }
    if vars.is_empty() {
        return Err(Error::new(
            input.ident.span(),
            "a model declares at least one #[variable(...)]",
        ));
    }
    // A declaration the standard forbids is one compile error at the field. The code is still
    // generated when it can be (the declarations parsed), so that the model's own impls and
    // `export_fmu!` do not add "the trait bound `M: Variables` is not satisfied" errors after it
    // (issue 23); a mistake the generator cannot get past (it panics on it) gives the error alone.
    field::output_clocks_are_no_dependencies(&mut vars);
    network::apply_mime_types(&model, &mut vars);
    let problem = check::check_declarations(&vars, &model).err();
    let generate = || codegen::generate(&input, fields, &model, &vars, &others, &internal);
    let generated = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(generate)) {
        Ok(generated) => generated,
        Err(panic) if problem.is_none() => std::panic::resume_unwind(panic),
        Err(_) => {
            return Ok(Expansion {
                generated: None,
                error: problem,
            });
        }
    };
    Ok(match (generated, problem) {
        (Ok(generated), problem) => Expansion {
            generated: Some(generated),
            error: problem,
        },
        (Err(e), None) => return Err(e),
        (Err(_), Some(problem)) => Expansion {
            generated: None,
            error: Some(problem),
        },
    })
}
