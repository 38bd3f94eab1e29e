//! The FMI 3.0 functions of a container: co-simulation without event mode (every function of
//! the standard is exported; those of model exchange, scheduled execution, clocks, configuration
//! mode, event mode and derivatives refuse with the reason). The container's variables are its
//! components' FMI 2.0 ones: Real as Float64, Integer as Int32, Enumeration as Int64 (FMI 3.0's
//! access type of an Enumeration), Boolean, String; after them the independent variable `time`
//! (value reference: the number of the others), read with fmi3GetFloat64.

use crate::export::exports;
use crate::*;
use rustfmu::fmi3::abi::*;

/// The rows of `fmi3Get{Type}` and `fmi3Set{Type}`: every one has the header's signature, so a
/// row names the function and its `values` type, and the function that runs, which takes the
/// arguments in the header's order (function name `F` second) and then the row's own.
macro_rules! value_functions {
    ($($name:ident(values: *$ptr:tt $ty:ty) => $f:ident($($arg:expr),* $(,)?);)*) => {
        exports! {
            $($name(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *$ptr $ty,
                nValues: usize,
            ) -> fmi3Status =>
                $f(instance, F, valueReferences, nValueReferences, values, nValues, $($arg),*);)*
        }
    };
}

mod refusals;

fn with3(c: fmi3Instance, function: &str, f: impl FnOnce(&mut Container) -> Outcome) -> fmi3Status {
    with(c, function, f) as fmi3Status
}

exports! {
    fmi3GetVersion() -> *const c_char =>
        VERSION.as_ptr();
    fmi3SetDebugLogging(
        instance: fmi3Instance,
        loggingOn: fmi3Boolean,
        nCategories: usize,
        categories: *const fmi3String,
    ) -> fmi3Status =>
        with3(instance, F, |me| {
            if nCategories > 0 && categories.is_null() {
                me.check(Call::SetDebugLogging, F)?;
                return Err(me.error(&format!("{F}: {nCategories} categories in a NULL array")));
            }
            me.set_debug_logging(F, loggingOn, slice(categories, nCategories))
        });
}

/// Logs `message` through an FMI 3.0 logger that has no instance (yet).
fn log_to(logger: fmi3LogMessageCallback, environment: fmi3InstanceEnvironment, message: &str) {
    let sink = Sink {
        logger: Logger::V3 { logger, environment },
        logging_on: Cell::new(true),
    };
    sink.log(fmi2Error, "logStatusError", message);
}

