//! `fmi_conformance::archive` on hand-made malicious archives: every refusal, and that nothing
//! is written outside the private folder or left behind.

use fmi_conformance::archive::{self, Limits, PrivateDir, check_entry_name, line_column};
use std::io::Write;
use std::path::Path;
use zip::write::SimpleFileOptions;

/// A zip archive with these entries (deflated).
fn zip_of(entries: &[(&str, &[u8])]) -> Vec<u8> {
    let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let opts = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    for (name, data) in entries {
        w.start_file(*name, opts).unwrap();
        w.write_all(data).unwrap();
    }
    w.finish().unwrap().into_inner()
}

/// Replaces every occurrence of `from` by `to` (same length): how a name no zip writer would
/// write gets into the local header and the central directory.
fn patch(mut bytes: Vec<u8>, from: &[u8], to: &[u8]) -> Vec<u8> {
    assert_eq!(from.len(), to.len());
    let mut found = 0;
    let mut i = 0;
    while i + from.len() <= bytes.len() {
        if &bytes[i..i + from.len()] == from {
            bytes[i..i + from.len()].copy_from_slice(to);
            found += 1;
            i += from.len();
        } else {
            i += 1;
        }
    }
    assert!(found >= 2, "the name is in the local header and the central directory");
    bytes
}

const MD: &[u8] = br#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="M" guid="{x}">
  <CoSimulation modelIdentifier="M"/>
</fmiModelDescription>
"#;

/// A private test folder, the archive written into it, and the folder to extract under.
struct Case {
    root: PrivateDir,
}

impl Case {
    fn new() -> Case {
        Case {
            root: PrivateDir::new_in(&std::env::temp_dir()).unwrap(),
        }
    }

    fn write(&self, bytes: &[u8]) -> std::path::PathBuf {
        let p = self.root.path().join("x.fmu");
        std::fs::write(&p, bytes).unwrap();
        p
    }

    fn under(&self) -> std::path::PathBuf {
        let p = self.root.path().join("under");
        std::fs::create_dir_all(&p).unwrap();
        p
    }

    /// Extracts with `limits`; on a refusal also checks that nothing is left under the parent
    /// and nothing was written next to the test folder.
    fn extract(&self, bytes: &[u8], limits: &Limits) -> Result<PrivateDir, String> {
        let path = self.write(bytes);
        let under = self.under();
        let mut a = archive::open(&path)?;
        let r = archive::extract_private(&mut a, &under, limits);
        if r.is_err() {
            assert_eq!(
                std::fs::read_dir(&under).unwrap().count(),
                0,
                "a refused archive left files behind"
            );
        }
        for outside in ["evil", "under/evil"] {
            assert!(!self.root.path().join(outside).exists(), "wrote {outside}");
        }
        r
    }

    fn refused(&self, bytes: &[u8], limits: &Limits, says: &str) {
        match self.extract(bytes, limits) {
            Ok(d) => panic!("accepted; unpacked into {}", d.path().display()),
            Err(e) => assert!(e.contains(says), "the refusal does not say '{says}': {e}"),
        }
    }
}

#[test]
fn a_regular_fmu_is_unpacked_into_a_private_folder_that_is_removed_on_drop() {
    let c = Case::new();
    let bytes = zip_of(&[
        ("modelDescription.xml", MD),
        ("binaries/linux64/M.so", b"\x7fELF not really"),
        ("resources/data/table.csv", b"1,2\n"),
    ]);
    let dir = c.extract(&bytes, &Limits::default()).unwrap();
    let p = dir.path().to_path_buf();
    assert!(p.starts_with(c.under()));
    assert_eq!(std::fs::read(p.join("resources/data/table.csv")).unwrap(), b"1,2\n");
    use std::os::unix::fs::PermissionsExt;
    assert_eq!(std::fs::metadata(&p).unwrap().permissions().mode() & 0o777, 0o700);
    let mut a = archive::open(&c.write(&bytes)).unwrap();
    assert!(
        archive::read_model_description(&mut a)
            .unwrap()
            .contains("modelIdentifier=\"M\"")
    );
    drop(dir);
    assert!(!p.exists(), "the private folder outlived its PrivateDir");
}

