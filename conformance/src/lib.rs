//! A black-box checker of FMI 2.0 and FMI 3.0 FMUs (co-simulation, and model exchange where the
//! FMU declares it): it loads an `.fmu` the way an importer does (unpacks it, reads its
//! `modelDescription.xml`, `dlopen`s its binary) and drives its C API through named checks: one
//! registry of both versions ([`checks::all_checks`]; the FMI 2.0 checks in [`checks`]' files,
//! the FMI 3.0 ones in [`fmi3::checks`]'), each check of one version, chosen by the file's
//! `fmiVersion`. An FMU is loaded as its version's [`Loaded`] kind: [`Fmu`] or [`Fmu3`].
//!
//! - [`runner::run`] checks one FMU file, each check in a child process of its own, so that an
//!   FMU that crashes or hangs fails that check and nothing else; [`runner::worker_main`] is the
//!   child's side. The `fmu-check` binary of this crate uses both; `cargo fmu check` too.
//! - [`archive`] is the one way an (untrusted) FMU file is opened and unpacked.
//! - The workspace's own test run (`cargo test -p fmi-conformance`) runs every check on every
//!   packaged FMU of its version ([`all`], [`checks::on_every_fmu`]; `target/fmu` and
//!   `target/fmu/fmi3`), strictly: there, a limitation or a skip fails.
//!
//! Nothing here knows a particular FMU: value references, types, causalities and variabilities
//! come from each FMU's model description, read by the `md-reader` crate (the reader
//! `cargo fmu` and the runner use too; it knows the standard, not this exporter). Nothing depends on the exporter either: the C types
//! are declared from the standard ([`fmi2`]). Where a check can do more on an FMU of this
//! exporter (whose serialized FMU state it can read and rewrite, see [`state`]), it finds out
//! with [`Fmu::own_state_format`] and, on another exporter's FMU, tests what an importer can
//! reach and reports the rest as a limitation.

pub mod api;
pub mod archive;
pub mod calllog;
pub mod checks;
pub mod fmi2;
pub mod fmi3;
pub mod guard;
pub mod instance;
pub mod instance_calls;
pub mod logger;
pub mod me;
pub mod outcome;
pub mod reference_results;
pub mod registry;
pub mod replay;
pub mod replay_calls;
pub mod report;
pub mod runner;
pub mod standard;
pub mod state;

pub use api::Api;
pub use fmi3::Fmu3;
pub use instance::Instance;
pub use logger::LogEntry;
pub use md_reader::Version;
pub use md_reader::fmi2::{ModelDescription as Description, Type, Variable};

use archive::PrivateDir;

/// Reads an FMI 2.0 description the suite can check: one with `<CoSimulation>` (the 2.0 checks
/// drive co-simulation, and model exchange besides where it is declared).
pub fn parse_description(xml: &str) -> Result<Description, String> {
    let md = Description::parse(xml)?;
    match &md.cs {
        Some(cs) if !cs.model_identifier.is_empty() => Ok(md),
        _ => Err("modelDescription.xml: no <CoSimulation modelIdentifier=...>: not a co-simulation FMU".into()),
    }
}

/// The FMI 2.0 binaries folder of the platform this checker runs on: it loads that binary.
#[cfg(not(windows))]
pub const PLATFORM2: &str = "linux64";
/// The FMI 2.0 binaries folder of the platform this checker runs on: it loads that binary.
#[cfg(windows)]
pub const PLATFORM2: &str = "win64";
/// The file extension of a shared library here.
#[cfg(not(windows))]
pub const LIBRARY_EXTENSION: &str = "so";
/// The file extension of a shared library here.
#[cfg(windows)]
pub const LIBRARY_EXTENSION: &str = "dll";
use fmi2::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Mutex, OnceLock};

