//! Windows binaries (PE): their export and import tables.

use super::check_exports;
use rustfmu::description::FmiVersion;

/// The DLLs of Windows itself that a Windows binary may import: every other DLL (MinGW's
/// `libgcc_s_seh-1.dll`, `libwinpthread-1.dll`, `libstdc++-6.dll`, ...) would have to be shipped
/// with the FMU, which it is not.
const WINDOWS_SYSTEM_DLLS: &[&str] = &[
    "kernel32.dll",
    "ntdll.dll",
    "msvcrt.dll",
    "ucrtbase.dll",
    "userenv.dll",
    "ws2_32.dll",
    "bcrypt.dll",
    "bcryptprimitives.dll",
    "advapi32.dll",
    "user32.dll",
    "shell32.dll",
    "ole32.dll",
    "oleaut32.dll",
    "secur32.dll",
    "crypt32.dll",
    "dbghelp.dll",
    "synchronization.dll",
];

/// What the export and import tables of a PE (Windows) binary say.
#[derive(Debug, Clone)]
pub struct PeTables {
    /// The exported names.
    pub exports: Vec<String>,
    /// The DLLs it imports from, each once, sorted.
    pub imports: Vec<String>,
}

/// The export and import tables of a PE (Windows) binary; `None` for another format.
pub fn pe_tables(binary: &[u8]) -> Option<Result<PeTables, String>> {
    use object::Object;
    let kind = object::FileKind::parse(binary).ok()?;
    if !matches!(kind, object::FileKind::Pe32 | object::FileKind::Pe64) {
        return None;
    }
    let read = || -> Result<PeTables, String> {
        let file = object::File::parse(binary).map_err(|e| format!("not a readable PE file: {e}"))?;
        let exports = file
            .exports()
            .map_err(|e| format!("its export table: {e}"))?
            .iter()
            .map(|e| String::from_utf8_lossy(e.name()).into_owned())
            .collect();
        let mut imports: Vec<String> = file
            .imports()
            .map_err(|e| format!("its import table: {e}"))?
            .iter()
            .map(|i| String::from_utf8_lossy(i.library()).into_owned())
            .collect();
        imports.sort_by_key(|d| d.to_ascii_lowercase());
        imports.dedup_by(|a, b| a.eq_ignore_ascii_case(b));
        Ok(PeTables { exports, imports })
    };
    Some(read())
}

/// The DLLs of a list that are not part of Windows (an FMU would have to ship them).
pub fn not_windows_dlls(dlls: &[String]) -> Vec<&str> {
    dlls.iter()
        .map(String::as_str)
        .filter(|d| {
            let l = d.to_ascii_lowercase();
            !(WINDOWS_SYSTEM_DLLS.contains(&l.as_str()) || l.starts_with("api-ms-win-") || l.starts_with("ext-ms-win-"))
        })
        .collect()
}

/// What a Windows binary exports and imports: every function of its FMI version's standard,
/// the other version's only whole ([`check_exports`]), nothing but FMI functions, and DLLs of
/// Windows only (the FMU ships no other DLL).
pub fn pe_problems(binary: &[u8], version: FmiVersion, bin_name: &str) -> Vec<String> {
    let PeTables { exports, imports } = match pe_tables(binary) {
        None => return vec![],
        Some(Err(e)) => return vec![format!("{bin_name}: {e}")],
        Some(Ok(t)) => t,
    };
    let mut problems = check_exports(&exports, version, bin_name);
    // check_exports judged the fmi2*/fmi3* names; nothing else may be exported.
    let other: Vec<&str> = exports
        .iter()
        .map(String::as_str)
        .filter(|n| !n.starts_with("fmi2") && !n.starts_with("fmi3"))
        .collect();
    if !other.is_empty() {
        problems.push(format!(
            "{bin_name} exports {}: an FMU's binary exports FMI functions only",
            other.join(", ")
        ));
    }
    let foreign = not_windows_dlls(&imports);
    if !foreign.is_empty() {
        problems.push(format!(
            "{bin_name} needs {}, which Windows does not have and the FMU does not ship (link the MinGW runtime statically)",
            foreign.join(", ")
        ));
    }
    problems
}
