//! Instantiation (either version): the spec read, the system loaded, the parameter set applied;
//! freeing; the resources folder of either version's argument; a call on every component.

use crate::*;

/// What an instantiation function was given, in either version.
pub(crate) struct Request<'a> {
    pub(crate) version: Version,
    pub(crate) function: &'a str,
    pub(crate) name: Option<String>,
    /// The GUID (2.0) or instantiation token (3.0).
    pub(crate) token: Option<String>,
    /// The resources folder (from 2.0's URI or 3.0's path), or why there is none.
    pub(crate) resources: Result<std::path::PathBuf, String>,
    pub(crate) logging_on: bool,
}

/// A new container, or None (the reason logged).
// ~150 lines: the steps of an instantiation in order (spec, GUID, system, components, parameter
// set, ports), each with the message that refuses it.
pub(crate) fn instantiate(sink: Box<Sink>, req: Request) -> Option<Box<Container>> {
    let function = req.function;
    let _using = Using::new(&sink);
    let fail = |m: String| {
        sink.log(fmi2Error, "logStatusError", &format!("{function}: {m}"));
        None
    };
    let name = req.name.unwrap_or_default();
    if name.is_empty() {
        return fail("instanceName is NULL or empty".into());
    }
    let dir = match req.resources {
        Ok(d) => d,
        Err(e) => return fail(e),
    };
    let spec_path = dir.join(SPEC_FILE);
    let spec = match std::fs::read_to_string(&spec_path)
        .map_err(|e| format!("{}: {e}", spec_path.display()))
        .and_then(|t| Spec::from_toml(&t))
    {
        Ok(s) => s,
        Err(e) => return fail(e),
    };
    let token = match req.version {
        Version::Fmi2 => "fmuGUID",
        Version::Fmi3 => "instantiationToken",
    };
    let given = req.token.unwrap_or_default();
    if given != spec.guid {
        return fail(format!(
            "{token} '{given}' is not this container's ({}): the modelDescription.xml and the resources are of different builds",
            spec.guid
        ));
    }
    let mut sim = match Simulation::from_dir(&dir.join(SYSTEM_FOLDER)) {
        Ok(s) => s,
        Err(e) => return fail(e.message),
    };
    let mut ports = Vec::with_capacity(spec.variables.len() + 1);
    let mut also = Vec::with_capacity(spec.variables.len() + 1);
    {
        let descriptions = sim.component_descriptions();
        for e in &spec.variables {
            // The further inputs a system input sets: the same type, the bounds of all of them.
            let (mut min, mut max) = (None::<f64>, None::<f64>);
            let mut more = Vec::new();
            for (c, name) in &e.also {
                let target = descriptions
                    .iter()
                    .position(|(n, _)| n == c)
                    .and_then(|ci| Some((ci, descriptions[ci].1.variable(name)?)));
                let Some((ci, v)) = target.filter(|(_, v)| v.ty == e.ty() && v.causality == Causality::Input) else {
                    return fail(format!(
                        "{SPEC_FILE}: '{}': '{c}.{name}' is not an input of its type in the system",
                        e.name
                    ));
                };
                min = match (min, v.min) {
                    (Some(a), Some(b)) => Some(a.max(b)),
                    (a, b) => a.or(b),
                };
                max = match (max, v.max) {
                    (Some(a), Some(b)) => Some(a.min(b)),
                    (a, b) => a.or(b),
                };
                more.push((ci, v.vr));
            }
            let Some(ci) = descriptions.iter().position(|(c, _)| *c == e.component) else {
                return fail(format!(
                    "{SPEC_FILE}: '{}': the system has no component '{}'",
                    e.name, e.component
                ));
            };
            let Some(v) = descriptions[ci].1.variable(&e.variable) else {
                return fail(format!(
                    "{SPEC_FILE}: '{}': component '{}' has no variable '{}'",
                    e.name, e.component, e.variable
                ));
            };
            if v.ty != e.ty() || v.causality != e.causality() {
                return fail(format!(
                    "{SPEC_FILE}: '{}' is not the component's variable of that type and causality",
                    e.name
                ));
            }
            ports.push(Port {
                component: ci,
                vr: v.vr,
                ty: v.ty,
                causality: v.causality,
                variability: v.variability,
                min: match (v.min, min) {
                    (Some(a), Some(b)) => Some(a.max(b)),
                    (a, b) => a.or(b),
                },
                max: match (v.max, max) {
                    (Some(a), Some(b)) => Some(a.min(b)),
                    (a, b) => a.or(b),
                },
            });
            also.push(more);
        }
    }
    if req.version == Version::Fmi3 {
        // FMI 3.0's independent variable, after the spec's (value reference: their count).
        ports.push(Port {
            component: TIME,
            vr: 0,
            ty: Type::Real,
            causality: Causality::Independent,
            variability: Variability::Continuous,
            min: None,
            max: None,
        });
        also.push(Vec::new());
    }
    if req.logging_on {
        for i in 0..sim.len() {
            let _ = sim.instance_mut(i).set_debug_logging(true, &[]);
        }
    }
    if let Err(e) = sim.apply_starts() {
        return fail(format!("the system's parameter set: {}", e.message));
    }
    drop(_using);
    let c = Box::new(Container {
        id: NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
        version: req.version,
        sink,
        spec,
        ports,
        also,
        sim,
        state: State::Instantiated,
        time: 0.0,
        dirty: true,
        stop_time: None,
        last_successful: 0.0,
        strings: Vec::new(),
        held: Vec::new(),
        held_strings: Vec::new(),
        free: Vec::new(),
        rollback: None,
    });
    c.debug(&format!(
        "instantiated: {} components, {} variables, internal step {} s",
        c.sim.len(),
        c.spec.variables.len(),
        c.spec.step
    ));
    Some(c)
}