/// One FMU, unpacked into a private folder and loaded.
pub struct Fmu {
    pub id: String,
    /// The `.fmu` archive.
    pub archive: PathBuf,
    /// Where it was unpacked (holds `modelDescription.xml`, `binaries/`, `resources/`...).
    pub dir: PathBuf,
    /// `binaries/linux64/<modelIdentifier>.so` inside `dir`.
    pub so: PathBuf,
    /// A private folder for the suite's own files (compiled hosts, state files, copies).
    pub scratch: PathBuf,
    pub md: Description,
    pub api: Api,
    own: OnceLock<Result<(), String>>,
    /// The state bytes of the model-exchange states (see [`me::StateCodes`]).
    me_codes: OnceLock<Result<me::StateCodes, String>>,
    /// Last: removed after the library is unloaded.
    _dirs: (PrivateDir, PrivateDir),
}

impl Fmu {
    /// Unpacks the archive (through [`archive::extract_private`]) into a new private folder
    /// under `parent` and loads its binary. The folders are removed when this is dropped.
    pub fn load(path: &Path, parent: &Path) -> Result<Fmu, String> {
        let mut zip = archive::open(path)?;
        let md = fmi2_description(&mut zip, path, "FMI 2.0 FMUs")?;
        let id = md.model_identifier().to_owned();
        let u = Unpacked::new(path, parent, &mut zip, &id, PLATFORM2)?;
        let api = Api::load(&u.so)?;
        Ok(Fmu {
            id,
            archive: path.to_path_buf(),
            dir: u.dir,
            so: u.so,
            scratch: u.scratch,
            md,
            api,
            own: OnceLock::new(),
            me_codes: OnceLock::new(),
            _dirs: u.dirs,
        })
    }

    /// `file:///...` URI of the unpacked `resources/` folder (on Windows `file:///C:/...`).
    pub fn resource_uri(&self) -> String {
        if cfg!(windows) {
            format!(
                "file:///{}/resources",
                self.dir.display().to_string().replace('\\', "/")
            )
        } else {
            format!("file://{}/resources", self.dir.display())
        }
    }

    /// Whether this FMU serializes its state in this exporter's format (magic `RFMUSTAT`, its
    /// own GUID, a valid checksum): then it was made by this exporter, and the checks may read
    /// and rewrite its state-machine state ([`state`]) and hold it to the exporter's conventions
    /// ([`outcome::convention`]). Found out once, by instantiating it and serializing its state.
    pub fn own_state_format(&self) -> bool {
        self.state_format().is_ok()
    }

    /// Ok for this exporter's state format, else why not.
    pub fn state_format(&self) -> &Result<(), String> {
        self.own.get_or_init(|| self.detect_state_format())
    }

    /// The `<CoSimulation>` element ([`Fmu::load`] refuses a description without one).
    pub fn cs(&self) -> &md_reader::fmi2::CoSimulation {
        self.md
            .cs
            .as_ref()
            .expect("Fmu::load refuses a description without <CoSimulation>")
    }

    /// Whether the FMU declares that its state can be taken and serialized, so that the checks
    /// can compare the whole state before and after a call.
    pub fn can_snapshot(&self) -> bool {
        self.cs().can_get_and_set_fmu_state && self.cs().can_serialize_fmu_state
    }

