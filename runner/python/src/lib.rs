//! `rustfmu_runner`: the SSP co-simulation runner ([`runner::Simulation`]) as a Python
//! module. A `System` loads an SSP file once (its FMUs instantiated once); every `run` after the
//! first starts with fmi2Reset, runs with the GIL released and returns numpy arrays:
//!
//! ```python
//! import rustfmu_runner
//! s = rustfmu_runner.System("target/fmu/PendulumMotors.ssp")
//! r = s.run(10.0, 1e-3, start={"pendulum.alpha1_0": 0.2}, record=["pendulum.alpha1"])
//! r["time"], r["pendulum.alpha1"]          # numpy float64 arrays, one value per communication point
//! ```
//!
//! Errors are exceptions, never panics: `SspError` (an SSP or FMU the runner cannot read or run),
//! `VariableError` (an unknown component or variable, a value of the wrong type), `FmuError`
//! (an FMI call that failed: attributes `component`, `variable`, `function`, `status`, `time`,
//! and `partial`, the arrays recorded up to the failure), `LoopError` (an algebraic loop not
//! solved at a communication point: the same attributes); all derive from `RunnerError`.

// runner::Error is large (it carries the details of a failure), on the cold path only.
#![allow(clippy::result_large_err)]

use numpy::PyArray1;
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyString};
use runner::sim::Failure;
use runner::{Adaptive, Error, ErrorKind, Override, RunOptions, RunResult, Scheme, Simulation};
use std::sync::Mutex;

create_exception!(rustfmu_runner, RunnerError, PyException, "Any error of the runner.");
create_exception!(
    rustfmu_runner,
    SspError,
    RunnerError,
    "An SSP file or FMU the runner cannot read or run."
);
create_exception!(
    rustfmu_runner,
    VariableError,
    RunnerError,
    "An unknown component or variable, or a value of the wrong type."
);
create_exception!(
    rustfmu_runner,
    FmuError,
    RunnerError,
    "An FMI call that failed during a run."
);
create_exception!(
    rustfmu_runner,
    LoopError,
    RunnerError,
    "An algebraic loop the runner's Newton iteration did not solve (singular, or not converged)."
);

/// The simulation, used by one thread at a time (behind the `Mutex`): here, or (isolate =
/// "system") in a child process.
enum Sim {
    Here(Simulation),
    Process(runner::isolate::SystemProcess),
}

// SAFETY: the FMU instances (raw pointers into the FMUs' libraries) are only ever called with
// the Mutex held, so by one thread at a time; FMI 2.0 requires no more than that of an instance.
unsafe impl Send for Sim {}

fn to_pyerr(py: Python<'_>, e: &Error, partial: Option<&RunResult>) -> PyErr {
    let err = match e.kind {
        ErrorKind::Io | ErrorKind::Unsupported => SspError::new_err(e.message.clone()),
        ErrorKind::Variable | ErrorKind::Usage => VariableError::new_err(e.message.clone()),
        ErrorKind::Fmi => FmuError::new_err(e.message.clone()),
        ErrorKind::Loop => LoopError::new_err(e.message.clone()),
        // A run returns the rows where a component asks to end it; seen here only if a caller
        // other than `run` ever passes one.
        ErrorKind::Terminated => FmuError::new_err(e.message.clone()),
    };
    let value = err.value(py);
    let set = |name: &str, v: Option<String>| {
        let _ = value.setattr(name, v);
    };
    set("component", e.component.clone());
    set("variable", e.variable.clone());
    set("function", e.function.clone());
    set("status", e.status.clone());
    let _ = value.setattr("time", e.time);
    let _ = value.setattr("partial", partial.and_then(|r| arrays(py, r).ok()));
    err
}

/// {"time": array, name: array, ...}
fn arrays<'py>(py: Python<'py>, r: &RunResult) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("time", PyArray1::from_slice(py, &r.time))?;
    for (i, name) in r.names.iter().enumerate() {
        d.set_item(name, PyArray1::from_vec(py, r.column(i)))?;
    }
    Ok(d)
}

