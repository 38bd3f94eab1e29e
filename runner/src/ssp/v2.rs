//! SSP 2.0: a `SystemStructure.ssd` (or `.ssv`) of `version="2.0"` checked against the
//! structure the SSP 2.0 schemas give it (`SystemStructureDescription.xsd`,
//! `SystemStructureCommon.xsd`, `SystemStructureParameterValues.xsd`), before it is read.
//!
//! SSP 2.0 keeps SSP 1.0's namespaces (`http://ssp-standard.org/SSP1/...`); what changes is the
//! root's `version` ("2.0") and what may stand in it: the FMI 3.0 connector and parameter types
//! (`Float64`, `Float32`, `Int8` ... `UInt64`, `Boolean`, `String`, `Enumeration`, `Binary`,
//! `Clock`, besides SSP 1.0's `Real` and `Integer`), `ssc:Dimension` (array connectors and
//! parameters), a connector's `ssd:Clock`, the connector kinds `structuralParameter`, `constant`
//! and `local`, `implementation="ScheduledExecution"`, a connection's `startIndices` /
//! `endIndices` and `suppressUnitConversion`, and SSV values as lists (an array, row-major).
//!
//! What is checked, each refusal naming the element and its line: every element of the SSD's
//! own namespaces where the schema allows it (its parent, its place in the parent's sequence, how
//! often it occurs, the children a sequence requires), the attributes the schema requires, the
//! values of its enumerated attributes (`kind`, `implementation`, `version`), and the values'
//! lexical types where the runner reads them (`startTime`, `stopTime`, `Dimension size`,
//! `startIndices`, every SSV value: `xs:double`, `xs:float`, `xs:byte` ... `xs:unsignedLong`,
//! `xs:boolean`, `xs:hexBinary`, each a list where the schema makes it one). Content the schema
//! leaves open (`xs:any`: an annotation's, a MetaData's or Signature's content, a
//! `ParameterValues` that is not an `ssv:ParameterSet`) is not looked into; nor are the graphical
//! elements' and signal dictionaries' insides (the runner refuses signal dictionaries and
//! parameter mappings when it reads them).

use crate::Error;
use quick_xml::NsReader;
use quick_xml::events::{BytesStart, Event};
use quick_xml::name::ResolveResult;

const SSD: &str = "http://ssp-standard.org/SSP1/SystemStructureDescription";
const SSC: &str = "http://ssp-standard.org/SSP1/SystemStructureCommon";
const SSV: &str = "http://ssp-standard.org/SSP1/SystemStructureParameterValues";
const SSM: &str = "http://ssp-standard.org/SSP1/SystemStructureParameterMapping";
const SSB: &str = "http://ssp-standard.org/SSP1/SystemStructureSignalDictionary";

/// The connector types of `ssc:GTypeChoice`, in SSP 2.0.
pub const CONNECTOR_TYPES: [&str; 17] = [
    "Real",
    "Float64",
    "Float32",
    "Integer",
    "Int8",
    "UInt8",
    "Int16",
    "UInt16",
    "Int32",
    "UInt32",
    "Int64",
    "UInt64",
    "Boolean",
    "String",
    "Enumeration",
    "Binary",
    "Clock",
];

/// The parameter types of `ssv:TParameter`, in SSP 2.0.
pub const SSV_TYPES: [&str; 16] = [
    "Real",
    "Float64",
    "Float32",
    "Integer",
    "Int8",
    "UInt8",
    "Int16",
    "UInt16",
    "Int32",
    "UInt32",
    "Int64",
    "UInt64",
    "Boolean",
    "String",
    "Enumeration",
    "Binary",
];

/// One slot of a sequence: the element names it takes (a choice if several), at least `min`,
/// any number if `many` (else at most one).
type Slot = (&'static [&'static str], usize, bool);

const METADATA: Slot = (&["ssc:MetaData"], 0, true);
const SIGNATURE: Slot = (&["ssc:Signature"], 0, true);

const TYPE_CHOICE: &[&str] = &[
    "ssc:Real",
    "ssc:Float64",
    "ssc:Float32",
    "ssc:Integer",
    "ssc:Int8",
    "ssc:UInt8",
    "ssc:Int16",
    "ssc:UInt16",
    "ssc:Int32",
    "ssc:UInt32",
    "ssc:Int64",
    "ssc:UInt64",
    "ssc:Boolean",
    "ssc:String",
    "ssc:Enumeration",
    "ssc:Binary",
    "ssc:Clock",
];

