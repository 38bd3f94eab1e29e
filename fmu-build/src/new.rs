//! `cargo fmu new NAME`: a crate that builds into a valid FMU unchanged (a first-order lag with
//! an input, an output, a tunable time constant and a test). The template files end in `.in`, so
//! that cargo does not take the template folder for a package of its own (which `cargo package`
//! would leave out).

use std::path::{Path, PathBuf};

const CARGO_TOML: &str = include_str!("../templates/lag/Cargo.toml.in");
const LIB_RS: &str = include_str!("../templates/lag/lib.rs.in");

/// `my-lag` → `MyLag`: the model struct and the model identifier.
pub fn model_name(crate_name: &str) -> String {
    crate_name
        .split(['-', '_'])
        .filter(|p| !p.is_empty())
        .map(|p| {
            let mut c = p.chars();
            match c.next() {
                Some(f) => f.to_uppercase().chain(c).collect::<String>(),
                None => String::new(),
            }
        })
        .collect()
}

fn valid_crate_name(name: &str) -> bool {
    name.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
}

/// The rustfmu this cargo-fmu was built from, when it is still there.
fn own_checkout() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).parent()?.to_path_buf();
    dir.join("src/lib.rs").is_file().then_some(dir)
}

pub fn create(name: &str, parent: Option<&Path>, rustfmu_path: Option<&Path>) -> Result<PathBuf, String> {
    if !valid_crate_name(name) {
        return Err(format!(
            "'{name}' is not a usable crate name: letters, digits, '-' and '_', starting with a letter"
        ));
    }
    let dir = parent.unwrap_or(Path::new(".")).join(name);
    if dir.exists() {
        return Err(format!("{} exists already; nothing written", dir.display()));
    }
    let dependency = match rustfmu_path.map(Path::to_path_buf).or_else(own_checkout) {
        Some(p) => {
            let p = std::fs::canonicalize(&p).map_err(|e| format!("{}: {e}", p.display()))?;
            format!("rustfmu = {{ path = {:?} }}", p.display().to_string())
        }
        None => format!("rustfmu = \"{}\"", env!("CARGO_PKG_VERSION")),
    };
    let model = model_name(name);
    let fill = |t: &str| {
        t.replace("{{crate_name}}", name)
            .replace("{{rustfmu_dependency}}", &dependency)
            .replace("{{Model}}", &model)
    };
    std::fs::create_dir_all(dir.join("src")).map_err(|e| format!("{}: {e}", dir.display()))?;
    std::fs::write(dir.join("Cargo.toml"), fill(CARGO_TOML)).map_err(|e| format!("{}: {e}", dir.display()))?;
    std::fs::write(dir.join("src/lib.rs"), fill(LIB_RS)).map_err(|e| format!("{}: {e}", dir.display()))?;
    std::fs::write(dir.join(".gitignore"), "/target\n").map_err(|e| format!("{}: {e}", dir.display()))?;
    Ok(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crate_names_become_camel_case_model_names() {
        assert_eq!(model_name("my-lag"), "MyLag");
        assert_eq!(model_name("lag"), "Lag");
        assert_eq!(model_name("first_order__lag"), "FirstOrderLag");
    }

    #[test]
    fn a_bad_name_or_an_existing_folder_writes_nothing() {
        let tmp = std::env::temp_dir().join(format!("cargo-fmu-new-{}", std::process::id()));
        std::fs::create_dir_all(tmp.join("taken")).unwrap();
        let e = create("9lives", Some(&tmp), None).unwrap_err();
        assert!(e.contains("'9lives'"), "got: {e}");
        let e = create("taken", Some(&tmp), None).unwrap_err();
        assert!(e.contains("exists already"), "got: {e}");
        let _ = std::fs::remove_dir_all(&tmp);
    }
}
