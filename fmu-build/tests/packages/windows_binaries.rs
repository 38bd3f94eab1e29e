//! The Windows binaries `cargo fmu build` puts next to the Linux ones in every FMU of the
//! workspace: read from their PE export and import tables, each exports exactly the functions of
//! its FMI version's standard and imports DLLs of Windows only (no MinGW runtime DLL).
//! Needs `target/fmu/{,fmi3/}{Pendulum,Controller,DCMotor}.fmu`
//! (`cargo run --release -p fmu-build -- build --workspace`). That they run: tests/python/test_windows.py.

use crate::common::{MODELS, entry, fmu_dir};
use fmu_build::validate::{FMI2_FUNCTIONS, FMI3_FUNCTIONS, info, not_windows_dlls, pe_problems, pe_tables};
use rustfmu::description::FmiVersion;
use std::collections::BTreeSet;

#[test]
fn every_fmu_has_a_linux_and_a_windows_binary_in_both_versions() {
    for id in MODELS {
        for (fmu, linux, windows) in [
            (fmu_dir().join(format!("{id}.fmu")), "linux64", "win64"),
            (
                fmu_dir().join("fmi3").join(format!("{id}.fmu")),
                "x86_64-linux",
                "x86_64-windows",
            ),
        ] {
            assert!(
                fmu.is_file(),
                "{} is missing: cargo run --release -p fmu-build",
                fmu.display()
            );
            assert!(entry(&fmu, &format!("binaries/{linux}/{id}.so")).starts_with(b"\x7fELF"));
            assert!(entry(&fmu, &format!("binaries/{windows}/{id}.dll")).starts_with(b"MZ"));
            // `cargo fmu info` lists them.
            let text = info(&fmu).unwrap();
            assert!(
                text.contains(&format!("{linux} ({id}.so)")) && text.contains(&format!("{windows} ({id}.dll)")),
                "{text}"
            );
        }
        // The FMI 3.0 file has aarch64 Linux too (FMI 2.0 names no folder for it).
        let fmu3 = fmu_dir().join("fmi3").join(format!("{id}.fmu"));
        let so = entry(&fmu3, &format!("binaries/aarch64-linux/{id}.so"));
        assert_eq!(&so[..4], b"\x7fELF");
        assert_eq!(
            u16::from_le_bytes([so[18], so[19]]),
            183,
            "{id}: e_machine is not EM_AARCH64"
        );
        assert!(info(&fmu3).unwrap().contains(&format!("aarch64-linux ({id}.so)")));
    }
}

#[test]
fn the_windows_binaries_export_both_standards_only_and_import_windows_dlls_only() {
    // One DLL per model serves both FMI versions: the same bytes in both packages.
    let standard: BTreeSet<&str> = FMI2_FUNCTIONS.iter().chain(FMI3_FUNCTIONS).copied().collect();
    for id in MODELS {
        let mut dlls = Vec::new();
        for (fmu, folder, version) in [
            (fmu_dir().join(format!("{id}.fmu")), "win64", FmiVersion::V2),
            (
                fmu_dir().join("fmi3").join(format!("{id}.fmu")),
                "x86_64-windows",
                FmiVersion::V3,
            ),
        ] {
            let name = format!("binaries/{folder}/{id}.dll");
            let dll = entry(&fmu, &name);
            let tables = pe_tables(&dll).expect("a PE file").expect("readable tables");
            let exported: BTreeSet<&str> = tables.exports.iter().map(String::as_str).collect();
            assert_eq!(exported, standard, "{id} {name}");
            assert_eq!(not_windows_dlls(&tables.imports), Vec::<&str>::new(), "{id} {name}");
            for mingw in ["libgcc_s_seh-1.dll", "libwinpthread-1.dll", "libstdc++-6.dll"] {
                assert!(
                    !tables.imports.iter().any(|d| d.eq_ignore_ascii_case(mingw)),
                    "{id} {name} imports {mingw}"
                );
            }
            assert_eq!(pe_problems(&dll, version, &name), Vec::<String>::new());
            dlls.push(dll);
        }
        assert!(
            dlls[0] == dlls[1],
            "{id}: the FMI 2.0 and 3.0 packages carry different DLLs"
        );
    }
}

#[test]
fn mingw_runtime_dlls_are_not_windows_dlls() {
    let dlls: Vec<String> = [
        "KERNEL32.dll",
        "msvcrt.dll",
        "api-ms-win-core-synch-l1-2-0.dll",
        "libgcc_s_seh-1.dll",
        "libwinpthread-1.dll",
    ]
    .map(String::from)
    .to_vec();
    assert_eq!(not_windows_dlls(&dlls), ["libgcc_s_seh-1.dll", "libwinpthread-1.dll"]);
    // An ELF file has no PE tables.
    assert!(pe_tables(b"\x7fELF\x02\x01\x01\0").is_none());
}
