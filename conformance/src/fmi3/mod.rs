//! The FMI 3.0 side of the suite: an FMI 3.0 FMU is loaded ([`Fmu3`], a [`crate::Loaded`] like
//! the FMI 2.0 [`crate::Fmu`]) and driven through its own C API ([`api`], declared from the
//! standard's headers) by the FMI 3.0 checks ([`checks`], registered with the FMI 2.0 ones in
//! [`crate::checks::all_checks`]). The runner picks them by the `fmiVersion` of the model
//! description, so one `fmu-check X.fmu` (and `cargo fmu check X.fmu`) checks 2.0 and 3.0 files
//! alike.

pub mod api;
pub mod checks;
pub mod probes;
pub mod standard;
pub mod types;

use crate::archive::{self, PrivateDir};
use crate::calllog::{Log, Val};
use crate::guard::{GETTER_RULE3, Guarded, STATE_RULE3};
use md_reader::fmi3::Dimension;
pub use md_reader::fmi3::{ModelDescription as Description, Type, Variable};
use md_reader::{Causality, Variability};
pub use standard::State;
use std::cell::{Cell, RefCell};
use std::collections::BTreeMap;
use std::ffi::{CStr, CString, c_char};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use types::*;

/// The FMI 3.0 platform tuple of this platform (FMI 3.0 section 2.5.1.1).
#[cfg(not(windows))]
pub const PLATFORM: &str = "x86_64-linux";
/// The FMI 3.0 platform tuple of this platform (FMI 3.0 section 2.5.1.1).
#[cfg(windows)]
pub const PLATFORM: &str = "x86_64-windows";

/// The value of every UInt64 structural parameter and constant a `<Dimension valueReference>`
/// may name, by value reference: what sizes the arrays (FMI 3.0, 2.4.7.2).
pub type Sizes = BTreeMap<u32, u64>;

/// One FMI 3.0 FMU, unpacked into a private folder and loaded.
pub struct Fmu3 {
    pub id: String,
    pub archive: PathBuf,
    pub dir: PathBuf,
    /// `binaries/x86_64-linux/<modelIdentifier>.so` inside `dir`.
    pub so: PathBuf,
    pub scratch: PathBuf,
    pub md: Description,
    pub api: api::Api,
    /// Whether the serialized states are this exporter's format ([`Fmu3::state_format`]).
    own: std::sync::OnceLock<Result<(), String>>,
    /// [`Fmu3::start_sizes`], read once.
    sizes: std::sync::OnceLock<Sizes>,
    _dirs: (PrivateDir, PrivateDir),
}

/// What the report's head says about a 3.0 file (from the archive alone).
fn describe(path: &Path) -> Result<Vec<String>, String> {
    let mut a = archive::open(path)?;
    let xml = archive::read_model_description(&mut a)?;
    let md = Description::parse(&xml).map_err(|e| format!("{}: {e}", path.display()))?;
    let so = format!(
        "binaries/{PLATFORM}/{}.{}",
        md.model_identifier(),
        crate::LIBRARY_EXTENSION
    );
    let tool = crate::binary_and_tool(a.has_entry(&so), path, &so, &md.generation_tool)?;
    let interfaces: Vec<&str> = [
        ("CoSimulation", md.cs.is_some()),
        ("ModelExchange", md.me.is_some()),
        ("ScheduledExecution", md.se),
    ]
    .iter()
    .filter(|x| x.1)
    .map(|x| x.0)
    .collect();
    Ok(vec![format!(
        "model {} (FMI {}, instantiationToken {}, {}), {tool}: the FMI 3.0 checks",
        md.model_identifier(),
        md.fmi_version,
        md.token,
        interfaces.join(" + ")
    )])
}

impl Fmu3 {
    pub fn load(path: &Path, parent: &Path) -> Result<Fmu3, String> {
        let mut zip = archive::open(path)?;
        let xml = archive::read_model_description(&mut zip)?;
        let md = Description::parse(&xml).map_err(|e| format!("{}: {e}", path.display()))?;
        if md_reader::Version::of(&md.fmi_version) != Some(md_reader::Version::Fmi3) {
            return Err(format!(
                "{}: fmiVersion \"{}\" is not 3.0",
                path.display(),
                md.fmi_version
            ));
        }
        let id = md.model_identifier().to_string();
        if let (Some(cs), Some(me)) = (&md.cs, &md.me)
            && cs.model_identifier != me.model_identifier
        {
            return Err(format!(
                "{}: CoSimulation and ModelExchange have different binaries ({} and {}): the suite checks one",
                path.display(),
                cs.model_identifier,
                me.model_identifier
            ));
        }
        let u = crate::Unpacked::new(path, parent, &mut zip, &id, PLATFORM)?;
        let api = api::Api::load(&u.so)?;
        Ok(Fmu3 {
            id,
            archive: path.to_path_buf(),
            dir: u.dir,
            so: u.so,
            scratch: u.scratch,
            md,
            api,
            own: std::sync::OnceLock::new(),
            sizes: std::sync::OnceLock::new(),
            _dirs: u.dirs,
        })
    }

    /// Ok when the FMU's serialized states are this exporter's format (`crate::state`: magic,
    /// version, the instantiation token, CRC-32), else why not: treated as another exporter's
    /// FMU ([`crate::set_as_foreign`]), no serializable state, or other bytes. Checks that need
    /// the format (damage only a checksum finds) are strict only where it is Ok.
    pub fn state_format(&self) -> &Result<(), String> {
        self.own.get_or_init(|| {
            if crate::as_foreign() {
                return Err("treated as another exporter's FMU on request".into());
            }
            let me = self.md.cs.is_none();
            if !self.can_snapshot(me) {
                return Err("the FMU does not declare canGetAndSetFMUState and canSerializeFMUState".into());
            }
            let inst = Inst::try_new(self, me, "probe")?;
            let bytes = inst.try_snapshot()?;
            drop(inst);
            let l = crate::state::parse(&bytes)?;
            if &bytes[l.guid_at..l.guid_at + l.guid_len] != self.md.token.as_bytes() {
                return Err("the serialized state holds another instantiation token".into());
            }
            Ok(())
        })
    }

    /// Whether the FMU has clocks (FMI 3.0: its co-simulation then needs eventModeUsed, and its
    /// clocked variables are read and set at their clocks' ticks only).
    pub fn has_clocks(&self) -> bool {
        self.md.variables.iter().any(|v| v.ty == Type::Clock)
    }

    pub fn own_state_format(&self) -> bool {
        self.state_format().is_ok()
    }

    /// The native path of the unpacked `resources/` folder, with a trailing separator (FMI 3.0
    /// section 2.3.1: resourcePath).
    pub fn resource_path(&self) -> String {
        format!("{}/resources/", self.dir.display())
    }

