//! macOS binaries (Mach-O, thin or universal): architectures, the oldest macOS each loads on,
//! exports and the libraries they load.

use super::check_exports;
use rustfmu::description::FmiVersion;
use std::path::Path;

/// The libraries of macOS itself a Mach-O binary may load: libSystem (the C library, libm,
/// pthreads, dyld's API: all Rust's standard library needs) and the libraries below
/// `/usr/lib/system/` it is made of. Any other would have to be on the user's Mac.
fn macos_system_library(path: &str) -> bool {
    path == "/usr/lib/libSystem.B.dylib" || path.starts_with("/usr/lib/system/")
}

/// The names a macOS dylib linked by zig exports besides the FMI functions, and why it may:
/// zig's Mach-O linker (0.17) ignores the `-exported_symbols_list` rustc passes (ziglang/zig#24662;
/// measured here: a two-function C library exports both with a list naming one), so the global
/// symbols that survive link-time optimisation stay exported: two the linker makes
/// (`__dso_handle`, `_mh_dylib_header`) and two of Rust's runtime
/// (`rust_eh_personality`, the unwinder's; `std::panicking::EMPTY_PANIC`, a constant). macOS binds
/// symbols per library (two-level namespace): they do not collide with the importer's. Any other
/// name is refused.
fn macos_runtime_export(name: &str) -> bool {
    matches!(name, "__dso_handle" | "_mh_dylib_header" | "rust_eh_personality")
        || (name.contains("std9panicking") && name.ends_with("EMPTY_PANIC"))
}

/// One architecture of a Mach-O binary: what [`macho_slices`] reads off it.
#[derive(Debug, Clone)]
pub struct MachOSlice {
    pub architecture: object::Architecture,
    /// Exported names, without the leading underscore of Mach-O symbols.
    pub exports: Vec<String>,
    /// The libraries it loads (LC_LOAD_DYLIB and its weak, re-exported, lazy and upward kinds).
    pub libraries: Vec<String>,
    /// The oldest macOS it loads on (LC_BUILD_VERSION or LC_VERSION_MIN_MACOSX), (major, minor).
    pub min_macos: Option<(u32, u32)>,
    /// Whether it carries a code signature (LC_CODE_SIGNATURE): macOS on Apple silicon runs no
    /// unsigned code; zig signs arm64 binaries ad hoc, as Apple's linker does.
    pub signed: bool,
}

/// The architectures of a Mach-O binary, thin or universal ("fat"); `None` for another format.
pub fn macho_slices(binary: &[u8]) -> Option<Result<Vec<MachOSlice>, String>> {
    use object::read::macho::{FatArch32, FatArch64};
    let kind = object::FileKind::parse(binary).ok()?;
    let read = || -> Result<Vec<MachOSlice>, String> {
        match kind {
            object::FileKind::MachO64 => Ok(vec![macho_slice(binary)?]),
            object::FileKind::MachOFat32 => universal_slices::<FatArch32>(binary),
            object::FileKind::MachOFat64 => universal_slices::<FatArch64>(binary),
            _ => Err(format!("a Mach-O file of kind {kind:?}, not a 64-bit shared library")),
        }
    };
    match kind {
        object::FileKind::MachO32
        | object::FileKind::MachO64
        | object::FileKind::MachOFat32
        | object::FileKind::MachOFat64 => Some(read()),
        _ => None,
    }
}

/// [`macho_slice`] of each architecture of a universal binary (32- or 64-bit fat header).
fn universal_slices<Fat: object::read::macho::FatArch>(binary: &[u8]) -> Result<Vec<MachOSlice>, String> {
    object::read::macho::MachOFatFile::<Fat>::parse(binary)
        .map_err(|e| format!("not a readable universal binary: {e}"))?
        .arches()
        .iter()
        .map(|a| {
            macho_slice(
                a.data(binary)
                    .map_err(|e| format!("a slice of the universal binary: {e}"))?,
            )
        })
        .collect()
}

fn macho_slice(data: &[u8]) -> Result<MachOSlice, String> {
    use object::macho;
    use object::read::macho::{LoadCommandVariant, MachOFile64};
    use object::{Object, ObjectKind};
    let file =
        MachOFile64::<object::Endianness>::parse(data).map_err(|e| format!("not a readable Mach-O file: {e}"))?;
    if file.kind() != ObjectKind::Dynamic {
        return Err(format!("a Mach-O file of kind {:?}, not a shared library", file.kind()));
    }
    let exports = file
        .exports()
        .map_err(|e| format!("its export trie: {e}"))?
        .iter()
        .map(|e| {
            let n = String::from_utf8_lossy(e.name());
            n.strip_prefix('_').unwrap_or(&n).to_string()
        })
        .collect();
    let endian = file.endian();
    let mut libraries = Vec::new();
    let mut min_macos = None;
    let mut signed = false;
    let mut commands = file
        .macho_load_commands()
        .map_err(|e| format!("its load commands: {e}"))?;
    let version = |v: u32| (v >> 16, (v >> 8) & 0xff);
    while let Some(c) = commands.next().map_err(|e| format!("its load commands: {e}"))? {
        match c.variant().map_err(|e| format!("its load commands: {e}"))? {
            LoadCommandVariant::Dylib(d)
                if matches!(
                    c.cmd(),
                    macho::LC_LOAD_DYLIB
                        | macho::LC_LOAD_WEAK_DYLIB
                        | macho::LC_REEXPORT_DYLIB
                        | macho::LC_LAZY_LOAD_DYLIB
                        | macho::LC_LOAD_UPWARD_DYLIB
                ) =>
            {
                let name = c
                    .string(endian, d.dylib.name)
                    .map_err(|e| format!("a library name of its load commands: {e}"))?;
                libraries.push(String::from_utf8_lossy(name).into_owned());
            }
            LoadCommandVariant::BuildVersion(b) if b.platform.get(endian) == macho::PLATFORM_MACOS => {
                min_macos = Some(version(b.minos.get(endian)));
            }
            LoadCommandVariant::VersionMin(v) if c.cmd() == macho::LC_VERSION_MIN_MACOSX => {
                min_macos = Some(version(v.version.get(endian)));
            }
            LoadCommandVariant::LinkeditData(_) if c.cmd() == macho::LC_CODE_SIGNATURE => signed = true,
            _ => {}
        }
    }
    Ok(MachOSlice {
        architecture: file.architecture(),
        exports,
        libraries,
        min_macos,
        signed,
    })
}

