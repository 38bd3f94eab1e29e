//! `terminalsAndIcons.xml` (FMI 3.0).

use super::{close, document, empty, finish, open};
use rustfmu::description::ModelDescription;

/// `terminalsAndIcons/terminalsAndIcons.xml` (FMI 3.0, 2.4.9) of a description with terminals,
/// in the order of `fmi3TerminalsAndIcons.xsd`; `None` without terminals. Every member names a
/// variable of the description (checked here, as the derive checked it).
pub fn terminals_and_icons(d: &ModelDescription) -> Result<Option<String>, String> {
    if d.terminals.is_empty() {
        return Ok(None);
    }
    let mut w = document()?;
    open(&mut w, "fmiTerminalsAndIcons", &[("fmiVersion", "3.0")])?;
    open(&mut w, "Terminals", &[])?;
    for t in d.terminals {
        let mut attrs = vec![("name", t.name), ("matchingRule", t.matching_rule)];
        if !t.kind.is_empty() {
            attrs.push(("terminalKind", t.kind));
        }
        if !t.description.is_empty() {
            attrs.push(("description", t.description));
        }
        open(&mut w, "Terminal", &attrs)?;
        for m in t.members {
            if d.by_name(m.variable).is_none() {
                return Err(format!(
                    "{}: terminal '{}': member '{}' names '{}', which is no variable",
                    d.model_identifier, t.name, m.member, m.variable
                ));
            }
            empty(
                &mut w,
                "TerminalMemberVariable",
                &[
                    ("variableName", m.variable),
                    ("memberName", m.member),
                    ("variableKind", m.kind),
                ],
            )?;
        }
        close(&mut w, "Terminal")?;
    }
    close(&mut w, "Terminals")?;
    close(&mut w, "fmiTerminalsAndIcons")?;
    finish(w).map(Some)
}
