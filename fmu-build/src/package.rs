//! The `.fmu` archive: a zip with `modelDescription.xml` at the root,
//! `binaries/linux64/<modelIdentifier>.so` and `documentation/index.html`.

use rustfmu::fmi2::FmuEntry;
use std::io::Write;
use std::path::Path;
use zip::write::SimpleFileOptions;

/// The platform folder of `binaries/` for the machine fmu-build runs on.
pub fn platform() -> Result<(&'static str, &'static str), String> {
    match (std::env::consts::OS, std::env::consts::ARCH) {
        ("linux", "x86_64") => Ok(("linux64", "so")),
        ("linux", "x86") => Ok(("linux32", "so")),
        ("windows", "x86_64") => Ok(("win64", "dll")),
        ("macos", "x86_64" | "aarch64") => Ok(("darwin64", "dylib")),
        (os, arch) => Err(format!("FMI 2.0 names no binaries folder for {os}/{arch}")),
    }
}

pub fn package(entry: &FmuEntry, shared_library: &Path, out: &Path) -> Result<(), String> {
    let id = entry.info.identifier;
    let xml = (entry.model_description)().map_err(|e| format!("{id}: {e}"))?;
    let binary = std::fs::read(shared_library)
        .map_err(|e| format!("{id}: cannot read the built library {}: {e}", shared_library.display()))?;
    let (folder, ext) = platform()?;
    let docs = crate::docs::index_html(entry);

    let tmp = out.with_extension("fmu.partial");
    let file = std::fs::File::create(&tmp).map_err(|e| format!("{}: {e}", tmp.display()))?;
    let mut zip = zip::ZipWriter::new(file);
    let deflate = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let files: [(String, &[u8]); 3] = [
        ("modelDescription.xml".into(), xml.as_bytes()),
        (format!("binaries/{folder}/{id}.{ext}"), &binary),
        ("documentation/index.html".into(), docs.as_bytes()),
    ];
    let zip_err = |e: &dyn std::fmt::Display| format!("{}: {e}", tmp.display());
    for (name, bytes) in files {
        let options = if name.starts_with("binaries/") {
            deflate.unix_permissions(0o755)
        } else {
            deflate
        };
        zip.start_file(name, options).map_err(|e| zip_err(&e))?;
        zip.write_all(bytes).map_err(|e| zip_err(&e))?;
    }
    zip.finish().map_err(|e| zip_err(&e))?;
    // Written aside and renamed, so an interrupted build never leaves a half-written .fmu.
    std::fs::rename(&tmp, out).map_err(|e| format!("{}: {e}", out.display()))
}
