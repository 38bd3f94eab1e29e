//! Systems of FMI 3.0 FMUs (`fmi-version = "3.0"` on a `[[system]]` of a systems file,
//! [`crate::systems`]): the components are the FMI 3.0 FMUs `<fmu-dir>/fmi3/<fmu>.fmu`, FMUs
//! that may have no FMI 2.0 twin (clocks, Binary variables: the FMI-LS-BUS network FMUs), and
//! the system is checked against their FMI 3.0 `modelDescription.xml` as any importer reads it
//! (md-reader); [`crate::ssp`] writes it in SSP 2.0 only (`<out>/fmi3/<system>.ssp`).
//!
//! What the check asks of a connection `a.x -> b.y`:
//! - both ends exist and have one type (Float64, Int8 .. UInt64, Boolean, String, Binary,
//!   Enumeration, Clock); two Enumerations have the same items (names and values), two
//!   Binaries one mime type;
//! - both are scalars, or both arrays of the same dimensions: fixed (`<Dimension start>`) or
//!   set by a structural parameter (`<Dimension valueReference>`, of the value the system gives
//!   it, else its start), each dimension of one size at both ends;
//! - data: `x` is an output, `y` an input;
//! - clocks: `y` is a triggered input clock (`intervalVariability="triggered"`), the one a
//!   connection can tick; `x` an output clock, or an input clock the importer ticks, its ticks
//!   passed on (FMI-LS-BUS 1.0.0, Time-based Tx Clocks: a node's countdown Tx_Clock connects to
//!   the bus's triggered Rx_Clock);
//! - a connection of two clocked variables (`clocks`) comes with a clock connection from one of
//!   the output's clocks to one of the input's, where the input's clocks are triggered ones:
//!   a clocked input is set only while its clock ticks, and a triggered clock ticks only through
//!   a connection, so without one from the output's clock the input never takes the value (the
//!   FMI-LS-BUS Bus Terminal: `Tx_Data` and `Tx_Clock` connect to `Rx_Data` and `Rx_Clock`);
//! - no input is driven twice.
//!
//! A parameter names a variable that takes a start value (not an input, a constant or a
//! clock) and gets a value of its type: a number for a Float, an integer in range for an Int or
//! UInt, `true`/`false`, a string, for a Binary a string of hexadecimal digits (two a byte), for
//! an Enumeration one of its items' values or names. An array takes a TOML array of as many
//! such values as it has elements (row-major; nested arrays are its rows), its dimensions
//! sized as for a connection.

use crate::systems::{Component, Connection, Description, End, Literal, Refusal, System};
use md_reader::Causality;
use std::collections::BTreeMap;
use std::path::Path;

pub use md_reader::fmi3::{
    Dimension, Enumeration as Enumeration3, ModelDescription as Fmu3Description, Type as Type3, Variable as Variable3,
};

/// The FMI 3.0 FMUs of a system, by the name its components give them (`fmu`).
pub type Fmus3 = BTreeMap<String, Fmu3Description>;

/// A Binary's mime type when it declares none (FMI 3.0, 2.4.7.5.4).
const OCTET_STREAM: &str = "application/octet-stream";

/// Reads a modelDescription.xml of FMI 3.0.
pub fn parse_description(xml: &str) -> Result<Fmu3Description, String> {
    let d = Fmu3Description::parse(xml)?;
    if !d.fmi_version.starts_with("3.") {
        return Err(format!(
            "fmiVersion is \"{}\", expected \"3.0\" (a system with fmi-version = \"3.0\" is of FMI 3.0 FMUs)",
            d.fmi_version
        ));
    }
    Ok(d)
}

/// Reads `modelDescription.xml` of FMI 3.0 from an `.fmu` archive.
pub fn read_description(fmu: &Path) -> Result<Fmu3Description, String> {
    let xml = crate::systems::read_xml(fmu)?;
    parse_description(&xml).map_err(|e| format!("{}: {e}", fmu.display()))
}

/// A connection of a checked FMI 3.0 system, with what its connectors declare.
#[derive(Debug, Clone, PartialEq)]
pub struct TypedConnection3<'a> {
    pub connection: &'a Connection,
    pub var_type: Type3,
    /// A Binary's mime type (both ends'), as the FMUs declare it; `None`: octet-stream.
    pub mime_type: Option<String>,
    /// The causality of the start and end variables (an input clock may start a connection).
    pub from_causality: Causality,
    pub to_causality: Causality,
    /// An Enumeration's type (the same items at both ends).
    pub enumeration: Option<Enumeration3>,
    /// The dimensions of the start and end variables, outermost first (empty: scalars).
    pub from_dimensions: Vec<Size>,
    pub to_dimensions: Vec<Size>,
}

/// One dimension of an array variable in a system: fixed, or set by a structural parameter of
/// its FMU.
#[derive(Debug, Clone, PartialEq)]
pub enum Size {
    Fixed(u64),
    Parameter {
        /// The structural parameter's name, type and causality (the SSD's `sizeConnector`, a
        /// connector of that kind).
        name: String,
        ty: Type3,
        causality: Causality,
        /// The value the system gives it, else its start; `None`: neither is a size.
        value: Option<u64>,
    },
}

