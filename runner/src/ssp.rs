//! Reading an SSP 1.0 or 2.0 archive: `SystemStructure.ssd` and the files it names. An SSD of
//! `version="2.0"` is checked against the SSP 2.0 schemas' structure first and read with SSP
//! 2.0's types (`ssp/v2.rs`); every other as SSP 1.0.
//!
//! What is read: the root `ssd:System` with its `ssd:Elements/ssd:Component`s (each an FMU,
//! `source="resources/X.fmu"` inside the archive), `ssd:Connections/ssd:Connection`
//! (`startElement.startConnector -> endElement.endConnector`), each component's
//! `ssd:ParameterBindings/ssd:ParameterBinding` with inline `ssd:ParameterValues/ssv:ParameterSet`
//! or `source="X.ssv"` (a file of the archive), the connectors' units and the
//! `ssd:DefaultExperiment`.
//!
//! The system's own connectors (`ssd:System/ssd:Connectors`, kind input or output) and their
//! connections (no `startElement` / `endElement`) are read into [`Ssd::connectors`]: a container
//! FMU exposes them (`cargo fmu container`); the runner runs the system without them (a
//! component input a system input feeds keeps its start value, as an unconnected input).
//!
//! What is refused, with the component and connector it concerns: a system connector of another
//! kind that a connection uses, a connection from the system to itself, a system output fed by
//! other than one connection, nested systems, connection
//! transformations (`ssc:LinearTransformation`, mapping transformations), connections between
//! connectors of different units (a unit conversion), parameter mappings and prefixes,
//! parameter bindings of the system itself, signal dictionaries, components that are not FMUs,
//! and sources outside the archive. A component with `implementation="ModelExchange"` is
//! integrated by the runner ([`crate::me`]).

use crate::{Error, ErrorKind, Value};
use quick_xml::Reader;
use quick_xml::events::{BytesStart, Event};
use std::io::{Read, Seek};

mod v2;

/// One component of the system: an FMU instance.
#[derive(Debug, Clone)]
pub struct Component {
    pub name: String,
    /// `source`, e.g. "resources/Pendulum.fmu".
    pub source: String,
    /// Parameter and start values of its parameter bindings, in the order written.
    pub parameters: Vec<(String, Value)>,
    /// Connectors: (name, kind, unit).
    pub connectors: Vec<(String, String, Option<String>)>,
    /// `implementation="ModelExchange"`: the runner integrates it ([`crate::me`]).
    pub model_exchange: bool,
    /// `implementation="ScheduledExecution"` (SSP 2.0): the runner activates its partitions
    /// ([`crate::sim::Simulation::use_scheduled_execution`]).
    pub scheduled: bool,
    /// `implementation="CoSimulation"` written out: its FMU must offer co-simulation (SSP 1.0 and
    /// 2.0, ssd:Component/@implementation: an error where the FMU does not), not the interface
    /// the runner would pick for an FMU of model exchange or Scheduled Execution only.
    pub co_simulation: bool,
    /// SSP 2.0: the connectors that declare a type or dimensions: (connector, its type element,
    /// e.g. "Float64", or "" if none, each `ssc:Dimension`'s `size`, None if it has none),
    /// checked against the FMU's variables when the system is built.
    pub declared: Vec<(String, String, Vec<Option<u64>>)>,
}

/// `start.0.start.1 -> end.0.end.1`: (component, connector).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Connection {
    pub start: (String, String),
    pub end: (String, String),
}

/// One of the system's own connectors (`ssd:System/ssd:Connectors/ssd:Connector`).
#[derive(Debug, Clone, PartialEq)]
pub struct SystemConnector {
    pub name: String,
    /// "input" or "output".
    pub kind: String,
    pub unit: Option<String>,
    /// An input: the component inputs it feeds (component, connector), in the connections'
    /// order; an output: the one component output that feeds it.
    pub links: Vec<(String, String)>,
}

