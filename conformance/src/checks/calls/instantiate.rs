//! fmi2Instantiate: wrong, NULL or empty GUIDs and names, unknown types, missing callbacks, every
//! resource-location form.

#![allow(non_upper_case_globals)] // fmi2OK etc. are the standard's names, matched on

use super::says;
use crate::Fmu;
use crate::fmi2::*;
use crate::instance::{Args, Instance, status_name, step_size};
use crate::outcome::info;
use std::ptr;

/// fmi2Instantiate with a wrong, an empty or a NULL fmuGUID should return NULL, with a message
/// that names the GUID.
///
/// Verdict: an instance for such a GUID is warned, not failed. FMI 2.0.5 §2.1.5 (fmi2Instantiate):
/// "Argument fmuGUID is used to check that the modelDescription.xml file (see section 2.3) is
/// compatible with the C code of the FMU. [...] It must be identical to the one stored inside the
/// fmi2Instantiate function. Otherwise the C code and the XML file of the FMU are not consistent
/// to each other. This argument cannot be null." Each "must" and "cannot" binds what the importer
/// passes (and the exporter's packaging); no sentence requires fmi2Instantiate to return NULL for
/// another GUID, so not checking it is the FMU's choice, which leaves an importer's mistake (a
/// description of another build) undetected. A refusal without a message fails: "If a null
/// pointer is returned, then instantiation failed. In that case, function logger is called with
/// detailed information about the reason" (ibid.); that it names the GUID is this exporter's
/// convention ([`says`]).
pub fn instantiate_refuses_a_wrong_null_or_empty_guid_with_a_message(fmu: &Fmu) {
    for guid in [Some("{00000000-0000-0000-0000-000000000000}"), Some(""), None] {
        let args = Args {
            guid: guid.map(String::from),
            ..Args::valid(fmu)
        };
        let what = format!("GUID {guid:?}");
        match Instance::with(fmu, &args) {
            Ok(_accepted) => crate::outcome::warn(format!(
                "{}: fmi2Instantiate with {what} returned an instance: the FMU does not check that its \
                 modelDescription.xml is the one of its C code (FMI 2.0.5 §2.1.5: fmuGUID \"is used to check\" \
                 that, but no sentence requires the FMU to refuse another GUID)",
                fmu.id
            )),
            Err(log) => assert!(
                says(fmu, &log, fmi2Error, &["GUID"]),
                "{}: {what}: no message about the GUID (FMI 2.0.5 §2.1.5: when fmi2Instantiate returns NULL, \
                 \"function logger is called with detailed information about the reason\"): {log:?}",
                fmu.id
            ),
        }
    }
}

/// fmi2Instantiate with an empty or a NULL instanceName should return NULL, with a message that
/// names the argument.
///
/// Verdict: an instance for such a name is warned, not failed (the reading of the GUID's
/// verdict). FMI 2.0.5 §2.1.5 (fmi2Instantiate): "Argument instanceName is a unique identifier
/// for the FMU instance. [...] It is not allowed to provide a null pointer and this string must be
/// non-empty (in other words must have at least one character that is no white space)": the
/// importer's obligation; no sentence requires fmi2Instantiate to return NULL for such a name. A
/// refusal without a message fails: "If a null pointer is returned, then instantiation failed. In
/// that case, function logger is called with detailed information about the reason" (ibid.);
/// that it names instanceName is this exporter's convention ([`says`]).
pub fn instantiate_refuses_a_null_or_empty_instance_name_with_a_message(fmu: &Fmu) {
    for name in [Some(""), None] {
        let args = Args {
            name: name.map(String::from),
            ..Args::valid(fmu)
        };
        let what = format!("instanceName {name:?}");
        match Instance::with(fmu, &args) {
            Ok(_accepted) => crate::outcome::warn(format!(
                "{}: fmi2Instantiate with {what} returned an instance: the importer's mistake is not detected \
                 (FMI 2.0.5 §2.1.5: \"It is not allowed to provide a null pointer and this string must be \
                 non-empty\" binds the importer; no sentence requires the FMU to refuse it)",
                fmu.id
            )),
            Err(log) => assert!(
                says(fmu, &log, fmi2Error, &["instanceName"]),
                "{}: {what}: no message about the instance name (FMI 2.0.5 §2.1.5: when fmi2Instantiate returns \
                 NULL, \"function logger is called with detailed information about the reason\"): {log:?}",
                fmu.id
            ),
        }
    }
}

