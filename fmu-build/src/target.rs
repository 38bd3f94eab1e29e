//! Build targets: a Rust target triple (`x86_64-unknown-linux-gnu`, `x86_64-pc-windows-gnu`,
//! `aarch64-unknown-linux-gnu`, ...), the folder of `binaries/` it goes to in each FMI version,
//! the file cargo makes, and the check that this machine can build it (the target's standard
//! library, the linker) before anything is built.
//!
//! Adding a platform is adding its triple to [`platform`].
//!
//! Two kinds of target are linked by zig through cargo-zigbuild (both from PyPI: `pip install
//! ziglang cargo-zigbuild`) instead of the system's linker:
//! - macOS (`x86_64-apple-darwin`, `aarch64-apple-darwin`) on a machine that is not a Mac: zig
//!   carries the stubs of macOS's system libraries, so no Apple SDK is needed;
//! - a Linux triple with a glibc version, `x86_64-unknown-linux-gnu.2.17` (cargo-zigbuild's
//!   spelling): linked against the symbol versions of that glibc, so the binary loads on every
//!   distribution with that glibc or a newer one (the system's linker links against the glibc of
//!   the build machine, 2.34 or newer here: no Ubuntu 20.04, RHEL 8 or Debian 11).

use rustfmu::description::FmiVersion;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Operating systems FMI names a binaries folder for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Os {
    Linux,
    Windows,
    Darwin,
}

/// What a triple is, as far as an FMU cares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Platform {
    pub os: Os,
    /// `x86_64`, `x86` or `aarch64`.
    pub arch: &'static str,
}

/// A triple without cargo-zigbuild's glibc suffix, and that suffix's version:
/// `x86_64-unknown-linux-gnu.2.17` is (`x86_64-unknown-linux-gnu`, Some((2, 17))).
pub fn split_glibc(triple: &str) -> (&str, Option<(u32, u32)>) {
    if let Some((base, version)) = triple.split_once('.')
        && base.ends_with("-linux-gnu")
        && let Some((major, minor)) = version.split_once('.')
        && let (Ok(major), Ok(minor)) = (major.parse(), minor.parse())
    {
        return (base, Some((major, minor)));
    }
    (triple, None)
}

/// Whether `triple` is linked by zig (cargo-zigbuild) on a machine whose triple is `host`: macOS
/// anywhere but on a Mac, and Linux with a glibc version.
pub fn uses_zig(triple: &str, host: &str) -> bool {
    let (base, glibc) = split_glibc(triple);
    glibc.is_some() || (base.contains("-apple-darwin") && !host.contains("-apple-darwin"))
}

/// The platform of a Rust target triple, or why this tool does not build FMUs for it.
pub fn platform(triple: &str) -> Result<Platform, String> {
    let (base, glibc) = split_glibc(triple);
    if triple.contains('.') && glibc.is_none() {
        return Err(format!(
            "target '{triple}': only a Linux GNU triple takes a glibc version (`x86_64-unknown-linux-gnu.2.17`)"
        ));
    }
    if let Some((major, minor)) = glibc
        && (major, minor) < (2, 17)
    {
        return Err(format!(
            "target '{triple}': Rust's standard library needs glibc 2.17 or newer; ask for {base}.2.17 or a newer version"
        ));
    }
    let triple = base;
    let arch = match triple.split('-').next().unwrap_or("") {
        "x86_64" => "x86_64",
        "i686" | "i586" => "x86",
        "aarch64" => "aarch64",
        other => {
            return Err(format!(
                "target '{triple}': FMI names no binaries folder for the architecture '{other}'"
            ));
        }
    };
    let os = if triple.contains("-linux-") {
        Os::Linux
    } else if triple.contains("-windows-") {
        Os::Windows
    } else if triple.contains("-apple-darwin") {
        Os::Darwin
    } else {
        return Err(format!(
            "target '{triple}': FMI names binaries folders for Linux, Windows and macOS only"
        ));
    };
    Ok(Platform { os, arch })
}