    fn detect_state_format(&self) -> Result<(), String> {
        if AS_FOREIGN.load(Ordering::Relaxed) {
            return Err("treated as another exporter's FMU on request".into());
        }
        if !self.can_snapshot() {
            return Err("the FMU does not declare canGetAndSetFMUstate and canSerializeFMUstate".into());
        }
        let sink = logger::LogSink::default();
        let callbacks = logger::callbacks(sink.env());
        let guid = std::ffi::CString::new(self.md.guid.as_str()).map_err(|e| e.to_string())?;
        let res = std::ffi::CString::new(self.resource_uri()).map_err(|e| e.to_string())?;
        // SAFETY: the standard's calls with valid arguments on an instance made here.
        unsafe {
            let api = &self.api;
            outcome::breadcrumb("fmi2Instantiate (probing the state format)");
            let c = api.instantiate_cs(c"probe", &guid, &res, &callbacks);
            if c.is_null() {
                return Err("fmi2Instantiate returned NULL".into());
            }
            let mut s: fmi2FMUstate = std::ptr::null_mut();
            let mut bytes = vec![];
            let mut status = crate::guard::fill_state2(&mut s, "fmi2GetFMUstate", |q| (api.get_fmu_state)(c, q));
            if status == fmi2OK {
                let mut size = 0usize;
                status = crate::guard::fill_state_size2(&mut size, "fmi2SerializedFMUstateSize", |p| {
                    (api.serialized_fmu_state_size)(c, s, p)
                });
                if status == fmi2OK && size <= 1 << 30 {
                    let mut guarded = guard::Guarded::new(size, 0u8);
                    outcome::breadcrumb("fmi2SerializeFMUstate (probing the state format)");
                    status = (api.serialize_fmu_state)(c, s, guarded.as_mut_ptr() as *mut fmi2Byte, size);
                    match guarded.try_values(
                        || format!("fmi2SerializeFMUstate with size = {size}"),
                        guard::STATE_RULE2,
                    ) {
                        Ok(b) => bytes = b,
                        Err(e) => {
                            crate::guard::fill_state2(&mut s, "fmi2FreeFMUstate", |q| (api.free_fmu_state)(c, q));
                            outcome::breadcrumb("fmi2FreeInstance (probing the state format)");
                            (api.free_instance)(c);
                            return Err(e);
                        }
                    }
                }
                crate::guard::fill_state2(&mut s, "fmi2FreeFMUstate", |q| (api.free_fmu_state)(c, q));
            }
            outcome::breadcrumb("fmi2FreeInstance (probing the state format)");
            (api.free_instance)(c);
            if status != fmi2OK {
                return Err(format!("serializing the state of a new instance answered {status}"));
            }
            let l = state::parse(&bytes)?;
            if &bytes[l.guid_at..l.guid_at + l.guid_len] != self.md.guid.as_bytes() {
                return Err("the serialized state holds another GUID".into());
            }
            Ok(())
        }
    }
}

/// What the suite loads and checks: an FMI 2.0 FMU ([`Fmu`]) or an FMI 3.0 one ([`fmi3::Fmu3`]).
/// One machinery over both: [`all`] loads the packaged FMUs of a version,
/// [`registry::Check::run_on`] runs a check of that version on one, [`checks::on_every_fmu`] runs a
/// check on every packaged FMU of its version, and the runner's worker loads a file as its
/// version's kind.
pub trait Loaded: Sized + Sync + 'static {
    /// The FMI version of this kind of FMU.
    const VERSION: Version;
    /// Unpacks the archive into a new private folder under `parent` and loads its binary; the
    /// folders are removed when the value is dropped.
    fn load(path: &Path, parent: &Path) -> Result<Self, String>;
    /// The model identifier.
    fn id(&self) -> &str;
    /// The FMU file it was loaded from.
    fn archive(&self) -> &Path;
    /// Ok for this exporter's serialized state format, else why not (see [`Fmu::state_format`]).
    fn state_format(&self) -> &Result<(), String>;
    /// The report's head for a file of this version, from the archive alone (no FMU code runs).
    fn describe(path: &Path) -> Result<Vec<String>, String>;
    /// The folder with the workspace's packaged FMUs of this version.
    fn packaged_dir() -> PathBuf;
    /// Every packaged FMU of this version ([`packaged_dir`](Loaded::packaged_dir)), loaded once.
    fn packaged() -> &'static [Self];
}

/// `impl Loaded for $fmu`, of that FMI version, from its type's own `load`, `id` and
/// `state_format`, the version's `describe` and its packaged folder: the two kinds differ in
/// nothing else.
macro_rules! impl_loaded {
    ($fmu:ty, $version:ident, $describe:path, $dir:path) => {
        impl $crate::Loaded for $fmu {
            const VERSION: $crate::Version = $crate::Version::$version;
            fn load(path: &std::path::Path, parent: &std::path::Path) -> Result<Self, String> {
                <$fmu>::load(path, parent)
            }
            fn id(&self) -> &str {
                &self.id
            }
            fn archive(&self) -> &std::path::Path {
                &self.archive
            }
            fn state_format(&self) -> &Result<(), String> {
                <$fmu>::state_format(self)
            }
            fn describe(path: &std::path::Path) -> Result<Vec<String>, String> {
                $describe(path)
            }
            fn packaged_dir() -> std::path::PathBuf {
                $dir()
            }
            fn packaged() -> &'static [Self] {
                static ALL: std::sync::OnceLock<Vec<$fmu>> = std::sync::OnceLock::new();
                ALL.get_or_init($crate::load_packaged)
            }
        }
    };
}
pub(crate) use impl_loaded;

