//! The declaration macros of rustfmu: `#[derive(Model)]` and `#[derive(FmuEnum)]`.
//!
//! Use them through the `rustfmu` crate (`use rustfmu::prelude::*`); their attributes are
//! documented there and in `docs/declarations.md`. Every mistake the standard's rules can catch
//! from the declarations alone is a compile error pointing at the field: duplicate names or
//! value references, illegal causality × variability × initial combinations, `depends` naming a
//! non-input, an undeclared unit, a start value where the standard forbids one.

mod enums;
mod metadata;
mod model;
mod units;

use proc_macro::TokenStream;

/// Declares a model's variables on its fields; see the `rustfmu` crate documentation.
#[proc_macro_derive(Model, attributes(fmu, variable))]
pub fn derive_model(input: TokenStream) -> TokenStream {
    let input = syn::parse_macro_input!(input as syn::DeriveInput);
    model::expand(input).unwrap_or_else(|e| e.to_compile_error()).into()
}

/// Makes a fieldless enum an FMI Enumeration type; see the `rustfmu` crate documentation.
#[proc_macro_derive(FmuEnum, attributes(fmu))]
pub fn derive_fmu_enum(input: TokenStream) -> TokenStream {
    let input = syn::parse_macro_input!(input as syn::DeriveInput);
    enums::expand(input).unwrap_or_else(|e| e.to_compile_error()).into()
}

/// The path of the `rustfmu` crate as the user's crate names it (it may be renamed in
/// Cargo.toml), or `crate` inside rustfmu itself.
pub(crate) fn runtime_path() -> proc_macro2::TokenStream {
    use proc_macro_crate::{FoundCrate, crate_name};
    match crate_name("rustfmu") {
        Ok(FoundCrate::Itself) => quote::quote!(::rustfmu),
        Ok(FoundCrate::Name(name)) => {
            let ident = syn::Ident::new(&name, proc_macro2::Span::call_site());
            quote::quote!(::#ident)
        }
        Err(_) => quote::quote!(::rustfmu),
    }
}

/// The doc comment's lines, trimmed and joined with spaces.
pub(crate) fn doc_text(attrs: &[syn::Attribute]) -> String {
    let mut lines = Vec::new();
    for a in attrs {
        if a.path().is_ident("doc")
            && let syn::Meta::NameValue(nv) = &a.meta
            && let syn::Expr::Lit(syn::ExprLit {
                lit: syn::Lit::Str(s), ..
            }) = &nv.value
        {
            lines.push(s.value().trim().to_string());
        }
    }
    lines
        .into_iter()
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}
