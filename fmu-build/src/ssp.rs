//! SSP 1.0 archives of the paper's composed systems: `target/fmu/<system>.ssp` holding
//! `SystemStructure.ssd` and the FMUs under `resources/`.
//!
//! The systems are described once, as data, in the library ([`rustfmu::systems`], which the
//! benchmarks run too); the SSD is generated from that description after
//! [`System::check`] has checked it against the FMUs' own variable declarations (every
//! connection goes from an output to an input of the same type, every parameter exists and has
//! the right type).
//! Every connection names its `startElement` and `endElement` (libcosim's SSP reader needs both;
//! no system-level connectors are used).

use rustfmu::fmi2::variables::{Value, VarType};
use rustfmu::systems::{System, systems};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use zip::write::SimpleFileOptions;

fn escape(s: &str) -> String {
    quick_xml::escape::escape(s).into_owned()
}

fn type_element(t: VarType) -> &'static str {
    match t {
        VarType::Real => "Real",
        VarType::Integer => "Integer",
        VarType::Boolean => "Boolean",
    }
}

fn value_text(v: Value) -> String {
    match v {
        Value::Real(x) => format!("{x:?}"),
        Value::Integer(x) => x.to_string(),
        Value::Boolean(x) => x.to_string(),
    }
}

/// `SystemStructure.ssd` of a system, after checking it against the FMUs' declarations.
pub fn ssd(system: &System) -> Result<String, String> {
    system.check()?;
    let mut connectors: Vec<Vec<(&str, &str, VarType)>> = vec![Vec::new(); system.components.len()];
    for &(from, out, to, inp) in &system.connections {
        let (_, o) = system.decl(from, out)?;
        for (comp, var, kind) in [(from, out, "output"), (to, inp, "input")] {
            let k = system
                .components
                .iter()
                .position(|c| c.name == comp)
                .expect("checked by System::check");
            if !connectors[k].iter().any(|(n, _, _)| *n == var) {
                connectors[k].push((var, kind, o.var_type));
            }
        }
    }
    let mut x = String::new();
    let w = &mut x;
    let _ = writeln!(w, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        w,
        r#"<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="{}" generationTool="rustfmu fmu-build">"#,
        escape(system.name)
    );
    let _ = writeln!(
        w,
        r#"  <ssd:System name="{}" description="{}">"#,
        escape(system.name),
        escape(system.description)
    );
    let _ = writeln!(w, "    <ssd:Elements>");
    for (k, c) in system.components.iter().enumerate() {
        let _ = writeln!(
            w,
            r#"      <ssd:Component name="{}" type="application/x-fmu-sharedlibrary" source="resources/{}.fmu">"#,
            escape(c.name),
            escape(c.fmu)
        );
        let _ = writeln!(w, "        <ssd:Connectors>");
        for (var, kind, t) in &connectors[k] {
            let _ = writeln!(
                w,
                r#"          <ssd:Connector name="{}" kind="{kind}"><ssc:{}/></ssd:Connector>"#,
                escape(var),
                type_element(*t)
            );
        }
        let _ = writeln!(w, "        </ssd:Connectors>");
        if !c.parameters.is_empty() {
            let _ = writeln!(
                w,
                "        <ssd:ParameterBindings>\n          <ssd:ParameterBinding>\n            <ssd:ParameterValues>"
            );
            let _ = writeln!(
                w,
                r#"              <ssv:ParameterSet version="1.0" name="{}">"#,
                escape(c.name)
            );
            let _ = writeln!(w, "                <ssv:Parameters>");
            for (name, value) in &c.parameters {
                let (_, d) = system.decl(c.name, name)?;
                let _ = writeln!(
                    w,
                    r#"                  <ssv:Parameter name="{}"><ssv:{} value="{}"/></ssv:Parameter>"#,
                    escape(name),
                    type_element(d.var_type),
                    value_text(*value)
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
    for (from, out, to, inp) in &system.connections {
        let _ = writeln!(
            w,
            r#"      <ssd:Connection startElement="{from}" startConnector="{out}" endElement="{to}" endConnector="{inp}"/>"#
        );
    }
    let _ = writeln!(w, "    </ssd:Connections>\n  </ssd:System>");
    let _ = writeln!(
        w,
        r#"  <ssd:DefaultExperiment startTime="0.0" stopTime="{:?}"/>"#,
        system.stop_time
    );
    let _ = writeln!(w, "</ssd:SystemStructureDescription>");
    Ok(x)
}

/// Writes `<fmu_dir>/<system>.ssp` for every system; the FMUs must be packaged in `fmu_dir`.
pub fn write_all(fmu_dir: &Path) -> Result<Vec<PathBuf>, String> {
    let mut written = Vec::new();
    for system in systems() {
        let ssd = ssd(&system)?;
        let out = fmu_dir.join(format!("{}.ssp", system.name));
        let tmp = out.with_extension("ssp.partial");
        let file = std::fs::File::create(&tmp).map_err(|e| format!("{}: {e}", tmp.display()))?;
        let mut zip = zip::ZipWriter::new(file);
        let options = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
        let zip_err = |e: &dyn std::fmt::Display| format!("{}: {e}", tmp.display());
        zip.start_file("SystemStructure.ssd", options)
            .map_err(|e| zip_err(&e))?;
        zip.write_all(ssd.as_bytes()).map_err(|e| zip_err(&e))?;
        let mut fmus: Vec<&str> = system.components.iter().map(|c| c.fmu).collect();
        fmus.sort_unstable();
        fmus.dedup();
        for id in fmus {
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
        written.push(out);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_connection_names_both_ends() {
        for s in systems() {
            let text = ssd(&s).unwrap_or_else(|e| panic!("{}: {e}", s.name));
            assert_eq!(
                text.matches("<ssd:Connection ").count(),
                text.matches("endElement=").count(),
                "{}: every connection needs an endElement",
                s.name
            );
        }
    }

    #[test]
    fn a_system_that_fails_its_check_is_not_written() {
        let mut s = rustfmu::systems::system("PendulumLQR").unwrap();
        s.connections.push(("controller", "M1", "pendulum", "alpha1"));
        let e = ssd(&s).unwrap_err();
        assert!(
            e.contains("controller.M1 -> pendulum.alpha1"),
            "expected the bad connection named, got: {e}"
        );
    }
}
