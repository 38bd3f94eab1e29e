//! The `.fmu` archive: a zip with `modelDescription.xml` at the root,
//! `binaries/<platform>/<modelIdentifier>.<ext>`, `documentation/index.html`, `resources/`, and
//! the default experiment's run as FMI-LS-REF reference results
//! (`extra/org.fmi-standard.fmi-ls-ref/`: `fmi-ls-manifest.xml` and `<modelIdentifier>_out.csv`).
//! An FMI 2.0 binary goes to `target/fmu/<id>.fmu` (`binaries/linux64/`), an FMI 3.0 one to
//! `target/fmu/fmi3/<id>.fmu` (`binaries/x86_64-linux/`, the FMI 3.0 platform tuple). One FMU
//! holds the binaries of every target it was built for (`binaries/win64/<id>.dll`,
//! `binaries/x86_64-windows/<id>.dll`, ...: [`crate::target`]), all carrying the same description.

use crate::cargo::FmuCrate;
use crate::library::{SelfDescription, model_description, read_library};
use rustfmu::description::FmiVersion;
use std::io::Write;
use std::path::{Path, PathBuf};
use zip::write::SimpleFileOptions;

/// The platform folder of `binaries/` (FMI 2.0 names) for the machine fmu-build runs on.
pub fn platform() -> Result<(&'static str, &'static str), String> {
    platform_of(FmiVersion::V2)
}

/// The platform folder of `binaries/` for the machine fmu-build runs on, in the names of an FMI
/// version (2.0: `linux64`, ...; 3.0: the platform tuple `x86_64-linux`, ...), and the
/// extension of a shared library.
pub fn platform_of(version: FmiVersion) -> Result<(&'static str, &'static str), String> {
    let (os, arch) = (std::env::consts::OS, std::env::consts::ARCH);
    let found = match version {
        FmiVersion::V2 => match (os, arch) {
            ("linux", "x86_64") => Some(("linux64", "so")),
            ("linux", "x86") => Some(("linux32", "so")),
            ("windows", "x86_64") => Some(("win64", "dll")),
            ("macos", "x86_64" | "aarch64") => Some(("darwin64", "dylib")),
            _ => None,
        },
        FmiVersion::V3 => match (os, arch) {
            ("linux", "x86_64") => Some(("x86_64-linux", "so")),
            ("linux", "x86") => Some(("x86-linux", "so")),
            ("linux", "aarch64") => Some(("aarch64-linux", "so")),
            ("windows", "x86_64") => Some(("x86_64-windows", "dll")),
            ("windows", "x86") => Some(("x86-windows", "dll")),
            ("macos", "x86_64") => Some(("x86_64-darwin", "dylib")),
            ("macos", "aarch64") => Some(("aarch64-darwin", "dylib")),
            _ => None,
        },
    };
    found.ok_or_else(|| format!("FMI {} names no binaries folder for {os}/{arch}", version.text()))
}

/// Where the package of a model goes: `<fmu_dir>/<id>.fmu` for FMI 2.0,
/// `<fmu_dir>/fmi3/<id>.fmu` for FMI 3.0.
pub fn fmu_path(fmu_dir: &Path, version: FmiVersion, model_identifier: &str) -> PathBuf {
    match version {
        FmiVersion::V2 => fmu_dir.join(format!("{model_identifier}.fmu")),
        FmiVersion::V3 => fmu_dir.join("fmi3").join(format!("{model_identifier}.fmu")),
    }
}

/// What was packaged.
pub struct Packaged {
    pub fmu: PathBuf,
    pub version: FmiVersion,
    pub model_identifier: String,
    pub model_description: String,
}

/// Every file below `dir`, as (path relative to it with '/', absolute path), sorted.
fn files_below(dir: &Path) -> Result<Vec<(String, PathBuf)>, String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries = std::fs::read_dir(&d).map_err(|e| format!("{}: {e}", d.display()))?;
        for e in entries {
            let e = e.map_err(|e| format!("{}: {e}", d.display()))?;
            let path = e.path();
            let kind = e.file_type().map_err(|e| format!("{}: {e}", path.display()))?;
            if kind.is_dir() {
                stack.push(path);
            } else if kind.is_file() {
                let rel = path.strip_prefix(dir).expect("below dir");
                let name: Vec<String> = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                out.push((name.join("/"), path));
            } else {
                return Err(format!(
                    "{}: resources may hold files and folders only (no links)",
                    path.display()
                ));
            }
        }
    }
    out.sort();
    Ok(out)
}

