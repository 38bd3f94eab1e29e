//! Arrays of more than 32 elements, which the standard library and serde implement their traits
//! for only up to 32. A model's FMU state is the struct serialized with serde: a longer array
//! field (a variable or internal state) needs `#[serde(with = "rustfmu::BigArray")]` (two
//! dimensions: `rustfmu::BigMatrix`). Without it
//! serde's derive fails with "the trait bound `[f64; 50]: Serialize` is not satisfied"; [`checks`]
//! says at the field what to add (a length written as a number is checked here; one written as
//! a constant, by the compiler: a compile-time assertion at the field). And an internal field
//! starts at its type's default, which an array of more than 32 has not: [`default_value`] starts
//! it element by element.

use proc_macro2::{Span, TokenStream, TokenTree};
use quote::{quote, quote_spanned};
use syn::spanned::Spanned;
use syn::{Data, DeriveInput, Expr, Fields, Lit, Type};

/// serde's derive (de)serializes arrays of up to this many elements.
const SERDE_MAX: usize = 32;

/// The checks for every array field of `input` without a serde attribute that serializes it
/// another way: `compile_error!`s where a length is a number above 32, assertions where it is
/// a constant.
pub(crate) fn checks(input: &DeriveInput) -> TokenStream {
    let Data::Struct(data) = &input.data else {
        return TokenStream::new();
    };
    let Fields::Named(fields) = &data.fields else {
        return TokenStream::new();
    };
    let rt = runtime_name();
    let mut out = TokenStream::new();
    for f in &fields.named {
        let lengths = lengths(&f.ty);
        if lengths.is_empty() || handled_by_serde_attribute(&f.attrs) {
            continue;
        }
        let (helper, along) = if lengths.len() == 1 {
            ("BigArray", "")
        } else {
            ("BigMatrix", " along a dimension")
        };
        let attribute = format!("#[serde(with = \"{rt}::{helper}\")]");
        let name = f.ident.as_ref().map(|i| i.to_string()).unwrap_or_default();
        let ty = &f.ty;
        let shape = quote!(#ty).to_string().replace(' ', "");
        let message = |what: &str| {
            format!(
                "'{name}' ({shape}) is an array {what}, and serde (de)serializes arrays of at most {SERDE_MAX} (the FMU \
                 state serializes the model): add {attribute} to the field (serde's errors about `Serialize`/`Deserialize` \
                 for this array that follow have the same cause)"
            )
        };
        let numbers: Option<Vec<usize>> = lengths.iter().map(literal_length).collect();
        match numbers {
            Some(numbers) => {
                if let Some(n) = numbers.into_iter().find(|n| *n > SERDE_MAX) {
                    let message = message(&format!("of {n} elements{along}"));
                    out.extend(syn::Error::new(f.ty.span(), message).to_compile_error());
                }
            }
            None => {
                let message = message(&format!("of more than {SERDE_MAX} elements{along}"));
                let span: Span = f.ty.span();
                let within = lengths.iter().map(|n| quote!(((#n) as usize) <= #SERDE_MAX));
                out.extend(quote_spanned!(span =>
                    #[allow(clippy::unnecessary_cast)]
                    const _: () = ::core::assert!(#(#within)&&*, #message);
                ));
            }
        }
    }
    out
}

/// What an internal (undeclared) field of type `ty` starts at: `Default::default()`, element by
/// element for an array (of any length).
pub(crate) fn default_value(ty: Option<&Type>) -> TokenStream {
    let depth = ty.map_or(0, |t| lengths(t).len());
    let mut value = quote!(::core::default::Default::default());
    for _ in 0..depth {
        value = quote!(::core::array::from_fn(|_| #value));
    }
    value
}

/// The lengths of an array type, outermost first (`[[f64; 4]; 2]`: `2`, `4`); none for others.
fn lengths(ty: &Type) -> Vec<&Expr> {
    let mut lengths = Vec::new();
    let mut t = ty;
    while let Type::Array(a) = t {
        lengths.push(&a.len);
        t = &a.elem;
    }
    lengths
}

fn literal_length(e: &&Expr) -> Option<usize> {
    match e {
        Expr::Lit(syn::ExprLit { lit: Lit::Int(n), .. }) => n.base10_parse().ok(),
        _ => None,
    }
}

/// Whether a `#[serde(..)]` of the field serializes it another way (`with`, `serialize_with`,
/// `deserialize_with`) or not at all (`skip`, ..).
fn handled_by_serde_attribute(attrs: &[syn::Attribute]) -> bool {
    const KEYS: [&str; 6] = [
        "with",
        "serialize_with",
        "deserialize_with",
        "skip",
        "skip_serializing",
        "skip_deserializing",
    ];
    attrs
        .iter()
        .filter(|a| a.path().is_ident("serde"))
        .any(|a| match &a.meta {
            syn::Meta::List(list) => list
                .tokens
                .clone()
                .into_iter()
                .any(|t| matches!(t, TokenTree::Ident(i) if KEYS.iter().any(|k| i == k))),
            _ => false,
        })
}

/// `rustfmu`, or the name the user's Cargo.toml gives it.
fn runtime_name() -> String {
    use proc_macro_crate::{FoundCrate, crate_name};
    match crate_name("rustfmu") {
        Ok(FoundCrate::Name(name)) => name,
        _ => "rustfmu".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::checks;

    fn check(src: &str) -> String {
        checks(&syn::parse_str(src).unwrap()).to_string()
    }

    #[test]
    fn a_long_array_without_a_serde_attribute_is_an_error_naming_the_attribute() {
        let out = check("struct Rod { #[variable(vr = 1, local)] cells: [f64; 50], short: [f64; 32] }");
        assert!(out.contains("compile_error"), "{out}");
        assert!(out.contains("'cells' ([f64;50]) is an array of 50 elements"), "{out}");
        assert!(
            out.contains(r#"add #[serde(with = \"rustfmu::BigArray\")] to the field"#),
            "{out}"
        );
        assert!(!out.contains("short"), "{out}");
        // Each dimension counts: serde fails on the rows as on the whole; a matrix has its own.
        let grid = check("struct G { grid: [[f64; 40]; 2] }");
        assert!(grid.contains("of 40 elements"), "{grid}");
        assert!(
            grid.contains(r#"add #[serde(with = \"rustfmu::BigMatrix\")]"#),
            "{grid}"
        );
    }

    #[test]
    fn an_internal_array_starts_element_by_element() {
        let ty: syn::Type = syn::parse_str("[[f64; 40]; 2]").unwrap();
        let value = super::default_value(Some(&ty)).to_string().replace(' ', "");
        assert_eq!(
            value,
            "::core::array::from_fn(|_|::core::array::from_fn(|_|::core::default::Default::default()))"
        );
        let ty: syn::Type = syn::parse_str("Vec<f64>").unwrap();
        assert_eq!(
            super::default_value(Some(&ty)).to_string().replace(' ', ""),
            "::core::default::Default::default()"
        );
    }

    #[test]
    fn a_serde_attribute_or_a_constant_length_is_left_to_serde_and_the_compiler() {
        assert_eq!(
            check(r#"struct Rod { #[serde(with = "rustfmu::BigArray")] cells: [f64; 50] }"#),
            ""
        );
        assert_eq!(check("struct Rod { #[serde(skip)] cells: [f64; 50] }"), "");
        let out = check("struct Rod { cells: [f64; N] }");
        assert!(
            out.contains("assert") && out.contains("N") && !out.contains("compile_error"),
            "{out}"
        );
    }
}
