//! SSP 1.0 archives of composed systems: `<out_dir>/<system>.ssp` holding
//! `SystemStructure.ssd` and the system's FMUs under `resources/`; and SSP 2.0 for the FMI 3.0
//! archive (`<out_dir>/fmi3/<system>.ssp`) of a system that asks for it (`ssp-version = "2.0"`).
//!
//! SSP 2.0 keeps SSP 1.0's namespaces; the SSD says `version="2.0"` (and its parameter sets
//! too), its connectors and parameter values take the FMI 3.0 types of the FMI 3.0 twins'
//! variables: a Real of the FMI 2.0 description is a Float64 of the FMI 3.0 one, an Integer an
//! Int32 (what `cargo fmu build` makes of one declaration), a Boolean, String or Enumeration the
//! same; an Enumeration parameter is written as SSP 1.0 writes it (`ssv:Integer`, which SSP 2.0
//! keeps).
//!
//! A system of FMI 3.0 FMUs (`fmi-version = "3.0"`, [`crate::systems_fmi3`]) is written in SSP
//! 2.0 only, to `<out_dir>/fmi3/<system>.ssp` with its FMUs of `<fmu_dir>/fmi3/`, checked
//! against their FMI 3.0 descriptions: its connectors take the FMUs' own types (`ssc:Float64`,
//! `ssc:Int32`, ..., `ssc:Binary` with the variable's `mime-type`, `ssc:Clock`) and the
//! variables' causalities as their kinds (a countdown Tx_Clock that starts a clock connection
//! is an `input` connector), its parameter values `ssv:<type>` (a Binary as hexadecimal digits).
//! There SSP 2.0's own forms are written, as its schemas define them: an Enumeration connector
//! `ssc:Enumeration` naming a type of `ssd:Enumerations`, an Enumeration value
//! `ssv:Enumeration value="<item name>"`, an array connector or value with its `ssc:Dimension`s
//! (a connector's `sizeConnector` the structural parameter that sets its size, a connector of
//! the component too), an array of numbers or Booleans as a list in `value` (row-major), an
//! array of Strings, Binaries or Enumerations as `ssv:Value` elements.
//!
//! A system comes from a systems file ([`crate::systems`]); the SSD is generated from it after
//! [`System::check`] has checked it against the packaged FMUs' modelDescription.xml (every
//! connection goes from an output to an input of the same type, every parameter exists, takes
//! a start value and has a value of its type). Only the packaged FMUs are read, as any
//! importer reads them.
//!
//! What the importers this project runs (fmpy.ssp, libcosim, Ecos, OMSimulator) need:
//! - every connection names its `startElement` and `endElement` (libcosim's SSP reader needs
//!   both; no system-level connectors are used);
//! - parameter values are inline `ssd:ParameterValues`, one `ssv:ParameterSet` per component,
//!   every one named after the system: libcosim applies a component's first set by default,
//!   Ecos merges the sets of one name into one and applies one set, by name, per run
//!   (`init(parameter_set="<system>")`), so one name gives it every component's values;
//! - OMSimulator's own annotation, `oms:SimulationInformation`, in `ssd:System` (a fixed-step
//!   master at the system's step size) and in `ssd:DefaultExperiment` (its result file): its
//!   command line stops with "internal error" without them;
//! - an Enumeration parameter is written as `ssv:Integer` with the item's value. SSP's own
//!   form, `ssv:Enumeration value="<item name>"`, makes libcosim (libcosimpy 0.0.6) abort the
//!   process while parsing the SSD (its parser panics on `ssv:Enumeration`) and fmpy 0.3
//!   (`simulate_ssp`) fail with `int('<item name>')`; fmpy applies `ssv:Integer` to an
//!   Enumeration variable through fmi2SetInteger. (libcosim ignores FMI 2.0 Enumeration
//!   variables altogether, so no form reaches them there.)
//! - a connection of Enumerations has `ssc:Enumeration` connectors naming a type of the SSD's
//!   `ssd:Enumerations`, as SSP defines it (fmpy accepts it; libcosim has no Enumeration
//!   connectors and aborts on them).

use crate::systems::{Checked, Fmus, System, Systems, Value};
use crate::systems_fmi3::{Checked3, Fmus3, Size, Type3, Value3};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use zip::write::SimpleFileOptions;

/// OMSimulator's namespace (of its `oms:SimulationInformation` annotations).
const OMS_NS: &str = "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd";

fn escape(s: &str) -> String {
    quick_xml::escape::escape(s).into_owned()
}

/// The SSV element and value text of a parameter value (`v2`: SSP 2.0's FMI 3.0 types).
fn ssv_value(v: &Value, v2: bool) -> (&'static str, String) {
    match v {
        Value::Real(x) => (if v2 { "Float64" } else { "Real" }, format!("{x:?}")),
        Value::Integer(x) => (if v2 { "Int32" } else { "Integer" }, x.to_string()),
        Value::Boolean(x) => ("Boolean", x.to_string()),
        Value::String(s) => ("String", escape(s)),
        // See the module's documentation: the importers take an Enumeration as an Integer.
        Value::Enumeration { value, .. } => ("Integer", value.to_string()),
    }
}