/// The crate an FMU file was made from is written beside it (`.<id>.fmu.crate`: its package name
/// and folder), so that a crate sharing the target folder (`CARGO_TARGET_DIR`) whose model has the
/// same identifier is refused instead of silently replacing the other crate's FMU. An FMU whose
/// crate is gone (a deleted or moved folder) may be replaced; one with no such file (made before
/// this check) too. Returns the file to write after packaging, and what to write in it.
fn claim(krate: &FmuCrate, out: &Path, id: &str) -> Result<(PathBuf, String), String> {
    let file_name = out.file_name().expect("a file name").to_string_lossy();
    let owner = out.with_file_name(format!(".{file_name}.crate"));
    let folder = std::fs::canonicalize(&krate.manifest_dir).unwrap_or_else(|_| krate.manifest_dir.clone());
    let mine = format!("{}\n{}\n", krate.package, folder.display());
    if !out.exists() {
        return Ok((owner, mine));
    }
    let theirs = std::fs::read_to_string(&owner).unwrap_or_default();
    let mut lines = theirs.lines();
    let (package, their_folder) = (lines.next().unwrap_or(""), Path::new(lines.next().unwrap_or("")));
    if theirs.is_empty() || theirs == mine {
        return Ok((owner, mine));
    }
    if !their_folder.join("Cargo.toml").is_file() {
        eprintln!(
            "fmu: note: replacing {} of crate '{package}' ({}), whose folder is gone",
            out.display(),
            their_folder.display()
        );
        return Ok((owner, mine));
    }
    Err(format!(
        "{}: {} is the FMU of crate '{package}' ({}), which shares this target folder and whose model has the \
         same identifier '{id}'; nothing was written. Give one of the models another name, or build one of the \
         crates into a target folder of its own (CARGO_TARGET_DIR)",
        krate.package,
        out.display(),
        their_folder.display()
    ))
}

/// One file per archive name: FMI 2.0's `darwin64` folder takes the x86_64 and the arm64
/// library as one universal ("fat") Mach-O binary, which a Mac of either architecture loads
/// (FMI 2.0 names no folder per macOS architecture; the Reference-FMUs ship theirs so). Two
/// targets of one other folder are refused (`x86_64-unknown-linux-gnu` and
/// `x86_64-unknown-linux-gnu.2.17` both go to `linux64`).
pub fn merge_universal(binaries: Vec<(String, String, Vec<u8>)>) -> Result<Vec<(String, Vec<u8>)>, String> {
    // (archive name, [(triple, bytes)]).
    type Slices = Vec<(String, Vec<u8>)>;
    let mut out: Vec<(String, Slices)> = Vec::new();
    for (name, triple, bytes) in binaries {
        match out.iter_mut().find(|(n, _)| *n == name) {
            Some((_, v)) => v.push((triple, bytes)),
            None => out.push((name, vec![(triple, bytes)])),
        }
    }
    out.into_iter()
        .map(|(name, mut slices)| {
            if slices.len() == 1 {
                return Ok((name, slices.pop().expect("one").1));
            }
            let triples: Vec<&str> = slices.iter().map(|(t, _)| t.as_str()).collect();
            if !name.ends_with(".dylib") {
                return Err(format!(
                    "the targets {} all go to {name}: name one of them",
                    triples.join(" and ")
                ));
            }
            let mut fat = fat_macho::FatWriter::new();
            for (triple, bytes) in &slices {
                fat.add(bytes.as_slice())
                    .map_err(|e| format!("{name}: the {triple} library is no Mach-O binary: {e}"))?;
            }
            let mut bytes = Vec::new();
            fat.write_to(&mut bytes)
                .map_err(|e| format!("{name}: the universal binary of {}: {e}", triples.join(" and ")))?;
            Ok((name, bytes))
        })
        .collect()
}

