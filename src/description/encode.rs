//! The const encoder: the description as the bytes the export macro embeds in the binary
//! (format [`FORMAT_VERSION`], found by [`MAGIC`]), computed in const evaluation.

use super::*;

/// Marks the encoded description inside a built library, where `cargo fmu` finds it.
pub const MAGIC: &[u8; 24] = b"\0RUSTFMU-DESCRIPTION-V1\0";
/// Bump when the encoding changes shape.
pub const FORMAT_VERSION: u32 = 1;

/// The FMI 3.0 parts of a variable that the encoding carries in blocks of their own
/// ([`Enc::parts`]), each added after the ones before it so that older encodings stay as they were.
#[derive(Clone, Copy)]
enum Part {
    /// `fmi3_only`, `maxSize`, `mimeType`, the array dimensions ([`FMI3_EXTRAS_TAG`]).
    Extras,
    /// A Clock's declaration and a clocked variable's clocks ([`CLOCKS_TAG`]).
    Clock,
    /// The structural parameters that size an array ([`SIZED_TAG`]).
    Sized,
    /// A Clock's priority ([`PRIORITIES_TAG`]).
    Priority,
}

impl Part {
    /// Whether `v` has this part.
    const fn of(self, v: &Variable) -> bool {
        match self {
            Part::Extras => !v.fmi3.is_none(),
            Part::Clock => v.fmi3.has_clock_part(),
            Part::Sized => v.is_sized(),
            Part::Priority => matches!(v.fmi3.clock, Some(ClockDecl { priority: Some(_), .. })),
        }
    }
}

/// A const-evaluable byte writer; with an empty buffer it only counts.
struct Enc<'a> {
    buf: &'a mut [u8],
    pos: usize,
}