impl_loaded!(Fmu, Fmi2, describe, fmu_dir);

/// The model description of the archive at `path`, which must be an FMI 2.0 one (else the
/// error says that this checker checks `what`).
fn fmi2_description(zip: &mut archive::Archive, path: &Path, what: &str) -> Result<Description, String> {
    let xml = archive::read_model_description(zip)?;
    let md = parse_description(&xml).map_err(|e| format!("{}: {e}", path.display()))?;
    if md.fmi_version != "2.0" {
        return Err(format!(
            "{}: fmiVersion \"{}\": this checker checks {what}",
            path.display(),
            md.fmi_version
        ));
    }
    Ok(md)
}

/// The head of the report for an FMI 2.0 file, from the archive alone.
fn describe(fmu_path: &Path) -> Result<Vec<String>, String> {
    let mut a = archive::open(fmu_path)?;
    let md = fmi2_description(&mut a, fmu_path, "FMI 2.0 and FMI 3.0 FMUs")?;
    let so = format!("binaries/{}/{}.{}", PLATFORM2, md.model_identifier(), LIBRARY_EXTENSION);
    let tool = binary_and_tool(a.has_entry(&so), fmu_path, &so, &md.generation_tool)?;
    Ok(vec![format!(
        "model {} (FMI {}, GUID {}), {tool}",
        md.model_identifier(),
        md.fmi_version,
        md.guid
    )])
}

/// What the report's head of either version says of the archive: an error where it has no
/// binary `so` for this platform (`has_binary`), else what generated the FMU.
pub(crate) fn binary_and_tool(
    has_binary: bool,
    path: &Path,
    so: &str,
    generation_tool: &str,
) -> Result<String, String> {
    if !has_binary {
        return Err(format!(
            "{}: no {so}: the FMU has no binary for this platform",
            path.display()
        ));
    }
    Ok(if generation_tool.is_empty() {
        "no generationTool".to_string()
    } else {
        format!("generated by {generation_tool}")
    })
}

/// Loads `paths` (`RTLD_GLOBAL`) before any FMU binary of this process and of the checks'
/// workers: the checker's and `cargo fmu replay`'s `--preload-lib` (the runner's option; see
/// [`rustfmu_libpython::preload`]).
pub fn preload_libraries(paths: &[PathBuf]) -> Result<(), String> {
    rustfmu_libpython::preload(paths, "--preload-lib")
}

/// The FMI version of the FMU file's model description (its `fmiVersion`).
pub fn file_version(path: &Path) -> Result<Version, String> {
    let mut zip = archive::open(path)?;
    let xml = archive::read_model_description(&mut zip)?;
    let v = md_reader::fmi_version(&xml).map_err(|e| format!("{}: {e}", path.display()))?;
    Version::of(&v).ok_or_else(|| format!("{}: fmiVersion \"{v}\": neither FMI 2.0 nor FMI 3.0", path.display()))
}

/// An FMU archive unpacked for loading: its folder, its binary for this platform, a scratch
/// folder; both folders are removed when `dirs` is dropped.
pub(crate) struct Unpacked {
    pub dir: PathBuf,
    pub so: PathBuf,
    pub scratch: PathBuf,
    pub dirs: (PrivateDir, PrivateDir),
}