exports! {
    fmi3InstantiateModelExchange(
        _instanceName: fmi3String,
        _instantiationToken: fmi3String,
        _resourcePath: fmi3String,
        _visible: fmi3Boolean,
        _loggingOn: fmi3Boolean,
        instanceEnvironment: fmi3InstanceEnvironment,
        logMessage: fmi3LogMessageCallback,
    ) -> fmi3Instance =>
        no_instance(logMessage, instanceEnvironment, "fmi3InstantiateModelExchange: a container is a co-simulation FMU only (no <ModelExchange> element)");
    fmi3InstantiateScheduledExecution(
        _instanceName: fmi3String,
        _instantiationToken: fmi3String,
        _resourcePath: fmi3String,
        _visible: fmi3Boolean,
        _loggingOn: fmi3Boolean,
        instanceEnvironment: fmi3InstanceEnvironment,
        logMessage: fmi3LogMessageCallback,
        _clockUpdate: fmi3ClockUpdateCallback,
        _lockPreemption: fmi3LockPreemptionCallback,
        _unlockPreemption: fmi3UnlockPreemptionCallback,
    ) -> fmi3Instance =>
        no_instance(logMessage, instanceEnvironment, "fmi3InstantiateScheduledExecution: a container is a co-simulation FMU only (no <ScheduledExecution> element)");
    fmi3InstantiateCoSimulation(
        instanceName: fmi3String,
        instantiationToken: fmi3String,
        resourcePath: fmi3String,
        _visible: fmi3Boolean,
        loggingOn: fmi3Boolean,
        eventModeUsed: fmi3Boolean,
        _earlyReturnAllowed: fmi3Boolean,
        _requiredIntermediateVariables: *const fmi3ValueReference,
        nRequiredIntermediateVariables: usize,
        instanceEnvironment: fmi3InstanceEnvironment,
        logMessage: fmi3LogMessageCallback,
        _intermediateUpdate: fmi3IntermediateUpdateCallback,
    ) -> fmi3Instance =>
        instantiate_cs3(
            instanceName,
            instantiationToken,
            resourcePath,
            loggingOn,
            eventModeUsed,
            nRequiredIntermediateVariables,
            instanceEnvironment,
            logMessage,
        );
    fmi3FreeInstance(instance: fmi3Instance) =>
        free_instance(instance);
    fmi3EnterInitializationMode(
        instance: fmi3Instance,
        toleranceDefined: fmi3Boolean,
        tolerance: fmi3Float64,
        startTime: fmi3Float64,
        stopTimeDefined: fmi3Boolean,
        stopTime: fmi3Float64,
    ) -> fmi3Status =>
        with3(instance, F, |me| {
            me.check(Call::EnterInitializationMode, F)?;
            me.setup(
                F,
                toleranceDefined.then_some(tolerance),
                startTime,
                stopTimeDefined.then_some(stopTime),
            )?;
            me.enter_initialization_mode(F)
        });
    fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status =>
        with3(instance, F, |me| {
            me.exit_initialization_mode(F)
        });
    fmi3Terminate(instance: fmi3Instance) -> fmi3Status =>
        with3(instance, F, |me| me.terminate(F));
    fmi3Reset(instance: fmi3Instance) -> fmi3Status =>
        with3(instance, F, |me| me.reset(F));
}

/// An instantiation of an interface a container does not have: refused in the importer's log.
fn no_instance(logger: fmi3LogMessageCallback, environment: fmi3InstanceEnvironment, message: &str) -> fmi3Instance {
    let _ = catch_unwind(AssertUnwindSafe(|| log_to(logger, environment, message)));
    std::ptr::null_mut()
}

/// fmi3InstantiateCoSimulation: without event mode or intermediate update.
fn instantiate_cs3(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    resourcePath: fmi3String,
    loggingOn: fmi3Boolean,
    eventModeUsed: fmi3Boolean,
    nRequiredIntermediateVariables: usize,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
) -> fmi3Instance {
    const F: &str = "fmi3InstantiateCoSimulation";
    let r = catch_unwind(AssertUnwindSafe(|| {
        let sink = Box::new(Sink {
            logger: Logger::V3 {
                logger: logMessage,
                environment: instanceEnvironment,
            },
            logging_on: Cell::new(loggingOn),
        });
        if eventModeUsed {
            sink.log(
                fmi2Error,
                "logStatusError",
                &format!("{F}: eventModeUsed = true, but a container has no event mode (hasEventMode = false)"),
            );
            return None;
        }
        if nRequiredIntermediateVariables > 0 {
            sink.log(
                fmi2Error,
                "logStatusError",
                &format!(
                    "{F}: {nRequiredIntermediateVariables} required intermediate variables, but a container has no intermediate update (providesIntermediateUpdate = false)"
                ),
            );
            return None;
        }
        instantiate(
            sink,
            Request {
                version: Version::Fmi3,
                function: F,
                name: text(instanceName),
                token: text(instantiationToken),
                resources: resources_of_path(text(resourcePath)),
                logging_on: loggingOn,
            },
        )
    }));
    match r {
        Ok(Some(c)) => Box::into_raw(c) as fmi3Instance,
        _ => std::ptr::null_mut(),
    }
}

/// The value references and the number of values of a getter or setter: NULL arrays and
/// nValues other than nValueReferences (every variable of a container is a scalar) refused.
fn arrays<'a, T>(
    me: &Container,
    function: &str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    value: *const T,
    n_values: usize,
) -> Result<&'a [u32], Status> {
    if nvr > 0 && (vr.is_null() || value.is_null()) {
        return Err(me.error(&format!("{function}: {nvr} values with a NULL array")));
    }
    if n_values != nvr {
        return Err(me.error(&format!(
            "{function}: nValues = {n_values} for {nvr} value references: every variable of a container is a scalar (one value each)"
        )));
    }
    Ok(slice(vr, nvr))
}