impl Enc<'_> {
    const fn u8(&mut self, b: u8) {
        if self.pos < self.buf.len() {
            self.buf[self.pos] = b;
        }
        self.pos += 1;
    }
    const fn bytes(&mut self, b: &[u8]) {
        let mut i = 0;
        while i < b.len() {
            self.u8(b[i]);
            i += 1;
        }
    }
    const fn u32(&mut self, x: u32) {
        self.bytes(&x.to_le_bytes());
    }
    const fn i32(&mut self, x: i32) {
        self.bytes(&x.to_le_bytes());
    }
    const fn f64(&mut self, x: f64) {
        self.bytes(&x.to_bits().to_le_bytes());
    }
    const fn str(&mut self, s: &str) {
        self.u32(s.len() as u32);
        self.bytes(s.as_bytes());
    }
    const fn opt_f64(&mut self, x: Option<f64>) {
        match x {
            None => self.u8(0),
            Some(x) => {
                self.u8(1);
                self.f64(x);
            }
        }
    }
    const fn opt_str(&mut self, x: Option<&str>) {
        match x {
            None => self.u8(0),
            Some(s) => {
                self.u8(1);
                self.str(s);
            }
        }
    }
    const fn bound(&mut self, b: Option<Bound>) {
        match b {
            None => self.u8(0),
            Some(b) => {
                self.u8(if b.exclusive { 2 } else { 1 });
                self.f64(b.value);
            }
        }
    }
    const fn enum_type(&mut self, e: &EnumType) {
        self.str(e.name);
        self.str(e.description);
        self.u32(e.items.len() as u32);
        let mut i = 0;
        while i < e.items.len() {
            self.str(e.items[i].name);
            self.i32(e.items[i].value);
            self.str(e.items[i].description);
            i += 1;
        }
    }
    const fn variable(&mut self, d: &ModelDescription, version: FmiVersion, v: &Variable) {
        self.str(v.name);
        self.u32(v.value_reference);
        self.rest(d, version, v, &v.start);
    }
    /// Element `k` of an array, as the scalar FMI 2.0 makes of it: `name[i,j]` (indices from 1),
    /// value reference `vr + k`, the element's start, the array's other attributes.
    const fn element(&mut self, d: &ModelDescription, v: &Variable, k: usize) {
        self.element_name_only(v, k);
        self.u32(v.value_reference + k as u32);
        let start = match v.start {
            Start::Array(items) if k < items.len() => items[k],
            _ => Start::None,
        };
        self.rest(d, FmiVersion::V2, v, &start);
    }
    /// The name of element `k` of array `v` (as [`Enc::str`] writes a name): `name[i,j]`.
    const fn element_name_only(&mut self, v: &Variable, k: usize) {
        let dims = v.fmi3.dimensions;
        // The indices, outermost first (at most 2 dimensions: the derive refuses more), and the
        // name's length.
        let mut indices = [0usize; 8];
        let mut len = v.name.len() + 1;
        let mut rest = k;
        let mut j = dims.len();
        while j > 0 {
            j -= 1;
            let n = if dims[j] == 0 { 1 } else { dims[j] as usize };
            indices[j] = rest % n + 1;
            rest /= n;
            len += digits(indices[j]) + 1;
        }
        self.u32(len as u32);
        self.bytes(v.name.as_bytes());
        self.u8(b'[');
        let mut j = 0;
        while j < dims.len() {
            if j > 0 {
                self.u8(b',');
            }
            self.decimal(indices[j]);
            j += 1;
        }
        self.u8(b']');
    }
    const fn decimal(&mut self, x: usize) {
        let mut div = 1;
        while x / div >= 10 {
            div *= 10;
        }
        while div > 0 {
            self.u8(b'0' + (x / div % 10) as u8);
            div /= 10;
        }
    }
    /// A variable's attributes after its name and value reference.
    const fn rest(&mut self, d: &ModelDescription, version: FmiVersion, v: &Variable, start: &Start) {
        self.u8(v.var_type as u8);
        self.u8(v.causality as u8);
        self.u8(v.variability as u8);
        match v.initial {
            None => self.u8(255),
            Some(i) => self.u8(i as u8),
        }
        self.start(start);
        self.str(v.unit);
        self.str(v.description);
        self.bound(v.min);
        self.bound(v.max);
        self.opt_f64(v.nominal);
        self.dependency_names(d, version, v.depends_on);
        self.dependency_names(d, version, v.initial_depends_on);
        self.opt_str(v.derivative_of);
        match v.enumeration {
            None => self.u8(0),
            Some(e) => {
                self.u8(1);
                self.enum_type(e);
            }
        }
    }
    /// [`Enc::names`] of dependencies; in FMI 2.0 an array named there is each of its elements.
    const fn dependency_names(&mut self, d: &ModelDescription, version: FmiVersion, names: Option<&[&str]>) {
        let Some(deps) = names else {
            return self.names(None);
        };
        if matches!(version, FmiVersion::V3) || !d.has_fmi2_arrays() {
            return self.names(names);
        }
        let mut n = 0;
        let mut i = 0;
        while i < deps.len() {
            n += match fmi2_array_named(d, deps[i]) {
                Some(a) => a.element_count(),
                None => 1,
            };
            i += 1;
        }
        self.u8(1);
        self.u32(n as u32);
        let mut i = 0;
        while i < deps.len() {
            match fmi2_array_named(d, deps[i]) {
                Some(a) => {
                    let mut k = 0;
                    while k < a.element_count() {
                        self.element_name_only(a, k);
                        k += 1;
                    }
                }
                None => self.str(deps[i]),
            }
            i += 1;
        }
    }
    const fn start(&mut self, start: &Start) {
        match *start {
            Start::None => self.u8(0),
            Start::Real(x) => {
                self.u8(1);
                self.f64(x);
            }
            Start::Integer(x) => {
                self.u8(2);
                self.i32(x);
            }
            Start::Boolean(x) => {
                self.u8(3);
                self.u8(x as u8);
            }
            Start::String(s) => {
                self.u8(4);
                self.str(s);
            }
            Start::Int64(x) => {
                self.u8(5);
                self.bytes(&x.to_le_bytes());
            }
            Start::UInt64(x) => {
                self.u8(6);
                self.bytes(&x.to_le_bytes());
            }
            Start::Binary(b) => {
                self.u8(7);
                self.u32(b.len() as u32);
                self.bytes(b);
            }
            Start::Array(items) => {
                self.u8(8);
                self.u32(items.len() as u32);
                let mut i = 0;
                while i < items.len() {
                    self.start(&items[i]);
                    i += 1;
                }
            }
        }
    }
    /// An optional list of names (`depends`, `initial_depends`).
    const fn names(&mut self, names: Option<&[&str]>) {
        match names {
            None => self.u8(0),
            Some(deps) => {
                self.u8(1);
                self.u32(deps.len() as u32);
                let mut i = 0;
                while i < deps.len() {
                    self.str(deps[i]);
                    i += 1;
                }
            }
        }
    }

    /// The terminals nested in one terminal, each with its own nested ones (recursively).
    const fn nested_terminals(&mut self, ts: &[Terminal]) {
        self.u32(ts.len() as u32);
        let mut i = 0;
        while i < ts.len() {
            self.terminal(&ts[i]);
            self.nested_terminals(ts[i].terminals);
            i += 1;
        }
    }

    /// One terminal's attributes and members (its nested terminals are written apart).
    const fn terminal(&mut self, t: &Terminal) {
        self.str(t.name);
        self.str(t.kind);
        self.str(t.matching_rule);
        self.str(t.description);
        self.u32(t.members.len() as u32);
        let mut j = 0;
        while j < t.members.len() {
            self.str(t.members[j].variable);
            self.str(t.members[j].member);
            self.str(t.members[j].kind);
            j += 1;
        }
    }

    /// The whole description, block after block in the order of the format (which
    /// [`decode`] reads in the same order). One function on purpose: the order of the blocks is
    /// the format, and the GUIDs of every FMU built are its hash, so every block is written from
    /// here, top to bottom beside `decode`; the four per-variable FMI 3.0 blocks share one
    /// writer ([`Enc::parts`]), called here in their order.
    const fn description(&mut self, d: &ModelDescription, interfaces: Interfaces) {
        self.str(d.model_identifier);
        self.str(d.description);
        self.str(d.author);
        self.str(d.version);
        self.str(d.copyright);
        self.str(d.license);
        self.str(d.generation_tool);
        self.u8(interfaces.co_simulation as u8);
        self.u8(interfaces.model_exchange as u8);
        match d.default_experiment {
            None => self.u8(0),
            Some(e) => {
                self.u8(1);
                self.opt_f64(e.start_time);
                self.opt_f64(e.stop_time);
                self.opt_f64(e.tolerance);
                self.opt_f64(e.step_size);
            }
        }
        self.u32(d.units.len() as u32);
        let mut i = 0;
        while i < d.units.len() {
            let u = &d.units[i];
            self.str(u.name);
            let b = u.base;
            self.i32(b.kg);
            self.i32(b.m);
            self.i32(b.s);
            self.i32(b.a);
            self.i32(b.k);
            self.i32(b.mol);
            self.i32(b.cd);
            self.i32(b.rad);
            self.f64(b.factor);
            self.f64(b.offset);
            i += 1;
        }
        self.u32(d.log_categories.len() as u32);
        let mut i = 0;
        while i < d.log_categories.len() {
            self.str(d.log_categories[i].name);
            self.str(d.log_categories[i].description);
            i += 1;
        }
        // A version's description holds the variables of that version (FMI 2.0 leaves out the
        // FMI-3.0-only ones).
        // FMI 2.0 has no arrays: an array is its elements there, scalars of structured names
        // (`K[1,2]`) with the value references vr, vr + 1, .. ([`Variable::element_name`]).
        let version = interfaces.version;
        let mut n = 0u32;
        let mut i = 0;
        while i < d.variables.len() {
            let v = &d.variables[i];
            if v.in_version(version) {
                if v.is_array() && matches!(version, FmiVersion::V2) {
                    n += v.element_count() as u32;
                } else {
                    n += 1;
                }
            }
            i += 1;
        }
        self.u32(n);
        let mut i = 0;
        while i < d.variables.len() {
            let v = &d.variables[i];
            if v.in_version(version) {
                if v.is_array() && matches!(version, FmiVersion::V2) {
                    let mut k = 0;
                    while k < v.element_count() {
                        self.element(d, v, k);
                        k += 1;
                    }
                } else {
                    self.variable(d, version, v);
                }
            }
            i += 1;
        }
        self.str(d.internal_state);
        // Only models with event indicators carry the block: the encodings (and GUIDs) of the
        // models without events are those before events existed.
        if !d.event_indicators.is_empty() {
            self.u8(EVENT_INDICATORS_TAG);
            self.names(Some(d.event_indicators));
        }
        // The terminals: FMI 3.0 only, and only where there are some.
        if !d.terminals.is_empty() && matches!(version, FmiVersion::V3) {
            self.u8(TERMINALS_TAG);
            self.u32(d.terminals.len() as u32);
            let mut i = 0;
            while i < d.terminals.len() {
                self.terminal(&d.terminals[i]);
                i += 1;
            }
            // Nested terminals in a block of their own, only where some terminal has them: the
            // encodings (and instantiation tokens) of terminals without are those from before.
            let mut nested = false;
            let mut k = 0;
            while k < d.terminals.len() {
                nested |= !d.terminals[k].terminals.is_empty();
                k += 1;
            }
            if nested {
                self.u8(NESTED_TERMINALS_TAG);
                let mut k = 0;
                while k < d.terminals.len() {
                    self.nested_terminals(d.terminals[k].terminals);
                    k += 1;
                }
            }
            if d.bus_simulation {
                self.u8(BUS_SIMULATION_TAG);
            }
        }
        // Likewise the FMI 3.0 declarations, then the clocks and the clocked variables, then the
        // arrays sized by structural parameters: each block only where some variable has its
        // part, so the encodings (and instantiation tokens) of the models without are those before.
        self.parts(d, version, FMI3_EXTRAS_TAG, Part::Extras);
        self.parts(d, version, CLOCKS_TAG, Part::Clock);
        self.parts(d, version, SIZED_TAG, Part::Sized);
        // canInterpolateInputs: only where it is true, so the other encodings are those before.
        if interfaces.can_interpolate_inputs {
            self.u8(INTERPOLATES_INPUTS_TAG);
        }
        // The clocks' priorities (FMI 3.0): only where a clock has one, so the other encodings
        // are those before.
        self.parts(d, version, PRIORITIES_TAG, Part::Priority);
        // Scheduled Execution: only where it is offered.
        if interfaces.scheduled_execution {
            self.u8(SCHEDULED_EXECUTION_TAG);
        }
        // Display units and aliases: only where there are some, so the other encodings are
        // those before.
        self.display_units_and_aliases(d, version);
        // FMI 3.0 binaries end with the version; FMI 2.0 encodings (and so their GUIDs) are
        // those of the releases before FMI 3.0 existed.
        if let FmiVersion::V3 = interfaces.version {
            self.u8(3);
        }
    }
}