const SSV_CHOICE: &[&str] = &[
    "ssv:Real",
    "ssv:Float64",
    "ssv:Float32",
    "ssv:Integer",
    "ssv:Int8",
    "ssv:UInt8",
    "ssv:Int16",
    "ssv:UInt16",
    "ssv:Int32",
    "ssv:UInt32",
    "ssv:Int64",
    "ssv:UInt64",
    "ssv:Boolean",
    "ssv:String",
    "ssv:Enumeration",
    "ssv:Binary",
];

const TRANSFORMATIONS: &[&str] = &[
    "ssc:LinearTransformation",
    "ssc:BooleanMappingTransformation",
    "ssc:IntegerMappingTransformation",
    "ssc:EnumerationMappingTransformation",
];

/// What an element holds.
enum Content {
    /// A sequence of slots, in order.
    Seq(&'static [Slot]),
    /// Anything (`xs:any`, or not looked into).
    Open,
}

/// The content of an element, by its parent (for the local elements whose name is reused) and
/// itself; None: the element does not belong there.
fn content(parent: &str, el: &str) -> Option<Content> {
    use Content::*;
    Some(match (parent, el) {
        ("", "ssd:SystemStructureDescription") => Seq(&[
            (&["ssd:System"], 1, false),
            (&["ssd:Enumerations"], 0, false),
            (&["ssd:Units"], 0, false),
            (&["ssd:DefaultExperiment"], 0, false),
            METADATA,
            SIGNATURE,
            (&["ssd:Annotations"], 0, false),
        ]),
        ("", "ssv:ParameterSet") | ("ssd:ParameterValues", "ssv:ParameterSet") => Seq(&[
            (&["ssv:Parameters"], 1, false),
            (&["ssv:Enumerations"], 0, false),
            (&["ssv:Units"], 0, false),
            METADATA,
            SIGNATURE,
            (&["ssv:Annotations"], 0, false),
        ]),
        (_, "ssd:System") => Seq(&[
            (&["ssd:Connectors"], 0, false),
            (&["ssd:ElementGeometry"], 0, false),
            (&["ssd:ParameterBindings"], 0, false),
            METADATA,
            SIGNATURE,
            (&["ssd:Elements"], 0, false),
            (&["ssd:Connections"], 0, false),
            (&["ssd:SignalDictionaries"], 0, false),
            (&["ssd:SystemGeometry"], 0, false),
            (&["ssd:GraphicalElements"], 0, false),
            (&["ssd:Annotations"], 0, false),
        ]),
        ("ssd:Elements", "ssd:Component") => Seq(&[
            (&["ssd:Connectors"], 0, false),
            (&["ssd:ElementGeometry"], 0, false),
            (&["ssd:ParameterBindings"], 0, false),
            METADATA,
            SIGNATURE,
            (&["ssd:Annotations"], 0, false),
        ]),
        ("ssd:System", "ssd:Elements") => Seq(&[(
            &["ssd:Component", "ssd:SignalDictionaryReference", "ssd:System"],
            0,
            true,
        )]),
        ("ssd:System", "ssd:Connections") => Seq(&[(&["ssd:Connection"], 1, true)]),
        ("ssd:Connections", "ssd:Connection") => Seq(&[
            (TRANSFORMATIONS, 0, false),
            (&["ssd:ConnectionGeometry"], 0, false),
            (&["ssd:Annotations"], 0, false),
        ]),
        ("ssd:System" | "ssd:Component", "ssd:Connectors") => Seq(&[(&["ssd:Connector"], 1, true)]),
        ("ssd:Connectors", "ssd:Connector") => Seq(&[
            (TYPE_CHOICE, 0, false),
            (&["ssc:Dimension"], 0, true),
            (&["ssd:Clock"], 0, true),
            (&["ssd:ConnectorGeometry"], 0, false),
            (&["ssd:Annotations"], 0, false),
        ]),
        ("ssd:Connector", t) if TYPE_CHOICE.contains(&t) => Seq(&[]),
        ("ssd:Connector" | "ssv:Parameter", "ssc:Dimension") | ("ssd:Connector", "ssd:Clock") => Seq(&[]),
        ("ssd:System" | "ssd:Component", "ssd:ParameterBindings") => Seq(&[(&["ssd:ParameterBinding"], 1, true)]),
        ("ssd:ParameterBindings", "ssd:ParameterBinding") => Seq(&[
            (&["ssd:ParameterValues"], 0, false),
            (&["ssd:ParameterMapping"], 0, false),
            METADATA,
            SIGNATURE,
            (&["ssd:Annotations"], 0, false),
        ]),
        ("ssv:ParameterSet", "ssv:Parameters") => Seq(&[(&["ssv:Parameter"], 0, true)]),
        ("ssv:Parameters", "ssv:Parameter") => Seq(&[
            (SSV_CHOICE, 1, false),
            (&["ssc:Dimension"], 0, true),
            (&["ssv:Annotations"], 0, false),
        ]),
        ("ssv:Parameter", "ssv:String" | "ssv:Enumeration" | "ssv:Binary") => Seq(&[(&["ssv:Value"], 0, true)]),
        ("ssv:Parameter", t) if SSV_CHOICE.contains(&t) => Seq(&[]),
        ("ssv:String" | "ssv:Enumeration" | "ssv:Binary", "ssv:Value") => Seq(&[]),
        ("ssd:SystemStructureDescription", "ssd:Enumerations") | ("ssv:ParameterSet", "ssv:Enumerations") => {
            Seq(&[(&["ssc:Enumeration"], 1, true)])
        }
        ("ssd:Enumerations" | "ssv:Enumerations", "ssc:Enumeration") => {
            Seq(&[(&["ssc:Item"], 1, true), (&["ssc:Annotations"], 0, false)])
        }
        ("ssc:Enumeration", "ssc:Item") => Seq(&[]),
        ("ssd:SystemStructureDescription", "ssd:Units") | ("ssv:ParameterSet", "ssv:Units") => {
            Seq(&[(&["ssc:Unit"], 1, true)])
        }
        ("ssd:Units" | "ssv:Units", "ssc:Unit") => {
            Seq(&[(&["ssc:BaseUnit"], 1, false), (&["ssc:Annotations"], 0, false)])
        }
        ("ssc:Unit", "ssc:BaseUnit") => Seq(&[]),
        ("ssd:SystemStructureDescription", "ssd:DefaultExperiment") => Seq(&[(&["ssd:Annotations"], 0, false)]),
        (_, "ssd:Annotations" | "ssv:Annotations" | "ssc:Annotations") => Seq(&[(&["ssc:Annotation"], 1, true)]),
        ("ssd:Annotations" | "ssv:Annotations" | "ssc:Annotations", "ssc:Annotation") => Open,
        (_, "ssc:MetaData" | "ssc:Signature") => Open,
        ("ssd:ParameterBinding", "ssd:ParameterValues") => Open,
        ("ssd:ParameterBinding", "ssd:ParameterMapping") => Open,
        ("ssd:Connection", t) if TRANSFORMATIONS.contains(&t) => Open,
        ("ssd:Connection", "ssd:ConnectionGeometry")
        | ("ssd:Connector", "ssd:ConnectorGeometry")
        | (_, "ssd:ElementGeometry")
        | ("ssd:System", "ssd:SystemGeometry" | "ssd:GraphicalElements" | "ssd:SignalDictionaries")
        | ("ssd:Elements", "ssd:SignalDictionaryReference") => Open,
        _ => return None,
    })
}

/// The attributes the schema requires of an element.
fn required(el: &str) -> &'static [&'static str] {
    match el {
        "ssd:SystemStructureDescription" | "ssv:ParameterSet" => &["version", "name"],
        "ssd:System" | "ssd:Component" | "ssv:Parameter" | "ssc:Enumeration" | "ssc:Unit" | "ssd:Clock" => &["name"],
        "ssd:Connector" => &["name", "kind"],
        "ssd:Connection" => &["startConnector", "endConnector"],
        "ssc:Item" => &["name", "value"],
        "ssc:Annotation" => &["type"],
        "ssv:Value" => &["value"],
        "ssv:Real" | "ssv:Float64" | "ssv:Float32" | "ssv:Integer" | "ssv:Int8" | "ssv:UInt8" | "ssv:Int16"
        | "ssv:UInt16" | "ssv:Int32" | "ssv:UInt32" | "ssv:Int64" | "ssv:UInt64" | "ssv:Boolean" => &["value"],
        _ => &[],
    }
}