impl Platform {
    /// The folder of `binaries/` in the names of an FMI version (2.0: `linux64`, `win64`,
    /// `darwin64`, ...; 3.0: the platform tuple `x86_64-linux`, `x86_64-windows`, ...).
    pub fn folder(self, version: FmiVersion) -> Result<String, String> {
        match version {
            FmiVersion::V2 => match (self.os, self.arch) {
                (Os::Linux, "x86_64") => Ok("linux64".into()),
                (Os::Linux, "x86") => Ok("linux32".into()),
                (Os::Windows, "x86_64") => Ok("win64".into()),
                (Os::Windows, "x86") => Ok("win32".into()),
                // FMI 2.0's one macOS folder: a universal binary of both architectures when
                // both are built (as the Reference-FMUs ship it), else the one built.
                (Os::Darwin, "x86_64" | "aarch64") => Ok("darwin64".into()),
                (os, arch) => Err(format!(
                    "FMI 2.0 names no binaries folder for {arch} {os:?} (its folders: linux32, linux64, win32, win64, darwin32, darwin64); build it as FMI 3.0"
                )),
            },
            FmiVersion::V3 => {
                let os = match self.os {
                    Os::Linux => "linux",
                    Os::Windows => "windows",
                    Os::Darwin => "darwin",
                };
                Ok(format!("{}-{os}", self.arch))
            }
        }
    }

    /// The extension of a shared library.
    pub fn extension(self) -> &'static str {
        match self.os {
            Os::Linux => "so",
            Os::Windows => "dll",
            Os::Darwin => "dylib",
        }
    }

    /// The file cargo makes of a cdylib named `lib_name`.
    pub fn cdylib_file(self, lib_name: &str) -> String {
        match self.os {
            Os::Windows => format!("{lib_name}.dll"),
            os => format!("lib{lib_name}.{}", if os == Os::Darwin { "dylib" } else { "so" }),
        }
    }
}

/// Every binaries folder of an FMI version this tool knows, with its file extension.
pub fn known_folders(version: FmiVersion) -> Vec<(String, &'static str)> {
    let mut out = Vec::new();
    for os in [Os::Linux, Os::Windows, Os::Darwin] {
        for arch in ["x86_64", "x86", "aarch64"] {
            let p = Platform { os, arch };
            if let Ok(f) = p.folder(version) {
                out.push((f, p.extension()));
            }
        }
    }
    if version == FmiVersion::V2 {
        out.push(("darwin32".into(), "dylib"));
    }
    out
}

/// The platform of the machine this program runs on (the one whose binary the smoke run loads).
pub fn this_machine() -> Option<Platform> {
    let os = match std::env::consts::OS {
        "linux" => Os::Linux,
        "windows" => Os::Windows,
        "macos" => Os::Darwin,
        _ => return None,
    };
    let arch = match std::env::consts::ARCH {
        "x86_64" => "x86_64",
        "x86" => "x86",
        "aarch64" => "aarch64",
        _ => return None,
    };
    Some(Platform { os, arch })
}

/// The host triple of the Rust toolchain (`rustc -vV`).
pub fn host_triple() -> Result<String, String> {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let out = Command::new(&rustc)
        .arg("-vV")
        .output()
        .map_err(|e| format!("cannot run {rustc} -vV: {e}"))?;
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .find_map(|l| l.strip_prefix("host: ").map(str::to_string))
        .ok_or_else(|| format!("{rustc} -vV names no host"))
}

/// The environment variable cargo reads the linker of a target from.
pub fn linker_variable(triple: &str) -> String {
    format!("CARGO_TARGET_{}_LINKER", triple.replace(['-', '.'], "_").to_uppercase())
}

