//! One FMU, loaded through the runner's importers ([`crate::fmi2`], [`crate::fmi3`]: an archive
//! unpacked into a temporary folder it removes again, or a folder already unpacked), with its
//! variables by name (an FMI 3.0 FMU's as the FMI 2.0 ones they are: [`crate::fmi3::as_fmi2`]).

use crate::Error;
use crate::fmi2::Fmi2Import;
use crate::fmi3::Fmi3Import;
use crate::instance::InstanceCS;
use md_reader::Causality;
use md_reader::fmi2::{ModelDescription as Description, Type, Variable};
use std::io::{Cursor, Read};

pub use md_reader::fmi2::Type as VarType;

/// The importer of an FMU's version.
pub enum Import {
    V2(Fmi2Import),
    V3(Fmi3Import),
}

/// What an FMI 3.0 description adds to the FMI 2.0 view of it (nothing for FMI 2.0).
#[derive(Default)]
struct Extra {
    skipped: Vec<(String, String)>,
    /// The input clocks the runner ticks ([`crate::fmi3::ClockPlan`]).
    clocks: Option<crate::fmi3::ClockPlan>,
    typed: Vec<crate::fmi3::Var3>,
    /// The inputs of every type with direct feedthrough.
    feedthrough: Vec<u32>,
    /// The number of continuous states (None: the FMI 2.0 view's derivatives).
    states: Option<usize>,
    has_event_mode: bool,
    /// The `<ScheduledExecution>` modelIdentifier (None: no Scheduled Execution).
    scheduled_execution: Option<String>,
    /// See [`Fmu::intermediate`].
    intermediate: Option<Vec<u32>>,
}

pub struct Fmu {
    /// Where it came from ("resources/Pendulum.fmu" of an SSP file, or a path).
    pub label: String,
    /// FMI 2.0's, or an FMI 3.0 FMU's read as FMI 2.0's.
    pub description: Description,
    pub import: Import,
    /// An FMI 3.0 FMU's variables the runner does not read (clocks, clocked variables):
    /// (name, what).
    pub skipped: Vec<(String, String)>,
    /// An FMI 3.0 FMU's variables of every type, scalars and arrays, as typed calls get and set
    /// them (empty for FMI 2.0).
    pub typed: Vec<crate::fmi3::Var3>,
    /// The number of continuous states (FMI 3.0: an array derivative counts its elements).
    pub states: usize,
    /// Value references of the inputs some output depends on directly (ModelStructure/Outputs
    /// `dependencies`; an output without the attribute depends on every input, as in fmpy).
    pub feedthrough: Vec<u32>,
    /// FMI 3.0 `<CoSimulation hasEventMode>` (false for FMI 2.0).
    pub has_event_mode: bool,
    /// FMI 3.0: the modelIdentifier of its `<ScheduledExecution>` (None: it has none; FMI 2.0).
    pub scheduled_execution: Option<String>,
    /// FMI 3.0 `<CoSimulation providesIntermediateUpdate="true">`: the scalar Float64 variables
    /// with `intermediateUpdate="true"` (None: no intermediate update; FMI 2.0).
    pub intermediate: Option<Vec<u32>>,
}

impl Fmu {
    /// Loads the FMU archive `bytes`; `component` names it in errors.
    pub fn from_bytes(component: &str, label: &str, bytes: Vec<u8>) -> Result<Fmu, Error> {
        let fail = |what: String| Error {
            component: Some(component.to_owned()),
            ..Error::io(format!("component '{component}' ({label}): {what}"))
        };
        let mut zip =
            zip::ZipArchive::new(Cursor::new(&bytes)).map_err(|e| fail(format!("not an FMU (zip) archive: {e}")))?;
        let mut xml = String::new();
        zip.by_name("modelDescription.xml")
            .map_err(|e| fail(format!("no modelDescription.xml: {e}")))?
            .read_to_string(&mut xml)
            .map_err(|e| fail(format!("modelDescription.xml: {e}")))?;
        let (description, int64, extra) = Fmu::description(component, label, &xml)?;
        let import = match int64 {
            None => Fmi2Import::from_bytes(&bytes, description.model_identifier(), &description.guid).map(Import::V2),
            Some(int64) => {
                Fmi3Import::from_bytes(&bytes, Fmu::identifier(&description, &extra), &description.guid, int64)
                    .and_then(|i| i.with_clocks(extra.clocks.clone()))
                    .map(Import::V3)
            }
        }
        .map_err(|e| fail(format!("cannot import: {e}")))?;
        Fmu::with(component, label, description, import, extra)
    }