/// `SystemStructure.ssd` of a system, after checking it against its FMUs' descriptions.
pub fn ssd(system: &System, fmus: &Fmus) -> Result<String, String> {
    Ok(ssd_of_checked(&system.check(fmus)?))
}

/// `SystemStructure.ssd` of a system in SSP 2.0 (of its FMI 3.0 FMUs), after checking it
/// against its FMUs' (FMI 2.0) descriptions.
pub fn ssd2(system: &System, fmus: &Fmus) -> Result<String, String> {
    Ok(write_ssd(&system.check(fmus)?, true))
}

/// `SystemStructure.ssd` of a checked system.
pub fn ssd_of_checked(checked: &Checked) -> String {
    write_ssd(checked, false)
}

/// The SSD connector type of an FMI 2.0 type (`v2`: its FMI 3.0 twin's).
fn connector_type(t: crate::systems::VarType, v2: bool) -> &'static str {
    use crate::systems::VarType;
    match (t, v2) {
        (VarType::Real, true) => "Float64",
        (VarType::Integer, true) => "Int32",
        (t, _) => t.name(),
    }
}

/// What an SSD says of a system's components: each one's connectors (variable, kind, the
/// connector's content: its type element and dimensions) and parameter values (variable, the
/// `ssv:Parameter`'s content), the Enumeration types (name, items) its connections and
/// parameters carry, and the SSP version.
struct Layout<'a> {
    system: &'a System,
    version: &'static str,
    connectors: Vec<Vec<(&'a str, &'static str, String)>>,
    parameters: Vec<Vec<(&'a str, String)>>,
    enumerations: Vec<(String, Vec<(String, i64)>)>,
}

impl<'a> Layout<'a> {
    fn new(system: &'a System, version: &'static str) -> Layout<'a> {
        let n = system.components.len();
        Layout {
            system,
            version,
            connectors: vec![Vec::new(); n],
            parameters: vec![Vec::new(); n],
            enumerations: Vec::new(),
        }
    }

    /// An Enumeration type of the SSD's `ssd:Enumerations`, the first time one names it.
    fn enumeration(&mut self, name: &str, items: Vec<(String, i64)>) {
        if !self.enumerations.iter().any(|(n, _)| n == name) {
            self.enumerations.push((name.to_owned(), items));
        }
    }

    /// The connector `variable` of `component`, the first time a connection names it.
    fn connector(&mut self, component: &str, variable: &'a str, kind: &'static str, type_element: &str) {
        let k = self
            .system
            .components
            .iter()
            .position(|comp| comp.name == component)
            .expect("checked by System::check");
        if !self.connectors[k].iter().any(|(n, _, _)| *n == variable) {
            self.connectors[k].push((variable, kind, type_element.to_owned()));
        }
    }
}

