//! FMI 3.0 variables of every type and shape on connections, parameters and records: the ones
//! FMI 2.0's view of an FMI 3.0 FMU leaves out (Float32, Int8 ... UInt64, Binary, arrays of any
//! type; [`crate::fmi3::Var3`]), and, on a connection, every FMI 3.0 variable but a Float64
//! scalar (whose connections are the Real ports of the module above).
//!
//! A connection joins an output and an input of one type and one shape (an array element-wise,
//! in row-major order); anything else is refused when the system is built, naming both ends.
//! Its output is read with the type's fmi3Get{Type} into a buffer made then, at its component's
//! turn in the evaluation order, and the inputs it feeds are set from that buffer, as the Real
//! ports are: a communication step allocates nothing.

use super::*;
use crate::fmi3::Var3;
use crate::values::Values;
use md_reader::fmi3::Type as Type3;

/// A connected FMI 3.0 output: read into `buf` at its component's turn.
pub(super) struct TypedRead {
    slave: usize,
    vr: [u32; 1],
    name: String,
    buf: Values,
}

/// An input set from a [`TypedRead`]'s buffer.
struct TypedWrite {
    slave: usize,
    vr: [u32; 1],
    name: String,
    read: usize,
}

/// The typed connections of a system, in the Gauss-Seidel order of its Real ports.
#[derive(Default)]
pub(super) struct TypedLinks {
    reads: Vec<TypedRead>,
    writes: Vec<TypedWrite>,
    /// For each component (system order): the writes into it from components before it in the
    /// evaluation order, and the reads of its outputs.
    before: Vec<Vec<usize>>,
    after: Vec<Vec<usize>>,
    /// Writes from components at or after their target in the evaluation order.
    late: Vec<usize>,
    /// The recorded variables of the current run ([`Simulation::typed_record`]).
    pub(super) records: Vec<TypedRecord>,
}

/// A recorded FMI 3.0 variable: its values, into the row's columns from `first` on.
pub(super) struct TypedRecord {
    slave: usize,
    vr: [u32; 1],
    buf: Values,
    first: usize,
}

/// The function a message names for a get or set of `values`.
fn function(set: bool, values: &Values) -> String {
    format!("fmi3{}{}", if set { "Set" } else { "Get" }, values.type_name())
}

impl Simulation {
    /// `component.variable` as an FMI 3.0 variable typed calls get and set: one of an FMI 3.0
    /// component that FMI 2.0's view leaves out, or (`any`) any of an FMI 3.0 component.
    pub(super) fn var3(&self, component: &str, variable: &str, any: bool) -> Result<Option<(usize, Var3)>, Error> {
        let slave = self.slave_index(component)?;
        let fmu = self.fmu_of(slave);
        let Some(v) = fmu.var3(variable) else {
            return Ok(None);
        };
        let in_fmi2_view = fmu.description.variables.iter().any(|d| d.name == variable);
        // Its dimensions as this component's structural parameters set them.
        Ok((any || !in_fmi2_view).then(|| (slave, v.sized(&self.slaves[slave].sizes))))
    }

    /// The names of the arrays of `slave`'s FMU whose dimensions the structural parameter `vr`
    /// sets (empty: it sizes none).
    fn sized_by(&self, slave: usize, vr: u32) -> Vec<&str> {
        self.fmu_of(slave)
            .typed
            .iter()
            .filter(|x| x.dims.iter().flatten().any(|(p, _)| *p == vr))
            .map(|x| x.name.as_str())
            .collect()
    }

    /// The size the structural parameter `var` of `slave` gives its arrays in a run: the
    /// system's value, or its start value.
    fn size_in_force(&self, slave: usize, var: &Var3) -> Option<usize> {
        match self.slaves[slave].sizes.iter().find(|(p, _)| *p == var.vr) {
            Some(&(_, n)) => Some(n),
            None => var.start.as_deref().and_then(|s| s.trim().parse().ok()),
        }
    }

