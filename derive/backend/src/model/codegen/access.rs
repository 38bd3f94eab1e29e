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
    // Value reference -> index in DESCRIPTION.variables: a match, not a search per call.
    let index_arms = vars.iter().enumerate().map(|(i, v)| {
        let vr = v.vr;
        quote!(#vr => ::core::option::Option::Some(#i))
    });

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
    let clock_fields: Vec<&Var> = vars.iter().filter(|v| v.kind == Kind::Clock).collect();
    let clock_arms = clock_fields.iter().map(|v| {
        let (f, vr) = (&v.field, v.vr);
        quote!(#vr => ::core::option::Option::Some(&self.#f))
    });
    let clock_mut_arms = clock_fields.iter().map(|v| {
        let (f, vr) = (&v.field, v.vr);
        quote!(#vr => ::core::option::Option::Some(&mut self.#f))
    });
    let deactivate = clock_fields.iter().map(|v| {
        let f = &v.field;
        quote!(self.#f.__set_active(false);)
    });
    let arrays: Vec<&Var> = vars.iter().filter(|v| !v.dims.is_empty()).collect();
    let flat = |v: &Var, mutable: bool| {
        let f = &v.field;
        match (v.dims.len(), mutable) {
            (2, false) => quote!(self.#f.as_flattened()),
            (2, true) => quote!(self.#f.as_flattened_mut()),
            (_, false) => quote!(self.#f.as_slice()),
            (_, true) => quote!(self.#f.as_mut_slice()),
        }
    };
    let get_elem_arms = arrays.iter().map(|v| {
        let (vr, flat) = (v.vr, flat(v, false));
        quote!(#vr => #flat.get(i).and_then(#rt::FmiType::to_value))
    });
    let set_elem_arms = arrays.iter().map(|v| {
        let (vr, flat, elem) = (v.vr, flat(v, true), &v.elem);
        quote!(#vr => match (#flat.get_mut(i), <#elem as #rt::FmiType>::from_value(value)) {
            (::core::option::Option::Some(slot), ::core::option::Option::Some(x)) => { *slot = x; true }
            _ => false,
        })
    });
    let strings: Vec<&Var> = vars.iter().filter(|v| v.kind == Kind::Str).collect();
    let binaries: Vec<&Var> = vars.iter().filter(|v| v.kind == Kind::Binary).collect();
    let get_bin_arms = binaries.iter().map(|v| {
        let (f, vr) = (&v.field, v.vr);
        quote!(#vr => ::core::option::Option::Some(self.#f.as_slice()))
    });
    let set_bin_arms = binaries.iter().map(|v| {
        let (f, vr) = (&v.field, v.vr);
        quote!(#vr => { self.#f = ::std::vec::Vec::from(value); true })
    });
    let get_arms = numeric.iter().map(|v| {
        let (f, vr) = (&v.field, v.vr);
        quote!(#vr => #rt::FmiType::to_value(&self.#f))
    });
    let set_arms = numeric.iter().map(|v| {
        let (f, vr, ty) = (&v.field, v.vr, &v.ty);
        quote!(#vr => match <#ty as #rt::FmiType>::from_value(value) {
            ::core::option::Option::Some(v) => { self.#f = v; true }
            ::core::option::Option::None => false,
        })
    });
    let get_str_arms = strings.iter().map(|v| {
        let (f, vr) = (&v.field, v.vr);
        quote!(#vr => ::core::option::Option::Some(self.#f.as_str()))
    });
    let set_str_arms = strings.iter().map(|v| {
        let (f, vr) = (&v.field, v.vr);
        quote!(#vr => { self.#f = ::std::string::String::from(value); true })
    });
    // The Real variables the model computes (inputs and parameters are checked when set): the
    // runtime asks after every step.
    let computed: Vec<(usize, &Ident)> = vars
        .iter()
        .enumerate()
        .filter(|(_, v)| {
            v.kind.is_float()
                && matches!(
                    v.causality,
                    Causality::Output | Causality::Local | Causality::CalculatedParameter | Causality::Independent
                )
        })
        .map(|(i, v)| (i, &v.field))
        .collect();
    let finite_checks = computed.iter().map(|(i, f)| {
        let v = &vars[*i];
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
            match vr {
                #(#index_arms,)*
                _ => ::core::option::Option::None,
            }
        }

        #[inline]
        fn get(&self, vr: u32) -> ::core::option::Option<#rt::Value> {
            match vr {
                #(#get_arms,)*
                _ => ::core::option::Option::None,
            }
        }

        #[inline]
        fn set(&mut self, vr: u32, value: #rt::Value) -> bool {
            let _ = &value;
            match vr {
                #(#set_arms,)*
                _ => false,
            }
        }

        #[inline]
        fn non_finite_computed(&self) -> ::core::option::Option<usize> {
            // One scalar test per field (an OR of them all, vectorized, read the fields the
            // step had just written through wider loads and stalled store forwarding).
            #(#finite_checks)*
            ::core::option::Option::None
        }

        fn get_string(&self, vr: u32) -> ::core::option::Option<&str> {
            match vr {
                #(#get_str_arms,)*
                _ => ::core::option::Option::None,
            }
        }

        fn set_string(&mut self, vr: u32, value: &str) -> bool {
            let _ = value;
            match vr {
                #(#set_str_arms,)*
                _ => false,
            }
        }

        fn get_element(&self, vr: u32, i: usize) -> ::core::option::Option<#rt::Value> {
            let _ = i;
            match vr {
                #(#get_elem_arms,)*
                _ => ::core::option::Option::None,
            }
        }

        fn set_element(&mut self, vr: u32, i: usize, value: #rt::Value) -> bool {
            let _ = (i, value);
            match vr {
                #(#set_elem_arms,)*
                _ => false,
            }
        }

        fn get_binary(&self, vr: u32) -> ::core::option::Option<&[u8]> {
            match vr {
                #(#get_bin_arms,)*
                _ => ::core::option::Option::None,
            }
        }

        fn set_binary(&mut self, vr: u32, value: &[u8]) -> bool {
            let _ = value;
            match vr {
                #(#set_bin_arms,)*
                _ => false,
            }
        }
        fn clock(&self, vr: u32) -> ::core::option::Option<&#rt::Clock> {
            match vr {
                #(#clock_arms,)*
                _ => ::core::option::Option::None,
            }
        }
        fn clock_mut(&mut self, vr: u32) -> ::core::option::Option<&mut #rt::Clock> {
            match vr {
                #(#clock_mut_arms,)*
                _ => ::core::option::Option::None,
            }
        }
        fn deactivate_clocks(&mut self) {
            #(#deactivate)*
        }
    }
}