const KINDS: [&str; 9] = [
    "input",
    "output",
    "parameter",
    "calculatedParameter",
    "structuralParameter",
    "constant",
    "local",
    "inout",
    "unspecified",
];

/// Whether `text` is a list (one word if `!list`) of the XML Schema type `ty`.
fn lexical(ty: &str, text: &str, list: bool) -> bool {
    fn all<T: std::str::FromStr>(words: &[&str]) -> bool {
        words.iter().all(|w| w.parse::<T>().is_ok())
    }
    let words: Vec<&str> = text.split_whitespace().collect();
    if words.is_empty() || !list && words.len() != 1 {
        return false;
    }
    match ty {
        // xs:double and xs:float: Rust's parse takes "inf"/"NaN" spellings XML Schema spells
        // INF / NaN; both are numbers.
        "double" => words.iter().all(|w| {
            matches!(*w, "INF" | "-INF" | "+INF" | "NaN")
                || w.parse::<f64>().is_ok_and(|_| !w.contains(['i', 'n', 'N', 'I']))
        }),
        "float" => words.iter().all(|w| {
            matches!(*w, "INF" | "-INF" | "+INF" | "NaN")
                || w.parse::<f32>().is_ok_and(|_| !w.contains(['i', 'n', 'N', 'I']))
        }),
        "byte" => all::<i8>(&words),
        "unsignedByte" => all::<u8>(&words),
        "short" => all::<i16>(&words),
        "unsignedShort" => all::<u16>(&words),
        "int" => all::<i32>(&words),
        "unsignedInt" => all::<u32>(&words),
        "long" => all::<i64>(&words),
        "unsignedLong" => all::<u64>(&words),
        "boolean" => words.iter().all(|w| matches!(*w, "true" | "false" | "1" | "0")),
        "hexBinary" => words
            .iter()
            .all(|w| w.len() % 2 == 0 && w.bytes().all(|b| b.is_ascii_hexdigit())),
        _ => true,
    }
}

