//! The FMI 2.0 calls the checks once made on the C functions directly, as [`Instance`] methods
//! that go through the call log ([`crate::calllog`]), so that a failure in them leaves a
//! reproducer with the failing call, which [`crate::replay_calls`] makes again: the String
//! getters and setters, directional derivatives (with the NULL arrays of the probes), the
//! input and output derivatives, fmi2CancelStep, the status getters, and the two halves of
//! serializing an FMU state.

use crate::calllog::Val;
use crate::fmi2::*;
use crate::guard::{GETTER_RULE2, Guarded, STATE_RULE2, STATUS_RULE2, fill_one};
use crate::instance::{Instance, Status};
use std::ffi::{CStr, CString};
use std::ptr;

/// An array argument as the call log writes it: its values, or NULL.
fn arg<T: Clone>(a: Option<&[T]>, of: impl FnOnce(Vec<T>) -> Val) -> Val {
    a.map_or(Val::Null, |a| of(a.to_vec()))
}

fn ptr_of<T>(a: Option<&[T]>) -> *const T {
    a.map_or(ptr::null(), <[T]>::as_ptr)
}

/// The name of a status kind, as the reproducer writes it.
#[allow(non_upper_case_globals)]
pub fn kind_name(kind: fmi2StatusKind) -> String {
    match kind {
        fmi2DoStepStatus => "fmi2DoStepStatus".into(),
        fmi2PendingStatus => "fmi2PendingStatus".into(),
        fmi2LastSuccessfulTime => "fmi2LastSuccessfulTime".into(),
        fmi2Terminated => "fmi2Terminated".into(),
        k => format!("{k}"),
    }
}

/// The status kind a reproducer names (or gives as a number: a kind the standard has not).
#[allow(non_upper_case_globals)]
pub fn kind_of(w: &str) -> Result<fmi2StatusKind, String> {
    Ok(match w {
        "fmi2DoStepStatus" => fmi2DoStepStatus,
        "fmi2PendingStatus" => fmi2PendingStatus,
        "fmi2LastSuccessfulTime" => fmi2LastSuccessfulTime,
        "fmi2Terminated" => fmi2Terminated,
        n => n.parse().map_err(|_| format!("kind={n}: not a status kind"))?,
    })
}

/// The arguments of fmi2GetDirectionalDerivative, each array possibly NULL (the probes of an
/// importer's mistakes); the counts apart from the arrays.
#[derive(Debug, Clone, Copy)]
pub struct Derivative<'x> {
    pub unknowns: Option<&'x [u32]>,
    pub n_unknown: usize,
    pub knowns: Option<&'x [u32]>,
    pub n_known: usize,
    pub seed: Option<&'x [f64]>,
    /// false: dvUnknown NULL.
    pub output: bool,
}

impl<'x> Derivative<'x> {
    /// A valid call: the counts are the arrays' lengths.
    pub fn of(unknowns: &'x [u32], knowns: &'x [u32], seed: &'x [f64]) -> Derivative<'x> {
        Derivative {
            unknowns: Some(unknowns),
            n_unknown: unknowns.len(),
            knowns: Some(knowns),
            n_known: knowns.len(),
            seed: Some(seed),
            output: true,
        }
    }
}

impl Instance<'_> {
    /// fmi2GetString of `vrs`: the texts (None where the FMU gave NULL).
    pub fn get_string(&self, vrs: &[u32]) -> (Status, Vec<Option<String>>) {
        let i = self.record("fmi2GetString", vec![("vr", Val::U32s(vrs.to_vec()))]);
        let mut v: Guarded<fmi2String> = Guarded::new(vrs.len(), ptr::null());
        // SAFETY: arrays of nvr elements (and the guard after `v`'s).
        let s = self.answered(i, unsafe {
            (self.fmu.api.get_string)(self.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr())
        });
        let v = v.into_values(|| format!("fmi2GetString with nvr = {}", vrs.len()), GETTER_RULE2);
        // Read only where the FMU answered that it gave them (a refused call may leave anything).
        let gave = s == fmi2OK || s == fmi2Warning;
        let texts = v
            .iter()
            .map(|p| {
                (gave && !p.is_null()).then(|| {
                    // SAFETY: a string the FMU returned, valid until its next call.
                    unsafe { CStr::from_ptr(*p) }.to_string_lossy().into_owned()
                })
            })
            .collect();
        (s, texts)
    }