/// fmi2ModelExchange is refused unless the FMU declares `<ModelExchange>` (then it is
/// accepted); an unknown fmuType always.
///
/// Verdict: refusing fmi2ModelExchange that the FMU declares fails (FMI 2.0.5 §2.1.5: the FMU
/// is instantiated with the fmuType of an interface it declares). Accepting an interface the FMU
/// does not declare, or an fmuType that does not exist (7), is the importer's mistake, which the
/// standard leaves undefined: a warning (the importer then runs an interface the FMU never made).
pub fn instantiate_refuses_model_exchange_and_unknown_types_with_a_message(fmu: &Fmu) {
    for (ty, word) in [(fmi2ModelExchange, "fmi2ModelExchange"), (7, "fmuType")] {
        if ty == fmi2ModelExchange && fmu.md.me.is_some() {
            // Declared: fmi2ModelExchange must be accepted (the model-exchange checks go on).
            let args = Args {
                fmu_type: ty,
                ..Args::valid(fmu)
            };
            if let Err(log) = Instance::with(fmu, &args) {
                panic!(
                    "{}: the FMU declares <ModelExchange>, but fmi2Instantiate(fmi2ModelExchange) refused: {log:?}",
                    fmu.id
                );
            }
            continue;
        }
        let args = Args {
            fmu_type: ty,
            ..Args::valid(fmu)
        };
        let Some(log) = Instance::with(fmu, &args).err() else {
            crate::outcome::warn(format!(
                "{}: fmi2Instantiate with fmuType {ty} ({word}, not declared by the FMU) accepted: an importer's mistake not detected",
                fmu.id
            ));
            continue;
        };
        crate::outcome::warn_unless(
            log.iter().any(|e| e.text.contains(word)) || says(fmu, &log, fmi2Error, &[word]),
            || {
                format!(
                    "{}: fmuType {ty} refused without a message naming {word}: {log:?}",
                    fmu.id
                )
            },
        );
    }
}

pub fn instantiate_without_callbacks_or_logger_returns_null_without_crashing(fmu: &Fmu) {
    let guid = std::ffi::CString::new(fmu.md.guid.as_str()).unwrap();
    let no_logger = fmi2CallbackFunctions {
        logger: None,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: ptr::null_mut(),
    };
    for callbacks in [ptr::null(), &no_logger as *const _] {
        // SAFETY: valid strings; the callbacks are NULL or have a NULL logger.
        let c = unsafe {
            (fmu.api.instantiate)(
                c"x".as_ptr(),
                fmi2CoSimulation,
                guid.as_ptr(),
                ptr::null(),
                callbacks,
                fmi2False,
                fmi2True,
            )
        };
        assert!(c.is_null(), "{}: instantiated without a logger", fmu.id);
    }
}

