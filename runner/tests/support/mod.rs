//! Where the runner's integration tests find their FMUs: ours in the workspace's `target/fmu`
//! (built by `cargo fmu build`), the C Reference-FMUs in `../shared/independent`.
//! (`mod support;` in each test file that needs it; not every file uses every function.)
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// The workspace's root folder.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

/// `target/fmu/<name>.fmu` (FMI 2.0) or `target/fmu/fmi3/<name>.fmu`, honouring
/// CARGO_TARGET_DIR; fails saying how to build it.
pub fn ours(name: &str, fmi3: bool) -> PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .map_or(
            root().join("target"),
            |t| if t.is_absolute() { t } else { root().join(t) },
        );
    let folder = if fmi3 { "fmu/fmi3" } else { "fmu" };
    let p = target.join(folder).join(format!("{name}.fmu"));
    assert!(
        p.exists(),
        "{} is missing: build it with `cargo fmu build` (`cargo run --release -p fmu-build`)",
        p.display()
    );
    p
}

/// The C Reference-FMUs' `name` of FMI `version` ("2.0" or "3.0").
pub fn theirs(version: &str, name: &str) -> PathBuf {
    let p = root().join(format!("../shared/independent/reference-fmus/{version}/{name}.fmu"));
    assert!(
        p.exists(),
        "{} is missing (the C Reference-FMUs v0.0.41 of shared/independent)",
        p.display()
    );
    p
}