/// What a macOS binary is, exports and loads: the architecture(s) its folder names
/// (`x86_64-darwin`: x86_64; `aarch64-darwin`: arm64; FMI 2.0's `darwin64`: x86_64, arm64 or a
/// universal binary of both), every function of its FMI version and no other name
/// ([`check_exports`]), macOS's own libraries only. Built here, never run here: these checks are
/// what this machine can say of a macOS binary.
pub fn macho_problems(binary: &[u8], version: FmiVersion, folder: &str, bin_name: &str) -> Vec<String> {
    use object::Architecture::{Aarch64, X86_64};
    let slices = match macho_slices(binary) {
        None => {
            return if folder.contains("darwin") {
                vec![format!(
                    "{bin_name} is no Mach-O binary, which binaries/{folder}/ holds"
                )]
            } else {
                vec![]
            };
        }
        Some(Err(e)) => return vec![format!("{bin_name}: {e}")],
        Some(Ok(s)) => s,
    };
    let mut problems = Vec::new();
    let allowed: &[object::Architecture] = match folder {
        "x86_64-darwin" => &[X86_64],
        "aarch64-darwin" => &[Aarch64],
        "darwin64" => &[X86_64, Aarch64],
        other => {
            return vec![format!("{bin_name} is a macOS (Mach-O) binary in binaries/{other}/")];
        }
    };
    for s in &slices {
        let arch = format!("{:?}", s.architecture).to_lowercase();
        if !allowed.contains(&s.architecture) {
            problems.push(format!(
                "{bin_name} holds a {arch} binary, which binaries/{folder}/ is not for"
            ));
        }
        let name = if slices.len() > 1 {
            format!("{bin_name} ({arch})")
        } else {
            bin_name.to_string()
        };
        problems.extend(check_exports(&s.exports, version, &name));
        let other: Vec<&str> = s
            .exports
            .iter()
            .map(String::as_str)
            .filter(|n| !n.starts_with("fmi2") && !n.starts_with("fmi3") && !macos_runtime_export(n))
            .collect();
        if !other.is_empty() {
            let shown: Vec<&str> = other.iter().copied().take(8).collect();
            problems.push(format!(
                "{name} exports {} name{} besides the FMI functions ({}{}): an FMU's binary exports FMI functions only \
                 (built without link-time optimisation? `cargo fmu build` builds with `--crate-type cdylib`)",
                other.len(),
                if other.len() == 1 { "" } else { "s" },
                shown.join(", "),
                if other.len() > shown.len() { ", ..." } else { "" }
            ));
        }
        let foreign: Vec<&str> = s
            .libraries
            .iter()
            .map(String::as_str)
            .filter(|l| !macos_system_library(l))
            .collect();
        if !foreign.is_empty() {
            problems.push(format!(
                "{name} loads {}, which macOS does not have and the FMU does not ship",
                foreign.join(", ")
            ));
        }
    }
    let mut archs: Vec<_> = slices.iter().map(|s| s.architecture).collect();
    archs.sort_by_key(|a| format!("{a:?}"));
    archs.dedup();
    if archs.len() != slices.len() {
        problems.push(format!("{bin_name} holds one architecture twice"));
    }
    problems
}

/// For each macOS binary of an FMU: its path in the archive and its architectures with the
/// oldest macOS each loads on (`x86_64 (macOS >= 10.12), aarch64 (macOS >= 11.0)`), or what is
/// wrong with it.
pub fn macos_binaries(fmu: &Path) -> Result<Vec<(String, String)>, String> {
    let mut zip = fmi_conformance::archive::open(fmu)?;
    let mut out = Vec::new();
    for name in zip.entry_names() {
        if name.starts_with("binaries/") && name.ends_with(".dylib") {
            let bytes = zip.read_entry_within(&name, 1 << 30)?.unwrap_or_default();
            let text = match macho_slices(&bytes) {
                None => "no Mach-O binary".to_string(),
                Some(Err(e)) => e,
                Some(Ok(slices)) => slices
                    .iter()
                    .map(|s| {
                        let arch = format!("{:?}", s.architecture).to_lowercase();
                        let other = s
                            .exports
                            .iter()
                            .filter(|n| !n.starts_with("fmi2") && !n.starts_with("fmi3") && !macos_runtime_export(n))
                            .count();
                        let other = if other > 0 {
                            format!(", {other} non-FMI exports")
                        } else {
                            String::new()
                        };
                        match s.min_macos {
                            Some((major, minor)) => format!("{arch} (macOS >= {major}.{minor}{other})"),
                            None => format!("{arch}{other}"),
                        }
                    })
                    .collect::<Vec<_>>()
                    .join(", "),
            };
            out.push((name, text));
        }
    }
    Ok(out)
}
