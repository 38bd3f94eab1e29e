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
        let mut v = 99;
        let i = self.record("fmi2GetStatus", vec![("kind", Val::Text(kind_name(kind)))]);
        // SAFETY: a valid out pointer (and the guard after it).
        let s = unsafe {
            fill_one(&mut v, "fmi2GetStatus", "one value", STATUS_RULE2, |p| {
                self.answered(i, (self.fmu.api.get_status)(self.c, kind, p))
            })
        };
        (s, v)
    }

    /// fmi2GetIntegerStatus of `kind`: the status and the value.
    pub fn get_integer_status(&self, kind: fmi2StatusKind) -> (Status, fmi2Integer) {
        let mut v = 0;
        let i = self.record("fmi2GetIntegerStatus", vec![("kind", Val::Text(kind_name(kind)))]);
        // SAFETY: a valid out pointer (and the guard after it).
        let s = unsafe {
            fill_one(&mut v, "fmi2GetIntegerStatus", "one value", STATUS_RULE2, |p| {
                self.answered(i, (self.fmu.api.get_integer_status)(self.c, kind, p))
            })
        };
        (s, v)
    }

    /// fmi2GetStringStatus of `kind`: the status and the text (None for NULL).
    pub fn get_string_status(&self, kind: fmi2StatusKind) -> (Status, Option<String>) {
        let mut v: fmi2String = ptr::null();
        let i = self.record("fmi2GetStringStatus", vec![("kind", Val::Text(kind_name(kind)))]);
        // SAFETY: a valid out pointer (and the guard after it).
        let s = unsafe {
            fill_one(&mut v, "fmi2GetStringStatus", "one value", STATUS_RULE2, |p| {
                self.answered(i, (self.fmu.api.get_string_status)(self.c, kind, p))
            })
        };
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
            || format!("fmi2SerializeFMUstate with size = {size} (fmi2SerializedFMUstateSize's answer)"),
            STATE_RULE2,
        );
        (st, bytes)
    }
}
