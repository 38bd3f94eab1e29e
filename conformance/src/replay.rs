//! Reproducers: the calls of a failing random call sequence as a small text file, one call a
//! line, and [`replay`], which makes those calls again on an FMU in this process (no worker:
//! `gdb --args cargo-fmu fmu replay FILE X.fmu` stops in the FMU), prints each call and its
//! status, and says whether the FMU answered as the file expects.
//!
//! The format (conformance/README.md, "Reproducers", describes it for users):
//!
//! ```text
//! # comments and blank lines are ignored; so is everything after " #" on a line
//! fmi2Instantiate fmuType=CoSimulation loggingOn=false
//! fmi2SetupExperiment startTime=0 -> OK
//! fmi2EnterInitializationMode -> OK
//! fmi2GetReal vr=[4294967295] -> Error
//! ```
//!
//! The first call instantiates (FMI 2.0: `fmi2Instantiate fmuType=CoSimulation|ModelExchange`,
//! FMI 3.0: `fmi3InstantiateCoSimulation` or `fmi3InstantiateModelExchange`); it fixes the
//! version and the interface, and with them which calls may follow (the calls of that random
//! check, [`crate::checks::random_sequences`] and [`crate::fmi3::checks`]). Every other line is
//! `function key=value ... -> EXPECTED`, where EXPECTED is the status the standard requires of
//! that call where the sequence stands (as the check's model of the state machine said when
//! the file was written): one status (`OK`, `Error`), several (`OK|Discard`), or `any` (OK,
//! Warning, Discard or Error: the standard leaves the answer open, but never Fatal). Values:
//! numbers as Rust prints them (`0.5`, `1e-5`, `NaN`, `inf`), lists `[1,2]`, `NULL` for a null
//! pointer. The instance is freed after the last line.
//!
//! A replay fails (exit code 1) at the first call whose status is not among those the file
//! expects, or that breaks one of the check's other assertions (a message for every status but
//! OK, an fmi2Error that changed the FMU state, a call of more than 10 s...).

use std::collections::BTreeMap;
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

/// The statuses a call may answer (FMI 2.0 and 3.0 share their values 0 to 4): a bit per status.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Expected(pub u8);

const NAMES: [&str; 5] = ["OK", "Warning", "Discard", "Error", "Fatal"];

impl Expected {
    pub const OK: Expected = Expected(1);
    pub const ERROR: Expected = Expected(1 << 3);
    pub const OK_OR_DISCARD: Expected = Expected(1 | 1 << 2);
    pub const OK_OR_WARNING: Expected = Expected(1 | 1 << 1);
    /// OK, Warning, Discard or Error: anything but Fatal.
    pub const ANY: Expected = Expected(0b1111);

    pub fn contains(self, status: u32) -> bool {
        status < 5 && self.0 & (1 << status) != 0
    }

    pub fn parse(text: &str) -> Result<Expected, String> {
        if text == "any" {
            return Ok(Expected::ANY);
        }
        let mut bits = 0u8;
        for part in text.split('|') {
            let i = NAMES
                .iter()
                .position(|n| *n == part)
                .ok_or_else(|| format!("expected status {part:?}: one of OK, Warning, Discard, Error, Fatal or any"))?;
            bits |= 1 << i;
        }
        Ok(Expected(bits))
    }
}

impl std::fmt::Display for Expected {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if *self == Expected::ANY {
            return f.write_str("any");
        }
        let names: Vec<&str> = (0..5).filter(|i| self.0 & (1 << i) != 0).map(|i| NAMES[i]).collect();
        f.write_str(&names.join("|"))
    }
}

/// A status as the file writes it (`OK`, ..., or the number when it is none).
pub fn status_word(status: u32) -> String {
    match usize::try_from(status).ok().and_then(|i| NAMES.get(i)) {
        Some(n) => n.to_string(),
        None => format!("status {status}"),
    }
}

/// One line of a reproducer: the function, its arguments in order, what the file expects.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// 1-based, for messages.
    pub number: usize,
    pub function: String,
    pub args: BTreeMap<String, String>,
    /// Bare words (`NULL`-free flags such as `all`).
    pub words: Vec<String>,
    pub expected: Option<Expected>,
}

