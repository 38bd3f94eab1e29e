//! The `depends` of every output and derivative, checked against the model itself when the FMU
//! is built: its directional derivatives are exact (the equations run on dual numbers), so a
//! derivative ∂unknown/∂known that is not 0 at some point proves a dependency. At a few random
//! points (states and continuous inputs spread around their start values, inside their bounds)
//! the smoke run asks `fmi2GetDirectionalDerivative` for every column of the model-exchange
//! Jacobian: a dependency the declaration leaves out is a problem (the importer trusts the
//! description: a missing dependency makes it order a feedthrough wrongly or skip an algebraic
//! loop); a declared dependency never seen, or an unknown declared without `depends` (written
//! as depending on everything), is a note with what was found.
//!
//! Checked through FMI 2.0 model exchange: the FMI 3.0 description of the same library is
//! written from the same declarations. Knowns that are not continuous Reals (Integer, Boolean or
//! discrete inputs) have no directional derivative: a `depends` on them is not checked.

use rustfmu::description::{Causality, Initial, ModelDescription, Start, VarType, Variability, Variable};

/// Random points of the check. The first has the parameters at their start values; at the
/// others every parameter is drawn too (a Boolean or enumeration parameter that switches a
/// dependency on shows it at some point: eight points miss one switch with probability 1/128).
const POINTS: usize = 8;

/// How often a point's parameters are drawn again when the model refuses them.
const DRAWS: usize = 5;

/// What the check found.
#[derive(Debug, Default, PartialEq)]
pub struct Report {
    /// Dependencies the declarations leave out: the build fails on them.
    pub problems: Vec<String>,
    /// Declared dependencies never seen, unknowns without `depends`, points that could not be
    /// checked: printed, not failed.
    pub notes: Vec<String>,
}

impl Report {
    /// A check that could not run: a note saying why, and no problem.
    pub(crate) fn not_run(note: String) -> Report {
        Report {
            notes: vec![note],
            ..Report::default()
        }
    }

    /// What random point `point` (from 0) gave, or `None` with a note that `check` skipped it.
    pub(crate) fn or_skip<T>(&mut self, check: &str, point: usize, at_point: Result<T, String>) -> Option<T> {
        at_point
            .map_err(|e| {
                self.notes
                    .push(format!("{check} skipped random point {}: {e}", point + 1))
            })
            .ok()
    }
}

/// Known `j` moved: for each unknown `i` whose value differs from `at_base` in any bit, the
/// first such difference is noted in `seen[i][j]` as `how` says it.
pub(crate) fn note_moved(
    seen: &mut [Vec<Option<String>>],
    j: usize,
    at_base: &[f64],
    values: &[f64],
    how: impl Fn(f64, f64) -> String,
) {
    for (i, (&a, &b)) in at_base.iter().zip(values).enumerate() {
        if a.to_bits() != b.to_bits() && seen[i][j].is_none() {
            seen[i][j] = Some(how(a, b));
        }
    }
}

/// A known of model exchange: a continuous state or a continuous Real input.
#[derive(Clone, Copy)]
pub(crate) enum Known<'a> {
    State(&'a Variable),
    Input(&'a Variable),
}

impl<'a> Known<'a> {
    pub(crate) fn var(&self) -> &'a Variable {
        match self {
            Known::State(v) | Known::Input(v) => v,
        }
    }
}

/// The states in the order of the state vector: the variables the derivatives are of, in the
/// order the derivatives are declared (the order of `<Derivatives>` and of the runtime's vector).
pub(crate) fn states(d: &ModelDescription) -> Vec<&Variable> {
    d.variables
        .iter()
        .filter_map(|der| der.derivative_of)
        .filter_map(|name| d.variables.iter().find(|v| v.name == name))
        .collect()
}

fn is_continuous_real(v: &Variable) -> bool {
    v.var_type == VarType::Real && v.variability == Variability::Continuous
}

/// The unknowns: the derivatives, then the continuous Real outputs, then the event indicators
/// (each once). FMI 2.0 lists no dependencies of its event indicators, but the same declaration
/// is FMI 3.0's `<EventIndicator dependencies>`: an event indicator is a continuous Real the
/// equations compute, so its directional derivatives are as exact as an output's.
fn unknowns(d: &ModelDescription) -> Vec<&Variable> {
    let mut out: Vec<&Variable> = d.variables.iter().filter(|v| v.derivative_of.is_some()).collect();
    for v in d
        .variables
        .iter()
        .filter(|v| (v.causality == Causality::Output && is_continuous_real(v)) || d.event_indicators.contains(&v.name))
    {
        if !out.iter().any(|u| u.value_reference == v.value_reference) {
            out.push(v);
        }
    }
    out
}