    /// Loads the FMU unpacked in the folder `dir` (a container's components).
    pub fn from_dir(component: &str, label: &str, dir: &std::path::Path) -> Result<Fmu, Error> {
        let fail = |what: String| Error {
            component: Some(component.to_owned()),
            ..Error::io(format!("component '{component}' ({label}): {what}"))
        };
        let path = dir.join("modelDescription.xml");
        let xml = std::fs::read_to_string(&path).map_err(|e| fail(format!("{}: {e}", path.display())))?;
        let (description, int64, extra) = Fmu::description(component, label, &xml)?;
        let import = match int64 {
            None => Fmi2Import::from_dir(dir, description.model_identifier(), &description.guid).map(Import::V2),
            Some(int64) => Fmi3Import::from_dir(dir, Fmu::identifier(&description, &extra), &description.guid, int64)
                .and_then(|i| i.with_clocks(extra.clocks.clone()))
                .map(Import::V3),
        }
        .map_err(|e| fail(format!("cannot import: {e}")))?;
        Fmu::with(component, label, description, import, extra)
    }

    /// The description of `xml`, checked to be one of an FMI 2.0 or 3.0 co-simulation FMU; for
    /// FMI 3.0 also the value references read with fmi3GetInt64 and what its view adds.
    fn description(
        component: &str,
        label: &str,
        xml: &str,
    ) -> Result<(Description, Option<std::collections::HashSet<u32>>, Extra), Error> {
        let fail = |what: String| Error {
            component: Some(component.to_owned()),
            ..Error::io(format!("component '{component}' ({label}): {what}"))
        };
        let version = md_reader::fmi_version(xml).map_err(fail)?;
        let (description, int64, extra) = if version.starts_with("3.") {
            let d3 = md_reader::fmi3::ModelDescription::parse(xml).map_err(fail)?;
            let parts = crate::fmi3::as_fmi2(&d3);
            let extra = Extra {
                skipped: parts.skipped,
                clocks: parts.clocks,
                typed: parts.typed,
                feedthrough: parts.feedthrough,
                states: Some(parts.states),
                has_event_mode: parts.has_event_mode,
                scheduled_execution: d3
                    .se_interface
                    .as_ref()
                    .map(|i| i.model_identifier.clone())
                    .filter(|_| d3.se),
                intermediate: d3.cs.as_ref().filter(|cs| cs.provides_intermediate_update).map(|_| {
                    d3.variables
                        .iter()
                        .filter(|v| v.intermediate_update && v.ty == md_reader::fmi3::Type::Float64 && !v.array)
                        .map(|v| v.vr)
                        .collect()
                }),
            };
            (parts.description, Some(parts.int64), extra)
        } else if version.starts_with("2.") {
            (Description::parse(xml).map_err(fail)?, None, Extra::default())
        } else {
            return Err(Error::unsupported(
                Some(component),
                None,
                format!(
                    "component '{component}' ({label}): an FMI {version} FMU; the runner runs FMI 2.0 and 3.0 co-simulation FMUs"
                ),
            ));
        };
        if description.cs.is_none() && description.me.is_none() && extra.scheduled_execution.is_none() {
            return Err(Error::unsupported(
                Some(component),
                None,
                format!(
                    "component '{component}' ({label}): neither a co-simulation nor a model-exchange FMU (scheduled execution only)"
                ),
            ));
        }
        Ok((description, int64, extra))
    }

