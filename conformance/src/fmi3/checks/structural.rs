//! FMI 3.0 structural parameters and Configuration Mode (the standard's array variables sized by
//! `<Dimension valueReference>`, `causality="structuralParameter"`, and the Configuration and
//! Reconfiguration Mode of its state machine): the suite is an importer that changes every UInt64
//! structural parameter in Configuration Mode (from Instantiated) and the tunable ones again in
//! Reconfiguration Mode (from Step Mode in co-simulation, from Event Mode in model exchange), and
//! checks what the standard says of it: each array whose `<Dimension valueReference>` names a
//! structural parameter then has that many elements per dimension (nValues of the getters counts
//! them, row-major, and the old count is refused); model exchange's state vector, its derivatives
//! and its Jacobian have the states' new element counts; the structural parameters are set
//! nowhere else, nothing else is set there, values outside min/max are refused.

use super::*;
use crate::calllog::Val;
use crate::fmi3::{Sizes, Variable, euler_step_n, floats};
use crate::outcome::NOT_DECLARED;
use md_reader::fmi3::Dimension;
use std::ffi::c_void;

/// A UInt64 structural parameter the check changes.
struct Param<'a> {
    v: &'a Variable,
    start: u64,
    min: u64,
    max: u64,
    tunable: bool,
    /// The value set in Configuration Mode (the start when no other value is legal).
    new: u64,
}

fn as_u64(x: f64) -> u64 {
    if x <= 0.0 {
        0
    } else if x >= u64::MAX as f64 {
        u64::MAX
    } else {
        x as u64
    }
}

fn parse_u64(v: &Variable) -> Option<u64> {
    v.start.as_deref().and_then(|s| s.trim().parse().ok())
}

/// Another legal value of the parameter: start ± 1 or ± 2 within min and max, the direction
/// alternating from parameter to parameter (`k`) so that the sizes differ from one another (a
/// dimension taken from the wrong parameter then gives another count); at least 1 for a
/// parameter that sizes arrays where that is possible.
fn another_value(start: u64, min: u64, max: u64, sizes_arrays: bool, k: usize) -> Option<u64> {
    let deltas: [i64; 4] = match k % 4 {
        0 => [-1, 1, -2, 2],
        1 => [1, -1, 2, -2],
        2 => [-2, 2, -1, 1],
        _ => [2, -2, 1, -1],
    };
    let legal = |x: &u64| *x >= min && *x <= max && *x != start;
    let candidates = || deltas.iter().filter_map(|d| start.checked_add_signed(*d)).filter(legal);
    candidates()
        .find(|x| !sizes_arrays || *x >= 1)
        .or_else(|| candidates().next())
}

/// What the check needs of the description, and the instances it makes.
struct Setup<'a> {
    fmu: &'a Fmu3,
    me: bool,
    params: Vec<Param<'a>>,
    /// The sizes with every structural parameter at its start.
    base: Sizes,
    /// The sizes after Configuration Mode.
    new: Sizes,
    /// The arrays a structural parameter sizes (types with a getter of values).
    arrays: Vec<&'a Variable>,
}

/// Whether fmi3Get{VariableType} shows the variable in Instantiated: start values only (FMI
/// 3.0.2: inputs, and initial exact or approx).
fn readable_in_instantiated(v: &Variable) -> bool {
    v.causality != Causality::Independent
        && (v.causality == Causality::Input
            || matches!(
                crate::standard::initial(v.causality, v.variability, v.declared_initial),
                Some(Initial::Exact | Initial::Approx)
            ))
}

fn get_u64(inst: &Inst, vr: u32) -> (fmi3Status, u64) {
    // Through the call log (Inst::get_as): `fmi3GetUInt64 vr=[..] nValues=1`.
    let (s, bytes) = inst.get_as(Type::UInt64, vr, 1);
    let x = bytes.try_into().map_or(0xdead_beef_u64, u64::from_ne_bytes);
    (s, x)
}

fn set_u64(inst: &Inst, vr: u32, x: u64) -> fmi3Status {
    inst.args(vec![
        ("vr", Val::U32s(vec![vr])),
        ("nValues", Val::U64(1)),
        ("bytes", Val::Bytes(x.to_ne_bytes().to_vec())),
    ])
    // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an FMU
    // state.
    .call("fmi3SetUInt64", |c| unsafe {
        (inst.api().set_uint64)(c, &vr, 1, &x as *const u64 as *const c_void, 1)
    })
}

fn enter_config(inst: &Inst) -> fmi3Status {
    inst.unary("fmi3EnterConfigurationMode", inst.api().enter_configuration_mode)
}