/// The system of an SSD.
#[derive(Debug, Clone)]
pub struct Ssd {
    pub name: String,
    pub components: Vec<Component>,
    /// The connections between components.
    pub connections: Vec<Connection>,
    /// The connections between Clock connectors of components (SSP 2.0 `ssc:Clock`): the
    /// receiver's clock ticks when the sender's does (`sim/clocks.rs`).
    pub clock_connections: Vec<Connection>,
    /// The system's own connectors, with the connections to and from them.
    pub connectors: Vec<SystemConnector>,
    /// `ssd:DefaultExperiment` startTime, stopTime, s.
    pub start_time: Option<f64>,
    pub stop_time: Option<f64>,
}

fn local(e: &BytesStart) -> String {
    String::from_utf8_lossy(e.local_name().as_ref()).into_owned()
}

fn attr(e: &BytesStart, name: &str) -> Option<String> {
    e.attributes()
        .flatten()
        .find(|a| a.key.local_name().as_ref() == name.as_bytes())
        .and_then(|a| a.unescape_value().ok())
        .map(|v| v.into_owned())
}

fn xml_error(file: &str, reader: &Reader<&[u8]>, e: impl std::fmt::Display) -> Error {
    Error::io(format!("{file}: XML error at byte {}: {e}", reader.error_position()))
}

/// The typed value of `<ssv:Real value=..>` etc.
fn typed_value(file: &str, param: &str, kind: &str, value: Option<String>) -> Result<Value, Error> {
    let text = value.ok_or_else(|| Error::io(format!("{file}: parameter '{param}': ssv:{kind} without a value")))?;
    let bad = |what: &str| Error::io(format!("{file}: parameter '{param}': '{text}' is not {what}"));
    Ok(match kind {
        "Real" => Value::Real(text.trim().parse().map_err(|_| bad("a Real"))?),
        "Integer" => Value::Integer(text.trim().parse().map_err(|_| bad("an Integer"))?),
        "Boolean" => Value::Boolean(match text.trim() {
            "true" | "1" => true,
            "false" | "0" => false,
            _ => return Err(bad("a Boolean (true or false)")),
        }),
        "String" => Value::String(text.clone()),
        "Enumeration" => Value::Enumeration(text.clone()),
        _ => return typed_value2(file, param, kind, text),
    })
}

/// An SSV 2.0 value of a type SSP 1.0 lacks (`Float64`, `Int8`, ..., `Binary`), or a list (an
/// array): a scalar as the SSP 1.0 value of its kind, the rest as [`Value::List`].
fn typed_value2(file: &str, param: &str, kind: &str, text: String) -> Result<Value, Error> {
    let words = text.split_whitespace().count();
    let bad = || Error::io(format!("{file}: parameter '{param}': '{text}' is not an ssv:{kind}"));
    if words != 1 || matches!(kind, "Binary" | "UInt64") {
        if kind == "UInt64"
            && words == 1
            && let Ok(i) = text.trim().parse::<i64>()
        {
            return Ok(Value::Integer(i));
        }
        return Ok(Value::List {
            ty: kind.to_owned(),
            text,
        });
    }
    Ok(match kind {
        "Float64" | "Float32" => Value::Real(text.trim().parse().map_err(|_| bad())?),
        "Int8" | "UInt8" | "Int16" | "UInt16" | "Int32" | "UInt32" | "Int64" => {
            Value::Integer(text.trim().parse().map_err(|_| bad())?)
        }
        _ => unreachable!("called for the SSV 2.0 types"),
    })
}

const SSV_TYPES: [&str; 5] = ["Real", "Integer", "Boolean", "String", "Enumeration"];

/// The SSV 2.0 value elements whose array values are `ssv:Value` elements.
const ITEM_TYPES: [&str; 3] = ["String", "Enumeration", "Binary"];

/// An SSV 2.0 array of String, Enumeration or Binary values being read: its parameter, its
/// element and the `ssv:Value`s so far.
#[derive(Default)]
struct Items {
    open: Option<(String, String, Vec<String>)>,
}

impl Items {
    /// `<ssv:String>` (Enumeration, Binary) of `param` without a `value`: its `ssv:Value`s follow
    /// (`empty`: none, an array of no element).
    fn start(&mut self, param: &str, ty: &str, empty: bool) -> Option<Value> {
        if empty {
            return Some(Value::Items {
                ty: ty.to_owned(),
                items: Vec::new(),
            });
        }
        self.open = Some((param.to_owned(), ty.to_owned(), Vec::new()));
        None
    }