    /// A system's value `value` of `c.v`: if `v` is a structural parameter that sizes arrays,
    /// its value is kept as the size of those arrays in `c` ([`Slave::sizes`]), which the
    /// connections, parameters and records of the system take.
    pub(super) fn note_size(&mut self, c: &str, v: &str, value: &Value) -> Result<(), Error> {
        let slave = self.slave_index(c)?;
        let Some(var) = self.fmu_of(slave).var3(v) else {
            return Ok(());
        };
        let sized = self.sized_by(slave, var.vr);
        if var.causality != Causality::StructuralParameter || !var.shape.is_empty() || sized.is_empty() {
            return Ok(());
        }
        let n = match value {
            Value::Integer(i) => usize::try_from(*i).ok(),
            Value::List { ty, text } if ty == "UInt64" => text.trim().parse::<usize>().ok(),
            _ => None,
        }
        .ok_or_else(|| {
            Error::variable(
                c,
                v,
                format!(
                    "component '{c}': {v} = {value:?}: a structural parameter that sets the size of {} takes one integer >= 0",
                    sized.join(", ")
                ),
            )
        })?;
        let vr = var.vr;
        let sizes = &mut self.slaves[slave].sizes;
        match sizes.iter_mut().find(|(p, _)| *p == vr) {
            Some(slot) => slot.1 = n,
            None => sizes.push((vr, n)),
        }
        Ok(())
    }

    /// Whether `t` is a structural parameter (set in Configuration Mode).
    pub(super) fn is_structural(&self, t: Target) -> bool {
        self.fmu_of(t.slave)
            .typed
            .iter()
            .any(|v| v.vr == t.vr && v.causality == Causality::StructuralParameter)
    }

    /// The structural parameters among `values`, set in Configuration Mode (FMI 3.0.2:
    /// fmi3EnterConfigurationMode, their fmi3Set{Type}, fmi3ExitConfigurationMode) component by
    /// component, before any other value: the arrays they size take their sizes then.
    pub(super) fn configure(&mut self, values: &[(String, Target, Setter)]) -> Result<(), Error> {
        for slave in 0..self.slaves.len() {
            let mine: Vec<&(String, Target, Setter)> = values
                .iter()
                .filter(|(_, t, _)| t.slave == slave && self.is_structural(*t))
                .collect();
            if mine.is_empty() {
                continue;
            }
            let name = self.slaves[slave].name.clone();
            let keys: Vec<&str> = mine.iter().map(|(k, _, _)| k.as_str()).collect();
            let what = format!("the structural parameters {}", keys.join(", "));
            for enter in [true, false] {
                if !enter {
                    for (key, target, value) in &mine {
                        self.set(key, *target, value)?;
                    }
                }
                let function = if enter {
                    "fmi3EnterConfigurationMode"
                } else {
                    "fmi3ExitConfigurationMode"
                };
                let inst = self.instance(slave);
                inst.configuration_mode(enter)
                    .and_then(|()| inst.sync())
                    .map_err(|e| Error::fmi(&name, function, &e, None, &what))?;
            }
        }
        Ok(())
    }

