//! The decoder, for `cargo fmu` (the FMU itself never decodes): finds the encoded description
//! in a built library and reads it back into a [`ModelDescription`] with its [`Interfaces`].

use super::encode::{
    CLOCKS_TAG, DISPLAY_TAG, EVENT_INDICATORS_TAG, FMI3_EXTRAS_TAG, HEADER, INTERPOLATES_INPUTS_TAG,
    NESTED_TERMINALS_TAG, PRIORITIES_TAG, SCHEDULED_EXECUTION_TAG, SIZED_TAG, TERMINALS_TAG,
};
use super::*;

/// Finds the first encoded description in a built library (ELF, PE or Mach-O alike: it looks
/// for [`MAGIC`]) and returns exactly its bytes. A binary of both FMI versions carries two:
/// [`find_all_encoded`], [`find_encoded_for`].
pub fn find_encoded(binary: &[u8]) -> Result<&[u8], String> {
    Ok(find_all_encoded(binary)?[0])
}

/// The encoded description that starts at `at` (where [`MAGIC`] is).
fn encoded_at(binary: &[u8], at: usize) -> Result<&[u8], String> {
    let rest = &binary[at..];
    if rest.len() < HEADER {
        return Err("the embedded description is truncated".into());
    }
    let version = u32::from_le_bytes(rest[MAGIC.len()..MAGIC.len() + 4].try_into().expect("4 bytes"));
    if version != FORMAT_VERSION {
        return Err(format!(
            "the embedded description has format version {version}; this cargo-fmu reads version {FORMAT_VERSION} (use the cargo-fmu of the same rustfmu release)"
        ));
    }
    let len = u32::from_le_bytes(rest[MAGIC.len() + 4..HEADER].try_into().expect("4 bytes")) as usize;
    rest.get(..HEADER + len)
        .ok_or_else(|| "the embedded description is truncated".to_string())
}

/// Every encoded description in a built library, in the order they appear: one per FMI version
/// it exports (two for `export_fmu!`). [`MAGIC`] can also occur as a constant of the code (a
/// Windows DLL keeps rustfmu's own copy of it): an occurrence that does not decode is not a
/// description. An error when there is none: the reason the first occurrence did not decode
/// (an older format, a damaged file), or that there is no occurrence at all.
pub fn find_all_encoded(binary: &[u8]) -> Result<Vec<&[u8]>, String> {
    let mut out = Vec::new();
    let mut first_error = None;
    let mut from = 0;
    while let Some(at) = binary[from..].windows(MAGIC.len()).position(|w| w == MAGIC) {
        let at = from + at;
        match encoded_at(binary, at).and_then(|e| decode(e).map(|_| e)) {
            Ok(e) => {
                out.push(e);
                from = at + e.len();
            }
            Err(why) => {
                first_error.get_or_insert(why);
                from = at + 1;
            }
        }
    }
    if out.is_empty() {
        return Err(first_error.unwrap_or_else(|| {
            "the library carries no rustfmu description (is it a cdylib that calls rustfmu::export_fmu!, export_fmi2! or export_fmi3!?)".into()
        }));
    }
    Ok(out)
}

/// The encoded description of FMI `version` in a built library, or why there is none.
pub fn find_encoded_for(binary: &[u8], version: FmiVersion) -> Result<&[u8], String> {
    let all = find_all_encoded(binary)?;
    let mut has = Vec::new();
    for e in all {
        let (_, interfaces) = decode(e)?;
        if interfaces.version == version {
            return Ok(e);
        }
        has.push(interfaces.version.text());
    }
    Err(format!(
        "the library implements FMI {} only, not FMI {} (it calls rustfmu::export_fmi{}! itself; \
         rustfmu::export_fmu! exports both versions)",
        has.join(" and "),
        version.text(),
        &has[0][..1]
    ))
}

/// `Ok($ty { .. })` of the fields read from `$d` in their encoded order, each by its reader
/// (`str`, `i32`, `f64`, `bool`).
macro_rules! read {
    ($d:ident => $ty:ident { $($field:ident: $reader:ident),* $(,)? }) => {
        Ok($ty { $($field: $d.$reader()?),* })
    };
}

struct Dec<'a> {
    b: &'a [u8],
    at: usize,
}

fn leak(s: String) -> &'static str {
    Box::leak(s.into_boxed_str())
}