#[test]
fn entries_with_dot_dot_components_are_refused() {
    let c = Case::new();
    for name in ["../evil", "a/../../evil", "a/b/../../../evil", ".."] {
        let bytes = zip_of(&[("modelDescription.xml", MD), (name, b"x")]);
        c.refused(&bytes, &Limits::default(), "'..'");
    }
}

#[test]
fn absolute_entries_backslashes_and_nul_bytes_are_refused() {
    let c = Case::new();
    // Written as harmless names, then patched into what no zip writer would write.
    let cases: [(&[u8], &[u8], &str); 4] = [
        (b"Xtmp/evil", b"/tmp/evil", "absolute"),
        (b"CXevil", b"C:evil", "drive letter"),
        (b"aXevil", b"a\\evil", "backslash"),
        (b"aXevil", b"a\0evil", "NUL"),
    ];
    for (written, patched, says) in cases {
        let name = std::str::from_utf8(written).unwrap();
        let bytes = patch(zip_of(&[("modelDescription.xml", MD), (name, b"x")]), written, patched);
        c.refused(&bytes, &Limits::default(), says);
    }
}

#[test]
fn the_name_check_itself() {
    assert_eq!(check_entry_name(b"a/./b//c").unwrap(), Path::new("a/b/c"));
    assert_eq!(check_entry_name(b"resources/").unwrap(), Path::new("resources"));
    for bad in [&b""[..], b"/", b"./", b"a/..", b"\\x", b"x\0"] {
        assert!(
            check_entry_name(bad).is_err(),
            "{:?} accepted",
            String::from_utf8_lossy(bad)
        );
    }
}

#[test]
fn symbolic_links_are_refused() {
    let c = Case::new();
    let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let opts = SimpleFileOptions::default();
    w.start_file("modelDescription.xml", opts).unwrap();
    w.write_all(MD).unwrap();
    w.add_symlink("resources/link", "/etc/passwd", opts).unwrap();
    let bytes = w.finish().unwrap().into_inner();
    c.refused(&bytes, &Limits::default(), "symbolic link");
}

/// Two names for one file (the zip reader itself keeps one entry per exact name).
#[test]
fn two_entries_for_one_file_are_refused() {
    let c = Case::new();
    let bytes = zip_of(&[("modelDescription.xml", MD), ("a/one", b"1"), ("a/./one", b"2")]);
    c.refused(&bytes, &Limits::default(), "a second entry");
}

#[test]
fn too_many_entries_are_refused() {
    let c = Case::new();
    let names: Vec<String> = (0..12).map(|i| format!("resources/{i}")).collect();
    let entries: Vec<(&str, &[u8])> = names.iter().map(|n| (n.as_str(), &b"x"[..])).collect();
    let limits = Limits {
        max_entries: 10,
        ..Limits::default()
    };
    c.refused(&zip_of(&entries), &limits, "12 entries, more than the 10 allowed");
    let limits = Limits {
        max_entries: 12,
        ..Limits::default()
    };
    assert!(c.extract(&zip_of(&entries), &limits).is_ok());
}

/// A bomb with honest headers (4 MiB of zeros deflate to a few KiB).
#[test]
fn an_honest_bomb_is_refused_by_its_declared_size() {
    let c = Case::new();
    let bomb = vec![0u8; 4 << 20];
    let bytes = zip_of(&[("modelDescription.xml", MD), ("resources/bomb", &bomb)]);
    assert!(bytes.len() < 64 * 1024);
    let limits = Limits {
        max_total_bytes: 1 << 20,
        ..Limits::default()
    };
    c.refused(&bytes, &limits, "more than the 1048576 allowed");
}