impl Size {
    fn value(&self) -> Option<u64> {
        match self {
            Size::Fixed(n) => Some(*n),
            Size::Parameter { value, .. } => *value,
        }
    }
}

/// `[3]`, `[n = 3, 2]`, `[m = ?]`
fn show_dimensions(dims: &[Size]) -> String {
    let shown: Vec<String> = dims
        .iter()
        .map(|d| match d {
            Size::Fixed(n) => n.to_string(),
            Size::Parameter { name, value, .. } => {
                format!("{name} = {}", value.map_or("?".into(), |n| n.to_string()))
            }
        })
        .collect();
    format!("[{}]", shown.join(", "))
}

/// The dimensions of `v`, a variable of `component`'s FMU `fmu`: a structural parameter's size
/// is the value `component` gives it, else its start.
fn dimensions(fmu: &Fmu3Description, component: Option<&Component>, v: &Variable3) -> Vec<Size> {
    v.dimensions
        .iter()
        .map(|d| match d {
            Dimension::Fixed(n) => Size::Fixed(*n),
            Dimension::Parameter(vr) => match fmu.by_vr(*vr) {
                Some(p) => {
                    let given = component.and_then(|c| c.parameters.iter().find(|q| q.name == p.name));
                    let value = match given {
                        Some(q) => match q.value {
                            Literal::Integer(n) => u64::try_from(n).ok(),
                            _ => None,
                        },
                        None => p.start.as_deref().and_then(|s| s.trim().parse().ok()),
                    };
                    Size::Parameter {
                        name: p.name.clone(),
                        ty: p.ty,
                        causality: p.causality,
                        value,
                    }
                }
                None => Size::Parameter {
                    name: format!("(value reference {vr}, no variable)"),
                    ty: Type3::UInt64,
                    causality: Causality::StructuralParameter,
                    value: None,
                },
            },
        })
        .collect()
}

/// A parameter value typed by its FMI 3.0 variable: its type and the SSV text of each element.
#[derive(Debug, Clone, PartialEq)]
pub struct Value3 {
    pub ty: Type3,
    /// The SSV text of each element, row-major (one for a scalar); an Enumeration's item names.
    pub values: Vec<String>,
    /// An array's sizes, outermost first (empty: a scalar).
    pub dimensions: Vec<u64>,
    /// An Enumeration's type.
    pub enumeration: Option<Enumeration3>,
}

/// An FMI 3.0 system that has passed [`System::check_fmi3`].
#[derive(Debug, Clone, PartialEq)]
pub struct Checked3<'a> {
    pub system: &'a System,
    /// For each component, in order: its parameters, in order, with their typed values.
    pub parameters: Vec<Vec<(&'a str, Value3)>>,
    /// Every connection, in order.
    pub connections: Vec<TypedConnection3<'a>>,
}

/// `output Float64`, `input Clock (triggered)`, `output Float64 array`,
/// `input Enumeration Option (Option 1 = 1, Option 2 = 2)`
fn describe(fmu: &Fmu3Description, v: &Variable3) -> String {
    let mut s = format!("{} {}", v.causality.name(), v.ty);
    if let Some(c) = &v.clock {
        s += &format!(" ({})", c.interval_variability);
    }
    if let Some(e) = fmu.enumeration_of(v).filter(|_| v.ty == Type3::Enumeration) {
        let items: Vec<String> = e.items.iter().map(|(n, k)| format!("{n} = {k}")).collect();
        s += &format!(" {} ({})", e.name, items.join(", "));
    }
    if v.array {
        s += " array";
    }
    s
}

impl Description for Fmu3Description {
    type Variable = Variable3;
    const VERSION: &'static str = " (FMI 3.0)";
    fn read(fmu: &Path) -> Result<Self, String> {
        read_description(fmu)
    }
    fn find(&self, name: &str) -> Option<&Variable3> {
        self.variables.iter().find(|v| v.name == name)
    }
    fn names(&self) -> Vec<&str> {
        self.variables.iter().map(|v| v.name.as_str()).collect()
    }
}

impl System {
    /// Whether the system is of FMI 3.0 FMUs (`fmi-version = "3.0"`).
    pub fn is_fmi3(&self) -> bool {
        self.fmi_version.as_deref() == Some("3.0")
    }

