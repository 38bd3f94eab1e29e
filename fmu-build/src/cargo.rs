//! Which crates are FMUs, and building them: `cargo metadata` and `cargo build`.
//!
//! An FMU crate is any package with a `cdylib` library that depends on `rustfmu` (under any
//! name in its Cargo.toml). Its `[package.metadata.fmu]` may name `documentation` (an HTML
//! fragment for documentation/index.html) and `resources` (a folder copied to resources/;
//! default `resources` when it exists). The workspace's `[workspace.metadata.fmu]` may name
//! `model-descriptions` (a folder that keeps a committed copy of every description) and
//! `systems` (files of composed systems to write as SSP).

use cargo_metadata::{Metadata, MetadataCommand, Package};
use std::path::{Path, PathBuf};
use std::process::Command;

/// One crate to build into an FMU.
#[derive(Debug, Clone)]
pub struct FmuCrate {
    pub package: String,
    pub manifest_dir: PathBuf,
    /// The library target's name (`lib<name>.so` in the target folder).
    pub lib_name: String,
    pub documentation: Option<PathBuf>,
    pub resources: Option<PathBuf>,
}

/// What `cargo metadata` says about the workspace.
#[derive(Debug, Clone)]
pub struct Workspace {
    pub root: PathBuf,
    pub target_dir: PathBuf,
    /// `[workspace.metadata.fmu]`, if any.
    pub fmu_metadata: serde_json::Value,
    pub crates: Vec<FmuCrate>,
    /// The package the manifest path names, when it is not a virtual manifest.
    pub root_package: Option<String>,
}

fn is_fmu_crate(p: &Package) -> bool {
    p.dependencies.iter().any(|d| d.name == "rustfmu")
        && p.targets
            .iter()
            .any(|t| t.crate_types.iter().any(|c| c.to_string() == "cdylib"))
}

fn fmu_crate(p: &Package) -> FmuCrate {
    let dir = p
        .manifest_path
        .parent()
        .map(|d| d.as_std_path().to_path_buf())
        .unwrap_or_default();
    let meta = p.metadata.get("fmu");
    let path_of = |key: &str| {
        meta.and_then(|m| m.get(key))
            .and_then(|v| v.as_str())
            .map(|s| dir.join(s))
    };
    let resources = path_of("resources").or_else(|| Some(dir.join("resources")).filter(|d| d.is_dir()));
    let lib = p
        .targets
        .iter()
        .find(|t| t.crate_types.iter().any(|c| c.to_string() == "cdylib"))
        .expect("checked by is_fmu_crate");
    FmuCrate {
        package: p.name.to_string(),
        manifest_dir: dir.clone(),
        lib_name: lib.name.replace('-', "_"),
        documentation: path_of("documentation"),
        resources,
    }
}

pub fn workspace(manifest_path: Option<&Path>) -> Result<Workspace, String> {
    let mut cmd = MetadataCommand::new();
    cmd.no_deps();
    if let Some(p) = manifest_path {
        cmd.manifest_path(p);
    }
    let m: Metadata = cmd.exec().map_err(|e| format!("cargo metadata: {e}"))?;
    let members: Vec<&Package> = m.workspace_packages();
    let crates = members
        .iter()
        .filter(|p| is_fmu_crate(p))
        .map(|p| fmu_crate(p))
        .collect();
    Ok(Workspace {
        root: m.workspace_root.as_std_path().to_path_buf(),
        target_dir: m.target_directory.as_std_path().to_path_buf(),
        fmu_metadata: m
            .workspace_metadata
            .get("fmu")
            .cloned()
            .unwrap_or(serde_json::Value::Null),
        crates,
        root_package: m.root_package().map(|p| p.name.to_string()),
    })
}

impl Workspace {
    /// The crates to build: those named, else the manifest's own package, else (a virtual
    /// manifest, or `all`) every FMU crate of the workspace.
    pub fn select(&self, names: &[String], all: bool) -> Result<Vec<FmuCrate>, String> {
        let known = || {
            self.crates
                .iter()
                .map(|c| c.package.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        if !names.is_empty() {
            return names
                .iter()
                .map(|n| {
                    self.crates.iter().find(|c| c.package == *n).cloned().ok_or_else(|| {
                        format!(
                            "package '{n}' is not an FMU crate of this workspace (a cdylib depending on rustfmu); FMU crates: {}",
                            known()
                        )
                    })
                })
                .collect();
        }
        if !all && let Some(root) = &self.root_package {
            return match self.crates.iter().find(|c| c.package == *root) {
                Some(c) => Ok(vec![c.clone()]),
                None => Err(format!(
                    "package '{root}' is not an FMU crate: it needs `crate-type = [\"cdylib\"]` in [lib] and a dependency on rustfmu \
                     (FMU crates in this workspace: {})",
                    if self.crates.is_empty() { "none".into() } else { known() }
                )),
            };
        }
        if self.crates.is_empty() {
            return Err("this workspace has no FMU crate (a cdylib depending on rustfmu)".into());
        }
        Ok(self.crates.clone())
    }

    /// A path from `[workspace.metadata.fmu]`, relative to the workspace root.
    pub fn metadata_path(&self, key: &str) -> Option<PathBuf> {
        self.fmu_metadata
            .get(key)
            .and_then(|v| v.as_str())
            .map(|s| self.root.join(s))
    }

    pub fn metadata_paths(&self, key: &str) -> Vec<PathBuf> {
        match self.fmu_metadata.get(key) {
            Some(serde_json::Value::String(s)) => vec![self.root.join(s)],
            Some(serde_json::Value::Array(a)) => {
                a.iter().filter_map(|v| v.as_str()).map(|s| self.root.join(s)).collect()
            }
            _ => vec![],
        }
    }

    pub fn fmu_dir(&self) -> PathBuf {
        self.target_dir.join("fmu")
    }

    /// The built library of a crate (release profile, host target).
    pub fn library(&self, c: &FmuCrate) -> PathBuf {
        let (prefix, ext) = match std::env::consts::OS {
            "windows" => ("", "dll"),
            "macos" => ("lib", "dylib"),
            _ => ("lib", "so"),
        };
        self.target_dir
            .join("release")
            .join(format!("{prefix}{}.{ext}", c.lib_name))
    }
}

/// `cargo build --release -p ...` in the workspace.
pub fn build(ws: &Workspace, crates: &[FmuCrate]) -> Result<(), String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(&cargo);
    cmd.current_dir(&ws.root).args(["build", "--release"]);
    for c in crates {
        cmd.args(["-p", &c.package]);
    }
    eprintln!(
        "fmu: {cargo} build --release {}",
        crates
            .iter()
            .map(|c| format!("-p {}", c.package))
            .collect::<Vec<_>>()
            .join(" ")
    );
    let status = cmd.status().map_err(|e| format!("cannot run {cargo}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("cargo build failed ({status})"))
    }
}