/// The XML Schema type of an SSV value attribute, and whether it is a list.
fn ssv_value_type(el: &str) -> Option<(&'static str, bool)> {
    Some(match el {
        "ssv:Real" | "ssv:Float64" => ("double", true),
        "ssv:Float32" => ("float", true),
        "ssv:Integer" | "ssv:Int32" => ("int", true),
        "ssv:Int8" => ("byte", true),
        "ssv:UInt8" => ("unsignedByte", true),
        "ssv:Int16" => ("short", true),
        "ssv:UInt16" => ("unsignedShort", true),
        "ssv:UInt32" => ("unsignedInt", true),
        "ssv:Int64" => ("long", true),
        "ssv:UInt64" => ("unsignedLong", true),
        "ssv:Boolean" => ("boolean", true),
        "ssv:Binary" => ("hexBinary", false),
        _ => return None,
    })
}

/// The canonical prefix of an element's namespace (`ssd`, `ssc`, `ssv`, `ssm`, `ssb`), or None
/// if it is of another namespace (or none).
fn prefix(ns: &ResolveResult) -> Option<&'static str> {
    let ResolveResult::Bound(ns) = ns else {
        return None;
    };
    Some(match ns.as_ref() {
        n if n == SSD.as_bytes() => "ssd",
        n if n == SSC.as_bytes() => "ssc",
        n if n == SSV.as_bytes() => "ssv",
        n if n == SSM.as_bytes() => "ssm",
        n if n == SSB.as_bytes() => "ssb",
        _ => return None,
    })
}

/// An open element: its name, its content, the slot of its sequence reached, how many of that
/// slot's elements were seen.
struct Open {
    name: String,
    content: Content,
    slot: usize,
    seen: usize,
    line: usize,
}

fn line_of(xml: &str, pos: usize) -> usize {
    xml.as_bytes()[..pos.min(xml.len())]
        .iter()
        .filter(|b| **b == b'\n')
        .count()
        + 1
}