    fn with(
        component: &str,
        label: &str,
        description: Description,
        import: Import,
        extra: Extra,
    ) -> Result<Fmu, Error> {
        let fail = |what: String| Error {
            component: Some(component.to_owned()),
            ..Error::io(format!("component '{component}' ({label}): {what}"))
        };
        let mut feedthrough = Vec::new();
        let inputs: Vec<&Variable> = description
            .variables
            .iter()
            .filter(|v| v.causality == Causality::Input)
            .collect();
        for output in &description.model_structure.outputs {
            match &output.dependencies {
                None => feedthrough.extend(inputs.iter().map(|v| v.vr)),
                Some(deps) => {
                    for d in deps {
                        let v = description.by_index(*d).ok_or_else(|| {
                            fail(format!("ModelStructure names variable index {d}, which does not exist"))
                        })?;
                        if v.causality == Causality::Input {
                            feedthrough.push(v.vr);
                        }
                    }
                }
            }
        }
        // FMI 3.0: the inputs of every type (FMI 2.0's view keeps only its own types).
        feedthrough.extend(&extra.feedthrough);
        feedthrough.sort_unstable();
        feedthrough.dedup();
        let states = extra.states.unwrap_or(description.model_structure.derivatives.len());
        Ok(Fmu {
            label: label.to_owned(),
            states,
            description,
            import,
            skipped: extra.skipped,
            typed: extra.typed,
            feedthrough,
            has_event_mode: extra.has_event_mode,
            scheduled_execution: extra.scheduled_execution,
            intermediate: extra.intermediate,
        })
    }

    /// The model identifier of the binary to load: co-simulation's, model exchange's, or
    /// Scheduled Execution's for an FMU that offers only that.
    fn identifier<'a>(description: &'a Description, extra: &'a Extra) -> &'a str {
        match description.model_identifier() {
            "" => extra.scheduled_execution.as_deref().unwrap_or(""),
            id => id,
        }
    }

    /// Loads the FMU file at `path`.
    pub fn from_path(component: &str, path: &std::path::Path) -> Result<Fmu, Error> {
        let bytes = std::fs::read(path).map_err(|e| Error {
            component: Some(component.to_owned()),
            ..Error::io(format!("component '{component}': cannot read {}: {e}", path.display()))
        })?;
        Fmu::from_bytes(component, &path.display().to_string(), bytes)
    }

    pub fn model_identifier(&self) -> &str {
        match self.description.model_identifier() {
            "" => self.scheduled_execution.as_deref().unwrap_or(""),
            id => id,
        }
    }

    /// Whether it runs only in Scheduled Execution (FMI 3.0: neither co-simulation nor model exchange).
    pub fn scheduled_execution_only(&self) -> bool {
        self.description.cs.is_none() && self.description.me.is_none() && self.scheduled_execution.is_some()
    }

    /// Its FMI 3.0 importer, if the FMU offers Scheduled Execution in the binary loaded; else
    /// why not.
    fn scheduled_import(&self, component: &str) -> Result<&Fmi3Import, Error> {
        let fail = |why: String| {
            Error::unsupported(
                Some(component),
                None,
                format!(
                    "component '{component}' ({}): no Scheduled Execution: {why}",
                    self.model_identifier()
                ),
            )
        };
        let i = match &self.import {
            Import::V2(_) => return Err(fail("an FMI 2.0 FMU (Scheduled Execution is FMI 3.0's)".into())),
            Import::V3(i) => i,
        };
        match &self.scheduled_execution {
            None => return Err(fail("its modelDescription.xml has no <ScheduledExecution>".into())),
            Some(id) if id != self.model_identifier() => {
                return Err(fail(format!(
                    "its <ScheduledExecution> modelIdentifier '{id}' is another binary than the one loaded ('{}')",
                    self.model_identifier()
                )));
            }
            Some(_) => {}
        }
        Ok(i)
    }

    /// An instance for Scheduled Execution (FMI 3.0, chapter 5: `fmi3/scheduled.rs`), or why
    /// the FMU has none.
    pub fn instantiate_scheduled(&self, component: &str) -> Result<InstanceCS, Error> {
        self.scheduled_import(component)?
            .instantiate_scheduled(component)
            .map(InstanceCS::V3)
            .map_err(|e| Error {
                component: Some(component.to_owned()),
                function: Some("fmi3InstantiateScheduledExecution".into()),
                ..Error::new(
                    crate::ErrorKind::Fmi,
                    format!(
                        "component '{component}' ({}): fmi3InstantiateScheduledExecution failed: {e}",
                        self.model_identifier()
                    ),
                )
            })
    }

