//! Writing reproducers ([`super`] is their format): where they go ([`reproducers_dir`]), a
//! random sequence's ([`reproducer_text`] of its [`Recorded`] calls), a named check's from its
//! call log ([`write_check_reproducer`]), and the sentence a failure message names one with.

use super::{Expected, status_word};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The environment variable that names the folder the random checks write their reproducers
/// into (`cargo fmu check --reproducers DIR` sets it for its workers); default
/// [`default_reproducers_dir`].
pub const REPRODUCERS_VAR: &str = "RUSTFMU_REPRODUCERS";

/// `<system temp dir>/fmu-check-reproducers`.
pub fn default_reproducers_dir() -> PathBuf {
    std::env::temp_dir().join("fmu-check-reproducers")
}

/// Where reproducers go: `$RUSTFMU_REPRODUCERS`, else [`default_reproducers_dir`].
pub fn reproducers_dir() -> PathBuf {
    std::env::var_os(REPRODUCERS_VAR)
        .map(PathBuf::from)
        .unwrap_or_else(default_reproducers_dir)
}

/// One call of a sequence as recorded while it ran: the line (without the expectation), what the
/// standard required, what the FMU answered.
#[derive(Debug, Clone)]
pub struct Recorded {
    pub call: String,
    pub expected: Expected,
    pub status: u32,
}

/// The text of a reproducer: a header of comments (`about`: the FMU, the check, the failure),
/// the instantiation, then each call with its expectation; a call the FMU did not answer as
/// expected says what it answered in a comment.
pub fn reproducer_text(about: &[String], instantiate: &str, calls: &[Recorded], failure: &str) -> String {
    let mut t =
        String::from("# A reproducer written by fmi-conformance: the calls of a failing random call sequence,\n");
    t.push_str("# one a line, each with the status the standard requires there (conformance/README.md,\n");
    t.push_str("# \"Reproducers\"). Run it again: cargo fmu replay THIS_FILE X.fmu\n");
    for a in about {
        let _ = writeln!(t, "# {a}");
    }
    for l in failure.lines().take(20) {
        let _ = writeln!(t, "# failure: {l}");
    }
    let _ = writeln!(t, "{instantiate}");
    for c in calls {
        let _ = write!(t, "{} -> {}", c.call, c.expected);
        if !c.expected.contains(c.status) {
            let _ = write!(t, " # answered {} when the sequence failed", status_word(c.status));
        }
        t.push('\n');
    }
    t
}

/// Writes `text` as `<dir>/<stem>-<n>.txt` (the first n not taken) under [`reproducers_dir`];
/// the path, or why it could not be written.
pub fn write_reproducer(stem: &str, text: &str) -> Result<PathBuf, String> {
    let dir = reproducers_dir();
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    for n in 1..10_000 {
        let path = dir.join(format!("{stem}-{n}.txt"));
        match std::fs::OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(mut f) => {
                use std::io::Write;
                return f
                    .write_all(text.as_bytes())
                    .map(|()| path.clone())
                    .map_err(|e| format!("{}: {e}", path.display()));
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(format!("{}: {e}", path.display())),
        }
    }
    Err(format!("{}: too many reproducers named {stem}", dir.display()))
}

/// How the sentence that names a reproducer starts ([`reproducer_note`]), in every failure
/// message that has one.
pub const REPRODUCER_SENTENCE: &str = "reproducer (";

/// Writes the reproducer of the named check `check` that failed with `failure` on the FMU `id`
/// (its file `archive`): the calls of `log`, the instance it failed on ([`crate::calllog`]) with the
/// check's `notes` on them, as
/// `<id>-fmi2-<check>-<n>.txt` (`-fmi3-`); the sentence that ends the failure message. `warning`:
/// the check only warned, `failure` is its first warning and `log` ends with the call it followed.
pub fn write_check_reproducer(
    id: &str,
    archive: &Path,
    version: crate::Version,
    check: &str,
    failure: &str,
    (log, notes): &(crate::calllog::Log, Vec<(u64, crate::calllog::Note)>),
    warning: bool,
) -> String {
    let v = match version {
        crate::Version::Fmi2 => "fmi2",
        crate::Version::Fmi3 => "fmi3",
    };
    let about = [
        format!(
            "FMU: {} (model {id}, {})",
            archive.display(),
            if v == "fmi2" { "FMI 2.0" } else { "FMI 3.0" }
        ),
        format!("check: {check}"),
    ];
    let text = crate::calllog::reproducer_text(log, notes, &about, failure, warning);
    let written = write_reproducer(&format!("{id}-{v}-{check}"), &text);
    let of = if warning {
        "the calls of the instance of the first warning, up to the call it followed, one a line"
    } else {
        "the calls of the instance the check failed on, one a line"
    };
    match written {
        Ok(path) => format!(
            "reproducer ({of}): {}; replay it with \
             `cargo fmu replay {} {}` (or `fmu-check --replay {} {}`)",
            path.display(),
            path.display(),
            archive.display(),
            path.display(),
            archive.display()
        ),
        Err(e) => format!("no reproducer written: {e}"),
    }
}

/// The reproducers a failure message names ([`reproducer_note`], [`write_check_reproducer`]).
pub fn reproducer_paths(message: &str) -> Vec<PathBuf> {
    message
        .split(REPRODUCER_SENTENCE)
        .skip(1)
        .filter_map(|rest| {
            let path = rest.split_once("): ")?.1;
            Some(PathBuf::from(path.split_once("; replay it")?.0))
        })
        .collect()
}

/// The sentence a failure message ends with: where the reproducer is and how to replay it.
pub fn reproducer_note(written: Result<PathBuf, String>, fmu: &Path) -> String {
    match written {
        Ok(path) => format!(
            "reproducer (the failing sequence, one call a line): {}; replay it with `cargo fmu replay {} {}` \
             (or `fmu-check --replay {} {}`)",
            path.display(),
            path.display(),
            fmu.display(),
            path.display(),
            fmu.display()
        ),
        Err(e) => format!("no reproducer written: {e}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reproducers_a_failure_message_names_are_found() {
        let fmu = Path::new("X.fmu");
        let m = format!(
            "broken\n{}\nand\n{}",
            reproducer_note(Ok(PathBuf::from("/t/a-1.txt")), fmu),
            reproducer_note(Ok(PathBuf::from("/t/b c-2.txt")), fmu)
        );
        assert_eq!(
            reproducer_paths(&m),
            [PathBuf::from("/t/a-1.txt"), PathBuf::from("/t/b c-2.txt")]
        );
        assert!(reproducer_paths("no reproducer written: full disk").is_empty());
    }
}