impl Enc<'_> {
    /// The block `tag` of the variables that have `part`, written only where some variable has
    /// it: their count, then for each its index among the version's scalar variables (an FMI 2.0
    /// array counts as its elements, and has no FMI 3.0 part) and the part.
    const fn parts(&mut self, d: &ModelDescription, version: FmiVersion, tag: u8, part: Part) {
        let mut count = 0u32;
        let mut i = 0;
        while i < d.variables.len() {
            let v = &d.variables[i];
            if v.in_version(version) && !(v.is_array() && matches!(version, FmiVersion::V2)) && part.of(v) {
                count += 1;
            }
            i += 1;
        }
        if count == 0 {
            return;
        }
        self.u8(tag);
        self.u32(count);
        let (mut i, mut at) = (0, 0u32);
        while i < d.variables.len() {
            let v = &d.variables[i];
            if v.in_version(version) && v.is_array() && matches!(version, FmiVersion::V2) {
                at += v.element_count() as u32;
            } else if v.in_version(version) {
                if part.of(v) {
                    self.u32(at);
                    self.part(v, part);
                }
                at += 1;
            }
            i += 1;
        }
    }

    /// `part` of `v` (which has it).
    const fn part(&mut self, v: &Variable, part: Part) {
        match part {
            Part::Extras => {
                self.u8(v.fmi3.only as u8);
                match v.fmi3.max_size {
                    None => self.u8(0),
                    Some(m) => {
                        self.u8(1);
                        self.u32(m);
                    }
                }
                self.str(v.fmi3.mime_type);
                self.u32(v.fmi3.dimensions.len() as u32);
                let mut k = 0;
                while k < v.fmi3.dimensions.len() {
                    self.u32(v.fmi3.dimensions[k]);
                    k += 1;
                }
            }
            Part::Clock => {
                match v.fmi3.clock {
                    None => self.u8(0),
                    Some(c) => {
                        self.u8(1);
                        self.u8(c.interval_variability as u8);
                        self.opt_f64(c.interval);
                        self.str(c.interval_parameter);
                        self.f64(c.shift);
                        self.u8(c.can_be_deactivated as u8);
                    }
                }
                self.names(Some(v.fmi3.clocks));
            }
            Part::Sized => {
                self.u32(v.fmi3.sized_by.len() as u32);
                let mut k = 0;
                while k < v.fmi3.sized_by.len() {
                    self.u32(v.fmi3.sized_by[k]);
                    k += 1;
                }
            }
            Part::Priority => {
                if let Some(ClockDecl { priority: Some(p), .. }) = v.fmi3.clock {
                    self.u32(p);
                }
            }
        }
    }

    /// The block of display units and aliases ([`DISPLAY_TAG`]): the units' display units (by
    /// the unit's index), then each variable's display unit and aliases (by its index in the
    /// version's variables; in FMI 2.0 an array's display unit is each element's, and an array
    /// has no aliases there). Left out where the model declares none.
    const fn display_units_and_aliases(&mut self, d: &ModelDescription, version: FmiVersion) {
        let mut units = 0u32;
        let mut i = 0;
        while i < d.units.len() {
            if !d.units[i].display_units.is_empty() {
                units += 1;
            }
            i += 1;
        }
        let mut entries = 0u32;
        let mut i = 0;
        while i < d.variables.len() {
            let v = &d.variables[i];
            if v.in_version(version) {
                if v.is_array() && matches!(version, FmiVersion::V2) {
                    if !v.display_unit.is_empty() {
                        entries += v.element_count() as u32;
                    }
                } else if !v.display_unit.is_empty() || !v.aliases.is_empty() {
                    entries += 1;
                }
            }
            i += 1;
        }
        if units == 0 && entries == 0 {
            return;
        }
        self.u8(DISPLAY_TAG);
        self.u32(units);
        let mut i = 0;
        while i < d.units.len() {
            let du = d.units[i].display_units;
            if !du.is_empty() {
                self.u32(i as u32);
                self.u32(du.len() as u32);
                let mut k = 0;
                while k < du.len() {
                    self.str(du[k].name);
                    self.f64(du[k].factor);
                    self.f64(du[k].offset);
                    self.u8(du[k].inverse as u8);
                    k += 1;
                }
            }
            i += 1;
        }
        self.u32(entries);
        let (mut i, mut at) = (0, 0u32);
        while i < d.variables.len() {
            let v = &d.variables[i];
            if v.in_version(version) && v.is_array() && matches!(version, FmiVersion::V2) {
                let mut k = 0;
                while k < v.element_count() {
                    if !v.display_unit.is_empty() {
                        self.u32(at);
                        self.str(v.display_unit);
                        self.u32(0);
                    }
                    at += 1;
                    k += 1;
                }
            } else if v.in_version(version) {
                if !v.display_unit.is_empty() || !v.aliases.is_empty() {
                    self.u32(at);
                    self.str(v.display_unit);
                    self.u32(v.aliases.len() as u32);
                    let mut k = 0;
                    while k < v.aliases.len() {
                        self.str(v.aliases[k].name);
                        self.str(v.aliases[k].description);
                        self.str(v.aliases[k].display_unit);
                        k += 1;
                    }
                }
                at += 1;
            }
            i += 1;
        }
    }
}