    /// The connection `k` if it is one of typed values (an end of an FMI 3.0 component that is
    /// not a Float64 scalar): checked (types, shapes, causality, units) and added to the typed
    /// links; its (target, source, input) for the evaluation order. None: a Real connection.
    pub(super) fn typed_connection(
        &mut self,
        k: &Connection,
        text: &str,
    ) -> Result<Option<(usize, usize, u32)>, Error> {
        let end = |c: &str, v: &str| self.var3(c, v, true);
        let at = |e: Error| Error {
            message: format!("connection {text}: {}", e.message),
            ..e
        };
        let from = end(&k.start.0, &k.start.1).map_err(at)?;
        let to = end(&k.end.0, &k.end.1).map_err(at)?;
        let plain = |v: &Option<(usize, Var3)>| {
            v.as_ref()
                .is_none_or(|(_, v)| v.ty == Type3::Float64 && v.shape.is_empty())
        };
        if plain(&from) && plain(&to) {
            return Ok(None);
        }
        let kind = |v: &Option<(usize, Var3)>, c: &str, n: &str| match v {
            Some((_, v)) => v.kind(),
            None => {
                let ty = self.resolve(c, n).map(|t| type_name(t.ty)).unwrap_or("?");
                format!("FMI 2.0 {ty}")
            }
        };
        let (Some((fs, fv)), Some((ts, tv))) = (&from, &to) else {
            return Err(Error::unsupported(
                Some(&k.end.0),
                Some(&k.end.1),
                format!(
                    "connection {text}: {}.{} is {} and {}.{} is {}: a connection joins two variables of one type and shape",
                    k.start.0,
                    k.start.1,
                    kind(&from, &k.start.0, &k.start.1),
                    k.end.0,
                    k.end.1,
                    kind(&to, &k.end.0, &k.end.1)
                ),
            ));
        };
        // FMI 3.0, 2.4.7.1: an Enumeration is set and got as an Int64; both ends must still
        // be of one declared type to mean the same.
        if fv.ty != tv.ty || fv.shape != tv.shape {
            // The dimensions as the components' structural parameters set them (the system's
            // values, or their start values).
            let resolved = if fv.dims.iter().chain(&tv.dims).any(Option::is_some) {
                format!(
                    "; their dimensions as the structural parameters in force set them: {}.{} {}, {}.{} {}",
                    k.start.0,
                    k.start.1,
                    fv.dimensions(),
                    k.end.0,
                    k.end.1,
                    tv.dimensions()
                )
            } else {
                String::new()
            };
            return Err(Error::unsupported(
                Some(&k.end.0),
                Some(&k.end.1),
                format!(
                    "connection {text}: {}.{} is {} and {}.{} is {}: a connection joins two variables of one type and shape (arrays element by element){resolved}",
                    k.start.0,
                    k.start.1,
                    fv.kind(),
                    k.end.0,
                    k.end.1,
                    tv.kind()
                ),
            ));
        }
        if tv.causality != Causality::Input {
            return Err(Error::unsupported(
                Some(&k.end.0),
                Some(&k.end.1),
                format!(
                    "connection {text}: {}.{} is not an input (causality '{}')",
                    k.end.0,
                    k.end.1,
                    tv.causality.name()
                ),
            ));
        }
        if let (Some(a), Some(b)) = (&fv.unit, &tv.unit)
            && a != b
        {
            return Err(Error::unsupported(
                Some(&k.end.0),
                Some(&k.end.1),
                format!("connection {text}: from unit '{a}' to unit '{b}': the runner converts no units"),
            ));
        }
        let (fs, ts) = (*fs, *ts);
        let n = self.slaves.len();
        let links = &mut self.typed;
        links.before.resize(n, Vec::new());
        links.after.resize(n, Vec::new());
        let read = match links.reads.iter().position(|r| r.slave == fs && r.vr[0] == fv.vr) {
            Some(r) => r,
            None => {
                links.reads.push(TypedRead {
                    slave: fs,
                    vr: [fv.vr],
                    name: fv.name.clone(),
                    buf: Values::zeros(fv.ty, fv.count()).expect("no clock is connected"),
                });
                links.reads.len() - 1
            }
        };
        links.writes.push(TypedWrite {
            slave: ts,
            vr: [tv.vr],
            name: tv.name.clone(),
            read,
        });
        Ok(Some((ts, fs, tv.vr)))
    }