/// The linker of a cross target when cargo's configuration names none: rustc's default for
/// `*-windows-gnu` is the MinGW gcc; for a Linux target of another architecture it is the
/// host's `cc`, which cannot link it, so this tool names Debian's cross gcc.
fn default_linker(triple: &str) -> Option<(&'static str, &'static str)> {
    match triple {
        "x86_64-pc-windows-gnu" => Some(("x86_64-w64-mingw32-gcc", "gcc-mingw-w64-x86-64")),
        "i686-pc-windows-gnu" => Some(("i686-w64-mingw32-gcc", "gcc-mingw-w64-i686")),
        "aarch64-unknown-linux-gnu" => Some(("aarch64-linux-gnu-gcc", "gcc-aarch64-linux-gnu")),
        _ => None,
    }
}

/// Whether a program is on `PATH` (or is a path to an executable file).
fn on_path(program: &str) -> bool {
    if program.contains('/') {
        return Path::new(program).is_file();
    }
    std::env::var_os("PATH").is_some_and(|p| std::env::split_paths(&p).any(|d| d.join(program).is_file()))
}

/// The oldest macOS a binary of `triple` is built for: Rust's own minimum for the architecture
/// (10.12 on Intel, 11.0 on Apple silicon, the first macOS that ran on it). Without it zig
/// writes the newest macOS it knows (15.0 with zig 0.17: measured), and older Macs refuse the
/// binary. `MACOSX_DEPLOYMENT_TARGET` in the environment overrides it.
pub fn macos_deployment_target(triple: &str) -> Option<&'static str> {
    match triple {
        "x86_64-apple-darwin" => Some("10.12"),
        "aarch64-apple-darwin" => Some("11.0"),
        _ => None,
    }
}

/// cargo-zigbuild and the zig it runs: `cargo-zigbuild` on `PATH` or beside the Python
/// interpreter given (`--python`: the venv `pip install ziglang cargo-zigbuild` went to), and zig
/// as `zig` on `PATH` or the `ziglang` package of that folder's `python3`.
#[derive(Debug, Clone)]
pub struct Zig {
    /// The `cargo-zigbuild` program.
    pub cargo_zigbuild: PathBuf,
    /// A folder put first on `PATH` for cargo-zigbuild (the venv's `bin`, where it finds
    /// `python3 -m ziglang`), if any.
    pub path_first: Option<PathBuf>,
}

impl Zig {
    /// Finds cargo-zigbuild and zig, or says what to install.
    pub fn find(python: Option<&Path>) -> Result<Zig, String> {
        let mut dirs: Vec<PathBuf> = Vec::new();
        if let Some(p) = python
            && let Some(d) = p.parent()
        {
            dirs.push(d.to_path_buf());
        }
        if let Some(p) = std::env::var_os("PATH") {
            dirs.extend(std::env::split_paths(&p));
        }
        let install = "install them with `pip install ziglang cargo-zigbuild` (into a venv: then pass its \
                       interpreter as --python; this project: `bash tests/setup-env.sh --main-job`)";
        let Some(dir) = dirs.iter().find(|d| d.join("cargo-zigbuild").is_file()) else {
            return Err(format!("cargo-zigbuild is not installed; {install}"));
        };
        let python3 = dir.join("python3");
        let zig_here = on_path("zig")
            || (python3.is_file()
                && Command::new(&python3)
                    .args(["-c", "import ziglang"])
                    .output()
                    .is_ok_and(|o| o.status.success()));
        if !zig_here {
            return Err(format!(
                "zig is not installed (no `zig` on PATH, no ziglang package for {}); {install}",
                python3.display()
            ));
        }
        Ok(Zig {
            cargo_zigbuild: std::path::absolute(dir.join("cargo-zigbuild"))
                .unwrap_or_else(|_| dir.join("cargo-zigbuild")),
            // Absolute: build scripts run in their package's folder, and cargo-zigbuild's `ar`
            // (cc-rs archives C code with it) finds zig through this PATH entry.
            path_first: python3
                .is_file()
                .then(|| std::path::absolute(dir).unwrap_or_else(|_| dir.clone())),
        })
    }