impl Unpacked {
    /// Checks that `id` (the model identifier) is a C identifier and that the archive has the
    /// binary `binaries/<platform>/<id>.<so>`, then unpacks it (through
    /// [`archive::extract_private`]) into a new private folder under `parent`, with a
    /// `resources/` folder (made empty when the archive has none).
    pub fn new(
        path: &Path,
        parent: &Path,
        zip: &mut archive::Archive,
        id: &str,
        platform: &str,
    ) -> Result<Unpacked, String> {
        let c_name = id.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && id.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !c_name {
            return Err(format!(
                "{}: modelIdentifier '{}' is not a C identifier",
                path.display(),
                id.escape_debug()
            ));
        }
        let so_entry = format!("binaries/{platform}/{id}.{LIBRARY_EXTENSION}");
        if !zip.has_entry(&so_entry) {
            let binaries: Vec<String> = zip
                .entry_names()
                .into_iter()
                .filter(|n| n.starts_with("binaries/") && !n.ends_with('/'))
                .collect();
            return Err(format!(
                "{}: no {so_entry}: no binary for this platform (binaries in the archive: {binaries:?})",
                path.display()
            ));
        }
        let unpacked = archive::extract_private(zip, parent, &archive::Limits::default())?;
        let scratch = PrivateDir::new_in(parent)?;
        let dir = unpacked.path().to_path_buf();
        std::fs::create_dir_all(dir.join("resources")).map_err(|e| format!("{}: {e}", dir.display()))?;
        Ok(Unpacked {
            so: dir.join(&so_entry),
            dir,
            scratch: scratch.path().to_path_buf(),
            dirs: (unpacked, scratch),
        })
    }
}

/// The folder with the packaged FMI 2.0 FMUs: `$RUSTFMU_FMU_DIR`, else `<workspace>/target/fmu`
/// (the FMI 3.0 ones are in its `fmi3/`, see [`fmi3::fmu3_dir`]).
pub fn fmu_dir() -> PathBuf {
    match std::env::var_os("RUSTFMU_FMU_DIR") {
        Some(d) => PathBuf::from(d),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/fmu"),
    }
}

/// Every packaged FMU of the workspace of one FMI version (`all::<Fmu>()`, `all::<Fmu3>()`:
/// `*.fmu` in [`Loaded::packaged_dir`]), loaded. Panics (failing the calling test with the
/// reason) when there is none: the suite must never pass by testing nothing.
pub fn all<F: Loaded>() -> &'static [F] {
    F::packaged()
}

/// The packaged FMI 2.0 FMU of that model identifier (for tests written against one model).
pub fn by_id(id: &str) -> &'static Fmu {
    all::<Fmu>()
        .iter()
        .find(|f| f.id == id)
        .unwrap_or_else(|| panic!("no packaged FMU '{id}'"))
}

/// Loads every `*.fmu` of [`Loaded::packaged_dir`]; panics when there is none or one does not load.
pub(crate) fn load_packaged<F: Loaded>() -> Vec<F> {
    let dir = F::packaged_dir();
    let hint = "build and package them first: cargo run --release -p fmu-build -- build --workspace";
    let mut archives: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("cannot list {}: {e} ({hint})", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "fmu"))
        .collect();
    archives.sort();
    assert!(!archives.is_empty(), "no .fmu in {}: {hint}", dir.display());
    let root = unpack_root().unwrap_or_else(|e| panic!("{e}"));
    archives
        .iter()
        .map(|a| F::load(a, &root).unwrap_or_else(|e| panic!("{e}")))
        .collect()
}

/// A folder of this process under the system temp dir; folders of processes that are gone
/// (an interrupted run) are removed.
pub(crate) fn unpack_root() -> Result<PathBuf, String> {
    let base = std::env::temp_dir().join("rustfmu-conformance");
    if let Ok(entries) = std::fs::read_dir(&base) {
        for e in entries.flatten() {
            let pid = e.file_name().to_string_lossy().parse::<u32>().ok();
            if pid.is_some_and(|p| !Path::new(&format!("/proc/{p}")).exists()) {
                let _ = std::fs::remove_dir_all(e.path());
            }
        }
    }
    let root = base.join(std::process::id().to_string());
    std::fs::create_dir_all(&root).map_err(|e| format!("{}: {e}", root.display()))?;
    Ok(root)
}

/// Bit patterns of floats, so that "identical" means bit-identical (and NaN equals NaN).
pub fn bits(values: &[f64]) -> Vec<u64> {
    values.iter().map(|v| v.to_bits()).collect()
}

/// How to start a worker process: the executable and the arguments before the worker's own
/// (see [`runner::worker_main`]). The check of restoring a state in another process needs it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Worker {
    pub exe: PathBuf,
    pub args_prefix: Vec<String>,
}