fn leak_slice<T>(v: Vec<T>) -> &'static [T] {
    Box::leak(v.into_boxed_slice())
}

/// The terminals nested in one terminal, each with its own (the encoder's `nested_terminals`).
fn nested_terminals(d: &mut Dec<'_>) -> Result<Vec<Terminal>, String> {
    d.list(|d| {
        let t = terminal(d)?;
        Ok(Terminal {
            terminals: leak_slice(nested_terminals(d)?),
            ..t
        })
    })
}

/// One terminal's attributes and members (the encoder's `terminal`), without nested terminals.
fn terminal(d: &mut Dec<'_>) -> Result<Terminal, String> {
    let (name, kind, matching_rule, description) = (d.str()?, d.str()?, d.str()?, d.str()?);
    let members = d.list(|d| read!(d => TerminalMember { variable: str, member: str, kind: str }))?;
    Ok(Terminal {
        name,
        kind,
        matching_rule,
        description,
        members: leak_slice(members),
        terminals: &[],
    })
}

impl Dec<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let end = self.at.checked_add(n).filter(|e| *e <= self.b.len()).ok_or_else(|| {
            format!(
                "the embedded description ends early (wanted {n} bytes at offset {})",
                self.at
            )
        })?;
        let s = &self.b[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }
    fn i32(&mut self) -> Result<i32, String> {
        Ok(i32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_bits(u64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        )))
    }
    fn str(&mut self) -> Result<&'static str, String> {
        let n = self.u32()? as usize;
        let bytes = self.take(n)?.to_vec();
        String::from_utf8(bytes)
            .map(leak)
            .map_err(|_| "a text in the embedded description is not UTF-8".to_string())
    }
    fn bool(&mut self) -> Result<bool, String> {
        Ok(self.u8()? != 0)
    }
    fn opt_f64(&mut self) -> Result<Option<f64>, String> {
        Ok(if self.u8()? == 0 { None } else { Some(self.f64()?) })
    }
    fn bound(&mut self) -> Result<Option<Bound>, String> {
        Ok(match self.u8()? {
            0 => None,
            tag => Some(Bound {
                value: self.f64()?,
                exclusive: tag == 2,
            }),
        })
    }
    fn names(&mut self) -> Result<Option<&'static [&'static str]>, String> {
        Ok(match self.u8()? {
            0 => None,
            _ => Some(leak_slice(self.list(Self::str)?)),
        })
    }
    fn count(&mut self) -> Result<usize, String> {
        let n = self.u32()? as usize;
        // Every element takes at least one byte: a larger count is corrupt, not a huge model.
        if n > self.b.len() - self.at {
            return Err(format!(
                "the embedded description claims {n} elements at offset {}",
                self.at
            ));
        }
        Ok(n)
    }
    /// A count, then that many items, each read by `item`.
    fn list<T>(&mut self, mut item: impl FnMut(&mut Self) -> Result<T, String>) -> Result<Vec<T>, String> {
        let n = self.count()?;
        let mut items = Vec::with_capacity(n);
        for _ in 0..n {
            items.push(item(self)?);
        }
        Ok(items)
    }
    /// Whether the optional block `tag` comes next (then its tag is read).
    fn block(&mut self, tag: u8) -> bool {
        let here = self.at < self.b.len() && self.b[self.at] == tag;
        self.at += usize::from(here);
        here
    }
    fn start(&mut self, name: &str) -> Result<Start, String> {
        Ok(match self.u8()? {
            0 => Start::None,
            1 => Start::Real(self.f64()?),
            2 => Start::Integer(self.i32()?),
            3 => Start::Boolean(self.u8()? != 0),
            4 => Start::String(self.str()?),
            5 => Start::Int64(i64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes"))),
            6 => Start::UInt64(u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes"))),
            7 => {
                let n = self.count()?;
                Start::Binary(leak_slice(self.take(n)?.to_vec()))
            }
            8 => Start::Array(leak_slice(self.list(|d| d.start(name))?)),
            t => return Err(format!("'{name}': unknown start code {t}")),
        })
    }
    fn variable(&mut self) -> Result<Variable, String> {
        let name = self.str()?;
        let value_reference = self.u32()?;
        let t = self.u8()?;
        let var_type = VarType::from_code(t).ok_or_else(|| format!("'{name}': unknown type code {t}"))?;
        let c = self.u8()?;
        let causality = Causality::from_code(c).ok_or_else(|| format!("'{name}': unknown causality code {c}"))?;
        let v = self.u8()?;
        let variability = Variability::from_code(v).ok_or_else(|| format!("'{name}': unknown variability code {v}"))?;
        let initial = match self.u8()? {
            255 => None,
            i => Some(Initial::from_code(i).ok_or_else(|| format!("'{name}': unknown initial code {i}"))?),
        };
        let start = self.start(name)?;
        let unit = self.str()?;
        let description = self.str()?;
        let min = self.bound()?;
        let max = self.bound()?;
        let nominal = self.opt_f64()?;
        let depends_on = self.names()?;
        let initial_depends_on = self.names()?;
        let derivative_of = if self.u8()? == 0 { None } else { Some(self.str()?) };
        let enumeration = if self.u8()? == 0 {
            None
        } else {
            let name = self.str()?;
            let description = self.str()?;
            let items = self.list(|d| read!(d => EnumItem { name: str, value: i32, description: str }))?;
            Some(&*Box::leak(Box::new(EnumType {
                name,
                description,
                items: leak_slice(items),
            })))
        };
        Ok(Variable {
            name,
            value_reference,
            var_type,
            causality,
            variability,
            initial,
            start,
            unit,
            display_unit: "",
            aliases: &[],
            description,
            min,
            max,
            nominal,
            depends_on,
            initial_depends_on,
            derivative_of,
            enumeration,
            fmi3: Fmi3Extras::NONE,
        })
    }
}

/// Element `at` of `items` (the `of` read so far) that a block refers to, as `what` `at`.
fn beyond<'a, T>(items: &'a mut [T], at: usize, what: &str, of: &str) -> Result<&'a mut T, String> {
    items.get_mut(at).ok_or_else(|| format!("{what} {at}, beyond the {of}"))
}