fn exit_config(inst: &Inst) -> fmi3Status {
    inst.unary("fmi3ExitConfigurationMode", inst.api().exit_configuration_mode)
}

impl<'a> Setup<'a> {
    fn new(fmu: &'a Fmu3, me: bool) -> Setup<'a> {
        let id = &fmu.id;
        let named: Vec<u32> = fmu
            .md
            .variables
            .iter()
            .flat_map(|v| v.dimensions.iter())
            .filter_map(|d| match d {
                Dimension::Parameter(vr) => Some(*vr),
                Dimension::Fixed(_) => None,
            })
            .collect();
        // The constants' values, and the structural parameters' starts (checked below).
        let mut base = fmu.start_sizes().clone();
        let mut params = vec![];
        for v in fmu
            .md
            .variables
            .iter()
            .filter(|v| v.causality == Causality::StructuralParameter)
        {
            if v.ty != Type::UInt64 || v.array {
                limitation(format!(
                    "structural parameter '{}' ({}{}): left at its start (the check changes scalar UInt64 ones)",
                    v.name,
                    v.ty,
                    if v.array { " array" } else { "" }
                ));
                continue;
            }
            let start = parse_u64(v).unwrap_or_else(|| {
                panic!(
                    "{id}: structural parameter '{}' has no UInt64 start value ({:?}; initial is exact for structural parameters)",
                    v.name, v.start
                )
            });
            let min = v.min.map_or(0, as_u64);
            let max = v.max.map_or(u64::MAX, as_u64);
            assert!(
                min <= start && start <= max,
                "{id}: structural parameter '{}': start {start} outside min {min} .. max {max}",
                v.name
            );
            let sizes_arrays = named.contains(&v.vr);
            let new = another_value(start, min, max, sizes_arrays, params.len()).unwrap_or_else(|| {
                limitation(format!(
                    "{NOT_DECLARED}another legal value of structural parameter '{}' (min {min}, max {max}, start {start})",
                    v.name
                ));
                start
            });
            base.insert(v.vr, start);
            params.push(Param {
                v,
                start,
                min,
                max,
                tunable: v.variability == Variability::Tunable,
                new,
            });
        }
        let mut new = base.clone();
        for p in &params {
            new.insert(p.v.vr, p.new);
        }
        let mut arrays = vec![];
        for v in fmu
            .md
            .variables
            .iter()
            .filter(|v| v.dimensions.iter().any(|d| matches!(d, Dimension::Parameter(_))))
        {
            if matches!(v.ty, Type::String | Type::Binary | Type::Clock) || !v.clocks.is_empty() {
                limitation(format!(
                    "array '{}' ({}{}): its element count is not read",
                    v.name,
                    v.ty,
                    if v.clocks.is_empty() { "" } else { ", clocked" }
                ));
                continue;
            }
            arrays.push(v);
        }
        Setup {
            fmu,
            me,
            params,
            base,
            new,
            arrays,
        }
    }

    fn id(&self) -> &str {
        &self.fmu.id
    }

    fn which(&self) -> &'static str {
        if self.me { "Model Exchange" } else { "Co-Simulation" }
    }

    /// The lengths of a variable's dimensions under `sizes` (none for a scalar).
    fn dims(&self, v: &Variable, sizes: &Sizes) -> Vec<u64> {
        self.fmu.dims_at(v, sizes)
    }

    /// The number of values of a variable under `sizes` (the product of its lengths; 1 for a scalar).
    fn count(&self, v: &Variable, sizes: &Sizes) -> usize {
        self.fmu.count_at(v, sizes)
    }

    /// The structural parameters' values, for messages ("m = 2, n = 4").
    fn show(&self, sizes: &Sizes) -> String {
        self.params
            .iter()
            .map(|p| format!("{} = {}", p.v.name, sizes[&p.v.vr]))
            .collect::<Vec<_>>()
            .join(", ")
    }

