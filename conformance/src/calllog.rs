//! The call log: every FMI call a named check makes on an instance, recorded as it is made (the
//! function, its arguments as typed values, the status it answered), so that a failing check
//! leaves a reproducer ([`crate::replay`]): the calls of the instance it failed on, up to the
//! failing call, one a line, which `cargo fmu replay FILE X.fmu` makes again.
//!
//! Cheap on purpose (checks make thousands of calls): a record is a few words and the
//! arguments' values, nothing is formatted until a check fails. Each instance (FMI 2.0
//! [`crate::instance::Instance`], FMI 3.0 [`crate::fmi3::Inst`]) keeps its own [`Log`]; when it
//! is dropped it hands the log here ([`retire`]): kept while the thread unwinds from a failure,
//! otherwise only the last one (a check may fail on values read before it compares them). The
//! failing instance is the one that made the last call of the check ([`take_failing`]).
//!
//! A check may say more about its last call: what the standard requires it to answer
//! ([`standard_requires`]) or the values it expected ([`expect_values`]); the reproducer then
//! expects that, so that the replay exits 1 where the FMU does it again.

use crate::replay::{Expected, list, real, status_word};
use std::cell::{Cell, RefCell};
use std::fmt::Write as _;

/// An argument's value, as the reproducer writes it.
#[derive(Debug, Clone)]
pub enum Val {
    F64(f64),
    U64(u64),
    Bool(bool),
    U32s(Vec<u32>),
    F64s(Vec<f64>),
    /// Integers and Booleans (0/1) of every width.
    I64s(Vec<i64>),
    /// Bytes, written `hex:0a1b...`.
    Bytes(Vec<u8>),
    /// Text (spaces, `#` and `%` percent-encoded).
    Text(String),
    /// A list of texts, each as [`Val::Text`].
    Texts(Vec<String>),
    /// A null pointer.
    Null,
    /// An FMU state, by its number in the log (the first one made is 1).
    State(usize),
    /// Written as it is (already in the file's words: a list with NULL elements).
    Raw(String),
}

impl std::fmt::Display for Val {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        /// `[a,b,...]` as [`list`] writes it, item by item (the breadcrumb of every call is
        /// formatted so, and stops formatting when full).
        fn items<T>(f: &mut std::fmt::Formatter<'_>, v: &[T], item: impl Fn(&T) -> String) -> std::fmt::Result
        where
            T: std::fmt::Display,
        {
            f.write_str("[")?;
            for (i, x) in v.iter().enumerate() {
                if i > 0 {
                    f.write_str(",")?;
                }
                f.write_str(&item(x))?;
            }
            f.write_str("]")
        }
        match self {
            Val::F64(x) => f.write_str(&real(*x)),
            Val::U64(x) => write!(f, "{x}"),
            Val::Bool(b) => write!(f, "{b}"),
            Val::U32s(v) => items(f, v, u32::to_string),
            Val::F64s(v) => items(f, v, |x| real(*x)),
            Val::I64s(v) => items(f, v, i64::to_string),
            Val::Bytes(b) => {
                f.write_str("hex:")?;
                b.iter().try_for_each(|x| write!(f, "{x:02x}"))
            }
            Val::Text(t) => f.write_str(&encode(t)),
            Val::Texts(t) => f.write_str(&list(t.iter().map(|t| encode(t)))),
            Val::Null => f.write_str("NULL"),
            Val::State(n) => write!(f, "{n}"),
            Val::Raw(t) => f.write_str(t),
        }
    }
}

/// Text as one word of a line: `%`, spaces, `#`, `,`, `[`, `]` and control characters
/// percent-encoded; the empty text as `%`.
pub fn encode(t: &str) -> String {
    if t.is_empty() {
        return "%".into();
    }
    let mut s = String::with_capacity(t.len());
    for c in t.chars() {
        if c == '%' || c == '#' || c == ',' || c == '[' || c == ']' || c == '=' || c.is_whitespace() || c.is_control() {
            let mut b = [0u8; 4];
            for x in c.encode_utf8(&mut b).bytes() {
                let _ = write!(s, "%{x:02X}");
            }
        } else {
            s.push(c);
        }
    }
    s
}

/// The text [`encode`] wrote.
pub fn decode(w: &str) -> Result<String, String> {
    if w == "%" {
        return Ok(String::new());
    }
    let b = w.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let h = w
                .get(i + 1..i + 3)
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| format!("{w}: % must be followed by two hex digits"))?;
            out.push(h);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|e| format!("{w}: {e}"))
}