/// Checks `xml` (the file `file`) against the SSP 2.0 schemas' structure; `root` is the element
/// it must begin with (`ssd:SystemStructureDescription` or `ssv:ParameterSet`).
pub fn validate(file: &str, xml: &str, root: &str) -> Result<(), Error> {
    let mut reader = NsReader::from_str(xml);
    let mut stack: Vec<Open> = Vec::new();
    let mut rooted = false;
    let schema = if root.starts_with("ssv") {
        "SystemStructureParameterValues.xsd"
    } else {
        "SystemStructureDescription.xsd"
    };
    let err = |line: usize, what: String| Error::io(format!("{file}:{line}: {what} (the SSP 2.0 schema, {schema})"));
    let xml_err = |reader: &NsReader<&[u8]>, e: quick_xml::Error| {
        Error::io(format!(
            "{file}:{}: XML error: {e}",
            line_of(xml, reader.error_position() as usize)
        ))
    };
    loop {
        let before = reader.buffer_position() as usize;
        let step = reader
            .read_resolved_event()
            .map(|(ns, event)| (prefix(&ns), event.into_owned()));
        let (ns, event) = match step {
            Ok(x) => x,
            Err(e) => return Err(xml_err(&reader, e)),
        };
        // The line of the tag: its '<', after whatever text the event began with.
        let at = before + xml[before.min(xml.len())..].find('<').unwrap_or(0);
        let line = line_of(xml, at);
        let (e, empty) = match event {
            Event::Eof => break,
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(_) => {
                let open = stack.pop().expect("the reader checks the nesting");
                check_end(&open).map_err(|w| err(open.line, w))?;
                continue;
            }
            _ => continue,
        };
        let local = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
        let parent = stack.last().map(|o| o.name.as_str()).unwrap_or("");
        let name = ns.map(|p| format!("{p}:{local}"));
        // ssd:ParameterValues holds any content: an ssv:ParameterSet is checked, the rest not.
        let skip = parent == "ssd:ParameterValues" && name.as_deref() != Some("ssv:ParameterSet");
        let content = match &name {
            _ if skip => Content::Open,
            None => {
                return Err(err(
                    line,
                    if parent.is_empty() {
                        format!("<{local}> is not of SSP's namespaces: the root must be {root}")
                    } else {
                        format!("<{local}> is not of SSP's namespaces and may not stand in {parent}")
                    },
                ));
            }
            Some(name) => {
                rooted = true;
                if stack.is_empty() && name != root {
                    return Err(err(line, format!("the root is {name}, not {root}")));
                }
                let Some(content) = content(parent, name) else {
                    return Err(err(line, format!("{name} may not stand in {parent}")));
                };
                if let Some(p) = stack.last_mut() {
                    place(p, name).map_err(|w| err(line, w))?;
                }
                attributes(&e, name).map_err(|w| err(line, w))?;
                if stack.is_empty() && root == "ssd:SystemStructureDescription" {
                    // Read as SSP 2.0 because it says so.
                    let v = attr(&e, "version").unwrap_or_default();
                    if v.trim() != "2.0" {
                        return Err(err(line, format!("{name} version=\"{v}\": expected \"2.0\"")));
                    }
                }
                content
            }
        };
        let opened = Open {
            name: name.unwrap_or(local),
            content,
            slot: 0,
            seen: 0,
            line,
        };
        if empty {
            check_end(&opened).map_err(|w| err(line, w))?;
        } else if matches!(opened.content, Content::Open) && opened.name != "ssd:ParameterValues" {
            // Content the schema leaves open (or the runner does not look into): skipped.
            let mut depth = 1usize;
            while depth > 0 {
                match reader.read_event().map_err(|e| xml_err(&reader, e))? {
                    Event::Start(_) => depth += 1,
                    Event::End(_) => depth -= 1,
                    Event::Eof => return Err(Error::io(format!("{file}: the file ends inside {}", opened.name))),
                    _ => {}
                }
            }
        } else {
            stack.push(opened);
        }
    }
    if let Some(open) = stack.last() {
        return Err(err(open.line, format!("{} is not closed", open.name)));
    }
    if !rooted {
        return Err(Error::io(format!("{file}: no {root}")));
    }
    Ok(())
}

