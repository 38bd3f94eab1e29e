//! FMI 3.0 calls the checks made through [`Inst::call`] without the arguments the call log
//! records, as [`Inst`] methods that record them, so that a failure in or after them leaves a
//! reproducer whose replay ([`crate::replay_calls`]) makes them again: fmi3GetFloat64 and
//! fmi3SetFloat64 with their arrays as given (NULL arrays, nValues other than the variables'
//! elements: the probes of an importer's mistakes, and no values with NULL arrays),
//! fmi3SetDebugLogging, fmi3GetBinary, fmi3GetNumberOfVariableDependencies and
//! fmi3GetVariableDependencies, fmi3DeserializeFMUState of NULL bytes, a model-exchange vector
//! into NULL, fmi3DoStep with NULL outputs, fmi3Get/AdjointDerivative with their counts as given
//! (a NULL seed, nSeed or nSensitivity other than the elements); and the checks' own valid calls
//! that had no wrapper: fmi3GetOutputDerivatives, the FMU-state calls, fmi3ActivateModelPartition,
//! and the state table's getters and setters of no variable.

use super::Inst;
use super::types::*;
use crate::calllog::Val;
use crate::guard::{DEPENDENCIES_RULE3, GETTER_RULE3, Guarded, fill, fill_one};
use std::ffi::CString;
use std::ptr::{null, null_mut};

/// An array argument as the call log writes it: its values, or NULL.
fn arg<T: Clone>(a: Option<&[T]>, of: impl FnOnce(Vec<T>) -> Val) -> Val {
    a.map_or(Val::Null, |a| of(a.to_vec()))
}

fn ptr_of<T>(a: Option<&[T]>) -> *const T {
    a.map_or(null(), <[T]>::as_ptr)
}

/// What fmi3GetVariableDependencies wrote: elementIndicesOfDependent, independents,
/// elementIndicesOfIndependents, dependencyKinds.
pub type Dependencies = (Vec<usize>, Vec<u32>, Vec<usize>, Vec<u32>);

