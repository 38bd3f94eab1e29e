//! The dependency checks of [`crate::depends`] through FMI 3.0, for a library that exports no
//! FMI 2.0 (`#[fmu(fmi3_only)]`, `export_fmi3!`): the same random points, asked through
//! `fmi3GetDirectionalDerivative` and the FMI 3.0 getters. And what only FMI 3.0 has: the
//! `depends` of a clocked output, checked by ticking its clocks with each input moved on its
//! own (a clocked output is discrete: it has no directional derivative, but a value that moves
//! proves a dependency as surely).
//!
//! Arrays are left out of these checks (their lengths may be structural parameters): a
//! `depends` naming an array, or of one, is not checked here.

use crate::depends::{Known, Point, Probe, Report, Rng, by_columns, note_moved, spread_by, start_of, states};
use fmi_conformance::fmi3::api::Api as Fmi3;
use fmi_conformance::fmi3::types::{fmi3Instance, fmi3Status};
use fmi_conformance::fmi3::{LogSink, log_message};
use rustfmu::description::{Causality, ModelDescription, VarType, Variable};
use std::ffi::{CString, c_void};
use std::path::Path;

/// How many random points the clocked check ticks at (each moves every input once).
const CLOCKED_POINTS: usize = 4;

/// A loaded FMI 3.0 library for the checks.
pub(crate) struct Api3 {
    fmi: Fmi3,
    token: CString,
    resource_path: CString,
    model_exchange: bool,
    co_simulation: bool,
    /// The FMU has clocks: its co-simulation instances are made with eventModeUsed, as FMI 3.0
    /// (4.2.1) requires.
    clocks: bool,
}

type Ok<'a> = &'a dyn Fn(fmi3Status, &str) -> Result<(), String>;

impl Api3 {
    pub(crate) fn load(
        so: &Path,
        d: &ModelDescription,
        token: &str,
        resource_path: &str,
        model_exchange: bool,
        co_simulation: bool,
    ) -> Result<Api3, String> {
        Ok(Api3 {
            fmi: Fmi3::load(so)?,
            token: CString::new(token).unwrap_or_default(),
            resource_path: CString::new(resource_path).unwrap_or_default(),
            model_exchange,
            co_simulation,
            clocks: d.variables.iter().any(|v| v.var_type == VarType::Clock),
        })
    }

    /// Runs `body` on a fresh instance (model exchange if `me`, else co-simulation), freeing it
    /// afterwards.
    fn with_instance<T>(
        &self,
        me: bool,
        body: impl FnOnce(fmi3Instance, Ok) -> Result<T, String>,
    ) -> Result<T, String> {
        let sink = Box::<LogSink>::default();
        let name = CString::new("fmu-build-depends").unwrap();
        // SAFETY: every string is NUL-terminated and outlives the call; the sink outlives the
        // instance (freed below, before the sink).
        let c = unsafe {
            if me {
                (self.fmi.instantiate_model_exchange)(
                    name.as_ptr(),
                    self.token.as_ptr(),
                    self.resource_path.as_ptr(),
                    false,
                    false,
                    sink.env(),
                    Some(log_message),
                )
            } else {
                (self.fmi.instantiate_co_simulation)(
                    name.as_ptr(),
                    self.token.as_ptr(),
                    self.resource_path.as_ptr(),
                    false,
                    false,
                    self.clocks,
                    false,
                    std::ptr::null(),
                    0,
                    sink.env(),
                    Some(log_message),
                    None,
                )
            }
        };
        let said = |sink: &LogSink| {
            sink.take()
                .into_iter()
                .map(|e| e.message)
                .collect::<Vec<_>>()
                .join("; ")
        };
        if c.is_null() {
            return Err(format!("fmi3Instantiate returned NULL: {}", said(&sink)));
        }
        let ok = |s: fmi3Status, what: &str| {
            if s == 0 {
                Ok(())
            } else {
                Err(format!("{what} answered status {s}: {}", said(&sink)))
            }
        };
        let result = body(c, &ok);
        // SAFETY: `c` is live and not used afterwards.
        unsafe { (self.fmi.free_instance)(c) };
        result
    }

