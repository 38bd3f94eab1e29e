//! Composed systems as data: a TOML file of systems, each a list of FMU instances
//! (components) with their parameter and start values, and connections from outputs to
//! inputs. A system is checked against the packaged FMUs it names, through their
//! `modelDescription.xml` as any importer reads it ([`FmuDescription`]); [`crate::ssp`] writes
//! a checked system as an SSP file. Nothing here knows the Rust types of the models.
//!
//! # The systems file
//!
//! ```toml
//! [[system]]
//! name = "PendulumLQR"        # the system's name, and its SSP file's: PendulumLQR.ssp
//! description = "..."         # optional
//! stop-time = 5.0             # optional: stopTime of the SSD's DefaultExperiment [s]
//! step-size = 1e-3            # optional: the communication step the system is made for [s]
//! ssp-version = "2.0"         # optional: "1.0" (default) or "2.0", the SSP of the FMI 3.0 twin
//! fmi-version = "3.0"         # optional: "2.0" (default) or "3.0": a system of FMI 3.0 FMUs
//! connections = [             # output -> input, of the same type
//!     "pendulum.alpha1 -> controller.alpha1",
//!     "controller.M1 -> pendulum.M1",
//! ]
//!
//! [[system.component]]        # one FMU instance of the system above; in order
//! name = "pendulum"           # unique in the system, without '.'
//! fmu = "Pendulum"            # the FMU's file: <fmu-dir>/Pendulum.fmu
//! parameters = { alpha1_0 = 0.1, alpha2_0 = -0.05 }   # optional; in order
//! ```
//!
//! In a connection the component is what precedes the first `.` of each end; the rest is the
//! variable's name (it may contain dots). A parameter names a variable that takes a start
//! value (not an input: an input's value comes from its connection; not a constant), and its
//! value is typed by the FMU's declaration: a Real takes a number (`200` or `200.0`), an
//! Integer an integer, a Boolean `true` or `false`, a String a string, an Enumeration an
//! integer that is one of its items' values or the name of one of its items (`"LQR"`).
//!
//! A system of FMI 3.0 FMUs (`fmi-version = "3.0"`: clocks, Binary variables, FMUs without an
//! FMI 2.0 twin, such as the FMI-LS-BUS network FMUs) is checked against their FMI 3.0
//! descriptions ([`crate::systems_fmi3`]) and written in SSP 2.0 only.
//!
//! A workspace names its systems files in its `Cargo.toml` ([`workspace_files`]):
//!
//! ```toml
//! [workspace.metadata.fmu]
//! systems = ["holonomic/systems.toml"]
//! ```

use serde::Deserialize;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use std::collections::BTreeMap;
use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};

/// A value as the systems file writes it, before an FMU's declaration gives it a type.
#[derive(Debug, Clone, PartialEq)]
pub enum Literal {
    Float(f64),
    Integer(i64),
    Boolean(bool),
    String(String),
    /// `[1.0, 0.0]`: the value of an FMI 3.0 array, row-major (nested arrays are its rows).
    Array(Vec<Literal>),
}

impl fmt::Display for Literal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Literal::Float(x) => write!(f, "{x:?}"),
            Literal::Integer(x) => write!(f, "{x}"),
            Literal::Boolean(x) => write!(f, "{x}"),
            Literal::String(s) => write!(f, "{s:?}"),
            Literal::Array(xs) => {
                let xs: Vec<String> = xs.iter().map(Literal::to_string).collect();
                write!(f, "[{}]", xs.join(", "))
            }
        }
    }
}

impl<'de> Deserialize<'de> for Literal {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Literal;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number, true or false, a string, or an array of them")
            }
            fn visit_f64<E: de::Error>(self, x: f64) -> Result<Literal, E> {
                Ok(Literal::Float(x))
            }
            fn visit_i64<E: de::Error>(self, x: i64) -> Result<Literal, E> {
                Ok(Literal::Integer(x))
            }
            fn visit_u64<E: de::Error>(self, x: u64) -> Result<Literal, E> {
                i64::try_from(x)
                    .map(Literal::Integer)
                    .map_err(|_| E::custom(format!("{x} is too large")))
            }
            fn visit_bool<E: de::Error>(self, x: bool) -> Result<Literal, E> {
                Ok(Literal::Boolean(x))
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<Literal, E> {
                Ok(Literal::String(s.to_owned()))
            }
            fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<Literal, A::Error> {
                let mut xs = Vec::new();
                while let Some(x) = seq.next_element::<Literal>()? {
                    xs.push(x);
                }
                Ok(Literal::Array(xs))
            }
        }
        d.deserialize_any(V)
    }
}

/// A parameter or start value of a component: `variable = value`.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    pub name: String,
    pub value: Literal,
}

/// The `parameters` table, in the order the file lists it.
fn ordered_parameters<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Parameter>, D::Error> {
    struct V;
    impl<'de> Visitor<'de> for V {
        type Value = Vec<Parameter>;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a table of variable = value")
        }
        fn visit_map<M: MapAccess<'de>>(self, mut map: M) -> Result<Vec<Parameter>, M::Error> {
            let mut out = Vec::new();
            while let Some((name, value)) = map.next_entry::<String, Literal>()? {
                out.push(Parameter { name, value });
            }
            Ok(out)
        }
    }
    d.deserialize_map(V)
}

