//! FMI 3.0 calls the checks made through [`Inst::call`] without the arguments the call log
//! records, as [`Inst`] methods that record them, so that a failure in or after them leaves a
//! reproducer whose replay ([`crate::replay_calls`]) makes them again: fmi3GetFloat64 and
//! fmi3SetFloat64 with their arrays as given (NULL arrays, nValues other than the variables'
//! elements: the probes of an importer's mistakes, and no values with NULL arrays),
//! fmi3SetDebugLogging, fmi3GetBinary, fmi3GetNumberOfVariableDependencies and
//! fmi3GetVariableDependencies, fmi3DeserializeFMUState of NULL bytes, a model-exchange vector
//! into NULL, fmi3DoStep with NULL outputs, fmi3Get/AdjointDerivative with their counts as given
//! (a NULL seed, nSeed or nSensitivity other than the elements).

use super::Inst;
use super::types::*;
use crate::calllog::Val;
use crate::guard::{DEPENDENCIES_RULE3, GETTER_RULE3, fill, fill_one};
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
}
