//! Guard values after the arrays the suite hands an FMU to fill: a getter that writes one value
//! past `nValues`, or a serialized state longer than the size its FMU announced, overwrites
//! memory of the importer, which in a real importer corrupts the heap silently (or crashes far
//! from the call). Every output array of the common call paths (the getters of both versions,
//! model exchange's vectors, the serialized FMU state) is allocated with [`GUARD_BYTES`] more
//! bytes than the call is told, filled with [`GUARD_BYTE`]; after the call, a changed guard is
//! a failure naming the function and the array's length.
//!
//! The standard's requirement (a failure, not a warning): the array belongs to the importer and
//! has exactly the length the call names. FMI 2.0.5 §2.1.7 (fmi2GetReal/Integer/Boolean/String:
//! `value` is a vector of `nvr` values), §2.1.8 (fmi2SerializeFMUstate copies the state "into
//! the byte vector serializedState of length size, that must be provided by the environment",
//! size being what fmi2SerializedFMUstateSize returned), §3.2.2 (the model-exchange vectors of
//! `nx` and `ni` elements); FMI 3.0.2 "Getting and Setting Variable Values" (fmi3Get{VariableType}:
//! `nValues` is the size of the `values` array), "Getting and Setting the Complete FMU State"
//! (fmi3SerializeFMUState: the byte vector of length `size` the importer provides), and the
//! model-exchange chapter's vectors of `nContinuousStates` and `nEventIndicators` elements.

/// How many bytes (at least) follow each array: a whole number of its elements.
pub const GUARD_BYTES: usize = 64;

/// The elements of `T` the guard has.
fn guard_elements<T>() -> usize {
    GUARD_BYTES.div_ceil(std::mem::size_of::<T>().max(1))
}

/// The byte the guard is filled with (no FMU value is likely to be this pattern in every byte).
pub const GUARD_BYTE: u8 = 0xDB;

/// Element types any bit pattern is a valid value of (so that the guard's bytes may be written
/// into them): the values of the getters and the bytes of a serialized state.
pub trait Plain: Copy {}
impl Plain for f64 {}
impl Plain for f32 {}
impl Plain for i8 {}
impl Plain for u8 {}
impl Plain for i16 {}
impl Plain for u16 {}
impl Plain for i32 {}
impl Plain for u32 {}
impl Plain for i64 {}
impl Plain for u64 {}
impl Plain for usize {}
impl Plain for *const std::ffi::c_char {}
impl Plain for *const u8 {}
/// FMU states (an opaque pointer the FMU writes).
impl Plain for *mut std::ffi::c_void {}

/// An output array of `n` elements, followed by [`GUARD_BYTES`] bytes of guard.
pub struct Guarded<T: Plain> {
    buf: Vec<T>,
    /// The elements the call is told of.
    n: usize,
    /// Where the guard starts, in bytes from the array's start.
    end: usize,
}

impl<T: Plain> Guarded<T> {
    /// `n` elements of `fill`, then the guard.
    pub fn new(n: usize, fill: T) -> Guarded<T> {
        Guarded::guard_from(vec![fill; n + guard_elements::<T>()], n, n * std::mem::size_of::<T>())
    }

    /// `buf`, its bytes from `end` on made the guard.
    fn guard_from(mut buf: Vec<T>, n: usize, end: usize) -> Guarded<T> {
        let total = buf.len() * std::mem::size_of::<T>();
        // SAFETY: bytes `end..total` are in the buffer, and any bit pattern is a valid `T`
        // ([`Plain`]).
        unsafe {
            std::ptr::write_bytes(buf.as_mut_ptr().cast::<u8>().add(end), GUARD_BYTE, total - end);
        }
        Guarded { buf, n, end }
    }

    /// Where the FMU writes (the array's first element).
    pub fn as_mut_ptr(&mut self) -> *mut T {
        self.buf.as_mut_ptr()
    }