/// `hex:...` back to bytes.
pub fn unhex(w: &str) -> Result<Vec<u8>, String> {
    let h = w
        .strip_prefix("hex:")
        .ok_or_else(|| format!("{w}: bytes are written hex:..."))?;
    if h.len() % 2 != 0 {
        return Err(format!("{w}: an odd number of hex digits"));
    }
    (0..h.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&h[i..i + 2], 16).map_err(|e| format!("{w}: {e}")))
        .collect()
}

/// One call as recorded.
#[derive(Debug, Clone)]
pub struct Rec {
    /// Its place among every call of the thread (which instance made the last one).
    pub seq: u64,
    pub function: std::borrow::Cow<'static, str>,
    pub args: Vec<(&'static str, Val)>,
    /// Whether the line can be replayed: false for a call recorded without its arguments (a
    /// comment in the reproducer).
    pub replayable: bool,
    /// None: the call did not come back to the log (the check failed inside it, on the guard
    /// after a buffer the FMU wrote past).
    pub status: Option<u32>,
}

/// The most calls one instance's log keeps: a longer run is cut (and says so), so that a check
/// that steps an instance 50 000 times keeps a bounded log.
pub const MAX_CALLS: usize = 200_000;

/// The calls of one instance: its instantiation and every call after it.
#[derive(Debug, Clone, Default)]
pub struct Log {
    pub instantiate: Option<Rec>,
    pub calls: Vec<Rec>,
    /// Calls left out after [`MAX_CALLS`].
    pub cut: usize,
    /// The FMU states this instance's calls made or used, by address: `Val::State(i + 1)`.
    states: Vec<usize>,
}

thread_local! {
    static SEQ: Cell<u64> = const { Cell::new(0) };
    static RETIRED: RefCell<Vec<Log>> = const { RefCell::new(Vec::new()) };
    static LAST: RefCell<Option<Log>> = const { RefCell::new(None) };
    static NOTES: RefCell<Vec<(u64, Note)>> = const { RefCell::new(Vec::new()) };
    /// The call a check said it failed on ([`fails_at`]), the first one said.
    static FAILING: Cell<Option<u64>> = const { Cell::new(None) };
    /// The last call made before the check's first warning ([`warned_at`]).
    static WARNED: Cell<Option<u64>> = const { Cell::new(None) };
}

/// What a check said about a call.
#[derive(Debug, Clone)]
pub enum Note {
    Requires(Expected),
    Values(Vec<f64>, f64),
    /// What the standard requires of a call a warning was about ([`warning_requires`]): the
    /// expectation of a warning's reproducer only (a failure's replays the path the check took).
    WarnedRequires(Expected),
}

fn next_seq() -> u64 {
    SEQ.with(|s| {
        let n = s.get() + 1;
        s.set(n);
        n
    })
}

impl Log {
    /// A log that starts with the instantiation `function args`.
    pub fn new(function: &'static str, args: Vec<(&'static str, Val)>) -> Log {
        Log {
            instantiate: Some(Rec {
                seq: next_seq(),
                function: function.into(),
                args,
                replayable: true,
                status: None,
            }),
            ..Log::default()
        }
    }

    /// A log of an instance the replay cannot make (its instantiation not replayable): a
    /// failure on it leaves no reproducer.
    pub fn not_replayable(function: &'static str) -> Log {
        let mut log = Log::new(function, vec![]);
        if let Some(i) = &mut log.instantiate {
            i.replayable = false;
        }
        log
    }

    /// Whether the replay can make this instance.
    pub fn replayable(&self) -> bool {
        self.instantiate.as_ref().is_some_and(|i| i.replayable)
    }

    fn last_seq(&self) -> u64 {
        self.calls.last().or(self.instantiate.as_ref()).map_or(0, |r| r.seq)
    }

    /// Whether call `seq` is this instance's.
    fn holds(&self, seq: u64) -> bool {
        self.instantiate.as_ref().is_some_and(|i| i.seq <= seq) && seq <= self.last_seq()
    }

