//! `modelDescription.xml`, FMI 2.0 ([`fmi2()`]) and FMI 3.0 ([`fmi3()`]), written with quick-xml
//! from the typed description that the built library carries, each in the element order of its
//! XSD. Both come from the same decoded `ModelDescription`; only the encoding of the XML differs.
//!
//! Here the writer's helpers and what both versions write alike; [`check`] the rules checked
//! once more before writing, [`sections`] the elements both versions share, [`arrays`] FMI
//! 3.0's array sizes, [`fmi2`] and [`fmi3`] each version's file, [`terminals`]
//! `terminalsAndIcons.xml`.

mod arrays;
mod check;
mod fmi2;
mod fmi3;
mod sections;
mod terminals;

#[cfg(test)]
mod alias_tests;
#[cfg(test)]
mod tests;

pub use arrays::array_sizes;
pub use check::check_description;
pub use fmi2::fmi2;
pub use fmi3::fmi3;
pub use terminals::{LS_BUS_DESCRIPTION, LS_BUS_MANIFEST, NETWORK_TERMINAL_KIND, ls_bus_manifest, terminals_and_icons};

use quick_xml::Writer;
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use rustfmu::description::{Bound, FmiVersion, Interfaces, ModelDescription};

/// Shortest text that reads back as the same f64 (Rust's `{:?}` is round-trip exact).
pub fn real_text(x: f64) -> String {
    format!("{x:?}")
}

type Xml = Writer<Vec<u8>>;

fn io(e: impl std::fmt::Display) -> String {
    format!("writing modelDescription.xml: {e}")
}

fn empty(w: &mut Xml, name: &str, attrs: &[(&str, &str)]) -> Result<(), String> {
    let mut el = BytesStart::new(name);
    for (k, v) in attrs {
        el.push_attribute((*k, *v));
    }
    w.write_event(Event::Empty(el)).map_err(io)
}

fn open(w: &mut Xml, name: &str, attrs: &[(&str, &str)]) -> Result<(), String> {
    let mut el = BytesStart::new(name);
    for (k, v) in attrs {
        el.push_attribute((*k, *v));
    }
    w.write_event(Event::Start(el)).map_err(io)
}

fn close(w: &mut Xml, name: &str) -> Result<(), String> {
    w.write_event(Event::End(BytesEnd::new(name))).map_err(io)
}

fn lower_camel<T: std::fmt::Debug>(v: T) -> String {
    let s = format!("{v:?}");
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_lowercase().chain(c).collect(),
        None => s,
    }
}

/// `min`/`max` as FMI 2.0 writes them: inclusive, so an exclusive bound is written as the
/// nearest representable value inside the range (`> 0` becomes 5e-324).
fn bound_value(b: Bound, is_min: bool) -> f64 {
    match (b.exclusive, is_min) {
        (false, _) => b.value,
        (true, true) => b.value.next_up(),
        (true, false) => b.value.next_down(),
    }
}

/// A flat name has no structure (`der(x)`, `a.b`, `a[1]` ask for "structured").
fn is_flat_name(name: &str) -> bool {
    !name.contains(['.', '[', '('])
}

/// A writer of one XML file, its declaration written.
fn document() -> Result<Xml, String> {
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))
        .map_err(io)?;
    Ok(w)
}

/// The text a writer wrote, with a final newline.
fn finish(w: Xml) -> Result<String, String> {
    let mut text = String::from_utf8(w.into_inner()).map_err(io)?;
    text.push('\n');
    Ok(text)
}

/// Refuses a binary of another FMI version than the file's (its functions have the other prefix).
fn of_version(d: &ModelDescription, interfaces: Interfaces, version: FmiVersion) -> Result<(), String> {
    if interfaces.version == version {
        return Ok(());
    }
    let prefix = match version {
        FmiVersion::V2 => "fmi2",
        FmiVersion::V3 => "fmi3",
    };
    Err(format!(
        "{}: the binary implements FMI {}, not {} (its functions are not {prefix}*)",
        d.model_identifier,
        interfaces.version.text(),
        version.text()
    ))
}

/// The attributes of `<fmiModelDescription>` both versions write: `fmi_version`, and `id` (the
/// GUID: `guid` in FMI 2.0, `instantiationToken` in 3.0) with its value.
fn root_attributes<'a>(
    d: &ModelDescription,
    fmi_version: &'a str,
    (id, guid): (&'a str, &'a str),
) -> Vec<(&'a str, &'a str)> {
    let mut root = vec![
        ("fmiVersion", fmi_version),
        ("modelName", d.model_identifier),
        (id, guid),
        ("description", d.description),
        ("author", d.author),
        ("version", d.version),
    ];
    if !d.copyright.is_empty() {
        root.push(("copyright", d.copyright));
    }
    if !d.license.is_empty() {
        root.push(("license", d.license));
    }
    root.extend([
        ("generationTool", d.generation_tool),
        (
            "variableNamingConvention",
            if d.variables.iter().any(|v| !is_flat_name(v.name)) {
                "structured"
            } else {
                "flat"
            },
        ),
    ]);
    root
}

/// An interface's element (`<ModelExchange>`, `<CoSimulation>`, ...): `modelIdentifier`, then
/// the attributes of each part of `parts`, in order.
fn interface(w: &mut Xml, element: &str, d: &ModelDescription, parts: &[&[(&str, &str)]]) -> Result<(), String> {
    let mut attrs = vec![("modelIdentifier", d.model_identifier)];
    for part in parts {
        attrs.extend_from_slice(part);
    }
    empty(w, element, &attrs)
}