    /// fmi2SetString of `vrs` to `values`.
    pub fn set_string(&mut self, vrs: &[u32], values: &[String]) -> Status {
        assert_eq!(vrs.len(), values.len());
        let owned: Vec<CString> = values
            .iter()
            .map(|t| CString::new(t.as_str()).unwrap_or_default())
            .collect();
        let v: Vec<fmi2String> = owned.iter().map(|c| c.as_ptr()).collect();
        let i = self.record(
            "fmi2SetString",
            vec![("vr", Val::U32s(vrs.to_vec())), ("values", Val::Texts(values.to_vec()))],
        );
        // SAFETY: arrays of nvr elements; the strings outlive the call.
        self.answered(i, unsafe {
            (self.fmu.api.set_string)(self.c, vrs.as_ptr(), vrs.len(), v.as_ptr())
        })
    }

    /// fmi2GetDirectionalDerivative as `d` says (NULL arrays included): the status and the
    /// nUnknown values (none when dvUnknown is NULL).
    pub fn directional_derivative(&self, d: Derivative) -> (Status, Vec<f64>) {
        let mut args = vec![
            ("unknowns", arg(d.unknowns, Val::U32s)),
            ("nUnknown", Val::U64(d.n_unknown as u64)),
            ("knowns", arg(d.knowns, Val::U32s)),
            ("nKnown", Val::U64(d.n_known as u64)),
            ("seed", arg(d.seed, Val::F64s)),
        ];
        if !d.output {
            args.push(("dvUnknown", Val::Null));
        }
        let i = self.record("fmi2GetDirectionalDerivative", args);
        let (u, k, seed) = (ptr_of(d.unknowns), ptr_of(d.knowns), ptr_of(d.seed));
        let f = self.fmu.api.get_directional_derivative;
        if !d.output {
            // SAFETY: the arrays are of the lengths passed, or NULL on purpose (a probe of an
            // importer's mistake, which a careful FMU refuses).
            let s = unsafe { f(self.c, u, d.n_unknown, k, d.n_known, seed, ptr::null_mut()) };
            return (self.answered(i, s), vec![]);
        }
        let mut out = Guarded::new(d.n_unknown, f64::NAN);
        // SAFETY: as above; `out` holds nUnknown values and the guard after them.
        let s = unsafe { f(self.c, u, d.n_unknown, k, d.n_known, seed, out.as_mut_ptr()) };
        self.answered(i, s);
        let out = out.into_values(
            || format!("fmi2GetDirectionalDerivative with nUnknown = {}", d.n_unknown),
            GETTER_RULE2,
        );
        (s, out)
    }

    /// fmi2SetRealInputDerivatives (NULL arrays when `vrs` is empty).
    pub fn set_real_input_derivatives(&mut self, vrs: &[u32], orders: &[i32], values: &[f64]) -> Status {
        assert!(orders.len() == vrs.len() && values.len() == vrs.len());
        let i = self.record(
            "fmi2SetRealInputDerivatives",
            vec![
                ("vr", Val::U32s(vrs.to_vec())),
                ("order", Val::I64s(orders.iter().map(|o| i64::from(*o)).collect())),
                ("values", Val::F64s(values.to_vec())),
            ],
        );
        let (a, b, c) = if vrs.is_empty() {
            (ptr::null(), ptr::null(), ptr::null())
        } else {
            (vrs.as_ptr(), orders.as_ptr(), values.as_ptr())
        };
        // SAFETY: arrays of nvr elements (NULL with nvr = 0).
        self.answered(i, unsafe {
            (self.fmu.api.set_real_input_derivatives)(self.c, a, vrs.len(), b, c)
        })
    }

    /// fmi2GetRealOutputDerivatives (NULL arrays when `vrs` is empty): the status and the values.
    pub fn get_real_output_derivatives(&self, vrs: &[u32], orders: &[i32]) -> (Status, Vec<f64>) {
        assert_eq!(orders.len(), vrs.len());
        let i = self.record(
            "fmi2GetRealOutputDerivatives",
            vec![
                ("vr", Val::U32s(vrs.to_vec())),
                ("order", Val::I64s(orders.iter().map(|o| i64::from(*o)).collect())),
            ],
        );
        let f = self.fmu.api.get_real_output_derivatives;
        if vrs.is_empty() {
            // SAFETY: nvr = 0 with NULL arrays.
            let s = unsafe { f(self.c, ptr::null(), 0, ptr::null(), ptr::null_mut()) };
            return (self.answered(i, s), vec![]);
        }
        let mut out = Guarded::new(vrs.len(), f64::NAN);
        // SAFETY: arrays of nvr elements (and the guard after `out`'s).
        let s = unsafe { f(self.c, vrs.as_ptr(), vrs.len(), orders.as_ptr(), out.as_mut_ptr()) };
        self.answered(i, s);
        let out = out.into_values(
            || format!("fmi2GetRealOutputDerivatives with nvr = {}", vrs.len()),
            GETTER_RULE2,
        );
        (s, out)
    }