impl Line {
    /// An error about this line.
    pub fn error(&self, what: impl std::fmt::Display) -> String {
        format!("line {} ({}): {what}", self.number, self.function)
    }

    pub fn has(&self, key: &str) -> bool {
        self.args.contains_key(key)
    }

    pub fn raw(&self, key: &str) -> Result<&str, String> {
        self.args
            .get(key)
            .map(String::as_str)
            .ok_or_else(|| self.error(format!("needs {key}=")))
    }

    pub fn parse<T: std::str::FromStr>(&self, key: &str) -> Result<T, String>
    where
        T::Err: std::fmt::Display,
    {
        let v = self.raw(key)?;
        v.parse().map_err(|e| self.error(format!("{key}={v}: {e}")))
    }

    pub fn parse_or<T: std::str::FromStr>(&self, key: &str, default: T) -> Result<T, String>
    where
        T::Err: std::fmt::Display,
    {
        if self.has(key) { self.parse(key) } else { Ok(default) }
    }

    /// `key=[a,b,...]` as a list (`key=NULL`: None).
    pub fn list<T: std::str::FromStr>(&self, key: &str) -> Result<Option<Vec<T>>, String>
    where
        T::Err: std::fmt::Display,
    {
        let v = self.raw(key)?;
        if v == "NULL" {
            return Ok(None);
        }
        let inner = v
            .strip_prefix('[')
            .and_then(|v| v.strip_suffix(']'))
            .ok_or_else(|| self.error(format!("{key}={v}: a list [a,b,...] or NULL")))?;
        inner
            .split(',')
            .filter(|s| !s.is_empty())
            .map(|s| s.parse().map_err(|e| self.error(format!("{key}: {s}: {e}"))))
            .collect::<Result<Vec<T>, String>>()
            .map(Some)
    }
}

/// Reads a reproducer: its lines without comments, the first being the instantiation.
pub fn parse_file(text: &str) -> Result<Vec<Line>, String> {
    let mut lines = vec![];
    for (i, raw) in text.lines().enumerate() {
        let content = match raw.find(" #") {
            Some(at) => &raw[..at],
            None if raw.trim_start().starts_with('#') => "",
            None => raw,
        };
        let content = content.trim();
        if content.is_empty() {
            continue;
        }
        let number = i + 1;
        let (call, expected) = match content.split_once("->") {
            Some((c, e)) => (
                c.trim(),
                Some(Expected::parse(e.trim()).map_err(|e| format!("line {number}: {e}"))?),
            ),
            None => (content, None),
        };
        let mut tokens = call.split_whitespace();
        let function = tokens.next().unwrap_or_default().to_string();
        let (mut args, mut words) = (BTreeMap::new(), vec![]);
        for t in tokens {
            match t.split_once('=') {
                Some((k, v)) => {
                    args.insert(k.to_string(), v.to_string());
                }
                None => words.push(t.to_string()),
            }
        }
        lines.push(Line {
            number,
            function,
            args,
            words,
            expected,
        });
    }
    if lines.is_empty() {
        return Err("no call in the file".into());
    }
    Ok(lines)
}

/// A value as the file writes it: Rust's shortest text that reads back to the same bits.
pub fn real(x: f64) -> String {
    format!("{x:?}")
}