/// One end of a connection: `component.variable`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Port {
    pub component: String,
    pub variable: String,
}

impl fmt::Display for Port {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{}", self.component, self.variable)
    }
}

/// `from -> to`: the output `from` drives the input `to`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Connection {
    pub from: Port,
    pub to: Port,
}

impl fmt::Display for Connection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} -> {}", self.from, self.to)
    }
}

impl std::str::FromStr for Connection {
    type Err = String;
    fn from_str(s: &str) -> Result<Connection, String> {
        let bad = || format!("connection '{s}' must read 'component.output -> component.input'");
        let port = |p: &str| -> Option<Port> {
            let (component, variable) = p.trim().split_once('.')?;
            (!component.is_empty() && !variable.is_empty()).then(|| Port {
                component: component.to_owned(),
                variable: variable.to_owned(),
            })
        };
        let (from, to) = s
            .split_once("->")
            .filter(|(_, to)| !to.contains("->"))
            .ok_or_else(bad)?;
        Ok(Connection {
            from: port(from).ok_or_else(bad)?,
            to: port(to).ok_or_else(bad)?,
        })
    }
}

/// One FMU instance of a system, with the parameter and start values it gets.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Component {
    pub name: String,
    /// The FMU's file name without `.fmu` (its modelIdentifier, for the FMUs fmu-build packages).
    pub fmu: String,
    #[serde(default, deserialize_with = "ordered_parameters")]
    pub parameters: Vec<Parameter>,
}

/// A composed system: components, and connections from outputs to inputs.
#[derive(Debug, Clone, PartialEq)]
pub struct System {
    /// The systems file it was read from (named in every error).
    pub file: PathBuf,
    pub name: String,
    pub description: Option<String>,
    /// Stop time of the SSP file's DefaultExperiment, in seconds.
    pub stop_time: Option<f64>,
    /// The communication step the system is made for, in seconds (the fixed-step master of
    /// OMSimulator's annotation in the SSP file).
    pub step_size: Option<f64>,
    /// The SSP version of the system's FMI 3.0 archive (`fmi3/<system>.ssp`): "1.0" (None) or
    /// "2.0"; the FMI 2.0 archive is SSP 1.0.
    pub ssp_version: Option<String>,
    /// The FMI version of the system's FMUs: "2.0" (None; the FMI 3.0 twins too, where every
    /// component has one) or "3.0" (FMI 3.0 FMUs only: [`crate::systems_fmi3`]).
    pub fmi_version: Option<String>,
    pub connections: Vec<Connection>,
    pub components: Vec<Component>,
}

/// A `[[system]]` table as the file writes it: its connections still text, with their place.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
struct SystemTable {
    name: String,
    #[serde(default)]
    description: Option<String>,
    #[serde(default)]
    stop_time: Option<f64>,
    #[serde(default)]
    step_size: Option<f64>,
    #[serde(default)]
    ssp_version: Option<String>,
    #[serde(default)]
    fmi_version: Option<String>,
    #[serde(default)]
    connections: Vec<toml::Spanned<String>>,
    #[serde(default)]
    component: Vec<Component>,
}

/// The systems of one file.
#[derive(Debug, Clone, PartialEq)]
pub struct Systems {
    pub file: PathBuf,
    pub systems: Vec<System>,
}

/// `file:line:column` of the byte `offset` of `text`.
fn place(file: &Path, text: &str, offset: usize) -> String {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.chars().rev().take_while(|c| *c != '\n').count() + 1;
    format!("{}:{line}:{column}", file.display())
}

/// `file:line:column: message` of a TOML error.
fn toml_error(file: &Path, text: &str, e: &toml::de::Error) -> String {
    match e.span() {
        Some(span) => format!("{}: {}", place(file, text, span.start), e.message().trim()),
        None => format!("{}: {}", file.display(), e.message().trim()),
    }
}

impl Systems {
    /// Reads and parses a systems file.
    pub fn load(file: &Path) -> Result<Systems, String> {
        let text = std::fs::read_to_string(file).map_err(|e| format!("{}: {e}", file.display()))?;
        Systems::parse(&text, file)
    }