fn knowns(d: &ModelDescription) -> Vec<Known<'_>> {
    let mut out: Vec<Known> = states(d).into_iter().map(Known::State).collect();
    out.extend(
        d.variables
            .iter()
            .filter(|v| v.causality == Causality::Input && is_continuous_real(v))
            .map(Known::Input),
    );
    out
}

/// A deterministic generator (splitmix64): the same points in every build.
pub(crate) struct Rng(pub(crate) u64);

impl Rng {
    pub(crate) fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        lo + (hi - lo) * ((z >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// A value spread around `center` (by up to `scale` times its magnitude, at least `scale`) and
/// kept inside the variable's bounds (an exclusive bound by a margin). Small spreads keep a model
/// inside its limits (a saturated output shows no dependency on what it saturates).
pub(crate) fn spread_by(rng: &mut Rng, v: &Variable, center: f64, scale: f64) -> f64 {
    let width = center.abs().max(1.0) * scale;
    let mut x = center + rng.uniform(-0.5, 0.5) * width;
    let (lo, hi) = (v.min.map(|b| b.value), v.max.map(|b| b.value));
    if let (Some(lo), Some(hi)) = (lo, hi) {
        // Inside both: a random point of the range.
        return lo + (hi - lo) * rng.uniform(0.05, 0.95);
    }
    if let Some(lo) = lo
        && x <= lo
    {
        x = lo + rng.uniform(0.05, 0.5) * width;
    }
    if let Some(hi) = hi
        && x >= hi
    {
        x = hi - rng.uniform(0.05, 0.5) * width;
    }
    x
}

/// A random value of a parameter or input: a Real spread around its start value, a Boolean
/// either way, an enumeration any of its items, an Integer inside its bounds (or near its start).
fn draw(rng: &mut Rng, v: &Variable) -> f64 {
    draw_by(rng, v, 1.0)
}

/// [`draw`], a Real spread by `scale` times as far ([`spread_by`]).
fn draw_by(rng: &mut Rng, v: &Variable, scale: f64) -> f64 {
    let x = start_number(v);
    match v.var_type {
        VarType::Real => spread_by(rng, v, x, scale),
        VarType::Boolean => (rng.uniform(0.0, 1.0) < 0.5) as u8 as f64,
        VarType::Enumeration => match v.enumeration {
            Some(e) if !e.items.is_empty() => {
                let i = ((rng.uniform(0.0, 1.0) * e.items.len() as f64) as usize).min(e.items.len() - 1);
                e.items[i].value as f64
            }
            _ => x,
        },
        _ => match (v.min, v.max) {
            (Some(lo), Some(hi)) => rng.uniform(lo.value, hi.value + 1.0).floor().min(hi.value),
            _ => x + rng.uniform(-2.0, 3.0).floor(),
        },
    }
}

/// The parameters the check draws at each random point but the first: tunable or fixed, with
/// initial = exact.
fn parameters(d: &ModelDescription) -> Vec<&Variable> {
    d.variables
        .iter()
        .filter(|v| {
            v.causality == Causality::Parameter
                && v.effective_initial() == Some(Initial::Exact)
                && v.var_type != VarType::String
        })
        .collect()
}

pub(crate) fn start_of(v: &Variable) -> f64 {
    match v.start {
        Start::Real(x) if x.is_finite() => x,
        _ => 0.0,
    }
}

/// One unknown's declaration against what the points showed (`seen[j]`: known `names[j]` moved
/// it): both checks read it the same way.
pub(crate) struct Comparison<'a> {
    /// The knowns it moved with.
    pub(crate) found: Vec<&'a str>,
    /// The indices of those the declaration leaves out.
    pub(crate) missing: Vec<usize>,
    /// The declared knowns no point showed.
    pub(crate) unseen: Vec<&'a str>,
}

pub(crate) fn compare<'a, T>(declared: Option<&[&str]>, names: &[&'a str], seen: &[Option<T>]) -> Comparison<'a> {
    let mut c = Comparison {
        found: vec![],
        missing: vec![],
        unseen: vec![],
    };
    for (j, (name, seen)) in names.iter().zip(seen).enumerate() {
        let listed = declared.map(|d| d.contains(name));
        match (seen.is_some(), listed) {
            (true, Some(false)) => c.missing.push(j),
            (false, Some(true)) => c.unseen.push(name),
            _ => {}
        }
        if seen.is_some() {
            c.found.push(name);
        }
    }
    c
}

