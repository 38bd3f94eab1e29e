//! The conformance suite's harness: it finds every packaged FMU (`target/fmu/*.fmu`), unpacks
//! it, reads its `modelDescription.xml` and loads its binary the way an importer does, and gives
//! the tests an instance wrapper that records every message the FMU logs.
//!
//! Nothing here knows a particular FMU: value references, types, causalities and variabilities
//! come from each FMU's model description, so every FMU added to `rustfmu::fmus::ALL` and
//! packaged by `fmu-build` is covered without a change.
//!
//! The FMU binaries are loaded once per test process (like an importer that keeps an FMU
//! loaded); the tests of unloading load their own copy.

pub mod api;
pub mod description;
pub mod instance;
pub mod logger;
pub mod standard;
pub mod state;

pub use api::Api;
pub use description::{Description, Type, Variable};
pub use instance::Instance;
pub use logger::LogEntry;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// One packaged FMU, unpacked and loaded.
pub struct Fmu {
    pub id: String,
    /// The `.fmu` archive.
    pub archive: PathBuf,
    /// Where it was unpacked (holds `modelDescription.xml`, `binaries/`, `resources/`...).
    pub dir: PathBuf,
    /// `binaries/linux64/<modelIdentifier>.so` inside `dir`.
    pub so: PathBuf,
    pub md: Description,
    pub api: Api,
}

impl Fmu {
    /// `file:///...` URI of the unpacked `resources/` folder.
    pub fn resource_uri(&self) -> String {
        format!("file://{}/resources", self.dir.display())
    }
}

/// The folder with the packaged FMUs: `$RUSTFMU_FMU_DIR`, else `<workspace>/target/fmu`.
pub fn fmu_dir() -> PathBuf {
    match std::env::var_os("RUSTFMU_FMU_DIR") {
        Some(d) => PathBuf::from(d),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/fmu"),
    }
}

/// Every packaged FMU of the workspace, loaded. Panics (failing the calling test with the
/// reason) when an FMU of `rustfmu::fmus::ALL` is not packaged or its package is stale: the
/// suite must never pass by testing fewer FMUs than the workspace has, or old binaries.
pub fn all() -> &'static [Fmu] {
    static ALL: OnceLock<Vec<Fmu>> = OnceLock::new();
    ALL.get_or_init(|| load_all().unwrap_or_else(|e| panic!("{e}")))
}

/// The packaged FMU of that model identifier (for tests written against one model).
pub fn by_id(id: &str) -> &'static Fmu {
    all()
        .iter()
        .find(|f| f.id == id)
        .unwrap_or_else(|| panic!("no packaged FMU '{id}'"))
}

fn load_all() -> Result<Vec<Fmu>, String> {
    let dir = fmu_dir();
    let hint = "build and package them first: cargo run --release -p fmu-build";
    let mut archives: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map_err(|e| format!("cannot list {}: {e} ({hint})", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "fmu"))
        .collect();
    archives.sort();
    let unpack_root = unpack_root()?;
    let mut fmus = Vec::new();
    for archive in archives {
        fmus.push(unpack(&archive, &unpack_root)?);
    }
    for entry in rustfmu::fmus::ALL {
        let id = entry.info.identifier;
        let Some(fmu) = fmus.iter().find(|f| f.id == id) else {
            return Err(format!(
                "{id} (in rustfmu::fmus::ALL) has no {id}.fmu in {}: {hint}",
                dir.display()
            ));
        };
        let expected = (entry.model_description)()?;
        let packaged = std::fs::read_to_string(fmu.dir.join("modelDescription.xml")).map_err(|e| e.to_string())?;
        if packaged != expected {
            return Err(format!(
                "{} is stale: its modelDescription.xml differs from what the declarations generate; {hint}",
                fmu.archive.display()
            ));
        }
    }
    if fmus.is_empty() {
        return Err(format!("no .fmu in {}: {hint}", dir.display()));
    }
    Ok(fmus)
}

/// A folder of this process under the system temp dir; folders of processes that are gone
/// (an interrupted run) are removed.
fn unpack_root() -> Result<PathBuf, String> {
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

fn unpack(archive: &Path, root: &Path) -> Result<Fmu, String> {
    let at = |e: &dyn std::fmt::Display| format!("{}: {e}", archive.display());
    let file = std::fs::File::open(archive).map_err(|e| at(&e))?;
    let mut zip = zip::ZipArchive::new(file).map_err(|e| at(&e))?;
    let mut xml = String::new();
    zip.by_name("modelDescription.xml")
        .map_err(|e| at(&e))?
        .read_to_string(&mut xml)
        .map_err(|e| at(&e))?;
    let md = Description::parse(&xml).map_err(|e| at(&e))?;
    let dir = root.join(&md.model_identifier);
    let _ = std::fs::remove_dir_all(&dir);
    zip.extract(&dir).map_err(|e| at(&e))?;
    std::fs::create_dir_all(dir.join("resources")).map_err(|e| at(&e))?;
    let so = dir.join(format!("binaries/linux64/{}.so", md.model_identifier));
    let api = Api::load(&so)?;
    Ok(Fmu {
        id: md.model_identifier.clone(),
        archive: archive.to_path_buf(),
        dir,
        so,
        md,
        api,
    })
}

/// Bit patterns of floats, so that "identical" means bit-identical (and NaN equals NaN).
pub fn bits(values: &[f64]) -> Vec<u64> {
    values.iter().map(|v| v.to_bits()).collect()
}