    pub fn can_snapshot(&self, me: bool) -> bool {
        let i = if me { self.md.me.as_ref() } else { self.md.cs.as_ref() };
        i.is_some_and(|i| i.can_get_and_set_fmu_state && i.can_serialize_fmu_state)
    }

    /// Every scalar UInt64 structural parameter and constant with its start value: the sizes of
    /// the arrays until an importer sets a structural parameter in Configuration Mode, which
    /// only the structural-parameter check does (every other check counts elements with these).
    pub fn start_sizes(&self) -> &Sizes {
        self.sizes.get_or_init(|| {
            self.md
                .variables
                .iter()
                .filter(|v| {
                    v.ty == Type::UInt64
                        && !v.array
                        && (v.causality == Causality::StructuralParameter || v.variability == Variability::Constant)
                })
                .filter_map(|v| Some((v.vr, v.start.as_deref()?.trim().parse().ok()?)))
                .collect()
        })
    }

    /// The lengths of a variable's dimensions under `sizes`, outermost first (none for a scalar).
    pub fn dims_at(&self, v: &Variable, sizes: &Sizes) -> Vec<u64> {
        v.dimensions
            .iter()
            .map(|d| match d {
                Dimension::Fixed(k) => *k,
                Dimension::Parameter(vr) => *sizes.get(vr).unwrap_or_else(|| {
                    panic!(
                        "{}: '{}' has <Dimension valueReference=\"{vr}\">, which names no UInt64 structural parameter or constant with a start value",
                        self.id, v.name
                    )
                }),
            })
            .collect()
    }

    /// The number of values of a variable under `sizes`: the product of its dimensions' lengths
    /// (row-major, the count nValues of the getters and setters gives it); 1 for a scalar.
    pub fn count_at(&self, v: &Variable, sizes: &Sizes) -> usize {
        self.dims_at(v, sizes).iter().product::<u64>() as usize
    }

    /// [`Fmu3::count_at`] with the structural parameters at their starts ([`Fmu3::start_sizes`]).
    pub fn element_count(&self, v: &Variable) -> usize {
        self.count_at(v, self.start_sizes())
    }

    /// The element count of the variable a `<ModelStructure>` entry names (1 where it names none).
    fn entry_count(&self, vr: u32, sizes: &Sizes) -> usize {
        self.md.by_vr(vr).map_or(1, |v| self.count_at(v, sizes))
    }

    /// The number of continuous states under `sizes`: every element of each
    /// `<ContinuousStateDerivative>`'s variable (a state array counts each element).
    pub fn nx_at(&self, sizes: &Sizes) -> usize {
        self.md.derivatives.iter().map(|u| self.entry_count(u.vr, sizes)).sum()
    }

    /// The number of continuous states with the structural parameters at their starts: what
    /// fmi3GetNumberOfContinuousStates must say, and nContinuousStates of the vector functions.
    pub fn n_states_declared(&self) -> usize {
        self.nx_at(self.start_sizes())
    }

    /// The number of event indicators with the structural parameters at their starts: every
    /// element of each `<EventIndicator>`'s variable.
    pub fn n_event_indicators_declared(&self) -> usize {
        let sizes = self.start_sizes();
        self.md
            .event_indicators
            .iter()
            .map(|u| self.entry_count(u.vr, sizes))
            .sum()
    }

    /// The continuous states (state, derivative) in the order of `<ContinuousStateDerivative>`:
    /// the order of the state vector, each expanded to its elements there.
    pub fn states(&self) -> Result<Vec<(&Variable, &Variable)>, String> {
        let md = &self.md;
        Ok(md
            .continuous_states()?
            .iter()
            .map(|(x, d)| (md.by_vr(*x).unwrap(), md.by_vr(*d).unwrap()))
            .collect())
    }

    /// Where each continuous state starts in the state vector (start sizes), with its element
    /// count: (state, derivative, offset, count), in the order of the state vector.
    pub fn state_slots(&self) -> Result<Vec<(&Variable, &Variable, usize, usize)>, String> {
        let mut at = 0;
        Ok(self
            .states()?
            .into_iter()
            .map(|(x, d)| {
                let n = self.element_count(x);
                at += n;
                (x, d, at - n, n)
            })
            .collect())
    }

    /// The default experiment's step, else 1e-3 s.
    pub fn step_size(&self) -> f64 {
        self.md
            .default_experiment
            .step_size()
            .filter(|h| *h > 0.0)
            .unwrap_or(1e-3)
    }
}

/// One logged message.
#[derive(Debug, Clone, PartialEq)]
pub struct LogEntry {
    pub status: fmi3Status,
    pub category: String,
    pub message: String,
}

/// What an instance's environment points to.
#[derive(Debug, Default)]
pub struct LogSink {
    pub entries: Mutex<Vec<LogEntry>>,
    /// The intermediate-update callback's calls: (intermediateUpdateTime,
    /// [intermediateVariableSetRequested, intermediateVariableGetAllowed,
    /// intermediateStepFinished, canReturnEarly]).
    pub intermediate: Mutex<Vec<(f64, [bool; 4])>>,
    /// Asks for an early return at `.1` once told a time at or after `.0`.
    pub early_request: Mutex<Option<(f64, f64)>>,
}

impl LogSink {
    pub fn env(&self) -> fmi3InstanceEnvironment {
        self as *const LogSink as fmi3InstanceEnvironment
    }
    pub fn take(&self) -> Vec<LogEntry> {
        std::mem::take(&mut *self.entries.lock().unwrap_or_else(|e| e.into_inner()))
    }
}

/// The importer's fmi3IntermediateUpdateCallback: records the call into the [`LogSink`] the
/// environment points to, and asks for the early return it holds.
///
/// # Safety
///
/// `env` is NULL or points to a live [`LogSink`]; the two outputs are writable (the FMU's).
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn intermediate_update(
    env: fmi3InstanceEnvironment,
    time: fmi3Float64,
    set_requested: fmi3Boolean,
    get_allowed: fmi3Boolean,
    finished: fmi3Boolean,
    can_return_early: fmi3Boolean,
    early_return_requested: *mut fmi3Boolean,
    early_return_time: *mut fmi3Float64,
) {
    if env.is_null() {
        return;
    }
    // SAFETY: the environment given at instantiation, a live sink.
    let sink = unsafe { &*(env as *const LogSink) };
    let lock = |m: &Mutex<Vec<(f64, [bool; 4])>>| {
        m.lock()
            .unwrap_or_else(|e| e.into_inner())
            .push((time, [set_requested, get_allowed, finished, can_return_early]))
    };
    lock(&sink.intermediate);
    let request = *sink.early_request.lock().unwrap_or_else(|e| e.into_inner());
    // FMI 3.0.2 §4.2.2 (fmi3IntermediateUpdateCallback): "If and only if canReturnEarly ==
    // fmi3True, the co-simulation algorithm may request the FMU to return early".
    if let Some((after, at)) = request
        && can_return_early
        && time >= after
        && !early_return_requested.is_null()
        && !early_return_time.is_null()
    {
        // SAFETY: checked not NULL; the FMU's outputs.
        unsafe {
            *early_return_requested = true;
            *early_return_time = at;
        }
    }
}

