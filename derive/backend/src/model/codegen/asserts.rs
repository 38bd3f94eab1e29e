//! The checks the compiler makes of the generated description (value checks that need the
//! declarations' values, a type taken for an enumeration, FMI 2.0 array elements, sized arrays'
//! capacities), each reported at the declaration it concerns; and the manifest, so that a change
//! of Cargo.toml rebuilds the model.

use crate::metadata::Metadata;
use crate::model::decl::{Kind, Var};
use crate::model::model_attr::ModelAttr;
use fmi_standard::Causality;
use proc_macro2::TokenStream;
use quote::quote;
use quote::quote_spanned;
use syn::Ident;
use syn::spanned::Spanned;

/// What each `ValueError` of the runtime's `check_values` says of a declaration (after the
/// variable's name), as the compile-time check reports it.
#[rustfmt::skip] // a table: one error a line
const VALUE_ERRORS: [(&str, &str); 12] = [
    ("MinNotFinite", "min is not a finite number"),
    ("MaxNotFinite", "max is not a finite number"),
    ("MinAboveMax", "min is above max"),
    ("IntegerMin", "an Integer's min must be an integer within i32"),
    ("IntegerMax", "an Integer's max must be an integer within i32"),
    ("StartNotFinite", "the start value is not a finite number"),
    ("StartBelowMin", "the start value is below min"),
    ("StartAboveMax", "the start value is above max"),
    ("Nominal", "nominal must be finite and > 0"),
    ("StartNotAnItem", "the start value is no item of the enumeration"),
    ("IntegerTypeMin", "an integer's min must be an integer of its type, within ±2^53"),
    ("IntegerTypeMax", "an integer's max must be an integer of its type, within ±2^53"),
];

/// The compile-time checks of model `ident` with `vars`, and the manifest's include.
pub(crate) fn compile_time_checks(
    rt: &TokenStream,
    ident: &Ident,
    vars: &[Var],
    model: &ModelAttr,
    meta: &Metadata,
) -> TokenStream {
    // Checks that need the values of the declarations (start within bounds, integral bounds
    // for Integers), evaluated at compile time and reported at the field.
    let value_checks = vars.iter().enumerate().map(|(i, v)| {
        let span = v.span;
        let prefix = format!("variable '{}' (field `{}`): ", v.name, v.field);
        let arms = VALUE_ERRORS.iter().map(|(error, message)| {
            let error = Ident::new(error, span);
            quote_spanned! {span=>
                ::core::result::Result::Err(#rt::description::ValueError::#error) => panic!(concat!(#prefix, #message)),
            }
        });
        quote_spanned! {span=>
            const _: () = match #rt::description::check_values(&<#ident as #rt::Variables>::DESCRIPTION.variables[#i]) {
                ::core::result::Result::Ok(()) => (),
                #(#arms)*
            };
        }
    });
    // A type the derive does not know by name is taken for a #[derive(FmuEnum)] enum; make sure it
    // is one (a type alias such as `type Real = f64` would otherwise get an Integer start).
    let enum_checks = vars.iter().filter(|v| v.kind == Kind::Enum).map(|v| {
        let (ty, span) = (&v.elem, v.ty.span());
        let message = format!(
            "variable '{}': its type is read as a #[derive(FmuEnum)] enumeration; write f64, i32, bool or String by name (no alias)",
            v.name
        );
        quote_spanned! {span=>
            const _: () = if !matches!(<#ty as #rt::FmiType>::TYPE, #rt::description::VarType::Enumeration) {
                panic!(#message)
            };
        }
    });
    // FMI 2.0 has no arrays: an array is its elements there, scalars with the value
    // references vr, vr + 1, ..; none may be another variable's (checked where the sizes are
    // known: at compile time, by the compiler).
    let element_checks = vars.iter().enumerate().filter(|(_, v)| !v.dims.is_empty() && !v.fmi3_only && model.fmi3_only.is_none()).map(|(i, v)| {
        let message = format!(
            "'{}' (vr {}) is an array, which FMI 2.0 lists as its elements `{}[i,j]` with the value references {} to {} + (elements - 1): \
             one of them is another variable's. Leave that range free (a vr above it), or declare the array `fmi3_only`",
            v.name, v.vr, v.name, v.vr, v.vr
        );
        quote_spanned!(v.span =>
            const _: () = ::core::assert!(
                !<#ident as #rt::Variables>::DESCRIPTION.fmi2_elements_overlap(#i),
                #message
            );
        )
    });

    // A structural parameter's max is at most the length of every array dimension it sets
    // (the Rust array's: its capacity). Lengths may be constants: the compiler checks.
    let capacity_checks = vars.iter().flat_map(|v| {
        v.sized_by.iter().zip(&v.dims).filter_map(|((p, span), cap)| {
            let i = vars.iter().position(|x| x.is_named(p))?;
            // (A sizing variable that is no structural parameter with a max has its own
            // compile error.)
            if vars[i].causality != Causality::StructuralParameter || vars[i].max.is_none() {
                return None;
            }
            let message = format!(
                "'{p}' sets a length of '{}', whose Rust array holds fewer elements along that dimension than \
                 '{p}''s max: make max at most the array's length",
                v.name
            );
            Some(quote_spanned!(*span =>
                #[allow(clippy::unnecessary_cast)]
                const _: () = ::core::assert!(
                    match <#ident as #rt::Variables>::DESCRIPTION.variables[#i].max {
                        ::core::option::Option::Some(b) => b.value <= (#cap) as f64,
                        ::core::option::Option::None => false,
                    },
                    #message
                );
            ))
        })
    });
    let capacity_checks: Vec<TokenStream> = capacity_checks.collect();
    let manifest = meta.manifest.as_ref().map(|p| {
        let p = p.display().to_string();
        quote!(
            const _: &[u8] = include_bytes!(#p);
        )
    });

    quote! {
        #(#value_checks)*
        #(#enum_checks)*
        #(#element_checks)*
        #(#capacity_checks)*
        #manifest
    }
}