#[allow(clippy::too_many_arguments)]
fn get3<T: Scalar>(
    instance: fmi3Instance,
    function: &'static str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    out: *mut T,
    n_values: usize,
    ty: Type,
    asked: &'static str,
    get: impl Fn(&mut InstanceCS, &[u32], &mut [T]) -> Result<(), Fmi2Error>,
    finite: impl Fn(&T) -> bool,
    time: impl Fn(f64) -> Option<T>,
) -> fmi3Status {
    with3(instance, function, |me| {
        me.check(Call::GetValues, function)?;
        let vrs = arrays(me, function, vr, nvr, out as *const T, n_values)?;
        me.get_values(function, ty, asked, vrs, slice_mut(out, nvr), get, finite, time)
    })
}

/// Values the components give as fmi2Integer (`get`), converted into the FMI 3.0 type of `out`.
fn through_i32<T>(
    n: usize,
    out: &mut [T],
    get: impl FnOnce(&mut [i32]) -> Result<(), Fmi2Error>,
    convert: impl Fn(i32) -> T,
) -> Result<(), Fmi2Error> {
    let mut ints = vec![0i32; n];
    get(&mut ints)?;
    for (o, x) in out.iter_mut().zip(ints) {
        *o = convert(x);
    }
    Ok(())
}

value_functions! {
    fmi3GetFloat64(values: *mut fmi3Float64) =>
        get3(Type::Real, "Float64", |i, v, out| i.get_real(v, out), |x| x.is_finite(), Some);
    fmi3GetInt32(values: *mut fmi3Int32) =>
        get3(Type::Integer, "Int32", |i, v, out| i.get_integer(v, out), |_| true, |_| None);
    // An Enumeration's values (its FMI 3.0 access type is Int64; the components' are fmi2Integer).
    fmi3GetInt64(values: *mut fmi3Int64) => get3(
        Type::Enumeration,
        "Int64 (an Enumeration)",
        |i, v, out| through_i32(v.len(), out, |w| i.get_integer(v, w), i64::from),
        |_| true,
        |_| None,
    );
    fmi3GetBoolean(values: *mut fmi3Boolean) => get3(
        Type::Boolean,
        "Boolean",
        |i, v, out| through_i32(v.len(), out, |w| i.get_boolean(v, w), |x| x != 0),
        |_| true,
        |_| None,
    );
}

exports! {
    fmi3GetString(
        instance: fmi3Instance,
        valueReferences: *const fmi3ValueReference,
        nValueReferences: usize,
        values: *mut fmi3String,
        nValues: usize,
    ) -> fmi3Status =>
        with3(instance, F, |me| {
            me.check(Call::GetValues, F)?;
            let vrs = arrays(
                me,
                F,
                valueReferences,
                nValueReferences,
                values as *const fmi3String,
                nValues,
            )?;
            me.get_strings(F, vrs)?;
            let out = slice_mut(values, nValueReferences);
            for (k, s) in me.strings.iter().enumerate() {
                out[k] = s.as_ptr();
            }
            Ok(fmi2OK)
        });
}

#[allow(clippy::too_many_arguments)]
fn set3<T: Scalar>(
    instance: fmi3Instance,
    function: &'static str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    value: *const T,
    n_values: usize,
    ty: Type,
    asked: &'static str,
    number: impl Fn(&T) -> Option<f64>,
    set: impl Fn(&mut InstanceCS, u32, T) -> Result<(), Fmi2Error>,
) -> fmi3Status {
    with3(instance, function, |me| {
        let vrs = arrays(me, function, vr, nvr, value, n_values)?;
        me.set_values(function, ty, asked, vrs, slice(value, nvr), number, set)
    })
}

