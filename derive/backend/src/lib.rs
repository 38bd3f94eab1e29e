//! The logic of rustfmu's declaration macros, `#[derive(Model)]` and `#[derive(FmuEnum)]`, as a
//! normal library on `proc_macro2` token streams: the proc-macro crate `rustfmu-derive` is a thin
//! shell that calls [`derive_model`] and [`derive_fmu_enum`], and everything else (parsing the
//! attributes, checking them against the standard's rules, generating the code) is unit-tested
//! here, without a compiler in between.
//!
//! Every mistake the standard's rules can catch from the declarations alone is one compile error
//! pointing at the field or the attribute: duplicate names or value references, illegal causality
//! × variability × initial combinations (the rules of `fmi-standard`), `depends` naming a
//! non-input, an undeclared unit, a start value where the standard forbids one.

mod enums;
mod long_arrays;
mod metadata;
mod model;
mod units;

use proc_macro2::TokenStream;

/// `#[derive(Model)]` on `input` (the item the derive sits on): the generated impls, or
/// `compile_error!`s where the declarations are wrong.
pub fn derive_model(input: TokenStream) -> TokenStream {
    match syn::parse2::<syn::DeriveInput>(input) {
        Ok(input) => {
            // First the arrays serde cannot serialize: its own errors about them say less.
            let mut out = long_arrays::checks(&input);
            out.extend(model::expand(input).unwrap_or_else(|e| e.to_compile_error()));
            out
        }
        Err(e) => e.to_compile_error(),
    }
}

/// `#[derive(FmuEnum)]` on `input`: the generated impls, or a `compile_error!`.
pub fn derive_fmu_enum(input: TokenStream) -> TokenStream {
    match syn::parse2::<syn::DeriveInput>(input) {
        Ok(input) => enums::expand(input).unwrap_or_else(|e| e.to_compile_error()),
        Err(e) => e.to_compile_error(),
    }
}

/// The path of the `rustfmu` crate as the user's crate names it (it may be renamed in
/// Cargo.toml), or `crate` inside rustfmu itself.
pub(crate) fn runtime_path() -> TokenStream {
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

#[cfg(test)]
mod alias_tests;
#[cfg(test)]
mod docs_tests;
#[cfg(test)]
mod network_tests;
#[cfg(test)]
mod tests;
