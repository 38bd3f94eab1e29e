//! One FMU instance driven through the C API, with its log recorded.
//!
//! Every message the FMU logs is checked as it is read ([`Instance::log`]) and when the instance
//! is dropped: it must come back with this instance's componentEnvironment and name, and (this
//! exporter's conventions) under a category declared in `<LogCategories>`, with the format
//! `"%s"`.

use crate::fmi2::*;
use crate::guard::{GETTER_RULE2, Guarded, STATE_RULE2};
use crate::logger::{LogEntry, LogSink, callbacks};
use crate::outcome::{breadcrumb, breadcrumbs_on, convention, limitation};

/// Why a refused call that changed the instance is a warning and not a failure (FMI 2.0).
pub const REFUSED_CHANGED_WHY: &str = "FMI 2.0.5 §2.1.3 leaves the instance undefined after fmi2Error, so this is \
     robustness beyond the standard; it matters to an importer that goes on after a refused call";
use crate::calllog::{Log, Val};
use crate::standard::State;
use crate::{Fmu, Type, state};
use md_reader::{Causality, Initial, Variability};
use std::cell::RefCell;
use std::ffi::CString;
use std::ptr;

pub type Status = fmi2Status;

#[allow(non_upper_case_globals)]
pub fn status_name(s: Status) -> &'static str {
    match s {
        fmi2OK => "fmi2OK",
        fmi2Warning => "fmi2Warning",
        fmi2Discard => "fmi2Discard",
        fmi2Error => "fmi2Error",
        fmi2Fatal => "fmi2Fatal",
        fmi2Pending => "fmi2Pending",
        _ => "(not a status)",
    }
}

/// Arguments of `fmi2Instantiate`; `None` strings are passed as NULL.
#[derive(Debug, Clone)]
pub struct Args {
    pub name: Option<String>,
    pub fmu_type: fmi2Type,
    pub guid: Option<String>,
    pub resources: Option<String>,
    pub logging_on: bool,
}

impl Args {
    pub fn valid(fmu: &Fmu) -> Args {
        Args {
            name: Some("conformance".into()),
            fmu_type: fmi2CoSimulation,
            guid: Some(fmu.md.guid.clone()),
            resources: Some(fmu.resource_uri()),
            logging_on: false,
        }
    }
}

pub struct Instance<'a> {
    pub fmu: &'a Fmu,
    pub c: fmi2Component,
    pub name: String,
    sink: Box<LogSink>,
    _callbacks: Box<fmi2CallbackFunctions>,
    /// The communication point of the next step, as the importer tracks it.
    pub time: f64,
    /// fmi2EnterInitializationMode answered fmi2OK since the instance was made or last reset: the
    /// getters may be called ([`Instance::fingerprint`] calls them only then).
    pub initialized: bool,
    /// Every call made on the instance ([`crate::calllog`]): a failing check's reproducer.
    pub calls: RefCell<Log>,
}

// SAFETY: an instance is used by one thread at a time (the standard's rule); the FMU has no
// thread affinity, and the sink is a Mutex.
unsafe impl Send for Instance<'_> {}

fn cstr(s: &Option<String>) -> Option<CString> {
    s.as_ref()
        .map(|s| CString::new(s.as_str()).expect("no NUL in test strings"))
}

/// Records the call about to be made (see [`crate::outcome::breadcrumb`]).
fn crumb(function: &str, args: impl FnOnce() -> String) {
    if breadcrumbs_on() {
        breadcrumb(&format!("{function}({})", args()));
    }
}