    pub fn cancel_step(&mut self) -> Status {
        let i = self.record("fmi2CancelStep", vec![]);
        // SAFETY: a live instance.
        self.answered(i, unsafe { (self.fmu.api.cancel_step)(self.c) })
    }

    /// fmi2GetStatus of `kind`: the status and the value (99 if the FMU wrote none).
    pub fn get_status(&self, kind: fmi2StatusKind) -> (Status, fmi2Status) {
        self.status_value("fmi2GetStatus", kind, 99, self.fmu.api.get_status)
    }

    /// The fmi2Get*Status `function` (`f`) of `kind` into a value that holds `v` before the call:
    /// the status and the value after it.
    fn status_value<T: crate::guard::Plain>(
        &self,
        function: &'static str,
        kind: fmi2StatusKind,
        mut v: T,
        f: fmi2GetStatusTYPE<T>,
    ) -> (Status, T) {
        let i = self.record(function, vec![("kind", Val::Text(kind_name(kind)))]);
        // SAFETY: a valid out pointer (and the guard after it).
        let s = unsafe {
            fill_one(&mut v, function, "one value", STATUS_RULE2, |p| {
                self.answered(i, f(self.c, kind, p))
            })
        };
        (s, v)
    }

    /// fmi2GetIntegerStatus of `kind`: the status and the value.
    pub fn get_integer_status(&self, kind: fmi2StatusKind) -> (Status, fmi2Integer) {
        self.status_value("fmi2GetIntegerStatus", kind, 0, self.fmu.api.get_integer_status)
    }

    /// fmi2GetStringStatus of `kind`: the status and the text (None for NULL).
    pub fn get_string_status(&self, kind: fmi2StatusKind) -> (Status, Option<String>) {
        let (s, v) = self.status_value("fmi2GetStringStatus", kind, ptr::null(), self.fmu.api.get_string_status);
        let gave = !v.is_null() && (s == fmi2OK || s == fmi2Warning);
        // SAFETY: a string the FMU returned, valid until its next call.
        let text = gave.then(|| unsafe { CStr::from_ptr(v) }.to_string_lossy().into_owned());
        (s, text)
    }

    /// The call log's argument for the FMU state `s`: None for a state another instance made
    /// (the call is then recorded without arguments, not replayable).
    fn state_arg(&self, s: fmi2FMUstate) -> Option<Val> {
        if s.is_null() {
            return Some(Val::Null);
        }
        self.calls.borrow_mut().state(s as usize, false).map(Val::State)
    }

    /// fmi2SerializedFMUstateSize of `s`: the status and the size.
    // The harness passes FMU states through to the FMU as an importer does.
    #[allow(clippy::not_unsafe_ptr_arg_deref)]
    pub fn serialized_size(&self, s: fmi2FMUstate) -> (Status, usize) {
        let mut size = 0usize;
        let i = match self.state_arg(s) {
            Some(v) => self.record("fmi2SerializedFMUstateSize", vec![("state", v)]),
            None => self.record_unreplayable("fmi2SerializedFMUstateSize"),
        };
        // SAFETY: a state of this FMU and a valid out pointer (and the guard after it).
        let st = unsafe {
            fill_one(
                &mut size,
                "fmi2SerializedFMUstateSize",
                "one size_t",
                STATE_RULE2,
                |p| self.answered(i, (self.fmu.api.serialized_fmu_state_size)(self.c, s, p)),
            )
        };
        (st, size)
    }

    /// fmi2SerializeFMUstate of `s` into `size` bytes (zeros before the call): the status and
    /// the bytes.
    // The harness passes FMU states through to the FMU as an importer does.
    #[allow(clippy::not_unsafe_ptr_arg_deref)]
    pub fn serialize_into(&self, s: fmi2FMUstate, size: usize) -> (Status, Vec<u8>) {
        let i = match self.state_arg(s) {
            Some(v) => self.record(
                "fmi2SerializeFMUstate",
                vec![("state", v), ("size", Val::U64(size as u64))],
            ),
            None => self.record_unreplayable("fmi2SerializeFMUstate"),
        };
        let mut bytes = Guarded::new(size, 0u8);
        // SAFETY: a buffer of `size` bytes (and the guard after it).
        let st = self.answered(i, unsafe {
            (self.fmu.api.serialize_fmu_state)(self.c, s, bytes.as_mut_ptr() as *mut fmi2Byte, size)
        });
        let bytes = bytes.into_values(
            || format!("fmi2SerializeFMUstate into a buffer of size = {size}"),
            STATE_RULE2,
        );
        (st, bytes)
    }
}

/// The getters and setters [`Instance::array_probe`] calls, as the standard names them.
pub use fmi_standard::functions::FMI2_VALUE_FUNCTIONS as ARRAY_PROBES;

