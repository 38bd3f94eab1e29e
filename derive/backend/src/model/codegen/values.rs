//! Values as the generated code writes them: an optional value, an array's value before
//! initialization.

use crate::model::decl::{Kind, Var};
use proc_macro2::TokenStream;
use quote::{ToTokens, quote};

/// `Some(x)` or `None`, spelled out (the model's crate may shadow `Option`).
pub(crate) fn option(x: Option<impl ToTokens>) -> TokenStream {
    match x {
        Some(x) => quote!(::core::option::Option::Some(#x)),
        None => quote!(::core::option::Option::None),
    }
}

/// A scalar zero of the variable's element kind (an enumeration's first item).
fn zero_of(rt: &TokenStream, v: &Var) -> TokenStream {
    let elem = &v.elem;
    match v.kind {
        Kind::Real | Kind::Float32 => quote!(0.0),
        Kind::Integer | Kind::Int3 | Kind::UInt64 => quote!(0),
        Kind::Boolean => quote!(false),
        Kind::Enum => quote!(<#elem as #rt::FmuEnum>::FIRST),
        Kind::Str => quote!(::std::string::String::new()),
        Kind::Binary => quote!(::std::vec::Vec::new()),
        Kind::Clock => quote!(#rt::Clock::default()),
    }
}

/// An array variable's value before initialization: its `start`, else zeros of its shape.
pub(crate) fn array_value(rt: &TokenStream, v: &Var) -> TokenStream {
    if let Some(e) = &v.start {
        return quote!(#e);
    }
    let mut value = zero_of(rt, v);
    for len in v.dims.iter().rev() {
        value = quote!([#value; #len]);
    }
    value
}