impl<'a> Instance<'a> {
    /// A co-simulation instance with valid arguments; panics with the FMU's log if refused.
    pub fn new(fmu: &'a Fmu) -> Instance<'a> {
        Instance::with(fmu, &Args::valid(fmu))
            .unwrap_or_else(|log| panic!("{}: fmi2Instantiate refused: {log:#?}", fmu.id))
    }

    pub fn with(fmu: &'a Fmu, args: &Args) -> Result<Instance<'a>, Vec<LogEntry>> {
        let sink = Box::<LogSink>::default();
        let cb = Box::new(callbacks(sink.env()));
        let (name, guid, res) = (cstr(&args.name), cstr(&args.guid), cstr(&args.resources));
        let p = |s: &Option<CString>| s.as_ref().map_or(ptr::null(), |s| s.as_ptr());
        crumb("fmi2Instantiate", || format!("{args:?}"));
        // SAFETY: valid (or NULL) strings and callbacks that outlive the instance.
        let c = unsafe {
            (fmu.api.instantiate)(
                p(&name),
                args.fmu_type,
                p(&guid),
                p(&res),
                &*cb,
                fmi2False,
                args.logging_on as fmi2Boolean,
            )
        };
        if c.is_null() {
            return Err(sink.take());
        }
        let text = |s: &Option<String>, own: &str| match s {
            None => Val::Null,
            Some(s) if s == own => Val::Text("own".into()),
            Some(s) => Val::Text(s.clone()),
        };
        let calls = RefCell::new(Log::new(
            "fmi2Instantiate",
            vec![
                ("instanceName", args.name.clone().map_or(Val::Null, Val::Text)),
                (
                    "fmuType",
                    Val::Text(
                        if args.fmu_type == fmi2ModelExchange {
                            "ModelExchange"
                        } else {
                            "CoSimulation"
                        }
                        .into(),
                    ),
                ),
                ("guid", text(&args.guid, &fmu.md.guid)),
                ("resourceLocation", text(&args.resources, &fmu.resource_uri())),
                ("loggingOn", Val::Bool(args.logging_on)),
            ],
        ));
        Ok(Instance {
            fmu,
            c,
            name: args.name.clone().unwrap_or_default(),
            sink,
            _callbacks: cb,
            time: 0.0,
            initialized: false,
            calls,
        })
    }

    /// Records a call about to be made ([`crate::calllog`]); its index for [`Instance::answered`].
    pub fn record(&self, function: &'static str, args: Vec<(&'static str, Val)>) -> usize {
        self.calls.borrow_mut().call(function, args, true)
    }

    /// Records a call whose arguments the log does not keep (a comment in the reproducer).
    pub fn record_unreplayable(&self, function: &'static str) -> usize {
        self.calls.borrow_mut().call(function, vec![], false)
    }

    /// The status the call [`Instance::record`] recorded answered; the status.
    pub fn answered(&self, i: usize, s: Status) -> Status {
        self.calls.borrow_mut().answered(i, s);
        s
    }

    /// The number of the FMU state `s` in the log (`made`: a state this call made).
    pub(crate) fn state_val(&self, s: fmi2FMUstate, made: bool) -> Option<Val> {
        if s.is_null() {
            return Some(Val::Null);
        }
        self.calls.borrow_mut().state(s as usize, made).map(Val::State)
    }

    /// Messages logged since the last call, each checked (see the module documentation).
    pub fn log(&self) -> Vec<LogEntry> {
        let entries = self.sink.take();
        for e in &entries {
            assert_eq!(
                e.env,
                self.sink.env() as usize,
                "{}: the logger got componentEnvironment {:#x}, not the one given to fmi2Instantiate ({:#x}): {e:?}",
                self.fmu.id,
                e.env,
                self.sink.env() as usize
            );
            assert_eq!(
                e.instance, self.name,
                "{}: message under another instance name: {e:?}",
                self.fmu.id
            );
            if !self.fmu.md.log_categories.contains(&e.category)
                && convention(self.fmu, "every message under a category that <LogCategories> declares")
            {
                panic!(
                    "{}: message under category '{}', which <LogCategories> does not declare ({:?}): {e:?}",
                    self.fmu.id, e.category, self.fmu.md.log_categories
                );
            }
            if e.format != "%s" {
                if convention(self.fmu, "the message format \"%s\" with the text as its argument") {
                    panic!("{}: the message format must be \"%s\": {e:?}", self.fmu.id);
                }
                if e.format.contains('%') {
                    limitation(
                        "messages with printf directives are recorded unformatted (their arguments cannot be read)",
                    );
                }
            }
        }
        entries
    }

    /// Whether a message of the log with that status contains every one of `words` (how this
    /// exporter's FMUs say what is wrong). For another exporter's FMU the wording is its own:
    /// then any message with that status will do (recorded as a limitation).
    pub fn says(&self, log: &[LogEntry], status: Status, words: &[&str]) -> bool {
        let worded = log
            .iter()
            .any(|e| e.status == status && words.iter().all(|w| e.text.contains(w)));
        worded
            || (!words.is_empty()
                && !convention(self.fmu, "the wording of messages (which words name what is wrong)")
                && log.iter().any(|e| e.status == status))
    }

    /// The log as one text, for failure messages and `contains` checks.
    pub fn log_text(&self) -> String {
        self.log()
            .iter()
            .map(|e| format!("[{} {}] {}", status_name(e.status), e.category, e.text))
            .collect::<Vec<_>>()
            .join("\n")
    }

    // ---- lifecycle -------------------------------------------------------------------------

    pub fn setup(&mut self, start: f64, stop: Option<f64>) -> Status {
        let i = self.record(
            "fmi2SetupExperiment",
            vec![
                ("startTime", Val::F64(start)),
                ("stopTime", stop.map_or(Val::Null, Val::F64)),
            ],
        );
        // SAFETY: a live instance.
        let s = unsafe {
            (self.fmu.api.setup_experiment)(
                self.c,
                fmi2False,
                0.0,
                start,
                stop.is_some() as fmi2Boolean,
                stop.unwrap_or(0.0),
            )
        };
        self.answered(i, s);
        if s == fmi2OK {
            self.time = start;
        }
        s
    }

    pub fn enter_init(&mut self) -> Status {
        let i = self.record("fmi2EnterInitializationMode", vec![]);
        // SAFETY: a live instance.
        let s = self.answered(i, unsafe { (self.fmu.api.enter_initialization_mode)(self.c) });
        self.initialized |= s == fmi2OK;
        s
    }

    pub fn exit_init(&mut self) -> Status {
        let i = self.record("fmi2ExitInitializationMode", vec![]);
        // SAFETY: a live instance.
        self.answered(i, unsafe { (self.fmu.api.exit_initialization_mode)(self.c) })
    }

    pub fn terminate(&mut self) -> Status {
        let i = self.record("fmi2Terminate", vec![]);
        // SAFETY: a live instance.
        self.answered(i, unsafe { (self.fmu.api.terminate)(self.c) })
    }

    pub fn reset(&mut self) -> Status {
        let i = self.record("fmi2Reset", vec![]);
        // SAFETY: a live instance.
        let s = self.answered(i, unsafe { (self.fmu.api.reset)(self.c) });
        if s == fmi2OK {
            self.time = 0.0;
            self.initialized = false;
        }
        s
    }

    /// Setup (start time 0, no stop time), enter and exit initialization mode; panics unless
    /// every call returns fmi2OK.
    pub fn initialize(&mut self) {
        let s = [self.setup(0.0, None), self.enter_init(), self.exit_init()];
        assert_eq!(
            s,
            [fmi2OK; 3],
            "{}: initialization failed: {}",
            self.fmu.id,
            self.log_text()
        );
    }

    pub fn do_step(&mut self, t: f64, h: f64) -> Status {
        let i = self.record(
            "fmi2DoStep",
            vec![
                ("currentCommunicationPoint", Val::F64(t)),
                ("communicationStepSize", Val::F64(h)),
            ],
        );
        // SAFETY: a live instance.
        self.answered(i, unsafe { (self.fmu.api.do_step)(self.c, t, h, fmi2False) })
    }

    /// One step from the tracked time; the time advances when the FMU answers fmi2OK.
    pub fn step(&mut self, h: f64) -> Status {
        let s = self.do_step(self.time, h);
        if s == fmi2OK {
            self.time += h;
        }
        s
    }

    // ---- values ----------------------------------------------------------------------------

    pub fn get_real(&self, vrs: &[u32]) -> (Status, Vec<f64>) {
        let i = self.record("fmi2GetReal", vec![("vr", Val::U32s(vrs.to_vec()))]);
        let mut v = Guarded::new(vrs.len(), 0.0);
        // SAFETY: arrays of nvr elements (and the guard after `v`'s).
        let s = self.answered(i, unsafe {
            (self.fmu.api.get_real)(self.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr())
        });
        let v = v.into_values(|| format!("fmi2GetReal with nvr = {}", vrs.len()), GETTER_RULE2);
        (s, v)
    }

    pub fn get_integer(&self, vrs: &[u32]) -> (Status, Vec<i32>) {
        let i = self.record("fmi2GetInteger", vec![("vr", Val::U32s(vrs.to_vec()))]);
        let mut v = Guarded::new(vrs.len(), 0);
        // SAFETY: arrays of nvr elements (and the guard after `v`'s).
        let s = self.answered(i, unsafe {
            (self.fmu.api.get_integer)(self.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr())
        });
        let v = v.into_values(|| format!("fmi2GetInteger with nvr = {}", vrs.len()), GETTER_RULE2);
        (s, v)
    }

    pub fn get_boolean(&self, vrs: &[u32]) -> (Status, Vec<i32>) {
        let i = self.record("fmi2GetBoolean", vec![("vr", Val::U32s(vrs.to_vec()))]);
        let mut v = Guarded::new(vrs.len(), 0);
        // SAFETY: arrays of nvr elements (and the guard after `v`'s).
        let s = self.answered(i, unsafe {
            (self.fmu.api.get_boolean)(self.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr())
        });
        let v = v.into_values(|| format!("fmi2GetBoolean with nvr = {}", vrs.len()), GETTER_RULE2);
        (s, v)
    }

    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        assert_eq!(vrs.len(), values.len());
        let i = self.record(
            "fmi2SetReal",
            vec![("vr", Val::U32s(vrs.to_vec())), ("values", Val::F64s(values.to_vec()))],
        );
        // SAFETY: arrays of nvr elements.
        self.answered(i, unsafe {
            (self.fmu.api.set_real)(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr())
        })
    }

    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Status {
        assert_eq!(vrs.len(), values.len());
        let i = self.record(
            "fmi2SetInteger",
            vec![
                ("vr", Val::U32s(vrs.to_vec())),
                ("values", Val::I64s(values.iter().map(|x| i64::from(*x)).collect())),
            ],
        );
        // SAFETY: arrays of nvr elements.
        self.answered(i, unsafe {
            (self.fmu.api.set_integer)(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr())
        })
    }

