//! The dispatch by value reference the runtime calls: the start values, value reference ->
//! index, and get/set of numbers, strings, array elements, binaries and clocks.

use super::values::array_value;
use crate::model::decl::{Kind, Var};
use fmi_standard::Causality;
use proc_macro2::TokenStream;
use quote::quote;
use syn::{FieldsNamed, Ident};

/// The impl's items from `fn start` on: the model's start, and get and set by value reference.
pub(crate) fn access_items(rt: &TokenStream, fields: &FieldsNamed, vars: &[Var], others: &[Ident]) -> TokenStream {
    let values = value_items(rt, fields, vars, others);
    let others = string_array_binary_items(rt, vars);
    let clocks = clock_items(rt, vars);
    quote!(#values #others #clocks)
}

/// `match vr { arms.., _ => otherwise }`.
fn by_vr(arms: impl IntoIterator<Item = TokenStream>, otherwise: TokenStream) -> TokenStream {
    let arms = arms.into_iter();
    quote! {
        match vr {
            #(#arms,)*
            _ => #otherwise,
        }
    }
}

/// A getter's answer for a value reference it has not.
fn none() -> TokenStream {
    quote!(::core::option::Option::None)
}

/// An array field as a slice of its elements (row-major), mutable or not.
fn flat(v: &Var, mutable: bool) -> TokenStream {
    let f = &v.field;
    match (v.dims.len(), mutable) {
        (2, false) => quote!(self.#f.as_flattened()),
        (2, true) => quote!(self.#f.as_flattened_mut()),
        (_, false) => quote!(self.#f.as_slice()),
        (_, true) => quote!(self.#f.as_mut_slice()),
    }
}

/// `start`, `variable_index`, and get, set and the finiteness check of the scalar numbers,
/// Booleans and enumerations.
fn value_items(rt: &TokenStream, fields: &FieldsNamed, vars: &[Var], others: &[Ident]) -> TokenStream {
    // Value reference -> index in DESCRIPTION.variables: a match, not a search per call.
    let index = by_vr(
        vars.iter().enumerate().map(|(i, v)| {
            let vr = v.vr;
            quote!(#vr => ::core::option::Option::Some(#i))
        }),
        none(),
    );
    let start_fields = vars.iter().map(|v| {
        let f = &v.field;
        if !v.dims.is_empty() {
            let value = array_value(rt, v);
            return quote!(#f: #value);
        }
        let value = match (v.kind, &v.start) {
            (Kind::Str, Some(e)) => quote!(::std::string::String::from(#e)),
            (Kind::Str, None) => quote!(::std::string::String::new()),
            (Kind::Binary, Some(e)) => quote!(::std::vec::Vec::from(&(#e)[..])),
            (Kind::Binary, None) => quote!(::std::vec::Vec::new()),
            (Kind::Clock, _) => quote!(#rt::Clock::default()),
            (_, Some(e)) => quote!(#e),
            (Kind::Real | Kind::Float32, None) => quote!(0.0),
            (Kind::Integer | Kind::Int3 | Kind::UInt64, None) => quote!(0),
            (Kind::Boolean, None) => quote!(false),
            // A calculated Enumeration: its first item until the model computes it.
            (Kind::Enum, None) => {
                let ty = &v.ty;
                quote!(<#ty as #rt::FmuEnum>::FIRST)
            }
        };
        quote!(#f: #value)
    });
    let other_fields = others.iter().map(|f| {
        let ty = fields.named.iter().find(|x| x.ident.as_ref() == Some(f)).map(|x| &x.ty);
        let value = crate::long_arrays::default_value(ty);
        quote!(#f: #value)
    });
    let numeric: Vec<&Var> = vars
        .iter()
        .filter(|v| !matches!(v.kind, Kind::Str | Kind::Binary | Kind::Clock) && v.dims.is_empty())
        .collect();
    let get = by_vr(
        numeric.iter().map(|v| {
            let (f, vr) = (&v.field, v.vr);
            quote!(#vr => #rt::FmiType::to_value(&self.#f))
        }),
        none(),
    );
    let set = by_vr(
        numeric.iter().map(|v| {
            let (f, vr, ty) = (&v.field, v.vr, &v.ty);
            quote!(#vr => match <#ty as #rt::FmiType>::from_value(value) {
                ::core::option::Option::Some(v) => { self.#f = v; true }
                ::core::option::Option::None => false,
            })
        }),
        quote!(false),
    );
    // The Real variables the model computes (inputs and parameters are checked when set): the
    // runtime asks after every step.
    let finite_checks = vars
        .iter()
        .enumerate()
        .filter(|(_, v)| {
            v.kind.is_float()
                && matches!(
                    v.causality,
                    Causality::Output | Causality::Local | Causality::CalculatedParameter | Causality::Independent
                )
        })
        .map(|(i, v)| {
            let f = &v.field;
            if v.dims.is_empty() {
                quote!(if !self.#f.is_finite() {
                    return ::core::option::Option::Some(#i);
                })
            } else {
                let flat = flat(v, false);
                quote!(if !#flat.iter().all(|x| x.is_finite()) {
                    return ::core::option::Option::Some(#i);
                })
            }
        });
    quote! {
        fn start() -> Self {
            Self { #(#start_fields,)* #(#other_fields,)* }
        }

        #[inline]
        fn variable_index(vr: u32) -> ::core::option::Option<usize> {
            #index
        }

        #[inline]
        fn get(&self, vr: u32) -> ::core::option::Option<#rt::Value> {
            #get
        }

        #[inline]
        fn set(&mut self, vr: u32, value: #rt::Value) -> bool {
            let _ = &value;
            #set
        }

        #[inline]
        fn non_finite_computed(&self) -> ::core::option::Option<usize> {
            // One scalar test per field (an OR of them all, vectorized, read the fields the
            // step had just written through wider loads and stalled store forwarding).
            #(#finite_checks)*
            ::core::option::Option::None
        }
    }
}

/// Get and set of strings, array elements and binaries.
fn string_array_binary_items(rt: &TokenStream, vars: &[Var]) -> TokenStream {
    let of = |kind: Kind| vars.iter().filter(move |v| v.kind == kind);
    // The getter and the setter of the fields of `kind`: `read` is the method that reads one,
    // `from` what makes one of the value given.
    let accessors = |kind: Kind, read: TokenStream, from: TokenStream| {
        let get = by_vr(
            of(kind).map(|v| {
                let (f, vr) = (&v.field, v.vr);
                quote!(#vr => ::core::option::Option::Some(self.#f.#read()))
            }),
            none(),
        );
        let set = by_vr(
            of(kind).map(|v| {
                let (f, vr) = (&v.field, v.vr);
                quote!(#vr => { self.#f = #from(value); true })
            }),
            quote!(false),
        );
        (get, set)
    };
    let (get_string, set_string) = accessors(Kind::Str, quote!(as_str), quote!(::std::string::String::from));
    let arrays: Vec<&Var> = vars.iter().filter(|v| !v.dims.is_empty()).collect();
    let get_element = by_vr(
        arrays.iter().map(|v| {
            let (vr, flat) = (v.vr, flat(v, false));
            quote!(#vr => #flat.get(i).and_then(#rt::FmiType::to_value))
        }),
        none(),
    );
    let set_element = by_vr(
        arrays.iter().map(|v| {
            let (vr, flat, elem) = (v.vr, flat(v, true), &v.elem);
            quote!(#vr => match (#flat.get_mut(i), <#elem as #rt::FmiType>::from_value(value)) {
                (::core::option::Option::Some(slot), ::core::option::Option::Some(x)) => { *slot = x; true }
                _ => false,
            })
        }),
        quote!(false),
    );
    let (get_binary, set_binary) = accessors(Kind::Binary, quote!(as_slice), quote!(::std::vec::Vec::from));
    quote! {
        fn get_string(&self, vr: u32) -> ::core::option::Option<&str> {
            #get_string
        }

        fn set_string(&mut self, vr: u32, value: &str) -> bool {
            let _ = value;
            #set_string
        }

        fn get_element(&self, vr: u32, i: usize) -> ::core::option::Option<#rt::Value> {
            let _ = i;
            #get_element
        }

        fn set_element(&mut self, vr: u32, i: usize, value: #rt::Value) -> bool {
            let _ = (i, value);
            #set_element
        }

        fn get_binary(&self, vr: u32) -> ::core::option::Option<&[u8]> {
            #get_binary
        }

        fn set_binary(&mut self, vr: u32, value: &[u8]) -> bool {
            let _ = value;
            #set_binary
        }
    }
}

/// The clocks by value reference, and their deactivation.
fn clock_items(rt: &TokenStream, vars: &[Var]) -> TokenStream {
    let clocks: Vec<&Var> = vars.iter().filter(|v| v.kind == Kind::Clock).collect();
    let clock = by_vr(
        clocks.iter().map(|v| {
            let (f, vr) = (&v.field, v.vr);
            quote!(#vr => ::core::option::Option::Some(&self.#f))
        }),
        none(),
    );
    let clock_mut = by_vr(
        clocks.iter().map(|v| {
            let (f, vr) = (&v.field, v.vr);
            quote!(#vr => ::core::option::Option::Some(&mut self.#f))
        }),
        none(),
    );
    let deactivate = clocks.iter().map(|v| {
        let f = &v.field;
        quote!(self.#f.__set_active(false);)
    });
    quote! {
        fn clock(&self, vr: u32) -> ::core::option::Option<&#rt::Clock> {
            #clock
        }
        fn clock_mut(&mut self, vr: u32) -> ::core::option::Option<&mut #rt::Clock> {
            #clock_mut
        }
        fn deactivate_clocks(&mut self) {
            #(#deactivate)*
        }
    }
}