    fn fresh(&self) -> Inst<'a> {
        if self.me {
            Inst::me(self.fmu)
        } else {
            Inst::cs(self.fmu)
        }
    }

    /// A new instance configured with the new values (back in Instantiated).
    fn configured(&self) -> Inst<'a> {
        let inst = self.fresh();
        self.ok(&inst, enter_config(&inst), "fmi3EnterConfigurationMode in Instantiated");
        for p in &self.params {
            let s = set_u64(&inst, p.v.vr, p.new);
            self.ok(
                &inst,
                s,
                &format!("fmi3SetUInt64('{}', {}) in Configuration Mode", p.v.name, p.new),
            );
        }
        self.ok(&inst, exit_config(&inst), "fmi3ExitConfigurationMode");
        inst
    }

    /// A configured instance, its inputs set, initialized, one step on: in Step Mode (CS) or
    /// in Event Mode (ME, entered after a step).
    fn stepping(&self) -> Inst<'a> {
        let mut inst = self.configured();
        self.set_inputs(&inst, &self.new);
        inst.initialize();
        if self.me {
            let nx = self.nx(&self.new);
            euler_step_n(&mut inst, nx, self.fmu.step_size());
            self.ok(
                &inst,
                inst.unary("fmi3EnterEventMode", inst.api().enter_event_mode),
                "fmi3EnterEventMode",
            );
        } else {
            inst.step(self.fmu.step_size());
        }
        inst
    }

    /// The tunable structural parameters that were changed (Reconfiguration Mode sets them back).
    fn tunables(&self) -> impl Iterator<Item = &Param<'a>> {
        self.params.iter().filter(|p| p.tunable && p.new != p.start)
    }

    /// The sizes after Reconfiguration Mode: the tunable parameters back at their starts.
    fn reconfigured_sizes(&self) -> Sizes {
        let mut s = self.new.clone();
        for p in self.tunables() {
            s.insert(p.v.vr, p.start);
        }
        s
    }

    /// From [`Setup::stepping`] into Reconfiguration Mode, the tunable parameters set to their
    /// starts, and out again (Step Mode, Event Mode).
    fn reconfigure(&self, inst: &Inst) {
        self.ok(
            inst,
            enter_config(inst),
            &format!("fmi3EnterConfigurationMode from {}", self.running()),
        );
        for p in self.tunables() {
            let (s, x) = get_u64(inst, p.v.vr);
            self.ok(
                inst,
                s,
                &format!("fmi3GetUInt64('{}') in Reconfiguration Mode", p.v.name),
            );
            assert_eq!(
                x,
                p.new,
                "{}: {}: '{}' reads {x} in Reconfiguration Mode, set to {} in Configuration Mode",
                self.id(),
                self.which(),
                p.v.name,
                p.new
            );
            let s = set_u64(inst, p.v.vr, p.start);
            self.ok(
                inst,
                s,
                &format!(
                    "fmi3SetUInt64 of tunable '{}' = {} in Reconfiguration Mode",
                    p.v.name, p.start
                ),
            );
        }
        self.ok(
            inst,
            exit_config(inst),
            "fmi3ExitConfigurationMode from Reconfiguration Mode",
        );
    }

    fn running(&self) -> &'static str {
        if self.me { "Event Mode" } else { "Step Mode" }
    }

    fn ok(&self, inst: &Inst, s: fmi3Status, what: &str) {
        assert_eq!(
            s,
            fmi3OK,
            "{}: {}: {what}: {}: {}",
            self.id(),
            self.which(),
            status_name(s),
            inst.log_text()
        );
    }

    /// `call` on `inst` must be refused with fmi3Error (and a message: [`Inst::call`]).
    fn refused(&self, inst: &Inst, what: &str, call: impl FnOnce(&Inst) -> fmi3Status) {
        let s = call(inst);
        crate::calllog::standard_requires(crate::replay::Expected::ERROR);
        assert_eq!(
            s,
            fmi3Error,
            "{}: {}: {what}: expected fmi3Error, got {}: {}",
            self.id(),
            self.which(),
            status_name(s),
            inst.log_text()
        );
    }

    /// Every structural parameter reads `want(p)`.
    fn read_params(&self, inst: &Inst, want: impl Fn(&Param) -> u64, at: &str) {
        for p in &self.params {
            let (s, x) = get_u64(inst, p.v.vr);
            self.ok(inst, s, &format!("fmi3GetUInt64('{}') {at}", p.v.name));
            assert_eq!(
                x,
                want(p),
                "{}: {}: structural parameter '{}' reads {x} {at}, expected {}",
                self.id(),
                self.which(),
                p.v.name,
                want(p)
            );
        }
    }

    /// Every sized array read with its element count under `sizes` (`all`: also those
    /// Instantiated does not show). Returns the number of reads.
    fn read_arrays(&self, inst: &Inst, sizes: &Sizes, all: bool, at: &str) -> usize {
        let mut n = 0;
        for v in self.arrays.iter().filter(|v| all || readable_in_instantiated(v)) {
            let (dims, count) = (self.dims(v, sizes), self.count(v, sizes));
            let (s, bytes) = inst.get_raw_n(v, count);
            assert_eq!(
                s,
                fmi3OK,
                "{}: {}: fmi3Get{}('{}') with nValues = {count} (dimensions {dims:?}: {}) {at}: {}: {}",
                self.id(),
                self.which(),
                crate::fmi3::accessor(v.ty),
                v.name,
                self.show(sizes),
                status_name(s),
                inst.log_text()
            );
            if v.ty.is_float() {
                let x = floats(v.ty, &bytes);
                assert!(
                    x.iter().all(|x| x.is_finite()),
                    "{}: {}: '{}' {at}: not finite: {x:?}",
                    self.id(),
                    self.which(),
                    v.name
                );
            }
            n += 1;
        }
        n
    }

    /// The continuous Float inputs sized by structural parameters, set with their counts under
    /// `sizes` (0.1, 0.2, ... inside min/max), and the scalar ones ([`excite_scalars`]).
    fn set_inputs(&self, inst: &Inst, sizes: &Sizes) {
        excite_scalars(inst);
        for v in self
            .arrays
            .iter()
            .filter(|v| v.causality == Causality::Input && v.ty.is_float() && v.variability == Variability::Continuous)
        {
            let n = self.count(v, sizes);
            let x: Vec<f64> = (0..n)
                .map(|k| {
                    let mut x = 0.1 * (k as f64 + 1.0);
                    if let Some(lo) = v.min {
                        x = x.max(lo);
                    }
                    if let Some(hi) = v.max {
                        x = x.min(hi);
                    }
                    x
                })
                .collect();
            let bytes: Vec<u8> = if v.ty == Type::Float32 {
                x.iter().flat_map(|x| (*x as f32).to_ne_bytes()).collect()
            } else {
                x.iter().flat_map(|x| x.to_ne_bytes()).collect()
            };
            let s = inst.set_raw(v, &bytes);
            self.ok(
                inst,
                s,
                &format!(
                    "fmi3Set{}('{}') with nValues = {n} ({})",
                    v.ty,
                    v.name,
                    self.show(sizes)
                ),
            );
        }
    }

    /// The continuous states (state, derivative) in the order of `<ContinuousStateDerivative>`.
    fn states(&self) -> Vec<(&'a Variable, &'a Variable)> {
        self.fmu.states().unwrap_or_else(|e| panic!("{}: {e}", self.id()))
    }

    /// The number of continuous states under `sizes`: each state's element count.
    fn nx(&self, sizes: &Sizes) -> usize {
        self.fmu.nx_at(sizes)
    }

    /// Model exchange under `sizes`: fmi3GetNumberOfContinuousStates is [`Setup::nx`]; the
    /// state, derivative and nominal vectors of that length; the states and derivatives are the
    /// state and derivative variables' elements, in order. Returns nx.
    fn me_vectors(&self, inst: &Inst, sizes: &Sizes, at: &str) -> usize {
        let (id, api) = (self.id(), inst.api());
        let nx = self.nx(sizes);
        let n = inst.n_states();
        assert_eq!(
            n,
            nx,
            "{id}: fmi3GetNumberOfContinuousStates {at}: {n}, but the states' arrays have {nx} elements ({})",
            self.show(sizes)
        );
        let (s, x) = inst.vector("fmi3GetContinuousStates", api.get_continuous_states, nx);
        self.ok(inst, s, &format!("fmi3GetContinuousStates with nx = {nx} {at}"));
        let (s, dx) = inst.vector(
            "fmi3GetContinuousStateDerivatives",
            api.get_continuous_state_derivatives,
            nx,
        );
        self.ok(
            inst,
            s,
            &format!("fmi3GetContinuousStateDerivatives with nx = {nx} {at}"),
        );
        let (s, nominal) = inst.vector(
            "fmi3GetNominalsOfContinuousStates",
            api.get_nominals_of_continuous_states,
            nx,
        );
        self.ok(
            inst,
            s,
            &format!("fmi3GetNominalsOfContinuousStates with nx = {nx} {at}"),
        );
        assert!(
            nominal.iter().all(|v| v.is_finite() && *v > 0.0),
            "{id}: nominals {nominal:?} {at} (finite and > 0)"
        );
        let (mut xs, mut ds) = (vec![], vec![]);
        for (xv, dv) in self.states() {
            for (v, out) in [(xv, &mut xs), (dv, &mut ds)] {
                let count = self.count(v, sizes);
                let (s, bytes) = inst.get_raw_n(v, count);
                self.ok(
                    inst,
                    s,
                    &format!("fmi3Get{}('{}') with nValues = {count} {at}", v.ty, v.name),
                );
                out.extend(floats(v.ty, &bytes));
            }
        }
        assert_eq!(
            crate::bits(&x),
            crate::bits(&xs),
            "{id}: {at}: fmi3GetContinuousStates {x:?} differs from the state variables' elements {xs:?}"
        );
        assert_eq!(
            crate::bits(&dx),
            crate::bits(&ds),
            "{id}: {at}: fmi3GetContinuousStateDerivatives {dx:?} differs from the derivative variables' elements {ds:?}"
        );
        nx
    }

    /// d der(x) / d x with nSeed = nSensitivity = nx (every element of the state and derivative
    /// arrays), against finite differences through fmi3SetContinuousStates; the adjoint its
    /// transpose. In Continuous-Time Mode; the states are restored after.
    fn jacobian(&self, inst: &Inst, nx: usize) {
        let (id, api) = (self.id(), inst.api());
        let Some(i) = self.fmu.md.me.as_ref() else { return };
        if !i.provides_directional_derivatives || nx == 0 {
            return;
        }
        let states = self.states();
        let unknowns: Vec<u32> = states.iter().map(|p| p.1.vr).collect();
        let knowns: Vec<u32> = states.iter().map(|p| p.0.vr).collect();
        let directional = |seed: &[f64]| {
            let mut out = vec![f64::NAN; nx];
            let s = inst.derivative(false, &unknowns, &knowns, seed, &mut out);
            self.ok(
                inst,
                s,
                &format!(
                    "fmi3GetDirectionalDerivative of the {} derivative(s) by the {} state(s), nSeed = nSensitivity = {nx}",
                    unknowns.len(),
                    knowns.len()
                ),
            );
            out
        };
        let (s, x0) = inst.vector("fmi3GetContinuousStates", api.get_continuous_states, nx);
        self.ok(inst, s, "fmi3GetContinuousStates");
        let derivatives = |x: &[f64]| {
            inst.args(vec![("values", Val::F64s(x[..nx].to_vec()))]);
            // SAFETY: a live instance; each pointer is to a live local of the length passed, or is
            // an FMU state.
            let s = inst.call("fmi3SetContinuousStates", |c| unsafe {
                (api.set_continuous_states)(c, x.as_ptr(), nx)
            });
            self.ok(inst, s, "fmi3SetContinuousStates");
            let (s, dx) = inst.vector(
                "fmi3GetContinuousStateDerivatives",
                api.get_continuous_state_derivatives,
                nx,
            );
            self.ok(inst, s, "fmi3GetContinuousStateDerivatives");
            dx
        };
        let f0 = derivatives(&x0);
        let mut jac = vec![vec![0.0; nx]; nx];
        for j in 0..nx {
            let mut seed = vec![0.0; nx];
            seed[j] = 1.0;
            let col = directional(&seed);
            let eps = 1e-6 * x0[j].abs().max(1.0);
            let mut x1 = x0.clone();
            x1[j] += eps;
            let f1 = derivatives(&x1);
            for r in 0..nx {
                let fd = (f1[r] - f0[r]) / eps;
                assert!(
                    (col[r] - fd).abs() <= 1e-4 * (1.0 + col[r].abs().max(fd.abs())),
                    "{id}: d der(x)[{r}] / d x[{j}]: fmi3GetDirectionalDerivative {}, finite differences {fd} (nx = {nx})",
                    col[r]
                );
                jac[r][j] = col[r];
            }
        }
        derivatives(&x0);
        if i.provides_adjoint_derivatives {
            for (r, row) in jac.iter().enumerate() {
                let mut seed = vec![0.0; nx];
                seed[r] = 1.0;
                let mut out = vec![f64::NAN; nx];
                let s = inst.derivative(true, &unknowns, &knowns, &seed, &mut out);
                self.ok(
                    inst,
                    s,
                    &format!("fmi3GetAdjointDerivative, nSeed = nSensitivity = {nx}"),
                );
                for j in 0..nx {
                    assert!(
                        (out[j] - row[j]).abs() <= 1e-10 * (1.0 + row[j].abs()),
                        "{id}: adjoint d der(x)[{r}] / d x[{j}] = {}, directional {}: the adjoint must be the transpose",
                        out[j],
                        row[j]
                    );
                }
            }
        }
    }

    /// A variable that is not a structural parameter, to be refused in (Re)configuration Mode:
    /// a tunable parameter, else a fixed one, else an input.
    fn non_structural(&self) -> Option<&'a Variable> {
        let ok = |v: &&Variable| {
            v.clocks.is_empty()
                && !matches!(v.ty, Type::String | Type::Binary | Type::Clock)
                && v.variability != Variability::Constant
        };
        let of = |c: Causality, var: Option<Variability>| {
            self.fmu
                .md
                .variables
                .iter()
                .filter(ok)
                .find(|v| v.causality == c && var.is_none_or(|x| v.variability == x))
        };
        of(Causality::Parameter, Some(Variability::Tunable))
            .or_else(|| of(Causality::Parameter, None))
            .or_else(|| of(Causality::Input, None))
    }
}