fn to_override(key: &str, v: &Bound<'_, PyAny>) -> PyResult<Override> {
    if v.is_instance_of::<PyBool>() {
        return Ok(Override::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(Override::Real(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(Override::Integer(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(Override::Text(v.extract()?));
    }
    // numpy scalars and other numbers; a numpy Boolean (numpy.bool, numpy.bool_) before them,
    // which converts to a number too.
    if v.get_type().name().is_ok_and(|n| n == "bool" || n == "bool_") {
        return Ok(Override::Boolean(v.is_truthy()?));
    }
    if let Ok(x) = v.extract::<i64>() {
        return Ok(Override::Integer(x));
    }
    if let Ok(x) = v.extract::<f64>() {
        return Ok(Override::Real(x));
    }
    // An array's elements (a list, a tuple, a numpy array of any shape, row-major): the text the
    // command line takes, parsed as the variable's type.
    if v.try_iter().is_ok() {
        let mut words = Vec::new();
        elements(v, &mut words)?;
        return Ok(Override::Text(words.join(" ")));
    }
    Err(VariableError::new_err(format!(
        "{key} = {v}: a start value must be a bool, int, float, str or a sequence of them (an array)"
    )))
}

/// The elements of `v`, nested sequences flattened in order, each as the runner's text of it.
fn elements(v: &Bound<'_, PyAny>, out: &mut Vec<String>) -> PyResult<()> {
    if v.is_instance_of::<PyString>() {
        out.push(v.extract()?);
        return Ok(());
    }
    if let Ok(items) = v.try_iter() {
        for x in items {
            elements(&x?, out)?;
        }
        return Ok(());
    }
    let text: String = v.str()?.extract()?;
    // A Python or numpy Boolean prints True / False; the runner reads true / false.
    out.push(match text.as_str() {
        "True" => "true".to_owned(),
        "False" => "false".to_owned(),
        _ => text,
    });
    Ok(())
}

/// An SSP system of FMI 2.0 co-simulation FMUs, loaded once; `run` runs it.
#[pyclass(name = "System", module = "rustfmu_runner")]
struct PySystem {
    inner: Mutex<Sim>,
    #[pyo3(get)]
    path: String,
    #[pyo3(get)]
    name: String,
    /// The components in the order a communication point evaluates them.
    #[pyo3(get)]
    evaluation_order: Vec<String>,
    /// [(instance name, model identifier)]
    #[pyo3(get)]
    components: Vec<(String, String)>,
    /// Every output, "component.variable" (what `run` records by default).
    #[pyo3(get)]
    outputs: Vec<String>,
    /// The system's parameter bindings, "component.variable".
    #[pyo3(get)]
    parameters: Vec<String>,
    /// What the last run made (`last_run`).
    last_run: Mutex<Option<Py<PyDict>>>,
}

#[pymethods]
impl PySystem {
    /// Loads the SSP file `path` (`order`: "gauss-seidel", the default, or "jacobi").
    ///
    /// `isolate=True` (or "component"): each component in a child process of its own (Linux),
    /// so that an FMU that crashes, aborts, exits or hangs fails the run with an FmuError naming
    /// the component, the function and the time, and this process lives on (the next run starts
    /// the components anew); `isolate="system"`: every FMU and the master in one child process
    /// (the same errors, at the in-process cost per step; an FMU can reach the others' memory). `call_timeout` (s): the longest one FMU call may take before its
    /// process is killed (default: no limit). `worker`: the rustfmu-runner binary the children
    /// run (default: $RUSTFMU_RUNNER, this environment's scripts folder, PATH).
    ///
    /// `event_mode`: FMI 3.0 co-simulation components (names) run with eventModeUsed and
    /// earlyReturnAllowed, as the command line's `--event-mode`: the events each reports are
    /// handled in Event Mode at their time, and a step one ends early ends every component's step
    /// there (each such point a row of its own); with `isolate` too.
    #[new]
    #[pyo3(signature = (path, order = "gauss-seidel", isolate = None, call_timeout = None, worker = None, event_mode = None))]
    fn new(
        py: Python<'_>,
        path: std::path::PathBuf,
        order: &str,
        isolate: Option<&Bound<'_, PyAny>>,
        call_timeout: Option<f64>,
        worker: Option<std::path::PathBuf>,
        event_mode: Option<Vec<String>>,
    ) -> PyResult<PySystem> {
        // isolate: False/None, True or "component" (each FMU in a process), "system" (one).
        let granularity = match isolate {
            None => None,
            Some(v) if v.is_instance_of::<PyBool>() => v.extract::<bool>()?.then_some("component"),
            Some(v) => match v.extract::<String>().ok().as_deref() {
                Some("component") => Some("component"),
                Some("system") => Some("system"),
                _ => {
                    return Err(PyValueError::new_err(format!(
                        "isolate = {v}: False, True (= \"component\"), \"component\" or \"system\""
                    )));
                }
            },
        };
        let isolate = granularity.is_some();
        let scheme = match order {
            "gauss-seidel" => Scheme::GaussSeidel,
            "jacobi" => Scheme::Jacobi,
            other => {
                return Err(VariableError::new_err(format!(
                    "order = '{other}': one of 'gauss-seidel', 'jacobi'"
                )));
            }
        };
        let shown = path.display().to_string();
        let isolation = if isolate {
            if let Some(t) = call_timeout
                && !(t.is_finite() && t > 0.0)
            {
                return Err(PyValueError::new_err(format!(
                    "call_timeout = {t}: a time > 0 in seconds"
                )));
            }
            let scripts: std::path::PathBuf = py
                .import("sysconfig")?
                .call_method1("get_path", ("scripts",))?
                .extract()?;
            let worker =
                runner::isolate::find_worker(worker.as_deref(), &[scripts]).map_err(|e| to_pyerr(py, &e, None))?;
            Some(runner::isolate::Isolation {
                worker,
                timeout: call_timeout.map(std::time::Duration::from_secs_f64),
            })
        } else {
            if call_timeout.is_some() || worker.is_some() {
                return Err(PyValueError::new_err("call_timeout and worker go with isolate=True"));
            }
            None
        };
        let jacobi = scheme == Scheme::Jacobi;
        let event_mode = event_mode.unwrap_or_default();
        let in_child = event_mode.clone();
        let sim = py
            .detach(move || match (granularity, isolation) {
                (Some("system"), Some(iso)) => {
                    runner::isolate::SystemProcess::spawn(iso, &path, jacobi, &in_child).map(Sim::Process)
                }
                (_, Some(iso)) => Simulation::from_ssp_isolated(&path, iso).map(Sim::Here),
                _ => Simulation::from_ssp(&path).map(Sim::Here),
            })
            .map_err(|e| to_pyerr(py, &e, None))?;
        let (name, evaluation_order, components, outputs, parameters) = match &sim {
            Sim::Here(sim) => (
                sim.name.clone(),
                sim.evaluation_order().iter().map(|s| s.to_string()).collect(),
                sim.components()
                    .iter()
                    .map(|(a, b)| (a.to_string(), b.to_string()))
                    .collect(),
                sim.outputs(),
                sim.parameters().iter().map(|s| s.to_string()).collect(),
            ),
            Sim::Process(p) => {
                let i = p.info();
                (
                    i.name.clone(),
                    i.evaluation_order.clone(),
                    i.components.clone(),
                    i.outputs.clone(),
                    i.parameters.clone(),
                )
            }
        };
        let mut sim = sim;
        if let Sim::Here(s) = &mut sim {
            s.scheme = scheme;
        }
        if let Sim::Here(s) = &mut sim {
            for c in &event_mode {
                s.use_event_mode(c).map_err(|e| to_pyerr(py, &e, None))?;
            }
        }
        Ok(PySystem {
            path: shown,
            name,
            evaluation_order,
            components,
            outputs,
            parameters,
            last_run: Mutex::new(None),
            inner: Mutex::new(sim),
        })
    }

    /// One run from t = 0 over round(stop_time / step) steps of `step` (s): fmi2Reset (from the
    /// second run on), the SSP's parameter bindings and `start` ({"component.variable": value})
    /// on top, initialization, then at each communication point the connections in dependency
    /// order, the `record`ed variables read (default: every output), every FMU stepped.
    /// `stop_when` ({"component.variable": limit}, recorded variables) ends the run after the
    /// first point where |value| > limit. Returns {"time": array, name: array, ...}.
    ///
    /// `tolerance`: error-controlled communication steps (step doubling with rollback through
    /// the FMUs' states; `step` is the first step, `min_step` and `max_step` bound them; the
    /// error estimated on the Real variables `error_on`, default every connected output): the
    /// points are where steps were accepted. A system that cannot (a component without FMU
    /// state or variable steps) runs with fixed steps, with a RuntimeWarning saying why.
    /// `last_run` says what the run made. `input_derivatives=True`: a first-order hold on the
    /// connections (the outputs' exact time derivatives, through each feedthrough by its
    /// directional derivative, set as input derivatives where a component interpolates inputs).
    /// `loops`: how algebraic loops are solved, {"rtol": 1e-10, "atol": 1e-10,
    /// "max_iterations": 20, "finite_differences": False} (any of them; runner/README.md).
    ///
    /// A component that asks to end the simulation (FMI 2.0 fmi2Terminated, FMI 3.0
    /// terminateSimulation) ends the run there, as fmusim does: the arrays up to that time are
    /// returned, with a RuntimeWarning saying who asked and when, and `last_run["terminated"]`.
    #[pyo3(signature = (stop_time, step, start = None, record = None, stop_when = None, tolerance = None, min_step = None, max_step = None, error_on = None, input_derivatives = false, loops = None))]
    #[allow(clippy::too_many_arguments)]
    fn run<'py>(
        &self,
        py: Python<'py>,
        stop_time: f64,
        step: f64,
        start: Option<&Bound<'py, PyDict>>,
        record: Option<Vec<String>>,
        stop_when: Option<&Bound<'py, PyDict>>,
        tolerance: Option<f64>,
        min_step: Option<f64>,
        max_step: Option<f64>,
        error_on: Option<Vec<String>>,
        input_derivatives: bool,
        loops: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let mut opts = RunOptions::new(stop_time, step);
        opts.input_derivatives = input_derivatives;
        if let Some(loops) = loops {
            for (k, v) in loops.iter() {
                let key: String = k.extract()?;
                match key.as_str() {
                    "rtol" => opts.loops.rtol = v.extract()?,
                    "atol" => opts.loops.atol = v.extract()?,
                    "max_iterations" => opts.loops.max_iterations = v.extract()?,
                    "finite_differences" => opts.loops.finite_differences = v.extract()?,
                    other => {
                        return Err(VariableError::new_err(format!(
                            "loops: no option '{other}' (rtol, atol, max_iterations, finite_differences)"
                        )));
                    }
                }
            }
        }
        if let Some(tolerance) = tolerance {
            opts.adaptive = Some(Adaptive {
                tolerance,
                min_step,
                max_step,
                error_on: error_on.unwrap_or_default(),
            });
        } else if min_step.is_some() || max_step.is_some() || error_on.is_some() {
            return Err(VariableError::new_err(
                "min_step, max_step and error_on are of error-controlled steps: give a tolerance too",
            ));
        }
        if let Some(start) = start {
            for (k, v) in start.iter() {
                let key: String = k.extract()?;
                let value = to_override(&key, &v)?;
                opts.overrides.push((key, value));
            }
        }
        opts.record = record.unwrap_or_else(|| self.outputs.clone());
        if let Some(stop) = stop_when {
            for (k, v) in stop.iter() {
                opts.stop_when_above.push((k.extract()?, v.extract()?));
            }
        }
        let inner = &self.inner;
        let result: Result<RunResult, Failure> = py.detach(|| match inner.lock() {
            Ok(mut sim) => match &mut *sim {
                Sim::Here(sim) => sim.run(&opts, &mut |_, _| {}),
                Sim::Process(p) => p.run(&opts),
            },
            Err(_) => Err(Failure::from(Error::usage(
                "the system is unusable: an earlier run panicked while holding it",
            ))),
        });
        let made = |r: &RunResult| -> PyResult<Py<PyDict>> {
            let d = PyDict::new(py);
            d.set_item("fmu_steps", r.fmu_steps)?;
            d.set_item("rejected", r.rejected)?;
            d.set_item("note", r.note.clone())?;
            let loops = pyo3::types::PyList::empty(py);
            for l in &r.loops {
                let e = PyDict::new(py);
                e.set_item("components", l.components.clone())?;
                e.set_item("unknowns", l.unknowns.clone())?;
                e.set_item("exact_jacobian", l.exact_jacobian)?;
                e.set_item("solves", l.solves)?;
                e.set_item("iterations", l.iterations)?;
                e.set_item("most_iterations", l.most_iterations)?;
                e.set_item("evaluations", l.evaluations)?;
                loops.append(e)?;
            }
            d.set_item("loops", loops)?;
            let terminated = match &r.terminated {
                Some(end) => {
                    let e = PyDict::new(py);
                    e.set_item("component", end.component.clone())?;
                    e.set_item("time", end.time)?;
                    e.set_item("message", end.message.clone())?;
                    Some(e)
                }
                None => None,
            };
            d.set_item("terminated", terminated)?;
            Ok(d.unbind())
        };
        match result {
            Ok(r) => {
                *self.last_run.lock().unwrap_or_else(|e| e.into_inner()) = Some(made(&r)?);
                for note in r.note.iter().chain(r.terminated.as_ref().map(|end| &end.message)) {
                    PyErr::warn(
                        py,
                        &py.get_type::<pyo3::exceptions::PyRuntimeWarning>(),
                        &std::ffi::CString::new(note.as_str()).unwrap_or_default(),
                        1,
                    )?;
                }
                arrays(py, &r)
            }
            Err(f) => {
                *self.last_run.lock().unwrap_or_else(|e| e.into_inner()) = Some(made(&f.partial)?);
                Err(to_pyerr(py, &f.error, Some(&f.partial)))
            }
        }
    }

    /// What the last run made: {"fmu_steps": fmi2DoStep calls (each one per component),
    /// "rejected": error-controlled steps rejected, "note": why an error-controlled run was made
    /// with fixed steps, or None, "loops": for each algebraic loop {"components", "unknowns",
    /// "exact_jacobian", "solves", "iterations", "most_iterations", "evaluations"},
    /// "terminated": {"component", "time", "message"} where a component asked to end the run,
    /// else None}; None before the first run.
    #[getter]
    fn last_run(&self, py: Python<'_>) -> Option<Py<PyDict>> {
        self.last_run
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .as_ref()
            .map(|d| d.clone_ref(py))
    }

    fn __repr__(&self) -> String {
        format!(
            "rustfmu_runner.System({:?}: {})",
            self.path,
            self.evaluation_order.join(" -> ")
        )
    }
}

#[pymodule]
fn rustfmu_runner(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<PySystem>()?;
    m.add("RunnerError", py.get_type::<RunnerError>())?;
    m.add("SspError", py.get_type::<SspError>())?;
    m.add("VariableError", py.get_type::<VariableError>())?;
    m.add("FmuError", py.get_type::<FmuError>())?;
    m.add("LoopError", py.get_type::<LoopError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