#[test]
fn more_bytes_than_allowed_are_refused() {
    let c = Case::new();
    let big = vec![0u8; 3000];
    let bytes = zip_of(&[("modelDescription.xml", MD), ("a", &big[..1500]), ("b", &big)]);
    let limits = Limits {
        max_total_bytes: 4000,
        ..Limits::default()
    };
    c.refused(&bytes, &limits, "more than the 4000 allowed");
}

/// A zip bomb whose headers lie: they declare 100 bytes for an entry that inflates to 4 MiB.
/// The limit holds on the bytes actually written, not on the header's claim (the zip reader
/// also stops at the declared size: either refusal will do; the unit test of the bounded copy
/// in `archive.rs` covers the count on its own).
#[test]
fn a_zip_bomb_with_lying_headers_is_refused() {
    let c = Case::new();
    let bomb = vec![0u8; 4 << 20];
    let mut bytes = zip_of(&[("modelDescription.xml", MD), ("resources/bomb", &bomb)]);
    // Patch the uncompressed size of the bomb in its local header (offset 22) and in its
    // central directory record (offset 24) to 100.
    let name = b"resources/bomb";
    let mut patched = 0;
    for i in 0..bytes.len() - 4 {
        let sig = &bytes[i..i + 4];
        let (off, name_at) = if sig == b"PK\x03\x04" {
            (22, 30)
        } else if sig == b"PK\x01\x02" {
            (24, 46)
        } else {
            continue;
        };
        if bytes.get(i + name_at..i + name_at + name.len()) == Some(&name[..]) {
            bytes[i + off..i + off + 4].copy_from_slice(&100u32.to_le_bytes());
            patched += 1;
        }
    }
    assert_eq!(patched, 2);
    let limits = Limits {
        max_total_bytes: 1 << 20,
        ..Limits::default()
    };
    match c.extract(&bytes, &limits) {
        Ok(_) => panic!("a bomb of 4 MiB was unpacked under a limit of 1 MiB"),
        Err(e) => assert!(
            e.contains("zip bomb") || e.contains("larger than its declared uncompressed size"),
            "refused, but not for its size: {e}"
        ),
    }
}

#[test]
fn a_malformed_model_description_is_reported_with_line_and_column() {
    let c = Case::new();
    let xml = b"<?xml version=\"1.0\"?>\n<fmiModelDescription fmiVersion=\"2.0\">\n  <CoSimulation modelIdentifier=\"M\">\n</fmiModelDescription>\n";
    let mut a = archive::open(&c.write(&zip_of(&[("modelDescription.xml", xml)]))).unwrap();
    let e = archive::read_model_description(&mut a).unwrap_err();
    assert!(e.contains("modelDescription.xml:4:"), "no line: {e}");
    let mut a = archive::open(&c.write(&zip_of(&[("modelDescription.xml", b"<a>\xff</a>")]))).unwrap();
    let e = archive::read_model_description(&mut a).unwrap_err();
    assert!(e.contains("modelDescription.xml:1:4: not UTF-8"), "{e}");
    let mut a = archive::open(&c.write(&zip_of(&[("modelDescription.xml", b"<a>\n <b/>\n")]))).unwrap();
    let e = archive::read_model_description(&mut a).unwrap_err();
    assert!(e.contains("modelDescription.xml:3:1"), "{e}");
    let mut a = archive::open(&c.write(&zip_of(&[("other.xml", MD)]))).unwrap();
    let e = archive::read_model_description(&mut a).unwrap_err();
    assert!(e.contains("no modelDescription.xml"), "{e}");
    let e = archive::open(&c.write(b"not a zip")).err().unwrap();
    assert!(e.contains("not a readable zip archive"), "{e}");
}

#[test]
fn line_and_column_of_a_byte_offset() {
    let t = "ab\ncdé\nf";
    assert_eq!(line_column(t, 0), (1, 1));
    assert_eq!(line_column(t, 2), (1, 3));
    assert_eq!(line_column(t, 3), (2, 1));
    // é is two bytes: the offset after it is the fourth character of line 2.
    assert_eq!(line_column(t, 7), (2, 4));
    assert_eq!(line_column(t, 100), (3, 2));
}