/// Packages built libraries of one crate (one per target: `(triple, library)`) as an FMU of FMI
/// `version` into `out_dir/<id>.fmu` (FMI 2.0) or `out_dir/fmi3/<id>.fmu` (FMI 3.0), with the
/// description of that version the libraries carry. Every library must carry the same one.
pub fn package(
    krate: &FmuCrate,
    version: FmiVersion,
    libraries: &[(String, PathBuf)],
    out_dir: &Path,
) -> Result<Packaged, String> {
    // (archive name, triple, bytes).
    let mut binaries: Vec<(String, String, Vec<u8>)> = Vec::new();
    let mut first: Option<SelfDescription> = None;
    for (triple, library) in libraries {
        let binary = std::fs::read(library).map_err(|e| {
            format!(
                "{}: cannot read the built library {}: {e}",
                krate.package,
                library.display()
            )
        })?;
        let me =
            read_library(&binary, version).map_err(|e| format!("{}: {}: {e}", krate.package, library.display()))?;
        let platform = crate::target::platform(triple)?;
        let folder = platform
            .folder(me.interfaces.version)
            .map_err(|e| format!("{}: target {triple}: {e}", krate.package))?;
        let name = format!(
            "binaries/{folder}/{}.{}",
            me.description.model_identifier,
            platform.extension()
        );
        match &first {
            None => first = Some(me),
            Some(f) if f.guid != me.guid || f.interfaces.version != me.interfaces.version => {
                return Err(format!(
                    "{}: {} (target {triple}) describes itself differently from the library of target {} \
                     (GUID {} against {}): the targets were built from different sources",
                    krate.package,
                    library.display(),
                    libraries[0].0,
                    me.guid,
                    f.guid
                ));
            }
            Some(_) => {}
        }
        binaries.push((name, triple.clone(), binary));
    }
    let binaries = merge_universal(binaries).map_err(|e| format!("{}: {e}", krate.package))?;
    let me = first.ok_or_else(|| format!("{}: no library to package", krate.package))?;
    let id = me.description.model_identifier;
    let version = me.interfaces.version;
    let xml = model_description(&me).map_err(|e| format!("{id}: {e}"))?;
    let fragment = match &krate.documentation {
        Some(p) => std::fs::read_to_string(p).map_err(|e| {
            format!(
                "{}: [package.metadata.fmu] documentation = {}: {e}",
                krate.package,
                p.display()
            )
        })?,
        None => String::new(),
    };
    let platforms: Vec<String> = binaries
        .iter()
        .filter_map(|(name, _)| name.split('/').nth(1).map(String::from))
        .collect();
    // The default experiment as a picture, run on this machine's library (none when no library
    // of this machine was built: a cross build alone).
    let here = crate::target::this_machine();
    let starts = krate
        .documentation_start
        .clone()
        .map_err(|e| format!("{}: [package.metadata.fmu] {e}", krate.package))?;
    let picture = libraries
        .iter()
        .find(|(triple, _)| crate::target::platform(triple).ok() == here)
        .map(|(_, library)| crate::plot::picture(library, krate.resources.as_deref(), &starts));
    let picture = match picture {
        // A documentation-start the model cannot take is the crate's mistake: said as an error.
        Some(Err(e)) if e.contains("documentation-start") => {
            return Err(format!("{}: [package.metadata.fmu] {e}", krate.package));
        }
        Some(Ok(svg)) => Some(svg),
        Some(Err(e)) => {
            eprintln!("fmu: note: {id}: documentation/index.html shows no default experiment: {e}");
            None
        }
        None => None,
    };
    let docs = crate::docs::index_html(
        &me.description,
        &fragment,
        me.interfaces,
        &platforms,
        picture.as_deref(),
    );
    let resources = match &krate.resources {
        Some(dir) => files_below(dir)?,
        None => vec![],
    };

    let out = fmu_path(out_dir, version, id);
    let dir = out.parent().expect("a folder");
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let owner = claim(krate, &out, id)?;
    let tmp = out.with_extension("fmu.partial");
    let file = std::fs::File::create(&tmp).map_err(|e| format!("{}: {e}", tmp.display()))?;
    let mut zip = zip::ZipWriter::new(file);
    let deflate = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let mut files: Vec<(String, Vec<u8>)> = vec![("modelDescription.xml".into(), xml.clone().into_bytes())];
    if version == FmiVersion::V3
        && let Some(terminals) = crate::xml::terminals_and_icons(&me.description)?
    {
        files.push(("terminalsAndIcons/terminalsAndIcons.xml".into(), terminals.into_bytes()));
    }
    if version == FmiVersion::V3
        && let Some(manifest) = crate::xml::ls_bus_manifest(&me.description)
    {
        files.push((crate::xml::LS_BUS_MANIFEST.into(), manifest.into_bytes()));
    }
    files.extend(binaries);
    files.push(("documentation/index.html".into(), docs.into_bytes()));
    // The page's run as FMI-LS-REF reference results, as the Reference-FMUs ship theirs
    // (`cargo fmu check` compares a run with them): no second simulation.
    if let Some(csv) = libraries
        .iter()
        .find(|(triple, _)| crate::target::platform(triple).ok() == here)
        .and_then(|(_, library)| crate::plot::reference_results(library))
    {
        use fmi_conformance::reference_results::{FOLDER, MANIFEST, manifest};
        let source = format!("{id}_out.csv");
        files.push((MANIFEST.into(), manifest(&source).into_bytes()));
        files.push((format!("{FOLDER}/{source}"), csv.into_bytes()));
    }
    for (name, path) in resources {
        let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        files.push((format!("resources/{name}"), bytes));
    }
    let zip_err = |e: &dyn std::fmt::Display| format!("{}: {e}", tmp.display());
    for (name, bytes) in files {
        let options = if name.starts_with("binaries/") {
            deflate.unix_permissions(0o755)
        } else {
            deflate
        };
        zip.start_file(name, options).map_err(|e| zip_err(&e))?;
        zip.write_all(&bytes).map_err(|e| zip_err(&e))?;
    }
    zip.finish().map_err(|e| zip_err(&e))?;
    // Written aside and renamed, so an interrupted build never leaves a half-written .fmu.
    std::fs::rename(&tmp, &out).map_err(|e| format!("{}: {e}", out.display()))?;
    std::fs::write(&owner.0, &owner.1).map_err(|e| format!("{}: {e}", owner.0.display()))?;
    Ok(Packaged {
        fmu: out,
        version,
        model_identifier: id.to_string(),
        model_description: xml,
    })
}
