//! The `.fmu` archive: a zip with `modelDescription.xml` at the root,
//! `binaries/<platform>/<modelIdentifier>.<ext>`, `documentation/index.html` and `resources/`.

use crate::cargo::FmuCrate;
use rustfmu::description::{self, Interfaces, ModelDescription};
use std::io::Write;
use std::path::{Path, PathBuf};
use zip::write::SimpleFileOptions;

/// The platform folder of `binaries/` (FMI 2.0 names) for the machine fmu-build runs on.
pub fn platform() -> Result<(&'static str, &'static str), String> {
    match (std::env::consts::OS, std::env::consts::ARCH) {
        ("linux", "x86_64") => Ok(("linux64", "so")),
        ("linux", "x86") => Ok(("linux32", "so")),
        ("windows", "x86_64") => Ok(("win64", "dll")),
        ("macos", "x86_64" | "aarch64") => Ok(("darwin64", "dylib")),
        (os, arch) => Err(format!("FMI 2.0 names no binaries folder for {os}/{arch}")),
    }
}

/// What a built library says about itself.
pub struct SelfDescription {
    pub description: ModelDescription,
    pub interfaces: Interfaces,
    pub guid: String,
}

/// Reads the description a rustfmu library carries.
pub fn read_library(binary: &[u8]) -> Result<SelfDescription, String> {
    let encoded = description::find_encoded(binary)?;
    let (d, interfaces) = description::decode(encoded)?;
    Ok(SelfDescription {
        description: d,
        interfaces,
        guid: description::guid_string(encoded),
    })
}

/// What was packaged.
pub struct Packaged {
    pub fmu: PathBuf,
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

pub fn package(krate: &FmuCrate, library: &Path, out_dir: &Path) -> Result<Packaged, String> {
    let binary = std::fs::read(library).map_err(|e| {
        format!(
            "{}: cannot read the built library {}: {e}",
            krate.package,
            library.display()
        )
    })?;
    let me = read_library(&binary).map_err(|e| format!("{}: {}: {e}", krate.package, library.display()))?;
    let id = me.description.model_identifier;
    let xml = crate::xml::fmi2(&me.description, me.interfaces, &me.guid).map_err(|e| format!("{id}: {e}"))?;
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
    let docs = crate::docs::index_html(&me.description, &fragment);
    let resources = match &krate.resources {
        Some(dir) => files_below(dir)?,
        None => vec![],
    };
    let (folder, ext) = platform()?;

    std::fs::create_dir_all(out_dir).map_err(|e| format!("{}: {e}", out_dir.display()))?;
    let out = out_dir.join(format!("{id}.fmu"));
    let tmp = out.with_extension("fmu.partial");
    let file = std::fs::File::create(&tmp).map_err(|e| format!("{}: {e}", tmp.display()))?;
    let mut zip = zip::ZipWriter::new(file);
    let deflate = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let mut files: Vec<(String, Vec<u8>)> = vec![
        ("modelDescription.xml".into(), xml.clone().into_bytes()),
        (format!("binaries/{folder}/{id}.{ext}"), binary),
        ("documentation/index.html".into(), docs.into_bytes()),
    ];
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
    Ok(Packaged {
        fmu: out,
        model_identifier: id.to_string(),
        model_description: xml,
    })
}
