//! FMU metadata that is not code, from the crate's `Cargo.toml`: `[package]` (version, authors,
//! license, description) and `[package.metadata.fmu]` (author, version, copyright, license,
//! description, default-experiment), read when the crate is compiled.

use std::path::PathBuf;

#[derive(Debug, Default)]
pub struct Metadata {
    pub author: String,
    pub version: String,
    pub copyright: String,
    pub license: String,
    pub description: String,
    pub default_experiment: Option<[Option<f64>; 4]>,
    /// The manifest, so that the crate is rebuilt when it changes.
    pub manifest: Option<PathBuf>,
}

fn env(name: &str) -> String {
    std::env::var(name).unwrap_or_default()
}

pub fn read() -> Result<Metadata, String> {
    let mut m = Metadata {
        author: env("CARGO_PKG_AUTHORS")
            .split(':')
            .filter(|s| !s.is_empty())
            .collect::<Vec<_>>()
            .join(", "),
        version: env("CARGO_PKG_VERSION"),
        license: env("CARGO_PKG_LICENSE"),
        description: env("CARGO_PKG_DESCRIPTION"),
        ..Metadata::default()
    };
    let Ok(dir) = std::env::var("CARGO_MANIFEST_DIR") else {
        return Ok(m);
    };
    let path = PathBuf::from(dir).join("Cargo.toml");
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Ok(m);
    };
    m.manifest = Some(path.clone());
    let doc: toml::Table = text.parse().map_err(|e| format!("{}: {e}", path.display()))?;
    let Some(fmu) = doc
        .get("package")
        .and_then(|p| p.get("metadata"))
        .and_then(|p| p.get("fmu"))
    else {
        return Ok(m);
    };
    let at = |key: &str| format!("{}: [package.metadata.fmu] {key}", path.display());
    // Read here: what goes into the description. Read by cargo fmu: documentation, resources,
    // fmi-versions (which FMI versions `cargo fmu build` makes), targets (the Rust target
    // triples whose binaries go into the FMU), documentation-start (the start values of the
    // documentation page's run), example (built for the host only by `--examples-on-host`).
    const KNOWN: [&str; 12] = [
        "author",
        "version",
        "copyright",
        "license",
        "description",
        "default-experiment",
        "documentation",
        "resources",
        "fmi-versions",
        "targets",
        "documentation-start",
        "example",
    ];
    if let Some(table) = fmu.as_table() {
        for key in table.keys() {
            if !KNOWN.contains(&key.as_str()) {
                return Err(format!(
                    "{}: [package.metadata.fmu] has no key '{key}' (known: {})",
                    path.display(),
                    KNOWN.join(", ")
                ));
            }
        }
    }
    let text_of = |key: &str, into: &mut String| -> Result<(), String> {
        match fmu.get(key) {
            None => Ok(()),
            Some(toml::Value::String(s)) => {
                *into = s.clone();
                Ok(())
            }
            Some(other) => Err(format!("{} must be a string, not a {}", at(key), other.type_str())),
        }
    };
    text_of("author", &mut m.author)?;
    text_of("version", &mut m.version)?;
    text_of("copyright", &mut m.copyright)?;
    text_of("license", &mut m.license)?;
    text_of("description", &mut m.description)?;
    if let Some(e) = fmu.get("default-experiment") {
        let table = e
            .as_table()
            .ok_or_else(|| format!("{} must be a table", at("default-experiment")))?;
        let known = ["start-time", "stop-time", "tolerance", "step-size"];
        for key in table.keys() {
            if !known.contains(&key.as_str()) {
                return Err(format!(
                    "{}: unknown key '{key}' (known: {})",
                    at("default-experiment"),
                    known.join(", ")
                ));
            }
        }
        let mut values = [None; 4];
        for (slot, key) in values.iter_mut().zip(known) {
            *slot = match table.get(key) {
                None => None,
                Some(toml::Value::Float(x)) => Some(*x),
                Some(toml::Value::Integer(n)) => Some(*n as f64),
                Some(other) => {
                    return Err(format!(
                        "{}.{key} must be a number, not a {}",
                        at("default-experiment"),
                        other.type_str()
                    ));
                }
            };
        }
        m.default_experiment = Some(values);
    }
    Ok(m)
}