/// The functions [`Instance::null_component`] calls with a NULL component, in the order the check
/// calls them: every co-simulation function that takes the instance, but fmi2FreeInstance (of a
/// NULL instance a no-op).
pub const NULL_COMPONENT_PROBES: [&str; 30] = fmi_standard::functions::without(
    fmi_standard::functions::FMI2_CS_FUNCTIONS,
    &[
        "fmi2GetTypesPlatform",
        "fmi2GetVersion",
        "fmi2Instantiate",
        "fmi2FreeInstance",
    ],
);

/// The model-exchange functions the check of a NULL component calls (`fmi2SetTime
/// component=NULL`), besides [`NULL_COMPONENT_PROBES`]: every one model exchange has alone.
pub use crate::api::ME_FUNCTIONS as ME_NULL_COMPONENT_PROBES;

/// `name` as the `&'static str` of `list` (a function a reproducer's line names).
pub fn named(list: &[&'static str], name: &str) -> Option<&'static str> {
    list.iter().copied().find(|f| *f == name)
}

impl Instance<'_> {
    /// A getter or setter of [`ARRAY_PROBES`] with its arrays as given: `vr` (None: NULL), `nvr`,
    /// and the values' array (`value` false: NULL; else `nvr` zeros, or empty texts, and for a
    /// getter a guard after them). The probes of an importer's mistakes (NULL arrays with
    /// nvr > 0) and of nvr = 0 with NULL arrays, which FMI 2.0.5 §2.1.7 allows. Recorded as
    /// `fmi2GetReal vr=NULL nvr=1` (`value=NULL` where the values' array was NULL).
    pub fn array_probe(&self, function: &'static str, vr: Option<&[u32]>, nvr: usize, value: bool) -> Status {
        use crate::guard::fill;
        assert!(
            vr.is_none_or(|v| v.len() >= nvr),
            "{function}: a vr array shorter than nvr"
        );
        let mut args = vec![("vr", arg(vr, Val::U32s)), ("nvr", Val::U64(nvr as u64))];
        if !value {
            args.push(("value", Val::Null));
        }
        let i = self.record(function, args);
        let (api, c, v) = (&self.fmu.api, self.c, ptr_of(vr));
        let (mut real, mut int) = (vec![0.0; nvr], vec![0; nvr]);
        let empty = c"";
        let mut texts: Vec<fmi2String> = vec![empty.as_ptr(); nvr];
        let s = if value {
            // SAFETY: `v` holds nvr value references or is NULL (on purpose: the FMU must check);
            // each values' array holds nvr elements (a getter's, the guard after them).
            unsafe {
                match function {
                    "fmi2GetReal" => fill(&mut real, function, "nvr", GETTER_RULE2, |p| {
                        (api.get_real)(c, v, nvr, p)
                    }),
                    "fmi2GetInteger" => fill(&mut int, function, "nvr", GETTER_RULE2, |p| {
                        (api.get_integer)(c, v, nvr, p)
                    }),
                    "fmi2GetBoolean" => fill(&mut int, function, "nvr", GETTER_RULE2, |p| {
                        (api.get_boolean)(c, v, nvr, p)
                    }),
                    "fmi2GetString" => fill(&mut texts, function, "nvr", GETTER_RULE2, |p| {
                        (api.get_string)(c, v, nvr, p)
                    }),
                    "fmi2SetReal" => (api.set_real)(c, v, nvr, real.as_ptr()),
                    "fmi2SetInteger" => (api.set_integer)(c, v, nvr, int.as_ptr()),
                    "fmi2SetBoolean" => (api.set_boolean)(c, v, nvr, int.as_ptr()),
                    "fmi2SetString" => (api.set_string)(c, v, nvr, texts.as_ptr()),
                    f => panic!("{f} is not one of the getters and setters of ARRAY_PROBES"),
                }
            }
        } else {
            // SAFETY: NULL values with nvr = 0 (allowed) or nvr > 0 (on purpose: the FMU must
            // check before writing or reading).
            unsafe {
                match function {
                    "fmi2GetReal" => (api.get_real)(c, v, nvr, ptr::null_mut()),
                    "fmi2GetInteger" => (api.get_integer)(c, v, nvr, ptr::null_mut()),
                    "fmi2GetBoolean" => (api.get_boolean)(c, v, nvr, ptr::null_mut()),
                    "fmi2GetString" => (api.get_string)(c, v, nvr, ptr::null_mut()),
                    "fmi2SetReal" => (api.set_real)(c, v, nvr, ptr::null()),
                    "fmi2SetInteger" => (api.set_integer)(c, v, nvr, ptr::null()),
                    "fmi2SetBoolean" => (api.set_boolean)(c, v, nvr, ptr::null()),
                    "fmi2SetString" => (api.set_string)(c, v, nvr, ptr::null()),
                    f => panic!("{f} is not one of the getters and setters of ARRAY_PROBES"),
                }
            }
        };
        self.answered(i, s)
    }

    /// fmi2GetRealStatus of `kind` (any kind: one of another getter is answered fmi2Discard),
    /// into a value that holds `value` before the call (None: a NULL value pointer, an
    /// importer's mistake): the status and the value after it.
    pub fn real_status(&self, kind: fmi2StatusKind, value: Option<f64>) -> (Status, f64) {
        let f = self.fmu.api.get_real_status;
        let Some(v) = value else {
            let args = vec![("kind", Val::Text(kind_name(kind))), ("value", Val::Null)];
            let i = self.record("fmi2GetRealStatus", args);
            // SAFETY: a NULL out pointer on purpose: the FMU must check before writing.
            let s = unsafe { f(self.c, kind, ptr::null_mut()) };
            return (self.answered(i, s), f64::NAN);
        };
        self.status_value("fmi2GetRealStatus", kind, v, f)
    }

    /// fmi2GetBooleanStatus of `kind` (any kind, or a number no kind has) into a value that holds
    /// -1 before the call: the status and the value after it.
    pub fn boolean_status(&self, kind: fmi2StatusKind) -> (Status, fmi2Boolean) {
        self.status_value("fmi2GetBooleanStatus", kind, -1, self.fmu.api.get_boolean_status)
    }

    /// fmi2SetDebugLogging with `n` categories as given: `categories` None is a NULL array, an
    /// element None a NULL string (the probes of an importer's mistakes). Recorded as
    /// `fmi2SetDebugLogging loggingOn=true nCategories=2 categories=NULL` (or
    /// `categories=[logEvents,NULL]`; a category named NULL is written `%4EULL`).
    pub fn set_debug_logging_raw(&mut self, on: bool, n: usize, categories: Option<&[Option<&str>]>) -> Status {
        let owned: Option<Vec<Option<CString>>> = categories.map(|cs| {
            cs.iter()
                .map(|c| c.map(|c| CString::new(c).unwrap_or_default()))
                .collect()
        });
        let ptrs: Option<Vec<fmi2String>> = owned.as_ref().map(|cs| {
            cs.iter()
                .map(|c| c.as_ref().map_or(ptr::null(), |c| c.as_ptr()))
                .collect()
        });
        assert!(
            ptrs.as_ref().is_none_or(|p| p.len() >= n),
            "fmi2SetDebugLogging: fewer categories than nCategories"
        );
        let written = categories.map_or(Val::Null, |cs| {
            Val::Raw(crate::replay::list(cs.iter().map(|c| match c {
                None => "NULL".to_string(),
                Some("NULL") => "%4EULL".to_string(),
                Some(c) => crate::calllog::encode(c),
            })))
        });
        let i = self.record(
            "fmi2SetDebugLogging",
            vec![
                ("loggingOn", Val::Bool(on)),
                ("nCategories", Val::U64(n as u64)),
                ("categories", written),
            ],
        );
        let p = ptrs.as_ref().map_or(ptr::null(), |p| p.as_ptr());
        // SAFETY: `p` holds n strings (some NULL on purpose) or is NULL (on purpose, with n > 0):
        // the FMU must check each before reading it.
        self.answered(i, unsafe {
            (self.fmu.api.set_debug_logging)(self.c, on as fmi2Boolean, n, p)
        })
    }

    /// fmi2FreeFMUstate with a NULL `fmi2FMUstate*` (not a pointer to a NULL state): an
    /// importer's mistake. Recorded as `fmi2FreeFMUstate statePointer=NULL`.
    pub fn free_state_pointer_null(&mut self) -> Status {
        let i = self.record("fmi2FreeFMUstate", vec![("statePointer", Val::Null)]);
        // SAFETY: a NULL fmi2FMUstate* on purpose, which a careful FMU refuses or ignores.
        self.answered(i, unsafe { (self.fmu.api.free_fmu_state)(self.c, ptr::null_mut()) })
    }

    /// fmi2DeSerializeFMUstate with its arguments as given: `bytes` None is a NULL
    /// serializedState of `size` bytes, `out` false a NULL `fmi2FMUstate*` (the probes of an
    /// importer's mistakes). A state it makes is not kept (the probes expect a refusal).
    /// Recorded as `fmi2DeSerializeFMUstate bytes=NULL size=16` or `... bytes=hex:...
    /// statePointer=NULL`.
    pub fn deserialize_raw(&mut self, bytes: Option<&[u8]>, size: usize, out: bool) -> Status {
        assert!(
            bytes.is_none_or(|b| b.len() == size),
            "fmi2DeSerializeFMUstate: size is the bytes' length"
        );
        let mut args = vec![("bytes", arg(bytes, Val::Bytes))];
        if bytes.is_none() {
            args.push(("size", Val::U64(size as u64)));
        }
        if !out {
            args.push(("statePointer", Val::Null));
        }
        let i = self.record("fmi2DeSerializeFMUstate", args);
        let b = ptr_of(bytes) as *const fmi2Byte;
        let f = self.fmu.api.deserialize_fmu_state;
        if !out {
            // SAFETY: a NULL fmi2FMUstate* on purpose: the FMU must check before writing.
            return self.answered(i, unsafe { f(self.c, b, size, ptr::null_mut()) });
        }
        let mut st: fmi2FMUstate = ptr::null_mut();
        // SAFETY: `b` holds `size` bytes or is NULL (on purpose); a valid out pointer.
        let s = unsafe {
            crate::guard::fill_state2(&mut st, "fmi2DeSerializeFMUstate", |q| {
                self.answered(i, f(self.c, b, size, q))
            })
        };
        // A state the FMU made though it should have refused is left as the check left it.
        s
    }

    /// One of the model-exchange vector getters (`name`, [`crate::me::VECTOR_GETTERS`]) into
    /// NULL with `n` values: an importer's mistake. Recorded as `fmi2GetDerivatives n=1
    /// values=NULL`.
    pub fn get_vector_null(&self, name: &'static str, n: usize) -> Status {
        let f = self.vector_getter(name);
        let i = self.record(name, vec![("n", Val::U64(n as u64)), ("values", Val::Null)]);
        // SAFETY: NULL on purpose (n > 0): the FMU must check before writing.
        self.answered(i, unsafe { f(self.c, ptr::null_mut(), n) })
    }

    /// fmi2SetContinuousStates of NULL with `nx` values: an importer's mistake. Recorded as
    /// `fmi2SetContinuousStates x=NULL nx=1`.
    pub fn set_continuous_states_null(&mut self, nx: usize) -> Status {
        let i = self.record(
            "fmi2SetContinuousStates",
            vec![("x", Val::Null), ("nx", Val::U64(nx as u64))],
        );
        // SAFETY: NULL on purpose (nx > 0): the FMU must check before reading.
        self.answered(i, unsafe { (self.me().set_continuous_states)(self.c, ptr::null(), nx) })
    }

    /// fmi2CompletedIntegratorStep with one output pointer NULL (`enter_null`: enterEventMode,
    /// else terminateSimulation; the other a value with a guard after it): an importer's
    /// mistake. Recorded as `fmi2CompletedIntegratorStep noSetFMUStatePriorToCurrentPoint=false
    /// enterEventMode=NULL`.
    pub fn completed_integrator_step_null(&mut self, enter_null: bool) -> Status {
        let null = if enter_null {
            "enterEventMode"
        } else {
            "terminateSimulation"
        };
        let i = self.record(
            "fmi2CompletedIntegratorStep",
            vec![
                ("noSetFMUStatePriorToCurrentPoint", Val::Bool(false)),
                (null, Val::Null),
            ],
        );
        let f = self.me().completed_integrator_step;
        let mut other: fmi2Boolean = 77;
        // SAFETY: one output NULL on purpose (the FMU must check before writing), the other a
        // live value with a guard after it.
        let s = unsafe {
            fill_one(
                &mut other,
                "fmi2CompletedIntegratorStep",
                "one value",
                GETTER_RULE2,
                |p| {
                    if enter_null {
                        f(self.c, fmi2False, ptr::null_mut(), p)
                    } else {
                        f(self.c, fmi2False, p, ptr::null_mut())
                    }
                },
            )
        };
        self.answered(i, s)
    }

    /// fmi2NewDiscreteStates with a NULL eventInfo: an importer's mistake. Recorded as
    /// `fmi2NewDiscreteStates eventInfo=NULL`.
    pub fn new_discrete_states_null(&mut self) -> Status {
        let i = self.record("fmi2NewDiscreteStates", vec![("eventInfo", Val::Null)]);
        // SAFETY: NULL on purpose: the FMU must check before writing.
        self.answered(i, unsafe { (self.me().new_discrete_states)(self.c, ptr::null_mut()) })
    }

    /// fmi2GetFMUstate into the existing FMU state `st` (FMI 2.0.5 §2.1.8: "If on entry
    /// *FMUstate is not a null pointer, fmi2GetFMUstate typically reuses the memory of this
    /// FMUstate"): `st` is then the state the FMU answered. Recorded as `fmi2GetFMUstate into=1`
    /// (and `state=N` where the FMU answered another state than it was given).
    pub fn get_state_into(&mut self, st: &mut fmi2FMUstate) -> Status {
        let i = match self.state_val(*st, false) {
            Some(v) => self.record("fmi2GetFMUstate", vec![("into", v)]),
            None => self.record_unreplayable("fmi2GetFMUstate"),
        };
        let old = *st;
        // SAFETY: a live instance; `st` is a live FMU state it returned, to be overwritten in
        // place (a guard after it).
        let s = unsafe {
            crate::guard::fill_state2(st, "fmi2GetFMUstate", |q| {
                self.answered(i, (self.fmu.api.get_fmu_state)(self.c, q))
            })
        };
        if *st != old
            && let Some(v) = self.state_val(*st, true)
        {
            self.calls.borrow_mut().add_arg(i, "state", v);
        }
        s
    }

    /// fmi2FreeInstance(NULL), which FMI 2.0.5 §2.1.5 makes a no-op ("If a null pointer is
    /// provided for c, the function call is ignored"); it returns nothing, and is recorded as
    /// answering OK: `fmi2FreeInstance component=NULL`.
    pub fn free_instance_null(&self) {
        let i = self.record("fmi2FreeInstance", vec![("component", Val::Null)]);
        // SAFETY: fmi2FreeInstance(NULL) is a no-op by the standard.
        unsafe { (self.fmu.api.free_instance)(ptr::null_mut()) };
        self.answered(i, fmi2OK);
    }

    /// `function` of [`NULL_COMPONENT_PROBES`] called with a NULL
    /// component (its other arguments valid or empty, as the check passes them): the status.
    /// Recorded as `fmi2DoStep component=NULL`. Panics where the call wrote an FMU state.
    pub fn null_component(&self, function: &'static str) -> Status {
        let i = self.record(function, vec![("component", Val::Null)]);
        let s = null_component_call(self.fmu, function);
        self.answered(i, s)
    }
}

/// `function` called on a NULL component, its other arguments as the check of a NULL component
/// passes them (one value reference 0 and valid arrays for the getters and setters, NULL
/// arrays with 0 elements elsewhere).
#[allow(clippy::too_many_lines)]
fn null_component_call(fmu: &crate::Fmu, function: &str) -> Status {
    use crate::guard::{GETTER_RULE2 as R, STATUS_RULE2 as S, fill};
    let api = &fmu.api;
    let c: fmi2Component = ptr::null_mut();
    let vr = [0u32];
    let mut real = [0.0];
    let mut int = [0];
    let mut st: fmi2FMUstate = ptr::null_mut();
    let mut size = 0usize;
    let mut status = 0;
    let mut string: fmi2String = ptr::null();
    let empty = c"";
    let text: fmi2String = empty.as_ptr();
    // SAFETY: every function must check the component before touching anything; the other
    // arguments are valid (or NULL with a count of 0).
    let s = unsafe {
        match function {
            "fmi2SetDebugLogging" => (api.set_debug_logging)(c, 1, 0, ptr::null()),
            "fmi2SetupExperiment" => (api.setup_experiment)(c, 0, 0.0, 0.0, 0, 0.0),
            "fmi2EnterInitializationMode" => (api.enter_initialization_mode)(c),
            "fmi2ExitInitializationMode" => (api.exit_initialization_mode)(c),
            "fmi2Terminate" => (api.terminate)(c),
            "fmi2Reset" => (api.reset)(c),
            "fmi2GetReal" => fill(&mut real, function, "nvr", R, |p| (api.get_real)(c, vr.as_ptr(), 1, p)),
            "fmi2GetInteger" => fill(&mut int, function, "nvr", R, |p| {
                (api.get_integer)(c, vr.as_ptr(), 1, p)
            }),
            "fmi2GetBoolean" => fill(&mut int, function, "nvr", R, |p| {
                (api.get_boolean)(c, vr.as_ptr(), 1, p)
            }),
            "fmi2GetString" => fill_one(&mut string, function, "nvr", R, |p| {
                (api.get_string)(c, vr.as_ptr(), 1, p)
            }),
            "fmi2SetReal" => (api.set_real)(c, vr.as_ptr(), 1, real.as_ptr()),
            "fmi2SetInteger" => (api.set_integer)(c, vr.as_ptr(), 1, int.as_ptr()),
            "fmi2SetBoolean" => (api.set_boolean)(c, vr.as_ptr(), 1, int.as_ptr()),
            "fmi2SetString" => (api.set_string)(c, vr.as_ptr(), 1, &text),
            "fmi2GetFMUstate" => crate::guard::fill_state2(&mut st, function, |q| (api.get_fmu_state)(c, q)),
            "fmi2SetFMUstate" => (api.set_fmu_state)(c, st),
            "fmi2FreeFMUstate" => crate::guard::fill_state2(&mut st, function, |q| (api.free_fmu_state)(c, q)),
            "fmi2SerializedFMUstateSize" => {
                crate::guard::fill_state_size2(&mut size, function, |p| (api.serialized_fmu_state_size)(c, st, p))
            }
            "fmi2SerializeFMUstate" => (api.serialize_fmu_state)(c, st, ptr::null_mut(), 0),
            "fmi2DeSerializeFMUstate" => {
                crate::guard::fill_state2(&mut st, function, |q| (api.deserialize_fmu_state)(c, ptr::null(), 0, q))
            }
            "fmi2GetDirectionalDerivative" => {
                (api.get_directional_derivative)(c, ptr::null(), 0, ptr::null(), 0, ptr::null(), ptr::null_mut())
            }
            "fmi2SetRealInputDerivatives" => {
                (api.set_real_input_derivatives)(c, ptr::null(), 0, ptr::null(), ptr::null())
            }
            "fmi2GetRealOutputDerivatives" => {
                (api.get_real_output_derivatives)(c, ptr::null(), 0, ptr::null(), ptr::null_mut())
            }
            "fmi2DoStep" => (api.do_step)(c, 0.0, 0.1, 0),
            "fmi2CancelStep" => (api.cancel_step)(c),
            "fmi2GetStatus" => fill_one(&mut status, function, "one value", S, |p| (api.get_status)(c, 0, p)),
            "fmi2GetRealStatus" => fill(&mut real, function, "one value", S, |p| (api.get_real_status)(c, 2, p)),
            "fmi2GetIntegerStatus" => fill(&mut int, function, "one value", S, |p| {
                (api.get_integer_status)(c, 0, p)
            }),
            "fmi2GetBooleanStatus" => fill(&mut int, function, "one value", S, |p| {
                (api.get_boolean_status)(c, 3, p)
            }),
            "fmi2GetStringStatus" => fill_one(&mut string, function, "one value", S, |p| {
                (api.get_string_status)(c, 0, p)
            }),
            f => return null_component_me(fmu, f),
        }
    };
    assert!(
        st.is_null(),
        "{}: {function} on a NULL component wrote an FMU state",
        fmu.id
    );
    s
}

/// [`null_component_call`] of a function of [`ME_NULL_COMPONENT_PROBES`] (valid outputs of a
/// few values, each with a guard after it).
fn null_component_me(fmu: &crate::Fmu, function: &str) -> Status {
    use crate::guard::{GETTER_RULE2 as R, fill};
    let me = fmu
        .api
        .me
        .as_ref()
        .unwrap_or_else(|e| panic!("{}: {function}: no model-exchange functions: {e}", fmu.id));
    let c: fmi2Component = ptr::null_mut();
    let n = fmu.md.number_of_continuous_states().min(4);
    let ni = fmu.md.number_of_event_indicators.min(4);
    let mut v = [0.0; 4];
    let mut info = fmi2EventInfo::default();
    let (mut a, mut b) = (0, 0);
    // SAFETY: every function must check the component before touching anything; the outputs
    // are valid, each with a guard after it.
    unsafe {
        match function {
            "fmi2EnterEventMode" => (me.enter_event_mode)(c),
            "fmi2NewDiscreteStates" => (me.new_discrete_states)(c, &mut info),
            "fmi2EnterContinuousTimeMode" => (me.enter_continuous_time_mode)(c),
            "fmi2CompletedIntegratorStep" => fill_one(
                &mut a,
                "fmi2CompletedIntegratorStep (enterEventMode)",
                "one value",
                R,
                |pa| {
                    fill_one(
                        &mut b,
                        "fmi2CompletedIntegratorStep (terminateSimulation)",
                        "one value",
                        R,
                        |pb| (me.completed_integrator_step)(c, 0, pa, pb),
                    )
                },
            ),
            "fmi2SetTime" => (me.set_time)(c, 0.0),
            "fmi2SetContinuousStates" => (me.set_continuous_states)(c, v.as_ptr(), n),
            "fmi2GetDerivatives" => fill(&mut v[..n], function, "nx", R, |p| (me.get_derivatives)(c, p, n)),
            "fmi2GetEventIndicators" => fill(&mut v[..ni], function, "ni", R, |p| (me.get_event_indicators)(c, p, ni)),
            "fmi2GetContinuousStates" => fill(&mut v[..n], function, "nx", R, |p| (me.get_continuous_states)(c, p, n)),
            "fmi2GetNominalsOfContinuousStates" => fill(&mut v[..n], function, "nx", R, |p| {
                (me.get_nominals_of_continuous_states)(c, p, n)
            }),
            f => panic!("{f} is not a function the check of a NULL component calls"),
        }
    }
}