    /// Sets a scalar variable of a number type (a Boolean from 0 or 1).
    ///
    /// # Safety
    /// `c` is a live instance of this library.
    unsafe fn set(&self, c: fmi3Instance, v: &Variable, x: f64) -> fmi3Status {
        let vr = [v.value_reference];
        let f = &self.fmi;
        let any = |set: fmi_conformance::fmi3::api::SetAny, bytes: &[u8]| {
            // SAFETY: one value reference, one value of the setter's type in `bytes`.
            unsafe { set(c, vr.as_ptr(), 1, bytes.as_ptr() as *const c_void, 1) }
        };
        // SAFETY: one value reference, one value of the setter's type.
        unsafe {
            match v.var_type {
                VarType::Real => (f.set_float64)(c, vr.as_ptr(), 1, [x].as_ptr(), 1),
                VarType::Float32 => any(f.set_float32, &(x as f32).to_ne_bytes()),
                VarType::Integer => (f.set_int32)(c, vr.as_ptr(), 1, [x as i32].as_ptr(), 1),
                VarType::Int8 => any(f.set_int8, &(x as i8).to_ne_bytes()),
                VarType::UInt8 => any(f.set_uint8, &(x as u8).to_ne_bytes()),
                VarType::Int16 => any(f.set_int16, &(x as i16).to_ne_bytes()),
                VarType::UInt16 => any(f.set_uint16, &(x as u16).to_ne_bytes()),
                VarType::UInt32 => any(f.set_uint32, &(x as u32).to_ne_bytes()),
                VarType::UInt64 => any(f.set_uint64, &(x as u64).to_ne_bytes()),
                VarType::Int64 | VarType::Enumeration => (f.set_int64)(c, vr.as_ptr(), 1, [x as i64].as_ptr(), 1),
                VarType::Boolean => (f.set_boolean)(c, vr.as_ptr(), 1, [x != 0.0].as_ptr(), 1),
                // Not moved by the checks (not a number).
                VarType::String | VarType::Binary | VarType::Clock => 0,
            }
        }
    }

    /// Reads a scalar variable of a number type as f64 (exact for every value these checks
    /// compare: a change in any bit of the value changes the f64, but for 64-bit integers above
    /// 2^53, which no check moves).
    ///
    /// # Safety
    /// `c` is a live instance of this library.
    unsafe fn get(&self, c: fmi3Instance, v: &Variable) -> Result<f64, fmi3Status> {
        let vr = [v.value_reference];
        let f = &self.fmi;
        let mut bytes = [0u8; 8];
        let any = |get: fmi_conformance::fmi3::api::GetAny, bytes: &mut [u8; 8]| {
            // SAFETY: one value reference; 8 bytes hold one value of any number type.
            unsafe { get(c, vr.as_ptr(), 1, bytes.as_mut_ptr() as *mut c_void, 1) }
        };
        let (status, x) = match v.var_type {
            VarType::Real => {
                let mut x = [0.0];
                // SAFETY: one value reference, one value.
                let status = unsafe { (f.get_float64)(c, vr.as_ptr(), 1, x.as_mut_ptr(), 1) };
                (status, x[0])
            }
            VarType::Integer => {
                let mut x = [0];
                // SAFETY: one value reference, one value.
                let status = unsafe { (f.get_int32)(c, vr.as_ptr(), 1, x.as_mut_ptr(), 1) };
                (status, x[0] as f64)
            }
            VarType::Int64 | VarType::Enumeration => {
                let mut x = [0];
                // SAFETY: one value reference, one value.
                let status = unsafe { (f.get_int64)(c, vr.as_ptr(), 1, x.as_mut_ptr(), 1) };
                (status, x[0] as f64)
            }
            VarType::Boolean => {
                let mut x = [0u8];
                // SAFETY: one value reference, one value (fmi3Boolean is C bool, one byte).
                let status = unsafe { (f.get_boolean)(c, vr.as_ptr(), 1, x.as_mut_ptr(), 1) };
                (status, x[0] as f64)
            }
            VarType::Float32 => (
                any(f.get_float32, &mut bytes),
                f32::from_ne_bytes(bytes[..4].try_into().unwrap()) as f64,
            ),
            VarType::Int8 => (any(f.get_int8, &mut bytes), bytes[0] as i8 as f64),
            VarType::UInt8 => (any(f.get_uint8, &mut bytes), bytes[0] as f64),
            VarType::Int16 => (
                any(f.get_int16, &mut bytes),
                i16::from_ne_bytes([bytes[0], bytes[1]]) as f64,
            ),
            VarType::UInt16 => (
                any(f.get_uint16, &mut bytes),
                u16::from_ne_bytes([bytes[0], bytes[1]]) as f64,
            ),
            VarType::UInt32 => (
                any(f.get_uint32, &mut bytes),
                u32::from_ne_bytes(bytes[..4].try_into().unwrap()) as f64,
            ),
            VarType::UInt64 => (any(f.get_uint64, &mut bytes), u64::from_ne_bytes(bytes) as f64),
            VarType::String | VarType::Binary | VarType::Clock => (0, 0.0),
        };
        if status == 0 { Ok(x) } else { Err(status) }
    }