/// Frees a container (its FMU states stay valid through their bytes; the importer frees them).
pub(crate) fn free_instance(c: *mut c_void) {
    if c.is_null() {
        return;
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: a non-NULL handle is a container this library boxed and returned, freed once
        // (fmi2FreeInstance / fmi3FreeInstance is its last call).
        let container = unsafe { Box::from_raw(c as *mut Container) };
        let _using = Using::new(&container.sink);
        drop(container);
    }));
}

/// Calls `f` on every component, in order; the first failure stops it and is returned.
pub(crate) fn each_raw(
    me: &mut Container,
    function: &str,
    f: impl Fn(&mut InstanceCS) -> Result<(), Fmi2Error>,
) -> Result<(), Error> {
    for i in 0..me.sim.len() {
        if let Err(e) = f(me.sim.instance_mut(i)) {
            let name = me.sim.component_descriptions()[i].0.to_owned();
            let t = me.time;
            return Err(Error::fmi(&name, function, &e, Some(t), ""));
        }
    }
    Ok(())
}

/// Calls `f` on every component, in order; the first failure stops it (the container failed).
pub(crate) fn each(
    me: &mut Container,
    function: &str,
    f: impl Fn(&mut InstanceCS) -> Result<(), Fmi2Error>,
) -> Result<(), Status> {
    each_raw(me, function, f).map_err(|e| me.failed(function, e))
}

/// The resources folder of a `file:` URI (FMI 2.0's fmuResourceLocation).
pub(crate) fn resources_of_uri(uri: Option<String>) -> Result<std::path::PathBuf, String> {
    let Some(uri) = uri else {
        return Err("fmuResourceLocation is NULL: the container's system is in its resources".into());
    };
    rustfmu::core::resources::resource_dir(&uri)
        .ok_or_else(|| format!("fmuResourceLocation '{uri}' is not a file: URI of a folder"))
}

/// The resources folder of FMI 3.0's resourcePath (a native absolute path).
pub(crate) fn resources_of_path(path: Option<String>) -> Result<std::path::PathBuf, String> {
    let Some(path) = path else {
        return Err("resourcePath is NULL: the container's system is in its resources".into());
    };
    let p = Path::new(&path);
    if p.is_absolute() {
        Ok(p.to_path_buf())
    } else {
        Err(format!("resourcePath '{path}' is not an absolute path"))
    }
}
