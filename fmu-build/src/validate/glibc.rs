//! The oldest glibc a Linux binary loads with.

use std::path::Path;

/// A glibc version: (major, minor).
pub type GlibcVersion = (u32, u32);

/// The highest `GLIBC_x.y` symbol version an ELF binary references (its `.gnu.version_r`
/// needs): the oldest glibc it loads with. `None` for a binary that is no ELF or needs no
/// glibc version.
pub fn glibc_needed(binary: &[u8]) -> Option<GlibcVersion> {
    use object::read::elf::{ElfFile64, FileHeader};
    let elf = ElfFile64::<object::Endianness>::parse(binary).ok()?;
    let endian = elf.endian();
    let sections = elf.elf_header().sections(endian, binary).ok()?;
    let (mut needs, link) = sections.gnu_verneed(endian, binary).ok()??;
    let strings = sections.strings(endian, binary, link).ok()?;
    let mut highest = None;
    while let Ok(Some((_, mut auxes))) = needs.next() {
        while let Ok(Some(aux)) = auxes.next() {
            let Ok(name) = aux.name(endian, strings) else { continue };
            let Some(version) = std::str::from_utf8(name).ok().and_then(|n| n.strip_prefix("GLIBC_")) else {
                continue;
            };
            let mut parts = version.split('.').map(|p| p.parse::<u32>());
            if let (Some(Ok(major)), Some(Ok(minor))) = (parts.next(), parts.next()) {
                highest = highest.max(Some((major, minor)));
            }
        }
    }
    highest
}

/// For each Linux binary of an FMU (`binaries/<folder>/<id>.so`): its path in the archive and
/// the glibc it needs at least ([`glibc_needed`]).
pub fn glibc_requirements(fmu: &Path) -> Result<Vec<(String, Option<GlibcVersion>)>, String> {
    let mut zip = fmi_conformance::archive::open(fmu)?;
    let mut out = Vec::new();
    for name in zip.entry_names() {
        if name.starts_with("binaries/") && name.ends_with(".so") {
            let bytes = zip.read_entry_within(&name, 1 << 30)?.unwrap_or_default();
            out.push((name, glibc_needed(&bytes)));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod glibc_tests {
    #[test]
    fn the_highest_glibc_version_of_this_test_binary_is_read() {
        // This test executable is an ELF linked against glibc (x86_64 and aarch64 Linux, where
        // the project builds): it references GLIBC_2.x versions.
        let me = std::fs::read(std::env::current_exe().unwrap()).unwrap();
        let (major, minor) = super::glibc_needed(&me).expect("a glibc version");
        assert_eq!(major, 2);
        assert!(minor >= 2, "GLIBC_2.{minor}");
        assert_eq!(super::glibc_needed(b"not an ELF file"), None);
    }
}