    /// Parses the text of a systems file (`file` names it in the errors). Checks what needs no
    /// FMU: names are unique, components have no '.' in their names, connections name
    /// components of their system.
    pub fn parse(text: &str, file: &Path) -> Result<Systems, String> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct File {
            #[serde(default)]
            system: Vec<SystemTable>,
        }
        let parsed: File = toml::from_str(text).map_err(|e| toml_error(file, text, &e))?;
        let mut systems = Vec::new();
        for t in parsed.system {
            let connections = t
                .connections
                .iter()
                .map(|c| {
                    c.get_ref()
                        .parse()
                        .map_err(|e| format!("{}: {e}", place(file, text, c.span().start)))
                })
                .collect::<Result<_, _>>()?;
            systems.push(System {
                file: file.to_path_buf(),
                name: t.name,
                description: t.description,
                stop_time: t.stop_time,
                step_size: t.step_size,
                ssp_version: t.ssp_version,
                fmi_version: t.fmi_version,
                connections,
                components: t.component,
            });
        }
        for (i, s) in systems.iter().enumerate() {
            let at = format!("{}: system '{}'", file.display(), s.name);
            if s.name.is_empty() {
                return Err(format!("{}: system {} has an empty name", file.display(), i + 1));
            }
            if let Some(h) = s.step_size
                && !(h.is_finite() && h > 0.0)
            {
                return Err(format!("{at}: step-size = {h} must be finite and > 0"));
            }
            if let Some(v) = &s.ssp_version
                && !matches!(v.as_str(), "1.0" | "2.0")
            {
                return Err(format!("{at}: ssp-version = \"{v}\": \"1.0\" or \"2.0\""));
            }
            if let Some(v) = &s.fmi_version
                && !matches!(v.as_str(), "2.0" | "3.0")
            {
                return Err(format!("{at}: fmi-version = \"{v}\": \"2.0\" or \"3.0\""));
            }
            if s.is_fmi3() && s.ssp_version.as_deref() == Some("1.0") {
                return Err(format!(
                    "{at}: fmi-version = \"3.0\" with ssp-version = \"1.0\": SSP 1.0 has no FMI 3.0 types (Clock, Binary, Float64, ...); a system of FMI 3.0 FMUs is written in SSP 2.0"
                ));
            }
            for (k, c) in s.components.iter().enumerate() {
                if c.name.is_empty() || c.name.contains('.') {
                    return Err(format!(
                        "{at}: component name '{}' must be non-empty and without '.'",
                        c.name
                    ));
                }
                if s.components[..k].iter().any(|o| o.name == c.name) {
                    return Err(format!("{at}: two components are named '{}'", c.name));
                }
            }
            for c in &s.connections {
                for p in [&c.from, &c.to] {
                    if s.component(&p.component).is_none() {
                        return Err(format!(
                            "{at}: connection {c} names no component of the system: '{}' (there are: {})",
                            p.component,
                            s.component_names().join(", ")
                        ));
                    }
                }
            }
        }
        for (i, s) in systems.iter().enumerate() {
            if systems[..i].iter().any(|o| o.name == s.name) {
                return Err(format!("{}: two systems are named '{}'", file.display(), s.name));
            }
        }
        Ok(Systems {
            file: file.to_path_buf(),
            systems,
        })
    }

    /// The system called `name`; the error lists the systems there are.
    pub fn get(&self, name: &str) -> Result<&System, String> {
        self.systems.iter().find(|s| s.name == name).ok_or_else(|| {
            format!(
                "{}: no system named '{name}' (there are: {})",
                self.file.display(),
                self.names().join(", ")
            )
        })
    }

    pub fn names(&self) -> Vec<&str> {
        self.systems.iter().map(|s| s.name.as_str()).collect()
    }
}

/// The systems files a workspace names in its `Cargo.toml` (`[workspace.metadata.fmu]
/// systems = [...]`, paths relative to the workspace root); none when it names none.
pub fn workspace_files(workspace_root: &Path) -> Result<Vec<PathBuf>, String> {
    let manifest = workspace_root.join("Cargo.toml");
    let text = std::fs::read_to_string(&manifest).map_err(|e| format!("{}: {e}", manifest.display()))?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| toml_error(&manifest, &text, &e))?;
    let root = toml::Value::Table(table);
    let Some(list) = ["workspace", "metadata", "fmu", "systems"]
        .iter()
        .try_fold(&root, |v, key| v.get(key))
    else {
        return Ok(vec![]);
    };
    let bad = || {
        format!(
            "{}: [workspace.metadata.fmu] systems must be a list of paths",
            manifest.display()
        )
    };
    list.as_array()
        .ok_or_else(bad)?
        .iter()
        .map(|p| p.as_str().map(|p| workspace_root.join(p)).ok_or_else(bad))
        .collect()
}

pub use md_reader::fmi2::{Enumeration, ModelDescription as FmuDescription, Type as VarType, Variable};
pub use md_reader::{Causality, Variability};

/// `Mode (LQR = 1, PID = 2)`
fn describe(e: &Enumeration) -> String {
    let items: Vec<String> = e.items.iter().map(|(n, v)| format!("{n} = {v}")).collect();
    format!("{} ({})", e.name, items.join(", "))
}

/// Reads a modelDescription.xml of FMI 2.0 (the version a system's FMUs are packaged in).
pub fn parse_description(xml: &str) -> Result<FmuDescription, String> {
    let d = FmuDescription::parse(xml)?;
    if d.fmi_version != "2.0" {
        return Err(format!(
            "fmiVersion is {}, expected \"2.0\"",
            if d.fmi_version.is_empty() {
                "missing".into()
            } else {
                format!("\"{}\"", d.fmi_version)
            }
        ));
    }
    Ok(d)
}

/// Reads `modelDescription.xml` from an `.fmu` archive.
pub fn read_description(fmu: &Path) -> Result<FmuDescription, String> {
    let xml = read_xml(fmu)?;
    parse_description(&xml).map_err(|e| format!("{}: {e}", fmu.display()))
}

/// The text of an `.fmu` archive's `modelDescription.xml`.
pub(crate) fn read_xml(fmu: &Path) -> Result<String, String> {
    let err = |e: &dyn fmt::Display| format!("{}: {e}", fmu.display());
    let file = std::fs::File::open(fmu).map_err(|e| {
        format!(
            "{}: {e} (package the FMUs first: `cargo run --release -p fmu-build`)",
            fmu.display()
        )
    })?;
    let mut zip = zip::ZipArchive::new(file).map_err(|e| err(&e))?;
    let mut xml = String::new();
    zip.by_name("modelDescription.xml")
        .map_err(|_| err(&"no modelDescription.xml at the archive's root"))?
        .read_to_string(&mut xml)
        .map_err(|e| err(&e))?;
    Ok(xml)
}