/// `depends = [a, b]` as written in the declaration.
pub(crate) fn list(names: &[&str]) -> String {
    format!("[{}]", names.join(", "))
}

/// One random point of the Jacobian check: the Jacobian of `unknowns` with respect to `knowns`,
/// `parameters` set before initialization, the states and the inputs spread by `scale` around
/// their initial and start values.
#[derive(Clone, Copy)]
pub(crate) struct Point<'a> {
    pub(crate) unknowns: &'a [&'a Variable],
    pub(crate) knowns: &'a [Known<'a>],
    pub(crate) parameters: &'a [(&'a Variable, f64)],
    pub(crate) scale: f64,
}

/// How the checks reach a model: through FMI 2.0 (`depends_fmi2::Api`) or, for a library without FMI 2.0,
/// FMI 3.0 ([`crate::depends_fmi3::Api3`]). Each call works on a fresh instance.
pub(crate) trait Probe {
    /// The directional derivative's C function, for messages.
    fn derivative_function(&self) -> &'static str;

    /// Whether the probe sets and reads `v` (the FMI 3.0 probe leaves arrays out).
    fn reaches(&self, _v: &Variable) -> bool {
        true
    }

    /// The model-exchange Jacobian of the point's unknowns with respect to its knowns (rows:
    /// unknowns), from a fresh instance.
    fn jacobian(&self, d: &ModelDescription, at: &Point, rng: &mut Rng) -> Result<Vec<Vec<f64>>, String>;

    /// The values of the initial unknowns after Initialization Mode with the knowns set to
    /// `values`.
    fn initial_values(&self, knowns: &[&Variable], values: &[f64], unknowns: &[&Variable]) -> Result<Vec<f64>, String>;
}

/// The check of `depends` through any [`Probe`] (FMI 2.0: `depends_fmi2::check`).
pub(crate) fn check_with(api: &dyn Probe, d: &ModelDescription) -> Report {
    let mut report = Report::default();
    let mut unknowns = unknowns(d);
    unknowns.retain(|v| api.reaches(v));
    let mut knowns = knowns(d);
    knowns.retain(|k| api.reaches(k.var()));
    if unknowns.is_empty() || knowns.is_empty() {
        return report;
    }
    // seen[u][k]: a point where ∂unknown u / ∂known k was not 0, and its value.
    let mut seen: Vec<Vec<Option<f64>>> = vec![vec![None; knowns.len()]; unknowns.len()];
    let mut checked_points = 0;
    let mut rng = Rng(0x0005_eed0_fde9_e0d5);
    let parameters = parameters(d);
    for point in 0..POINTS {
        // The parameters drawn, again while the model refuses them (a combination it does not
        // accept), at most DRAWS times; then this point with their start values.
        let mut jacobian = Err(String::new());
        for attempt in 0..=DRAWS {
            let drawn: Vec<(&Variable, f64)> = if point == 0 || attempt == DRAWS {
                vec![]
            } else {
                parameters.iter().map(|v| (*v, draw(&mut rng, v))).collect()
            };
            // Every other point close to the initial state and the start values of the inputs.
            let scale = if point % 2 == 1 { 1e-3 } else { 1.0 };
            let at = Point {
                unknowns: &unknowns,
                knowns: &knowns,
                parameters: &drawn,
                scale,
            };
            jacobian = api.jacobian(d, &at, &mut rng);
            if jacobian.is_ok() || drawn.is_empty() {
                break;
            }
        }
        let Some(jacobian) = report.or_skip("the dependency check", point, jacobian) else {
            continue;
        };
        checked_points += 1;
        for (i, row) in jacobian.iter().enumerate() {
            for (j, &value) in row.iter().enumerate() {
                if value != 0.0 && seen[i][j].is_none() {
                    seen[i][j] = Some(value);
                }
            }
        }
    }
    if checked_points == 0 {
        report
            .notes
            .push("`depends` was not checked: no random point could be evaluated (above)".into());
        return report;
    }
    for (i, u) in unknowns.iter().enumerate() {
        let what = if u.derivative_of.is_some() {
            "derivative"
        } else if d.event_indicators.contains(&u.name) && u.causality != Causality::Output {
            "event indicator"
        } else {
            "output"
        };
        let names: Vec<&str> = knowns.iter().map(|k| k.var().name).collect();
        let c = compare(u.depends_on, &names, &seen[i]);
        let Some(declared) = u.depends_on else {
            report.notes.push(format!(
                "{what} '{}' declares no `depends`, so its description says it depends on every input and state; \
                 at {checked_points} random points it depended on {}: `depends = {}` would say so",
                u.name,
                list(&c.found),
                list(&c.found)
            ));
            continue;
        };
        for j in c.missing {
            let (name, value) = (names[j], seen[i][j].unwrap_or_default());
            report.problems.push(format!(
                "{what} '{}' depends on {} '{name}' (∂{}/∂{name} = {value:e} at a random point, by \
                 {}), which its `depends = {}` leaves out: add '{name}' to it",
                u.name,
                match knowns[j] {
                    Known::State(_) => "the state",
                    Known::Input(_) => "the input",
                },
                u.name,
                api.derivative_function(),
                list(declared)
            ));
        }
        if !c.unseen.is_empty() {
            report.notes.push(format!(
                "{what} '{}' declares dependencies on {} that {checked_points} random points never showed \
                 (a derivative 0 at each): drop them from `depends` if they are not there (a dependency \
                 through a switch or a limit has derivative 0 and shows only as a jump: keep it then)",
                u.name,
                list(&c.unseen)
            ));
        }
    }
    report
}