    /// An `ssv:Value` of the open array.
    fn value(&mut self, file: &str, param: &str, value: Option<String>) -> Result<(), Error> {
        let Some((_, ty, items)) = &mut self.open else {
            return Err(Error::io(format!(
                "{file}: parameter '{param}': an ssv:Value outside an ssv:String, ssv:Enumeration or ssv:Binary"
            )));
        };
        let v = value.ok_or_else(|| Error::io(format!("{file}: parameter '{param}': ssv:Value without a value")))?;
        if ty == "Binary" && !(v.trim().len() % 2 == 0 && v.trim().bytes().all(|b| b.is_ascii_hexdigit())) {
            return Err(Error::io(format!(
                "{file}: parameter '{param}': ssv:Value '{v}' of an ssv:Binary is not hexadecimal digits (xs:hexBinary)"
            )));
        }
        items.push(v);
        Ok(())
    }

    /// The end of element `tag`: the array, (parameter, value), if it closes one.
    fn end(&mut self, tag: &str) -> Option<(String, Value)> {
        if self.open.as_ref().is_some_and(|(_, ty, _)| ty == tag) {
            let (param, ty, items) = self.open.take()?;
            return Some((param, Value::Items { ty, items }));
        }
        None
    }
}

/// The root's `version`, if the document has a root.
fn root_version(xml: &str) -> Option<String> {
    let mut reader = Reader::from_str(xml);
    loop {
        match reader.read_event().ok()? {
            Event::Start(e) | Event::Empty(e) => return attr(&e, "version"),
            Event::Eof => return None,
            _ => {}
        }
    }
}

/// The parameters of an SSV document (`ssv:ParameterSet`), in order; `v2`: of an SSP 2.0
/// system (checked against the SSP 2.0 schema first, its values of the SSP 2.0 types).
pub fn parse_ssv(file: &str, xml: &str, v2: bool) -> Result<Vec<(String, Value)>, Error> {
    if v2 {
        v2::validate(file, xml, "ssv:ParameterSet")?;
    }
    let types: &[&str] = if v2 { &v2::SSV_TYPES } else { &SSV_TYPES };
    let mut reader = Reader::from_str(xml);
    let mut out = Vec::new();
    let mut param: Option<String> = None;
    let mut items = Items::default();
    loop {
        let event = reader.read_event().map_err(|e| xml_error(file, &reader, e))?;
        let empty = matches!(event, Event::Empty(_));
        match event {
            Event::Eof => break,
            Event::Start(e) | Event::Empty(e) => {
                let tag = local(&e);
                if tag == "Parameter" {
                    param = Some(
                        attr(&e, "name").ok_or_else(|| Error::io(format!("{file}: ssv:Parameter without a name")))?,
                    );
                } else if let (Some(p), true, None) =
                    (&param, v2 && ITEM_TYPES.contains(&tag.as_str()), attr(&e, "value"))
                {
                    // An array of ssv:Value elements (SSP 2.0).
                    if let Some(v) = items.start(p, &tag, empty) {
                        out.push((p.clone(), v));
                    }
                } else if let (Some(p), true) = (&param, types.contains(&tag.as_str())) {
                    out.push((p.clone(), typed_value(file, p, &tag, attr(&e, "value"))?));
                } else if v2 && tag == "Value" && param.is_some() {
                    items.value(file, param.as_deref().unwrap_or(""), attr(&e, "value"))?;
                } else if !v2 && tag == "Binary" || tag == "Unit" && param.is_some() {
                    return Err(Error::unsupported(
                        None,
                        param.as_deref(),
                        format!(
                            "{file}: parameter '{}': ssv:{tag} values are not supported",
                            param.as_deref().unwrap_or("")
                        ),
                    ));
                }
            }
            Event::End(e) => {
                let tag = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
                if tag == "Parameter" {
                    param = None;
                } else if let Some(array) = items.end(&tag) {
                    out.push(array);
                }
            }
            _ => {}
        }
    }
    Ok(out)
}