    /// `PATH` for cargo-zigbuild: [`Zig::path_first`] first.
    pub fn path(&self) -> Option<std::ffi::OsString> {
        let first = self.path_first.as_ref()?;
        let rest = std::env::var_os("PATH").unwrap_or_default();
        std::env::join_paths(std::iter::once(first.clone()).chain(std::env::split_paths(&rest))).ok()
    }
}

/// What `cargo build --target <triple>` needs set in its environment (the linker of an
/// aarch64 Linux target), after [`preflight`] said it is there.
pub fn build_env(triple: &str) -> Vec<(String, String)> {
    if let Some(version) = macos_deployment_target(triple)
        && std::env::var_os("MACOSX_DEPLOYMENT_TARGET").is_none()
    {
        return vec![("MACOSX_DEPLOYMENT_TARGET".into(), version.into())];
    }
    let var = linker_variable(triple);
    match default_linker(triple) {
        Some((linker, _)) if triple.contains("-linux-") && std::env::var_os(&var).is_none() => {
            vec![(var, linker.to_string())]
        }
        _ => vec![],
    }
}

/// Checks, before anything is built, that this machine can build `triple`: the platform has a
/// binaries folder, the target's standard library is installed, the linker exists. The error
/// says what to install.
pub fn preflight(triple: &str, host: &str, python: Option<&Path>) -> Result<(), String> {
    platform(triple)?;
    if triple == host {
        return Ok(());
    }
    let zig = uses_zig(triple, host);
    let triple = split_glibc(triple).0;
    if zig {
        Zig::find(python).map_err(|e| format!("target '{triple}' is linked by zig: {e}"))?;
    }
    if triple == host {
        return Ok(());
    }
    if !std_installed(triple)? {
        return Err(format!(
            "target '{triple}': its Rust standard library is not installed; install it with `rustup target add {triple}` \
             (this project: `bash tests/setup-env.sh`)"
        ));
    }
    if zig {
        return Ok(());
    }
    let var = linker_variable(triple);
    if let Some(linker) = std::env::var_os(&var) {
        let linker = linker.to_string_lossy().into_owned();
        if !on_path(&linker) {
            return Err(format!(
                "target '{triple}': {var} names the linker '{linker}', which is not installed"
            ));
        }
    } else if let Some((linker, package)) = default_linker(triple)
        && !on_path(linker)
    {
        return Err(format!(
            "target '{triple}': its linker {linker} is not installed; install it with `apt-get install {package}` \
             (this project: `bash tests/setup-env.sh`)"
        ));
    }
    Ok(())
}

/// Whether the standard library of `triple` is in the toolchain's sysroot.
fn std_installed(triple: &str) -> Result<bool, String> {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let out = Command::new(&rustc)
        .args(["--print", "sysroot"])
        .output()
        .map_err(|e| format!("cannot run {rustc} --print sysroot: {e}"))?;
    let sysroot = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
    let lib = sysroot.join("lib/rustlib").join(triple).join("lib");
    Ok(std::fs::read_dir(&lib).is_ok_and(|mut d| {
        d.any(|e| {
            e.is_ok_and(|e| {
                let n = e.file_name();
                let n = n.to_string_lossy();
                n.starts_with("libstd-") && n.ends_with(".rlib")
            })
        })
    }))
}