    /// The first bytes of the guard the call changed, if any: (index of the first changed byte
    /// after the array, how many bytes changed).
    fn overrun(&self) -> Option<(usize, usize)> {
        let total = self.buf.len() * std::mem::size_of::<T>();
        let bytes = self.buf.as_ptr().cast::<u8>();
        // SAFETY: the guard's bytes, in the buffer (`end` <= `total`, both in bytes of it).
        let guard = unsafe { std::slice::from_raw_parts(bytes.add(self.end), total - self.end) };
        let changed = guard.iter().filter(|b| **b != GUARD_BYTE).count();
        guard.iter().position(|b| *b != GUARD_BYTE).map(|at| (at, changed))
    }

    /// The offset of the last changed byte of the guard, if any.
    fn last_changed(&self) -> Option<usize> {
        let total = self.buf.len() * std::mem::size_of::<T>();
        let bytes = self.buf.as_ptr().cast::<u8>();
        // SAFETY: the guard's bytes, in the buffer (`end` <= `total`, both in bytes of it).
        let guard = unsafe { std::slice::from_raw_parts(bytes.add(self.end), total - self.end) };
        guard.iter().rposition(|b| *b != GUARD_BYTE)
    }

    /// The array's `n` values; panics (the check fails) when the FMU wrote into the guard.
    /// `call` names the function and its length argument (`fmi2GetReal with nvr = 3`), `rule`
    /// the standard's requirement ([`GETTER_RULE2`] and the like).
    pub fn into_values(self, call: impl FnOnce() -> String, rule: &str) -> Vec<T> {
        self.try_values(call, rule).unwrap_or_else(|e| panic!("{e}"))
    }

    /// [`Guarded::into_values`], the failure as an error.
    pub fn try_values(mut self, call: impl FnOnce() -> String, rule: &str) -> Result<Vec<T>, String> {
        if let Some((at, changed)) = self.overrun() {
            let size = std::mem::size_of::<T>().max(1);
            // How many values of the array's type the writes reached past its end (where the
            // array is a whole number of them).
            let values = if self.end == self.n * size {
                let last = self.last_changed().unwrap_or(at);
                format!(", as far as {} value(s) past the array's end", last / size + 1)
            } else {
                String::new()
            };
            return Err(format!(
                "{} wrote past the end of the array it was given: {changed} byte(s) of the guard after its {} \
                 byte(s) changed, the first at offset {at} past the end{values} ({rule})",
                call(),
                self.end
            ));
        }
        self.buf.truncate(self.n);
        Ok(self.buf)
    }
}

/// Hands the FMU `out` through `call` (which passes the pointer it is given to the function
/// under test as the array of `out.len()` elements), in a buffer with a guard after it, and
/// copies what the FMU wrote back into `out`. `function` and `count` name the function and its
/// length argument for the message (`fmi3GetClock`, `nValueReferences`), `rule` the standard's
/// requirement ([`GETTER_RULE3`] and the like). A guard the call overwrote fails the check; in a
/// call made as an importer's mistake on purpose ([`crate::outcome::on_purpose`]: NULL value
/// references, a wrong nValues, a variable through another type's getter) it is a warning, as
/// the standard leaves what the FMU does with such arguments undefined (FMI 2.0.5 §2.1.3, FMI
/// 3.0.2 §2.2.4), though writing past the array the importer gave corrupts the importer's memory.
pub fn fill<T: Plain, R>(out: &mut [T], function: &str, count: &str, rule: &str, call: impl FnOnce(*mut T) -> R) -> R {
    let n = out.len();
    let mut g = Guarded::guard_from(
        out.iter()
            .copied()
            .chain(std::iter::repeat_n(
                out.first().copied().unwrap_or_else(zeroed),
                guard_elements::<T>(),
            ))
            .collect(),
        n,
        std::mem::size_of_val(out),
    );
    let r = call(g.as_mut_ptr());
    let call = || {
        if count.starts_with("one ") {
            format!("{function}, given {count},")
        } else {
            format!("{function} with {count} = {n}")
        }
    };
    match g.try_values(call, rule) {
        Ok(v) => out.copy_from_slice(&v),
        Err(e) if crate::outcome::is_on_purpose() => crate::outcome::warn(on_purpose_overrun(&e)),
        Err(e) => panic!("{e}"),
    }
    r
}