    /// Checks the system against the FMI 3.0 descriptions of its FMUs (see the module).
    pub fn check_fmi3<'a>(&'a self, fmus: &Fmus3) -> Result<Checked3<'a>, String> {
        let mime = |v: &Variable3| v.mime_type.clone().unwrap_or_else(|| OCTET_STREAM.into());
        let connect = |c: &'a Connection, (ofmu, o): End<Fmu3Description>, (ifmu, inp): End<Fmu3Description>| {
            let wrong = |why: String| {
                format!(
                    "{}: connection {c}: {} is {}, {} is {}: {why}",
                    self.at(),
                    c.from,
                    describe(ofmu, o),
                    c.to,
                    describe(ifmu, inp)
                )
            };
            if o.ty != inp.ty {
                return Err(wrong(format!(
                    "a connection joins two variables of one type ({} to {})",
                    o.ty, inp.ty
                )));
            }
            if o.ty == Type3::Clock {
                let triggered = |v: &Variable3| v.clock.as_ref().is_some_and(|k| k.interval_variability == "triggered");
                if inp.causality != Causality::Input || !triggered(inp) {
                    return Err(wrong(format!(
                        "a clock connection ticks a triggered input clock (intervalVariability=\"triggered\"), and {} is not one",
                        c.to
                    )));
                }
                if !matches!(o.causality, Causality::Output | Causality::Input) {
                    return Err(wrong(format!(
                        "a clock connection starts at an output clock or at an input clock the importer ticks, and {} is neither",
                        c.from
                    )));
                }
            } else if o.causality != Causality::Output || inp.causality != Causality::Input {
                return Err(wrong("a connection goes from an output to an input".into()));
            }
            if let Some(missing) = self.missing_clock_connection(c, (ofmu, o), (ifmu, inp)) {
                return Err(wrong(missing));
            }
            let from_dimensions = dimensions(ofmu, self.component(&c.from.component), o);
            let to_dimensions = dimensions(ifmu, self.component(&c.to.component), inp);
            let sizes = |d: &[Size]| d.iter().map(Size::value).collect::<Vec<_>>();
            let (fs, ts) = (sizes(&from_dimensions), sizes(&to_dimensions));
            if fs != ts || fs.contains(&None) {
                let show = |d: &[Size]| {
                    if d.is_empty() {
                        "a scalar".to_owned()
                    } else {
                        show_dimensions(d)
                    }
                };
                return Err(wrong(format!(
                    "a connection joins a scalar to a scalar or an array to an array of the same dimensions, each of a known size: {} is {}, {} is {}",
                    c.from,
                    show(&from_dimensions),
                    c.to,
                    show(&to_dimensions)
                )));
            }
            let enumeration = if o.ty == Type3::Enumeration {
                let (oe, ie) = (ofmu.enumeration_of(o), ifmu.enumeration_of(inp));
                let (Some(oe), Some(ie)) = (oe, ie) else {
                    let port = if oe.is_none() { &c.from } else { &c.to };
                    return Err(wrong(format!(
                        "{port}'s declaredType names no EnumerationType of its FMU's TypeDefinitions"
                    )));
                };
                if oe.items != ie.items {
                    return Err(wrong("the Enumerations have different items".into()));
                }
                Some(oe.clone())
            } else {
                None
            };
            if o.ty == Type3::Binary && mime(o) != mime(inp) {
                return Err(wrong(format!(
                    "the Binaries carry different mime types: '{}' and '{}'",
                    mime(o),
                    mime(inp)
                )));
            }
            Ok(TypedConnection3 {
                connection: c,
                var_type: o.ty,
                mime_type: (o.ty == Type3::Binary).then(|| mime(o)),
                from_causality: o.causality,
                to_causality: inp.causality,
                enumeration,
                from_dimensions,
                to_dimensions,
            })
        };
        let parameter = |component: &Component, literal: &Literal, (fmu, v): End<Fmu3Description>| {
            let refused = |why| Refusal::Valueless {
                variable: format!("'{}' ({})", v.name, describe(fmu, v)),
                why,
            };
            if v.causality == Causality::Input {
                return Err(refused("it is an input (its value comes from its connection)"));
            }
            if v.variability == md_reader::Variability::Constant {
                return Err(refused("it is a constant"));
            }
            if v.ty == Type3::Clock {
                return Err(refused("it is a clock"));
            }
            if v.start.is_none() {
                return Err(refused("it declares no start value"));
            }
            let enumeration = fmu.enumeration_of(v).filter(|_| v.ty == Type3::Enumeration);
            if v.ty == Type3::Enumeration && enumeration.is_none() {
                return Err(refused(
                    "its declaredType names no EnumerationType of its FMU's TypeDefinitions",
                ));
            }
            let typed = |x: &Literal| match enumeration {
                Some(e) => item_of(x, e),
                None => typed_text(x, v.ty),
            };
            let (values, dimensions) = if v.array {
                let dims = dimensions(fmu, Some(component), v);
                let sizes: Option<Vec<u64>> = dims.iter().map(Size::value).collect();
                let Some(sizes) = sizes else {
                    return Err(Refusal::Mistyped(format!(
                        "an array of dimensions {}, one of them of no known size",
                        show_dimensions(&dims)
                    )));
                };
                let Literal::Array(_) = literal else {
                    return Err(Refusal::Mistyped(format!(
                        "an array of {} {}: give it an array of values (row-major)",
                        show_dimensions(&dims),
                        v.ty
                    )));
                };
                let mut elements = Vec::new();
                flatten(literal, &mut elements);
                let count: u64 = sizes.iter().product();
                if elements.len() as u64 != count {
                    return Err(Refusal::Mistyped(format!(
                        "an array of {} {}, {count} values, and the value has {}",
                        show_dimensions(&dims),
                        v.ty,
                        elements.len()
                    )));
                }
                let values = elements
                    .into_iter()
                    .map(|x| typed(x).map_err(|e| format!("{e} (an element of the array {})", show_dimensions(&dims))))
                    .collect::<Result<Vec<_>, _>>()
                    .map_err(Refusal::Mistyped)?;
                (values, sizes)
            } else {
                (vec![typed(literal).map_err(Refusal::Mistyped)?], Vec::new())
            };
            Ok(Value3 {
                ty: v.ty,
                values,
                dimensions,
                enumeration: enumeration.cloned(),
            })
        };
        let (connections, parameters) = self.check_with(fmus, connect, parameter)?;
        Ok(Checked3 {
            system: self,
            parameters,
            connections,
        })
    }
}