/// Reads `[package.metadata.fmu] targets = ["x86_64-unknown-linux-gnu", ...]`.
pub fn parse_targets(value: &serde_json::Value) -> Result<Vec<String>, String> {
    let items = value
        .as_array()
        .ok_or("targets must be a list of Rust target triples such as [\"x86_64-unknown-linux-gnu\", \"x86_64-pc-windows-gnu\"]")?;
    let mut out: Vec<String> = Vec::new();
    for item in items {
        let t = item
            .as_str()
            .ok_or_else(|| format!("targets: {item} is not a text such as \"x86_64-pc-windows-gnu\""))?;
        platform(t).map_err(|e| format!("targets: {e}"))?;
        if !out.iter().any(|o| o == t) {
            out.push(t.to_string());
        }
    }
    if out.is_empty() {
        return Err("targets is empty: name at least one Rust target triple".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triples_map_to_the_folders_of_each_version() {
        let cases = [
            (
                "x86_64-unknown-linux-gnu",
                Some("linux64"),
                "x86_64-linux",
                "so",
                "libm.so",
            ),
            ("x86_64-pc-windows-gnu", Some("win64"), "x86_64-windows", "dll", "m.dll"),
            (
                "x86_64-pc-windows-msvc",
                Some("win64"),
                "x86_64-windows",
                "dll",
                "m.dll",
            ),
            ("aarch64-unknown-linux-gnu", None, "aarch64-linux", "so", "libm.so"),
            (
                "x86_64-apple-darwin",
                Some("darwin64"),
                "x86_64-darwin",
                "dylib",
                "libm.dylib",
            ),
            (
                "aarch64-apple-darwin",
                Some("darwin64"),
                "aarch64-darwin",
                "dylib",
                "libm.dylib",
            ),
        ];
        for (triple, v2, v3, ext, file) in cases {
            let p = platform(triple).unwrap();
            assert_eq!(p.folder(FmiVersion::V2).ok().as_deref(), v2, "{triple}");
            assert_eq!(p.folder(FmiVersion::V3).unwrap(), v3, "{triple}");
            assert_eq!(p.extension(), ext);
            assert_eq!(p.cdylib_file("m"), file);
        }
        assert!(platform("wasm32-unknown-unknown").is_err());
        assert!(platform("riscv64gc-unknown-linux-gnu").is_err());
    }

    #[test]
    fn targets_are_read_from_the_metadata() {
        let t = parse_targets(&serde_json::json!([
            "x86_64-unknown-linux-gnu",
            "x86_64-pc-windows-gnu"
        ]))
        .unwrap();
        assert_eq!(t, ["x86_64-unknown-linux-gnu", "x86_64-pc-windows-gnu"]);
        crate::test_support::refuses_each(
            parse_targets,
            r#"["x86_64-pc-windows-gnu", [], ["wasm32-unknown-unknown"], [64]]"#,
        );
    }

    #[test]
    fn a_glibc_version_is_read_off_a_linux_triple_only() {
        let linux = "x86_64-unknown-linux-gnu";
        assert_eq!(split_glibc("x86_64-unknown-linux-gnu.2.17"), (linux, Some((2, 17))));
        assert_eq!(split_glibc(linux), (linux, None));
        assert_eq!(split_glibc("aarch64-apple-darwin"), ("aarch64-apple-darwin", None));
        let p = platform("aarch64-unknown-linux-gnu.2.28").unwrap();
        assert_eq!(p.folder(FmiVersion::V3).unwrap(), "aarch64-linux");
        assert!(platform("x86_64-unknown-linux-gnu.2.12").unwrap_err().contains("2.17"));
        assert!(platform("x86_64-pc-windows-gnu.2.17").is_err());
        let host = "x86_64-unknown-linux-gnu";
        assert!(uses_zig("x86_64-unknown-linux-gnu.2.17", host));
        assert!(uses_zig("aarch64-apple-darwin", host));
        assert!(!uses_zig("aarch64-apple-darwin", "aarch64-apple-darwin"));
        assert!(!uses_zig("x86_64-pc-windows-gnu", host));
        assert!(!uses_zig(linux, host));
    }

    #[test]
    fn both_macos_architectures_go_to_darwin64_in_fmi2() {
        for t in ["x86_64-apple-darwin", "aarch64-apple-darwin"] {
            assert_eq!(platform(t).unwrap().folder(FmiVersion::V2).unwrap(), "darwin64");
        }
        assert!(preflight("x86_64-unknown-linux-gnu", "x86_64-unknown-linux-gnu", None).is_ok());
    }
}