/// The FMUs of a system, by the name its components give them (`fmu`).
pub type Fmus = BTreeMap<String, FmuDescription>;

/// A parameter or start value, typed by the variable it sets.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Real(f64),
    Integer(i32),
    Boolean(bool),
    String(String),
    /// An item of an Enumeration: its value (what fmi2SetInteger sets) and its name.
    Enumeration {
        value: i32,
        item: String,
    },
}

impl Value {
    pub fn var_type(&self) -> VarType {
        match self {
            Value::Real(_) => VarType::Real,
            Value::Integer(_) => VarType::Integer,
            Value::Boolean(_) => VarType::Boolean,
            Value::String(_) => VarType::String,
            Value::Enumeration { .. } => VarType::Enumeration,
        }
    }
}

/// A connection, with the type both its ends have.
#[derive(Debug, Clone, PartialEq)]
pub struct TypedConnection<'a> {
    pub connection: &'a Connection,
    pub var_type: VarType,
    /// For an Enumeration: its type (the same items at both ends).
    pub enumeration: Option<Enumeration>,
}

/// A system that has passed [`System::check`], its values typed by the FMUs' declarations.
#[derive(Debug, Clone, PartialEq)]
pub struct Checked<'a> {
    pub system: &'a System,
    /// For each component, in order: its parameters, in order, with their typed values.
    pub parameters: Vec<Vec<(&'a str, Value)>>,
    /// Every connection, in order.
    pub connections: Vec<TypedConnection<'a>>,
}

impl System {
    pub fn component(&self, name: &str) -> Option<&Component> {
        self.components.iter().find(|c| c.name == name)
    }

    pub(crate) fn component_names(&self) -> Vec<&str> {
        self.components.iter().map(|c| c.name.as_str()).collect()
    }

    /// `file: system 'name'`, the start of every error about the system.
    pub(crate) fn at(&self) -> String {
        format!("{}: system '{}'", self.file.display(), self.name)
    }

    /// Reads the description of every FMU the system names from `<dir>/<fmu>.fmu`: of FMI 2.0
    /// ([`Fmus`]) or of FMI 3.0 ([`crate::systems_fmi3::Fmus3`], from `<fmu-dir>/fmi3`).
    pub fn read_fmus<D: Description>(&self, dir: &Path) -> Result<BTreeMap<String, D>, String> {
        let mut fmus = BTreeMap::new();
        for c in &self.components {
            if !fmus.contains_key(&c.fmu) {
                let path = dir.join(format!("{}.fmu", c.fmu));
                let d = D::read(&path).map_err(|e| format!("{}: component '{}': {e}", self.at(), c.name))?;
                fmus.insert(c.fmu.clone(), d);
            }
        }
        Ok(fmus)
    }