value_functions! {
    fmi3SetFloat64(values: *const fmi3Float64) =>
        set3(Type::Real, "Float64", |x| Some(*x), |i, v, x| i.set_real(&[v], &[x]).map(|_| ()));
    fmi3SetInt32(values: *const fmi3Int32) => set3(
        Type::Integer,
        "Int32",
        |x| Some(f64::from(*x)),
        |i, v, x| i.set_integer(&[v], &[x]).map(|_| ()),
    );
    fmi3SetBoolean(values: *const fmi3Boolean) => set3(
        Type::Boolean,
        "Boolean",
        |_| None,
        |i, v, x| i.set_boolean(&[v], &[i32::from(x)]).map(|_| ()),
    );
}

exports! {
    fmi3SetInt64(
        instance: fmi3Instance,
        valueReferences: *const fmi3ValueReference,
        nValueReferences: usize,
        values: *const fmi3Int64,
        nValues: usize,
    ) -> fmi3Status =>
        with3(instance, F, |me| {
            let vrs = arrays(me, F, valueReferences, nValueReferences, values, nValues)?;
            let given = slice(values, nValueReferences);
            // The components' Enumerations are fmi2Integer: a value outside 32 bits is no item.
            let mut narrow = Vec::with_capacity(given.len());
            for (k, &x) in given.iter().enumerate() {
                match i32::try_from(x) {
                    Ok(x) => narrow.push(x),
                    Err(_) => {
                        me.check(Call::SetDiscreteValues, F)?;
                        me.port(vrs[k], Type::Enumeration, "Int64 (an Enumeration)", F)?;
                        return Err(me.error(&format!(
                            "{F}: '{}' (vr {}) = {x} is no item of its enumeration; nothing set",
                            me.name(vrs[k]),
                            vrs[k]
                        )));
                    }
                }
            }
            me.set_values(
                F,
                Type::Enumeration,
                "Int64 (an Enumeration)",
                vrs,
                &narrow,
                |x| Some(f64::from(*x)),
                |i, v, x| i.set_integer(&[v], &[x]).map(|_| ()),
            )
        });
    fmi3SetString(
        instance: fmi3Instance,
        valueReferences: *const fmi3ValueReference,
        nValueReferences: usize,
        values: *const fmi3String,
        nValues: usize,
    ) -> fmi3Status =>
        with3(instance, F, |me| {
            let vrs = arrays(me, F, valueReferences, nValueReferences, values, nValues)?;
            me.set_strings(F, vrs, slice(values, nValueReferences))
        });
}

// FMU states.

exports! {
    fmi3GetFMUState(instance: fmi3Instance, FMUState: *mut fmi3FMUState) -> fmi3Status =>
        with3(instance, F, |me| {
            me.get_fmu_state(F, FMUState)
        });
    fmi3SetFMUState(instance: fmi3Instance, FMUState: fmi3FMUState) -> fmi3Status =>
        with3(instance, F, |me| {
            me.set_fmu_state(F, FMUState)
        });
    fmi3FreeFMUState(instance: fmi3Instance, FMUState: *mut fmi3FMUState) -> fmi3Status =>
        with3(instance, F, |me| {
            me.free_fmu_state(F, FMUState)
        });
    fmi3SerializedFMUStateSize(
        instance: fmi3Instance,
        FMUState: fmi3FMUState,
        size: *mut usize,
    ) -> fmi3Status =>
        with3(instance, F, |me| {
            me.serialized_size(F, FMUState, size)
        });
    fmi3SerializeFMUState(
        instance: fmi3Instance,
        FMUState: fmi3FMUState,
        serializedState: *mut fmi3Byte,
        size: usize,
    ) -> fmi3Status =>
        with3(instance, F, |me| {
            me.serialize_state(F, FMUState, serializedState, size)
        });
    fmi3DeserializeFMUState(
        instance: fmi3Instance,
        serializedState: *const fmi3Byte,
        size: usize,
        FMUState: *mut fmi3FMUState,
    ) -> fmi3Status =>
        with3(instance, F, |me| {
            me.deserialize_state(F, serializedState, size, FMUState)
        });
}

// Variable dependencies (FMI 3.0, 2.3.9): those of <ModelStructure>.