/// What one interface's run counted, for the report.
#[derive(Default)]
struct Counts {
    reads: usize,
    refusals: usize,
    steps: usize,
}

// Over ~150 lines: one instance through a sequence of structural changes, each step depending on
// the sizes the one before set.
fn one_interface(fmu: &Fmu3, me: bool) -> Counts {
    let st = Setup::new(fmu, me);
    let which = st.which();
    let h = fmu.step_size();
    let mut n = Counts::default();

    // 1. The starts in Instantiated; Configuration Mode sets the new values; the arrays follow.
    let mut inst = st.fresh();
    st.read_params(&inst, |p| p.start, "in Instantiated");
    n.reads += st.read_arrays(&inst, &st.base, false, "in Instantiated with the start sizes");
    st.ok(&inst, enter_config(&inst), "fmi3EnterConfigurationMode in Instantiated");
    st.read_params(&inst, |p| p.start, "in Configuration Mode");
    for p in &st.params {
        let s = set_u64(&inst, p.v.vr, p.new);
        st.ok(
            &inst,
            s,
            &format!(
                "fmi3SetUInt64 of {} structural parameter '{}' = {} (start {}) in Configuration Mode",
                p.v.variability, p.v.name, p.new, p.start
            ),
        );
    }
    st.read_params(&inst, |p| p.new, "in Configuration Mode after setting it");
    st.ok(&inst, exit_config(&inst), "fmi3ExitConfigurationMode to Instantiated");
    st.read_params(&inst, |p| p.new, "in Instantiated after Configuration Mode");
    n.reads += st.read_arrays(&inst, &st.new, false, "in Instantiated after Configuration Mode");
    st.set_inputs(&inst, &st.new);

    // 3. Initialization and a run with the new sizes.
    let s = inst.enter_init(0.0);
    st.ok(&inst, s, "fmi3EnterInitializationMode after Configuration Mode");
    n.reads += st.read_arrays(&inst, &st.new, true, "in Initialization Mode");
    st.ok(&inst, inst.exit_init(), "fmi3ExitInitializationMode");
    if me {
        inst.event_iteration();
        let s = inst.unary("fmi3EnterContinuousTimeMode", fmu.api.enter_continuous_time_mode);
        st.ok(&inst, s, "fmi3EnterContinuousTimeMode");
        let nx = st.me_vectors(&inst, &st.new, "after initialization with the new sizes");
        st.jacobian(&inst, nx);
        for k in 0..5 {
            euler_step_n(&mut inst, nx, h);
            n.steps += 1;
            st.me_vectors(&inst, &st.new, &format!("after Euler step {}", k + 1));
            n.reads += st.read_arrays(&inst, &st.new, true, &format!("after Euler step {}", k + 1));
        }
    } else {
        for k in 0..5 {
            inst.step(h);
            n.steps += 1;
            n.reads += st.read_arrays(&inst, &st.new, true, &format!("after fmi3DoStep {}", k + 1));
        }
    }

    // 4. Reconfiguration Mode: the tunable ones back to their starts.
    let again = st.reconfigured_sizes();
    let tunable = st.tunables().count() > 0;
    if tunable {
        if me {
            let s = inst.unary("fmi3EnterEventMode", fmu.api.enter_event_mode);
            st.ok(&inst, s, "fmi3EnterEventMode");
        }
        st.reconfigure(&inst);
        st.read_params(
            &inst,
            |p| if p.tunable { p.start } else { p.new },
            &format!("in {} after Reconfiguration Mode", st.running()),
        );
        n.reads += st.read_arrays(&inst, &again, true, "after Reconfiguration Mode");
        if me {
            let nx = st.me_vectors(&inst, &again, "in Event Mode after Reconfiguration Mode");
            inst.event_iteration();
            let s = inst.unary("fmi3EnterContinuousTimeMode", fmu.api.enter_continuous_time_mode);
            st.ok(&inst, s, "fmi3EnterContinuousTimeMode after Reconfiguration Mode");
            st.jacobian(&inst, nx);
            for k in 0..3 {
                euler_step_n(&mut inst, nx, h);
                n.steps += 1;
                st.me_vectors(
                    &inst,
                    &again,
                    &format!("Euler step {} after Reconfiguration Mode", k + 1),
                );
            }
        } else {
            for k in 0..3 {
                inst.step(h);
                n.steps += 1;
                n.reads += st.read_arrays(
                    &inst,
                    &again,
                    true,
                    &format!("after fmi3DoStep {} after Reconfiguration Mode", k + 1),
                );
            }
        }
    } else {
        limitation(format!(
            "{NOT_DECLARED}a tunable structural parameter with another legal value (Reconfiguration Mode)"
        ));
    }
    drop(inst);

    // 2. Refusals, each on a fresh instance (fmi3Error ends an instance's use).
    // The old element counts after Configuration Mode.
    for v in &st.arrays {
        let (old, new) = (st.count(v, &st.base), st.count(v, &st.new));
        if old == new {
            continue;
        }
        let mut inst = st.configured();
        let mut at = "in Instantiated";
        if !readable_in_instantiated(v) {
            let s = inst.enter_init(0.0);
            st.ok(&inst, s, "fmi3EnterInitializationMode");
            at = "in Initialization Mode";
        }
        st.refused(
            &inst,
            &format!(
                "fmi3Get{}('{}') {at} with nValues = {old}, the count of the start sizes, after Configuration Mode made it {new} ({})",
                crate::fmi3::accessor(v.ty),
                v.name,
                st.show(&st.new)
            ),
            |i| i.get_raw_n(v, old).0,
        );
        n.refusals += 1;
    }
    if me {
        let (old, new) = (st.nx(&st.base), st.nx(&st.new));
        if old != new {
            let inst = st.stepping();
            st.refused(
                &inst,
                &format!(
                    "fmi3GetContinuousStates with nx = {old} (the start sizes) after Configuration Mode made it {new}"
                ),
                |i| {
                    i.vector("fmi3GetContinuousStates", i.api().get_continuous_states, old)
                        .0
                },
            );
            n.refusals += 1;
        }
    }
    for p in &st.params {
        // Set outside Configuration Mode.
        let inst = st.fresh();
        st.refused(
            &inst,
            &format!(
                "fmi3SetUInt64 of structural parameter '{}' in Instantiated, without Configuration Mode",
                p.v.name
            ),
            |i| set_u64(i, p.v.vr, p.new),
        );
        n.refusals += 1;
        // Outside min and max.
        for (bad, what) in [
            (p.max.checked_add(1), format!("above max = {}", p.max)),
            (p.min.checked_sub(1), format!("below min = {}", p.min)),
        ] {
            let Some(bad) = bad else { continue };
            let inst = st.fresh();
            st.ok(&inst, enter_config(&inst), "fmi3EnterConfigurationMode");
            st.refused(
                &inst,
                &format!("fmi3SetUInt64('{}', {bad}) in Configuration Mode, {what}", p.v.name),
                |i| set_u64(i, p.v.vr, bad),
            );
            n.refusals += 1;
        }
    }
    // Nothing but structural parameters in Configuration Mode (the value it has, set again).
    if let Some(v) = st.non_structural() {
        let inst = st.fresh();
        let count = st.count(v, &st.base);
        let (s, bytes) = inst.get_raw_n(v, count);
        st.ok(&inst, s, &format!("fmi3Get{}('{}') in Instantiated", v.ty, v.name));
        st.ok(&inst, enter_config(&inst), "fmi3EnterConfigurationMode");
        st.refused(
            &inst,
            &format!(
                "fmi3Set{}('{}', {} {}, its own value) in Configuration Mode",
                crate::fmi3::accessor(v.ty),
                v.name,
                v.variability,
                v.causality
            ),
            |i| i.set_raw(v, &bytes),
        );
        n.refusals += 1;
    }
    let inst = st.fresh();
    st.ok(&inst, enter_config(&inst), "fmi3EnterConfigurationMode");
    st.refused(&inst, "fmi3EnterInitializationMode in Configuration Mode", |i| {
        i.args(vec![("startTime", Val::F64(0.0))])
            // SAFETY: bad on purpose, for the FMU to refuse; pointers NULL or to live locals of
            // the lengths passed.
            .call("fmi3EnterInitializationMode", |c| unsafe {
                (fmu.api.enter_initialization_mode)(c, false, 0.0, 0.0, false, 0.0)
            })
    });
    let inst = st.fresh();
    st.ok(&inst, enter_config(&inst), "fmi3EnterConfigurationMode");
    st.refused(&inst, "fmi3EnterConfigurationMode in Configuration Mode", enter_config);
    n.refusals += 2;

    // 4. Refusals of Reconfiguration Mode.
    if tunable {
        // The element counts of before the reconfiguration.
        for v in &st.arrays {
            let (before, after) = (st.count(v, &st.new), st.count(v, &again));
            if before == after {
                continue;
            }
            let inst = st.stepping();
            st.reconfigure(&inst);
            st.refused(
                &inst,
                &format!(
                    "fmi3Get{}('{}') with nValues = {before} after Reconfiguration Mode made it {after} ({})",
                    crate::fmi3::accessor(v.ty),
                    v.name,
                    st.show(&again)
                ),
                |i| i.get_raw_n(v, before).0,
            );
            n.refusals += 1;
        }
        let fixed: Vec<&Param> = st.params.iter().filter(|p| !p.tunable).collect();
        for p in &fixed {
            let value = if p.new != p.start { p.start } else { p.new };
            let inst = st.stepping();
            st.ok(
                &inst,
                enter_config(&inst),
                &format!("fmi3EnterConfigurationMode from {}", st.running()),
            );
            st.refused(
                &inst,
                &format!(
                    "fmi3SetUInt64 of fixed structural parameter '{}' in Reconfiguration Mode",
                    p.v.name
                ),
                |i| set_u64(i, p.v.vr, value),
            );
            n.refusals += 1;
        }
        if fixed.is_empty() {
            limitation(format!(
                "{NOT_DECLARED}a fixed structural parameter (refused in Reconfiguration Mode)"
            ));
        }
        if let Some(v) = st.non_structural() {
            let inst = st.stepping();
            let count = st.count(v, &st.new);
            let (s, bytes) = inst.get_raw_n(v, count);
            st.ok(&inst, s, &format!("fmi3Get{}('{}') in {}", v.ty, v.name, st.running()));
            st.ok(
                &inst,
                enter_config(&inst),
                &format!("fmi3EnterConfigurationMode from {}", st.running()),
            );
            st.refused(
                &inst,
                &format!(
                    "fmi3Set{}('{}', {} {}, its own value) in Reconfiguration Mode",
                    crate::fmi3::accessor(v.ty),
                    v.name,
                    v.variability,
                    v.causality
                ),
                |i| i.set_raw(v, &bytes),
            );
            n.refusals += 1;
        }
    }
    info(format!(
        "{which}: {} set in Configuration Mode ({} -> {}){}; {} array reads with the counts those give, {} steps, {} refusals",
        st.params
            .iter()
            .map(|p| p.v.name.as_str())
            .collect::<Vec<_>>()
            .join(", "),
        st.show(&st.base),
        st.show(&st.new),
        if tunable {
            format!(
                ", the tunable ones back in Reconfiguration Mode from {} ({})",
                st.running(),
                st.show(&again)
            )
        } else {
            String::new()
        },
        n.reads,
        n.steps,
        n.refusals
    ));
    n
}