    pub fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Status {
        assert_eq!(vrs.len(), values.len());
        let v: Vec<fmi2Boolean> = values.iter().map(|b| *b as fmi2Boolean).collect();
        let i = self.record(
            "fmi2SetBoolean",
            vec![
                ("vr", Val::U32s(vrs.to_vec())),
                ("values", Val::I64s(v.iter().map(|x| i64::from(*x)).collect())),
            ],
        );
        // SAFETY: arrays of nvr elements.
        self.answered(i, unsafe {
            (self.fmu.api.set_boolean)(self.c, vrs.as_ptr(), vrs.len(), v.as_ptr())
        })
    }

    /// Every Real, Integer and Boolean variable as bit patterns, in description order: the
    /// observable state, for bit-identity comparisons. Panics unless the gets answer fmi2OK.
    pub fn observe(&self) -> Vec<u64> {
        let md = &self.fmu.md;
        let (s1, r) = self.get_real(&md.vrs_of_type(Type::Real));
        let (s2, i) = self.get_integer(&md.vrs_of_type(Type::Integer));
        let (s3, b) = self.get_boolean(&md.vrs_of_type(Type::Boolean));
        assert_eq!(
            [s1, s2, s3],
            [fmi2OK; 3],
            "{}: reading every variable failed: {}",
            self.fmu.id,
            self.log_text()
        );
        let mut out = crate::bits(&r);
        out.extend(i.iter().map(|x| *x as u32 as u64));
        out.extend(b.iter().map(|x| *x as u32 as u64));
        out
    }