impl Container {
    /// The value references `dependent` depends on now: in Instantiated and Initialization Mode
    /// an <InitialUnknown>'s (every known: the inputs, time and the initial = exact variables,
    /// as its element leaves `dependencies` out), afterwards an <Output>'s (composed through the
    /// components' dependencies and the connections, as the element says).
    fn dependencies(&self, function: &str, dependent: u32) -> Result<Vec<u32>, Status> {
        let Some(p) = self.ports.get(dependent as usize) else {
            return Err(self.error(&format!(
                "{function}: value reference {dependent} is not a variable of {}",
                self.spec.model_identifier
            )));
        };
        let initialization = matches!(self.state, State::Instantiated | State::InitializationMode);
        let e = (p.component != TIME).then(|| &self.spec.variables[dependent as usize]);
        let unknown = match e {
            Some(e) if e.causality() == Causality::Output => !initialization || e.start.is_none(),
            _ => false,
        };
        let Some(e) = e.filter(|_| unknown) else {
            return Err(self.error(&format!(
                "{function}: '{}' (vr {dependent}) is no unknown {}: it has no dependencies to report",
                self.name(dependent),
                if initialization {
                    "of Initialization Mode (<InitialUnknown>)"
                } else {
                    "of <ModelStructure> (an output)"
                }
            )));
        };
        if initialization {
            let mut knowns: Vec<u32> = self
                .spec
                .variables
                .iter()
                .filter(|k| match k.causality() {
                    Causality::Input | Causality::Parameter => true,
                    Causality::Output => k.start.is_some(),
                    _ => false,
                })
                .map(|k| k.vr)
                .collect();
            knowns.push(self.spec.variables.len() as u32);
            knowns.sort_unstable();
            return Ok(knowns);
        }
        Ok(self
            .spec
            .output_dependencies(&self.sim, e)
            .into_iter()
            .map(|i| i - 1)
            .collect())
    }
}

exports! {
    fmi3GetNumberOfVariableDependencies(
        instance: fmi3Instance,
        dependent: fmi3ValueReference,
        nDependencies: *mut usize,
    ) -> fmi3Status =>
        with3(instance, F, |me| {
            me.check(Call::SetDebugLogging, F)?;
            if nDependencies.is_null() {
                return Err(me.error(&format!("{F}: nDependencies is NULL")));
            }
            let deps = me.dependencies(F, dependent)?;
            put(nDependencies, deps.len());
            Ok(fmi2OK)
        });
    fmi3GetVariableDependencies(
        instance: fmi3Instance,
        dependent: fmi3ValueReference,
        elementIndicesOfDependent: *mut usize,
        independents: *mut fmi3ValueReference,
        elementIndicesOfIndependents: *mut usize,
        dependencyKinds: *mut fmi3DependencyKind,
        nDependencies: usize,
    ) -> fmi3Status =>
        with3(instance, F, |me| {
            me.check(Call::SetDebugLogging, F)?;
            let deps = me.dependencies(F, dependent)?;
            if nDependencies != deps.len() {
                return Err(me.error(&format!(
                    "{F}: nDependencies = {nDependencies}, but '{}' (vr {dependent}) has {} (fmi3GetNumberOfVariableDependencies)",
                    me.name(dependent),
                    deps.len()
                )));
            }
            let n = deps.len();
            if n > 0
                && (elementIndicesOfDependent.is_null()
                    || independents.is_null()
                    || elementIndicesOfIndependents.is_null()
                    || dependencyKinds.is_null())
            {
                return Err(me.error(&format!("{F}: an output array is NULL with nDependencies = {n}")));
            }
            let (e_dep, ind, e_ind, kinds) = (
                slice_mut(elementIndicesOfDependent, n),
                slice_mut(independents, n),
                slice_mut(elementIndicesOfIndependents, n),
                slice_mut(dependencyKinds, n),
            );
            for (k, vr) in deps.into_iter().enumerate() {
                // Every variable is a scalar (element index 0); the kind is not analysed further
                // than "depends" (the components' FMI 2.0 dependenciesKind are not composed).
                e_dep[k] = 0;
                ind[k] = vr;
                e_ind[k] = 0;
                kinds[k] = fmi3Dependent;
            }
            Ok(fmi2OK)
        });
}