pub fn fmi3_structural_parameters_are_set_in_configuration_mode_and_size_the_arrays(fmu: &Fmu3) {
    let id = &fmu.id;
    let declared = fmu
        .md
        .variables
        .iter()
        .any(|v| v.causality == Causality::StructuralParameter);
    if !declared {
        // fmi3EnterConfigurationMode is for FMUs with structural parameters: an FMU without
        // them refuses it, or accepts it (and leaves it again); never fmi3Fatal or a crash.
        let me = fmu.md.cs.is_none();
        let inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        let s = enter_config(&inst);
        assert!(
            s == fmi3Error || s == fmi3OK,
            "{id}: fmi3EnterConfigurationMode without structural parameters: {} (fmi3Error or fmi3OK): {}",
            status_name(s),
            inst.log_text()
        );
        if s == fmi3OK {
            let s = exit_config(&inst);
            assert_eq!(
                s,
                fmi3OK,
                "{id}: fmi3ExitConfigurationMode after an accepted fmi3EnterConfigurationMode: {}",
                inst.log_text()
            );
        }
        skip_not_declared("structural parameters");
    }
    let mut done = vec![];
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) {
            continue;
        }
        one_interface(fmu, me);
        done.push(if me { "Model Exchange" } else { "Co-Simulation" });
    }
    info(format!("checked in {}", done.join(" and ")));
}