    // ---- FMU state -------------------------------------------------------------------------

    pub fn get_state(&mut self) -> (Status, fmi2FMUstate) {
        let mut s: fmi2FMUstate = ptr::null_mut();
        let i = self.record("fmi2GetFMUstate", vec![]);
        // SAFETY: a live instance and a valid out pointer.
        let st = unsafe {
            crate::guard::fill_state2(&mut s, "fmi2GetFMUstate", |q| {
                self.answered(i, (self.fmu.api.get_fmu_state)(self.c, q))
            })
        };
        if let Some(v) = self.state_val(s, true) {
            self.calls.borrow_mut().add_arg(i, "state", v);
        }
        (st, s)
    }

    // The harness passes FMU states through to the FMU as an importer does; checking them
    // is the FMU's job, which is what the tests test.
    #[allow(clippy::not_unsafe_ptr_arg_deref)]
    pub fn set_state(&mut self, s: fmi2FMUstate) -> Status {
        let i = match self.state_val(s, false) {
            Some(v) => self.record("fmi2SetFMUstate", vec![("state", v)]),
            None => self.record_unreplayable("fmi2SetFMUstate"),
        };
        // SAFETY: a state of this FMU (or NULL, which the FMU must refuse).
        self.answered(i, unsafe { (self.fmu.api.set_fmu_state)(self.c, s) })
    }

