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
//!
//! This file is the format, the room below everything that reads or writes it (the call log
//! [`crate::calllog`] writes its lines): [`Expected`], [`Line`], [`parse_file`], how values and
//! statuses are written, and the line a replay prints for a call ([`replay_line`]). Above it,
//! [`write`] writes reproducers (a random sequence's, a named check's from its call log), and
//! [`run`] replays a file, through [`crate::replay_calls`] (a named check's) or the random
//! sequences (theirs). [`fmi3`] says which FMI 3.0 calls a reproducer can hold.

pub mod fmi3;
pub mod run;
pub mod write;

use std::collections::BTreeMap;
use std::fmt::Write as _;

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

/// What a replay found: each call as printed, and the first difference (None: the FMU answered
/// every call as the file expects).
#[derive(Debug, Clone, Default)]
pub struct ReplayReport {
    pub lines: Vec<String>,
    pub difference: Option<String>,
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