    /// The FMI 3.0 variable `name` as typed calls get and set it (None: an FMI 2.0 FMU, or no
    /// such variable).
    pub fn var3(&self, name: &str) -> Option<&crate::fmi3::Var3> {
        self.typed.iter().find(|v| v.name == name)
    }

    /// The variable `name`; the error names the component and lists the variables there are.
    pub fn variable(&self, component: &str, name: &str) -> Result<&Variable, Error> {
        self.description
            .variables
            .iter()
            .find(|v| v.name == name)
            .ok_or_else(|| {
                if let Some((_, ty)) = self.skipped.iter().find(|(n, _)| n == name) {
                    return Error::unsupported(
                        Some(component),
                        Some(name),
                        format!(
                            "component '{component}' ({}): '{name}' is an FMI 3.0 {ty}: the runner does not set, read or record it (a Clock is connected only to a Clock, by a clock connection; runner/README.md, FMI 3.0)",
                            self.model_identifier()
                        ),
                    );
                }
                let mut names: Vec<&str> = self.description.variables.iter().map(|v| v.name.as_str()).collect();
                for v in &self.typed {
                    if !names.contains(&v.name.as_str()) {
                        names.push(&v.name);
                    }
                }
                Error::variable(
                    component,
                    name,
                    format!(
                        "component '{component}' ({}): no variable '{name}' in its modelDescription.xml; it has: {}",
                        self.model_identifier(),
                        names.join(", ")
                    ),
                )
            })
    }

    /// A co-simulation instance.
    pub fn instantiate(&self, component: &str) -> Result<InstanceCS, Error> {
        let (function, r) = match &self.import {
            Import::V2(i) => (
                "fmi2Instantiate",
                i.instantiate_cs(component, false, false).map(InstanceCS::V2),
            ),
            Import::V3(i) => (
                "fmi3InstantiateCoSimulation",
                i.instantiate_cs(component, false, false).map(InstanceCS::V3),
            ),
        };
        r.map_err(|e: String| Error {
            component: Some(component.to_owned()),
            function: Some(function.into()),
            ..Error::new(
                crate::ErrorKind::Fmi,
                format!(
                    "component '{component}' ({}): {function} failed: {e}",
                    self.model_identifier()
                ),
            )
        })
    }

    /// A co-simulation instance with eventModeUsed and earlyReturnAllowed (FMI 3.0, hasEventMode):
    /// the events it reports are handled in Event Mode and its early returns end every
    /// component's step there (`sim/clocks.rs`).
    pub fn instantiate_events(&self, component: &str) -> Result<InstanceCS, Error> {
        self.event_mode_import(component)?
            .instantiate_cs_events(component)
            .map(InstanceCS::V3)
            .map_err(|e| Error {
                component: Some(component.to_owned()),
                function: Some("fmi3InstantiateCoSimulation".into()),
                ..Error::new(
                    crate::ErrorKind::Fmi,
                    format!(
                        "component '{component}' ({}): fmi3InstantiateCoSimulation failed: {e}",
                        self.model_identifier()
                    ),
                )
            })
    }

    /// The FMI 3.0 import of an FMU whose co-simulation has Event Mode, or why it has none.
    fn event_mode_import(&self, component: &str) -> Result<&Fmi3Import, Error> {
        let fail = |why: &str| {
            Err(Error::unsupported(
                Some(component),
                None,
                format!(
                    "component '{component}' ({}): no event mode: {why}",
                    self.model_identifier()
                ),
            ))
        };
        match &self.import {
            Import::V3(_) if !self.has_event_mode => fail("its <CoSimulation> does not say hasEventMode=\"true\""),
            Import::V3(i) => Ok(i),
            Import::V2(_) => fail("an FMI 2.0 FMU has no Event Mode in co-simulation"),
        }
    }