    /// The direct feedthrough of the typed connections `typed` ((target, source, input)) into
    /// `feeds`, for the evaluation order. One within a cycle of direct feedthrough is refused:
    /// the runner solves algebraic loops of Float64 (Real) values only ([`super::loops`]).
    pub(super) fn typed_feeds(&self, typed: &[(usize, usize, u32)], feeds: &mut [Vec<usize>]) -> Result<(), Error> {
        let mut through = Vec::new();
        for &(target, source, input) in typed {
            if self.fmu_of(target).feedthrough.contains(&input) {
                through.push((target, source, input));
                if !feeds[target].contains(&source) {
                    feeds[target].push(source);
                }
            }
        }
        let (_, blocks) = super::loops::order(feeds);
        for (target, source, input) in through {
            if blocks.iter().any(|b| b.contains(&target) && b.contains(&source)) {
                let write = self
                    .typed
                    .writes
                    .iter()
                    .find(|w| w.slave == target && w.vr[0] == input)
                    .expect("a typed connection");
                let read = &self.typed.reads[write.read];
                let (t, s) = (&self.slaves[target].name, &self.slaves[source].name);
                return Err(Error::unsupported(
                    Some(t),
                    Some(&write.name),
                    format!(
                        "system '{}': connection {s}.{} -> {t}.{} ({}) closes an algebraic loop (direct feedthrough in a cycle): the runner solves loops of Float64 values only",
                        self.name,
                        read.name,
                        write.name,
                        read.buf.type_name()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The typed links in the evaluation order (`self.steps`): each write before its target or
    /// late, each read after its component.
    pub(super) fn order_typed(&mut self) {
        let order: Vec<usize> = self.steps.iter().map(|(c, _)| *c).collect();
        let position = |i: usize| order.iter().position(|&s| s == i).unwrap_or(usize::MAX);
        let links = &mut self.typed;
        for (r, read) in links.reads.iter().enumerate() {
            links.after[read.slave].push(r);
        }
        for (w, write) in links.writes.iter().enumerate() {
            let source = links.reads[write.read].slave;
            if position(source) < position(write.slave) {
                links.before[write.slave].push(w);
            } else {
                links.late.push(w);
            }
        }
    }

    fn typed_read(&mut self, r: usize, t: f64) -> Result<(), Error> {
        let read = &mut self.typed.reads[r];
        let s = &mut self.slaves[read.slave];
        s.instance
            .as_mut()
            .expect("instantiated")
            .get_typed(&read.vr, &mut read.buf)
            .map_err(|e| {
                Error::fmi(
                    &s.name,
                    &function(false, &read.buf),
                    &e,
                    Some(t),
                    &format!("connected output {}", read.name),
                )
            })
    }

    fn typed_write(&mut self, w: usize, t: f64) -> Result<(), Error> {
        let write = &self.typed.writes[w];
        let buf = &self.typed.reads[write.read].buf;
        let s = &mut self.slaves[write.slave];
        s.instance
            .as_mut()
            .expect("instantiated")
            .set_typed(&write.vr, buf)
            .map_err(|e| {
                Error::fmi(
                    &s.name,
                    &function(true, buf),
                    &e,
                    Some(t),
                    &format!("connected input {}", write.name),
                )
            })
    }

    /// Gauss-Seidel, before component `c`'s Real inputs are set: its typed inputs from the
    /// components before it.
    pub(super) fn typed_inputs(&mut self, c: usize, t: f64) -> Result<(), Error> {
        for j in 0..self.typed.before.get(c).map_or(0, Vec::len) {
            self.typed_write(self.typed.before[c][j], t)?;
        }
        Ok(())
    }

    /// Gauss-Seidel, after component `c`'s Real outputs are read: its typed connected outputs.
    pub(super) fn typed_outputs(&mut self, c: usize, t: f64) -> Result<(), Error> {
        for j in 0..self.typed.after.get(c).map_or(0, Vec::len) {
            self.typed_read(self.typed.after[c][j], t)?;
        }
        Ok(())
    }

    /// Gauss-Seidel: the typed inputs from components later in the order.
    pub(super) fn typed_late(&mut self, t: f64) -> Result<(), Error> {
        for j in 0..self.typed.late.len() {
            self.typed_write(self.typed.late[j], t)?;
        }
        Ok(())
    }

    /// The typed inputs of the components `receivers` set again from the outputs last read:
    /// those from later components (every one under `jacobi`), see [`Simulation::late_round`].
    pub(super) fn typed_into(&mut self, receivers: &[usize], jacobi: bool, t: f64) -> Result<(), Error> {
        let list: Vec<usize> = if jacobi {
            (0..self.typed.writes.len()).collect()
        } else {
            self.typed.late.clone()
        };
        for w in list {
            if receivers.contains(&self.typed.writes[w].slave) {
                self.typed_write(w, t)?;
            }
        }
        Ok(())
    }

    /// Jacobi: every typed output read (`read`), or every typed input set.
    pub(super) fn typed_all(&mut self, read: bool, t: f64) -> Result<(), Error> {
        if read {
            (0..self.typed.reads.len()).try_for_each(|r| self.typed_read(r, t))
        } else {
            (0..self.typed.writes.len()).try_for_each(|w| self.typed_write(w, t))
        }
    }

    /// A parameter or start value of the system (`value`) for an FMI 3.0 variable FMI 2.0's view
    /// leaves out; None: any other variable.
    pub(super) fn typed_start(&self, c: &str, v: &str, value: &Value) -> Result<Option<(Target, Setter)>, Error> {
        let Some((slave, var)) = self.var3(c, v, false)? else {
            return Ok(None);
        };
        let bad = |why: String| {
            Error::variable(
                c,
                v,
                format!("component '{c}': {v} ({}) = {value:?}: {why}", var.kind()),
            )
        };
        let count = var.count();
        let values = match value {
            Value::List { ty, text } if same_type(ty, var.ty) => Values::parse(var.ty, count, text),
            Value::List { ty, .. } => Err(format!("an ssv:{ty} value for a {} variable", var.ty)),
            Value::Items { ty, items } if same_type(ty, var.ty) && var.ty == Type3::Enumeration => {
                self.enumeration_items(slave, &var, count, items)
            }
            Value::Items { ty, items } if same_type(ty, var.ty) => Values::from_items(var.ty, count, items),
            Value::Items { ty, .. } => Err(format!("ssv:{ty} values (ssv:Value elements) for a {} variable", var.ty)),
            _ if !var.shape.is_empty() => Err(format!(
                "an array of {count}: SSP 1.0 values are scalars; give it to the run as \"{count} values separated by spaces\""
            )),
            Value::Real(x) if var.ty.is_float() => Values::from_number(var.ty, *x, None),
            Value::Integer(i) => Values::from_number(var.ty, *i as f64, Some(*i)),
            Value::Boolean(b) if var.ty == Type3::Boolean => Ok(Values::Boolean(vec![*b])),
            Value::String(s) if matches!(var.ty, Type3::String | Type3::Binary) => Values::parse(var.ty, 1, s),
            _ => Err(format!("a {} value for a {} variable", value.type_name(), var.ty)),
        }
        .map_err(bad)?;
        Ok(Some((target(slave, &var), Setter::Values(values))))
    }

    /// The values of the Enumeration `var` of `slave` whose items `items` names (SSP 2.0: "the
    /// actual numeric value this value is mapped to at run time will depend on the item mapping
    /// of the enumeration type of the variables being parameterized"), as fmi3SetInt64 sets them.
    fn enumeration_items(&self, slave: usize, var: &Var3, count: usize, items: &[String]) -> Result<Values, String> {
        if items.len() != count {
            return Err(format!(
                "{} value(s) given, the variable has {count} (one ssv:Value an element)",
                items.len()
            ));
        }
        let fmu = self.fmu_of(slave);
        let e = var
            .declared_type
            .as_deref()
            .and_then(|t| fmu.description.enumerations.iter().find(|e| e.name == t))
            .ok_or("its declaredType names no enumeration type of the FMU's TypeDefinitions")?;
        items
            .iter()
            .map(|item| {
                e.items
                    .iter()
                    .find(|(n, _)| n == item)
                    .map(|(_, x)| i64::from(*x))
                    .ok_or_else(|| {
                        let names: Vec<&str> = e.items.iter().map(|(n, _)| n.as_str()).collect();
                        format!("{} has no item '{item}' (it has: {})", e.name, names.join(", "))
                    })
            })
            .collect::<Result<Vec<i64>, String>>()
            .map(Values::Int64)
    }

    /// A run's override of an FMI 3.0 variable FMI 2.0's view leaves out; None: any other.
    pub(super) fn typed_override(&self, qualified: &str, value: &Override) -> Result<Option<(Target, Setter)>, Error> {
        let (c, v) = qualified
            .split_once('.')
            .ok_or_else(|| Error::variable(qualified, "", format!("'{qualified}': expected component.variable")))?;
        let Some((slave, var)) = self.var3(c, v, false)? else {
            return Ok(None);
        };
        let bad = |why: String| Error::variable(c, v, format!("{qualified} ({}) = {value:?}: {why}", var.kind()));
        let count = var.count();
        let values = match value {
            Override::Text(s) => Values::parse(var.ty, count, s),
            _ if !var.shape.is_empty() => Err(format!("an array of {count}: give {count} values separated by spaces")),
            Override::Real(x) => Values::from_number(var.ty, *x, None),
            Override::Integer(i) => Values::from_number(var.ty, *i as f64, Some(*i)),
            Override::Boolean(b) if var.ty == Type3::Boolean => Ok(Values::Boolean(vec![*b])),
            Override::Boolean(_) => Err(format!("a Boolean for a {} variable", var.ty)),
        }
        .map_err(&bad)?;
        self.fixed_size(slave, &var, &values).map_err(bad)?;
        Ok(Some((target(slave, &var), Setter::Values(values))))
    }

    /// A run's override `values` of `var` of `slave`: a structural parameter that sizes arrays
    /// keeps the size the system was built with (its connections' and parameters' buffers are
    /// made then); any other value is the run's.
    fn fixed_size(&self, slave: usize, var: &Var3, values: &Values) -> Result<(), String> {
        if var.causality != Causality::StructuralParameter {
            return Ok(());
        }
        let sized = self.sized_by(slave, var.vr);
        if sized.is_empty() {
            return Ok(());
        }
        let given = if values.len() == 1 { values.number(0) } else { None };
        let now = self.size_in_force(slave, var);
        if given.is_some() && given == now.map(|n| n as f64) {
            return Ok(());
        }
        Err(format!(
            "a structural parameter that sets the size of {} ({} in this system): a run does not change the sizes the system was built with; give its value in the system's parameter values (SSP)",
            sized.join(", "),
            now.map_or_else(|| "?".to_owned(), |n| n.to_string())
        ))
    }

    /// The recorded FMI 3.0 variable `key` FMI 2.0's view leaves out, its columns from `first`
    /// on (None: any other variable), and the names of its columns: `key` for a scalar,
    /// `key[i,j]` (from 1, row-major) for each element of an array.
    pub(super) fn typed_record(
        &self,
        key: &str,
        first: usize,
        names: &mut Vec<String>,
    ) -> Result<Option<TypedRecord>, Error> {
        let (c, v) = key.split_once('.').unwrap_or((key, ""));
        let Some((slave, var)) = self.var3(c, v, false)? else {
            return Ok(None);
        };
        if matches!(var.ty, Type3::String | Type3::Binary) {
            return Err(Error::variable(
                c,
                v,
                format!(
                    "{key} is a {}: it cannot be recorded (the runner records numbers)",
                    var.kind()
                ),
            ));
        }
        if var.shape.is_empty() {
            names.push(key.to_owned());
        } else {
            let mut index = vec![0usize; var.shape.len()];
            for _ in 0..var.count() {
                let at: Vec<String> = index.iter().map(|i| (i + 1).to_string()).collect();
                names.push(format!("{key}[{}]", at.join(",")));
                for d in (0..index.len()).rev() {
                    index[d] += 1;
                    if index[d] < var.shape[d] {
                        break;
                    }
                    index[d] = 0;
                }
            }
        }
        Ok(Some(TypedRecord {
            slave,
            vr: [var.vr],
            buf: Values::zeros(var.ty, var.count()).expect("no clock is recorded"),
            first,
        }))
    }

    /// The recorded FMI 3.0 variables' values into `row`.
    pub(super) fn read_typed_record(
        &mut self,
        records: &mut [TypedRecord],
        row: &mut [f64],
        t: f64,
    ) -> Result<(), Error> {
        for r in records.iter_mut() {
            let s = &mut self.slaves[r.slave];
            s.instance
                .as_mut()
                .expect("instantiated")
                .get_typed(&r.vr, &mut r.buf)
                .map_err(|e| Error::fmi(&s.name, &function(false, &r.buf), &e, Some(t), "recorded variables"))?;
            for (j, x) in row[r.first..r.first + r.buf.len()].iter_mut().enumerate() {
                *x = r.buf.number(j).unwrap_or(f64::NAN);
            }
        }
        Ok(())
    }

    /// The outputs of FMI 3.0 components FMI 2.0's view leaves out that can be recorded
    /// (numbers, scalars and arrays), "component.variable".
    pub(super) fn typed_outputs_list(&self, out: &mut Vec<String>) {
        for s in &self.slaves {
            let fmu = &self.fmus[s.fmu];
            for v in &fmu.typed {
                let in_view = fmu.description.variables.iter().any(|d| d.name == v.name);
                if v.causality == Causality::Output && !in_view && !matches!(v.ty, Type3::String | Type3::Binary) {
                    out.push(format!("{}.{}", s.name, v.name));
                }
            }
        }
    }
}

/// The target of a typed value: its type there is FMI 2.0's nearest, for messages only (a
/// [`Setter::Values`] carries its own).
fn target(slave: usize, var: &Var3) -> Target {
    let ty = match var.ty {
        Type3::Boolean => Type::Boolean,
        Type3::String | Type3::Binary => Type::String,
        t if t.is_float() => Type::Real,
        _ => Type::Integer,
    };
    Target { slave, vr: var.vr, ty }
}

/// Whether an SSV 2.0 value element `ty` (`Float64`, `Int8`, ...; SSP 1.0's `Real` and `Integer`
/// are Float64 and Int32) is of the FMI 3.0 type `var`.
fn same_type(ty: &str, var: Type3) -> bool {
    let ty = match ty {
        "Real" => "Float64",
        "Integer" => "Int32",
        t => t,
    };
    ty == var.name() || ty == "Int64" && var == Type3::Enumeration
}

/// A value of one `ssv:Value` element (SSP 2.0: "for scalar and one element array parameters
/// the Value element CAN be used") for a scalar of FMI 2.0's view: the String, or the
/// Enumeration item, it gives; any other value as it is.
pub(super) fn one_item(value: Value) -> Value {
    match value {
        Value::Items { ty, mut items } if items.len() == 1 && ty == "String" => Value::String(items.remove(0)),
        Value::Items { ty, mut items } if items.len() == 1 && ty == "Enumeration" => {
            Value::Enumeration(items.remove(0))
        }
        other => other,
    }
}