/// How many decimal digits `x` has.
const fn digits(x: usize) -> usize {
    let mut n = 1;
    let mut x = x;
    while x >= 10 {
        x /= 10;
        n += 1;
    }
    n
}

/// The array variable of FMI 2.0's description named `name`, if any.
const fn fmi2_array_named(d: &ModelDescription, name: &str) -> Option<&'static Variable> {
    let mut i = 0;
    while i < d.variables.len() {
        let v = &d.variables[i];
        if v.is_array() && v.in_version(FmiVersion::V2) && str_eq(v.name, name) {
            return Some(v);
        }
        i += 1;
    }
    None
}

const fn str_eq(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

pub(super) const HEADER: usize = MAGIC.len() + 4 + 4;
/// Marks the event indicators' block after the internal state (distinct from the version tag 3).
pub(super) const EVENT_INDICATORS_TAG: u8 = 0xE1;
/// Marks the block of FMI 3.0 declarations ([`Fmi3Extras`]) after that.
pub(super) const FMI3_EXTRAS_TAG: u8 = 0xE2;
/// Marks the terminals' block (FMI 3.0 encodings only), before the FMI 3.0 declarations.
pub(super) const TERMINALS_TAG: u8 = 0xE3;
/// Marks the nested terminals of the terminals' block (only where some terminal has them).
pub(super) const NESTED_TERMINALS_TAG: u8 = 0xEA;
/// Marks an FMI-LS-BUS bus simulation (after the terminals; only where it is one).
pub(super) const BUS_SIMULATION_TAG: u8 = 0xEB;
/// Marks the block of the clocks and clocked variables, after the FMI 3.0 declarations.
pub(super) const CLOCKS_TAG: u8 = 0xE4;
/// Marks a co-simulation step that follows input derivatives (canInterpolateInputs), last.
pub(super) const INTERPOLATES_INPUTS_TAG: u8 = 0xE5;
/// Marks the block of arrays sized by structural parameters, after the clocks.
pub(super) const SIZED_TAG: u8 = 0xE6;
/// Marks the clocks' priorities.
pub(super) const PRIORITIES_TAG: u8 = 0xE7;
/// Marks an FMU that offers Scheduled Execution.
pub(super) const SCHEDULED_EXECUTION_TAG: u8 = 0xE8;
/// Marks the block of display units and aliases, after Scheduled Execution.
pub(super) const DISPLAY_TAG: u8 = 0xE9;
/// [`Fmi3Extras::sized_by`] of a dimension of fixed length.
pub const NOT_SIZED: u32 = u32::MAX;

const fn write(d: &ModelDescription, interfaces: Interfaces, buf: &mut [u8]) -> usize {
    let mut body = Enc { buf, pos: 0 };
    body.bytes(MAGIC);
    body.u32(FORMAT_VERSION);
    body.u32(0); // payload length, filled in below
    body.description(d, interfaces);
    let total = body.pos;
    let len = ((total - HEADER) as u32).to_le_bytes();
    if body.buf.len() >= HEADER {
        let mut i = 0;
        while i < 4 {
            body.buf[MAGIC.len() + 4 + i] = len[i];
            i += 1;
        }
    }
    total
}

/// Length of [`encode`]'s output, for the array it is written into.
pub const fn encoded_len(d: &ModelDescription, interfaces: Interfaces) -> usize {
    write(d, interfaces, &mut [])
}

/// The description as bytes: [`MAGIC`], format version, payload length, payload.
/// `N` must be [`encoded_len`] of the same arguments.
pub const fn encode<const N: usize>(d: &ModelDescription, interfaces: Interfaces) -> [u8; N] {
    let mut out = [0u8; N];
    let n = write(d, interfaces, &mut out);
    assert!(n == N, "encode: N is not encoded_len of the same description");
    out
}

/// [`encode`] at run time, for tools and tests.
pub fn encode_to_vec(d: &ModelDescription, interfaces: Interfaces) -> Vec<u8> {
    let mut out = vec![0u8; encoded_len(d, interfaces)];
    write(d, interfaces, &mut out);
    out
}
