//! The dependency checks' way into a library through FMI 2.0 ([`Api`], a [`Probe`]): fresh
//! instances of the conformance suite's table of FMI 2.0 functions, the model-exchange Jacobian
//! by `fmi2GetDirectionalDerivative`, the initial unknowns after Initialization Mode. Also the
//! default experiment's plot's way into a library ([`crate::plot`]).

use crate::depends::{
    Known, Point, Probe, Report, Rng, by_columns, check_initial_with, check_with, spread_by, start_of, states,
};
use fmi_conformance::fmi2::*;
use rustfmu::description::{ModelDescription, VarType, Variable};
use std::ffi::CString;
use std::path::Path;

/// A loaded rustfmu library for the checks (and the default experiment's plot): the conformance
/// suite's table of FMI 2.0 functions ([`fmi_conformance::Api`]), the interface instances are
/// made for, and fmi2Instantiate's GUID and resource location.
pub(crate) struct Api {
    pub(crate) fmi: fmi_conformance::Api,
    /// Model exchange when asked for (and exported), else co-simulation.
    kind: fmi2Type,
    guid: CString,
    location: CString,
}

impl Api {
    pub(crate) fn load(so: &Path, model_exchange: bool, guid: &str, resource_uri: &str) -> Result<Api, String> {
        let fmi = fmi_conformance::Api::load(so)?;
        if model_exchange && let Err(e) = &fmi.me {
            return Err(format!("the library has no model exchange: {e}"));
        }
        Ok(Api {
            fmi,
            kind: if model_exchange {
                fmi2ModelExchange
            } else {
                fmi2CoSimulation
            },
            guid: CString::new(guid).unwrap_or_default(),
            location: CString::new(resource_uri).unwrap_or_default(),
        })
    }

    /// Sets a Real, Integer, enumeration or Boolean variable (a Boolean from 0 or 1).
    ///
    /// # Safety
    /// `c` is a live instance of this library.
    pub(crate) unsafe fn set(&self, c: fmi2Component, v: &Variable, x: f64) -> fmi2Status {
        let vr = [v.value_reference];
        // SAFETY: one value reference, one value.
        unsafe {
            match v.var_type {
                VarType::Real => (self.fmi.set_real)(c, vr.as_ptr(), 1, [x].as_ptr()),
                VarType::Boolean => (self.fmi.set_boolean)(
                    c,
                    vr.as_ptr(),
                    1,
                    [if x != 0.0 { fmi2True } else { fmi2False }].as_ptr(),
                ),
                _ => (self.fmi.set_integer)(c, vr.as_ptr(), 1, [x as i32].as_ptr()),
            }
        }
    }

    /// Sets `values`, then enters and leaves Initialization Mode; a value the model refuses is
    /// said as `setting(v, x)` says it.
    ///
    /// # Safety
    /// `c` is a live instance of this library, set up (fmi2SetupExperiment) and not initialized.
    pub(crate) unsafe fn initialize<'v>(
        &self,
        c: fmi2Component,
        ok: &dyn Fn(fmi2Status, &str) -> Result<(), String>,
        values: impl IntoIterator<Item = (&'v Variable, f64)>,
        setting: impl Fn(&Variable, f64) -> String,
    ) -> Result<(), String> {
        // SAFETY: `c` is live (the caller's promise); each call passes only values.
        unsafe {
            for (v, x) in values {
                ok(self.set(c, v, x), &setting(v, x))?;
            }
            ok((self.fmi.enter_initialization_mode)(c), "fmi2EnterInitializationMode")?;
            ok((self.fmi.exit_initialization_mode)(c), "fmi2ExitInitializationMode")
        }
    }

    /// Runs `body` on a fresh instance set up for t = 0, freeing it afterwards.
    fn with_instance<T>(
        &self,
        body: impl FnOnce(fmi2Component, &dyn Fn(fmi2Status, &str) -> Result<(), String>) -> Result<T, String>,
    ) -> Result<T, String> {
        self.with_instance_at(0.0, None, body)
    }

    /// [`Self::with_instance`] set up for `start` (and a stop time, when given).
    pub(crate) fn with_instance_at<T>(
        &self,
        start: f64,
        stop: Option<f64>,
        body: impl FnOnce(fmi2Component, &dyn Fn(fmi2Status, &str) -> Result<(), String>) -> Result<T, String>,
    ) -> Result<T, String> {
        // The log and the callbacks outlive the instance (freed below).
        let log = Box::new(fmi_conformance::logger::LogSink::default());
        let callbacks = Box::new(fmi_conformance::logger::callbacks(log.env()));
        let name = CString::new("fmu-build-depends").unwrap();
        // SAFETY: every string is NUL-terminated and outlives the call; so do the callbacks.
        let c = unsafe {
            (self.fmi.instantiate)(
                name.as_ptr(),
                self.kind,
                self.guid.as_ptr(),
                self.location.as_ptr(),
                &*callbacks,
                fmi2False,
                fmi2False,
            )
        };
        if c.is_null() {
            return Err(format!("fmi2Instantiate returned NULL: {}", said(&log)));
        }
        let ok = |s: fmi2Status, what: &str| {
            if s == fmi2OK {
                Ok(())
            } else {
                Err(format!("{what} answered status {s}: {}", said(&log)))
            }
        };
        // SAFETY: `c` is a live instance of this library until the free below.
        let status = unsafe {
            (self.fmi.setup_experiment)(
                c,
                fmi2False,
                0.0,
                start,
                if stop.is_some() { fmi2True } else { fmi2False },
                stop.unwrap_or(start),
            )
        };
        let result = ok(status, "fmi2SetupExperiment").and_then(|_| body(c, &ok));
        // SAFETY: as above; not used afterwards.
        unsafe { (self.fmi.free_instance)(c) };
        result
    }
}