/// A list as the file writes it: `[a,b]`.
pub fn list<T: std::fmt::Display>(items: impl IntoIterator<Item = T>) -> String {
    let v: Vec<String> = items.into_iter().map(|x| x.to_string()).collect();
    format!("[{}]", v.join(","))
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

/// What a replay found: each call as printed, and the first difference (None: the FMU answered
/// every call as the file expects).
#[derive(Debug, Clone, Default)]
pub struct ReplayReport {
    pub lines: Vec<String>,
    pub difference: Option<String>,
}

/// Replays the reproducer `file` on the FMU file `fmu` in this process, printing each call as it
/// goes through `out`. Err: the file or the FMU could not be read.
pub fn replay(file: &Path, fmu: &Path, out: &mut dyn FnMut(&str)) -> Result<ReplayReport, String> {
    let text = std::fs::read_to_string(file).map_err(|e| format!("{}: {e}", file.display()))?;
    let lines = parse_file(&text).map_err(|e| format!("{}: {e}", file.display()))?;
    let root = crate::unpack_root()?;
    let version = crate::file_version(fmu)?;
    let first = &lines[0];
    // The checks' own assertions panic: a panic is a difference too, with its message.
    let caught = |run: &mut dyn FnMut() -> Result<ReplayReport, String>| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(run)).unwrap_or_else(|payload| {
            let message = payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "a panic without a message".into());
            Ok(ReplayReport {
                lines: vec![],
                difference: Some(message),
            })
        })
    };
    // A named check's reproducer names its instance; a random sequence's does not.
    let named = first.has("instanceName");
    let report = match (version, first.function.as_str()) {
        (crate::Version::Fmi2, "fmi2Instantiate") if named => {
            let loaded = crate::Fmu::load(fmu, &root)?;
            caught(&mut || crate::replay_calls::replay2(&loaded, &lines, out))
        }
        (crate::Version::Fmi3, "fmi3InstantiateCoSimulation" | "fmi3InstantiateModelExchange") if named => {
            let loaded = crate::Fmu3::load(fmu, &root)?;
            caught(&mut || crate::replay_calls::replay3(&loaded, &lines, out))
        }
        (crate::Version::Fmi2, "fmi2Instantiate") => {
            let loaded = crate::Fmu::load(fmu, &root)?;
            caught(&mut || crate::checks::random_sequences::replay(&loaded, &lines, out))
        }
        (crate::Version::Fmi3, "fmi3InstantiateCoSimulation" | "fmi3InstantiateModelExchange") => {
            let loaded = crate::Fmu3::load(fmu, &root)?;
            caught(&mut || crate::fmi3::checks::replay(&loaded, &lines, out))
        }
        (v, f) => Err(format!(
            "{}: the first call is {f}, which does not instantiate an FMU of {} (FMI {})",
            file.display(),
            fmu.display(),
            match v {
                crate::Version::Fmi2 => "2.0: fmi2Instantiate",
                crate::Version::Fmi3 => "3.0: fmi3InstantiateCoSimulation or fmi3InstantiateModelExchange",
            }
        )),
    };
    report.map_err(|e| format!("{}: {e}", file.display()))
}

/// The replay's line for a call: its number, the call, the status, and the expectation when the
/// status is not among it.
pub fn replay_line(line: &Line, call: &str, status: u32, expected: Expected) -> String {
    let mut s = format!("{:>4} {call} -> {}", line.number, status_word(status));
    if !expected.contains(status) {
        let _ = write!(s, "   DIFFERS: the file expects {expected}");
    }
    s
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

    #[test]
    fn expectations_read_back_as_written() {
        for e in [Expected::OK, Expected::ERROR, Expected::OK_OR_DISCARD, Expected::ANY] {
            assert_eq!(Expected::parse(&e.to_string()), Ok(e));
        }
        assert!(Expected::ANY.contains(3) && !Expected::ANY.contains(4));
        assert!(Expected::parse("Fine").is_err());
    }

    #[test]
    fn a_line_gives_its_function_arguments_and_expectation() {
        let lines = parse_file(
            "# about\nfmi2Instantiate fmuType=CoSimulation\n\nfmi2SetReal vr=[1,2] values=[0.5,NaN] -> any # a note\n",
        )
        .unwrap();
        assert_eq!(lines.len(), 2);
        let l = &lines[1];
        assert_eq!(
            (l.number, l.function.as_str(), l.expected),
            (4, "fmi2SetReal", Some(Expected::ANY))
        );
        assert_eq!(l.list::<u32>("vr").unwrap(), Some(vec![1, 2]));
        let v = l.list::<f64>("values").unwrap().unwrap();
        assert!(v[0] == 0.5 && v[1].is_nan());
        assert!(l.parse::<f64>("x").unwrap_err().contains("line 4"));
    }
}