/// Parses `SystemStructure.ssd`; `read` returns another file of the archive (a `.ssv`).
// Long (~330 lines) because it is one pass of quick-xml events over the document: each arm of
// its match is one SSD element, checked where it stands (its parents are the state of the pass),
// and the refusals name the element and the attribute; split into functions, every arm would
// take the whole state.
pub fn parse_ssd(xml: &str, read: &mut dyn FnMut(&str) -> Result<String, Error>) -> Result<Ssd, Error> {
    const FILE: &str = "SystemStructure.ssd";
    // SSP 2.0: checked against its schemas' structure first, read with its types.
    let v2 = root_version(xml).is_some_and(|v| v.trim() == "2.0");
    if v2 {
        v2::validate(FILE, xml, "ssd:SystemStructureDescription")?;
    }
    let ssv_types: &[&str] = if v2 { &v2::SSV_TYPES } else { &SSV_TYPES };
    let connector_types: &[&str] = if v2 {
        &v2::CONNECTOR_TYPES
    } else {
        &["Real", "Integer", "Boolean", "String", "Enumeration"]
    };
    let mut reader = Reader::from_str(xml);
    let mut ssd = Ssd {
        name: String::new(),
        components: Vec::new(),
        connections: Vec::new(),
        clock_connections: Vec::new(),
        connectors: Vec::new(),
        start_time: None,
        stop_time: None,
    };
    // Connections that name a system connector: (system connector, component end, text),
    // resolved once every connector is read.
    let mut boundary: Vec<(String, bool, (String, String), String)> = Vec::new();
    let mut system_connector: Option<usize> = None;
    // The end (component, connector) of the connection being read.
    let mut connection_end: (Option<String>, String) = (None, String::new());
    // The open elements' local names.
    let mut stack: Vec<String> = Vec::new();
    let mut systems = 0usize;
    let mut param: Option<String> = None;
    let mut connector: Option<usize> = None;
    let mut connection: Option<String> = None;
    // The components' Clock connectors (component, connector).
    let mut clock_connectors: Vec<(String, String)> = Vec::new();
    // An array of ssv:Value elements being read.
    let mut items = Items::default();
    loop {
        let event = reader.read_event().map_err(|e| xml_error(FILE, &reader, e))?;
        let (e, empty) = match event {
            Event::Eof => break,
            Event::End(e) => {
                let tag = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
                if let Some(array) = items.end(&tag) {
                    ssd.components.last_mut().expect("inside").parameters.push(array);
                }
                match tag.as_str() {
                    "Parameter" => param = None,
                    "Connector" => {
                        connector = None;
                        system_connector = None;
                    }
                    "Connection" => connection = None,
                    _ => {}
                }
                stack.pop();
                continue;
            }
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            _ => continue,
        };
        let tag = local(&e);
        let parent = stack.last().map(String::as_str).unwrap_or("");
        let in_component = stack.iter().any(|t| t == "Component");
        let component = ssd.components.last().map(|c| c.name.clone());
        match tag.as_str() {
            "System" => {
                systems += 1;
                if systems > 1 {
                    return Err(Error::unsupported(
                        attr(&e, "name").as_deref(),
                        None,
                        format!(
                            "{FILE}: system '{}' contains the subsystem '{}': nested systems are not supported",
                            ssd.name,
                            attr(&e, "name").unwrap_or_default()
                        ),
                    ));
                }
                ssd.name = attr(&e, "name").unwrap_or_default();
            }
            "Component" => {
                let name =
                    attr(&e, "name").ok_or_else(|| Error::io(format!("{FILE}: a ssd:Component without a name")))?;
                let source =
                    attr(&e, "source").ok_or_else(|| Error::io(format!("{FILE}: component '{name}' has no source")))?;
                if let Some(t) = attr(&e, "type")
                    && t != "application/x-fmu-sharedlibrary"
                {
                    return Err(Error::unsupported(
                        Some(&name),
                        None,
                        format!(
                            "component '{name}': type '{t}' is not supported (only FMUs, application/x-fmu-sharedlibrary)"
                        ),
                    ));
                }
                let implementation = attr(&e, "implementation");
                let co_simulation = implementation.as_deref() == Some("CoSimulation");
                let (model_exchange, scheduled) = match implementation.as_deref() {
                    None | Some("any") | Some("CoSimulation") => (false, false),
                    Some("ModelExchange") => (true, false),
                    // SSP 2.0 (SystemStructureDescription.xsd, ssd:Component/@implementation);
                    // SSP 1.0 does not define it.
                    Some("ScheduledExecution") if v2 => (false, true),
                    Some(other) => {
                        return Err(Error::unsupported(
                            Some(&name),
                            None,
                            format!(
                                "component '{name}': implementation=\"{other}\" is not supported (CoSimulation, ModelExchange or any; ScheduledExecution in an SSP 2.0 file, version=\"2.0\")"
                            ),
                        ));
                    }
                };
                ssd.components.push(Component {
                    name,
                    source,
                    parameters: Vec::new(),
                    connectors: Vec::new(),
                    model_exchange,
                    scheduled,
                    co_simulation,
                    declared: Vec::new(),
                });
            }
            "SignalDictionary" | "SignalDictionaryReference" => {
                return Err(Error::unsupported(
                    component.as_deref(),
                    None,
                    format!(
                        "{FILE}: ssd:{tag} is not supported{}",
                        component
                            .as_deref()
                            .map(|c| format!(" (component '{c}')"))
                            .unwrap_or_default()
                    ),
                ));
            }
            "Connector" if parent == "Connectors" => {
                let name = attr(&e, "name").unwrap_or_default();
                let kind = attr(&e, "kind").unwrap_or_default();
                if in_component {
                    let c = ssd.components.last_mut().expect("inside a component");
                    c.connectors.push((name, kind, None));
                    connector = Some(c.connectors.len() - 1);
                } else {
                    ssd.connectors.push(SystemConnector {
                        name,
                        kind,
                        unit: None,
                        links: Vec::new(),
                    });
                    system_connector = Some(ssd.connectors.len() - 1);
                }
            }
            // ssd:Clock (a connector's clock, by name): the FMU's description says which
            // variables are clocked and the runner runs or refuses them by it.
            "Clock" if v2 && attr(&e, "name").is_some() => {}
            // ssc:Clock, a Clock connector: a connection of clocks is refused once all are read.
            "Clock" if v2 && param.is_none() => {
                if let Some(k) = connector {
                    let c = ssd.components.last().expect("inside a component");
                    clock_connectors.push((c.name.clone(), c.connectors[k].0.clone()));
                } else if let Some(k) = system_connector {
                    let name = ssd.connectors[k].name.clone();
                    return Err(Error::unsupported(
                        None,
                        Some(&name),
                        format!(
                            "{FILE}: system '{}': its connector '{name}' is a Clock (ssc:Clock): clock connectors of the system are not supported",
                            ssd.name
                        ),
                    ));
                }
            }
            "Dimension" if v2 && connector.is_some() && param.is_none() => {
                let c = ssd.components.last_mut().expect("inside a component");
                let name = &c.connectors[connector.expect("checked")].0;
                let size = attr(&e, "size").and_then(|v| v.trim().parse().ok());
                match c.declared.last_mut() {
                    Some((n, _, dims)) if n == name => dims.push(size),
                    _ => c.declared.push((name.clone(), String::new(), vec![size])),
                }
            }
            t if connector.is_some() && param.is_none() && connector_types.contains(&t) => {
                if v2 {
                    let c = ssd.components.last_mut().expect("inside a component");
                    let name = c.connectors[connector.expect("checked")].0.clone();
                    c.declared.push((name, t.to_owned(), Vec::new()));
                }
                if let Some(unit) = attr(&e, "unit") {
                    let c = ssd.components.last_mut().expect("inside a component");
                    c.connectors[connector.expect("checked")].2 = Some(unit);
                }
            }
            t if system_connector.is_some() && connector_types.contains(&t) => {
                if let Some(unit) = attr(&e, "unit") {
                    ssd.connectors[system_connector.expect("checked")].unit = Some(unit);
                }
            }
            "ParameterBinding" => {
                let Some(c) = component.as_deref().filter(|_| in_component) else {
                    return Err(Error::unsupported(
                        None,
                        None,
                        format!(
                            "{FILE}: system '{}' has parameter bindings of its own (of the system's connectors): not supported, only those of components",
                            ssd.name
                        ),
                    ));
                };
                if attr(&e, "prefix").is_some_and(|p| !p.is_empty()) {
                    return Err(Error::unsupported(
                        Some(c),
                        None,
                        format!("component '{c}': a ParameterBinding with a prefix is not supported"),
                    ));
                }
                if let Some(src) = attr(&e, "source") {
                    if src.contains("://") || src.starts_with('/') {
                        return Err(Error::unsupported(
                            Some(c),
                            None,
                            format!(
                                "component '{c}': parameter binding source '{src}' lies outside the archive: not supported"
                            ),
                        ));
                    }
                    let text = read(&src)?;
                    let values = parse_ssv(&src, &text, v2)?;
                    ssd.components.last_mut().expect("inside").parameters.extend(values);
                }
            }
            "ParameterMapping" => {
                return Err(Error::unsupported(
                    component.as_deref(),
                    None,
                    format!(
                        "component '{}': ssd:ParameterMapping is not supported",
                        component.as_deref().unwrap_or("")
                    ),
                ));
            }
            "Parameter" if in_component && stack.iter().any(|t| t == "ParameterBinding") => {
                param =
                    Some(attr(&e, "name").ok_or_else(|| Error::io(format!("{FILE}: ssv:Parameter without a name")))?);
            }
            "Value" if v2 && param.is_some() => {
                items.value(FILE, param.as_deref().unwrap_or(""), attr(&e, "value"))?;
            }
            t if v2 && param.is_some() && ITEM_TYPES.contains(&t) && attr(&e, "value").is_none() => {
                // An array of ssv:Value elements (SSP 2.0).
                let p = param.clone().expect("checked");
                if let Some(v) = items.start(&p, t, empty) {
                    ssd.components.last_mut().expect("inside").parameters.push((p, v));
                }
            }
            t if param.is_some() && ssv_types.contains(&t) => {
                let p = param.clone().expect("checked");
                let v = typed_value(FILE, &p, t, attr(&e, "value"))?;
                ssd.components.last_mut().expect("inside").parameters.push((p, v));
            }
            "Connection" => {
                let start = (attr(&e, "startElement"), attr(&e, "startConnector").unwrap_or_default());
                let end = (attr(&e, "endElement"), attr(&e, "endConnector").unwrap_or_default());
                let text = format!(
                    "{}.{} -> {}.{}",
                    start.0.as_deref().unwrap_or("<system>"),
                    start.1,
                    end.0.as_deref().unwrap_or("<system>"),
                    end.1
                );
                for a in ["startIndices", "endIndices"] {
                    if let Some(i) = attr(&e, a) {
                        return Err(Error::unsupported(
                            end.0.as_deref(),
                            Some(&end.1),
                            format!(
                                "connection {text}: {a}=\"{i}\" (a connection of some elements of an array connector) is not supported: an array connects whole"
                            ),
                        ));
                    }
                }
                let (Some(se), Some(ee)) = (start.0.clone(), end.0.clone()) else {
                    match (start.0.clone(), end.0.clone()) {
                        (None, Some(ee)) => boundary.push((start.1.clone(), true, (ee, end.1.clone()), text.clone())),
                        (Some(se), None) => boundary.push((end.1.clone(), false, (se, start.1.clone()), text.clone())),
                        _ => {
                            return Err(Error::unsupported(
                                None,
                                Some(&start.1),
                                format!(
                                    "connection {text}: from the system's connector '{}' to its connector '{}': a system that passes a value through itself is not supported",
                                    start.1, end.1
                                ),
                            ));
                        }
                    }
                    connection_end = (end.0.clone(), end.1.clone());
                    connection = Some(text);
                    if !empty {
                        stack.push(tag);
                    }
                    continue;
                };
                connection_end = (Some(ee.clone()), end.1.clone());
                ssd.connections.push(Connection {
                    start: (se, start.1),
                    end: (ee, end.1),
                });
                connection = Some(text);
            }
            "LinearTransformation"
            | "BooleanMappingTransformation"
            | "IntegerMappingTransformation"
            | "EnumerationMappingTransformation"
                if connection.is_some() =>
            {
                return Err(Error::unsupported(
                    connection_end.0.as_deref(),
                    Some(&connection_end.1),
                    format!(
                        "connection {}: ssc:{tag} is not supported",
                        connection.as_deref().unwrap_or("")
                    ),
                ));
            }
            "DefaultExperiment" if systems <= 1 => {
                ssd.start_time = attr(&e, "startTime").and_then(|v| v.trim().parse().ok());
                ssd.stop_time = attr(&e, "stopTime").and_then(|v| v.trim().parse().ok());
            }
            _ => {}
        }
        if !empty {
            stack.push(tag);
        }
    }
    if systems == 0 {
        return Err(Error::io(format!("{FILE}: no ssd:System")));
    }
    // The connections of the system's own connectors.
    for (name, from_system, end, text) in boundary {
        let Some(sc) = ssd.connectors.iter_mut().find(|c| c.name == name) else {
            return Err(Error::io(format!(
                "{FILE}: connection {text}: the system '{}' has no connector '{name}'",
                ssd.name
            )));
        };
        let wanted = if from_system { "input" } else { "output" };
        if sc.kind != wanted {
            return Err(Error::unsupported(
                None,
                Some(&name),
                format!(
                    "connection {text}: the system's connector '{name}' is of kind '{}': only system inputs feed components and only system outputs are fed by them (kinds parameter, calculatedParameter and inout are not supported)",
                    sc.kind
                ),
            ));
        }
        if !from_system && !sc.links.is_empty() {
            return Err(Error::unsupported(
                None,
                Some(&name),
                format!("connection {text}: the system's output '{name}' is fed by more than one connection"),
            ));
        }
        let unit = ssd
            .components
            .iter()
            .find(|x| x.name == end.0)
            .and_then(|x| x.connectors.iter().find(|(n, _, _)| *n == end.1))
            .and_then(|(_, _, u)| u.clone());
        if let (Some(a), Some(b)) = (&sc.unit, &unit)
            && a != b
        {
            return Err(Error::unsupported(
                Some(&end.0),
                Some(&end.1),
                format!("connection {text}: unit conversion between '{a}' and '{b}' is not supported"),
            ));
        }
        sc.links.push(end);
    }
    // Connections of clocks: run apart from the data connections (`sim/clocks.rs`); a clock
    // connected to a connector of another kind is refused.
    let (clocks, data): (Vec<Connection>, Vec<Connection>) = std::mem::take(&mut ssd.connections)
        .into_iter()
        .partition(|k| clock_connectors.contains(&k.start) || clock_connectors.contains(&k.end));
    ssd.connections = data;
    for k in &clocks {
        if let Some(end) = [&k.start, &k.end].into_iter().find(|e| !clock_connectors.contains(e)) {
            return Err(Error::unsupported(
                Some(&end.0),
                Some(&end.1),
                format!(
                    "connection {}.{} -> {}.{}: '{}.{}' is no Clock connector: a Clock (ssc:Clock) connects to a Clock only",
                    k.start.0, k.start.1, k.end.0, k.end.1, end.0, end.1
                ),
            ));
        }
    }
    ssd.clock_connections = clocks;
    // Unit conversions: both ends declare a unit and they differ.
    for k in &ssd.connections {
        let unit = |(c, v): &(String, String)| {
            ssd.components
                .iter()
                .find(|x| &x.name == c)
                .and_then(|x| x.connectors.iter().find(|(n, _, _)| n == v))
                .and_then(|(_, _, u)| u.clone())
        };
        if let (Some(a), Some(b)) = (unit(&k.start), unit(&k.end))
            && a != b
        {
            return Err(Error::unsupported(
                Some(&k.end.0),
                Some(&k.end.1),
                format!(
                    "connection {}.{} -> {}.{}: unit conversion from '{a}' to '{b}' is not supported",
                    k.start.0, k.start.1, k.end.0, k.end.1
                ),
            ));
        }
    }
    Ok(ssd)
}

