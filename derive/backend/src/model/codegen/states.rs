//! The state vector: each scalar state one entry, each array state its elements, in the order
//! of the derivatives' declarations; its value references, element indices, nominals, and the
//! copies between it and the fields.

use crate::model::decl::{Var, by_name};
use proc_macro2::TokenStream;
use quote::quote;
use syn::Ident;

/// The state vector's lists and copies, as tokens of the generated impl.
pub(crate) struct StateVector {
    pub n_states: TokenStream,
    pub state_vrs: TokenStream,
    pub state_elements: TokenStream,
    pub deriv_vrs: TokenStream,
    pub nominals: TokenStream,
    pub states_self: TokenStream,
    pub states_c: TokenStream,
    pub derivs_c: TokenStream,
    pub set_states_self: TokenStream,
    pub set_states_c: TokenStream,
}

impl StateVector {
    /// The state vector of `vars`: the states of its derivatives.
    // About 150 lines: the general lists (of array states, element by element, computed at
    // compile time) and the literal ones of scalar states side by side, so that the two can be
    // compared.
    pub fn of(vars: &[Var]) -> StateVector {
        let derivs: Vec<&Var> = vars.iter().filter(|v| v.derivative_of.is_some()).collect();
        let states: Vec<&Var> = derivs
            .iter()
            .map(|d| {
                let n = &d.derivative_of.as_ref().expect("filtered").0;
                by_name(vars, n).expect("checked")
            })
            .collect();
        // The state vector: each scalar state one entry, each array state its elements (all of
        // its capacity; the runtime gives the importer the first `n` of a sized one).
        let len_of = |v: &Var| match v.dims.first() {
            Some(n) => quote!((#n)),
            None => quote!(1usize),
        };
        let lens: Vec<TokenStream> = states.iter().map(|v| len_of(v)).collect();
        let n_states = quote!(0usize #(+ #lens)*);
        // A const array of the state vector's length, element k of state variable i given by
        // `each(i)` (a const expression of `j`, the element's index).
        let per_element = |ty: TokenStream, zero: TokenStream, each: &dyn Fn(usize) -> TokenStream| {
            let fills = (0..states.len()).map(|i| {
                let (len, value) = (&lens[i], each(i));
                quote!({
                    let mut j = 0usize;
                    while j < #len {
                        a[k] = #value;
                        k += 1;
                        j += 1;
                    }
                })
            });
            quote!(&{
                let mut a: [#ty; #n_states] = [#zero; #n_states];
                let mut k = 0usize;
                #(#fills)*
                let _ = k;
                a
            })
        };
        // Scalar states only (every model before arrays could be states): the lists as literals.
        let scalar_states = states.iter().all(|v| v.dims.is_empty());
        let state_vrs = per_element(quote!(u32), quote!(0u32), &|i| {
            let vr = states[i].vr;
            quote!({ let _ = j; #vr })
        });
        let state_elements = per_element(quote!(u32), quote!(0u32), &|_| quote!(j as u32));
        let deriv_vrs = per_element(quote!(u32), quote!(0u32), &|i| {
            let vr = derivs[i].vr;
            quote!({ let _ = j; #vr })
        });
        let nominals = per_element(quote!(f64), quote!(0.0f64), &|i| {
            let nominal = match &states[i].nominal {
                Some(e) => quote!((#e) as f64),
                None => quote!(1.0),
            };
            quote!({ let _ = j; #nominal })
        });
        // Copies between the state vector and the fields: `x[k]` and a field's element.
        let copy_out = |from: TokenStream, vars: &[&Var]| {
            let parts = vars.iter().map(|v| {
                let f = &v.field;
                if v.dims.is_empty() {
                    quote!(x[k] = #from.#f; k += 1;)
                } else {
                    quote!(for e in #from.#f.iter() { x[k] = *e; k += 1; })
                }
            });
            quote!({
                let mut x = [0.0f64; #n_states];
                let mut k = 0usize;
                #(#parts)*
                let _ = k;
                x
            })
        };
        let copy_in = |to: TokenStream| {
            let parts = states.iter().map(|v| {
                let f = &v.field;
                if v.dims.is_empty() {
                    quote!(#to.#f = x[k]; k += 1;)
                } else {
                    quote!(for e in #to.#f.iter_mut() { *e = x[k]; k += 1; })
                }
            });
            quote!({
                let mut k = 0usize;
                #(#parts)*
                let _ = k;
            })
        };
        let (
            state_vrs,
            state_elements,
            deriv_vrs,
            nominals,
            states_self,
            states_c,
            derivs_c,
            set_states_self,
            set_states_c,
        ) = if scalar_states {
            let (svrs, dvrs) = (states.iter().map(|v| v.vr), derivs.iter().map(|v| v.vr));
            let zeros = states.iter().map(|_| 0u32);
            let noms = states.iter().map(|v| match &v.nominal {
                Some(e) => quote!((#e) as f64),
                None => quote!(1.0),
            });
            let sf: Vec<&Ident> = states.iter().map(|v| &v.field).collect();
            let df: Vec<&Ident> = derivs.iter().map(|v| &v.field).collect();
            let idx: Vec<usize> = (0..states.len()).collect();
            (
                quote!(&[#(#svrs),*]),
                quote!(&[#(#zeros),*]),
                quote!(&[#(#dvrs),*]),
                quote!(&[#(#noms),*]),
                quote!([#(self.#sf),*]),
                quote!([#(c.#sf),*]),
                quote!([#(c.#df),*]),
                quote!(#(self.#sf = x[#idx];)*),
                quote!(#(c.#sf = x[#idx];)*),
            )
        } else {
            (
                state_vrs,
                state_elements,
                deriv_vrs,
                nominals,
                copy_out(quote!(self), &states),
                copy_out(quote!(c), &states),
                copy_out(quote!(c), &derivs),
                copy_in(quote!(self)),
                copy_in(quote!(c)),
            )
        };
        let n_states = if scalar_states {
            let n = states.len();
            quote!(#n)
        } else {
            n_states
        };
        StateVector {
            n_states,
            state_vrs,
            state_elements,
            deriv_vrs,
            nominals,
            states_self,
            states_c,
            derivs_c,
            set_states_self,
            set_states_c,
        }
    }
}