/// Hands the FMU `N` one-byte output arguments (`flags`, fmi3Boolean) and one Float64 (`time`)
/// through `call`, each with a guard after it (the output arguments of fmi3DoStep and
/// fmi3UpdateDiscreteStates), and copies what it wrote back; a guard overwritten as in [`fill`].
pub fn fill_outputs<const N: usize, R>(
    function: &str,
    flags: &mut [u8; N],
    time: &mut f64,
    call: impl FnOnce([*mut u8; N], *mut f64) -> R,
) -> R {
    fill_one(
        time,
        function,
        "one Float64 output argument",
        OUTPUT_ARGUMENTS_RULE3,
        |t| {
            let mut guarded: [Guarded<u8>; N] = std::array::from_fn(|i| Guarded::new(1, flags[i]));
            let pointers = std::array::from_fn(|i| guarded[i].as_mut_ptr());
            let r = call(pointers, t);
            for (i, g) in guarded.into_iter().enumerate() {
                let what = || format!("{function}, given one Boolean as output argument {},", i + 1);
                match g.try_values(what, OUTPUT_ARGUMENTS_RULE3) {
                    Ok(v) => flags[i] = v[0],
                    Err(e) if crate::outcome::is_on_purpose() => crate::outcome::warn(on_purpose_overrun(&e)),
                    Err(e) => panic!("{e}"),
                }
            }
            r
        },
    )
}

/// The warning for an overrun in a call made as an importer's mistake on purpose.
fn on_purpose_overrun(e: &str) -> String {
    format!(
        "{e}; the call was an importer's mistake on purpose, whose outcome the standard leaves undefined, \
         but an FMU that writes past the array it is given corrupts the importer's memory"
    )
}

/// [`fill`] for one value (`x` is an array of one element).
pub fn fill_one<T: Plain, R>(x: &mut T, function: &str, count: &str, rule: &str, call: impl FnOnce(*mut T) -> R) -> R {
    fill(std::slice::from_mut(x), function, count, rule, call)
}

/// [`fill_one`] of the FMU state an FMI 2.0 call writes (fmi2GetFMUstate, fmi2FreeFMUstate, ...).
pub fn fill_state2<T: Plain, R>(st: &mut T, function: &str, call: impl FnOnce(*mut T) -> R) -> R {
    fill_one(st, function, "one FMU state", STATE_RULE2, call)
}

/// [`fill_one`] of the FMU state an FMI 3.0 call writes (fmi3GetFMUState, fmi3FreeFMUState, ...).
pub fn fill_state3<T: Plain, R>(st: &mut T, function: &str, call: impl FnOnce(*mut T) -> R) -> R {
    fill_one(st, function, "one FMU state", STATE_RULE3, call)
}

/// [`fill_one`] of the size fmi2SerializedFMUstateSize writes.
pub fn fill_state_size2<R>(size: &mut usize, function: &str, call: impl FnOnce(*mut usize) -> R) -> R {
    fill_one(size, function, "one size_t", STATE_RULE2, call)
}

/// [`fill_one`] of the size fmi3SerializedFMUStateSize writes.
pub fn fill_state_size3<R>(size: &mut usize, function: &str, call: impl FnOnce(*mut usize) -> R) -> R {
    fill_one(size, function, "one size_t", STATE_RULE3, call)
}

/// [`fill_one`] of the value an FMI 2.0 status getter writes (fmi2GetStatus, fmi2GetRealStatus, ...).
pub fn fill_status2<T: Plain, R>(value: &mut T, function: &str, call: impl FnOnce(*mut T) -> R) -> R {
    fill_one(value, function, "one value", STATUS_RULE2, call)
}

