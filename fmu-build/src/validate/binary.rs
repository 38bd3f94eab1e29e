//! What any binary exports against its FMI version, read from ELF by hand (PE in [`super::pe`],
//! Mach-O in [`super::macho`]), and its architecture against its platform folder.

use super::{FMI2_CS_FUNCTIONS, FMI2_FUNCTIONS, FMI3_FUNCTIONS};
use rustfmu::description::FmiVersion;
use std::collections::BTreeSet;

/// The architecture of an ELF or PE binary against its folder (`x86_64-linux`, `linux64`,
/// `aarch64-linux`, `win64`, ...): a binary of another architecture does not load there.
pub fn architecture_problems(binary: &[u8], folder: &str, bin_name: &str) -> Vec<String> {
    use object::Object;
    let Ok(kind) = object::FileKind::parse(binary) else {
        return vec![];
    };
    if !matches!(
        kind,
        object::FileKind::Elf64 | object::FileKind::Elf32 | object::FileKind::Pe32 | object::FileKind::Pe64
    ) {
        return vec![];
    }
    let Ok(file) = object::File::parse(binary) else {
        return vec![];
    };
    let want = match folder {
        "linux64" | "win64" | "x86_64-linux" | "x86_64-windows" => object::Architecture::X86_64,
        "linux32" | "win32" | "x86-linux" | "x86-windows" => object::Architecture::I386,
        "aarch64-linux" | "aarch64-windows" => object::Architecture::Aarch64,
        _ => return vec![],
    };
    if file.architecture() == want {
        vec![]
    } else {
        vec![format!(
            "{bin_name} is a {:?} binary, which binaries/{folder}/ is not for ({want:?})",
            file.architecture()
        )]
    }
}

/// The names an ELF shared library exports (defined global or weak symbols of `.dynsym`);
/// `None` for another format (PE, Mach-O) or a file this reader does not understand.
pub fn elf_exports(bin: &[u8]) -> Option<Vec<String>> {
    let u16_at = |o: usize| Some(u16::from_le_bytes(bin.get(o..o + 2)?.try_into().ok()?));
    let u32_at = |o: usize| Some(u32::from_le_bytes(bin.get(o..o + 4)?.try_into().ok()?));
    let u64_at = |o: usize| Some(u64::from_le_bytes(bin.get(o..o + 8)?.try_into().ok()?) as usize);
    // ELF, 64-bit, little-endian.
    if bin.get(..6)? != b"\x7fELF\x02\x01" {
        return None;
    }
    let (shoff, shentsize, shnum) = (u64_at(0x28)?, u16_at(0x3a)? as usize, u16_at(0x3c)? as usize);
    let section = |i: usize| shoff.checked_add(i.checked_mul(shentsize)?);
    let mut out = Vec::new();
    for i in 0..shnum {
        let sh = section(i)?;
        if u32_at(sh + 4)? != 11 {
            continue; // not SHT_DYNSYM
        }
        let (off, size, link, entsize) = (
            u64_at(sh + 0x18)?,
            u64_at(sh + 0x20)?,
            u32_at(sh + 0x28)? as usize,
            u64_at(sh + 0x38)?,
        );
        let strtab = section(link)?;
        let (str_off, str_size) = (u64_at(strtab + 0x18)?, u64_at(strtab + 0x20)?);
        let strings = bin.get(str_off..str_off.checked_add(str_size)?)?;
        if entsize < 24 {
            return None;
        }
        for k in 0..size / entsize {
            let sym = off.checked_add(k * entsize)?;
            let (name, info, shndx) = (u32_at(sym)? as usize, *bin.get(sym + 4)?, u16_at(sym + 6)?);
            let binding = info >> 4;
            if shndx == 0 || !(binding == 1 || binding == 2) {
                continue; // undefined, or local
            }
            let rest = strings.get(name..)?;
            let end = rest.iter().position(|b| *b == 0)?;
            out.push(String::from_utf8_lossy(&rest[..end]).into_owned());
        }
    }
    Some(out)
}

/// What a binary exports against what its FMI version asks: every function of the standard of
/// its version, the other version's functions only all of them (a binary of both versions), no
/// other `fmi2`/`fmi3` name. (ELF here;
/// PE in [`pe_problems`]; the smoke run looks every function up on this machine's binary.)
pub fn export_problems(binary: &[u8], version: FmiVersion, bin_name: &str) -> Vec<String> {
    let Some(exports) = elf_exports(binary) else {
        return vec![];
    };
    check_exports(&exports, version, bin_name)
}

/// [`export_problems`] of a list of exported names (of an ELF or a PE binary).
pub fn check_exports(exports: &[String], version: FmiVersion, bin_name: &str) -> Vec<String> {
    let (own, own_prefix, other, other_prefix) = match version {
        FmiVersion::V2 => (FMI2_FUNCTIONS, "fmi2", FMI3_FUNCTIONS, "fmi3"),
        FmiVersion::V3 => (FMI3_FUNCTIONS, "fmi3", FMI2_FUNCTIONS, "fmi2"),
    };
    let mut problems = Vec::new();
    let exported: BTreeSet<&str> = exports.iter().map(String::as_str).collect();
    // FMI 2.0: the co-simulation functions are required (model exchange ones where offered).
    let required: &[&str] = match version {
        FmiVersion::V2 => FMI2_CS_FUNCTIONS,
        FmiVersion::V3 => FMI3_FUNCTIONS,
    };
    let missing: Vec<&str> = required.iter().copied().filter(|f| !exported.contains(f)).collect();
    if !missing.is_empty() {
        problems.push(format!("{bin_name} does not export {}", missing.join(", ")));
    }
    // A binary may implement the other version too (`rustfmu::export_fmu!` exports both): then
    // all of that version's required functions and no other name of its prefix.
    let foreign: Vec<&str> = exported
        .iter()
        .copied()
        .filter(|n| n.starts_with(other_prefix) || other.contains(n))
        .collect();
    let other_required: &[&str] = match version {
        FmiVersion::V2 => FMI3_FUNCTIONS,
        FmiVersion::V3 => FMI2_CS_FUNCTIONS,
    };
    let whole_other = other_required.iter().all(|f| exported.contains(f)) && foreign.iter().all(|n| other.contains(n));
    if !foreign.is_empty() && !whole_other {
        problems.push(format!(
            "{bin_name} is an FMI {} binary and exports {}: a binary may implement the other FMI version \
             too, but then every function that version requires and no name its standard does not define",
            version.text(),
            foreign.join(", ")
        ));
    }
    let unknown: Vec<&str> = exported
        .iter()
        .copied()
        .filter(|n| n.starts_with(own_prefix) && !own.contains(n))
        .collect();
    if !unknown.is_empty() {
        problems.push(format!(
            "{bin_name} exports {}, which the FMI {} standard does not define",
            unknown.join(", "),
            version.text()
        ));
    }
    problems
}