    // The harness passes FMU states through to the FMU as an importer does; checking them
    // is the FMU's job, which is what the tests test.
    #[allow(clippy::not_unsafe_ptr_arg_deref)]
    pub fn free_state(&mut self, s: &mut fmi2FMUstate) -> Status {
        let i = match self.state_val(*s, false) {
            Some(v) => self.record("fmi2FreeFMUstate", vec![("state", v)]),
            None => self.record_unreplayable("fmi2FreeFMUstate"),
        };
        // SAFETY: a state of this FMU, freed once.
        self.answered(i, unsafe { (self.fmu.api.free_fmu_state)(self.c, s) })
    }

    // The harness passes FMU states through to the FMU as an importer does; checking them
    // is the FMU's job, which is what the tests test.
    #[allow(clippy::not_unsafe_ptr_arg_deref)]
    pub fn serialize(&mut self, s: fmi2FMUstate) -> Result<Vec<u8>, Status> {
        let mut size = 0usize;
        let state = self.state_val(s, false);
        let i = match &state {
            Some(v) => self.record("fmi2SerializedFMUstateSize", vec![("state", v.clone())]),
            None => self.record_unreplayable("fmi2SerializedFMUstateSize"),
        };
        // SAFETY: a state of this FMU and valid out pointers.
        let st = unsafe {
            crate::guard::fill_state_size2(&mut size, "fmi2SerializedFMUstateSize", |p| {
                self.answered(i, (self.fmu.api.serialized_fmu_state_size)(self.c, s, p))
            })
        };
        if st != fmi2OK {
            return Err(st);
        }
        let mut bytes = Guarded::new(size, 0u8);
        let i = match state {
            Some(v) => self.record(
                "fmi2SerializeFMUstate",
                vec![("state", v), ("size", Val::U64(size as u64))],
            ),
            None => self.record_unreplayable("fmi2SerializeFMUstate"),
        };
        // SAFETY: a buffer of `size` bytes (and the guard after it).
        let st = self.answered(i, unsafe {
            (self.fmu.api.serialize_fmu_state)(self.c, s, bytes.as_mut_ptr() as *mut fmi2Byte, size)
        });
        let bytes = bytes.into_values(
            || format!("fmi2SerializeFMUstate with size = {size} (fmi2SerializedFMUstateSize's answer)"),
            STATE_RULE2,
        );
        if st != fmi2OK {
            return Err(st);
        }
        Ok(bytes)
    }