/// The Jacobian of `unknowns` with respect to `knowns` (rows: unknowns), a column per known:
/// `column(known, out)` asks the model for the directional derivative of every unknown with
/// respect to `known` into `out` (one place per unknown). Each value must be finite.
pub(crate) fn by_columns(
    probe: &dyn Probe,
    unknowns: &[&Variable],
    knowns: &[Known],
    mut column: impl FnMut(&Variable, &mut [f64]) -> Result<(), String>,
) -> Result<Vec<Vec<f64>>, String> {
    let function = probe.derivative_function();
    let mut jacobian = vec![vec![0.0; knowns.len()]; unknowns.len()];
    for (j, k) in knowns.iter().enumerate() {
        let mut values = vec![f64::NAN; unknowns.len()];
        column(k.var(), &mut values)?;
        for (i, value) in values.into_iter().enumerate() {
            if !value.is_finite() {
                // fmi2OK or fmi3OK: the status of the function's version.
                return Err(format!(
                    "{function} answered {}OK with ∂{}/∂{} = {value}",
                    &function[..4],
                    unknowns[i].name,
                    k.var().name
                ));
            }
            jacobian[i][j] = value;
        }
    }
    Ok(jacobian)
}

fn is_initial_unknown(d: &ModelDescription, v: &Variable) -> bool {
    d.is_initial_unknown(v)
}

/// Whether the check can set `v` (a known of Initialization Mode: an input or a variable with
/// initial = exact, not a constant) and read it back as a number.
fn is_settable_known(v: &Variable) -> bool {
    (v.causality == Causality::Input || v.effective_initial() == Some(Initial::Exact))
        && v.causality != Causality::Independent
        && v.variability != Variability::Constant
        && v.var_type != VarType::String
}

fn is_number(v: &Variable) -> bool {
    matches!(v.var_type, VarType::Real | VarType::Integer | VarType::Enumeration)
}

/// One known's value, as set before Initialization Mode.
pub(crate) fn start_number(v: &Variable) -> f64 {
    match v.start {
        Start::Real(x) if x.is_finite() => x,
        Start::Integer(i) => i as f64,
        Start::Boolean(b) => b as u8 as f64,
        _ => 0.0,
    }
}

/// The value a known is moved to: a small step inside its bounds (a Real), the other Boolean,
/// the next enumeration item, an Integer by one.
pub(crate) fn perturbed(v: &Variable, x: f64) -> f64 {
    match v.var_type {
        VarType::Boolean => 1.0 - x,
        VarType::Enumeration if v.enumeration.is_some_and(|e| e.items.len() > 1) => {
            let items = v.enumeration.map(|e| e.items).unwrap_or(&[]);
            let at = items.iter().position(|i| i.value as f64 == x).unwrap_or(0);
            items[(at + 1) % items.len()].value as f64
        }
        _ => {
            let step = if v.var_type == VarType::Real {
                1e-3 * x.abs().max(1.0)
            } else {
                1.0
            };
            let above = |y: f64| v.max.is_some_and(|b| y > b.value || (b.exclusive && y >= b.value));
            if above(x + step) { x - step } else { x + step }
        }
    }
}