/// An SSP archive, opened: its system and its files.
pub struct Archive {
    pub path: String,
    pub ssd: Ssd,
    files: Files,
}

/// Where an archive's files are: a zip file, or a folder (an SSP unpacked).
enum Files {
    Zip(zip::ZipArchive<std::fs::File>),
    Dir(std::path::PathBuf),
}

impl Files {
    fn read(&mut self, archive: &str, name: &str) -> Result<Vec<u8>, Error> {
        match self {
            Files::Zip(zip) => read_entry(zip, archive, name),
            Files::Dir(dir) => {
                let name = name.trim_start_matches("./");
                if name.split('/').any(|part| part == "..") {
                    return Err(Error::io(format!(
                        "{archive}: '{name}' lies outside the system's folder"
                    )));
                }
                std::fs::read(dir.join(name)).map_err(|e| Error::io(format!("{archive}: cannot read '{name}': {e}")))
            }
        }
    }
}

fn read_entry<R: Read + Seek>(zip: &mut zip::ZipArchive<R>, archive: &str, name: &str) -> Result<Vec<u8>, Error> {
    let name = name.trim_start_matches("./");
    let mut f = zip
        .by_name(name)
        .map_err(|e| Error::io(format!("{archive}: no file '{name}' in the archive ({e})")))?;
    let mut out = Vec::new();
    f.read_to_end(&mut out)
        .map_err(|e| Error::io(format!("{archive}: reading '{name}': {e}")))?;
    Ok(out)
}