    /// `fmi2DeSerializeFMUstate` into a new state (NULL on entry).
    pub fn deserialize(&mut self, bytes: &[u8]) -> (Status, fmi2FMUstate) {
        let mut s: fmi2FMUstate = ptr::null_mut();
        let i = self.record("fmi2DeSerializeFMUstate", vec![("bytes", Val::Bytes(bytes.to_vec()))]);
        // SAFETY: `bytes.len()` readable bytes, a valid out pointer.
        let st = unsafe {
            crate::guard::fill_state2(&mut s, "fmi2DeSerializeFMUstate", |q| {
                self.answered(
                    i,
                    (self.fmu.api.deserialize_fmu_state)(self.c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), q),
                )
            })
        };
        if let Some(v) = self.state_val(s, true) {
            self.calls.borrow_mut().add_arg(i, "state", v);
        }
        (st, s)
    }

    /// The complete FMU state, serialized; panics unless every call answers fmi2OK.
    pub fn snapshot(&mut self) -> Vec<u8> {
        let (st, mut s) = self.get_state();
        assert_eq!(st, fmi2OK, "{}: fmi2GetFMUstate: {}", self.fmu.id, self.log_text());
        let bytes = self.serialize(s);
        assert_eq!(self.free_state(&mut s), fmi2OK, "{}: fmi2FreeFMUstate", self.fmu.id);
        assert!(
            s.is_null(),
            "{}: fmi2FreeFMUstate must set *FMUstate = NULL",
            self.fmu.id
        );
        bytes.unwrap_or_else(|st| panic!("{}: serializing failed ({st}): {}", self.fmu.id, self.log_text()))
    }

    /// Restores a serialized state; panics unless every call answers fmi2OK.
    pub fn restore(&mut self, bytes: &[u8]) {
        let made = self.deserialize(bytes);
        let mut s = self.set_deserialized(made, None);
        assert_eq!(self.free_state(&mut s), fmi2OK);
    }

    /// Sets the FMU state that fmi2DeSerializeFMUstate `made` (on this instance, or on `maker`),
    /// and gives it back to be freed; panics unless both calls answer fmi2OK.
    fn set_deserialized(&mut self, (st, s): (Status, fmi2FMUstate), maker: Option<&Instance>) -> fmi2FMUstate {
        assert_eq!(
            st,
            fmi2OK,
            "{}: fmi2DeSerializeFMUstate: {}",
            self.fmu.id,
            maker.unwrap_or(self).log_text()
        );
        assert_eq!(
            self.set_state(s),
            fmi2OK,
            "{}: fmi2SetFMUstate: {}",
            self.fmu.id,
            self.log_text()
        );
        s
    }

    /// What the instance shows of itself, for before/after comparisons around a refused call:
    /// on this exporter's FMUs, and under `--strict` ([`crate::outcome::strict`]), the serialized
    /// FMU state (hidden state included; theirs is deterministic); otherwise what an importer
    /// observes, the value of every variable as the getters read it, with their statuses. FMI
    /// 2.0.5 promises nothing of the bytes of a serialized state (one that holds addresses differs
    /// on every serialization), so another exporter's FMU is judged by what it shows.
    pub fn fingerprint(&mut self) -> Option<Vec<u8>> {
        if self.fmu.can_snapshot() && (self.fmu.own_state_format() || crate::outcome::strict()) {
            Some(self.snapshot())
        } else {
            Some(self.observable())
        }
    }

    /// The value of every Real, Integer and Boolean variable and the getters' statuses, as bytes
    /// (the getters' log messages dropped). Nothing before initialization: FMI 2.0.5 allows no
    /// getter in Instantiated, and an FMU may take the call for an error and stop.
    fn observable(&mut self) -> Vec<u8> {
        let md = &self.fmu.md;
        let mut out = vec![];
        if !self.initialized {
            return out;
        }
        let reals = md.vrs_of_type(Type::Real);
        if !reals.is_empty() {
            let (s, v) = self.get_real(&reals);
            out.push(s as u8);
            out.extend(v.iter().flat_map(|x| x.to_bits().to_le_bytes()));
        }
        for ty in [Type::Integer, Type::Boolean] {
            let vrs = md.vrs_of_type(ty);
            if vrs.is_empty() {
                continue;
            }
            let (s, v) = if ty == Type::Integer {
                self.get_integer(&vrs)
            } else {
                self.get_boolean(&vrs)
            };
            out.push(s as u8);
            out.extend(v.iter().flat_map(|x| x.to_le_bytes()));
        }
        let _ = self.sink.take();
        out
    }

    /// Warns unless the instance shows what it showed `before` ([`Instance::fingerprint`]):
    /// a refused call that changed the instance. A warning, not a failure: FMI 2.0.5 §2.1.3
    /// (fmi2Error) says "the simulation cannot be continued with this FMU instance" and leaves
    /// the instance undefined until fmi2SetFMUstate, fmi2Reset or fmi2FreeInstance; a refusal
    /// that changes nothing is robustness beyond the standard (an importer can go on after
    /// catching its own mistake).
    /// Only after a refusal (`status` fmi2Error): a call accepted changes what it changes.
    pub fn warn_if_changed(&mut self, before: &Option<Vec<u8>>, status: Status, what: impl std::fmt::Display) {
        if status == fmi2Error && before.is_some() && &self.fingerprint() != before {
            crate::outcome::warn(format!(
                "{}: {what}: refused, but the instance changed ({})",
                self.fmu.id, REFUSED_CHANGED_WHY
            ));
        }
    }

    /// The state-machine state, read from a serialized FMU state (only of this exporter's FMUs:
    /// [`Fmu::own_state_format`]).
    pub fn machine_state(&mut self) -> State {
        assert!(
            self.fmu.own_state_format(),
            "{}: the state machine can be read only from this exporter's serialized states",
            self.fmu.id
        );
        let bytes = self.snapshot();
        state::machine_state(&bytes).unwrap_or_else(|e| panic!("{}: {e}", self.fmu.id))
    }

    /// Puts the instance into `target` by restoring a forged copy of its own state (see
    /// [`crate::state`]). The instance must be in a state where fmi2SetFMUstate is allowed.
    pub fn force_state(&mut self, target: State) {
        assert!(
            self.fmu.own_state_format(),
            "{}: only this exporter's FMUs can be forced into a state",
            self.fmu.id
        );
        let bytes = state::forge(&self.snapshot(), target);
        self.restore_forged(Instance::new(self.fmu), &bytes);
    }

    /// Restores `bytes`, a forged copy of this instance's own serialized state, with
    /// fmi2SetFMUstate. `helper`, an instance of the same kind, makes and frees the FMU state,
    /// so that this works for Fatal too.
    pub(crate) fn restore_forged(&mut self, mut helper: Instance, bytes: &[u8]) {
        let made = helper.deserialize(bytes);
        let mut s = self.set_deserialized(made, Some(&helper));
        assert_eq!(helper.free_state(&mut s), fmi2OK);
    }

    // ---- status ----------------------------------------------------------------------------

    pub fn last_successful_time(&self) -> (Status, f64) {
        let mut t = f64::NAN;
        let i = self.record(
            "fmi2GetRealStatus",
            vec![("kind", Val::Text("fmi2LastSuccessfulTime".into()))],
        );
        // SAFETY: a valid out pointer.
        let s = unsafe {
            crate::guard::fill_status2(&mut t, "fmi2GetRealStatus", |p| {
                self.answered(i, (self.fmu.api.get_real_status)(self.c, fmi2LastSuccessfulTime, p))
            })
        };
        (s, t)
    }

    pub fn terminated(&self) -> (Status, fmi2Boolean) {
        let mut b = -1;
        let i = self.record(
            "fmi2GetBooleanStatus",
            vec![("kind", Val::Text("fmi2Terminated".into()))],
        );
        // SAFETY: a valid out pointer.
        let s = unsafe {
            crate::guard::fill_status2(&mut b, "fmi2GetBooleanStatus", |p| {
                self.answered(i, (self.fmu.api.get_boolean_status)(self.c, fmi2Terminated, p))
            })
        };
        (s, b)
    }

    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Status {
        let owned: Vec<CString> = categories.iter().map(|c| CString::new(*c).unwrap()).collect();
        let ptrs: Vec<fmi2String> = owned.iter().map(|c| c.as_ptr()).collect();
        let p = if ptrs.is_empty() { ptr::null() } else { ptrs.as_ptr() };
        let i = self.record(
            "fmi2SetDebugLogging",
            vec![
                ("loggingOn", Val::Bool(on)),
                (
                    "categories",
                    Val::Texts(categories.iter().map(|c| c.to_string()).collect()),
                ),
            ],
        );
        // SAFETY: nCategories valid strings (or NULL with 0).
        self.answered(i, unsafe {
            (self.fmu.api.set_debug_logging)(self.c, on as fmi2Boolean, ptrs.len(), p)
        })
    }
}

