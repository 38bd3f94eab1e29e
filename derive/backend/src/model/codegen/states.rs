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
    /// The state vector of `vars`: the states of its derivatives. The general lists (of array
    /// states, element by element, computed at compile time); scalar states have literal ones
    /// (`scalar`).
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
        if states.iter().all(|v| v.dims.is_empty()) {
            return StateVector::scalar(&states, &derivs);
        }
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
        let (states_self, states_c, derivs_c) = (
            copy_out(quote!(self), &states),
            copy_out(quote!(c), &states),
            copy_out(quote!(c), &derivs),
        );
        let (set_states_self, set_states_c) = (copy_in(quote!(self)), copy_in(quote!(c)));
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

    /// The state vector of scalar states only (every model before arrays could be states): the
    /// lists as literals, the copies one assignment per state.
    fn scalar(states: &[&Var], derivs: &[&Var]) -> StateVector {
        let n = states.len();
        let (svrs, dvrs) = (states.iter().map(|v| v.vr), derivs.iter().map(|v| v.vr));
        let zeros = states.iter().map(|_| 0u32);
        let noms = states.iter().map(|v| match &v.nominal {
            Some(e) => quote!((#e) as f64),
            None => quote!(1.0),
        });
        let sf: Vec<&Ident> = states.iter().map(|v| &v.field).collect();
        let df: Vec<&Ident> = derivs.iter().map(|v| &v.field).collect();
        let idx: Vec<usize> = (0..states.len()).collect();
        StateVector {
            n_states: quote!(#n),
            state_vrs: quote!(&[#(#svrs),*]),
            state_elements: quote!(&[#(#zeros),*]),
            deriv_vrs: quote!(&[#(#dvrs),*]),
            nominals: quote!(&[#(#noms),*]),
            states_self: quote!([#(self.#sf),*]),
            states_c: quote!([#(c.#sf),*]),
            derivs_c: quote!([#(c.#df),*]),
            set_states_self: quote!(#(self.#sf = x[#idx];)*),
            set_states_c: quote!(#(c.#sf = x[#idx];)*),
        }
    }

    /// The impl's type `States` and the state vector's lists (value references, element
    /// indices, derivatives' value references, nominals).
    pub fn lists(&self) -> TokenStream {
        let StateVector {
            n_states,
            state_vrs,
            state_elements,
            deriv_vrs,
            nominals,
            ..
        } = self;
        quote! {
            type States = [f64; #n_states];
            const STATES: &'static [u32] = #state_vrs;
            const STATE_ELEMENTS: &'static [u32] = #state_elements;
            const DERIVATIVES: &'static [u32] = #deriv_vrs;
            const NOMINALS: &'static [f64] = #nominals;
        }
    }

    /// The impl's copies between the state vector and the model or the struct `cont_ident`.
    pub fn copies(&self, cont_ident: &Ident) -> TokenStream {
        let StateVector {
            n_states,
            states_self,
            states_c,
            derivs_c,
            set_states_self,
            set_states_c,
            ..
        } = self;
        quote! {
            #[inline]
            fn states(&self) -> [f64; #n_states] {
                #states_self
            }

            #[inline]
            fn set_states(&mut self, x: &[f64; #n_states]) {
                let _ = x;
                #set_states_self
            }

            #[inline]
            fn states_of(c: &#cont_ident<f64>) -> [f64; #n_states] {
                let _ = c;
                #states_c
            }

            #[inline]
            fn set_states_of(c: &mut #cont_ident<f64>, x: &[f64; #n_states]) {
                let _ = (&c, x);
                #set_states_c
            }

            #[inline]
            fn derivatives_of(c: &#cont_ident<f64>) -> [f64; #n_states] {
                let _ = c;
                #derivs_c
            }
        }
    }
}