    /// Event Mode until the model needs no more updates (after initialization, or after the
    /// clocks were set).
    ///
    /// # Safety
    /// `c` is a live instance of this library, in Event Mode.
    unsafe fn update_discrete_states(&self, c: fmi3Instance, ok: Ok) -> Result<(), String> {
        for _ in 0..100 {
            let (mut again, mut terminate, mut nominals, mut values, mut defined) = (0u8, 0u8, 0u8, 0u8, 0u8);
            let mut next = 0.0;
            // SAFETY: `c` is live (the caller's promise); every output points to a local of its type.
            let status = unsafe {
                (self.fmi.update_discrete_states)(
                    c,
                    &mut again,
                    &mut terminate,
                    &mut nominals,
                    &mut values,
                    &mut defined,
                    &mut next,
                )
            };
            ok(status, "fmi3UpdateDiscreteStates")?;
            if terminate != 0 {
                return Err("fmi3UpdateDiscreteStates asked to terminate".into());
            }
            if again == 0 {
                return Ok(());
            }
        }
        Err("fmi3UpdateDiscreteStates asked for another update 100 times".into())
    }

    /// Sets `values`, then enters and leaves Initialization Mode at t = 0.
    ///
    /// # Safety
    /// `c` is a live instance of this library, in Instantiated.
    unsafe fn initialize(&self, c: fmi3Instance, ok: Ok, values: &[(&Variable, f64)]) -> Result<(), String> {
        for (v, x) in values {
            // SAFETY: `c` is live (the caller's promise).
            ok(unsafe { self.set(c, v, *x) }, &format!("setting '{}' to {x}", v.name))?;
        }
        // SAFETY: as above.
        unsafe {
            ok(
                (self.fmi.enter_initialization_mode)(c, false, 0.0, 0.0, false, 0.0),
                "fmi3EnterInitializationMode",
            )?;
            ok((self.fmi.exit_initialization_mode)(c), "fmi3ExitInitializationMode")
        }
    }
}

impl Probe for Api3 {
    fn derivative_function(&self) -> &'static str {
        "fmi3GetDirectionalDerivative"
    }

    fn reaches(&self, v: &Variable) -> bool {
        !v.is_array()
    }

    fn jacobian(&self, d: &ModelDescription, at: &Point, rng: &mut Rng) -> Result<Vec<Vec<f64>>, String> {
        let Point {
            unknowns,
            knowns,
            parameters,
            scale,
        } = *at;
        if !self.model_exchange {
            return Err("the library has no FMI 3.0 model exchange".into());
        }
        self.with_instance(true, |c, ok| {
            // SAFETY: `c` is live; every array passed has the length passed with it.
            unsafe {
                self.initialize(c, ok, parameters)?;
                self.update_discrete_states(c, ok)?;
                ok((self.fmi.enter_continuous_time_mode)(c), "fmi3EnterContinuousTimeMode")?;
                let mut n = 0usize;
                ok(
                    (self.fmi.get_number_of_continuous_states)(c, &mut n),
                    "fmi3GetNumberOfContinuousStates",
                )?;
                let mut x = vec![0.0; n];
                ok(
                    (self.fmi.get_continuous_states)(c, x.as_mut_ptr(), n),
                    "fmi3GetContinuousStates",
                )?;
                // The states spread as FMI 2.0's check does, where each is one element of the
                // vector (no array state: then their places in it are known).
                let states = states(d);
                if states.len() == n && states.iter().all(|s| !s.is_array()) {
                    for (xj, s) in x.iter_mut().zip(&states) {
                        *xj = spread_by(rng, s, *xj, scale);
                    }
                }
                ok(
                    (self.fmi.set_continuous_states)(c, x.as_ptr(), n),
                    "fmi3SetContinuousStates",
                )?;
                for k in knowns {
                    if let Known::Input(v) = k {
                        let x = spread_by(rng, v, start_of(v), scale);
                        ok(self.set(c, v, x), &format!("fmi3SetFloat64 of the input '{}'", v.name))?;
                    }
                }
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
                            1,
                            column.as_mut_ptr(),
                            column.len(),
                        ),
                        &format!("fmi3GetDirectionalDerivative with respect to '{}'", k.name),
                    )
                })
            }
        })
    }

    fn initial_values(&self, knowns: &[&Variable], values: &[f64], unknowns: &[&Variable]) -> Result<Vec<f64>, String> {
        // Co-simulation where the library has it (as FMI 2.0's check).
        self.with_instance(!self.co_simulation, |c, ok| {
            let set: Vec<(&Variable, f64)> = knowns.iter().copied().zip(values.iter().copied()).collect();
            // SAFETY: `c` is live.
            unsafe {
                self.initialize(c, ok, &set)?;
                unknowns
                    .iter()
                    .map(|v| {
                        self.get(c, v)
                            .or_else(|s| ok(s, &format!("getting '{}'", v.name)).map(|_| f64::NAN))
                    })
                    .collect()
            }
        })
    }
}