    /// The FMU of `port`'s component and its declaration of `port.variable`.
    fn lookup<'f, D: Description>(
        &self,
        fmus: &'f BTreeMap<String, D>,
        port: &Port,
    ) -> Result<(&'f D, &'f D::Variable), String> {
        let c = self
            .component(&port.component)
            .ok_or_else(|| format!("{}: no component '{}'", self.at(), port.component))?;
        let fmu = fmus
            .get(&c.fmu)
            .ok_or_else(|| format!("{}: the description of {}.fmu was not read", self.at(), c.fmu))?;
        let v = fmu.find(&port.variable).ok_or_else(|| {
            format!(
                "{}: {port}: {}.fmu{} has no variable '{}' (it has: {})",
                self.at(),
                c.fmu,
                D::VERSION,
                port.variable,
                fmu.names().join(", ")
            )
        })?;
        Ok((fmu, v))
    }

    /// The check of either FMI version: each connection's ends looked up and judged by
    /// `connect` (which gives the connection its type), no input driven twice, each parameter's
    /// variable looked up and its value typed by `parameter` (given the component).
    pub(crate) fn check_with<'a, D: Description, C, V>(
        &'a self,
        fmus: &BTreeMap<String, D>,
        connect: impl Fn(&'a Connection, End<'_, D>, End<'_, D>) -> Result<C, String>,
        parameter: impl Fn(&Component, &Literal, End<'_, D>) -> Result<V, Refusal>,
    ) -> Result<(Vec<C>, Parameters<'a, V>), String> {
        let mut connections = Vec::new();
        for (i, c) in self.connections.iter().enumerate() {
            let from = self.lookup(fmus, &c.from)?;
            let to = self.lookup(fmus, &c.to)?;
            let typed = connect(c, from, to)?;
            if let Some(first) = self.connections[..i].iter().find(|d| d.to == c.to) {
                return Err(format!(
                    "{}: input {} is driven twice: by {} and by {}",
                    self.at(),
                    c.to,
                    first.from,
                    c.from
                ));
            }
            connections.push(typed);
        }
        let mut parameters = Vec::new();
        for c in &self.components {
            let mut typed = Vec::new();
            for p in &c.parameters {
                let port = Port {
                    component: c.name.clone(),
                    variable: p.name.clone(),
                };
                let value = parameter(c, &p.value, self.lookup(fmus, &port)?).map_err(|refusal| match refusal {
                    Refusal::Valueless { variable, why } => format!(
                        "{}: parameter {port}: {}.fmu's {variable} cannot be given a value: {why}",
                        self.at(),
                        c.fmu
                    ),
                    Refusal::Mistyped(why) => format!(
                        "{}: parameter {port} = {}: {}.fmu declares '{}' {why}",
                        self.at(),
                        p.value,
                        c.fmu,
                        p.name
                    ),
                })?;
                typed.push((p.name.as_str(), value));
            }
            parameters.push(typed);
        }
        Ok((connections, parameters))
    }

    /// Checks the system against the descriptions of its FMUs: every connection goes from an
    /// output to an input of the same type (for an Enumeration, of the same items), no input
    /// is driven twice, and every parameter names a variable that takes a start value
    /// ([`Variable::takes_start_value`]) and has a value of its type.
    pub fn check<'a>(&'a self, fmus: &Fmus) -> Result<Checked<'a>, String> {
        let connect = |c: &'a Connection, (ofmu, o): End<FmuDescription>, (ifmu, inp): End<FmuDescription>| {
            let (oe, ie) = (ofmu.enumeration_of(o), ifmu.enumeration_of(inp));
            let same_items = o.ty != VarType::Enumeration || oe.map(|e| &e.items) == ie.map(|e| &e.items);
            if o.causality != Causality::Output || inp.causality != Causality::Input || o.ty != inp.ty || !same_items {
                let describe = |v: &Variable, e: Option<&Enumeration>| match e {
                    Some(e) if v.ty == VarType::Enumeration => {
                        format!("{} Enumeration {}", v.causality.name(), describe(e))
                    }
                    _ => format!("{} {}", v.causality.name(), v.ty),
                };
                return Err(format!(
                    "{}: connection {c} must go from an output to an input of the same type: {} is {}, {} is {}",
                    self.at(),
                    c.from,
                    describe(o, oe),
                    c.to,
                    describe(inp, ie)
                ));
            }
            Ok(TypedConnection {
                connection: c,
                var_type: o.ty,
                enumeration: oe.filter(|_| o.ty == VarType::Enumeration).cloned(),
            })
        };
        let parameter = |_: &Component, literal: &Literal, (fmu, v): End<FmuDescription>| {
            if !v.takes_start_value() {
                let why = if v.causality == Causality::Input {
                    "it is an input (its value comes from its connection)"
                } else if v.variability == Variability::Constant {
                    "it is a constant"
                } else {
                    "it declares no start value"
                };
                let variable = format!("'{}'", v.name);
                return Err(Refusal::Valueless { variable, why });
            }
            typed_value(literal, v, fmu).map_err(Refusal::Mistyped)
        };
        let (connections, parameters) = self.check_with(fmus, connect, parameter)?;
        Ok(Checked {
            system: self,
            parameters,
            connections,
        })
    }
}

/// What checking a system asks of an FMU's description, of either FMI version.
pub trait Description: Sized {
    type Variable;
    /// How an error names the FMU's version after its file: "" or " (FMI 3.0)".
    const VERSION: &'static str;
    /// Reads the description from an `.fmu` archive.
    fn read(fmu: &Path) -> Result<Self, String>;
    /// The variable called `name`.
    fn find(&self, name: &str) -> Option<&Self::Variable>;
    /// The names of all variables, in order.
    fn names(&self) -> Vec<&str>;
}

impl Description for FmuDescription {
    type Variable = Variable;
    const VERSION: &'static str = "";
    fn read(fmu: &Path) -> Result<Self, String> {
        read_description(fmu)
    }
    fn find(&self, name: &str) -> Option<&Variable> {
        self.variable(name)
    }
    fn names(&self) -> Vec<&str> {
        self.variables.iter().map(|v| v.name.as_str()).collect()
    }
}

/// One end of a connection, or a parameter's variable: the FMU and its declaration.
pub(crate) type End<'f, D> = (&'f D, &'f <D as Description>::Variable);

/// For each component, in order: its parameters, in order, with their typed values.
pub(crate) type Parameters<'a, V> = Vec<Vec<(&'a str, V)>>;

/// Why a parameter's value is refused.
pub(crate) enum Refusal {
    /// The variable (`'name'`, perhaps with what it is) takes no value, for the reason `why`.
    Valueless { variable: String, why: &'static str },
    /// The value is not one of the variable's type; completes "declares 'v' ...".
    Mistyped(String),
}

/// `literal` as a value of `v`'s type; the error completes "declares 'v' ...".
fn typed_value(literal: &Literal, v: &Variable, fmu: &FmuDescription) -> Result<Value, String> {
    let mismatch = |want: &str| format!("{}, which takes {want}", v.ty);
    match (v.ty, literal) {
        (VarType::Real, Literal::Float(x)) => Ok(Value::Real(*x)),
        (VarType::Real, Literal::Integer(x)) => Ok(Value::Real(*x as f64)),
        (VarType::Real, _) => Err(mismatch("a number")),
        (VarType::Integer, Literal::Integer(x)) => i32::try_from(*x)
            .map(Value::Integer)
            .map_err(|_| format!("Integer, a 32-bit integer: {x} is out of range")),
        (VarType::Integer, _) => Err(mismatch("an integer")),
        (VarType::Boolean, Literal::Boolean(x)) => Ok(Value::Boolean(*x)),
        (VarType::Boolean, _) => Err(mismatch("true or false")),
        (VarType::String, Literal::String(s)) => Ok(Value::String(s.clone())),
        (VarType::String, _) => Err(mismatch("a string")),
        (VarType::Enumeration, Literal::Integer(_) | Literal::String(_)) => {
            let e = fmu
                .enumeration_of(v)
                .expect("FmuDescription::parse checks every declaredType");
            let item = e.items.iter().find(|(name, value)| match literal {
                Literal::Integer(x) => i64::from(*value) == *x,
                Literal::String(s) => name == s,
                _ => false,
            });
            item.map(|(name, value)| Value::Enumeration {
                value: *value,
                item: name.clone(),
            })
            .ok_or_else(|| format!("Enumeration {}, which has no item {literal}", describe(e)))
        }
        (VarType::Enumeration, _) => {
            let e = fmu
                .enumeration_of(v)
                .expect("FmuDescription::parse checks every declaredType");
            Err(format!(
                "Enumeration {}, which takes an item's value or name",
                describe(e)
            ))
        }
    }
}

/// What the tests of this crate share: the workspace's systems file and the descriptions of
/// its FMUs, from the committed `modelDescription/*.xml` (what fmu-build packages; no build
/// needed).
#[cfg(test)]
pub(crate) mod testing {
    use super::*;

