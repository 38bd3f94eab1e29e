//! `cargo fmu info`: what an FMU file offers, from its archive and description.

use super::{glibc_requirements, macos_binaries};
use md_reader::{Causality, ModelDescription, fmi3};
use std::path::Path;

/// `cargo fmu info`: what an FMU file offers, from its archive and description.
pub fn info(fmu: &Path) -> Result<String, String> {
    let at = |e: &dyn std::fmt::Display| format!("{}: {e}", fmu.display());
    let mut zip = fmi_conformance::archive::open(fmu)?;
    let mut platforms = std::collections::BTreeSet::new();
    for name in zip.entry_names() {
        let parts: Vec<&str> = name.split('/').collect();
        if parts.len() == 3 && parts[0] == "binaries" && !parts[2].is_empty() {
            platforms.insert(format!("{} ({})", parts[1], parts[2]));
        }
    }
    let xml = fmi_conformance::archive::read_model_description(&mut zip)?;
    let md = md_reader::parse(&xml).map_err(|e| at(&e))?;
    let mut out = String::new();
    let mut counts: std::collections::BTreeMap<&str, usize> = Default::default();
    let mut interfaces = Vec::new();
    let mut variables = Vec::new();
    // The head, the experiment and the interfaces, from the fields both versions' descriptions
    // name alike (the identity: FMI 2.0's GUID, FMI 3.0's instantiation token).
    macro_rules! head_and_interfaces {
        ($d:ident, $identity:ident) => {
            out.push_str(&head(
                fmu,
                &$d.fmi_version,
                &$d.model_name,
                &$d.version,
                &$d.$identity,
                &$d.generation_tool,
                &$d.description,
            ));
            out.push_str(&experiment(&$d.default_experiment));
            interfaces.extend(
                $d.me
                    .as_ref()
                    .map(|i| format!("ModelExchange ({})", i.model_identifier)),
            );
            interfaces.extend(
                $d.cs
                    .as_ref()
                    .map(|i| format!("CoSimulation ({})", i.model_identifier)),
            );
        };
    }
    // (value reference, name, causality, type, unit) of every variable, in order.
    let listed: Vec<(u32, &str, Causality, String, Option<&str>)> = match &md {
        ModelDescription::Fmi2(d) => {
            head_and_interfaces!(d, guid);
            let v = d.variables.iter();
            v.map(|v| {
                (
                    v.vr,
                    v.name.as_str(),
                    v.causality,
                    v.ty.name().to_string(),
                    v.unit.as_deref(),
                )
            })
            .collect()
        }
        ModelDescription::Fmi3(d) => {
            head_and_interfaces!(d, token);
            // An array's type with its dimensions: Float64[2,4]; a length set by a structural
            // parameter by the parameter's name: Float64[n,n].
            d.variables
                .iter()
                .map(|v| {
                    let ty = if v.array {
                        let dims: Vec<String> = v
                            .dimensions
                            .iter()
                            .map(|dim| match dim {
                                fmi3::Dimension::Fixed(n) => n.to_string(),
                                // Set by a structural parameter: its name (Float64[n,n]).
                                fmi3::Dimension::Parameter(vr) => match d.by_vr(*vr) {
                                    Some(p) => p.name.clone(),
                                    None => format!("vr {vr}"),
                                },
                            })
                            .collect();
                        format!("{}[{}]", v.ty.name(), dims.join(","))
                    } else {
                        v.ty.name().to_string()
                    };
                    (v.vr, v.name.as_str(), v.causality, ty, v.unit.as_deref())
                })
                .collect()
        }
    };
    // FMI 3.0 terminals: their names and members.
    let terminals: Vec<String> = match zip.read_entry("terminalsAndIcons/terminalsAndIcons.xml") {
        Ok(Some(text)) => terminal_lines(&String::from_utf8_lossy(&text)),
        _ => Vec::new(),
    };
    for (vr, name, causality, ty, unit) in listed {
        *counts.entry(causality.name()).or_default() += 1;
        let unit = unit.map(|u| format!(", {u}")).unwrap_or_default();
        variables.push(format!("    {vr:>5} {name} ({causality}, {ty}{unit})"));
    }
    out.push_str(&format!("  interfaces: {}\n", interfaces.join(", ")));
    out.push_str(&format!(
        "  platforms: {}\n",
        if platforms.is_empty() {
            "none".to_string()
        } else {
            platforms.into_iter().collect::<Vec<_>>().join(", ")
        }
    ));
    // The oldest glibc each Linux binary loads with.
    for (name, needed) in glibc_requirements(fmu)? {
        if let Some((major, minor)) = needed {
            out.push_str(&format!("  {name} needs glibc >= {major}.{minor}\n"));
        }
    }
    // The architectures of each macOS binary and the oldest macOS each loads on.
    for (name, slices) in macos_binaries(fmu)? {
        out.push_str(&format!("  {name}: {slices}\n"));
    }
    let counts: Vec<String> = counts.iter().map(|(k, v)| format!("{v} {k}")).collect();
    out.push_str(&format!("  variables: {} ({})\n", variables.len(), counts.join(", ")));
    for v in variables {
        out.push_str(&v);
        out.push('\n');
    }
    if !terminals.is_empty() {
        out.push_str(&format!("  terminals: {}\n", terminals.len()));
        for t in terminals {
            out.push_str(&format!("    {t}\n"));
        }
    }
    Ok(out)
}

/// One line per `<Terminal>` of terminalsAndIcons.xml: `name (kind): member = variable (kind), ...`.
fn terminal_lines(text: &str) -> Vec<String> {
    use super::ls_bus::{TerminalXml, walk_terminals};
    let mut out: Vec<String> = Vec::new();
    let mut members: Vec<String> = Vec::new();
    let mut current: Option<String> = None;
    walk_terminals(text, |element| match element {
        TerminalXml::EndOfTerminal => {
            if let Some(t) = current.take() {
                out.push(format!("{t}: {}", members.join(", ")));
                members.clear();
            }
        }
        TerminalXml::Open { name, attr, empty } => match name {
            b"Terminal" => {
                let kind = attr("terminalKind");
                current = Some(if kind.is_empty() {
                    attr("name")
                } else {
                    format!("{} ({kind})", attr("name"))
                });
                if empty {
                    out.extend(current.take());
                }
            }
            b"TerminalMemberVariable" => members.push(format!(
                "{} = {} ({})",
                attr("memberName"),
                attr("variableName"),
                attr("variableKind")
            )),
            _ => {}
        },
    });
    out
}

/// The first lines of `cargo fmu info`.
fn head(
    fmu: &Path,
    fmi_version: &str,
    name: &str,
    version: &str,
    token: &str,
    tool: &str,
    description: &str,
) -> String {
    format!(
        "{}: FMI {fmi_version}, model '{name}', version '{version}'\n  GUID/token {token}\n  generated by {tool}\n  {description}\n",
        fmu.display()
    )
}

/// `cargo fmu info`'s line of the default experiment, its values as written (none without one).
fn experiment(e: &md_reader::DefaultExperiment) -> String {
    let parts: Vec<String> = [
        ("start", &e.start_time),
        ("stop", &e.stop_time),
        ("step", &e.step_size),
        ("tolerance", &e.tolerance),
    ]
    .iter()
    .filter_map(|(label, v)| v.as_ref().filter(|v| !v.is_empty()).map(|v| format!("{label} {v}")))
    .collect();
    if parts.is_empty() {
        String::new()
    } else {
        format!("  default experiment: {}\n", parts.join(", "))
    }
}
