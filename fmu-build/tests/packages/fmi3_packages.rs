//! The FMI 3.0 packages `cargo fmu build` makes next to the FMI 2.0 ones: every FMU of the
//! workspace in both versions, each valid, one binary per platform serving both (it exports the
//! functions of both versions and carries both descriptions).
//! Needs `target/fmu/{,fmi3/}{Pendulum,Controller,DCMotor}.fmu` (`cargo fmu build --workspace`).

use crate::common::{MODELS, entry, fmu_dir};
use fmu_build::validate::{FMI2_FUNCTIONS, FMI3_FUNCTIONS, check_exports, elf_exports, export_problems, validate};
use rustfmu::description::FmiVersion;
use std::collections::BTreeSet;
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
        // One binary in both packages (the 3.0 one in the platform tuple's folder): it exports
        // every function of both standards and nothing else, and carries both descriptions.
        let so3 = entry(&fmu3, &format!("binaries/x86_64-linux/{id}.so"));
        let so2 = entry(&fmu2, &format!("binaries/linux64/{id}.so"));
        assert!(
            so2 == so3,
            "{id}: the FMI 2.0 and 3.0 packages carry different binaries"
        );
        let exports: BTreeSet<String> = elf_exports(&so3).expect("an ELF library").into_iter().collect();
        let standard: BTreeSet<String> = FMI2_FUNCTIONS
            .iter()
            .chain(FMI3_FUNCTIONS)
            .map(|f| f.to_string())
            .collect();
        assert_eq!(exports, standard, "{id}");
        // One description of each version, in the linker's order.
        let mut versions: Vec<FmiVersion> = fmu_build::library::library_versions(&so3)
            .unwrap()
            .iter()
            .map(|me| me.interfaces.version)
            .collect();
        versions.sort();
        assert_eq!(versions, [FmiVersion::V2, FmiVersion::V3], "{id}");
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
    let so = entry(&fmu2, "binaries/linux64/Pendulum.so");
    assert_eq!(export_problems(&so, FmiVersion::V2, "x"), Vec::<String>::new());
    assert_eq!(export_problems(&so, FmiVersion::V3, "x"), Vec::<String>::new());
    // A binary of FMI 2.0 only (what `export_fmi2!` alone makes) in an FMI 3.0 package.
    let only2: Vec<String> = FMI2_FUNCTIONS.iter().map(|f| f.to_string()).collect();
    let problems = check_exports(&only2, FmiVersion::V3, "x");
    assert!(
        problems.iter().any(|p| p.contains("does not export fmi3GetVersion")),
        "{problems:?}"
    );
    // The other version is allowed whole only: part of it, or a name outside its standard, is not.
    let mut partly: Vec<String> = FMI3_FUNCTIONS.iter().map(|f| f.to_string()).collect();
    partly.push("fmi2DoStep".into());
    let problems = check_exports(&partly, FmiVersion::V3, "x");
    assert!(
        problems.iter().any(|p| p.contains("and exports fmi2DoStep")),
        "{problems:?}"
    );
    let mut odd: Vec<String> = FMI2_FUNCTIONS
        .iter()
        .chain(FMI3_FUNCTIONS)
        .map(|f| f.to_string())
        .collect();
    odd.push("fmi2Frobnicate".into());
    let problems = check_exports(&odd, FmiVersion::V3, "x");
    assert!(problems.iter().any(|p| p.contains("fmi2Frobnicate")), "{problems:?}");

    // An FMI 3.0 package whose binary carries the FMI 2.0 description only (its 3.0 one made
    // unreadable): the description does not match it.
    let mut only2 = so.clone();
    let e3 = rustfmu::description::find_encoded_for(&so, FmiVersion::V3).unwrap();
    let at = e3.as_ptr() as usize - so.as_ptr() as usize;
    only2[at..at + 8].fill(0);
    let fmu3 = fmu_dir().join("fmi3").join("Pendulum.fmu");
    let doctored = std::env::temp_dir().join(format!("fmi3-with-fmi2-binary-{}.fmu", std::process::id()));
    let mut zip = zip::ZipWriter::new(std::fs::File::create(&doctored).unwrap());
    let options = zip::write::SimpleFileOptions::default();
    zip.start_file("modelDescription.xml", options).unwrap();
    zip.write_all(&entry(&fmu3, "modelDescription.xml")).unwrap();
    zip.start_file("binaries/x86_64-linux/Pendulum.so", options).unwrap();
    zip.write_all(&only2).unwrap();
    zip.finish().unwrap();
    let problems = validate(&doctored);
    let _ = std::fs::remove_file(&doctored);
    assert!(
        problems
            .iter()
            .any(|p| p.contains("says FMI 3.0") && p.contains("implements FMI 2.0 only")),
        "{problems:?}"
    );
}