impl Drop for Instance<'_> {
    fn drop(&mut self) {
        crumb("fmi2FreeInstance", String::new);
        crate::calllog::retire(std::mem::take(self.calls.get_mut()));
        // SAFETY: freed once; the callbacks outlive the call.
        unsafe { (self.fmu.api.free_instance)(self.c) };
        if !std::thread::panicking() {
            self.log();
        }
    }
}

/// Values a generic test sets to make every FMU do something non-trivial: each Real input and
/// each non-parameter Real with initial="exact" (an initial state) moved off its start value,
/// within min/max.
pub fn excitation(fmu: &Fmu) -> Vec<(u32, f64)> {
    fmu.md
        .of_type(Type::Real)
        .filter(|v| {
            v.causality == Causality::Input
                || (v.causality != Causality::Parameter
                    && crate::standard::initial(v.causality, v.variability, v.declared_initial) == Some(Initial::Exact))
        })
        .filter(|v| v.variability != Variability::Constant)
        .map(|v| (v.vr, excite(v)))
        .collect()
}

/// Another value than the start value, inside [min, max]; variables with the same start value
/// get different ones (spread by value reference): a controller's reference and measurement
/// excited alike leave its error at 0, and nothing its gains do can be seen.
pub fn excite(v: &crate::Variable) -> f64 {
    let start = v.start_real().unwrap_or(0.0);
    let spread = f64::from(v.vr % 8);
    let x = if start == 0.0 {
        0.1 * (1.0 + 0.5 * spread)
    } else {
        start * (1.5 + 0.0625 * spread)
    };
    let x = v.max.map_or(x, |m| x.min(m));
    let x = v.min.map_or(x, |m| x.max(m));
    if x == start {
        // Clamped back onto the start value: go the other way.
        v.min.map_or(start - 0.1, |m| (m + start) / 2.0)
    } else {
        x
    }
}