impl Archive {
    pub fn open(path: &std::path::Path) -> Result<Archive, Error> {
        let shown = path.display().to_string();
        let file = std::fs::File::open(path).map_err(|e| Error::io(format!("{shown}: cannot open: {e}")))?;
        let zip =
            zip::ZipArchive::new(file).map_err(|e| Error::io(format!("{shown}: not an SSP (zip) archive: {e}")))?;
        Archive::of_files(shown, Files::Zip(zip))
    }

    /// An SSP archive unpacked into the folder `dir`.
    pub fn open_dir(dir: &std::path::Path) -> Result<Archive, Error> {
        Archive::of_files(dir.display().to_string(), Files::Dir(dir.to_owned()))
    }

    fn of_files(shown: String, mut files: Files) -> Result<Archive, Error> {
        let text = |bytes: Vec<u8>, name: &str| {
            String::from_utf8(bytes).map_err(|_| Error::io(format!("{shown}: {name} is not UTF-8")))
        };
        let ssd_text = text(files.read(&shown, "SystemStructure.ssd")?, "SystemStructure.ssd")?;
        let mut read = |name: &str| -> Result<String, Error> { text(files.read(&shown, name)?, name) };
        let ssd = parse_ssd(&ssd_text, &mut read).map_err(|e| Error {
            message: format!("{shown}: {}", e.message),
            ..e
        })?;
        Ok(Archive {
            path: shown,
            ssd,
            files,
        })
    }