/// `name` placed in its parent's sequence, after what came before.
fn place(parent: &mut Open, name: &str) -> Result<(), String> {
    let Content::Seq(slots) = parent.content else {
        // ssd:ParameterValues: any content; an ssv:ParameterSet is checked.
        return Ok(());
    };
    let Some(k) = slots.iter().position(|(names, _, _)| names.contains(&name)) else {
        return Err(format!("{name} may not stand in {}", parent.name));
    };
    if k < parent.slot {
        return Err(format!(
            "{name} stands after {} in {}: the schema's sequence puts it before",
            slots[parent.slot].0.join(" or "),
            parent.name
        ));
    }
    if k > parent.slot {
        check_slots(parent, k)?;
        parent.slot = k;
        parent.seen = 0;
    }
    parent.seen += 1;
    if parent.seen > 1 && !slots[k].2 {
        return Err(format!(
            "a second {} in {}: at most one",
            slots[k].0.join(" or "),
            parent.name
        ));
    }
    Ok(())
}

/// Every slot of `open` before `upto` has its minimum.
fn check_slots(open: &Open, upto: usize) -> Result<(), String> {
    let Content::Seq(slots) = open.content else {
        return Ok(());
    };
    for (k, (names, min, _)) in slots.iter().enumerate().take(upto).skip(open.slot) {
        let seen = if k == open.slot { open.seen } else { 0 };
        if seen < *min {
            return Err(format!("{} lacks its {}", open.name, names.join(" or ")));
        }
    }
    Ok(())
}

fn check_end(open: &Open) -> Result<(), String> {
    match open.content {
        Content::Seq(slots) => check_slots(open, slots.len()),
        Content::Open => Ok(()),
    }
}

fn attr(e: &BytesStart, name: &str) -> Option<String> {
    e.attributes()
        .flatten()
        .find(|a| a.key.as_ref() == name.as_bytes())
        .and_then(|a| a.unescape_value().ok())
        .map(|v| v.into_owned())
}

/// The attributes the schema requires, and the values of those it types that the runner reads.
fn attributes(e: &BytesStart, name: &str) -> Result<(), String> {
    for a in required(name) {
        if attr(e, a).is_none() {
            return Err(format!("{name} lacks the attribute {a}, which the schema requires"));
        }
    }
    let bad = |a: &str, v: &str, what: &str| Err(format!("{name} {a}=\"{v}\" is not {what}"));
    let check = |a: &str, ty: &str, list: bool| -> Result<(), String> {
        match attr(e, a) {
            Some(v) if !lexical(ty, &v, list) => {
                bad(a, &v, &format!("{}an xs:{ty}", if list { "a list of " } else { "" }))
            }
            _ => Ok(()),
        }
    };
    match name {
        "ssd:SystemStructureDescription" | "ssv:ParameterSet" => {
            if let Some(v) = attr(e, "version")
                && !matches!(v.trim(), "1.0" | "2.0")
            {
                return bad("version", &v, "1.0 or 2.0");
            }
        }
        "ssd:Connector" => {
            if let Some(v) = attr(e, "kind")
                && !KINDS.contains(&v.as_str())
            {
                return bad("kind", &v, &format!("one of {}", KINDS.join(", ")));
            }
        }
        "ssd:Component" => {
            if let Some(v) = attr(e, "implementation")
                && !matches!(
                    v.as_str(),
                    "any" | "ModelExchange" | "CoSimulation" | "ScheduledExecution"
                )
            {
                return bad(
                    "implementation",
                    &v,
                    "any, ModelExchange, CoSimulation or ScheduledExecution",
                );
            }
        }
        "ssd:Connection" => {
            check("startIndices", "unsignedLong", true)?;
            check("endIndices", "unsignedLong", true)?;
            check("suppressUnitConversion", "boolean", false)?;
        }
        "ssd:DefaultExperiment" => {
            check("startTime", "double", false)?;
            check("stopTime", "double", false)?;
        }
        "ssc:Dimension" => check("size", "unsignedLong", false)?,
        "ssc:Item" => check("value", "int", false)?,
        "ssv:String" | "ssv:Enumeration" | "ssv:Value" => {}
        _ => {
            if let Some((ty, list)) = ssv_value_type(name) {
                check("value", ty, list)?;
            }
        }
    }
    Ok(())
}
