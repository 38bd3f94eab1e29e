//! `#[derive(FmuEnum)]`: a fieldless enum becomes an FMI Enumeration type. The enum's doc
//! comment is the type's description, each variant's doc comment the item's; `#[fmu(name =
//! "..")]` renames the type or an item (default: the Rust identifiers). Item values are the
//! discriminants (explicit or counted on from the previous one, as Rust counts them).

use proc_macro2::TokenStream;
use quote::quote;
use syn::spanned::Spanned;
use syn::{Data, DeriveInput, Error, Expr, Fields, LitStr};

fn renamed(attrs: &[syn::Attribute]) -> syn::Result<Option<String>> {
    let mut name = None;
    for a in attrs.iter().filter(|a| a.path().is_ident("fmu")) {
        a.parse_nested_meta(|m| {
            if m.path.is_ident("name") {
                name = Some(m.value()?.parse::<LitStr>()?.value());
                Ok(())
            } else {
                Err(m.error("on an FmuEnum, #[fmu] takes `name = \"..\"`"))
            }
        })?;
    }
    Ok(name)
}

pub fn expand(input: DeriveInput) -> syn::Result<TokenStream> {
    let rt = crate::runtime_path();
    let Data::Enum(data) = &input.data else {
        return Err(Error::new(
            input.ident.span(),
            "#[derive(FmuEnum)] is for fieldless enums",
        ));
    };
    if data.variants.is_empty() {
        return Err(Error::new(input.ident.span(), "an Enumeration needs at least one item"));
    }
    let ident = &input.ident;
    let type_name = renamed(&input.attrs)?.unwrap_or_else(|| ident.to_string());
    let type_description = crate::doc_text(&input.attrs);
    let mut items = Vec::new();
    let mut from_arms = Vec::new();
    let mut next: i64 = 1;
    let mut seen = std::collections::BTreeMap::new();
    for v in &data.variants {
        if !matches!(v.fields, Fields::Unit) {
            return Err(Error::new(v.span(), "Enumeration items carry no data"));
        }
        let value = match &v.discriminant {
            Some((
                _,
                Expr::Lit(syn::ExprLit {
                    lit: syn::Lit::Int(i), ..
                }),
            )) => i.base10_parse::<i64>()?,
            Some((_, e)) => return Err(Error::new(e.span(), "write the item's value as an integer literal")),
            None => next,
        };
        if i32::try_from(value).is_err() {
            return Err(Error::new(v.span(), "an item's value must fit an i32 (FMI Integer)"));
        }
        if let Some(first) = seen.insert(value, v.ident.to_string()) {
            return Err(Error::new(
                v.span(),
                format!("value {value} is used twice (first by {first})"),
            ));
        }
        next = value + 1;
        let value = value as i32;
        let name = renamed(&v.attrs)?.unwrap_or_else(|| v.ident.to_string());
        let description = crate::doc_text(&v.attrs);
        let vi = &v.ident;
        items.push(quote!(#rt::description::EnumItem { name: #name, value: #value, description: #description }));
        from_arms.push(quote!(#value => ::core::option::Option::Some(#ident::#vi)));
    }
    if data.variants.iter().any(|v| v.discriminant.is_none()) && data.variants.iter().any(|v| v.discriminant.is_some())
    {
        // Rust counts on from the previous discriminant exactly as above; nothing to do.
    }
    let first_has_discriminant = data.variants.first().is_some_and(|v| v.discriminant.is_some());
    if !first_has_discriminant {
        return Err(Error::new(
            data.variants.first().expect("non-empty").span(),
            "give the first item its value (`Item = 1`): Rust would start at 0, FMI tools usually at 1",
        ));
    }
    let first = &data.variants.first().expect("non-empty").ident;
    Ok(quote! {
        impl #rt::FmuEnum for #ident {
            const FIRST: Self = #ident::#first;
            const TYPE: &'static #rt::description::EnumType = &#rt::description::EnumType {
                name: #type_name,
                description: #type_description,
                items: &[#(#items),*],
            };
            fn code(self) -> i32 {
                self as i32
            }
            fn from_code(code: i32) -> ::core::option::Option<Self> {
                match code {
                    #(#from_arms,)*
                    _ => ::core::option::Option::None,
                }
            }
        }

        impl #rt::FmiType for #ident {
            const TYPE: #rt::description::VarType = #rt::description::VarType::Enumeration;
            const ENUMERATION: ::core::option::Option<&'static #rt::description::EnumType> =
                ::core::option::Option::Some(<#ident as #rt::FmuEnum>::TYPE);
            fn to_value(&self) -> ::core::option::Option<#rt::Value> {
                ::core::option::Option::Some(#rt::Value::Integer(*self as i32))
            }
            fn from_value(v: #rt::Value) -> ::core::option::Option<Self> {
                match v {
                    #rt::Value::Integer(code) => <#ident as #rt::FmuEnum>::from_code(code),
                    _ => ::core::option::Option::None,
                }
            }
        }
    })
}
