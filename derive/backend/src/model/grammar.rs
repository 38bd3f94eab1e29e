//! The grammar of the derive's attributes, one piece for all of them: an attribute is a table of
//! keys, each with the parser that reads its value (a typed value: a `u32`, a string, an
//! expression, a list of names, a bound, a nested attribute) into the attribute it fills. The
//! "known:" lists of the error messages and of the documentation are the tables' key names, so
//! the parser and the lists cannot disagree.
//!
//! An attribute's first mistake is its one error (the derive reports one mistake at a time, at
//! the key or value it concerns), as the compile-error tests pin them.

use proc_macro2::Span;
use syn::meta::ParseNestedMeta;
use syn::parse::{Parse, ParseStream};
use syn::{Error, Expr, Ident, LitStr, Result, Token};

/// One key of an attribute: its name as the "known:" list writes it (`clock(..)` for a key
/// followed by a parenthesized list) and the parser of its value.
pub(crate) struct Key<P> {
    pub name: &'static str,
    pub parse: P,
}

/// A key's parser in a `key = value, ..` list (`#[variable(..)]`, `clock(..)`, `alias(..)`):
/// reads what follows the key into the attribute `A`.
pub(crate) type Parser<A> = fn(&mut A, &Ident, ParseStream) -> Result<()>;

/// A key's parser in an attribute syn reads as nested meta (`#[fmu(..)]`).
pub(crate) type MetaParser<A> = fn(&mut A, &ParseNestedMeta) -> Result<()>;

/// The names of a table's keys, in its order.
pub(crate) const fn key_names<P, const N: usize>(keys: &[Key<P>; N]) -> [&'static str; N] {
    let mut names = [""; N];
    let mut i = 0;
    while i < N {
        names[i] = keys[i].name;
        i += 1;
    }
    names
}

/// The parser of `key` (written bare, or as `key(..)` for a nested list) in `keys`.
pub(crate) fn find<'k, P>(keys: &'k [Key<P>], key: &str) -> Option<&'k P> {
    keys.iter()
        .find(|k| k.name.strip_suffix("(..)").unwrap_or(k.name) == key)
        .map(|k| &k.parse)
}

/// "unknown declaration `x`; known: a, b, ..": one message for each table of keys.
pub(crate) fn unknown_key(span: Span, what: &str, key: &str, keys: &[&str]) -> Error {
    Error::new(span, format!("unknown {what} `{key}`; known: {}", keys.join(", ")))
}

/// A comma-separated list of keys and their values, parsed into `A` (from its default).
pub(crate) struct Grammar<A: 'static> {
    pub keys: &'static [Key<Parser<A>>],
    /// How a key is read: `#[variable]` reads keywords too (`type` is an unknown declaration
    /// there, not "expected identifier").
    pub key: fn(ParseStream) -> Result<Ident>,
    /// The error for a key the table has not (`alias(..)` reads its value first).
    pub unknown: fn(&Ident, ParseStream) -> Error,
}

impl<A: Default> Grammar<A> {
    pub fn parse(&self, input: ParseStream) -> Result<A> {
        let mut attr = A::default();
        while !input.is_empty() {
            let key = (self.key)(input)?;
            let Some(parse) = find(self.keys, &key.to_string()) else {
                return Err((self.unknown)(&key, input));
            };
            parse(&mut attr, &key, input)?;
            if input.is_empty() {
                break;
            }
            input.parse::<Token![,]>()?;
        }
        Ok(attr)
    }
}

/// An identifier, or a keyword read as one.
pub(crate) fn any_ident(input: ParseStream) -> Result<Ident> {
    input.call(syn::ext::IdentExt::parse_any)
}

/// A plain identifier.
pub(crate) fn ident(input: ParseStream) -> Result<Ident> {
    input.parse()
}

/// Fills `slot` with `value`'s parse of the input, unless the key has been given already
/// ("`key` is given twice", at the key, before its value is read).
pub(crate) fn once<T>(
    slot: &mut Option<T>,
    key: &Ident,
    input: ParseStream,
    value: impl FnOnce(ParseStream) -> Result<T>,
) -> Result<()> {
    if slot.is_some() {
        return Err(Error::new(key.span(), format!("`{key}` is given twice")));
    }
    *slot = Some(value(input)?);
    Ok(())
}

/// Sets `slot` to `value` (a key given more than once: the last one counts).
pub(crate) fn set<T>(slot: &mut T, value: T) -> Result<()> {
    *slot = value;
    Ok(())
}

/// Sets `slot` to `value` (a key that is its own value, as `input` is a causality), unless
/// another key of the same kind took it: "two causalities: Input and Output; a variable has one".
pub(crate) fn one_of<T: std::fmt::Debug>(
    slot: &mut Option<(T, Span)>,
    value: T,
    key: &Ident,
    kinds: &str,
) -> Result<()> {
    if let Some((prev, _)) = slot {
        return Err(Error::new(
            key.span(),
            format!("two {kinds}: {prev:?} and {value:?}; a variable has one"),
        ));
    }
    *slot = Some((value, key.span()));
    Ok(())
}

/// `= value`.
pub(crate) fn assigned<T: Parse>(input: ParseStream) -> Result<T> {
    input.parse::<Token![=]>()?;
    input.parse()
}

/// `= 7`, as a `u32` (value references, priorities), with the literal's span.
pub(crate) fn assigned_u32(input: ParseStream) -> Result<(u32, Span)> {
    let n: syn::LitInt = assigned(input)?;
    Ok((n.base10_parse()?, n.span()))
}

/// `= [a, "b.c", d]`: names of variables, by field or by FMI name.
pub(crate) fn names(input: ParseStream) -> Result<Vec<(String, Span)>> {
    input.parse::<Token![=]>()?;
    let content;
    syn::bracketed!(content in input);
    let list = content.parse_terminated(name_or_ident, Token![,])?;
    Ok(list.into_iter().collect())
}

/// A variable named by its field (`x`) or its FMI name (`"b.c"`).
pub(crate) fn name_or_ident(input: ParseStream) -> Result<(String, Span)> {
    if input.peek(LitStr) {
        let s: LitStr = input.parse()?;
        Ok((s.value(), s.span()))
    } else {
        let i: Ident = input.parse()?;
        Ok((i.to_string(), i.span()))
    }
}

/// A bound after `min` (`= x` and `>= x`: x is legal; `> x`: it is not) or `max` (`=`, `<=`,
/// `<`): the value and whether it is exclusive.
pub(crate) fn bound(key: &Ident, input: ParseStream) -> Result<(Expr, bool)> {
    let lower = key == "min";
    let exclusive = if lower && input.peek(Token![>=]) {
        input.parse::<Token![>=]>()?;
        false
    } else if !lower && input.peek(Token![<=]) {
        input.parse::<Token![<=]>()?;
        false
    } else if lower && input.peek(Token![>]) {
        input.parse::<Token![>]>()?;
        true
    } else if !lower && input.peek(Token![<]) {
        input.parse::<Token![<]>()?;
        true
    } else {
        let (inclusive, exclusive) = if lower { (">=", ">") } else { ("<=", "<") };
        input.parse::<Token![=]>().map_err(|e| {
            Error::new(
                e.span(),
                format!("expected `{key} = x` (x is legal), `{key} {inclusive} x` or `{key} {exclusive} x` (x is not)"),
            )
        })?;
        false
    };
    Ok((input.parse()?, exclusive))
}

/// `(..)`: a nested attribute.
pub(crate) fn nested<T: Parse>(input: ParseStream) -> Result<T> {
    let content;
    syn::parenthesized!(content in input);
    content.parse()
}