    pub fn workspace_root() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
    }

    pub fn paper_systems() -> Systems {
        Systems::load(&workspace_root().join("holonomic/systems.toml")).unwrap_or_else(|e| panic!("{e}"))
    }

    pub fn xml(id: &str) -> String {
        let path = workspace_root().join("modelDescription").join(format!("{id}.xml"));
        std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    pub fn description(id: &str) -> FmuDescription {
        parse_description(&xml(id)).unwrap_or_else(|e| panic!("{id}: {e}"))
    }

    pub fn fmus() -> Fmus {
        ["Pendulum", "Controller", "DCMotor"]
            .into_iter()
            .map(|id| (id.to_owned(), description(id)))
            .collect()
    }

    /// Controller's description, whose `mode` is an Enumeration (LQR = 1, PID = 2, LQR_PID = 3).
    pub fn enumeration_controller_xml() -> String {
        let committed = xml("Controller");
        if committed.contains(r#"<Enumeration declaredType="ControlMode""#) {
            return committed.replace("ControlMode", "Mode");
        }
        let xml = committed.replacen(
            "  <LogCategories>",
            "  <TypeDefinitions>\n    <SimpleType name=\"Mode\">\n      <Enumeration>\n        \
             <Item name=\"LQR\" value=\"1\"/>\n        <Item name=\"PID\" value=\"2\"/>\n        \
             <Item name=\"LQR_PID\" value=\"3\"/>\n      </Enumeration>\n    </SimpleType>\n  \
             </TypeDefinitions>\n  <LogCategories>",
            1,
        );
        let integer = r#"<Integer min="1" max="3" start="1"/>"#;
        assert_eq!(
            xml.matches(integer).count(),
            1,
            "Controller.xml declares mode as expected"
        );
        xml.replace(integer, r#"<Enumeration declaredType="Mode" start="1"/>"#)
    }

    pub fn fmus_with_enumeration_mode() -> Fmus {
        let mut fmus = fmus();
        fmus.insert(
            "Controller".into(),
            parse_description(&enumeration_controller_xml()).unwrap_or_else(|e| panic!("{e}")),
        );
        fmus
    }

    /// `text` parsed as the systems file `test.toml`; its only system.
    pub fn one_system(text: &str) -> System {
        let s = Systems::parse(text, Path::new("test.toml")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.systems.len(), 1);
        s.systems.into_iter().next().unwrap()
    }

    /// A system of one Controller whose parameters are `parameters` (TOML inline table body).
    pub fn controller_with(parameters: &str) -> System {
        one_system(&format!(
            "[[system]]\nname = \"S\"\n[[system.component]]\nname = \"controller\"\nfmu = \"Controller\"\n\
             parameters = {{ {parameters} }}\n"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::testing::*;
    use super::*;

    #[test]
    fn the_paper_systems_check_against_their_fmus() {
        let systems = paper_systems();
        assert_eq!(systems.names(), ["PendulumLQR", "PendulumMotors", "NetworkedPendulum"]);
        // The networked pendulum is of FMI 3.0 FMUs: crate::systems_fmi3's tests check it.
        for s in systems.systems.iter().filter(|s| !s.is_fmi3()) {
            s.check(&fmus()).unwrap_or_else(|e| panic!("{e}"));
        }
    }

    #[test]
    fn the_paper_systems_hold_the_values_of_the_paper() {
        let systems = paper_systems();
        let motors = systems.get("PendulumMotors").unwrap();
        assert_eq!(motors.stop_time, Some(5.0));
        assert_eq!(motors.step_size, Some(1e-3));
        let checked = motors.check(&fmus()).unwrap();
        let controller = motors.components.iter().position(|c| c.name == "controller").unwrap();
        assert_eq!(
            checked.parameters[controller],
            [
                (
                    "mode",
                    Value::Enumeration {
                        value: 3,
                        item: "LQR_PID".into()
                    }
                ),
                ("gear_ratio", Value::Real(200.0)),
                ("motor_B", Value::Real(1e-6)),
                ("drives_motors", Value::Boolean(true)),
                ("J1", Value::Real(0.872)),
                ("J2", Value::Real(0.872)),
            ],
            "values typed by the declarations, in the file's order (not sorted)"
        );
        let pendulum = &checked.parameters[0];
        assert_eq!(
            pendulum,
            &[
                ("alpha1_0", Value::Real(0.1)),
                ("alpha2_0", Value::Real(-0.05)),
                ("J1", Value::Real(0.872)),
                ("J2", Value::Real(0.872))
            ]
        );
        let motor1 = motors.components.iter().position(|c| c.name == "motor1").unwrap();
        assert_eq!(
            checked.parameters[motor1][0],
            ("coupled", Value::Boolean(true)),
            "the loop selects the coupled motor (the default is the unloaded one)"
        );
        assert_eq!(motors.connections.len(), 10);
        assert_eq!(motors.connections[4].to_string(), "controller.U1 -> motor1.U");
    }

    /// Why the paper's system `name` is refused with the connection `extra` added (its own
    /// connections those `keep` keeps).
    fn refused_with_connection(name: &str, keep: impl Fn(&Connection) -> bool, extra: &str) -> String {
        let mut s = paper_systems().get(name).unwrap().clone();
        s.connections.retain(keep);
        s.connections.push(extra.parse().unwrap());
        s.check(&fmus()).unwrap_err()
    }

    #[test]
    fn a_connection_between_two_outputs_is_refused() {
        let e = refused_with_connection("PendulumLQR", |_| true, "controller.M1 -> pendulum.alpha1");
        assert!(
            e.contains("connection controller.M1 -> pendulum.alpha1")
                && e.contains("holonomic/systems.toml")
                && e.contains("'PendulumLQR'")
                && e.contains("pendulum.alpha1 is output Real"),
            "expected the file, the system and the bad connection named, got: {e}"
        );
    }

    #[test]
    fn a_connection_of_two_types_is_refused() {
        let e = refused_with_connection(
            "PendulumMotors",
            |c| c.to.to_string() != "pendulum.M1",
            "motor1.tau -> controller.drives_motors",
        );
        assert!(
            e.contains("motor1.tau -> controller.drives_motors") && e.contains("parameter Boolean"),
            "{e}"
        );
    }

    #[test]
    fn an_input_driven_twice_is_refused() {
        let e = refused_with_connection("PendulumLQR", |_| true, "pendulum.alpha2 -> controller.alpha1");
        assert!(
            e.contains("input controller.alpha1 is driven twice") && e.contains("pendulum.alpha2"),
            "{e}"
        );
    }

    #[test]
    fn a_parameter_of_the_wrong_type_is_refused() {
        for (value, takes) in [("1.5", "an item's value or name"), ("true", "an item's value or name")] {
            let e = controller_with(&format!("mode = {value}")).check(&fmus()).unwrap_err();
            assert!(
                e.starts_with("test.toml: system 'S': parameter controller.mode = ")
                    && e.contains("'mode' Enumeration")
                    && e.contains(takes),
                "expected file, system, component and variable named with the declared type, got: {e}"
            );
        }
        let e = controller_with("drives_motors = 1").check(&fmus()).unwrap_err();
        assert!(
            e.contains("controller.drives_motors = 1") && e.contains("Boolean"),
            "{e}"
        );
        let e = controller_with("gear_ratio = \"200\"").check(&fmus()).unwrap_err();
        assert!(
            e.contains("controller.gear_ratio") && e.contains("Real, which takes a number"),
            "{e}"
        );
        let e = controller_with("mode = 4294967296").check(&fmus()).unwrap_err();
        assert!(e.contains("has no item 4294967296"), "{e}");
    }

    #[test]
    fn an_integer_sets_a_real() {
        let s = controller_with("gear_ratio = 200");
        let checked = s.check(&fmus()).unwrap();
        assert_eq!(checked.parameters[0], [("gear_ratio", Value::Real(200.0))]);
    }

    #[test]
    fn an_input_an_unknown_variable_and_a_calculated_value_take_no_value() {
        let e = controller_with("alpha1 = 0.1").check(&fmus()).unwrap_err();
        assert!(e.contains("controller.alpha1") && e.contains("it is an input"), "{e}");
        let e = controller_with("torque = 1.0").check(&fmus()).unwrap_err();
        assert!(
            e.contains("controller.torque")
                && e.contains("Controller.fmu has no variable 'torque'")
                && e.contains("gear_ratio"),
            "expected the variables there are listed: {e}"
        );
        // K11 is a calculatedParameter: no start value to give.
        let e = controller_with("K11 = 1.0").check(&fmus()).unwrap_err();
        assert!(
            e.contains("controller.K11") && e.contains("declares no start value"),
            "{e}"
        );
    }

    #[test]
    fn an_enumeration_takes_an_item_value_or_name() {
        let fmus = fmus_with_enumeration_mode();
        let lqr_pid = Value::Enumeration {
            value: 3,
            item: "LQR_PID".into(),
        };
        for literal in ["3", "\"LQR_PID\""] {
            let s = controller_with(&format!("mode = {literal}"));
            let checked = s.check(&fmus).unwrap();
            assert_eq!(checked.parameters[0], [("mode", lqr_pid.clone())]);
        }
        for (literal, why) in [
            ("4", "has no item 4"),
            ("\"MPC\"", "has no item \"MPC\""),
            ("1.0", "takes an item's value or name"),
        ] {
            let e = controller_with(&format!("mode = {literal}")).check(&fmus).unwrap_err();
            assert!(
                e.contains("controller.mode")
                    && e.contains("Enumeration Mode (LQR = 1, PID = 2, LQR_PID = 3)")
                    && e.contains(why),
                "expected the items listed: {e}"
            );
        }
    }

    #[test]
    fn an_unknown_system_is_reported_with_the_names_there_are() {
        let e = paper_systems().get("Nope").unwrap_err();
        assert!(
            e.contains("'Nope'") && e.contains("PendulumLQR, PendulumMotors") && e.contains("holonomic/systems.toml"),
            "expected the unknown name and the list of systems, got: {e}"
        );
    }

    #[test]
    fn a_step_size_that_is_not_positive_and_finite_is_refused() {
        for bad in ["0.0", "-1e-3", "inf", "nan"] {
            let text = format!("[[system]]\nname = \"S\"\nstep-size = {bad}\n");
            let e = Systems::parse(&text, Path::new("bad.toml")).unwrap_err();
            assert!(
                e.contains("system 'S'") && e.contains("step-size") && e.contains("finite and > 0"),
                "step-size = {bad}: {e}"
            );
        }
        let ok = Systems::parse("[[system]]\nname = \"S\"\nstep-size = 1e-3\n", Path::new("ok.toml")).unwrap();
        assert_eq!(ok.systems[0].step_size, Some(1e-3));
    }

    #[test]
    fn malformed_toml_reports_file_and_line() {
        let text =
            "[[system]]\nname = \"S\"\nstop-time = 5.0\n\n[[system.component]]\nname = \"c\"\nfmu = Controller\n";
        let e = Systems::parse(text, Path::new("dir/bad.toml")).unwrap_err();
        assert!(
            e.starts_with("dir/bad.toml:7:7: "),
            "expected file:line:column, got: {e}"
        );
        let e = Systems::parse("[[system]]\nname = \"S\"\nstoptime = 5\n", Path::new("bad.toml")).unwrap_err();
        assert!(
            e.starts_with("bad.toml:3:") && e.contains("stoptime") && e.contains("stop-time"),
            "an unknown key is an error with its line: {e}"
        );
        let e = Systems::parse(
            "[[system]]\nname = \"S\"\nconnections = [\n  \"a.x -> b.y\",\n  \"a.x => b.y\",\n]\n",
            Path::new("bad.toml"),
        )
        .unwrap_err();
        assert!(
            e.starts_with("bad.toml:5:") && e.contains("'a.x => b.y' must read 'component.output -> component.input'"),
            "a malformed connection is reported with its line: {e}"
        );
        let e = Systems::load(Path::new("/nonexistent/systems.toml")).unwrap_err();
        assert!(e.starts_with("/nonexistent/systems.toml: "), "{e}");
    }

    #[test]
    fn names_are_checked_when_the_file_is_read() {
        let parse = |t: &str| Systems::parse(t, Path::new("t.toml")).unwrap_err();
        let e = parse(
            "[[system]]\nname = \"S\"\nconnections = [\"a.x -> b.y\"]\n[[system.component]]\nname = \"a\"\nfmu = \"A\"\n",
        );
        assert!(
            e.contains("system 'S'") && e.contains("a.x -> b.y") && e.contains("'b' (there are: a)"),
            "{e}"
        );
        let e = parse("[[system]]\nname = \"S\"\n[[system]]\nname = \"S\"\n");
        assert!(e.contains("two systems are named 'S'"), "{e}");
        let e = parse("[[system]]\nname = \"S\"\n[[system.component]]\nname = \"a.b\"\nfmu = \"A\"\n");
        assert!(e.contains("'a.b' must be non-empty and without '.'"), "{e}");
        let e = parse(
            "[[system]]\nname = \"S\"\n[[system.component]]\nname = \"a\"\nfmu = \"A\"\n[[system.component]]\nname = \"a\"\nfmu = \"B\"\n",
        );
        assert!(e.contains("two components are named 'a'"), "{e}");
    }

    #[test]
    fn a_connection_is_split_at_the_first_dot_of_each_end() {
        let c: Connection = " plant.body.x -> ctl.in.x ".parse().unwrap();
        assert_eq!(
            (c.from.component.as_str(), c.from.variable.as_str()),
            ("plant", "body.x")
        );
        assert_eq!((c.to.component.as_str(), c.to.variable.as_str()), ("ctl", "in.x"));
        for bad in ["a.x", "a -> b.y", "a.x -> .y", "a.x -> b.y -> c.z"] {
            assert!(bad.parse::<Connection>().is_err(), "'{bad}' must be refused");
        }
    }

    #[test]
    fn the_workspace_names_its_systems_file() {
        let root = workspace_root();
        assert_eq!(workspace_files(&root).unwrap(), [root.join("holonomic/systems.toml")]);
    }

    #[test]
    fn a_missing_fmu_is_reported_with_the_command_that_packages_it() {
        let s = paper_systems().get("PendulumLQR").unwrap().clone();
        let e = s.read_fmus::<FmuDescription>(Path::new("/nonexistent")).unwrap_err();
        assert!(
            e.contains("component 'pendulum'")
                && e.contains("/nonexistent/Pendulum.fmu")
                && e.contains("cargo run --release -p fmu-build"),
            "{e}"
        );
    }
}