/// fmi3CompletedIntegratorStep's outputs enterEventMode and terminateSimulation, one value each
/// with a guard after it: `call` gets the pointers to `enter` and `term`.
pub fn fill_integrator_step3<T: Plain, R>(enter: &mut T, term: &mut T, call: impl FnOnce(*mut T, *mut T) -> R) -> R {
    fill_one(
        enter,
        "fmi3CompletedIntegratorStep (enterEventMode)",
        "one value",
        OUTPUT_ARGUMENTS_RULE3,
        |qa| {
            fill_one(
                term,
                "fmi3CompletedIntegratorStep (terminateSimulation)",
                "one value",
                OUTPUT_ARGUMENTS_RULE3,
                |qb| call(qa, qb),
            )
        },
    )
}

/// A `T` of zero bytes (any bit pattern is a valid [`Plain`] value).
fn zeroed<T: Plain>() -> T {
    // SAFETY: any bit pattern, zero included, is a valid `T` ([`Plain`]).
    unsafe { std::mem::zeroed() }
}

impl Guarded<u64> {
    /// `bytes` bytes in 8-byte aligned memory (values of any type, as [`crate::fmi3::Inst::get_raw`]
    /// reads them), then the guard; [`Guarded::into_values`] gives the words that hold them.
    pub fn aligned_bytes(bytes: usize) -> Guarded<u64> {
        let words = bytes.div_ceil(8);
        Guarded::guard_from(vec![0; words + guard_elements::<u64>()], words, bytes)
    }
}

/// FMI 2.0.5's requirement for the getters and the model-exchange vectors.
pub const GETTER_RULE2: &str =
    "FMI 2.0.5 §2.1.7 and §3.2.2: the array the importer provides has exactly the number of elements the call names";
/// FMI 3.0.2's requirement for the getters and the model-exchange vectors.
pub const GETTER_RULE3: &str = "FMI 3.0.2, Getting and Setting Variable Values (and the model-exchange vectors): nValues (nContinuousStates, \
     nEventIndicators) is the size of the array the importer provides";
/// FMI 3.0.2's requirement for fmi3GetNumberOfContinuousStates and
/// fmi3GetNumberOfEventIndicators: the number, through one size_t.
pub const COUNT_RULE3: &str = "FMI 3.0.2 (Model Exchange): fmi3GetNumberOfContinuousStates and \
     fmi3GetNumberOfEventIndicators return the number through the one size_t the importer's pointer holds";
/// FMI 2.0.5's requirement for the status getters (fmi2GetStatus, fmi2GetRealStatus, ...): one
/// value at the pointer `value`.
pub const STATUS_RULE2: &str =
    "FMI 2.0.5 §4.2.3: fmi2Get*Status returns one value, through the pointer `value` the importer provides";
/// FMI 3.0.2's requirement for the clock getters (fmi3GetClock, fmi3GetInterval*, fmi3GetShift*).
pub const CLOCK_RULE3: &str = "FMI 3.0.2 §2.2.9 (Clocks): fmi3GetClock, fmi3GetInterval* and fmi3GetShift* fill arrays of \
     nValueReferences elements (nValues for fmi3GetClock) that the importer provides";
/// FMI 3.0.2's requirement for fmi3GetVariableDependencies and its count.
pub const DEPENDENCIES_RULE3: &str = "FMI 3.0.2 §2.2.10: fmi3GetVariableDependencies fills arrays of nDependencies elements, \
     the number fmi3GetNumberOfVariableDependencies returned (which it writes to one size_t)";
/// FMI 3.0.2's requirement for the output arguments of fmi3DoStep and fmi3UpdateDiscreteStates:
/// one value each.
pub const OUTPUT_ARGUMENTS_RULE3: &str = "FMI 3.0.2 (fmi3DoStep in the Co-Simulation chapter, \
     fmi3UpdateDiscreteStates in the common Event Mode functions): each output argument is one value at the pointer the \
     importer provides";
/// FMI 2.0.5's requirement for fmi2SerializeFMUstate.
pub const STATE_RULE2: &str = "FMI 2.0.5 §2.1.8: fmi2SerializeFMUstate copies the state \"into the byte vector \
     serializedState of length size, that must be provided by the environment\", size being what \
     fmi2SerializedFMUstateSize returned";