/// The importer's fmi3LogMessageCallback: records into the [`LogSink`] the environment points to.
///
/// # Safety
///
/// `env` is NULL or points to a live [`LogSink`]; `category` and `message` are NULL or
/// NUL-terminated strings (what an FMU passes).
pub unsafe extern "C" fn log_message(
    env: fmi3InstanceEnvironment,
    status: fmi3Status,
    category: fmi3String,
    message: fmi3String,
) {
    let text = |p: *const c_char| {
        if p.is_null() {
            "<NULL>".to_string()
        } else {
            // SAFETY: the FMU passes NUL-terminated strings (NULL handled).
            unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    let entry = LogEntry {
        status,
        category: text(category),
        message: text(message),
    };
    if env.is_null() {
        eprintln!("log message with a NULL instanceEnvironment: {entry:?}");
        return;
    }
    // SAFETY: every instance the suite makes passes a live &LogSink as its environment.
    let sink = unsafe { &*(env as *const LogSink) };
    sink.entries.lock().unwrap_or_else(|e| e.into_inner()).push(entry);
}

/// One instance, with its own log sink; freed when dropped.
pub struct Inst<'a> {
    pub fmu: &'a Fmu3,
    pub c: fmi3Instance,
    pub me: bool,
    pub sink: Box<LogSink>,
    pub time: f64,
    /// A co-simulation instance of an FMU with clocks, made with eventModeUsed because the
    /// standard requires it, for a check that does not itself handle Event Mode: the suite passes
    /// Event Mode for it (after initialization and where a step needs it) with
    /// fmi3UpdateDiscreteStates and fmi3EnterStepMode, activating no clock.
    pub auto_events: bool,
    /// The time at which a co-simulation step answered terminateSimulation (FMI 3.0.2 §4.2.1,
    /// fmi3DoStep: the FMU "requests to stop the simulation"): [`Inst::step`] makes no step after
    /// it, as an importer stops there.
    pub ended_at: Option<f64>,
    /// Every call made on the instance ([`crate::calllog`]): a failing check's reproducer.
    pub calls: RefCell<Log>,
    /// The arguments of the call [`Inst::call`] makes next, as its wrapper gives them
    /// ([`Inst::args`]); a call made without them is recorded as not replayable, unless it
    /// takes none ([`crate::replay::fmi3::fmi3_call`]).
    pending: RefCell<Option<Vec<(&'static str, Val)>>>,
    /// The index of the last call in [`Inst::calls`].
    last_call: Cell<usize>,
}

impl<'a> Inst<'a> {
    /// A co-simulation instance (no event mode, no early return), panicking if it is NULL.
    pub fn cs(fmu: &'a Fmu3) -> Inst<'a> {
        Self::try_new(fmu, false, "cs").unwrap_or_else(|e| panic!("{}: {e}", fmu.id))
    }
    /// A model-exchange instance, panicking if it is NULL.
    pub fn me(fmu: &'a Fmu3) -> Inst<'a> {
        Self::try_new(fmu, true, "me").unwrap_or_else(|e| panic!("{}: {e}", fmu.id))
    }

    /// A co-simulation instance with event mode and early return, panicking if it is NULL.
    pub fn cs_event_mode(fmu: &'a Fmu3) -> Inst<'a> {
        Self::try_new_with(fmu, false, "cs-events", true).unwrap_or_else(|e| panic!("{}: {e}", fmu.id))
    }

    pub fn try_new(fmu: &'a Fmu3, me: bool, name: &str) -> Result<Inst<'a>, String> {
        Self::try_new_with(fmu, me, name, false)
    }

    /// A co-simulation instance with the intermediate-update callback (the calls and the early
    /// return requests in its [`LogSink`]), earlyReturnAllowed as given, no event mode.
    pub fn cs_intermediate_update(fmu: &'a Fmu3, early_return_allowed: bool) -> Inst<'a> {
        Self::try_new_full(fmu, false, "cs-intermediate", (false, early_return_allowed), true)
            .unwrap_or_else(|e| panic!("{}: {e}", fmu.id))
    }

    /// `event_mode`: co-simulation with eventModeUsed and earlyReturnAllowed.
    pub fn try_new_with(fmu: &'a Fmu3, me: bool, name: &str, event_mode: bool) -> Result<Inst<'a>, String> {
        Self::try_new_full(fmu, me, name, (event_mode, event_mode), false)
    }

    /// (eventModeUsed, earlyReturnAllowed) as given; `intermediate`: with the
    /// intermediate-update callback.
    pub(crate) fn try_new_full(
        fmu: &'a Fmu3,
        me: bool,
        name: &str,
        (event_mode, early_return): (bool, bool),
        intermediate: bool,
    ) -> Result<Inst<'a>, String> {
        let sink = Box::<LogSink>::default();
        // FMI 3.0, 4.2.1: "For FMUs that have clocks, eventModeUsed == fmi3True is required."
        let auto_events = !me && !event_mode && fmu.has_clocks();
        let event_mode = event_mode || auto_events;
        let name = CString::new(name).unwrap();
        let token = CString::new(fmu.md.token.as_str()).map_err(|e| e.to_string())?;
        let res = CString::new(fmu.resource_path()).map_err(|e| e.to_string())?;
        crate::outcome::breadcrumb(if me {
            "fmi3InstantiateModelExchange"
        } else {
            "fmi3InstantiateCoSimulation"
        });
        // SAFETY: valid strings and callbacks; the sink outlives the instance (dropped after it).
        let c = unsafe {
            if me {
                (fmu.api.instantiate_model_exchange)(
                    name.as_ptr(),
                    token.as_ptr(),
                    res.as_ptr(),
                    false,
                    false,
                    sink.env(),
                    Some(log_message),
                )
            } else {
                (fmu.api.instantiate_co_simulation)(
                    name.as_ptr(),
                    token.as_ptr(),
                    res.as_ptr(),
                    false,
                    false,
                    event_mode,
                    early_return,
                    std::ptr::null(),
                    0,
                    sink.env(),
                    Some(log_message),
                    if intermediate { Some(intermediate_update) } else { None },
                )
            }
        };
        if c.is_null() {
            return Err(format!(
                "fmi3Instantiate{} returned NULL: {:?}",
                if me { "ModelExchange" } else { "CoSimulation" },
                sink.take()
            ));
        }
        let calls = RefCell::new(Log::new(
            if me {
                "fmi3InstantiateModelExchange"
            } else {
                "fmi3InstantiateCoSimulation"
            },
            if me {
                vec![("instanceName", Val::Text(name.to_string_lossy().into_owned()))]
            } else {
                vec![
                    ("instanceName", Val::Text(name.to_string_lossy().into_owned())),
                    ("eventModeUsed", Val::Bool(event_mode)),
                    ("earlyReturnAllowed", Val::Bool(early_return)),
                    ("intermediateUpdate", Val::Bool(intermediate)),
                ]
            },
        ));
        Ok(Inst {
            fmu,
            c,
            me,
            sink,
            time: 0.0,
            auto_events,
            ended_at: None,
            calls,
            pending: RefCell::new(None),
            last_call: Cell::new(usize::MAX),
        })
    }

    /// The arguments of the next [`Inst::call`], for the call log ([`crate::calllog`]); `self`.
    pub fn args(&self, args: Vec<(&'static str, Val)>) -> &Self {
        *self.pending.borrow_mut() = Some(args);
        self
    }

    /// Adds an output of the last call (an FMU state it made) to its record.
    fn output(&self, key: &'static str, v: Val) {
        self.calls.borrow_mut().add_arg(self.last_call.get(), key, v);
    }

    /// The number of the FMU state `st` in the log (`made`: the call made it).
    fn state_val(&self, st: fmi3FMUState, made: bool) -> Option<Val> {
        if st.is_null() {
            return Some(Val::Null);
        }
        self.calls.borrow_mut().state(st as usize, made).map(Val::State)
    }

    /// [`Inst::args`] for a call on the FMU state `st` (`state=N` first); a state this instance's
    /// calls did not make (another instance's) leaves the call unreplayable.
    fn state_args(&self, st: fmi3FMUState, mut rest: Vec<(&'static str, Val)>) -> &Self {
        if let Some(v) = self.state_val(st, false) {
            rest.insert(0, ("state", v));
            self.args(rest);
        }
        self
    }

    /// An instance fmi3InstantiateScheduledExecution made (with `sink` as its environment). Its
    /// calls are recorded, but it leaves no reproducer: the replay does not instantiate
    /// Scheduled Execution (whose clocks the FMU ticks through callbacks).
    pub(crate) fn scheduled_execution(fmu: &'a Fmu3, c: fmi3Instance, sink: Box<LogSink>) -> Inst<'a> {
        Inst {
            fmu,
            c,
            me: false,
            sink,
            time: 0.0,
            auto_events: false,
            ended_at: None,
            calls: RefCell::new(Log::not_replayable("fmi3InstantiateScheduledExecution")),
            pending: RefCell::new(None),
            last_call: Cell::new(usize::MAX),
        }
    }

    /// No instance: every call passes NULL (the checks of a NULL instance). Nothing is logged
    /// then (there is no logger), and nothing is freed.
    pub fn null(fmu: &'a Fmu3, me: bool) -> Inst<'a> {
        Inst {
            fmu,
            c: std::ptr::null_mut(),
            me,
            sink: Box::default(),
            time: 0.0,
            auto_events: false,
            ended_at: None,
            calls: RefCell::default(),
            pending: RefCell::new(None),
            last_call: Cell::new(usize::MAX),
        }
    }

    pub fn api(&self) -> &'a api::Api {
        &self.fmu.api
    }

    pub fn log_text(&self) -> String {
        let e = self.sink.entries.lock().unwrap_or_else(|e| e.into_inner());
        e.iter()
            .map(|l| format!("[{} {}] {}", status_name(l.status), l.category, l.message))
            .collect::<Vec<_>>()
            .join("; ")
    }

    /// fmi3GetContinuousStateDerivatives of `nx` values, which must succeed (the message says
    /// where it did not).
    pub fn derivatives_ok(&self, nx: usize) -> Vec<f64> {
        let f = self.api().get_continuous_state_derivatives;
        let (s, dx) = self.vector("fmi3GetContinuousStateDerivatives", f, nx);
        assert_eq!(
            s,
            fmi3OK,
            "{}: fmi3GetContinuousStateDerivatives (nx = {nx}): {}",
            self.fmu.id,
            self.log_text()
        );
        dx
    }

    /// [`Inst::call`] of a function that takes only the instance (fmi3Terminate,
    /// fmi3EnterEventMode, fmi3EnterContinuousTimeMode, ...).
    pub fn unary(&self, what: &str, f: api::Unary) -> fmi3Status {
        // SAFETY: `f` is a function of the library `self.fmu` keeps loaded, with the standard's
        // signature; its one argument is this instance's handle, live until `self` is dropped
        // (or NULL for an `Inst::null`, which the FMU must refuse without dereferencing it).
        self.call(what, |c| unsafe { f(c) })
    }

    /// fmi3GetDirectionalDerivative, or (`adjoint`) fmi3GetAdjointDerivative, of `unknowns` by
    /// `knowns` with `seed`, into `sensitivity` (nSeed and nSensitivity: the slices' lengths).
    pub fn derivative(
        &self,
        adjoint: bool,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        sensitivity: &mut [f64],
    ) -> fmi3Status {
        let api = self.api();
        let (what, f) = if adjoint {
            ("fmi3GetAdjointDerivative", api.get_adjoint_derivative)
        } else {
            ("fmi3GetDirectionalDerivative", api.get_directional_derivative)
        };
        let n = sensitivity.len();
        let mut out = Guarded::new(n, 0.0);
        out_of(sensitivity, &mut out);
        let p = out.as_mut_ptr();
        self.args(vec![
            ("unknowns", Val::U32s(unknowns.to_vec())),
            ("knowns", Val::U32s(knowns.to_vec())),
            ("seed", Val::F64s(seed.to_vec())),
            ("nSensitivity", Val::U64(n as u64)),
        ]);
        // SAFETY: this instance's live handle (or NULL, which the FMU must refuse); each array is
        // a live slice passed with its own length (`p`: `n` values and the guard after them).
        let s = self.call(what, |c| unsafe {
            f(
                c,
                unknowns.as_ptr(),
                unknowns.len(),
                knowns.as_ptr(),
                knowns.len(),
                seed.as_ptr(),
                seed.len(),
                p,
                n,
            )
        });
        sensitivity.copy_from_slice(&out.into_values(|| format!("{what} with nSensitivity = {n}"), GETTER_RULE3));
        s
    }

    /// Runs a call that returns a status; when it is not fmi3OK and no message was logged with
    /// that status, a warning (`--strict`: a failure; this exporter's FMUs always log one).
    pub fn call(&self, what: &str, f: impl FnOnce(fmi3Instance) -> fmi3Status) -> fmi3Status {
        let args = self.pending.borrow_mut().take();
        if self.c.is_null() {
            // Not logged (no instance): the breadcrumb the call log writes for the others.
            crate::outcome::breadcrumb(what);
        } else {
            let i = match crate::replay::fmi3::fmi3_call(what) {
                Some((name, no_arguments)) => {
                    let replayable = args.is_some() || no_arguments;
                    self.calls.borrow_mut().call(name, args.unwrap_or_default(), replayable)
                }
                None => self.calls.borrow_mut().call(what.to_string(), vec![], false),
            };
            self.last_call.set(i);
        }
        let before = self.sink.entries.lock().unwrap_or_else(|e| e.into_inner()).len();
        let s = f(self.c);
        if !self.c.is_null() {
            self.calls.borrow_mut().answered(self.last_call.get(), s);
        }
        {
            // logMessage's category: one of <LogCategories>, NULL if there are none.
            let entries = self.sink.entries.lock().unwrap_or_else(|e| e.into_inner());
            let cats = &self.fmu.md.log_categories;
            for e in &entries[before.min(entries.len())..] {
                let ok = if cats.is_empty() {
                    e.category == "<NULL>"
                } else {
                    cats.contains(&e.category)
                };
                assert!(
                    ok,
                    "{}: {what} logged with the category '{}', which <LogCategories> does not declare ({cats:?})",
                    self.fmu.id, e.category
                );
            }
        }
        if s != fmi3OK && !self.c.is_null() {
            // Warned, not failed: FMI 3.0.2 §2.2.4 (fmi3Status) says of fmi3Warning, fmi3Discard
            // and fmi3Error "Function logMessage should be called by the FMU with further
            // information before returning this status, respecting the current logging settings":
            // a recommendation, and one that logging settings may switch off.
            let entries = self.sink.entries.lock().unwrap_or_else(|e| e.into_inner());
            let new = &entries[before.min(entries.len())..];
            if !new.iter().any(|e| e.status == s) {
                crate::outcome::warn(format!(
                    "{}: {what} returned {} without logging a message with that status (logged: {new:?}); FMI 3.0.2 \
                     §2.2.4: logMessage \"should be called by the FMU with further information before returning this \
                     status\": an importer's user sees no reason",
                    self.fmu.id,
                    status_name(s)
                ));
            }
        }
        s
    }

    pub fn enter_init(&mut self, start: f64) -> fmi3Status {
        let s = self
            .args(vec![("startTime", Val::F64(start))])
            // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an
            // FMU state.
            .call("fmi3EnterInitializationMode", |c| unsafe {
                (self.fmu.api.enter_initialization_mode)(c, false, 0.0, start, false, 0.0)
            });
        if s == fmi3OK {
            self.time = start;
        }
        s
    }
    pub fn exit_init(&self) -> fmi3Status {
        let s = self.unary("fmi3ExitInitializationMode", self.fmu.api.exit_initialization_mode);
        if s == fmi3OK && self.auto_events {
            return self.pass_event_mode();
        }
        s
    }

    /// [`Inst::auto_events`]: from Event Mode to Step Mode (the event iteration, no clock active).
    pub fn pass_event_mode(&self) -> fmi3Status {
        self.event_iteration();
        self.unary("fmi3EnterStepMode", self.fmu.api.enter_step_mode)
    }

    /// Enter and exit initialization at t = 0 (ME: then the event iteration and continuous-time mode).
    pub fn initialize(&mut self) {
        assert_eq!(
            self.enter_init(0.0),
            fmi3OK,
            "{}: fmi3EnterInitializationMode: {}",
            self.fmu.id,
            self.log_text()
        );
        assert_eq!(
            self.exit_init(),
            fmi3OK,
            "{}: fmi3ExitInitializationMode: {}",
            self.fmu.id,
            self.log_text()
        );
        if self.me {
            self.event_iteration();
            let s = self.unary("fmi3EnterContinuousTimeMode", self.fmu.api.enter_continuous_time_mode);
            assert_eq!(
                s,
                fmi3OK,
                "{}: fmi3EnterContinuousTimeMode: {}",
                self.fmu.id,
                self.log_text()
            );
        }
    }

    /// fmi3UpdateDiscreteStates until no update is needed (ME, event mode).
    pub fn event_iteration(&self) -> [u8; 5] {
        self.event_iteration_timed().0
    }

    /// [`event_iteration`](Self::event_iteration), with the next time event it announced.
    pub fn event_iteration_timed(&self) -> ([u8; 5], Option<f64>) {
        for _ in 0..100 {
            let mut flags = [0u8; 5];
            let mut next = 0.0;
            // SAFETY: a live instance; each pointer is to a live local of the length passed, or is
            // an FMU state.
            let s = self.call("fmi3UpdateDiscreteStates", |c| unsafe {
                crate::guard::fill_outputs(
                    "fmi3UpdateDiscreteStates",
                    &mut flags,
                    &mut next,
                    |[a, b, cc, d, e], t| (self.fmu.api.update_discrete_states)(c, a, b, cc, d, e, t),
                )
            });
            assert_eq!(
                s,
                fmi3OK,
                "{}: fmi3UpdateDiscreteStates: {}",
                self.fmu.id,
                self.log_text()
            );
            assert!(
                flags.iter().all(|f| *f <= 1),
                "{}: fmi3UpdateDiscreteStates wrote a bool that is neither 0 nor 1: {flags:?}",
                self.fmu.id
            );
            if flags[0] == 0 {
                return (flags, (flags[4] == 1).then_some(next));
            }
        }
        panic!(
            "{}: the event iteration did not end in 100 fmi3UpdateDiscreteStates",
            self.fmu.id
        )
    }

    /// fmi3GetFloat64 of scalars: one value per value reference.
    pub fn get_f64(&self, vrs: &[u32]) -> (fmi3Status, Vec<f64>) {
        self.get_f64_n(vrs, vrs.len())
    }
    /// fmi3GetFloat64 with `n` values (an array's elements count each, row-major, one variable
    /// after the other).
    pub fn get_f64_n(&self, vrs: &[u32], n: usize) -> (fmi3Status, Vec<f64>) {
        let mut v = Guarded::new(n, 0.0);
        let p = v.as_mut_ptr();
        let s = self
            .args(vec![("vr", Val::U32s(vrs.to_vec())), ("nValues", Val::U64(n as u64))])
            // SAFETY: a live instance; `p` holds `n` values (and the guard after them).
            .call("fmi3GetFloat64", |c| unsafe {
                (self.fmu.api.get_float64)(c, vrs.as_ptr(), vrs.len(), p, n)
            });
        let v = v.into_values(|| format!("fmi3GetFloat64 with nValues = {n}"), GETTER_RULE3);
        (s, v)
    }
    /// fmi3GetFloat64 of every element of the variables (scalars and arrays, start sizes).
    pub fn get_f64_of(&self, vars: &[&Variable]) -> (fmi3Status, Vec<f64>) {
        let vrs: Vec<u32> = vars.iter().map(|v| v.vr).collect();
        self.get_f64_n(&vrs, vars.iter().map(|v| self.fmu.element_count(v)).sum())
    }
    pub fn set_f64(&self, vrs: &[u32], v: &[f64]) -> fmi3Status {
        self.args(vec![("vr", Val::U32s(vrs.to_vec())), ("values", Val::F64s(v.to_vec()))])
            // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an
            // FMU state.
            .call("fmi3SetFloat64", |c| unsafe {
                (self.fmu.api.set_float64)(c, vrs.as_ptr(), vrs.len(), v.as_ptr(), v.len())
            })
    }

    /// One fmi3DoStep from `self.time`; returns the status and (eventHandlingNeeded,
    /// terminateSimulation, earlyReturn, lastSuccessfulTime).
    pub fn do_step(&mut self, h: f64) -> (fmi3Status, [u8; 3], f64) {
        let mut flags = [7u8; 3];
        let mut last = f64::NAN;
        let t = self.time;
        let s = self
            .args(vec![
                ("currentCommunicationPoint", Val::F64(t)),
                ("communicationStepSize", Val::F64(h)),
            ])
            // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an
            // FMU state.
            .call("fmi3DoStep", |c| unsafe {
                crate::guard::fill_outputs("fmi3DoStep", &mut flags, &mut last, |[a, b, d], l| {
                    (self.fmu.api.do_step)(c, t, h, true, a, b, d, l)
                })
            });
        if s == fmi3OK {
            self.time = t + h;
            if self.auto_events && flags[0] == 1 {
                // An event inside the step (no early return): handled before the next step.
                let e = self.unary("fmi3EnterEventMode", self.fmu.api.enter_event_mode);
                assert_eq!(e, fmi3OK, "{}: fmi3EnterEventMode: {}", self.fmu.id, self.log_text());
                assert_eq!(
                    self.pass_event_mode(),
                    fmi3OK,
                    "{}: fmi3EnterStepMode: {}",
                    self.fmu.id,
                    self.log_text()
                );
            }
        }
        (s, flags, last)
    }

    /// A step that must succeed: DoStep (CS) or an explicit-Euler step (ME). After a step that
    /// answered terminateSimulation, none (an importer ends the run there): the instance stays at
    /// the time it ended, and the check's comparisons see the same end in every run.
    pub fn step(&mut self, h: f64) {
        if self.me {
            euler_step(self, h);
        } else if self.ended_at.is_none() {
            let (s, flags, last) = self.do_step(h);
            if s == fmi3OK && flags[1] == 1 {
                self.ended_at = Some(last);
            }
            assert_eq!(
                s,
                fmi3OK,
                "{}: fmi3DoStep at t = {}: {}",
                self.fmu.id,
                self.time,
                self.log_text()
            );
        }
    }

    pub fn n_states(&self) -> usize {
        let mut n = usize::MAX;
        // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an
        // FMU state.
        let s = self.call("fmi3GetNumberOfContinuousStates", |c| unsafe {
            crate::guard::fill_one(
                &mut n,
                "fmi3GetNumberOfContinuousStates",
                "one size_t",
                crate::guard::COUNT_RULE3,
                |q| (self.fmu.api.get_number_of_continuous_states)(c, q),
            )
        });
        assert_eq!(
            s,
            fmi3OK,
            "{}: fmi3GetNumberOfContinuousStates: {}",
            self.fmu.id,
            self.log_text()
        );
        n
    }

    pub fn vector(&self, what: &str, f: api::Vector, n: usize) -> (fmi3Status, Vec<f64>) {
        let mut v = Guarded::new(n, 0.0);
        let p = v.as_mut_ptr();
        let s = self
            .args(vec![("n", Val::U64(n as u64))])
            // SAFETY: a live instance; `p` holds `n` values (and the guard after them).
            .call(what, |c| unsafe { f(c, p, n) });
        let v = v.into_values(|| format!("{what} with n = {n}"), GETTER_RULE3);
        (s, v)
    }

    /// Every Float64 value (bit patterns), then every value of the other numeric types and
    /// Booleans (their C bytes), every element of the arrays (those a structural parameter sizes
    /// at its start) and every Binary (its length and bytes), for comparing runs. Clocked
    /// variables are left out: they are read at their clocks' ticks only.
    pub fn observe(&self) -> Vec<u64> {
        let vrs: Vec<u32> = self
            .fmu
            .md
            .of_type(Type::Float64)
            .filter(|v| v.clocks.is_empty())
            .map(|v| v.vr)
            .collect();
        let (s, v) = self.get_f64(&vrs);
        assert_eq!(
            s,
            fmi3OK,
            "{}: fmi3GetFloat64 of every Float64: {}",
            self.fmu.id,
            self.log_text()
        );
        let mut out = crate::bits(&v);
        for var in self.fmu.md.variables.iter().filter(|v| {
            (v.array || v.ty != Type::Float64)
                && !matches!(v.ty, Type::String | Type::Clock)
                && v.clocks.is_empty()
                && v.causality != md_reader::Causality::Independent
        }) {
            let (s, bytes) = self.get_raw(var);
            assert_eq!(
                s,
                fmi3OK,
                "{}: fmi3Get{} of '{}': {}",
                self.fmu.id,
                accessor(var.ty),
                var.name,
                self.log_text()
            );
            if var.ty == Type::Binary {
                out.push(bytes.len() as u64);
            }
            out.extend(bytes.chunks(8).map(|c| {
                let mut b = [0u8; 8];
                b[..c.len()].copy_from_slice(c);
                u64::from_le_bytes(b)
            }));
        }
        out
    }

    /// The value of a variable of any type but String and Clock (every element of an array,
    /// row-major, the structural parameters at their starts: [`Fmu3::element_count`]), read with
    /// its type's getter, as its C bytes (native order; a Binary's bytes).
    pub fn get_raw(&self, v: &Variable) -> (fmi3Status, Vec<u8>) {
        self.get_raw_n(v, self.fmu.element_count(v))
    }

    /// [`Inst::get_raw`] with `n` as nValues (which may be wrong on purpose).
    pub fn get_raw_n(&self, v: &Variable, n: usize) -> (fmi3Status, Vec<u8>) {
        if v.ty == Type::Binary {
            // Through the call log (Inst::get_binary): a failure leaves a reproducer with it.
            let (s, _, mut bytes) = self.get_binary(&[v.vr], 1);
            return (s, bytes.pop().unwrap_or_default());
        }
        self.get_as(v.ty, v.vr, n)
    }

    /// The getter of type `ty` (a number or Boolean) of the value reference `vr`, whatever the
    /// variable's own type (a getter of another type: an importer's mistake, on purpose), into
    /// `n` values of that type with a guard after them: the status and the C bytes. Recorded as
    /// `fmi3GetInt32 vr=[1] nValues=1`.
    pub fn get_as(&self, ty: Type, vr: u32, n: usize) -> (fmi3Status, Vec<u8>) {
        let api = self.api();
        let mut guarded = Guarded::aligned_bytes(n * c_size(ty));
        let p = guarded.as_mut_ptr();
        let vr = &vr;
        let what = format!("fmi3Get{}", accessor(ty));
        let s = self
            .args(vec![("vr", Val::U32s(vec![*vr])), ("nValues", Val::U64(n as u64))])
            // SAFETY: this instance's live handle; `words` holds `n` values of any of the types,
            // 8-byte aligned.
            .call(&what, |c| unsafe { api.get_values(c, ty, vr, p, n) });
        let words = guarded.into_values(|| format!("{what} with nValues = {n}"), GETTER_RULE3);
        let bytes: Vec<u8> = words
            .iter()
            .flat_map(|w| w.to_ne_bytes())
            .take(n * c_size(ty))
            .collect();
        (s, bytes)
    }

    /// Sets a variable of any type but String and Clock from its C bytes (as [`Inst::get_raw`]
    /// gives them; an array's elements one after the other).
    pub fn set_raw(&self, v: &Variable, bytes: &[u8]) -> fmi3Status {
        let api = self.api();
        let vr = &v.vr;
        let what = format!("fmi3Set{}", accessor(v.ty));
        if v.ty == Type::Binary {
            let (size, data) = (bytes.len(), bytes.as_ptr());
            self.args(vec![
                ("vr", Val::U32s(vec![*vr])),
                ("nValues", Val::U64(1)),
                ("bytes", Val::Bytes(bytes.to_vec())),
            ]);
            // SAFETY: a live instance; each pointer is to a live local of the length passed, or is
            // an FMU state.
            return self.call(&what, |c| unsafe { (api.set_binary)(c, vr, 1, &size, &data, 1) });
        }
        let n = bytes.len() / c_size(v.ty);
        let mut words = vec![0u64; (bytes.len() / 8 + 1).max(1)];
        // SAFETY: the words hold at least bytes.len() bytes; u8 has no alignment.
        unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), words.as_mut_ptr() as *mut u8, bytes.len()) };
        let p = words.as_ptr() as *const std::ffi::c_void;
        self.args(vec![
            ("vr", Val::U32s(vec![*vr])),
            ("nValues", Val::U64(n as u64)),
            ("bytes", Val::Bytes(bytes.to_vec())),
        ]);
        // SAFETY: for every call, one value reference, `n` values of the type in an aligned buffer.
        self.call(&what, |c| unsafe {
            match v.ty {
                Type::Float32 => (api.set_float32)(c, vr, 1, p, n),
                Type::Float64 => (api.set_float64)(c, vr, 1, p as *const f64, n),
                Type::Int8 => (api.set_int8)(c, vr, 1, p, n),
                Type::UInt8 => (api.set_uint8)(c, vr, 1, p, n),
                Type::Int16 => (api.set_int16)(c, vr, 1, p, n),
                Type::UInt16 => (api.set_uint16)(c, vr, 1, p, n),
                Type::Int32 => (api.set_int32)(c, vr, 1, p as *const i32, n),
                Type::UInt32 => (api.set_uint32)(c, vr, 1, p, n),
                Type::Int64 | Type::Enumeration => (api.set_int64)(c, vr, 1, p as *const i64, n),
                Type::UInt64 => (api.set_uint64)(c, vr, 1, p, n),
                Type::Boolean => (api.set_boolean)(c, vr, 1, p as *const bool, n),
                Type::String | Type::Binary | Type::Clock => fmi3Error,
            }
        })
    }

    /// [`Inst::snapshot`] without panicking: the first call that was not fmi3OK, named.
    pub fn try_snapshot(&self) -> Result<Vec<u8>, String> {
        let api = self.api();
        let mut st: fmi3FMUState = std::ptr::null_mut();
        // SAFETY: the standard's calls with valid pointers on a live instance.
        unsafe {
            if crate::guard::fill_state3(&mut st, "fmi3GetFMUState", |q| (api.get_fmu_state)(self.c, q)) != fmi3OK {
                return Err("fmi3GetFMUState of a new instance failed".into());
            }
            let mut size = 0usize;
            let mut bytes = vec![];
            let mut s = crate::guard::fill_state_size3(&mut size, "fmi3SerializedFMUStateSize", |p| {
                (api.serialized_fmu_state_size)(self.c, st, p)
            });
            if s == fmi3OK && size <= 1 << 30 {
                let mut guarded = Guarded::new(size, 0u8);
                crate::outcome::breadcrumb("fmi3SerializeFMUState");
                s = (api.serialize_fmu_state)(self.c, st, guarded.as_mut_ptr(), size);
                match guarded.try_values(|| format!("fmi3SerializeFMUState with size = {size}"), STATE_RULE3) {
                    Ok(b) => bytes = b,
                    Err(e) => {
                        crate::guard::fill_state3(&mut st, "fmi3FreeFMUState", |q| (api.free_fmu_state)(self.c, q));
                        return Err(e);
                    }
                }
            }
            crate::guard::fill_state3(&mut st, "fmi3FreeFMUState", |q| (api.free_fmu_state)(self.c, q));
            if s != fmi3OK {
                return Err(format!(
                    "serializing the state of a new instance answered {}",
                    status_name(s)
                ));
            }
            Ok(bytes)
        }
    }

    /// Takes the FMU state and serializes it.
    pub fn snapshot(&self) -> Vec<u8> {
        let api = self.api();
        let mut st: fmi3FMUState = std::ptr::null_mut();
        assert_eq!(
            self.get_state(&mut st),
            fmi3OK,
            "{}: fmi3GetFMUState: {}",
            self.fmu.id,
            self.log_text()
        );
        let mut size = 0usize;
        assert_eq!(
            self.state_args(st, vec![])
                // SAFETY: a live instance; each pointer is to a live local of the length passed,
                // or is an FMU state.
                .call("fmi3SerializedFMUStateSize", |c| unsafe {
                    crate::guard::fill_state_size3(&mut size, "fmi3SerializedFMUStateSize", |p| {
                        (api.serialized_fmu_state_size)(c, st, p)
                    })
                }),
            fmi3OK
        );
        assert!(size < 1 << 30, "{}: serialized state of {size} bytes", self.fmu.id);
        let mut guarded = Guarded::new(size, 0u8);
        let p = guarded.as_mut_ptr();
        assert_eq!(
            self.state_args(st, vec![("size", Val::U64(size as u64))])
                // SAFETY: a live instance; `p` holds `size` bytes (and the guard after them).
                .call("fmi3SerializeFMUState", |c| unsafe {
                    (api.serialize_fmu_state)(c, st, p, size)
                }),
            fmi3OK
        );
        let bytes = guarded.into_values(
            || format!("fmi3SerializeFMUState with size = {size} (fmi3SerializedFMUStateSize's answer)"),
            STATE_RULE3,
        );
        assert_eq!(self.free_state(&mut st), fmi3OK);
        assert!(
            st.is_null(),
            "{}: fmi3FreeFMUState did not set the state pointer to NULL",
            self.fmu.id
        );
        bytes
    }

    /// Deserializes and sets a state; returns the status of the first call that was not OK.
    pub fn restore(&self, bytes: &[u8]) -> fmi3Status {
        let mut st: fmi3FMUState = std::ptr::null_mut();
        let s = self.deserialize(bytes, &mut st);
        if s != fmi3OK {
            return s;
        }
        let s = self.set_state(st);
        let f = self.free_state(&mut st);
        assert_eq!(f, fmi3OK, "{}: fmi3FreeFMUState: {}", self.fmu.id, self.log_text());
        s
    }
}

impl Drop for Inst<'_> {
    fn drop(&mut self) {
        if self.c.is_null() {
            return;
        }
        crate::outcome::breadcrumb("fmi3FreeInstance");
        crate::calllog::retire(std::mem::take(self.calls.get_mut()));
        // SAFETY: an instance made by this value, freed once.
        unsafe { (self.fmu.api.free_instance)(self.c) };
    }
}

/// One explicit-Euler step of an ME instance in continuous-time mode, handling a step event
/// (CompletedIntegratorStep asks for event mode) as an importer must; nx is every element of the
/// state arrays at the structural parameters' starts ([`Fmu3::n_states_declared`]).
pub fn euler_step(inst: &mut Inst, h: f64) {
    let nx = inst.fmu.n_states_declared();
    euler_step_n(inst, nx, h);
}

/// [`euler_step`] with `nx` continuous states (the structural-parameter check's, whose sizes
/// are not the starts).
pub fn euler_step_n(inst: &mut Inst, nx: usize, h: f64) {
    let api = inst.api();
    let id = &inst.fmu.id;
    let (s, x) = inst.vector("fmi3GetContinuousStates", api.get_continuous_states, nx);
    assert_eq!(
        s,
        fmi3OK,
        "{id}: fmi3GetContinuousStates (nx = {nx}): {}",
        inst.log_text()
    );
    let dx = inst.derivatives_ok(nx);
    let t = inst.time + h;
    let x1: Vec<f64> = x.iter().zip(&dx).map(|(x, d)| x + h * d).collect();
    assert_eq!(
        inst.args(vec![("time", Val::F64(t))])
            // SAFETY: a live instance.
            .call("fmi3SetTime", |c| unsafe { (api.set_time)(c, t) }),
        fmi3OK,
        "{id}: fmi3SetTime({t}): {}",
        inst.log_text()
    );
    assert_eq!(
        inst.args(vec![("values", Val::F64s(x1.clone()))])
            // SAFETY: a live instance; `x1` holds nx values.
            .call("fmi3SetContinuousStates", |c| unsafe {
                (api.set_continuous_states)(c, x1.as_ptr(), nx)
            }),
        fmi3OK,
        "{id}: fmi3SetContinuousStates (nx = {nx}): {}",
        inst.log_text()
    );
    inst.time = t;
    let (mut enter, mut term) = (7u8, 7u8);
    // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an FMU
    // state.
    let s = inst.args(vec![]).call("fmi3CompletedIntegratorStep", |c| unsafe {
        crate::guard::fill_integrator_step3(&mut enter, &mut term, |qa, qb| {
            (api.completed_integrator_step)(c, true, qa, qb)
        })
    });
    assert_eq!(s, fmi3OK, "{id}: fmi3CompletedIntegratorStep: {}", inst.log_text());
    assert!(
        enter <= 1 && term <= 1,
        "{id}: fmi3CompletedIntegratorStep wrote bools {enter}, {term}"
    );
    assert_eq!(
        term, 0,
        "{id}: fmi3CompletedIntegratorStep asks to terminate at t = {t}"
    );
    if enter == 1 {
        assert_eq!(
            inst.unary("fmi3EnterEventMode", api.enter_event_mode),
            fmi3OK,
            "{id}: fmi3EnterEventMode: {}",
            inst.log_text()
        );
        inst.event_iteration();
        assert_eq!(
            inst.unary("fmi3EnterContinuousTimeMode", api.enter_continuous_time_mode),
            fmi3OK,
            "{id}: fmi3EnterContinuousTimeMode: {}",
            inst.log_text()
        );
    }
}

/// Float values from a getter's bytes (Float64, or Float32 widened).
pub fn floats(ty: Type, bytes: &[u8]) -> Vec<f64> {
    match ty {
        Type::Float32 => bytes
            .chunks_exact(4)
            .map(|c| f32::from_ne_bytes(c.try_into().unwrap()) as f64)
            .collect(),
        _ => bytes
            .chunks_exact(8)
            .map(|c| f64::from_ne_bytes(c.try_into().unwrap()))
            .collect(),
    }
}

/// The folder with the packaged FMI 3.0 FMUs: `$RUSTFMU_FMU3_DIR`, else `<workspace>/target/fmu/fmi3`.
pub fn fmu3_dir() -> PathBuf {
    match std::env::var_os("RUSTFMU_FMU3_DIR") {
        Some(d) => PathBuf::from(d),
        None => crate::fmu_dir().join("fmi3"),
    }
}

crate::impl_loaded!(Fmu3, Fmi3, describe, fmu3_dir);

/// The bytes of one value of a scalar type in the C API (Enumerations are Int64).
pub fn c_size(ty: Type) -> usize {
    match ty {
        Type::Int8 | Type::UInt8 | Type::Boolean => 1,
        Type::Int16 | Type::UInt16 => 2,
        Type::Float32 | Type::Int32 | Type::UInt32 => 4,
        _ => 8,
    }
}

/// The type name of a variable's getter and setter (`Int64` for an Enumeration).
pub fn accessor(ty: Type) -> &'static str {
    match ty {
        Type::Enumeration => "Int64",
        other => other.name(),
    }
}

/// Starts `out` with the values of `from` (what the caller put there: the FMU may leave them).
fn out_of(from: &[f64], out: &mut Guarded<f64>) {
    // SAFETY: `out` holds `from.len()` values before its guard.
    unsafe { std::ptr::copy_nonoverlapping(from.as_ptr(), out.as_mut_ptr(), from.len()) };
}