static WORKER: Mutex<Option<Worker>> = Mutex::new(None);
static RANDOM_SEQUENCES: AtomicU32 = AtomicU32::new(0);
static AS_FOREIGN: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Treats every FMU loaded from now on as another exporter's: the checks then test only what
/// an importer can reach, as they do on a foreign FMU. For testing the checks themselves (a
/// conformant FMU must pass them that way too).
pub fn set_as_foreign(on: bool) {
    AS_FOREIGN.store(on, Ordering::Relaxed);
}

/// Whether [`set_as_foreign`] is on (FMI 2.0 and 3.0 FMUs alike).
pub fn as_foreign() -> bool {
    AS_FOREIGN.load(Ordering::Relaxed)
}

/// Sets how checks start a worker process of their own.
pub fn set_worker(worker: Worker) {
    *WORKER.lock().unwrap_or_else(|e| e.into_inner()) = Some(worker);
}

pub fn worker() -> Option<Worker> {
    WORKER.lock().unwrap_or_else(|e| e.into_inner()).clone()
}

/// Sets the number of random call sequences per FMU (0: the default).
pub fn set_random_sequences(n: u32) {
    RANDOM_SEQUENCES.store(n, Ordering::Relaxed);
}

/// Random call sequences per FMU: as set, else `$PROPTEST_CASES`, else 2000.
pub fn random_sequences() -> u32 {
    match RANDOM_SEQUENCES.load(Ordering::Relaxed) {
        0 => std::env::var("PROPTEST_CASES")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(2000),
        n => n,
    }
}

/// The environment variable that fixes the seed of the random checks (the random call
/// sequences of both FMI versions): a number from 0 to 2^64 - 1. Without it a seed is drawn;
/// either way every random check prints it ([`seed_note`]), and the same seed with the same
/// number of sequences ([`random_sequences`]) makes the same calls.
pub const SEED_VAR: &str = "RUSTFMU_SEED";

static SEED: OnceLock<u64> = OnceLock::new();

/// `$RUSTFMU_SEED` ([`SEED_VAR`]): `None` when it is not set, an error when it is no u64.
pub fn seed_from_env() -> Result<Option<u64>, String> {
    match std::env::var(SEED_VAR) {
        Ok(v) => v
            .trim()
            .parse()
            .map(Some)
            .map_err(|_| format!("{SEED_VAR}={v:?} is not a seed (a number from 0 to 2^64 - 1)")),
        Err(std::env::VarError::NotPresent) => Ok(None),
        Err(e) => Err(format!("{SEED_VAR}: {e}")),
    }
}

/// The seed of the random checks in this process: `$RUSTFMU_SEED`, else one drawn once (from
/// the system's entropy, by proptest's RNG) and kept for the process. [`runner::run`] resolves
/// it once for a run and hands it to every worker in `$RUSTFMU_SEED`, so all of a run's checks
/// share it. Panics when `$RUSTFMU_SEED` is set but is no u64.
pub fn seed() -> u64 {
    *SEED.get_or_init(|| match seed_from_env() {
        Ok(Some(seed)) => seed,
        Ok(None) => {
            use proptest::prelude::Rng;
            use proptest::test_runner::{Config, RngSeed, TestRunner};
            let config = Config {
                rng_seed: RngSeed::Random,
                failure_persistence: None,
                ..Config::default()
            };
            TestRunner::new(config).rng().next_u64()
        }
        Err(e) => panic!("{e}"),
    })
}

/// A proptest configuration whose RNG is seeded from [`seed`] (proptest's own seeding:
/// `RngSeed::Fixed`, its ChaCha RNG): the same seed generates the same cases.
pub fn seeded(config: proptest::test_runner::Config) -> proptest::test_runner::Config {
    proptest::test_runner::Config {
        rng_seed: proptest::test_runner::RngSeed::Fixed(seed()),
        ..config
    }
}

/// What a random check prints in its report and in its failure message: the seed and how to run
/// the same sequences again.
pub fn seed_note() -> String {
    let (seed, n) = (seed(), random_sequences());
    format!(
        "random seed {seed}; rerun with {SEED_VAR}={seed} PROPTEST_CASES={n} (cargo test), or {SEED_VAR}={seed} and --random-sequences {n} (fmu-check, cargo fmu check), to repeat these sequences"
    )
}