/// FMI 3.0.2's requirement for fmi3SerializeFMUState.
pub const STATE_RULE3: &str = "FMI 3.0.2, Getting and Setting the Complete FMU State: fmi3SerializeFMUState copies the state into the byte vector \
     serializedState of length size that the importer provides, size being what fmi3SerializedFMUStateSize returned";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_array_written_within_its_length_comes_back_whole() {
        let mut g = Guarded::new(3, 0.0f64);
        // SAFETY: three elements of the array.
        unsafe { std::ptr::copy_nonoverlapping([1.0, 2.0, 3.0].as_ptr(), g.as_mut_ptr(), 3) };
        assert_eq!(g.into_values(|| "f".into(), "rule"), vec![1.0, 2.0, 3.0]);
    }

    #[test]
    fn one_value_past_the_end_fails_naming_the_call_and_the_rule() {
        let mut g = Guarded::new(2, 0.0f64);
        // SAFETY: the first guard element, inside the buffer.
        unsafe { *g.as_mut_ptr().add(2) = 1.0 };
        let e = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            g.into_values(|| "fmi2GetReal with nvr = 2".into(), GETTER_RULE2)
        }))
        .unwrap_err();
        let m = e.downcast_ref::<String>().unwrap();
        assert!(m.contains("fmi2GetReal with nvr = 2 wrote past the end"), "{m}");
        assert!(m.contains("FMI 2.0.5 §2.1.7"), "{m}");
    }

    #[test]
    fn fill_fails_an_overrun_and_warns_of_one_made_on_purpose() {
        use crate::outcome::{Outcome, capture, on_purpose};
        // SAFETY: one element past the array, inside the guard (what the closures below write).
        let overrun = |p: *mut f64| unsafe { *p.add(1) = 1.0 };
        let (o, _) = capture(|| fill(&mut [0.0], "fmi2GetReal", "nvr", GETTER_RULE2, overrun));
        assert!(
            matches!(&o, Outcome::Fail(m) if m.contains("fmi2GetReal with nvr = 1 wrote past the end")
                && m.contains("as far as 1 value(s) past")),
            "{o:?}"
        );
        let (o, _) = capture(|| on_purpose(|| fill(&mut [0.0], "fmi2GetReal", "nvr", GETTER_RULE2, overrun)));
        assert!(
            matches!(&o, Outcome::Warn(m) if m.contains("importer's mistake on purpose")),
            "{o:?}"
        );
        let mut x = 0.0;
        // SAFETY: the one value the pointer holds.
        fill_one(&mut x, "f", "one value", "r", |p| unsafe { *p = 2.0 });
        assert_eq!(x, 2.0);
        let (mut flags, mut t) = ([0u8; 2], 0.0);
        // SAFETY: the output arguments, one value each.
        fill_outputs("fmi3DoStep", &mut flags, &mut t, |[a, b], l| unsafe {
            (*a, *b, *l) = (1, 0, 0.5)
        });
        assert_eq!((flags, t), ([1, 0], 0.5));
    }

    #[test]
    fn an_empty_array_has_its_guard_too() {
        let mut g = Guarded::<u8>::new(0, 0);
        // SAFETY: the first guard byte.
        unsafe { *g.as_mut_ptr() = 7 };
        let e = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| g.into_values(|| "f".into(), "r")));
        assert!(e.is_err());
    }

    #[test]
    fn aligned_bytes_are_guarded_from_their_last_byte_on() {
        let mut g = Guarded::aligned_bytes(3);
        // SAFETY: the three bytes of the array.
        unsafe { std::ptr::write_bytes(g.as_mut_ptr().cast::<u8>(), 1, 3) };
        assert_eq!(g.into_values(|| "f".into(), "r")[0].to_ne_bytes()[..3], [1, 1, 1]);
        let mut g = Guarded::aligned_bytes(3);
        // SAFETY: the fourth byte, the guard's first.
        unsafe { *g.as_mut_ptr().cast::<u8>().add(3) = 1 };
        let e = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| g.into_values(|| "f".into(), "r")));
        assert!(e.is_err());
    }
}