impl System {
    /// Why the data connection `c` of two clocked variables misses its clock connection (see the
    /// module); None: it has one, or the input is unclocked or has a clock that ticks by itself.
    fn missing_clock_connection(
        &self,
        c: &Connection,
        (ofmu, o): End<Fmu3Description>,
        (ifmu, inp): End<Fmu3Description>,
    ) -> Option<String> {
        let clocks = |fmu: &Fmu3Description, v: &Variable3| -> Vec<(String, bool)> {
            v.clocks
                .iter()
                .filter_map(|vr| fmu.by_vr(*vr))
                .map(|k| {
                    let triggered = k.clock.as_ref().is_some_and(|a| a.interval_variability == "triggered");
                    (k.name.clone(), triggered && k.causality == Causality::Input)
                })
                .collect()
        };
        let (senders, receivers) = (clocks(ofmu, o), clocks(ifmu, inp));
        if senders.is_empty() || receivers.is_empty() || !receivers.iter().all(|(_, triggered)| *triggered) {
            return None;
        }
        let joined = self.connections.iter().any(|k| {
            k.from.component == c.from.component
                && k.to.component == c.to.component
                && senders.iter().any(|(n, _)| *n == k.from.variable)
                && receivers.iter().any(|(n, _)| *n == k.to.variable)
        });
        if joined {
            return None;
        }
        let names = |component: &str, list: &[(String, bool)]| {
            list.iter()
                .map(|(n, _)| format!("{component}.{n}"))
                .collect::<Vec<_>>()
                .join(" or ")
        };
        let (from, to) = (names(&c.from.component, &senders), names(&c.to.component, &receivers));
        Some(format!(
            "{} is clocked by {from}, {} by the triggered {to}, which ticks only through a clock connection: without the clock connection {from} -> {to} the input is never set (FMI 3.0: a clocked variable is set only while its clock ticks); add \"{from} -> {to}\"",
            c.from, c.to
        ))
    }
}

/// The elements of an array literal, row-major (nested arrays are its rows).
fn flatten<'l>(literal: &'l Literal, out: &mut Vec<&'l Literal>) {
    match literal {
        Literal::Array(xs) => xs.iter().for_each(|x| flatten(x, out)),
        x => out.push(x),
    }
}

/// The name of the item of `e` that `literal` names (by its value or its name); the error
/// completes "declares 'v' ...".
fn item_of(literal: &Literal, e: &Enumeration3) -> Result<String, String> {
    let items: Vec<String> = e.items.iter().map(|(n, k)| format!("{n} = {k}")).collect();
    let described = format!("Enumeration {} ({})", e.name, items.join(", "));
    let item = e.items.iter().find(|(name, value)| match literal {
        Literal::Integer(x) => value == x,
        Literal::String(s) => name == s,
        _ => false,
    });
    match (item, literal) {
        (Some((name, _)), _) => Ok(name.clone()),
        (None, Literal::Integer(_) | Literal::String(_)) => Err(format!("{described}, which has no item {literal}")),
        (None, _) => Err(format!("{described}, which takes an item's value or name")),
    }
}

