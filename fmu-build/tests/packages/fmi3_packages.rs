//! The FMI 3.0 packages `cargo fmu build` makes next to the FMI 2.0 ones: every FMU of the
//! workspace in both versions, each valid, each binary exporting its own version's functions only.
//! Needs `target/fmu/{,fmi3/}{Pendulum,Controller,DCMotor}.fmu`
//! (`cargo run --release -p fmu-build -- build --workspace`).

use crate::common::{MODELS, entry, fmu_dir};
use fmu_build::validate::{FMI2_FUNCTIONS, FMI3_FUNCTIONS, elf_exports, export_problems, validate};
use rustfmu::description::FmiVersion;
use std::io::Write;
use std::path::PathBuf;

#[test]
fn every_fmu_is_packaged_in_both_versions_and_valid() {
    for id in MODELS {
        let fmu2 = fmu_dir().join(format!("{id}.fmu"));
        let fmu3 = fmu_dir().join("fmi3").join(format!("{id}.fmu"));
        for f in [&fmu2, &fmu3] {
            assert!(
                f.is_file(),
                "{} is missing: cargo run --release -p fmu-build",
                f.display()
            );
            assert_eq!(validate(f), Vec::<String>::new(), "{}", f.display());
        }
        let xml3 = String::from_utf8(entry(&fmu3, "modelDescription.xml")).unwrap();
        assert!(
            xml3.contains("fmiVersion=\"3.0\"") && xml3.contains("instantiationToken=\"{"),
            "{xml3}"
        );
        let xml2 = String::from_utf8(entry(&fmu2, "modelDescription.xml")).unwrap();
        assert!(xml2.contains("fmiVersion=\"2.0\""), "{xml2}");
        // The 3.0 binary is in the platform tuple's folder and exports fmi3* only; the 2.0 one the reverse.
        let so3 = entry(&fmu3, &format!("binaries/x86_64-linux/{id}.so"));
        let so2 = entry(&fmu2, &format!("binaries/linux64/{id}.so"));
        let exports3 = elf_exports(&so3).expect("an ELF library");
        assert!(
            FMI3_FUNCTIONS.iter().all(|f| exports3.iter().any(|e| e == f)),
            "{id}: {exports3:?}"
        );
        assert!(!exports3.iter().any(|e| e.starts_with("fmi2")), "{id}: {exports3:?}");
        let exports2 = elf_exports(&so2).expect("an ELF library");
        assert!(
            FMI2_FUNCTIONS.iter().all(|f| exports2.iter().any(|e| e == f)),
            "{id}: {exports2:?}"
        );
        assert!(!exports2.iter().any(|e| e.starts_with("fmi3")), "{id}: {exports2:?}");
        // The committed copy is what was packaged.
        let committed = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../modelDescription/fmi3/{id}.xml"));
        assert_eq!(
            std::fs::read_to_string(&committed).unwrap(),
            xml3,
            "{}",
            committed.display()
        );
    }
}

#[test]
fn a_binary_of_the_other_version_is_reported() {
    let fmu2 = fmu_dir().join("Pendulum.fmu");
    let so2 = entry(&fmu2, "binaries/linux64/Pendulum.so");
    assert_eq!(export_problems(&so2, FmiVersion::V2, "x"), Vec::<String>::new());
    let problems = export_problems(&so2, FmiVersion::V3, "x");
    assert!(
        problems.iter().any(|p| p.contains("does not export fmi3GetVersion")),
        "{problems:?}"
    );
    assert!(
        problems
            .iter()
            .any(|p| p.contains("but exports") && p.contains("fmi2DoStep")),
        "{problems:?}"
    );

    // An FMI 3.0 package whose binary is the FMI 2.0 one: the description does not match it.
    let fmu3 = fmu_dir().join("fmi3").join("Pendulum.fmu");
    let doctored = std::env::temp_dir().join(format!("fmi3-with-fmi2-binary-{}.fmu", std::process::id()));
    let mut zip = zip::ZipWriter::new(std::fs::File::create(&doctored).unwrap());
    let options = zip::write::SimpleFileOptions::default();
    zip.start_file("modelDescription.xml", options).unwrap();
    zip.write_all(&entry(&fmu3, "modelDescription.xml")).unwrap();
    zip.start_file("binaries/x86_64-linux/Pendulum.so", options).unwrap();
    zip.write_all(&so2).unwrap();
    zip.finish().unwrap();
    let problems = validate(&doctored);
    let _ = std::fs::remove_file(&doctored);
    assert!(
        problems
            .iter()
            .any(|p| p.contains("says FMI 3.0") && p.contains("implements FMI 2.0")),
        "{problems:?}"
    );
}