/// A fresh instance, excited, initialized at t = 0, run for `steps` steps of `h`: the
/// observations after initialization and after every step.
pub fn run(fmu: &Fmu, steps: usize, h: f64) -> Vec<Vec<u64>> {
    let mut inst = Instance::new(fmu);
    run_on(&mut inst, steps, h)
}

/// As [`run`], on an existing instance in state Instantiated.
pub fn run_on(inst: &mut Instance, steps: usize, h: f64) -> Vec<Vec<u64>> {
    let ex = excitation(inst.fmu);
    let (vrs, vals): (Vec<u32>, Vec<f64>) = ex.into_iter().unzip();
    assert_eq!(
        inst.set_real(&vrs, &vals),
        fmi2OK,
        "{}: {}",
        inst.fmu.id,
        inst.log_text()
    );
    inst.initialize();
    let mut out = vec![inst.observe()];
    for _ in 0..steps {
        let s = inst.step(h);
        assert_eq!(
            s,
            fmi2OK,
            "{}: fmi2DoStep at t = {}: {}",
            inst.fmu.id,
            inst.time,
            inst.log_text()
        );
        out.push(inst.observe());
    }
    out
}

/// A communication step size for a short run: the default experiment's, else 1 ms.
pub fn step_size(fmu: &Fmu) -> f64 {
    fmu.md.default_experiment.step_size().unwrap_or(1e-3)
}