/// Decodes what [`encode`] wrote (as [`find_encoded`] returns it). The texts are leaked: this is
/// for short-lived tools such as `cargo fmu`, never for the FMU itself. One function of ~260
/// lines on purpose: it reads the blocks in the order `Enc::description` writes them, and the
/// two read side by side.
pub fn decode(encoded: &[u8]) -> Result<(ModelDescription, Interfaces), String> {
    if encoded.len() < HEADER || &encoded[..MAGIC.len()] != MAGIC {
        return Err("not an encoded rustfmu description".into());
    }
    let mut d = Dec {
        b: &encoded[HEADER..],
        at: 0,
    };
    let (model_identifier, description, author, version, copyright, license, generation_tool) =
        (d.str()?, d.str()?, d.str()?, d.str()?, d.str()?, d.str()?, d.str()?);
    let mut interfaces = Interfaces {
        co_simulation: d.u8()? != 0,
        model_exchange: d.u8()? != 0,
        version: FmiVersion::V2,
        can_interpolate_inputs: false,
        scheduled_execution: false,
    };
    let default_experiment = if d.u8()? == 0 {
        None
    } else {
        Some(DefaultExperiment {
            start_time: d.opt_f64()?,
            stop_time: d.opt_f64()?,
            tolerance: d.opt_f64()?,
            step_size: d.opt_f64()?,
        })
    };
    let mut units = d.list(|d| {
        Ok(Unit {
            name: d.str()?,
            base: BaseUnit {
                kg: d.i32()?,
                m: d.i32()?,
                s: d.i32()?,
                a: d.i32()?,
                k: d.i32()?,
                mol: d.i32()?,
                cd: d.i32()?,
                rad: d.i32()?,
                factor: d.f64()?,
                offset: d.f64()?,
            },
            display_units: &[],
        })
    })?;
    let log_categories = d.list(|d| read!(d => LogCategory { name: str, description: str }))?;
    let mut variables = d.list(Dec::variable)?;
    let internal_state = d.str()?;
    let mut event_indicators: &'static [&'static str] = &[];
    if d.block(EVENT_INDICATORS_TAG) {
        event_indicators = d.names()?.unwrap_or(&[]);
    }
    let mut terminals = if !d.block(TERMINALS_TAG) {
        Vec::new()
    } else {
        d.list(terminal)?
    };
    if !terminals.is_empty() && d.block(NESTED_TERMINALS_TAG) {
        for t in &mut terminals {
            t.terminals = leak_slice(nested_terminals(&mut d)?);
        }
    }
    let bus_simulation = !terminals.is_empty() && d.block(BUS_SIMULATION_TAG);
    if d.block(FMI3_EXTRAS_TAG) {
        let n = d.count()?;
        for _ in 0..n {
            let at = d.u32()? as usize;
            let only = d.u8()? != 0;
            let max_size = if d.u8()? == 0 { None } else { Some(d.u32()?) };
            let mime_type = d.str()?;
            let dimensions = leak_slice(d.list(Dec::u32)?);
            let v = beyond(&mut variables, at, "FMI 3.0 declarations of variable", "variables")?;
            v.fmi3 = Fmi3Extras {
                only,
                max_size,
                mime_type,
                dimensions,
                sized_by: &[],
                clock: None,
                clocks: &[],
            };
        }
    }
    if d.block(CLOCKS_TAG) {
        let n = d.count()?;
        for _ in 0..n {
            let at = d.u32()? as usize;
            let clock = if d.u8()? == 0 {
                None
            } else {
                let c = d.u8()?;
                let interval_variability = IntervalVariability::from_code(c)
                    .ok_or_else(|| format!("variable {at}: unknown intervalVariability code {c}"))?;
                Some(ClockDecl {
                    interval_variability,
                    interval: d.opt_f64()?,
                    interval_parameter: d.str()?,
                    shift: d.f64()?,
                    can_be_deactivated: d.u8()? != 0,
                    priority: None,
                })
            };
            let clocks = d.names()?.unwrap_or(&[]);
            let v = beyond(&mut variables, at, "the clocks of variable", "variables")?;
            v.fmi3.clock = clock;
            v.fmi3.clocks = clocks;
        }
    }
    if d.block(SIZED_TAG) {
        let n = d.count()?;
        for _ in 0..n {
            let at = d.u32()? as usize;
            let sized_by = leak_slice(d.list(Dec::u32)?);
            beyond(&mut variables, at, "the sizes of variable", "variables")?
                .fmi3
                .sized_by = sized_by;
        }
    }
    if d.block(INTERPOLATES_INPUTS_TAG) {
        interfaces.can_interpolate_inputs = true;
    }
    if d.block(PRIORITIES_TAG) {
        let n = d.count()?;
        for _ in 0..n {
            let at = d.u32()? as usize;
            let p = d.u32()?;
            match variables.get_mut(at).and_then(|v| v.fmi3.clock.as_mut()) {
                Some(c) => c.priority = Some(p),
                None => return Err(format!("a priority for variable {at}, which is no Clock")),
            }
        }
    }
    if d.block(SCHEDULED_EXECUTION_TAG) {
        interfaces.scheduled_execution = true;
    }
    // The last byte of an FMI 3.0 encoding is its version tag, never this block's tag.
    if d.at + 1 < d.b.len() && d.b[d.at] == DISPLAY_TAG {
        d.u8()?;
        let n = d.count()?;
        for _ in 0..n {
            let at = d.u32()? as usize;
            let list = d.list(|d| read!(d => DisplayUnit { name: str, factor: f64, offset: f64, inverse: bool }))?;
            beyond(&mut units, at, "display units of unit", "units")?.display_units = leak_slice(list);
        }
        let n = d.count()?;
        for _ in 0..n {
            let at = d.u32()? as usize;
            let display_unit = d.str()?;
            let aliases = d.list(|d| read!(d => Alias { name: str, description: str, display_unit: str }))?;
            let v = beyond(
                &mut variables,
                at,
                "the display unit and aliases of variable",
                "variables",
            )?;
            v.display_unit = display_unit;
            v.aliases = leak_slice(aliases);
        }
    }
    if d.at + 1 == d.b.len() {
        match d.u8()? {
            3 => interfaces.version = FmiVersion::V3,
            other => {
                return Err(format!(
                    "unknown FMI version tag {other} after the embedded description"
                ));
            }
        }
    }
    if d.at != d.b.len() {
        return Err(format!(
            "{} unexpected bytes after the embedded description",
            d.b.len() - d.at
        ));
    }
    Ok((
        ModelDescription {
            model_identifier,
            description,
            author,
            version,
            copyright,
            license,
            generation_tool,
            default_experiment,
            units: leak_slice(units),
            log_categories: leak_slice(log_categories),
            variables: leak_slice(variables),
            internal_state,
            event_indicators,
            terminals: leak_slice(terminals),
            bus_simulation,
        },
        interfaces,
    ))
}
