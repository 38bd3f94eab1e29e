//! The checks whose every call is an importer's mistake made on purpose, each with the
//! standard's sentence that puts the obligation on the importer (FMI 2.0.5 / FMI 3.0.2): what
//! the FMU then does the standard leaves undefined, so a check of them is *warned*, never
//! *failed*, when the FMU does not detect the mistake (issue 51 item 1; `--strict` fails it, as
//! this exporter's FMUs detect them all). [`crate::registry::Check::run_on`] runs these checks
//! inside [`crate::outcome::importers_mistake`]. A check that mixes mistakes with requirements
//! wraps only its mistakes itself.

/// `(check, why)`: the check's name and the standard's sentence, in a few words. Not here: a
/// wrong GUID / instantiationToken accepted (FMI 2.0.5 §2.1.5, FMI 3.0.2 §2.3.1: it "is used to
/// check that the modelDescription.xml file is compatible with the C code of the FMU"), which
/// the defective fixture TOKEN (conformance/tests/defective_fmus.rs) holds to be the FMU's.
pub const CHECKS: &[(&str, &str)] = &[
    (
        "instantiate_refuses_a_null_or_empty_instance_name_with_a_message",
        "FMI 2.0.5 §2.1.5 (fmi2Instantiate, instanceName): \"It is not allowed to provide a null pointer and this \
         string must be non-empty\": an obligation of the importer",
    ),
    (
        "instantiate_without_callbacks_or_logger_returns_null_without_crashing",
        "FMI 2.0.5 §2.1.5 (fmi2Instantiate, functions): the importer provides the callback functions \
         (logger, allocateMemory, freeMemory); missing ones are the importer's mistake",
    ),
    (
        "unknown_value_references_are_refused_with_a_message_naming_them",
        "FMI 2.0.5 §2.1.7 (fmi2GetXXX/fmi2SetXXX): the value references passed are those of the description's \
         variables of that type; an unknown one is the importer's mistake, whose answer is not prescribed",
    ),
    (
        "set_debug_logging_refuses_unknown_categories_and_null_arrays",
        "FMI 2.0.5 §2.1.5 (fmi2SetDebugLogging): the allowed categories are \"defined by the modeling \
         environment that generated the FMU\"; one it does not know, or a NULL array with nCategories > 0, \
         is the importer's mistake",
    ),
    (
        "a_null_component_is_refused_by_every_function",
        "FMI 2.0.5 §2.1.2/§2.1.5: the fmi2Component passed is the one fmi2Instantiate returned; NULL is the \
         importer's mistake",
    ),
    (
        "terminate_twice_is_refused_with_a_message",
        "FMI 2.0.5 §4.3.1 (state machine of co-simulation): fmi2Terminate is not a call of state Terminated; a \
         call outside the state machine is the importer's mistake, whose answer is not prescribed",
    ),
    (
        "fmi3_a_null_instance_is_refused_by_every_function",
        "FMI 3.0.2 §2.3.1: the fmi3Instance passed is the one fmi3Instantiate... returned; NULL is the \
         importer's mistake",
    ),
    (
        "fmi3_set_debug_logging_refuses_unknown_categories",
        "FMI 3.0.2 §2.3.1 (fmi3SetDebugLogging): categories are those of the modeling environment, \"none, some \
         or all\" declared in <LogCategories>; one the FMU does not know is the importer's mistake",
    ),
];

/// The standard's sentence of `check` if it is one of [`CHECKS`].
pub fn why(check: &str) -> Option<&'static str> {
    CHECKS.iter().find(|(name, _)| *name == check).map(|(_, why)| *why)
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_check_named_is_a_registered_check() {
        let names: Vec<&str> = crate::checks::all_checks().iter().map(|c| c.name).collect();
        for (name, _) in super::CHECKS {
            assert!(names.contains(name), "{name} is no check");
        }
    }
}