impl Probe for Api {
    fn derivative_function(&self) -> &'static str {
        "fmi2GetDirectionalDerivative"
    }

    fn jacobian(&self, d: &ModelDescription, at: &Point, rng: &mut Rng) -> Result<Vec<Vec<f64>>, String> {
        let Point {
            unknowns,
            knowns,
            parameters,
            scale,
        } = *at;
        let n_states = knowns.iter().filter(|k| matches!(k, Known::State(_))).count();
        let inputs: Vec<&Variable> = knowns
            .iter()
            .filter_map(|k| match k {
                Known::Input(v) => Some(*v),
                Known::State(_) => None,
            })
            .collect();
        let me = self
            .fmi
            .me
            .as_ref()
            .map_err(|e| format!("the library has no model exchange: {e}"))?;
        let (enter_continuous, get_states, set_states) = (
            me.enter_continuous_time_mode,
            me.get_continuous_states,
            me.set_continuous_states,
        );
        self.with_instance(|c, ok| {
            // SAFETY: `c` is live; every array passed has the length passed with it.
            unsafe {
                let setting = |v: &Variable, x: f64| format!("setting the parameter '{}' to {x}", v.name);
                self.initialize(c, ok, parameters.iter().copied(), setting)?;
                ok(enter_continuous(c), "fmi2EnterContinuousTimeMode")?;
                let mut x = vec![0.0; n_states];
                ok(get_states(c, x.as_mut_ptr(), x.len()), "fmi2GetContinuousStates")?;
                let states: Vec<&Variable> = states(d);
                for (j, xj) in x.iter_mut().enumerate() {
                    *xj = spread_by(rng, states[j], *xj, scale);
                }
                ok(set_states(c, x.as_ptr(), x.len()), "fmi2SetContinuousStates")?;
                let vrs: Vec<u32> = inputs.iter().map(|v| v.value_reference).collect();
                let values: Vec<f64> = inputs.iter().map(|v| spread_by(rng, v, start_of(v), scale)).collect();
                ok(
                    (self.fmi.set_real)(c, vrs.as_ptr(), vrs.len(), values.as_ptr()),
                    "fmi2SetReal of the inputs",
                )?;
                let u_vrs: Vec<u32> = unknowns.iter().map(|v| v.value_reference).collect();
                by_columns(self, unknowns, knowns, |k, column| {
                    ok(
                        (self.fmi.get_directional_derivative)(
                            c,
                            u_vrs.as_ptr(),
                            u_vrs.len(),
                            [k.value_reference].as_ptr(),
                            1,
                            [1.0].as_ptr(),
                            column.as_mut_ptr(),
                        ),
                        &format!("fmi2GetDirectionalDerivative with respect to '{}'", k.name),
                    )
                })
            }
        })
    }

    fn initial_values(&self, knowns: &[&Variable], values: &[f64], unknowns: &[&Variable]) -> Result<Vec<f64>, String> {
        self.with_instance(|c, ok| {
            // SAFETY: `c` is live; every array passed has the length passed with it.
            unsafe {
                let setting = |v: &Variable, x: f64| format!("setting '{}' to {x}", v.name);
                self.initialize(c, ok, knowns.iter().copied().zip(values.iter().copied()), setting)?;
                let mut out = Vec::with_capacity(unknowns.len());
                for v in unknowns {
                    let vr = [v.value_reference];
                    if v.var_type == VarType::Real {
                        let mut x = [0.0];
                        ok(
                            (self.fmi.get_real)(c, vr.as_ptr(), 1, x.as_mut_ptr()),
                            &format!("fmi2GetReal of '{}'", v.name),
                        )?;
                        out.push(x[0]);
                    } else {
                        let mut x = [0];
                        ok(
                            (self.fmi.get_integer)(c, vr.as_ptr(), 1, x.as_mut_ptr()),
                            &format!("fmi2GetInteger of '{}'", v.name),
                        )?;
                        out.push(x[0] as f64);
                    }
                }
                Ok(out)
            }
        })
    }
}

pub(crate) fn said(log: &fmi_conformance::logger::LogSink) -> String {
    log.take().into_iter().map(|e| e.text).collect::<Vec<_>>().join("; ")
}

/// Checks the declared dependencies of the library at `so` (a rustfmu model whose declarations
/// are `d`) through FMI 2.0 model exchange. `guid` and `resource_uri` as for fmi2Instantiate.
pub fn check(so: &Path, d: &ModelDescription, guid: &str, resource_uri: &str) -> Report {
    match Api::load(so, true, guid, resource_uri) {
        Ok(api) => check_with(&api, d),
        Err(e) => Report::not_run(format!("`depends` was not checked: {e}")),
    }
}

/// Checks the declared `initial_depends` of the library at `so` (a rustfmu model whose
/// declarations are `d`): at a few random points (Real knowns spread around their start values,
/// inside their bounds; Booleans and enumerations drawn), each known of Initialization Mode is
/// moved a little on its own, in a fresh instance, and the initial unknowns read after
/// Initialization Mode. An unknown that moved depends on that known. Integer knowns move by one,
/// Booleans to the other value, enumerations to the next item; String knowns are not moved (a
/// dependency on them is not checked).
pub fn check_initial(so: &Path, d: &ModelDescription, guid: &str, resource_uri: &str, co_simulation: bool) -> Report {
    // Co-simulation where the library has it: the InitialUnknowns are the same for both
    // interfaces, and co-simulation accepts every parameter model exchange does (not the other
    // way round: a sampled controller).
    match Api::load(so, !co_simulation, guid, resource_uri) {
        Ok(api) => check_initial_with(&api, d),
        Err(e) => Report::not_run(format!("`initial_depends` was not checked: {e}")),
    }
}