    /// The `source` of a component.
    fn source_of(&self, component: &str) -> Result<&str, Error> {
        self.ssd
            .components
            .iter()
            .find(|c| c.name == component)
            .map(|c| c.source.as_str())
            .ok_or_else(|| Error::new(ErrorKind::Variable, format!("no component '{component}'")))
    }

    /// The folder of a component's FMU when the system is a folder and the FMU is unpacked
    /// there (a container's `resources/system/`: its `source` is a folder), else None.
    pub fn unpacked_fmu(&self, component: &str) -> Result<Option<std::path::PathBuf>, Error> {
        let Files::Dir(dir) = &self.files else {
            return Ok(None);
        };
        let source = self.source_of(component)?.trim_start_matches("./");
        if source.contains("://") || source.starts_with('/') || source.split('/').any(|p| p == "..") {
            return Ok(None);
        }
        let path = dir.join(source);
        Ok(path.is_dir().then_some(path))
    }

    /// The bytes of a component's FMU (its `source`, inside the archive).
    pub fn fmu_bytes(&mut self, component: &str) -> Result<Vec<u8>, Error> {
        let source = self.source_of(component)?.to_owned();
        if source.contains("://") || source.starts_with('/') {
            return Err(Error::unsupported(
                Some(component),
                None,
                format!("component '{component}': source '{source}' lies outside the archive: not supported"),
            ));
        }
        self.files.read(&self.path, &source).map_err(|e| Error {
            component: Some(component.to_owned()),
            message: format!("component '{component}': {}", e.message),
            ..e
        })
    }
}