    /// Records a call about to be made (its status unknown until [`Log::answered`]); its index.
    pub fn call(
        &mut self,
        function: impl Into<std::borrow::Cow<'static, str>>,
        args: Vec<(&'static str, Val)>,
        replayable: bool,
    ) -> usize {
        let rec = Rec {
            seq: next_seq(),
            function: function.into(),
            args,
            replayable,
            status: None,
        };
        // Every call recorded names itself in the breadcrumb, so that a crash inside the FMU is
        // reported with the call that crashed (its arguments as the reproducer writes them).
        if crate::outcome::breadcrumbs_on() {
            crate::outcome::breadcrumb(&line_of_at_most(&rec, crate::outcome::BREADCRUMB_BYTES));
        }
        if self.calls.len() >= MAX_CALLS {
            self.cut += 1;
            return usize::MAX;
        }
        self.calls.push(rec);
        self.calls.len() - 1
    }

    /// The status call `i` answered.
    pub fn answered(&mut self, i: usize, status: u32) {
        if let Some(r) = self.calls.get_mut(i) {
            r.status = Some(status);
        }
    }

    /// The number of the FMU state at `address` (a new one when `made`); None for a state this
    /// instance's calls neither made nor used (made by another instance: not replayable).
    pub fn state(&mut self, address: usize, made: bool) -> Option<usize> {
        if let Some(i) = self.states.iter().position(|a| *a == address) {
            if made {
                // The address was freed and reused for a new state.
                self.states.push(address);
                return Some(self.states.len());
            }
            return Some(i + 1);
        }
        if made {
            self.states.push(address);
            return Some(self.states.len());
        }
        None
    }

    /// Marks the last call with `args` (an output that became known when it returned).
    pub fn add_arg(&mut self, i: usize, key: &'static str, v: Val) {
        if let Some(r) = self.calls.get_mut(i) {
            r.args.push((key, v));
        }
    }
}

/// Starts a check: forgets the logs and notes of the one before (and makes sure a warning
/// notes the call it followed, [`warned_at`]).
pub fn begin() {
    crate::outcome::on_warning(|| warned_at(last_call()));
    RETIRED.with(|r| r.borrow_mut().clear());
    LAST.with(|l| *l.borrow_mut() = None);
    NOTES.with(|n| n.borrow_mut().clear());
    FAILING.with(|f| f.set(None));
    WARNED.with(|f| f.set(None));
}

/// An instance's log, handed over when the instance is dropped.
pub fn retire(log: Log) {
    if log.instantiate.is_none() {
        return;
    }
    // The instance of the call the check said it failed on is kept, though the check goes on
    // with other instances (and fails when it has gathered every failure).
    let holds =
        |at: &'static std::thread::LocalKey<Cell<Option<u64>>>| at.with(Cell::get).is_some_and(|s| log.holds(s));
    if std::thread::panicking() || holds(&FAILING) || holds(&WARNED) {
        RETIRED.with(|r| r.borrow_mut().push(log));
    } else {
        LAST.with(|l| *l.borrow_mut() = Some(log));
    }
}

/// The check says the standard requires its last call to answer `expected` (where it failed
/// because the FMU answered otherwise): the reproducer expects that.
pub fn standard_requires(expected: Expected) {
    let seq = SEQ.with(Cell::get);
    NOTES.with(|n| n.borrow_mut().push((seq, Note::Requires(expected))));
}

/// The check warned ([`crate::outcome::warn`]) just after call `seq` ([`last_call`]): the first
/// warning's call ends the reproducer of a check that only warned ([`take_warned`]).
pub fn warned_at(seq: u64) {
    if seq > 0 && WARNED.with(Cell::get).is_none() {
        WARNED.with(|w| w.set(Some(seq)));
    }
}

/// The check warned because its last call answered otherwise than `expected`, what the standard
/// requires there (an importer's mistake the FMU must refuse with fmi3Error, FMI 3.0.2 §2.2.4):
/// a warning's reproducer expects that, so that its replay exits 1 where the FMU does it again;
/// a failure's reproducer (the check went on past it) expects what the FMU answered.
pub fn warning_requires(expected: Expected) {
    let seq = SEQ.with(Cell::get);
    NOTES.with(|n| n.borrow_mut().push((seq, Note::WarnedRequires(expected))));
}

/// The check expected its last call (a getter, a step's lastSuccessfulTime) to give `values`,
/// each within `within`: the reproducer says so, and the replay compares.
pub fn expect_values(values: &[f64], within: f64) {
    let seq = SEQ.with(Cell::get);
    NOTES.with(|n| n.borrow_mut().push((seq, Note::Values(values.to_vec(), within))));
}

/// The number of the last call recorded on this thread (for [`fails_at`] once the check has
/// made more calls).
pub fn last_call() -> u64 {
    SEQ.with(Cell::get)
}

/// The check failed on call `seq` ([`last_call`] just after it), which gave `values` where it
/// expected `expected`, each within `within`: the reproducer is of that call's instance, ends
/// with that call and expects those values, so that the replay exits 1 where the FMU gives
/// them again. For a check that gathers its failures and fails at the end: the first one said
/// is the one written.
pub fn fails_at(seq: u64, expected: &[f64], within: f64) {
    if FAILING.with(Cell::get).is_some() {
        return;
    }
    FAILING.with(|f| f.set(Some(seq)));
    NOTES.with(|n| n.borrow_mut().push((seq, Note::Values(expected.to_vec(), within))));
}

/// The log of the instance the check failed on, with the notes the check made on its calls: the
/// instance of the call [`fails_at`] named, cut after it; else the instance that made the last
/// call of the check (among those dropped).
pub fn take_failing() -> Option<(Log, Vec<(u64, Note)>)> {
    let mut logs = RETIRED.with(|r| std::mem::take(&mut *r.borrow_mut()));
    logs.extend(LAST.with(|l| l.borrow_mut().take()));
    let notes = NOTES.with(|n| std::mem::take(&mut *n.borrow_mut()));
    if let Some(seq) = FAILING.with(|f| f.take())
        && let Some(mut log) = logs.iter().position(|l| l.holds(seq)).map(|i| logs.swap_remove(i))
    {
        log.calls.retain(|r| r.seq <= seq);
        return Some((log, notes));
    }
    let log = logs.into_iter().max_by_key(Log::last_seq)?;
    Some((log, notes))
}

/// The log of the instance of the call the check's first warning followed ([`warned_at`]), cut
/// after that call, with the notes the check made; None where no instance made it (a warning
/// about the archive, the description or the binary's exports).
pub fn take_warned() -> Option<(Log, Vec<(u64, Note)>)> {
    let seq = WARNED.with(|w| w.take())?;
    let mut logs = RETIRED.with(|r| std::mem::take(&mut *r.borrow_mut()));
    logs.extend(LAST.with(|l| l.borrow_mut().take()));
    let notes = NOTES.with(|n| std::mem::take(&mut *n.borrow_mut()));
    let mut log = logs.into_iter().find(|l| l.holds(seq))?;
    log.calls.retain(|r| r.seq <= seq);
    Some((log, notes))
}

/// A record's line: `function key=value ...`.
fn line_of(r: &Rec) -> String {
    line_of_at_most(r, usize::MAX)
}

/// [`line_of`], formatted no further than about `max` bytes (a breadcrumb's: a state's bytes
/// are not written out for it).
fn line_of_at_most(r: &Rec, max: usize) -> String {
    /// A writer that stops (with an error that ends the formatting) once full.
    struct Bounded(String, usize);
    impl std::fmt::Write for Bounded {
        fn write_str(&mut self, s: &str) -> std::fmt::Result {
            if self.0.len() >= self.1 {
                return Err(std::fmt::Error);
            }
            self.0.push_str(s);
            Ok(())
        }
    }
    let mut w = Bounded(r.function.to_string(), max);
    for (k, v) in &r.args {
        if write!(w, " {k}={v}").is_err() {
            break;
        }
    }
    w.0
}

/// The reproducer of a failed check from the log of the instance it failed on: `about` (the FMU,
/// the check) and the failure as comments, the instantiation, and every call up to the last
/// one, each expecting the status it answered (or what the check said the standard requires).
///
/// `warning`: the check only warned, and the log ends with the call its first warning followed
/// (the file says so; a call the warning said the standard requires another status of expects
/// that status, [`warning_requires`]).
pub fn reproducer_text(log: &Log, notes: &[(u64, Note)], about: &[String], failure: &str, warning: bool) -> String {
    let mut t = String::from(if warning {
        "# A reproducer written by fmi-conformance: the calls a named check made on the instance of its first\n\
         # warning, up to the call the warning followed, one a line, each expecting the status it answered (where\n\
         # the warning is about a status, the status the standard requires). conformance/README.md, \"Reproducers\".\n\
         # Run it again: cargo fmu replay THIS_FILE X.fmu\n"
    } else {
        "# A reproducer written by fmi-conformance: the calls a named check made on the instance it failed on,\n\
         # up to its last call, one a line, each expecting the status it answered (where the check failed on a\n\
         # status, the status the standard requires). conformance/README.md, \"Reproducers\".\n\
         # Run it again: cargo fmu replay THIS_FILE X.fmu\n"
    });
    for a in about {
        let _ = writeln!(t, "# {a}");
    }
    let kind = if warning { "warning" } else { "failure" };
    for l in failure.lines().take(30) {
        let _ = writeln!(t, "# {kind}: {l}");
    }
    if log.cut > 0 {
        let _ = writeln!(
            t,
            "# the instance made {} more calls than the log keeps ({MAX_CALLS}): the failing call is not among these, \
             and the replay cannot show it",
            log.cut
        );
    }
    if let Some(i) = &log.instantiate {
        let _ = writeln!(t, "{}", line_of(i));
    }
    for r in &log.calls {
        let line = line_of(r);
        if !r.replayable {
            let _ = writeln!(
                t,
                "# {line} -> {} (recorded without its arguments: not replayed)",
                r.status.map_or("no status".into(), status_word)
            );
            continue;
        }
        let mut expected = match r.status {
            Some(s) if s < 5 => Expected(1 << s),
            _ => Expected::ANY,
        };
        let mut extra = String::new();
        let mut comment = String::new();
        for (_, n) in notes.iter().filter(|(s, _)| *s == r.seq) {
            match n {
                Note::WarnedRequires(_) if !warning => {}
                Note::Requires(e) | Note::WarnedRequires(e) => {
                    if let Some(s) = r.status.filter(|s| !e.contains(*s)) {
                        let _ = write!(comment, " # answered {}: the standard requires {e}", status_word(s));
                    }
                    expected = *e;
                }
                Note::Values(v, within) => {
                    let _ = write!(
                        extra,
                        " expect={} within={}",
                        list(v.iter().map(|x| real(*x))),
                        real(*within)
                    );
                }
            }
        }
        if r.status.is_none() {
            comment += " # the call did not come back to the check: it failed inside it (the guard after a buffer)";
        }
        let _ = writeln!(t, "{line}{extra} -> {expected}{comment}");
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_and_bytes_read_back_as_written() {
        for t in ["", "conformance", "a b#c%d,[x]=\n", "é"] {
            assert_eq!(decode(&encode(t)).as_deref(), Ok(t));
            assert!(!encode(t).contains(char::is_whitespace));
        }
        let b = vec![0u8, 1, 0xab, 0xff];
        assert_eq!(unhex(&Val::Bytes(b.clone()).to_string()), Ok(b));
    }

    #[test]
    fn the_failing_instance_is_the_one_that_made_the_last_call() {
        begin();
        let mut a = Log::new("fmi2Instantiate", vec![]);
        let mut b = Log::new("fmi2Instantiate", vec![("instanceName", Val::Text("b".into()))]);
        let i = a.call("fmi2EnterInitializationMode", vec![], true);
        a.answered(i, 0);
        let i = b.call("fmi2GetReal", vec![("vr", Val::U32s(vec![1]))], true);
        b.answered(i, 0);
        expect_values(&[0.5], 1e-9);
        retire(a);
        retire(b);
        let (log, notes) = take_failing().expect("a log");
        let text = reproducer_text(&log, &notes, &[], "the failure", false);
        assert!(text.contains("fmi2Instantiate instanceName=b\n"), "{text}");
        assert!(
            text.contains("fmi2GetReal vr=[1] expect=[0.5] within=1e-9 -> OK\n"),
            "{text}"
        );
        assert!(!text.contains("EnterInitializationMode"), "{text}");
        assert!(take_failing().is_none());
    }

    #[test]
    fn the_call_a_check_failed_on_ends_the_reproducer_though_the_check_went_on() {
        begin();
        let mut a = Log::new("fmi2Instantiate", vec![("instanceName", Val::Text("a".into()))]);
        let i = a.call(
            "fmi2GetDirectionalDerivative",
            vec![("unknowns", Val::U32s(vec![1]))],
            true,
        );
        a.answered(i, 0);
        fails_at(last_call(), &[1.0], 1e-5);
        // A second failure said later is not the one written.
        fails_at(last_call(), &[2.0], 0.0);
        let i = a.call("fmi2GetReal", vec![("vr", Val::U32s(vec![1]))], true);
        a.answered(i, 0);
        retire(a);
        let mut b = Log::new("fmi2Instantiate", vec![("instanceName", Val::Text("b".into()))]);
        let i = b.call("fmi2GetReal", vec![("vr", Val::U32s(vec![1]))], true);
        b.answered(i, 0);
        retire(b);
        let (log, notes) = take_failing().expect("a log");
        let text = reproducer_text(&log, &notes, &[], "the failure", false);
        assert!(text.contains("fmi2Instantiate instanceName=a\n"), "{text}");
        assert!(
            text.ends_with("fmi2GetDirectionalDerivative unknowns=[1] expect=[1.0] within=1e-5 -> OK\n"),
            "{text}"
        );
    }
}