impl Inst<'_> {
    /// fmi3GetFloat64 (`set` false) or fmi3SetFloat64 with its arguments as given: `vr` (None:
    /// NULL), nValueReferences `n_vr`, the values (a getter's: `Some` is a buffer of `n_values`
    /// zeros with a guard after it; a setter's: those values) or NULL, and nValues `n_values`.
    /// Recorded as `fmi3GetFloat64 vr=NULL nValueReferences=1 nValues=1` (`values=NULL`, a
    /// setter's `values=[...]`).
    pub fn float64_probe(
        &self,
        set: bool,
        vr: Option<&[u32]>,
        n_vr: usize,
        values: Option<&[f64]>,
        n_values: usize,
    ) -> fmi3Status {
        assert!(
            vr.is_none_or(|v| v.len() >= n_vr),
            "a vr array shorter than nValueReferences"
        );
        let mut args = vec![("vr", arg(vr, Val::U32s)), ("nValueReferences", Val::U64(n_vr as u64))];
        if set || values.is_none() {
            args.push(("values", arg(values, Val::F64s)));
        }
        args.push(("nValues", Val::U64(n_values as u64)));
        let api = self.api();
        let v = ptr_of(vr);
        if set {
            assert!(values.is_none_or(|x| x.len() >= n_values), "fewer values than nValues");
            let x = ptr_of(values);
            // SAFETY: `v` and `x` hold the counts passed, or are NULL on purpose (the FMU must
            // check before reading).
            return self.args(args).call("fmi3SetFloat64", |c| unsafe {
                (api.set_float64)(c, v, n_vr, x, n_values)
            });
        }
        match values {
            Some(_) => {
                let mut out = vec![0.0; n_values];
                // SAFETY: `v` holds nValueReferences value references or is NULL on purpose;
                // `out` holds nValues values (and the guard after them).
                self.args(args).call("fmi3GetFloat64", |c| unsafe {
                    fill(&mut out, "fmi3GetFloat64", "nValues", GETTER_RULE3, |p| {
                        (api.get_float64)(c, v, n_vr, p, n_values)
                    })
                })
            }
            // SAFETY: NULL values on purpose (or with nValues = 0): the FMU must check first.
            None => self.args(args).call("fmi3GetFloat64", |c| unsafe {
                (api.get_float64)(c, v, n_vr, null_mut(), n_values)
            }),
        }
    }

    /// fmi3SetDebugLogging with nCategories `n` and `categories` as given (None: NULL).
    /// Recorded as `fmi3SetDebugLogging loggingOn=true nCategories=1 categories=NULL` (or
    /// `categories=[logEvents,...]`).
    pub fn set_debug_logging(&self, on: bool, n: usize, categories: Option<&[String]>) -> fmi3Status {
        let owned: Option<Vec<CString>> = categories.map(|cs| {
            cs.iter()
                .map(|c| CString::new(c.as_str()).unwrap_or_default())
                .collect()
        });
        let ptrs: Option<Vec<fmi3String>> = owned.as_ref().map(|cs| cs.iter().map(|c| c.as_ptr()).collect());
        assert!(
            ptrs.as_ref().is_none_or(|p| p.len() >= n),
            "fewer categories than nCategories"
        );
        let p = ptrs.as_ref().map_or(null(), |p| p.as_ptr());
        let api = self.api();
        self.args(vec![
            ("loggingOn", Val::Bool(on)),
            ("nCategories", Val::U64(n as u64)),
            ("categories", categories.map_or(Val::Null, |c| Val::Texts(c.to_vec()))),
        ])
        // SAFETY: `p` holds n strings or is NULL (with n = 0, or on purpose: the FMU must check).
        .call("fmi3SetDebugLogging", |c| unsafe {
            (api.set_debug_logging)(c, on, n, p)
        })
    }

    /// fmi3GetBinary of `vr` with nValues `n`, each output array with a guard after it: the
    /// status, the sizes and the values' bytes (empty where the FMU answered no value).
    /// Recorded as `fmi3GetBinary vr=[1] nValues=1`.
    pub fn get_binary(&self, vr: &[u32], n: usize) -> (fmi3Status, Vec<usize>, Vec<Vec<u8>>) {
        let api = self.api();
        let (mut sizes, mut data) = (vec![0usize; n], vec![null::<u8>(); n]);
        let s = self
            .args(vec![("vr", Val::U32s(vr.to_vec())), ("nValues", Val::U64(n as u64))])
            // SAFETY: a live instance; `vr` and the outputs hold the counts passed (each output
            // with a guard after it).
            .call("fmi3GetBinary", |c| unsafe {
                fill(
                    &mut sizes,
                    "fmi3GetBinary (valueSizes)",
                    "nValues",
                    GETTER_RULE3,
                    |ps| {
                        fill(&mut data, "fmi3GetBinary (values)", "nValues", GETTER_RULE3, |pd| {
                            (api.get_binary)(c, vr.as_ptr(), vr.len(), ps, pd, n)
                        })
                    },
                )
            });
        let bytes = sizes
            .iter()
            .zip(&data)
            .map(|(size, p)| {
                if s == fmi3OK && !p.is_null() {
                    // SAFETY: the FMU's answer: `size` bytes at `p`, valid until its next call.
                    unsafe { std::slice::from_raw_parts(*p, *size) }.to_vec()
                } else {
                    vec![]
                }
            })
            .collect();
        (s, sizes, bytes)
    }

    /// fmi3GetNumberOfVariableDependencies of `dependent`: the status and the count (usize::MAX
    /// where the FMU wrote none). Recorded as `fmi3GetNumberOfVariableDependencies dependent=5`.
    pub fn number_of_dependencies(&self, dependent: u32) -> (fmi3Status, usize) {
        let api = self.api();
        let mut count = usize::MAX;
        let s = self
            .args(vec![("dependent", Val::U64(u64::from(dependent)))])
            // SAFETY: a live instance; one size_t with a guard after it.
            .call("fmi3GetNumberOfVariableDependencies", |c| unsafe {
                fill_one(
                    &mut count,
                    "fmi3GetNumberOfVariableDependencies",
                    "one nDependencies",
                    DEPENDENCIES_RULE3,
                    |p| (api.get_number_of_variable_dependencies)(c, dependent, p),
                )
            });
        (s, count)
    }

    /// fmi3GetVariableDependencies of `dependent` into arrays of `n` elements, each with a guard
    /// after it. Recorded as `fmi3GetVariableDependencies dependent=5 nDependencies=2`.
    pub fn dependencies(&self, dependent: u32, n: usize) -> (fmi3Status, Dependencies) {
        let api = self.api();
        let (mut e_dep, mut ind, mut e_ind, mut kinds) =
            (vec![9usize; n], vec![0u32; n], vec![9usize; n], vec![99u32; n]);
        let s = self
            .args(vec![
                ("dependent", Val::U64(u64::from(dependent))),
                ("nDependencies", Val::U64(n as u64)),
            ])
            // SAFETY: a live instance; four arrays of n elements, each with a guard after it.
            .call("fmi3GetVariableDependencies", |c| unsafe {
                let (f, r) = ("fmi3GetVariableDependencies", DEPENDENCIES_RULE3);
                fill(&mut e_dep, f, "nDependencies (elementIndicesOfDependent)", r, |a| {
                    fill(&mut ind, f, "nDependencies (independents)", r, |b| {
                        fill(&mut e_ind, f, "nDependencies (elementIndicesOfIndependents)", r, |d| {
                            fill(&mut kinds, f, "nDependencies (dependencyKinds)", r, |k| {
                                (api.get_variable_dependencies)(c, dependent, a, b, d, k, n)
                            })
                        })
                    })
                })
            });
        (s, (e_dep, ind, e_ind, kinds))
    }

    /// fmi3GetContinuousStates (or another model-exchange vector `what`, `f`) into NULL with
    /// `n` values. Recorded as `fmi3GetContinuousStateDerivatives n=1 values=NULL`.
    pub fn vector_null(&self, what: &str, f: super::api::Vector, n: usize) -> fmi3Status {
        self.args(vec![("n", Val::U64(n as u64)), ("values", Val::Null)])
            // SAFETY: NULL on purpose (with n > 0): the FMU must check before writing.
            .call(what, |c| unsafe { f(c, null_mut(), n) })
    }

    /// fmi3DoStep from `t` of `h` with NULL output pointers (noSetFMUStatePriorToCurrentPoint
    /// true). Recorded as `fmi3DoStep currentCommunicationPoint=0.0 communicationStepSize=0.1
    /// outputs=NULL`.
    pub fn do_step_null_outputs(&self, t: f64, h: f64) -> fmi3Status {
        let api = self.api();
        self.args(vec![
            ("currentCommunicationPoint", Val::F64(t)),
            ("communicationStepSize", Val::F64(h)),
            ("outputs", Val::Null),
        ])
        // SAFETY: NULL output pointers on purpose: the FMU must not write through them.
        .call("fmi3DoStep", |c| unsafe {
            (api.do_step)(c, t, h, true, null_mut(), null_mut(), null_mut(), null_mut())
        })
    }

    /// fmi3DeserializeFMUState of NULL bytes with the size `size`, into one FMU state with a
    /// guard after it (the state it made, if any, left to the instance). Recorded as
    /// `fmi3DeserializeFMUState bytes=NULL size=64`.
    pub fn deserialize_null(&self, size: usize) -> fmi3Status {
        let api = self.api();
        let mut st: fmi3FMUState = null_mut();
        self.args(vec![("bytes", Val::Null), ("size", Val::U64(size as u64))])
            // SAFETY: NULL bytes with a size on purpose: the FMU must refuse without reading
            // them; `st` is a live local with a guard after it.
            .call("fmi3DeserializeFMUState", |c| unsafe {
                crate::guard::fill_state3(&mut st, "fmi3DeserializeFMUState", |q| {
                    (api.deserialize_fmu_state)(c, null(), size, q)
                })
            })
    }

    /// fmi3GetDirectionalDerivative, or (`adjoint`) fmi3GetAdjointDerivative, with every count
    /// as given: `unknowns` (nUnknowns their length), `knowns`, the seed (None: NULL) with
    /// nSeed `n_seed`, and nSensitivity `n_sensitivity` values (a guard after them). Recorded
    /// as `fmi3GetDirectionalDerivative unknowns=[1] knowns=[0] seed=NULL nSeed=1
    /// nSensitivity=1`.
    pub fn derivative_probe(
        &self,
        adjoint: bool,
        unknowns: &[u32],
        knowns: &[u32],
        seed: Option<&[f64]>,
        n_seed: usize,
        n_sensitivity: usize,
    ) -> fmi3Status {
        assert!(seed.is_none_or(|x| x.len() >= n_seed), "a seed shorter than nSeed");
        let api = self.api();
        let (what, f) = if adjoint {
            ("fmi3GetAdjointDerivative", api.get_adjoint_derivative)
        } else {
            ("fmi3GetDirectionalDerivative", api.get_directional_derivative)
        };
        let mut out = vec![0.0; n_sensitivity];
        let p = ptr_of(seed);
        self.args(vec![
            ("unknowns", Val::U32s(unknowns.to_vec())),
            ("knowns", Val::U32s(knowns.to_vec())),
            ("seed", arg(seed.map(|x| &x[..n_seed]), Val::F64s)),
            ("nSeed", Val::U64(n_seed as u64)),
            ("nSensitivity", Val::U64(n_sensitivity as u64)),
        ])
        // SAFETY: each array holds the count passed (the seed may be NULL on purpose: the FMU
        // must check); the sensitivity has a guard after it.
        .call(what, |c| unsafe {
            fill(&mut out, what, "nSensitivity", GETTER_RULE3, |q| {
                f(
                    c,
                    unknowns.as_ptr(),
                    unknowns.len(),
                    knowns.as_ptr(),
                    knowns.len(),
                    p,
                    n_seed,
                    q,
                    n_sensitivity,
                )
            })
        })
    }

    /// fmi3GetOutputDerivatives of `vrs` with `orders`, into as many values with a guard after
    /// them: the status and the values. Recorded as `fmi3GetOutputDerivatives vr=[3] order=[1]`.
    pub fn get_output_derivatives(&self, vrs: &[u32], orders: &[i32]) -> (fmi3Status, Vec<f64>) {
        assert_eq!(vrs.len(), orders.len(), "one order for each value reference");
        let api = self.api();
        let n = vrs.len();
        let mut out = Guarded::new(n, f64::NAN);
        let p = out.as_mut_ptr();
        let s = self
            .args(vec![
                ("vr", Val::U32s(vrs.to_vec())),
                ("order", Val::I64s(orders.iter().map(|o| i64::from(*o)).collect())),
            ])
            // SAFETY: a live instance; `vrs` and `orders` hold n elements, `p` n values (and the
            // guard after them).
            .call("fmi3GetOutputDerivatives", |c| unsafe {
                (api.get_output_derivatives)(c, vrs.as_ptr(), n, orders.as_ptr(), p, n)
            });
        (
            s,
            out.into_values(|| format!("fmi3GetOutputDerivatives with nValues = {n}"), GETTER_RULE3),
        )
    }

    /// fmi3GetFMUState into `st` (NULL: a new state; else the state it holds, which the FMU
    /// updates), with a guard after the pointer. Recorded as `fmi3GetFMUState state=N` (N the
    /// state it made), or `fmi3GetFMUState into=N` (`state=M` added where the FMU answered
    /// another state than it was given).
    pub fn get_state(&self, st: &mut fmi3FMUState) -> fmi3Status {
        let api = self.api();
        let given = *st;
        if given.is_null() {
            self.args(vec![]);
        } else if let Some(v) = self.state_val(given, false) {
            self.args(vec![("into", v)]);
        }
        // SAFETY: a live instance; `st` is NULL or a state it made, with a guard after it.
        let s = self.call("fmi3GetFMUState", |c| unsafe {
            crate::guard::fill_state3(st, "fmi3GetFMUState", |q| (api.get_fmu_state)(c, q))
        });
        if !st.is_null()
            && *st != given
            && let Some(v) = self.state_val(*st, true)
        {
            self.output("state", v);
        }
        s
    }

    /// fmi3SetFMUState of `st`. Recorded as `fmi3SetFMUState state=N` (without arguments, not
    /// replayable, for a state another instance made).
    // The harness passes FMU states through to the FMU as an importer does; checking them is the
    // FMU's job, which is what the checks test (as `Instance::set_state`).
    #[allow(clippy::not_unsafe_ptr_arg_deref)]
    pub fn set_state(&self, st: fmi3FMUState) -> fmi3Status {
        let api = self.api();
        self.state_args(st, vec![])
            // SAFETY: a live instance and an FMU state of this FMU (or NULL, which it must refuse).
            .call("fmi3SetFMUState", |c| unsafe { (api.set_fmu_state)(c, st) })
    }

    /// fmi3FreeFMUState of `st` (which the FMU sets to NULL), with a guard after the pointer.
    /// Recorded as `fmi3FreeFMUState state=N`.
    pub fn free_state(&self, st: &mut fmi3FMUState) -> fmi3Status {
        let api = self.api();
        let given = *st;
        // SAFETY: a live instance; `st` is NULL or a state it made, freed once, with a guard
        // after it.
        self.state_args(given, vec![]).call("fmi3FreeFMUState", |c| unsafe {
            crate::guard::fill_state3(st, "fmi3FreeFMUState", |q| (api.free_fmu_state)(c, q))
        })
    }

    /// fmi3DeserializeFMUState of `bytes` into `st`, with a guard after the pointer. Recorded as
    /// `fmi3DeserializeFMUState bytes=hex:... state=N`.
    pub fn deserialize(&self, bytes: &[u8], st: &mut fmi3FMUState) -> fmi3Status {
        let api = self.api();
        let s = self
            .args(vec![("bytes", Val::Bytes(bytes.to_vec()))])
            // SAFETY: a live instance; `bytes` is readable for the length passed; `st` a live
            // local with a guard after it.
            .call("fmi3DeserializeFMUState", |c| unsafe {
                crate::guard::fill_state3(st, "fmi3DeserializeFMUState", |q| {
                    (api.deserialize_fmu_state)(c, bytes.as_ptr(), bytes.len(), q)
                })
            });
        if let Some(v) = self.state_val(*st, true) {
            self.output("state", v);
        }
        s
    }

    /// fmi3ActivateModelPartition of the clock `clock` at `time`. Recorded as
    /// `fmi3ActivateModelPartition clockReference=0 activationTime=0.0`.
    pub fn activate_model_partition(&self, clock: u32, time: f64) -> fmi3Status {
        let api = self.api();
        self.args(vec![
            ("clockReference", Val::U64(u64::from(clock))),
            ("activationTime", Val::F64(time)),
        ])
        // SAFETY: a live instance; no pointer.
        .call("fmi3ActivateModelPartition", |c| unsafe {
            (api.activate_model_partition)(c, clock, time)
        })
    }

    /// `function` ([`crate::replay::fmi3::takes_no_variable`]: a getter or setter of values, clocks, intervals or
    /// shifts) of no variable: every array NULL, nValueReferences and nValues 0
    /// (the state table's valid call of it). Recorded as `fmi3GetUInt16 vr=NULL
    /// nValueReferences=0 values=NULL nValues=0`; None for another function.
    pub fn with_no_variable(&self, function: &str) -> Option<fmi3Status> {
        let f = crate::replay::fmi3::takes_no_variable(function)?;
        let a = self.api();
        let (v, z) = (null(), null_mut());
        self.args(vec![
            ("vr", Val::Null),
            ("nValueReferences", Val::U64(0)),
            ("values", Val::Null),
            ("nValues", Val::U64(0)),
        ]);
        // SAFETY: every array NULL with a count of 0: the FMU reads and writes none of them.
        Some(self.call(f, |c| unsafe {
            match f {
                "fmi3GetFloat32" => (a.get_float32)(c, v, 0, z, 0),
                "fmi3GetFloat64" => (a.get_float64)(c, v, 0, null_mut(), 0),
                "fmi3GetInt8" => (a.get_int8)(c, v, 0, z, 0),
                "fmi3GetUInt8" => (a.get_uint8)(c, v, 0, z, 0),
                "fmi3GetInt16" => (a.get_int16)(c, v, 0, z, 0),
                "fmi3GetUInt16" => (a.get_uint16)(c, v, 0, z, 0),
                "fmi3GetInt32" => (a.get_int32)(c, v, 0, null_mut(), 0),
                "fmi3GetUInt32" => (a.get_uint32)(c, v, 0, z, 0),
                "fmi3GetInt64" => (a.get_int64)(c, v, 0, null_mut(), 0),
                "fmi3GetUInt64" => (a.get_uint64)(c, v, 0, z, 0),
                "fmi3GetBoolean" => (a.get_boolean)(c, v, 0, null_mut(), 0),
                "fmi3GetString" => (a.get_string)(c, v, 0, null_mut(), 0),
                "fmi3GetBinary" => (a.get_binary)(c, v, 0, null_mut(), null_mut(), 0),
                "fmi3GetClock" => (a.get_clock)(c, v, 0, null_mut()),
                "fmi3SetFloat32" => (a.set_float32)(c, v, 0, null(), 0),
                "fmi3SetFloat64" => (a.set_float64)(c, v, 0, null(), 0),
                "fmi3SetInt8" => (a.set_int8)(c, v, 0, null(), 0),
                "fmi3SetUInt8" => (a.set_uint8)(c, v, 0, null(), 0),
                "fmi3SetInt16" => (a.set_int16)(c, v, 0, null(), 0),
                "fmi3SetUInt16" => (a.set_uint16)(c, v, 0, null(), 0),
                "fmi3SetInt32" => (a.set_int32)(c, v, 0, null(), 0),
                "fmi3SetUInt32" => (a.set_uint32)(c, v, 0, null(), 0),
                "fmi3SetInt64" => (a.set_int64)(c, v, 0, null(), 0),
                "fmi3SetUInt64" => (a.set_uint64)(c, v, 0, null(), 0),
                "fmi3SetBoolean" => (a.set_boolean)(c, v, 0, null(), 0),
                "fmi3SetString" => (a.set_string)(c, v, 0, null(), 0),
                "fmi3SetBinary" => (a.set_binary)(c, v, 0, null(), null(), 0),
                "fmi3SetClock" => (a.set_clock)(c, v, 0, null()),
                "fmi3GetIntervalDecimal" => (a.get_interval_decimal)(c, v, 0, null_mut(), null_mut()),
                "fmi3GetIntervalFraction" => (a.get_interval_fraction)(c, v, 0, null_mut(), null_mut(), null_mut()),
                "fmi3GetShiftDecimal" => (a.get_shift_decimal)(c, v, 0, null_mut()),
                "fmi3GetShiftFraction" => (a.get_shift_fraction)(c, v, 0, null_mut(), null_mut()),
                "fmi3SetIntervalDecimal" => (a.set_interval_decimal)(c, v, 0, null()),
                "fmi3SetIntervalFraction" => (a.set_interval_fraction)(c, v, 0, null(), null()),
                "fmi3SetShiftDecimal" => (a.set_shift_decimal)(c, v, 0, null()),
                "fmi3SetShiftFraction" => (a.set_shift_fraction)(c, v, 0, null(), null()),
                other => unreachable!("{other} is a getter or setter takes_no_variable knows"),
            }
        }))
    }
}