/// The inputs a clocked output may depend on at its tick: every scalar number input, clocked
/// or not.
fn clocked_knowns(d: &ModelDescription) -> Vec<&Variable> {
    d.variables
        .iter()
        .filter(|v| {
            v.causality == Causality::Input
                && !v.is_array()
                && !matches!(v.var_type, VarType::String | VarType::Binary | VarType::Clock)
        })
        .collect()
}

/// Checks the `depends` of the clocked outputs: at a few random points (inputs drawn around their
/// start values) every input clock is activated twice in the Event Mode after initialization
/// (two super-dense ticks), the inputs set and the discrete states updated each time; each input
/// moved on its own at the second tick, in a fresh instance. An output that moved depends on
/// that input: a problem where the declaration leaves it out. A dependency seen at the first
/// tick only (a sampled controller whose first command uses the first sample, where later ones
/// hold the previous) is a note. An output computed from an earlier tick (a delay) depends on
/// no input at its tick.
///
/// One function of ~170 lines, kept whole: the tick closures, the points and the report all
/// read the outputs, inputs and clocks it selects first.
pub(crate) fn check_clocked(api: &Api3, d: &ModelDescription) -> Report {
    let mut report = Report::default();
    let outputs: Vec<&Variable> = d
        .variables
        .iter()
        .filter(|v| {
            v.is_clocked()
                && v.causality == Causality::Output
                && !v.is_array()
                && !matches!(v.var_type, VarType::String | VarType::Binary | VarType::Clock)
        })
        .collect();
    let inputs = clocked_knowns(d);
    let input_clocks: Vec<&Variable> = d
        .variables
        .iter()
        .filter(|v| v.var_type == VarType::Clock && v.causality == Causality::Input)
        .collect();
    let clocks: Vec<u32> = input_clocks.iter().map(|v| v.value_reference).collect();
    // The outputs of the input clocks' ticks (an output clock's variables are readable only when
    // the model ticks it: not checked here).
    let outputs: Vec<&Variable> = outputs
        .into_iter()
        .filter(|v| v.fmi3.clocks.iter().all(|c| input_clocks.iter().any(|k| k.name == *c)))
        .collect();
    if outputs.is_empty() || inputs.is_empty() || clocks.is_empty() {
        return report;
    }
    // One tick: the input clocks activated, the inputs set, the clocked outputs read while their
    // clocks are active (FMI 3.0, 5.2.2: before fmi3UpdateDiscreteStates ends the tick).
    let one_tick = |c: fmi3Instance, ok: Ok, values: &[f64]| -> Result<Vec<f64>, String> {
        // SAFETY: `c` is live; every array passed has the length passed with it.
        unsafe {
            ok(
                (api.fmi.set_clock)(c, clocks.as_ptr(), clocks.len(), vec![true; clocks.len()].as_ptr()),
                "fmi3SetClock of the input clocks",
            )?;
            for (v, &x) in inputs.iter().zip(values) {
                ok(api.set(c, v, x), &format!("setting the input '{}' to {x}", v.name))?;
            }
            let out: Vec<f64> = outputs
                .iter()
                .map(|v| {
                    api.get(c, v)
                        .or_else(|s| ok(s, &format!("getting '{}' at the tick", v.name)).map(|_| f64::NAN))
                })
                .collect::<Result<_, _>>()?;
            api.update_discrete_states(c, ok)?;
            Ok(out)
        }
    };
    // Two ticks after initialization (the second in the same Event Mode, a later super-dense
    // instant): the outputs of each. A model may treat its first tick apart (no earlier sample
    // to hold yet): the second shows what every later tick does.
    let two_ticks = |first: &[f64], second: &[f64]| -> Result<(Vec<f64>, Vec<f64>), String> {
        api.with_instance(api.model_exchange, |c, ok| {
            // SAFETY: `c` is live, in Instantiated.
            unsafe { api.initialize(c, ok, &[])? };
            Ok((one_tick(c, ok, first)?, one_tick(c, ok, second)?))
        })
    };
    // seen[u][k]: how input k moved output u at a later tick; first[u][k]: at the first tick.
    let mut seen: Vec<Vec<Option<String>>> = vec![vec![None; inputs.len()]; outputs.len()];
    let mut first: Vec<Vec<Option<String>>> = vec![vec![None; inputs.len()]; outputs.len()];
    let mut rng = Rng(0x000c_10c4_edde_9ed5);
    let mut checked_points = 0;
    for point in 0..CLOCKED_POINTS {
        let base: Vec<f64> = inputs
            .iter()
            .map(|v| {
                let x = crate::depends::start_number(v);
                match (point, v.var_type) {
                    (0, _) => x,
                    (_, VarType::Boolean) => (rng.uniform(0.0, 1.0) < 0.5) as u8 as f64,
                    (_, VarType::Real | VarType::Float32) => spread_by(&mut rng, v, x, 1.0),
                    _ => x + rng.uniform(-2.0, 3.0).floor(),
                }
            })
            .collect();
        let Some(at_base) = report.or_skip("the clocked dependency check", point, two_ticks(&base, &base)) else {
            continue;
        };
        checked_points += 1;
        for (j, v) in inputs.iter().enumerate() {
            let mut moved = base.clone();
            moved[j] = crate::depends::perturbed(v, base[j]);
            let how = |a: f64, b: f64| format!("{} = {} gave {a}, {} = {} gave {b}", v.name, base[j], v.name, moved[j]);
            // A later tick: the first one with the base inputs, the second with this one moved.
            match two_ticks(&base, &moved) {
                Ok((_, values)) => note_moved(&mut seen, j, &at_base.1, &values, how),
                Err(e) => report.notes.push(format!(
                    "the clocked dependency check could not move '{}' from {} to {}: {e}",
                    v.name, base[j], moved[j]
                )),
            }
            // The first tick.
            if let Ok((values, _)) = two_ticks(&moved, &moved) {
                note_moved(&mut first, j, &at_base.0, &values, how);
            }
        }
    }
    if checked_points == 0 {
        return report;
    }
    let names: Vec<&str> = inputs.iter().map(|v| v.name).collect();
    for (i, u) in outputs.iter().enumerate() {
        let c = crate::depends::compare(u.depends_on, &names, &seen[i]);
        let Some(declared) = u.depends_on else {
            continue;
        };
        // The clocks a clocked output depends on are added by the derive (FMI 3.0's
        // `dependencies` of a clocked variable name its clocks): the declaration the user wrote is
        // the rest.
        let written: Vec<&str> = declared
            .iter()
            .copied()
            .filter(|n| !d.variables.iter().any(|v| v.name == *n && v.var_type == VarType::Clock))
            .collect();
        // Only at the first tick: said, not refused (a model may compute its first command from
        // the first sample, where later ticks hold the previous one).
        let at_first = crate::depends::compare(u.depends_on, &names, &first[i]);
        let only_first: Vec<usize> = at_first
            .missing
            .iter()
            .copied()
            .filter(|j| !c.missing.contains(j))
            .collect();
        if !only_first.is_empty() {
            report.notes.push(format!(
                "clocked output '{}' depends at the first tick after initialization on {} ({}), which its \
                 `depends = {}` leaves out; later ticks do not: a direct feedthrough at the first tick only, \
                 which an importer reading the description does not expect",
                u.name,
                crate::depends::list(&only_first.iter().map(|j| names[*j]).collect::<Vec<_>>()),
                first[i][only_first[0]].as_deref().unwrap_or_default(),
                crate::depends::list(&written)
            ));
        }
        for j in c.missing {
            report.problems.push(format!(
                "clocked output '{}' depends at its tick on the input '{}' ({} for '{}'), which its \
                 `depends = {}` leaves out: add '{}' to it",
                u.name,
                names[j],
                seen[i][j].as_deref().unwrap_or_default(),
                u.name,
                crate::depends::list(&written),
                names[j]
            ));
        }
    }
    report
}

/// Every check of [`crate::depends`] through FMI 3.0, and the clocked outputs' `depends`, on a
/// library [`Api3::load`] loaded (or a note of why it did not).
pub(crate) fn check_all(api: Result<Api3, String>, d: &ModelDescription) -> Vec<Report> {
    let api = match api {
        Ok(api) => api,
        Err(e) => {
            return vec![Report::not_run(format!(
                "`depends` was not checked through FMI 3.0: {e}"
            ))];
        }
    };
    let mut reports = vec![crate::depends::check_initial_with(&api, d)];
    if api.model_exchange {
        reports.push(crate::depends::check_with(&api, d));
    }
    reports.push(check_clocked(&api, d));
    reports
}