    /// A co-simulation instance with the intermediateUpdate callback reading `vrs` (FMI 3.0,
    /// `fmi3/intermediate.rs`); with eventModeUsed and earlyReturnAllowed where `events`.
    pub fn instantiate_intermediate(&self, component: &str, vrs: &[u32], events: bool) -> Result<InstanceCS, Error> {
        let fail = |e: String| Error {
            component: Some(component.to_owned()),
            function: Some("fmi3InstantiateCoSimulation".into()),
            ..Error::new(
                crate::ErrorKind::Fmi,
                format!(
                    "component '{component}' ({}): fmi3InstantiateCoSimulation with an intermediateUpdate callback failed: {e}",
                    self.model_identifier()
                ),
            )
        };
        match &self.import {
            Import::V3(i) => i
                .instantiate_cs_intermediate(component, vrs, events)
                .map(InstanceCS::V3)
                .map_err(fail),
            Import::V2(_) => Err(fail("an FMI 2.0 FMU has no intermediate update".into())),
        }
    }

    /// A model-exchange instance the runner integrates (FMI 2.0 FMUs with `<ModelExchange>`).
    pub fn instantiate_me(&self, component: &str) -> Result<InstanceCS, Error> {
        let fail = |m: String| Error {
            component: Some(component.to_owned()),
            function: Some("fmi2Instantiate".into()),
            ..Error::new(
                crate::ErrorKind::Unsupported,
                format!("component '{component}' ({}): {m}", self.model_identifier()),
            )
        };
        if self.description.me.is_none() {
            return Err(fail("no <ModelExchange> in its modelDescription.xml".into()));
        }
        if matches!(&self.import, Import::V3(i) if i.has_clocks()) {
            return Err(fail(
                "it has input clocks: the runner ticks them in co-simulation only (run it as co-simulation)".into(),
            ));
        }
        let nx = self.states;
        let nz = self.description.number_of_event_indicators;
        let inner = match &self.import {
            Import::V2(import) => import
                .instantiate_me(component, false, false)
                .map(crate::me::MeInner::V2)
                .map_err(|e| fail(format!("fmi2Instantiate(fmi2ModelExchange) failed: {e}")))?,
            Import::V3(import) => import
                .instantiate_me(component, false, false)
                .map(crate::me::MeInner::V3)
                .map_err(|e| fail(format!("fmi3InstantiateModelExchange failed: {e}")))?,
        };
        Ok(InstanceCS::Me(crate::me::MeInstance::new(inner, nx, nz)))
    }

    /// An instance in a child process of its own ([`crate::isolate`]), instantiated there for
    /// `interface` (model exchange: integrated by the runner in the child).
    pub fn instantiate_isolated(
        &self,
        component: &str,
        interface: crate::isolate::Interface,
        isolation: &crate::isolate::Isolation,
    ) -> Result<InstanceCS, Error> {
        // The in-process refusals, with their reasons.
        match interface {
            crate::isolate::Interface::EventMode => {
                self.event_mode_import(component)?;
            }
            crate::isolate::Interface::ScheduledExecution => {
                self.scheduled_import(component)?;
            }
            crate::isolate::Interface::ModelExchange if self.description.me.is_none() => {
                return self.instantiate_me(component);
            }
            _ => {}
        }
        #[cfg(target_os = "linux")]
        {
            let dir = match &self.import {
                Import::V2(i) => i.dir(),
                Import::V3(i) => i.dir(),
            };
            crate::isolate::Isolated::spawn(isolation, component, &self.label, dir, interface)
                .map(|i| InstanceCS::Isolated(Box::new(i)))
        }
        #[cfg(not(target_os = "linux"))]
        {
            let _ = (interface, isolation);
            Err(Error::unsupported(
                Some(component),
                None,
                format!("component '{component}': isolation (a child process per component) runs on Linux only"),
            ))
        }
    }

    /// The FMI version of the FMU, "2.0" or "3.0".
    pub fn fmi_version(&self) -> &'static str {
        match self.import {
            Import::V2(_) => "2.0",
            Import::V3(_) => "3.0",
        }
    }
}

/// The FMI 2.0 name of a variable type.
pub fn type_name(t: Type) -> &'static str {
    t.name()
}