/// fmi2Instantiate with the FMU's resources/ named in each form of a `file` URI (`file:///abs`,
/// `file:/abs`, `file://localhost/abs`, percent-encoded), then initialized and stepped; and with
/// locations that hold nothing (a missing folder, http, empty, NULL).
///
/// Verdict: failed where a `file` URI of the FMU's own resources is refused or its
/// initialization fails: FMI 2.0.5 §2.1.5 (fmi2Instantiate, fmuResourceLocation): "The following
/// schemes must be understood by the FMU: Mandatory: "file" with absolute path (either including
/// or omitting the authority component)" (RFC 8089: the authority `localhost` is this machine).
/// Without the files, an fmi2Error with a message is the right answer of a model that reads them.
pub fn instantiate_accepts_every_resource_location_form_and_a_missing_folder(fmu: &Fmu) {
    // The FMU's own unpacked resources/, and a copy of it under a name that needs encoding.
    let abs = fmu.dir.join("resources");
    let dir = fmu.dir.join("resources with space%");
    copy_tree(&abs, &dir).unwrap_or_else(|e| panic!("{}: copying resources/: {e}", fmu.id));
    let encoded = format!(
        "file://{}",
        dir.display().to_string().replace('%', "%25").replace(' ', "%20")
    );
    assert!(encoded.ends_with("resources%20with%20space%25"));
    // (location, whether it holds the FMU's resources)
    let locations = [
        (Some(format!("file://{}", abs.display())), true),
        (Some(format!("file:{}", abs.display())), true),
        (Some(format!("file://localhost{}", abs.display())), true),
        (Some(encoded), true),
        (Some(format!("file://{}/no/such/folder", fmu.dir.display())), false),
        (Some("http://example.org/resources".into()), false),
        (Some(String::new()), false),
        (None, false),
    ];
    let mut needs_them = vec![];
    for (loc, has_files) in locations {
        let args = Args {
            resources: loc.clone(),
            ..Args::valid(fmu)
        };
        let mut inst = match Instance::with(fmu, &args) {
            Ok(inst) => inst,
            // An FMU that reads its resources when it is instantiated (a container FMU, whose
            // system is there) cannot be made without them: NULL with an fmi2Error message
            // naming what is missing is its answer. With its files, refusing is a failure.
            Err(log) if !has_files && log.iter().any(|e| e.status == fmi2Error) => {
                needs_them.push(format!("{loc:?} (at fmi2Instantiate)"));
                continue;
            }
            Err(log) => panic!("{}: resourceLocation {loc:?} refused: {log:?}", fmu.id),
        };
        if has_files {
            let s = [inst.setup(0.0, None), inst.enter_init(), inst.exit_init()];
            assert!(
                s.iter().all(|s| *s == fmi2OK || *s == fmi2Warning),
                "{}: with fmuResourceLocation {loc:?} (the FMU's own resources/), initialization answered {:?}: {} \
                 (FMI 2.0.5 §2.1.5, fmi2Instantiate: the scheme \"file\" with an absolute path, \"either including or \
                 omitting the authority component\", must be understood; RFC 8089: the authority \"localhost\" is this \
                 machine)",
                fmu.id,
                s.map(status_name),
                inst.log_text()
            );
            assert_eq!(
                inst.step(step_size(fmu)),
                fmi2OK,
                "{}: after resourceLocation {loc:?}",
                fmu.id
            );
            continue;
        }
        // Without its files a model that reads them cannot initialize: an fmi2Error with a
        // message is its right answer (the standard only says a missing folder is no reason
        // to refuse the instance); anything else must run as usual.
        let s = [inst.setup(0.0, None), inst.enter_init(), inst.exit_init()];
        if s.iter().all(|s| *s == fmi2OK) {
            assert_eq!(
                inst.step(step_size(fmu)),
                fmi2OK,
                "{}: after resourceLocation {loc:?}",
                fmu.id
            );
        } else {
            let log = inst.log();
            assert!(
                s.iter().all(|s| *s == fmi2OK || *s == fmi2Error) && log.iter().any(|e| e.status == fmi2Error),
                "{}: initialization with resourceLocation {loc:?} answered {s:?} with no fmi2Error message: {log:?}",
                fmu.id
            );
            needs_them.push(format!("{loc:?}"));
        }
    }
    if !needs_them.is_empty() {
        info(format!(
            "initialization needs the FMU's resources: refused with a message for {}",
            needs_them.join(", ")
        ));
    }
}

/// Copies the folder `from` (files and sub-folders) to `to`.
pub(super) fn copy_tree(from: &std::path::Path, to: &std::path::Path) -> std::io::Result<()> {
    std::fs::create_dir_all(to)?;
    for e in std::fs::read_dir(from)? {
        let e = e?;
        let target = to.join(e.file_name());
        if e.file_type()?.is_dir() {
            copy_tree(&e.path(), &target)?;
        } else {
            std::fs::copy(e.path(), target)?;
        }
    }
    Ok(())
}