/// The SSV value text of `literal` for a variable of type `ty`; the error completes
/// "declares 'v' ...".
fn typed_text(literal: &Literal, ty: Type3) -> Result<String, String> {
    let mismatch = |want: &str| format!("{ty}, which takes {want}");
    let integer = |min: i128, max: i128| match literal {
        Literal::Integer(x) if (min..=max).contains(&i128::from(*x)) => Ok(x.to_string()),
        Literal::Integer(x) => Err(format!("{ty}, an integer in [{min}, {max}]: {x} is out of range")),
        _ => Err(mismatch("an integer")),
    };
    match ty {
        Type3::Float64 | Type3::Float32 => match literal {
            Literal::Float(x) => Ok(format!("{x:?}")),
            Literal::Integer(x) => Ok(format!("{:?}", *x as f64)),
            _ => Err(mismatch("a number")),
        },
        Type3::Int8 => integer(i8::MIN.into(), i8::MAX.into()),
        Type3::UInt8 => integer(0, u8::MAX.into()),
        Type3::Int16 => integer(i16::MIN.into(), i16::MAX.into()),
        Type3::UInt16 => integer(0, u16::MAX.into()),
        Type3::Int32 => integer(i32::MIN.into(), i32::MAX.into()),
        Type3::UInt32 => integer(0, u32::MAX.into()),
        Type3::Int64 => integer(i64::MIN.into(), i64::MAX.into()),
        Type3::UInt64 => integer(0, u64::MAX.into()),
        Type3::Boolean => match literal {
            Literal::Boolean(x) => Ok(x.to_string()),
            _ => Err(mismatch("true or false")),
        },
        Type3::String => match literal {
            Literal::String(s) => Ok(s.clone()),
            _ => Err(mismatch("a string")),
        },
        Type3::Binary => match literal {
            Literal::String(s) if s.len() % 2 == 0 && s.bytes().all(|b| b.is_ascii_hexdigit()) => Ok(s.clone()),
            _ => Err(mismatch("a string of hexadecimal digits, two a byte (\"00ff\")")),
        },
        Type3::Enumeration | Type3::Clock => Err(format!("{ty}, which takes no value here")),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::systems::Systems;
    use crate::systems::testing::*;

    /// The FMUs of the networked pendulum, the bus last.
    pub(crate) const NETWORKED_FMUS: [&str; 6] = [
        "Pendulum",
        "DCMotor",
        "CanSensor",
        "CanController",
        "CanMotorDrive",
        "CanBus",
    ];

    pub(crate) fn fmus3() -> Fmus3 {
        NETWORKED_FMUS
            .into_iter()
            .map(|id| {
                let path = workspace_root().join("modelDescription/fmi3").join(format!("{id}.xml"));
                let xml = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                (
                    id.to_owned(),
                    parse_description(&xml).unwrap_or_else(|e| panic!("{id}: {e}")),
                )
            })
            .collect()
    }

    /// A scalar value of a type without items.
    fn scalar(ty: Type3, text: &str) -> Value3 {
        Value3 {
            ty,
            values: vec![text.into()],
            dimensions: vec![],
            enumeration: None,
        }
    }

    fn networked() -> System {
        paper_systems().get("NetworkedPendulum").unwrap().clone()
    }

    /// Why the networked pendulum is refused with its connection `old` replaced by `new`.
    fn refused_with(old: &str, new: &str) -> String {
        let mut s = networked();
        let k = s
            .connections
            .iter()
            .position(|c| c.to_string() == old)
            .unwrap_or_else(|| panic!("no connection {old}"));
        s.connections[k] = new.parse().unwrap();
        s.check_fmi3(&fmus3()).unwrap_err()
    }

    #[test]
    fn the_networked_pendulum_checks_against_its_fmi3_fmus() {
        let s = networked();
        assert!(s.is_fmi3());
        let checked = s.check_fmi3(&fmus3()).unwrap_or_else(|e| panic!("{e}"));
        let count = |t: Type3| checked.connections.iter().filter(|c| c.var_type == t).count();
        // 4 measurements, 2 x (U, omega, tau); each of the 4 nodes: 2 clocks and 2 Binaries.
        assert_eq!(
            (count(Type3::Float64), count(Type3::Clock), count(Type3::Binary)),
            (10, 8, 8)
        );
        let can = r#"application/org.fmi-standard.fmi-ls-bus.can; version="1.0.0""#;
        assert!(
            checked
                .connections
                .iter()
                .filter(|c| c.var_type == Type3::Binary)
                .all(|c| c.mime_type.as_deref() == Some(can))
        );
        let sensor = s.components.iter().position(|c| c.name == "sensor").unwrap();
        assert_eq!(
            checked.parameters[sensor][0],
            ("tx_id", scalar(Type3::Int32, "32")),
            "0x020 typed by the FMU's Int32"
        );
    }

    #[test]
    fn a_clock_connection_to_a_time_based_clock_or_from_data_is_refused() {
        // Into the bus's countdown Tx_Clock: a connection cannot tick a time-based clock.
        let e = refused_with(
            "sensor.CAN.Tx_Clock -> bus.Node1.Rx_Clock",
            "sensor.CAN.Tx_Clock -> bus.Node1.Tx_Clock",
        );
        assert!(
            e.contains("holonomic/systems.toml: system 'NetworkedPendulum'")
                && e.contains("connection sensor.CAN.Tx_Clock -> bus.Node1.Tx_Clock")
                && e.contains("bus.Node1.Tx_Clock is input Clock (countdown)")
                && e.contains("ticks a triggered input clock"),
            "expected file, system, connection and the clock's kind named, got: {e}"
        );
        // A Binary into a clock.
        let e = refused_with(
            "sensor.CAN.Tx_Clock -> bus.Node1.Rx_Clock",
            "sensor.CAN.Tx_Data -> bus.Node1.Rx_Clock",
        );
        assert!(
            e.contains("connection sensor.CAN.Tx_Data -> bus.Node1.Rx_Clock")
                && e.contains("sensor.CAN.Tx_Data is output Binary")
                && e.contains("one type (Binary to Clock)"),
            "{e}"
        );
        // Two triggered clocks the wrong way round: the node's Rx_Clock is no source of ticks
        // into the bus's Tx_Clock (countdown).
        let e = refused_with(
            "bus.Node1.Tx_Clock -> sensor.CAN.Rx_Clock",
            "sensor.CAN.Rx_Clock -> bus.Node1.Tx_Clock",
        );
        assert!(e.contains("bus.Node1.Tx_Clock is not one"), "{e}");
    }

    #[test]
    fn a_clocked_binary_without_the_clock_connection_of_its_clocks_is_refused() {
        // The sensor's Tx_Data into the bus's port, its Tx_Clock -> Rx_Clock connection left out.
        let mut s = networked();
        s.connections
            .retain(|c| c.to_string() != "sensor.CAN.Tx_Clock -> bus.Node1.Rx_Clock");
        let e = s.check_fmi3(&fmus3()).unwrap_err();
        assert!(
            e.contains("holonomic/systems.toml: system 'NetworkedPendulum': connection sensor.CAN.Tx_Data -> bus.Node1.Rx_Data")
                && e.contains("sensor.CAN.Tx_Data is clocked by sensor.CAN.Tx_Clock, bus.Node1.Rx_Data by the triggered bus.Node1.Rx_Clock")
                && e.contains("without the clock connection sensor.CAN.Tx_Clock -> bus.Node1.Rx_Clock"),
            "expected both variables and the missing clock connection named, got: {e}"
        );
        // The other way: the bus's Tx_Data to the sensor without the bus's Tx_Clock -> the
        // sensor's Rx_Clock.
        let mut s = networked();
        s.connections
            .retain(|c| c.to_string() != "bus.Node1.Tx_Clock -> sensor.CAN.Rx_Clock");
        let e = s.check_fmi3(&fmus3()).unwrap_err();
        assert!(
            e.contains("connection bus.Node1.Tx_Data -> sensor.CAN.Rx_Data")
                && e.contains("without the clock connection bus.Node1.Tx_Clock -> sensor.CAN.Rx_Clock"),
            "{e}"
        );
        // A clock connection from another node's clock does not stand for it.
        let e = refused_with(
            "sensor.CAN.Tx_Clock -> bus.Node1.Rx_Clock",
            "drive1.CAN.Tx_Clock -> bus.Node1.Rx_Clock",
        );
        assert!(
            e.contains("connection sensor.CAN.Tx_Data -> bus.Node1.Rx_Data")
                && e.contains("without the clock connection sensor.CAN.Tx_Clock -> bus.Node1.Rx_Clock"),
            "{e}"
        );
    }

    #[test]
    fn a_binary_to_a_float64_and_an_output_into_an_output_are_refused() {
        let e = refused_with(
            "bus.Node3.Tx_Data -> drive1.CAN.Rx_Data",
            "bus.Node3.Tx_Data -> motor1.U",
        );
        assert!(
            e.contains("connection bus.Node3.Tx_Data -> motor1.U")
                && e.contains("bus.Node3.Tx_Data is output Binary, motor1.U is input Float64")
                && e.contains("(Binary to Float64)"),
            "{e}"
        );
        let e = refused_with("drive1.U -> motor1.U", "drive1.U -> motor1.tau");
        assert!(
            e.contains("motor1.tau is output Float64") && e.contains("from an output to an input"),
            "{e}"
        );
        let e = refused_with("drive2.U -> motor2.U", "drive1.U -> motor1.U");
        assert!(
            e.contains("input motor1.U is driven twice: by drive1.U and by drive1.U"),
            "{e}"
        );
    }

    #[test]
    fn an_unknown_variable_is_refused_with_the_variables_there_are() {
        let e = refused_with(
            "sensor.CAN.Tx_Data -> bus.Node1.Rx_Data",
            "sensor.CAN.Tx_Data -> bus.Node9.Rx_Data",
        );
        assert!(
            e.contains(
                "system 'NetworkedPendulum': bus.Node9.Rx_Data: CanBus.fmu (FMI 3.0) has no variable 'Node9.Rx_Data'"
            ) && e.contains("Node4.Rx_Data"),
            "{e}"
        );
    }

    #[test]
    fn binaries_of_different_mime_types_are_refused() {
        let mut fmus = fmus3();
        let bus = fmus.get_mut("CanBus").unwrap();
        let rx = bus.variables.iter_mut().find(|v| v.name == "Node1.Rx_Data").unwrap();
        rx.mime_type = Some("application/org.fmi-standard.fmi-ls-bus.flexray".into());
        let e = networked().check_fmi3(&fmus).unwrap_err();
        assert!(
            e.contains("sensor.CAN.Tx_Data -> bus.Node1.Rx_Data")
                && e.contains("different mime types")
                && e.contains("fmi-ls-bus.flexray"),
            "{e}"
        );
    }

    #[test]
    fn parameters_are_typed_by_the_fmi3_declarations() {
        let with = |component: &str, fmu: &str, parameters: &str| {
            one_system(&format!(
                "[[system]]\nname = \"S\"\nfmi-version = \"3.0\"\n[[system.component]]\nname = \"{component}\"\n\
                 fmu = \"{fmu}\"\nparameters = {{ {parameters} }}\n"
            ))
            .check_fmi3(&fmus3())
            .map(|c| {
                c.parameters[0]
                    .iter()
                    .map(|(n, v)| (n.to_string(), v.clone()))
                    .collect::<Vec<_>>()
            })
        };
        let ok = with("bus", "CanBus", "baud_rate = 250000, background_load = 1").unwrap();
        assert_eq!(
            ok,
            [
                ("baud_rate".to_string(), scalar(Type3::Int32, "250000")),
                ("background_load".to_string(), scalar(Type3::Float64, "1.0"))
            ]
        );
        let e = with("bus", "CanBus", "baud_rate = 4294967296").unwrap_err();
        assert!(
            e.contains("parameter bus.baud_rate = 4294967296") && e.contains("Int32, an integer in"),
            "{e}"
        );
        let e = with("bus", "CanBus", "baud_rate = 5e5").unwrap_err();
        assert!(e.contains("Int32, which takes an integer"), "{e}");
        let e = with("sensor", "CanSensor", "alpha1 = 0.1").unwrap_err();
        assert!(e.contains("sensor.alpha1") && e.contains("it is an input"), "{e}");
        let e = with("sensor", "CanSensor", "\"CAN.Tx_Clock\" = 1").unwrap_err();
        assert!(e.contains("sensor.CAN.Tx_Clock") && e.contains("it is an input"), "{e}");
        let e = with("sensor", "CanSensor", "frames = 1").unwrap_err();
        assert!(e.contains("CanSensor.fmu (FMI 3.0) has no variable 'frames'"), "{e}");
    }

    #[test]
    fn an_fmi3_system_is_declared_with_its_version() {
        let parse = |t: &str| Systems::parse(t, Path::new("v.toml"));
        let e = parse("[[system]]\nname = \"S\"\nfmi-version = \"3\"\n").unwrap_err();
        assert!(e.contains("fmi-version = \"3\"") && e.contains("\"3.0\""), "{e}");
        let e = parse("[[system]]\nname = \"S\"\nfmi-version = \"3.0\"\nssp-version = \"1.0\"\n").unwrap_err();
        assert!(e.contains("SSP 1.0 has no FMI 3.0 types"), "{e}");
        let s = parse("[[system]]\nname = \"S\"\nfmi-version = \"3.0\"\n").unwrap();
        assert!(s.systems[0].is_fmi3());
        let s = parse("[[system]]\nname = \"S\"\n").unwrap();
        assert!(!s.systems[0].is_fmi3());
    }

    #[test]
    fn an_fmi2_description_is_refused_for_an_fmi3_system() {
        let e = parse_description(&xml("Pendulum")).unwrap_err();
        assert!(e.contains("fmiVersion is \"2.0\", expected \"3.0\""), "{e}");
    }

    /// The descriptions of these of our FMI 3.0 FMUs (the committed modelDescription/fmi3/).
    pub(crate) fn described(ids: &[&str]) -> Fmus3 {
        ids.iter()
            .map(|id| {
                let path = workspace_root().join("modelDescription/fmi3").join(format!("{id}.xml"));
                let xml = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                (
                    id.to_string(),
                    parse_description(&xml).unwrap_or_else(|e| panic!("{id}: {e}")),
                )
            })
            .collect()
    }

    /// An FMI 3.0 system of two StateSpace FMUs (`s1`, `s2`), two Feedthroughs (`f1`, `f2`)
    /// and a Controller (`c`), with `connections` and each component's parameters (TOML inline
    /// table bodies).
    pub(crate) fn arrays_and_enumerations(connections: &[&str], parameters: [&str; 5]) -> System {
        let mut text = String::from("[[system]]\nname = \"AE\"\nfmi-version = \"3.0\"\nconnections = [");
        for c in connections {
            text += &format!("\"{c}\", ");
        }
        text += "]\n";
        for ((name, fmu), p) in [
            ("s1", "StateSpace"),
            ("s2", "StateSpace"),
            ("f1", "Feedthrough"),
            ("f2", "Feedthrough"),
            ("c", "Controller"),
        ]
        .into_iter()
        .zip(parameters)
        {
            text += &format!("[[system.component]]\nname = \"{name}\"\nfmu = \"{fmu}\"\nparameters = {{ {p} }}\n");
        }
        one_system(&text)
    }

    fn ae_fmus() -> Fmus3 {
        described(&["StateSpace", "Feedthrough", "Controller"])
    }

    #[test]
    fn arrays_of_the_same_dimensions_connect_and_others_are_refused_naming_both_ends() {
        let s = arrays_and_enumerations(&["s1.y -> s2.u"], ["", "", "", "", ""]);
        let checked = s.check_fmi3(&ae_fmus()).unwrap_or_else(|e| panic!("{e}"));
        let sized = |name: &str| Size::Parameter {
            name: name.into(),
            ty: Type3::UInt64,
            causality: Causality::StructuralParameter,
            value: Some(3),
        };
        let c = &checked.connections[0];
        assert_eq!(
            (c.var_type, &c.from_dimensions, &c.to_dimensions),
            (Type3::Float64, &vec![sized("r")], &vec![sized("m")])
        );
        // s2's structural parameter m set to 2: 3 outputs into 2 inputs.
        let s = arrays_and_enumerations(&["s1.y -> s2.u"], ["", "m = 2", "", "", ""]);
        let e = s.check_fmi3(&ae_fmus()).unwrap_err();
        assert!(
            e.contains("test.toml: system 'AE': connection s1.y -> s2.u")
                && e.contains("s1.y is output Float64 array, s2.u is input Float64 array")
                && e.contains("same dimensions, each of a known size: s1.y is [r = 3], s2.u is [m = 2]"),
            "expected both ends' dimensions named, got: {e}"
        );
        // Set alike at both ends, they connect again.
        let s = arrays_and_enumerations(&["s1.y -> s2.u"], ["r = 2", "m = 2", "", "", ""]);
        s.check_fmi3(&ae_fmus()).unwrap_or_else(|e| panic!("{e}"));
        let e = arrays_and_enumerations(&["f1.Float64_continuous_output -> s2.u"], ["", "", "", "", ""])
            .check_fmi3(&ae_fmus())
            .unwrap_err();
        assert!(
            e.contains("f1.Float64_continuous_output is a scalar, s2.u is [m = 3]"),
            "{e}"
        );
    }

    #[test]
    fn enumerations_connect_when_their_items_are_the_same() {
        let s = arrays_and_enumerations(&["f1.Enumeration_output -> f2.Enumeration_input"], ["", "", "", "", ""]);
        let checked = s.check_fmi3(&ae_fmus()).unwrap_or_else(|e| panic!("{e}"));
        let e = checked.connections[0]
            .enumeration
            .as_ref()
            .expect("an Enumeration's type");
        assert_eq!(
            (e.name.as_str(), e.items.clone()),
            ("Option", vec![("Option 1".into(), 1), ("Option 2".into(), 2)])
        );
        // f2 a Feedthrough whose Option's second item has another value.
        let mut s = arrays_and_enumerations(&["f1.Enumeration_output -> f2.Enumeration_input"], ["", "", "", "", ""]);
        s.components[3].fmu = "Feedthrough2".into();
        let mut fmus = ae_fmus();
        let mut other = fmus["Feedthrough"].clone();
        other.enumerations[0].items[1].1 = 3;
        fmus.insert("Feedthrough2".into(), other);
        let e = s.check_fmi3(&fmus).unwrap_err();
        assert!(
            e.contains("connection f1.Enumeration_output -> f2.Enumeration_input")
                && e.contains("output Enumeration Option (Option 1 = 1, Option 2 = 2)")
                && e.contains("input Enumeration Option (Option 1 = 1, Option 2 = 3)")
                && e.contains("the Enumerations have different items"),
            "{e}"
        );
        let s = arrays_and_enumerations(&["f1.Enumeration_output -> f2.Enumeration_input"], ["", "", "", "", ""]);
        let mut fmus = ae_fmus();
        let ft = fmus.get_mut("Feedthrough").unwrap();
        let out = ft
            .variables
            .iter_mut()
            .find(|v| v.name == "Enumeration_output")
            .unwrap();
        out.declared_type = Some("ControlMode".into());
        let e = s.check_fmi3(&fmus).unwrap_err();
        assert!(
            e.contains("f1.Enumeration_output's declaredType names no EnumerationType"),
            "{e}"
        );
    }

    #[test]
    fn array_and_enumeration_parameters_are_typed_element_by_element() {
        let values = |p: [&str; 5], k: usize| {
            arrays_and_enumerations(&[], p)
                .check_fmi3(&ae_fmus())
                .map(|c| c.parameters[k][0].1.clone())
        };
        let a = values(["A = [[-1, 0, 0], [0, -2, 0], [0, 0, -3.5]]", "", "", "", ""], 0).unwrap();
        assert_eq!(a.dimensions, [3, 3]);
        assert_eq!(
            a.values,
            ["-1.0", "0.0", "0.0", "0.0", "-2.0", "0.0", "0.0", "0.0", "-3.5"]
        );
        // A structural parameter given before or after the array sizes it.
        let x0 = values(["x0 = [1, 2], n = 2", "", "", "", ""], 0).unwrap();
        assert_eq!(
            (x0.values, x0.dimensions),
            (vec!["1.0".to_string(), "2.0".into()], vec![2])
        );
        let e = values(["x0 = [1, 2]", "", "", "", ""], 0).unwrap_err();
        assert!(
            e.contains("parameter s1.x0 = [1, 2]: StateSpace.fmu declares 'x0' an array of [n = 3] Float64, 3 values, and the value has 2"),
            "{e}"
        );
        let e = values(["x0 = 1.0", "", "", "", ""], 0).unwrap_err();
        assert!(e.contains("give it an array of values"), "{e}");
        let e = values(["x0 = [1, true, 0]", "", "", "", ""], 0).unwrap_err();
        assert!(
            e.contains("Float64, which takes a number (an element of the array [n = 3])"),
            "{e}"
        );
        let e = values(["n = [3]", "", "", "", ""], 0).unwrap_err();
        assert!(e.contains("UInt64, which takes an integer"), "{e}");
        // An Enumeration by its item's name or value, written as the name.
        let mode = values(["", "", "", "", "mode = \"PID\""], 4).unwrap();
        assert_eq!(mode.values, ["PID"]);
        assert_eq!(mode.enumeration.as_ref().map(|e| e.name.as_str()), Some("ControlMode"));
        assert_eq!(values(["", "", "", "", "mode = 3"], 4).unwrap().values, ["LQR_PID"]);
        let e = values(["", "", "", "", "mode = \"LQR_PLUS\""], 4).unwrap_err();
        assert!(
            e.contains("declares 'mode' Enumeration ControlMode (LQR = 1, PID = 2, LQR_PID = 3), which has no item \"LQR_PLUS\""),
            "{e}"
        );
        let e = values(["", "", "", "", "mode = 1.0"], 4).unwrap_err();
        assert!(e.contains("which takes an item's value or name"), "{e}");
    }
}