/// The check of `initial_depends` through any [`Probe`] (FMI 2.0: `depends_fmi2::check_initial`).
pub(crate) fn check_initial_with(api: &dyn Probe, d: &ModelDescription) -> Report {
    let mut report = Report::default();
    let unknowns: Vec<&Variable> = d
        .variables
        .iter()
        .filter(|v| is_initial_unknown(d, v) && is_number(v) && api.reaches(v))
        .collect();
    let knowns: Vec<&Variable> = d
        .variables
        .iter()
        .filter(|v| is_settable_known(v) && api.reaches(v))
        .collect();
    if unknowns.is_empty() {
        return report;
    }
    // seen[u][k]: how known k moved unknown u, at the first point it did.
    let mut seen: Vec<Vec<Option<String>>> = vec![vec![None; knowns.len()]; unknowns.len()];
    let mut checked_points = 0;
    let mut rng = Rng(0x1_0171_a1de_9e05);
    for point in 0..POINTS {
        // The first point is the start values themselves; the others are drawn, again while the
        // model refuses them, at most DRAWS times.
        let mut base: Vec<f64> = knowns.iter().map(|v| start_number(v)).collect();
        let mut at_base = Err(String::new());
        for attempt in 0..DRAWS {
            if point > 0 {
                // Every other point close to the start values (inside the model's limits).
                let scale = if point % 2 == 1 { 1e-3 } else { 1.0 };
                base = knowns.iter().map(|v| draw_by(&mut rng, v, scale)).collect();
            }
            at_base = api.initial_values(&knowns, &base, &unknowns);
            if at_base.is_ok() || point == 0 || attempt + 1 == DRAWS {
                break;
            }
        }
        let Some(at_base) = report.or_skip("the initial dependency check", point, at_base) else {
            continue;
        };
        checked_points += 1;
        for (j, k) in knowns.iter().enumerate() {
            let mut moved = base.clone();
            moved[j] = perturbed(k, base[j]);
            match api.initial_values(&knowns, &moved, &unknowns) {
                Ok(values) => note_moved(&mut seen, j, &at_base, &values, |a, b| {
                    format!("{} = {} gave {a}, {} = {} gave {b}", k.name, base[j], k.name, moved[j])
                }),
                // The model refuses the moved value: whatever it initializes depends on it.
                Err(e) => report.notes.push(format!(
                    "the initial dependency check could not move '{}' from {} to {}: {e}",
                    k.name, base[j], moved[j]
                )),
            }
        }
    }
    if checked_points == 0 {
        return report;
    }
    for (i, u) in unknowns.iter().enumerate() {
        let names: Vec<&str> = knowns.iter().map(|k| k.name).collect();
        let c = compare(u.initial_depends_on, &names, &seen[i]);
        let Some(declared) = u.initial_depends_on else {
            report.notes.push(format!(
                "initial unknown '{}' declares no `initial_depends`, so its InitialUnknowns entry says it depends on \
                 every known of Initialization Mode; at {checked_points} random points it depended on {}: \
                 `initial_depends = {}` would say so",
                u.name,
                list(&c.found),
                list(&c.found)
            ));
            continue;
        };
        for j in c.missing {
            let how = seen[i][j].as_deref().unwrap_or_default();
            report.problems.push(format!(
                "initial unknown '{}' depends in Initialization Mode on '{}' ({how} for '{}'), which its \
                 `initial_depends = {}` leaves out: add '{}' to it",
                u.name,
                names[j],
                u.name,
                list(declared),
                names[j]
            ));
        }
        if !c.unseen.is_empty() {
            report.notes.push(format!(
                "initial unknown '{}' declares initial dependencies on {} that {checked_points} random points \
                 never showed: drop them from `initial_depends` if they are not there (a dependency through a \
                 switch or a limit shows only where the switch flips: keep it then)",
                u.name,
                list(&c.unseen)
            ));
        }
    }
    report
}
