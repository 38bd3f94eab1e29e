//! Packaged FMUs from `target/fmu`, loaded into this process as a master loads them (for the
//! tests that put several FMUs in one process). Needs `target/fmu/<name>.fmu`
//! (`cargo run --release -p fmu-build -- build --workspace`).
#![allow(dead_code)] // each test binary uses a part

use rustfmu::__private::abi::*;
use rustfmu::description::{ModelDescription, decode, find_encoded_for};
use std::io::Read;
use std::path::PathBuf;

/// fmi2GetRealStatus (the abi names no type for it).
type RealStatus = unsafe extern "C" fn(fmi2Component, fmi2StatusKind, *mut fmi2Real) -> fmi2Status;

/// One FMU's binary, loaded, its description, and the functions the tests call.
pub struct Fmu {
    pub name: &'static str,
    pub guid: String,
    pub md: ModelDescription,
    pub instantiate: Instantiate,
    pub free_instance: fmi2FreeInstanceTYPE,
    pub setup: fmi2SetupExperimentTYPE,
    pub enter_init: fmi2ComponentFunctionTYPE,
    pub exit_init: fmi2ComponentFunctionTYPE,
    pub terminate: fmi2ComponentFunctionTYPE,
    pub reset: fmi2ComponentFunctionTYPE,
    pub do_step: fmi2DoStepTYPE,
    pub get_real: fmi2GetTYPE<fmi2Real>,
    pub set_real: fmi2SetTYPE<fmi2Real>,
    pub set_integer: fmi2SetTYPE<fmi2Integer>,
    pub set_boolean: fmi2SetTYPE<fmi2Boolean>,
    pub real_status: RealStatus,
    pub get_state: fmi2GetFMUstateTYPE,
    pub set_state: fmi2SetFMUstateTYPE,
    pub free_state: fmi2GetFMUstateTYPE,
    pub state_size: fmi2SerializedFMUstateSizeTYPE,
    pub serialize: fmi2SerializeFMUstateTYPE,
    pub deserialize: fmi2DeSerializeFMUstateTYPE,
    _lib: libloading::Library,
}

/// The FMU crates of the workspace, by model identifier.
pub const MODELS: [&str; 3] = ["Pendulum", "Controller", "DCMotor"];

/// `target/fmu` (`$CARGO_TARGET_DIR/fmu`): the FMI 2.0 FMUs, the 3.0 ones in `fmi3/`.
pub fn fmu_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target"))
        .join("fmu")
}

/// The bytes of the archive entry `name` of `fmu`.
pub fn entry(fmu: &std::path::Path, name: &str) -> Vec<u8> {
    let mut zip = zip::ZipArchive::new(std::fs::File::open(fmu).unwrap()).unwrap();
    let mut e = zip
        .by_name(name)
        .unwrap_or_else(|_| panic!("{}: no {name}", fmu.display()));
    let mut out = Vec::new();
    e.read_to_end(&mut out).unwrap();
    out
}

impl Fmu {
    /// Unpacks `target/fmu/<name>.fmu`'s linux64 binary and loads it.
    pub fn load(name: &'static str) -> Fmu {
        let path = fmu_dir().join(format!("{name}.fmu"));
        let file = std::fs::File::open(&path).unwrap_or_else(|e| {
            panic!(
                "{}: {e}: run `cargo run --release -p fmu-build -- build --workspace` first",
                path.display()
            )
        });
        let mut zip = zip::ZipArchive::new(file).expect("an FMU is a zip archive");
        let mut binary = Vec::new();
        zip.by_name(&format!("binaries/linux64/{name}.so"))
            .unwrap_or_else(|e| panic!("{name}.fmu: {e}"))
            .read_to_end(&mut binary)
            .unwrap();
        // The FMI 2.0 description: the binary carries one per version, in whatever order the
        // linker laid them out.
        let encoded =
            find_encoded_for(&binary, rustfmu::description::FmiVersion::V2).unwrap_or_else(|e| panic!("{name}: {e}"));
        let (md, _) = decode(encoded).unwrap_or_else(|e| panic!("{name}: {e}"));
        let guid = rustfmu::description::guid_string(encoded);
        let so = std::env::temp_dir().join(format!("rustfmu-test-{}-{name}.so", std::process::id()));
        std::fs::write(&so, &binary).unwrap();
        // SAFETY: an FMU's binary; loading runs no initializers beyond Rust's own.
        let lib = unsafe { libloading::Library::new(&so) }.unwrap_or_else(|e| panic!("{name}: {e}"));
        let _ = std::fs::remove_file(&so);
        // SAFETY: the FMI 2.0 functions have these signatures (tests/abi_matches_fmi_sys.rs).
        unsafe {
            macro_rules! f {
                ($sym:literal) => {
                    *lib.get($sym).unwrap_or_else(|e| panic!("{name}: {e}"))
                };
            }
            Fmu {
                name,
                guid,
                md,
                instantiate: f!(b"fmi2Instantiate"),
                free_instance: f!(b"fmi2FreeInstance"),
                setup: f!(b"fmi2SetupExperiment"),
                enter_init: f!(b"fmi2EnterInitializationMode"),
                exit_init: f!(b"fmi2ExitInitializationMode"),
                terminate: f!(b"fmi2Terminate"),
                reset: f!(b"fmi2Reset"),
                do_step: f!(b"fmi2DoStep"),
                get_real: f!(b"fmi2GetReal"),
                set_real: f!(b"fmi2SetReal"),
                set_integer: f!(b"fmi2SetInteger"),
                set_boolean: f!(b"fmi2SetBoolean"),
                real_status: f!(b"fmi2GetRealStatus"),
                get_state: f!(b"fmi2GetFMUstate"),
                set_state: f!(b"fmi2SetFMUstate"),
                free_state: f!(b"fmi2FreeFMUstate"),
                state_size: f!(b"fmi2SerializedFMUstateSize"),
                serialize: f!(b"fmi2SerializeFMUstate"),
                deserialize: f!(b"fmi2DeSerializeFMUstate"),
                _lib: lib,
            }
        }
    }

    /// A new instance and its log (leaked: the tests make a bounded number).
    pub fn instance(&self, logging_on: bool) -> (fmi2Component, &'static Log) {
        let log = Log::leak();
        let how = Instantiation {
            logging_on,
            ..Instantiation::new(fmi2CoSimulation, c"test")
        };
        let c = how.call(self.instantiate, &self.guid, log);
        assert!(!c.is_null(), "{}: fmi2Instantiate: {:?}", self.name, log.take_texts());
        (c, log)
    }

    /// The serialized form of c's current state.
    pub fn serialized(&self, c: fmi2Component) -> Vec<u8> {
        // SAFETY: c is a live instance of this FMU; the buffers are as large as passed.
        unsafe {
            let mut s: fmi2FMUstate = std::ptr::null_mut();
            assert_eq!((self.get_state)(c, &mut s), fmi2OK);
            let mut n = 0;
            assert_eq!((self.state_size)(c, s, &mut n), fmi2OK);
            let mut bytes = vec![0u8; n];
            assert_eq!((self.serialize)(c, s, bytes.as_mut_ptr() as *mut fmi2Byte, n), fmi2OK);
            assert_eq!((self.free_state)(c, &mut s), fmi2OK);
            bytes
        }
    }
}

/// One instance's log, reached through its componentEnvironment.
pub use rustfmu::testing::Log;
use rustfmu::testing::fmi2::{Instantiate, Instantiation};