/// `SystemStructure.ssd` of a checked system, SSP 1.0 or (`v2`) 2.0.
fn write_ssd(checked: &Checked, v2: bool) -> String {
    let system = checked.system;
    let mut layout = Layout::new(system, if v2 { "2.0" } else { "1.0" });
    for tc in &checked.connections {
        let c = tc.connection;
        let type_element = match &tc.enumeration {
            Some(e) => {
                let items = e.items.iter().map(|(n, v)| (n.clone(), i64::from(*v))).collect();
                layout.enumeration(&e.name, items);
                format!(r#"<ssc:Enumeration name="{}"/>"#, escape(&e.name))
            }
            None => format!("<ssc:{}/>", connector_type(tc.var_type, v2)),
        };
        layout.connector(&c.from.component, &c.from.variable, "output", &type_element);
        layout.connector(&c.to.component, &c.to.variable, "input", &type_element);
    }
    for (k, parameters) in checked.parameters.iter().enumerate() {
        for (name, value) in parameters {
            let (element, text) = ssv_value(value, v2);
            layout.parameters[k].push((name, format!(r#"<ssv:{element} value="{text}"/>"#)));
        }
    }
    layout.write()
}

/// `SystemStructure.ssd` (SSP 2.0) of a system of FMI 3.0 FMUs, after checking it against
/// their FMI 3.0 descriptions.
pub fn ssd_fmi3(system: &System, fmus: &Fmus3) -> Result<String, String> {
    Ok(write_ssd_fmi3(&system.check_fmi3(fmus)?))
}

/// `SystemStructure.ssd` (SSP 2.0) of a checked system of FMI 3.0 FMUs.
pub fn write_ssd_fmi3(checked: &Checked3) -> String {
    let mut layout = Layout::new(checked.system, "2.0");
    for tc in &checked.connections {
        let c = tc.connection;
        let type_element = match (&tc.var_type, &tc.mime_type, &tc.enumeration) {
            (Type3::Binary, Some(m), _) if m != "application/octet-stream" => {
                format!(r#"<ssc:Binary mime-type="{}"/>"#, escape(m))
            }
            (Type3::Enumeration, _, Some(e)) => {
                layout.enumeration(&e.name, e.items.clone());
                format!(r#"<ssc:Enumeration name="{}"/>"#, escape(&e.name))
            }
            (t, _, _) => format!("<ssc:{}/>", t.name()),
        };
        for (port, causality, dims) in [
            (&c.from, tc.from_causality, &tc.from_dimensions),
            (&c.to, tc.to_causality, &tc.to_dimensions),
        ] {
            // An array connector's dimensions (SSP 2.0, ssc:GDimensions): a fixed size, or the
            // structural parameter that sets it, itself a connector of the component.
            let mut content = type_element.clone();
            for d in dims {
                match d {
                    Size::Fixed(n) => content += &format!(r#"<ssc:Dimension size="{n}"/>"#),
                    Size::Parameter {
                        name, ty, causality, ..
                    } => {
                        content += &format!(r#"<ssc:Dimension sizeConnector="{}"/>"#, escape(name));
                        layout.connector(&port.component, name, causality.name(), &format!("<ssc:{ty}/>"));
                    }
                }
            }
            layout.connector(&port.component, &port.variable, causality.name(), &content);
        }
    }
    for (k, parameters) in checked.parameters.iter().enumerate() {
        for (name, value) in parameters {
            let content = ssv_value3(value);
            if let Some(e) = &value.enumeration {
                layout.enumeration(&e.name, e.items.clone());
            }
            layout.parameters[k].push((name, content));
        }
    }
    layout.write()
}

/// The content of the `ssv:Parameter` of an FMI 3.0 value (SSP 2.0,
/// SystemStructureParameterValues.xsd): numbers and Booleans in the element's `value`, an
/// array's as a list, row-major; a String, Binary or Enumeration (its item's name, the type
/// named) in `value`, an array's as `ssv:Value` elements; an array's dimensions as
/// `ssc:Dimension`s after it.
fn ssv_value3(value: &Value3) -> String {
    let ty = value.ty.name();
    let named = match &value.enumeration {
        Some(e) => format!(r#" name="{}""#, escape(&e.name)),
        None => String::new(),
    };
    let texts: Vec<String> = value.values.iter().map(|t| escape(t)).collect();
    let mut out = match value.ty {
        Type3::String | Type3::Binary | Type3::Enumeration if !value.dimensions.is_empty() => {
            let each: String = texts.iter().map(|t| format!(r#"<ssv:Value value="{t}"/>"#)).collect();
            format!("<ssv:{ty}{named}>{each}</ssv:{ty}>")
        }
        _ => format!(r#"<ssv:{ty} value="{}"{named}/>"#, texts.join(" ")),
    };
    for n in &value.dimensions {
        out += &format!(r#"<ssc:Dimension size="{n}"/>"#);
    }
    out
}

impl Layout<'_> {
    fn write(&self) -> String {
        let (system, version, connectors, enumerations) =
            (self.system, self.version, &self.connectors, &self.enumerations);
        let mut x = String::new();
        let w = &mut x;
        let _ = writeln!(w, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
        let _ = writeln!(
            w,
            r#"<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" xmlns:oms="{OMS_NS}" version="{version}" name="{}" generationTool="rustfmu fmu-build">"#,
            escape(&system.name)
        );
        let description = match &system.description {
            Some(d) => format!(r#" description="{}""#, escape(d)),
            None => String::new(),
        };
        let _ = writeln!(w, r#"  <ssd:System name="{}"{description}>"#, escape(&system.name));
        let _ = writeln!(w, "    <ssd:Elements>");
        for (k, c) in system.components.iter().enumerate() {
            let _ = writeln!(
                w,
                r#"      <ssd:Component name="{}" type="application/x-fmu-sharedlibrary" source="resources/{}.fmu">"#,
                escape(&c.name),
                escape(&c.fmu)
            );
            // A component no connection names has no ssd:Connectors (which holds one or more).
            if !connectors[k].is_empty() {
                let _ = writeln!(w, "        <ssd:Connectors>");
                for (var, kind, type_element) in &connectors[k] {
                    let _ = writeln!(
                        w,
                        r#"          <ssd:Connector name="{}" kind="{kind}">{type_element}</ssd:Connector>"#,
                        escape(var)
                    );
                }
                let _ = writeln!(w, "        </ssd:Connectors>");
            }
            let parameters = &self.parameters[k];
            if !parameters.is_empty() {
                let _ = writeln!(
                    w,
                    "        <ssd:ParameterBindings>\n          <ssd:ParameterBinding>\n            <ssd:ParameterValues>"
                );
                let _ = writeln!(
                    w,
                    r#"              <ssv:ParameterSet version="{version}" name="{}">"#,
                    escape(&system.name)
                );
                let _ = writeln!(w, "                <ssv:Parameters>");
                for (name, content) in parameters {
                    let _ = writeln!(
                        w,
                        r#"                  <ssv:Parameter name="{}">{content}</ssv:Parameter>"#,
                        escape(name)
                    );
                }
                let _ = writeln!(
                    w,
                    "                </ssv:Parameters>\n              </ssv:ParameterSet>"
                );
                let _ = writeln!(
                    w,
                    "            </ssd:ParameterValues>\n          </ssd:ParameterBinding>\n        </ssd:ParameterBindings>"
                );
            }
            let _ = writeln!(w, "      </ssd:Component>");
        }
        let _ = writeln!(w, "    </ssd:Elements>\n    <ssd:Connections>");
        for c in &system.connections {
            let _ = writeln!(
                w,
                r#"      <ssd:Connection startElement="{}" startConnector="{}" endElement="{}" endConnector="{}"/>"#,
                escape(&c.from.component),
                escape(&c.from.variable),
                escape(&c.to.component),
                escape(&c.to.variable)
            );
        }
        let _ = writeln!(w, "    </ssd:Connections>");
        if let Some(h) = system.step_size {
            let _ = writeln!(
                w,
                r#"    <ssd:Annotations>
      <ssc:Annotation type="org.openmodelica">
        <oms:Annotations>
          <oms:SimulationInformation>
            <oms:FixedStepMaster description="oms-ma" stepSize="{h:?}"/>
          </oms:SimulationInformation>
        </oms:Annotations>
      </ssc:Annotation>
    </ssd:Annotations>"#
            );
        }
        let _ = writeln!(w, "  </ssd:System>");
        if !enumerations.is_empty() {
            let _ = writeln!(w, "  <ssd:Enumerations>");
            for (name, items) in enumerations {
                let _ = writeln!(w, r#"    <ssc:Enumeration name="{}">"#, escape(name));
                for (item, value) in items {
                    let _ = writeln!(w, r#"      <ssc:Item name="{}" value="{value}"/>"#, escape(item));
                }
                let _ = writeln!(w, "    </ssc:Enumeration>");
            }
            let _ = writeln!(w, "  </ssd:Enumerations>");
        }
        let stop = match system.stop_time {
            Some(t) => format!(r#" stopTime="{t:?}""#),
            None => String::new(),
        };
        if system.step_size.is_some() {
            let _ = writeln!(
                w,
                r#"  <ssd:DefaultExperiment startTime="0.0"{stop}>
    <ssd:Annotations>
      <ssc:Annotation type="org.openmodelica">
        <oms:Annotations>
          <oms:SimulationInformation resultFile="{}_res.mat" loggingInterval="0.0" bufferSize="10"/>
        </oms:Annotations>
      </ssc:Annotation>
    </ssd:Annotations>
  </ssd:DefaultExperiment>"#,
                escape(&system.name)
            );
        } else {
            let _ = writeln!(w, r#"  <ssd:DefaultExperiment startTime="0.0"{stop}/>"#);
        }
        let _ = writeln!(w, "</ssd:SystemStructureDescription>");
        x
    }
}

/// Writes `<out_dir>/<system>.ssp`: the SSD and the system's FMUs, read from
/// `<fmu_dir>/<fmu>.fmu` (packaged before).
pub fn write(system: &System, fmu_dir: &Path, out_dir: &Path) -> Result<PathBuf, String> {
    write_from(system, fmu_dir, fmu_dir, out_dir, false)
}

/// Writes `<out_dir>/fmi3/<system>.ssp`, the same system of the FMI 3.0 FMUs
/// (`<fmu_dir>/fmi3/<fmu>.fmu`, the same models as the FMI 2.0 ones the SSD is checked against:
/// `cargo fmu build` makes both from one crate); `None` if a component has no FMI 3.0 FMU.
/// A system of FMI 3.0 FMUs (`fmi-version = "3.0"`) is checked against their FMI 3.0
/// descriptions and written in SSP 2.0; a missing FMU of it is an error.
pub fn write_fmi3(system: &System, fmu_dir: &Path, out_dir: &Path) -> Result<Option<PathBuf>, String> {
    let fmi3 = fmu_dir.join("fmi3");
    if system.is_fmi3() {
        let fmus = system.read_fmus(&fmi3)?;
        let ssd = ssd_fmi3(system, &fmus)?;
        let out = out_dir.join("fmi3");
        std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
        return write_archive(system, &ssd, fmus.keys(), &fmi3, &out).map(Some);
    }
    if system
        .components
        .iter()
        .any(|c| !fmi3.join(format!("{}.fmu", c.fmu)).is_file())
    {
        return Ok(None);
    }
    let out = out_dir.join("fmi3");
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let v2 = system.ssp_version.as_deref() == Some("2.0");
    write_from(system, fmu_dir, &fmi3, &out, v2).map(Some)
}

/// Writes `<out_dir>/<system>.ssp`: the SSD checked against the FMUs of `check_dir`, the FMU
/// files of `files_dir`; in SSP 2.0 if `v2`.
fn write_from(
    system: &System,
    check_dir: &Path,
    files_dir: &Path,
    out_dir: &Path,
    v2: bool,
) -> Result<PathBuf, String> {
    let fmus = system.read_fmus(check_dir)?;
    let ssd = if v2 { ssd2(system, &fmus)? } else { ssd(system, &fmus)? };
    write_archive(system, &ssd, fmus.keys(), files_dir, out_dir)
}

/// Writes `<out_dir>/<system>.ssp`: `ssd` and the FMUs `ids` (each once, in order) of `fmu_dir`.
fn write_archive<'a>(
    system: &System,
    ssd: &str,
    ids: impl Iterator<Item = &'a String>,
    fmu_dir: &Path,
    out_dir: &Path,
) -> Result<PathBuf, String> {
    let out = out_dir.join(format!("{}.ssp", system.name));
    // Written aside and renamed, so an interrupted build never leaves a half-written .ssp.
    let tmp = out.with_extension("ssp.partial");
    let file = std::fs::File::create(&tmp).map_err(|e| format!("{}: {e}", tmp.display()))?;
    let mut zip = zip::ZipWriter::new(file);
    let options = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let zip_err = |e: &dyn std::fmt::Display| format!("{}: {e}", tmp.display());
    zip.start_file("SystemStructure.ssd", options)
        .map_err(|e| zip_err(&e))?;
    zip.write_all(ssd.as_bytes()).map_err(|e| zip_err(&e))?;
    // Fmus is ordered by name: each FMU once, sorted.
    for id in ids {
        let path = fmu_dir.join(format!("{id}.fmu"));
        let bytes = std::fs::read(&path).map_err(|e| {
            format!(
                "{}: {e} (package the FMUs first: `cargo run --release -p fmu-build`)",
                path.display()
            )
        })?;
        // Stored, not deflated: an .fmu is already compressed.
        zip.start_file(
            format!("resources/{id}.fmu"),
            SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored),
        )
        .map_err(|e| zip_err(&e))?;
        zip.write_all(&bytes).map_err(|e| zip_err(&e))?;
    }
    zip.finish().map_err(|e| zip_err(&e))?;
    std::fs::rename(&tmp, &out).map_err(|e| format!("{}: {e}", out.display()))?;
    Ok(out)
}

/// Writes `<out_dir>/<system>.ssp` for every system of FMI 2.0 FMUs of a file, and
/// `<out_dir>/fmi3/<system>.ssp` where every component has an FMI 3.0 FMU too and for every
/// system of FMI 3.0 FMUs.
pub fn write_all(systems: &Systems, fmu_dir: &Path, out_dir: &Path) -> Result<Vec<PathBuf>, String> {
    let mut out = Vec::new();
    for s in &systems.systems {
        if !s.is_fmi3() {
            out.push(write(s, fmu_dir, out_dir)?);
        }
        out.extend(write_fmi3(s, fmu_dir, out_dir)?);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::systems::FmuDescription;
    use crate::systems::testing::*;
    use std::io::Read as _;

    /// Writes an `.fmu` archive at `path` that holds only `modelDescription.xml`.
    fn packaged(path: &Path, description: &[u8]) {
        let mut zip = zip::ZipWriter::new(std::fs::File::create(path).unwrap());
        zip.start_file("modelDescription.xml", SimpleFileOptions::default())
            .unwrap();
        zip.write_all(description).unwrap();
        zip.finish().unwrap();
    }

    /// The entry names of the archive at `path`, in order, and the text of its SSD.
    fn unpacked(path: &Path) -> (Vec<String>, String) {
        let mut zip = zip::ZipArchive::new(std::fs::File::open(path).unwrap()).unwrap();
        let names = (0..zip.len())
            .map(|i| zip.by_index(i).unwrap().name().unwrap().into_owned())
            .collect();
        let mut text = String::new();
        zip.by_name("SystemStructure.ssd")
            .unwrap()
            .read_to_string(&mut text)
            .unwrap();
        (names, text)
    }

    fn fixture(name: &str) -> String {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/fixtures/{name}.ssd"));
        std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    /// SSP 2.0 is SSP 1.0's SSD with its version, FMI 3.0 type names and nothing else changed
    /// (the schema validation and the run are tests/python/test_ssp2.py's).
    #[test]
    fn the_ssp2_ssd_is_the_ssp1_one_with_fmi3_types() {
        let systems = paper_systems();
        for name in ["PendulumLQR", "PendulumMotors"] {
            let system = systems.get(name).unwrap();
            let v1 = ssd(system, &fmus()).unwrap();
            let v2 = ssd2(system, &fmus()).unwrap();
            assert!(v2.contains(r#"version="2.0" name=""#) && !v2.contains(r#"Set version="1.0""#));
            assert!(!v2.contains("<ssc:Real/>") && !v2.contains("<ssv:Real "));
            let back = v2
                .replace(r#"version="2.0""#, r#"version="1.0""#)
                .replace("<ssc:Float64/>", "<ssc:Real/>")
                .replace("<ssv:Float64 ", "<ssv:Real ")
                .replace("<ssc:Int32/>", "<ssc:Integer/>")
                .replace("<ssv:Int32 ", "<ssv:Integer ");
            assert_eq!(back, v1, "{name}");
        }
        let e =
            crate::systems::Systems::parse("[[system]]\nname = \"S\"\nssp-version = \"1.1\"\n", Path::new("v.toml"))
                .unwrap_err();
        assert!(e.contains("ssp-version = \"1.1\"") && e.contains("\"2.0\""), "{e}");
    }

    /// The fixtures are the SSDs of the paper's systems file, reviewed by hand: any change to
    /// the writer or to holonomic/systems.toml shows here first.
    #[test]
    fn the_ssd_of_each_paper_system_is_the_reference() {
        let systems = paper_systems();
        for name in ["PendulumLQR", "PendulumMotors"] {
            let text = ssd(systems.get(name).unwrap(), &fmus()).unwrap_or_else(|e| panic!("{e}"));
            assert!(
                text == fixture(name),
                "{name}: the SSD differs from tests/fixtures/{name}.ssd:\n{text}"
            );
        }
    }

    /// libcosim's SSP reader needs both ends of every connection.
    #[test]
    fn every_connection_names_both_ends() {
        let systems = paper_systems();
        for s in systems.systems.iter().filter(|s| !s.is_fmi3()) {
            let text = ssd(s, &fmus()).unwrap_or_else(|e| panic!("{}: {e}", s.name));
            assert_eq!(
                text.matches("<ssd:Connection ").count(),
                text.matches("endElement=").count(),
                "{}: every connection needs an endElement",
                s.name
            );
            assert_eq!(text.matches("<ssd:Connection ").count(), s.connections.len());
        }
    }

    /// Ecos applies one parameter set per run, by name, merging the components' sets of that
    /// name: every component's set is named after the system, so one name applies them all.
    /// OMSimulator needs its master and result file in its own annotations.
    #[test]
    fn one_parameter_set_name_and_the_omsimulator_annotations() {
        let systems = paper_systems();
        for s in systems.systems.iter().filter(|s| !s.is_fmi3()) {
            let text = ssd(s, &fmus()).unwrap_or_else(|e| panic!("{}: {e}", s.name));
            let named = format!(r#"<ssv:ParameterSet version="1.0" name="{}">"#, s.name);
            assert_eq!(
                text.matches("<ssv:ParameterSet ").count(),
                text.matches(&named).count(),
                "{}: every parameter set should be named {:?}:\n{text}",
                s.name,
                s.name
            );
            assert_eq!(
                text.matches(&named).count(),
                s.components.len(),
                "{}: one set per component",
                s.name
            );
            let master = r#"<oms:FixedStepMaster description="oms-ma" stepSize="0.001"/>"#;
            let (system_end, experiment) = (
                text.find("</ssd:System>").unwrap(),
                text.find("<ssd:DefaultExperiment").unwrap(),
            );
            assert!(
                text.find(master)
                    .is_some_and(|i| i > text.find("</ssd:Connections>").unwrap() && i < system_end),
                "{}: the fixed-step master belongs in ssd:System's Annotations, after its Connections:\n{text}",
                s.name
            );
            let result = format!(r#"<oms:SimulationInformation resultFile="{}_res.mat""#, s.name);
            assert!(
                text.find(&result).is_some_and(|i| i > experiment),
                "{}: the DefaultExperiment should carry OMSimulator's result file:\n{text}",
                s.name
            );
            assert!(text.contains(
                r#"xmlns:oms="https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd""#
            ));
        }
    }

    #[test]
    fn a_system_that_fails_its_check_is_not_written() {
        let systems = paper_systems();
        let mut s = systems.get("PendulumLQR").unwrap().clone();
        s.connections.push("controller.M1 -> pendulum.alpha1".parse().unwrap());
        let e = ssd(&s, &fmus()).unwrap_err();
        assert!(
            e.contains("controller.M1 -> pendulum.alpha1"),
            "expected the bad connection named, got: {e}"
        );
    }

    /// When the Controller's `mode` becomes an Enumeration, the SSD stays what it is: an
    /// Enumeration parameter is written as ssv:Integer with the item's value (what fmpy.ssp
    /// applies; ssv:Enumeration aborts libcosim), whether the file gives the value or the name.
    #[test]
    fn an_enumeration_parameter_is_written_as_the_integer_of_its_item() {
        let fmus = fmus_with_enumeration_mode();
        let systems = paper_systems();
        let lqr = systems.get("PendulumLQR").unwrap();
        assert_eq!(ssd(lqr, &fmus).unwrap(), fixture("PendulumLQR"));
        let mut named = systems.get("PendulumMotors").unwrap().clone();
        let controller = named.components.iter_mut().find(|c| c.name == "controller").unwrap();
        let mode = controller.parameters.iter_mut().find(|p| p.name == "mode").unwrap();
        mode.value = crate::systems::Literal::String("LQR_PID".into());
        assert_eq!(ssd(&named, &fmus).unwrap(), fixture("PendulumMotors"));
        // A name that is no item is refused.
        let controller = named.components.iter_mut().find(|c| c.name == "controller").unwrap();
        let mode = controller.parameters.iter_mut().find(|p| p.name == "mode").unwrap();
        mode.value = crate::systems::Literal::String("LQR_PLUS".into());
        assert!(ssd(&named, &fmus).is_err());
    }

    /// A small FMU description: one Enumeration variable `m` of type `Mode` with `items`.
    fn enumeration_fmu(id: &str, causality: &str, items: &str) -> FmuDescription {
        let start = if causality == "input" { r#" start="1""# } else { "" };
        let initial = if causality == "output" {
            r#" initial="calculated""#
        } else {
            ""
        };
        FmuDescription::parse(&format!(
            r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="{id}" guid="{{0}}">
  <CoSimulation modelIdentifier="{id}"/>
  <TypeDefinitions>
    <SimpleType name="Mode"><Enumeration>{items}</Enumeration></SimpleType>
  </TypeDefinitions>
  <ModelVariables>
    <ScalarVariable name="m" valueReference="0" causality="{causality}" variability="discrete"{initial}>
      <Enumeration declaredType="Mode"{start}/>
    </ScalarVariable>
  </ModelVariables>
  <ModelStructure/>
</fmiModelDescription>
"#
        ))
        .unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn an_enumeration_connection_declares_its_type() {
        let items = r#"<Item name="A" value="1"/><Item name="B" value="2"/>"#;
        let system = one_system(
            "[[system]]\nname = \"E\"\nconnections = [\"src.m -> dst.m\"]\n\
             [[system.component]]\nname = \"src\"\nfmu = \"Source\"\n\
             [[system.component]]\nname = \"dst\"\nfmu = \"Sink\"\n",
        );
        let mut fmus = Fmus::new();
        fmus.insert("Source".into(), enumeration_fmu("Source", "output", items));
        fmus.insert("Sink".into(), enumeration_fmu("Sink", "input", items));
        let text = ssd(&system, &fmus).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            text.matches(r#"<ssc:Enumeration name="Mode"/></ssd:Connector>"#)
                .count(),
            2,
            "{text}"
        );
        assert!(
            text.contains(
                "  </ssd:System>\n  <ssd:Enumerations>\n    <ssc:Enumeration name=\"Mode\">\n      \
                 <ssc:Item name=\"A\" value=\"1\"/>\n      <ssc:Item name=\"B\" value=\"2\"/>\n    \
                 </ssc:Enumeration>\n  </ssd:Enumerations>\n  <ssd:DefaultExperiment startTime=\"0.0\"/>\n"
            ),
            "the type follows the System, before the DefaultExperiment (stopTime omitted when the \
             file gives none):\n{text}"
        );
        assert!(
            !text.contains("description="),
            "no description given, none written: {text}"
        );
        // Enumerations of different items do not connect.
        fmus.insert(
            "Sink".into(),
            enumeration_fmu(
                "Sink",
                "input",
                r#"<Item name="A" value="1"/><Item name="C" value="3"/>"#,
            ),
        );
        let e = ssd(&system, &fmus).unwrap_err();
        assert!(e.contains("src.m -> dst.m") && e.contains("Mode (A = 1, C = 3)"), "{e}");
    }

    /// The networked pendulum's SSD (FMI 3.0 FMUs) is the reviewed fixture, passes the
    /// runner's SSP 2.0 schema check and reading (tests/python/test_ssp2.py validates it against
    /// the standard's XSDs with lxml), and keeps its clock connections apart from its data.
    #[test]
    // The file reader parse_ssd takes returns the runner's Error, whatever its size.
    #[allow(clippy::result_large_err)]
    fn the_networked_pendulum_is_written_in_ssp2_with_clock_and_binary_connectors() {
        let systems = paper_systems();
        let system = systems.get("NetworkedPendulum").unwrap();
        let text = ssd_fmi3(system, &crate::systems_fmi3::tests::fmus3()).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            text == fixture("NetworkedPendulum"),
            "the SSD differs from tests/fixtures/NetworkedPendulum.ssd:\n{text}"
        );
        let ssd = rustfmu_runner::ssp::parse_ssd(&text, &mut |f| panic!("reads no file: {f}"))
            .unwrap_or_else(|e| panic!("{}\n{text}", e.message));
        assert_eq!((ssd.connections.len(), ssd.clock_connections.len()), (18, 8));
        assert_eq!(ssd.components.len(), 8);
        let sensor = &ssd.components[3];
        assert_eq!(sensor.source, "resources/CanSensor.fmu");
        assert!(
            sensor
                .connectors
                .iter()
                .any(|(n, kind, _)| n == "CAN.Tx_Clock" && kind == "input"),
            "a countdown Tx_Clock that starts a connection is an input connector: {:?}",
            sensor.connectors
        );
        assert!(text.contains(
            r#"<ssd:Connector name="CAN.Tx_Data" kind="output"><ssc:Binary mime-type="application/org.fmi-standard.fmi-ls-bus.can; version=&quot;1.0.0&quot;"/></ssd:Connector>"#
        ));
        assert!(text.contains(r#"<ssv:Parameter name="tx_id"><ssv:Int32 value="32"/></ssv:Parameter>"#));
        // A system that fails its check is not written.
        let mut bad = system.clone();
        bad.connections[10] = "sensor.CAN.Tx_Clock -> bus.Node1.Tx_Clock".parse().unwrap();
        assert!(ssd_fmi3(&bad, &crate::systems_fmi3::tests::fmus3()).is_err());
    }

    #[test]
    // The file reader parse_ssd takes returns the runner's Error, whatever its size.
    #[allow(clippy::result_large_err)]
    fn arrays_and_enumerations_of_fmi3_fmus_are_written_as_ssp2_defines_them() {
        use crate::systems_fmi3::tests::{arrays_and_enumerations, described};
        let system = arrays_and_enumerations(
            &["s1.y -> s2.u", "f1.Enumeration_output -> f2.Enumeration_input"],
            ["A = [[-1, 0, 0], [0, -2, 0], [0, 0, -3]]", "", "", "", "mode = 2"],
        );
        let fmus = described(&["StateSpace", "Feedthrough", "Controller"]);
        let text = ssd_fmi3(&system, &fmus).unwrap_or_else(|e| panic!("{e}"));
        for line in [
            // An array connector sized by a structural parameter, itself a connector.
            r#"<ssd:Connector name="r" kind="structuralParameter"><ssc:UInt64/></ssd:Connector>"#,
            r#"<ssd:Connector name="y" kind="output"><ssc:Float64/><ssc:Dimension sizeConnector="r"/></ssd:Connector>"#,
            r#"<ssd:Connector name="u" kind="input"><ssc:Float64/><ssc:Dimension sizeConnector="m"/></ssd:Connector>"#,
            r#"<ssd:Connector name="Enumeration_input" kind="input"><ssc:Enumeration name="Option"/></ssd:Connector>"#,
            // A list, row-major, with its dimensions; an item by its name, its type named.
            r#"<ssv:Parameter name="A"><ssv:Float64 value="-1.0 0.0 0.0 0.0 -2.0 0.0 0.0 0.0 -3.0"/><ssc:Dimension size="3"/><ssc:Dimension size="3"/></ssv:Parameter>"#,
            r#"<ssv:Parameter name="mode"><ssv:Enumeration value="PID" name="ControlMode"/></ssv:Parameter>"#,
            r#"<ssc:Enumeration name="Option">"#,
            r#"<ssc:Item name="Option 2" value="2"/>"#,
            r#"<ssc:Enumeration name="ControlMode">"#,
        ] {
            assert!(text.contains(line), "expected {line} in:\n{text}");
        }
        // The runner reads it (its SSP 2.0 structure checked first).
        let ssd = rustfmu_runner::ssp::parse_ssd(&text, &mut |f| panic!("reads no file: {f}"))
            .unwrap_or_else(|e| panic!("{}\n{text}", e.message));
        assert_eq!(ssd.connections.len(), 2);
        let s1 = &ssd.components[0];
        assert!(
            s1.declared.contains(&("y".into(), "Float64".into(), vec![None])),
            "{:?}",
            s1.declared
        );
        assert_eq!(ssd.components[4].parameters[0].0, "mode");
    }

    /// A system of FMI 3.0 FMUs goes to fmi3/ alone (no SSP 1.0 twin); its missing FMU is an
    /// error naming the component and the file.
    #[test]
    fn an_fmi3_system_is_written_to_fmi3_only_and_needs_its_fmus() {
        let dir = std::env::temp_dir().join(format!("fmu-build-ssp3-test-{}", std::process::id()));
        let (fmu_dir, out_dir) = (dir.join("fmus"), dir.join("out"));
        std::fs::create_dir_all(fmu_dir.join("fmi3")).unwrap();
        let mut systems = paper_systems();
        systems.systems.retain(|s| s.is_fmi3());
        let ids = crate::systems_fmi3::tests::NETWORKED_FMUS;
        let package = |id: &str| {
            let xml = std::fs::read(workspace_root().join(format!("modelDescription/fmi3/{id}.xml"))).unwrap();
            packaged(&fmu_dir.join(format!("fmi3/{id}.fmu")), &xml);
        };
        ids[..5].iter().for_each(|id| package(id));
        let e = write_all(&systems, &fmu_dir, &out_dir).unwrap_err();
        assert!(
            e.contains("system 'NetworkedPendulum': component 'bus'") && e.contains("fmi3/CanBus.fmu"),
            "{e}"
        );
        package("CanBus");
        let written = write_all(&systems, &fmu_dir, &out_dir).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(written, [out_dir.join("fmi3/NetworkedPendulum.ssp")]);
        let (mut names, text) = unpacked(&written[0]);
        names.sort();
        let mut want: Vec<String> = ids.iter().map(|id| format!("resources/{id}.fmu")).collect();
        want.push("SystemStructure.ssd".into());
        want.sort();
        assert_eq!(names, want);
        assert_eq!(text, fixture("NetworkedPendulum"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The archive: the SSD, then each FMU once under resources/, stored as it was packaged.
    #[test]
    fn the_archive_holds_the_ssd_and_each_fmu_once() {
        let dir = std::env::temp_dir().join(format!("fmu-build-ssp-test-{}", std::process::id()));
        let (fmu_dir, out_dir) = (dir.join("fmus"), dir.join("out"));
        std::fs::create_dir_all(&fmu_dir).unwrap();
        std::fs::create_dir_all(&out_dir).unwrap();
        for id in ["Pendulum", "Controller", "DCMotor"] {
            packaged(&fmu_dir.join(format!("{id}.fmu")), xml(id).as_bytes());
        }
        let mut systems = paper_systems();
        // The systems of FMI 2.0 FMUs (those of FMI 3.0 FMUs need FMUs of fmi3/).
        systems.systems.retain(|s| !s.is_fmi3());
        let written = write_all(&systems, &fmu_dir, &out_dir).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            written,
            [out_dir.join("PendulumLQR.ssp"), out_dir.join("PendulumMotors.ssp")]
        );
        let (names, text) = unpacked(&written[1]);
        assert_eq!(
            names,
            [
                "SystemStructure.ssd",
                "resources/Controller.fmu",
                "resources/DCMotor.fmu",
                "resources/Pendulum.fmu"
            ]
        );
        assert_eq!(text, fixture("PendulumMotors"));
        let mut zip = zip::ZipArchive::new(std::fs::File::open(&written[1]).unwrap()).unwrap();
        let motor = zip.by_name("resources/DCMotor.fmu").unwrap();
        assert_eq!(motor.compression(), zip::CompressionMethod::Stored);
        drop(motor);
        assert_eq!(
            std::fs::read(fmu_dir.join("DCMotor.fmu")).unwrap().len() as u64,
            zip.by_name("resources/DCMotor.fmu").unwrap().size()
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
