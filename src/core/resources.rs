//! `fmuResourceLocation`: a file URI of the unpacked `resources/` folder.

use std::path::PathBuf;

/// The folder a `file:` URI names: `file:///abs`, `file://localhost/abs` and `file:/abs`, with
/// percent-encoding decoded. `None` for other schemes or undecodable text.
pub fn resource_dir(uri: &str) -> Option<PathBuf> {
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
    percent_decode(path).map(PathBuf::from)
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
    use super::resource_dir;
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
}
