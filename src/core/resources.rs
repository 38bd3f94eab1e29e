//! `fmuResourceLocation`: a file URI of the unpacked `resources/` folder.

use std::path::PathBuf;

/// The folder a `file:` URI names: `file:///abs`, `file://localhost/abs` and `file:/abs`, with
/// percent-encoding decoded; on Windows `file:///C:/dir` is `C:/dir` (RFC 8089, appendix E.2).
/// `None` for other schemes or undecodable text.
pub fn resource_dir(uri: &str) -> Option<PathBuf> {
    path_of(uri, cfg!(windows))
}

fn path_of(uri: &str, windows: bool) -> Option<PathBuf> {
    let rest = uri.strip_prefix("file:")?;
    let path = if let Some(after) = rest.strip_prefix("//") {
        // authority: empty or localhost
        let slash = after.find('/')?;
        let host = &after[..slash];
        if !(host.is_empty() || host.eq_ignore_ascii_case("localhost")) {
            return None;
        }
        &after[slash..]
    } else {
        rest
    };
    if !path.starts_with('/') {
        return None;
    }
    let decoded = percent_decode(path)?;
    // "/C:/dir" -> "C:/dir": a drive letter after the path's slash (what every Windows importer
    // sends; wine's "Z:" too).
    let b = decoded.as_bytes();
    if windows && b.len() >= 3 && b[0] == b'/' && b[1].is_ascii_alphabetic() && b[2] == b':' {
        return Some(PathBuf::from(&decoded[1..]));
    }
    Some(PathBuf::from(decoded))
}

fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = s.get(i + 1..i + 3)?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::{path_of, resource_dir};
    use std::path::Path;

    #[test]
    fn accepts_the_file_uri_forms_importers_send() {
        assert_eq!(
            resource_dir("file:///tmp/a%20b/resources").as_deref(),
            Some(Path::new("/tmp/a b/resources"))
        );
        assert_eq!(resource_dir("file:/tmp/x").as_deref(), Some(Path::new("/tmp/x")));
        assert_eq!(
            resource_dir("file://localhost/tmp/x/").as_deref(),
            Some(Path::new("/tmp/x/"))
        );
        assert_eq!(resource_dir("http://example.org/x"), None);
        assert_eq!(resource_dir("file:///bad%zz"), None);
        assert_eq!(resource_dir("file://otherhost/x"), None);
    }

    #[test]
    fn a_windows_drive_letter_loses_the_slash_before_it_on_windows_only() {
        assert_eq!(
            path_of("file:///Z:/work/a%20b/resources", true).as_deref(),
            Some(Path::new("Z:/work/a b/resources"))
        );
        assert_eq!(path_of("file:/C:/x", true).as_deref(), Some(Path::new("C:/x")));
        assert_eq!(path_of("file:///Z:/x", false).as_deref(), Some(Path::new("/Z:/x")));
        assert_eq!(path_of("file:///tmp/x", true).as_deref(), Some(Path::new("/tmp/x")));
    }
}
