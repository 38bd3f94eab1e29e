//! The typed getters and setters of FMI 3.0: `nValues` against the value references (an array
//! counts each element), the added `time` variable, Int64 enumerations, C `bool` booleans,
//! binaries, strings.
//!
//! # Safety
//! As for [`super`]: every `unsafe fn` has the contract of the `fmi3*` function it implements.

use super::*;

/// The value reference FMI 3.0's added `time` variable has, if the model does not declare its
/// own independent variable.
#[inline]
pub(super) fn added_time_vr<M: CoSimulation>() -> Option<u32> {
    const {
        if M::DESCRIPTION.declares_independent() {
            None
        } else {
            Some(M::DESCRIPTION.time_value_reference())
        }
    }
}

/// The checks every 3.0 getter and setter makes of its arrays first.
pub(super) fn arrays<'a, M: CoSimulation, T>(
    inst: &Instance<M>,
    function: &str,
    vrs: Option<&'a [u32]>,
    n_values: usize,
    values: Option<T>,
) -> Result<(&'a [u32], T), fmi3Status> {
    match (vrs, values) {
        (Some(vrs), Some(values)) if n_values == value_count::<M>(&inst.sim.model, vrs) => Ok((vrs, values)),
        (Some(vrs), Some(_)) if !M::DESCRIPTION.has_arrays() => Err(inst.error(&format!(
            "{function}: nValues = {n_values}, but nValueReferences = {} (every variable of this FMU is a scalar)",
            vrs.len()
        ))),
        (Some(vrs), Some(_)) => Err(inst.error(&format!(
            "{function}: nValues = {n_values}, but the {} value references have {} values (an array counts each element)",
            vrs.len(),
            value_count::<M>(&inst.sim.model, vrs)
        ))),
        _ => Err(inst.error(&format!(
            "{function}: valueReferences or values is NULL with nValueReferences = {}, nValues = {n_values}",
            vrs.map_or(0, |v| v.len())
        ))),
    }
}

/// How many values the variables of `vrs` have (FMI 3.0's nValues): one per scalar, every
/// element of an array (an unknown value reference counts one; it is refused afterwards).
/// A sized array's elements within its lengths now (the structural parameters' values).
pub(super) fn value_count<M: CoSimulation>(model: &M, vrs: &[u32]) -> usize {
    if !const { M::DESCRIPTION.has_arrays() } {
        return vrs.len();
    }
    vrs.iter().map(|vr| count_of::<M>(model, *vr)).sum()
}

/// The number of values of one value reference (1 for a scalar or an unknown one).
pub(super) fn count_of<M: CoSimulation>(model: &M, vr: u32) -> usize {
    crate::core::structural::count_of(model, vr)
}

/// Refuses a value reference whose variable is declared with another 3.0 type: Int32 is
/// `Integer`, Int64 the enumerations (2.0 reads both as fmi2Integer).
fn check_declared<M: CoSimulation>(
    inst: &Instance<M>,
    function: &str,
    vrs: &[u32],
    want: VarType,
) -> Result<(), fmi3Status> {
    for vr in vrs {
        if let Some(v) = M::variable_index(*vr).map(|i| &M::DESCRIPTION.variables[i])
            && v.var_type != want
            && crate::description::same_api_type(v.var_type, want)
        {
            return Err(inst.error(&format!(
                "{function}: value reference {vr} ('{}') is {}, read and written with {}",
                v.name,
                fmi3_type_name(v.var_type),
                accessor(v.var_type)
            )));
        }
    }
    Ok(())
}

pub(super) fn fmi3_type_name(t: VarType) -> String {
    let name = t.fmi3_name();
    let article = if matches!(name.as_bytes()[0], b'E' | b'I') {
        "an"
    } else {
        "a"
    };
    format!("{article} {name} variable")
}

fn accessor(t: VarType) -> String {
    let name = match t {
        // FMI 3.0's Enumerations are Int64 values.
        VarType::Enumeration => "Int64",
        other => other.fmi3_name(),
    };
    format!("fmi3Get{name}/fmi3Set{name}")
}

/// What every 3.0 getter does before its type's own part: the instance and the state check
/// (`with_instance`), the two arrays (NULL and length checks, [`arrays`]); `read` then fills
/// `values` for the value references. One copy for every type (issue 22); each getter below is
/// its type's conversion only.
///
/// # Safety
/// The getter's contract: `c` NULL or a live instance of this library for `M`; `vr` NULL or
/// `nvr` elements; `values` NULL or `n_values` writable elements of `T`.
#[inline(always)]
unsafe fn getter<M: CoSimulation, T>(
    function: &'static str,
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut T,
    n_values: usize,
    read: impl FnOnce(&mut Instance<M>, &[u32], &mut [T]) -> fmi3Status,
) -> fmi3Status {
    with_instance(c, Call::GetValues, function, |inst| {
        // SAFETY: `slice` and `slice_mut` check NULL; the contract makes `vr` hold `nvr`
        // elements and `values` `n_values`.
        let (vrs, given) = unsafe { (slice(vr, nvr), slice_mut(values, n_values)) };
        match arrays(inst, function, vrs, n_values, given) {
            Ok((vrs, out)) => read(inst, vrs, out),
            Err(status) => status,
        }
    })
}

/// What every 3.0 setter does before its type's own part (as [`getter`]); `call` is the state
/// table's row: Float64 may be set where continuous inputs may, the other types where discrete
/// ones may.
///
/// # Safety
/// The setter's contract: `c` NULL or a live instance of this library for `M`; `vr` NULL or
/// `nvr` elements; `values` NULL or `n_values` elements of `T`.
#[inline(always)]
unsafe fn setter<M: CoSimulation, T>(
    function: &'static str,
    call: Call,
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const T,
    n_values: usize,
    write: impl FnOnce(&mut Instance<M>, &[u32], &[T]) -> fmi3Status,
) -> fmi3Status {
    with_instance(c, call, function, |inst| {
        // SAFETY: `slice` checks NULL; the contract makes `vr` hold `nvr` elements and `values`
        // `n_values`.
        let (vrs, given) = unsafe { (slice(vr, nvr), slice(values, n_values)) };
        match arrays(inst, function, vrs, n_values, given) {
            Ok((vrs, values)) => write(inst, vrs, values),
            Err(status) => status,
        }
    })
}

pub unsafe fn get_float64<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Float64,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetFloat64";
    let read = |inst: &mut Instance<M>, vrs: &[u32], out: &mut [f64]| match added_time_vr::<M>() {
        Some(time) if vrs.contains(&time) && inst.state() == State::Instantiated => inst.error(&format!(
            "{F}: value reference {time} is 'time', the independent variable: it has no start value and no \
             value before fmi3EnterInitializationMode sets the start time"
        )),
        Some(time) if vrs.contains(&time) => {
            let others: Vec<u32> = vrs.iter().copied().filter(|v| *v != time).collect();
            let mut got = vec![0.0; value_count::<M>(&inst.sim.model, &others)];
            let status = inst.get_values(F, &others, &mut got);
            if status != fmi3OK {
                return status;
            }
            let mut got = got.into_iter();
            let mut slots = out.iter_mut();
            for vr in vrs {
                if *vr == time {
                    if let Some(slot) = slots.next() {
                        *slot = inst.sim.time;
                    }
                    continue;
                }
                for _ in 0..count_of::<M>(&inst.sim.model, *vr) {
                    if let Some(slot) = slots.next() {
                        *slot = got.next().unwrap_or(f64::NAN);
                    }
                }
            }
            fmi3OK
        }
        _ => inst.get_values(F, vrs, out),
    };
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter::<M, _>(F, c, vr, nvr, values, n_values, read) }
}

pub unsafe fn set_float64<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Float64,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3SetFloat64";
    let write = |inst: &mut Instance<M>, vrs: &[u32], values: &[f64]| {
        if let Some(time) = added_time_vr::<M>()
            && vrs.contains(&time)
        {
            return inst.error(&format!(
                "{F}: value reference {time} is 'time', the independent variable: it cannot be set \
                 (fmi3EnterInitializationMode sets the start time, fmi3SetTime the time in model exchange); nothing set"
            ));
        }
        inst.set_values(F, vrs, values)
    };
    // SAFETY: this function's contract is `setter`'s.
    unsafe { setter::<M, _>(F, Call::SetValues, c, vr, nvr, values, n_values, write) }
}

pub unsafe fn get_int32<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Int32,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetInt32";
    let read =
        |inst: &mut Instance<M>, vrs: &[u32], out: &mut [i32]| match check_declared(inst, F, vrs, VarType::Integer) {
            Ok(()) => inst.get_values(F, vrs, out),
            Err(status) => status,
        };
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter::<M, _>(F, c, vr, nvr, values, n_values, read) }
}

pub unsafe fn set_int32<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Int32,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3SetInt32";
    let write =
        |inst: &mut Instance<M>, vrs: &[u32], values: &[i32]| match check_declared(inst, F, vrs, VarType::Integer) {
            Ok(()) => inst.set_values(F, vrs, values),
            Err(status) => status,
        };
    // SAFETY: this function's contract is `setter`'s.
    unsafe { setter::<M, _>(F, Call::SetDiscreteValues, c, vr, nvr, values, n_values, write) }
}

/// Int64 variables and Enumerations (fmi3GetInt64 is their 3.0 type's accessor; the values
/// are the items' `value`s), in one call if need be.
pub unsafe fn get_int64<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Int64,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetInt64";
    let read = |inst: &mut Instance<M>, vrs: &[u32], out: &mut [i64]| {
        let enums = match int64_or_enumerations(inst, F, vrs) {
            Ok(e) => e,
            Err(status) => return status,
        };
        if !enums.iter().any(|e| *e) {
            return inst.get_values(F, vrs, out);
        }
        // Both kinds read into their own arrays, copied out only when both succeeded.
        let pick = |want: bool| -> Vec<u32> {
            vrs.iter()
                .zip(&enums)
                .filter(|(_, e)| **e == want)
                .map(|(v, _)| *v)
                .collect()
        };
        let (e_vrs, i_vrs) = (pick(true), pick(false));
        let mut e_got = vec![0i32; value_count::<M>(&inst.sim.model, &e_vrs)];
        let mut i_got = vec![0i64; value_count::<M>(&inst.sim.model, &i_vrs)];
        let status = inst.get_values(F, &e_vrs, &mut e_got);
        if status != fmi3OK {
            return status;
        }
        let status = inst.get_values(F, &i_vrs, &mut i_got);
        if status != fmi3OK {
            return status;
        }
        let (mut e_got, mut i_got) = (e_got.into_iter(), i_got.into_iter());
        let mut slots = out.iter_mut();
        for (vr, e) in vrs.iter().zip(enums) {
            for _ in 0..count_of::<M>(&inst.sim.model, *vr) {
                if let Some(o) = slots.next() {
                    *o = if e {
                        e_got.next().map(i64::from).unwrap_or_default()
                    } else {
                        i_got.next().unwrap_or_default()
                    };
                }
            }
        }
        fmi3OK
    };
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter::<M, _>(F, c, vr, nvr, values, n_values, read) }
}

pub unsafe fn set_int64<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Int64,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3SetInt64";
    let write = |inst: &mut Instance<M>, vrs: &[u32], values: &[i64]| {
        let enums = match int64_or_enumerations(inst, F, vrs) {
            Ok(e) => e,
            Err(status) => return status,
        };
        let mut list = Vec::with_capacity(values.len());
        let mut given = values.iter();
        for (vr, e) in vrs.iter().zip(enums) {
            for v in given.by_ref().take(count_of::<M>(&inst.sim.model, *vr)) {
                if !e {
                    list.push(Value::Int64(*v));
                    continue;
                }
                match i32::try_from(*v) {
                    Ok(x) => list.push(Value::Integer(x)),
                    Err(_) => {
                        return inst.error(&format!(
                            "{F}: {v} for value reference {vr} is no item of its enumeration (every item's value is an Int32); nothing set"
                        ));
                    }
                }
            }
        }
        inst.set_value_list(F, vrs, &list)
    };
    // SAFETY: this function's contract is `setter`'s.
    unsafe { setter::<M, _>(F, Call::SetDiscreteValues, c, vr, nvr, values, n_values, write) }
}

/// For each value reference of an fmi3GetInt64/fmi3SetInt64 call: whether it is an Enumeration
/// (else an Int64); a variable of another type is refused with its accessor named.
fn int64_or_enumerations<M: CoSimulation>(
    inst: &Instance<M>,
    function: &str,
    vrs: &[u32],
) -> Result<Vec<bool>, fmi3Status> {
    let mut out = Vec::with_capacity(vrs.len());
    for vr in vrs {
        match M::variable_index(*vr).map(|i| &M::DESCRIPTION.variables[i]) {
            Some(v) if v.var_type == VarType::Enumeration => out.push(true),
            Some(v) if v.var_type == VarType::Int64 => out.push(false),
            Some(v) => {
                return Err(inst.error(&format!(
                    "{function}: value reference {vr} ('{}') is {}, read and written with {}",
                    v.name,
                    fmi3_type_name(v.var_type),
                    accessor(v.var_type)
                )));
            }
            None => {
                return Err(inst.error(&format!(
                    "{function}: value reference {vr} is not an Int64 or Enumeration variable of {} (see modelDescription.xml)",
                    M::DESCRIPTION.model_identifier
                )));
            }
        }
    }
    Ok(out)
}

/// The getter of an FMI 3.0 numeric type without a 2.0 counterpart (Float32, Int8, UInt8,
/// Int16, UInt16, UInt32, UInt64): the C array is the Rust type's.
pub unsafe fn get_typed<M: CoSimulation, T: FmiType + Copy>(
    c: Option<&Component<M>>,
    function: &'static str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut T,
    n_values: usize,
) -> fmi3Status {
    let read = |inst: &mut Instance<M>, vrs: &[u32], out: &mut [T]| inst.get_values(function, vrs, out);
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter::<M, T>(function, c, vr, nvr, values, n_values, read) }
}

pub unsafe fn set_typed<M: CoSimulation, T: FmiType + Copy>(
    c: Option<&Component<M>>,
    function: &'static str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const T,
    n_values: usize,
) -> fmi3Status {
    let write = |inst: &mut Instance<M>, vrs: &[u32], values: &[T]| inst.set_values(function, vrs, values);
    // Float32 may be continuous, so set where continuous inputs may be; the integers are discrete.
    let call = if T::TYPE.is_float() {
        Call::SetValues
    } else {
        Call::SetDiscreteValues
    };
    // SAFETY: this function's contract is `setter`'s.
    unsafe { setter::<M, T>(function, call, c, vr, nvr, values, n_values, write) }
}

pub unsafe fn get_binary<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    value_sizes: *mut usize,
    values: *mut fmi3Binary,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetBinary";
    with_instance(c, Call::GetValues, F, |inst| {
        // SAFETY: `slice` and `slice_mut` check NULL; the contract makes `vr` hold `nvr`
        // elements, and `valueSizes` and `values` `n_values` each.
        let (vrs, sizes, out) = unsafe {
            (
                slice(vr, nvr),
                slice_mut(value_sizes, n_values),
                slice_mut(values, n_values),
            )
        };
        let both = sizes.zip(out);
        match arrays(inst, F, vrs, n_values, both) {
            Ok((vrs, (sizes, out))) => inst.get_binaries(F, vrs, sizes, out),
            Err(status) => status,
        }
    })
}

pub unsafe fn set_binary<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    value_sizes: *const usize,
    values: *const fmi3Binary,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3SetBinary";
    with_instance(c, Call::SetDiscreteValues, F, |inst| {
        // SAFETY: `slice` checks NULL; the contract makes `vr` hold `nvr` elements, and
        // `valueSizes` and `values` `n_values` each.
        let (vrs, sizes, ptrs) = unsafe { (slice(vr, nvr), slice(value_sizes, n_values), slice(values, n_values)) };
        let (vrs, (sizes, ptrs)) = match arrays(inst, F, vrs, n_values, sizes.zip(ptrs)) {
            Ok(a) => a,
            Err(status) => return status,
        };
        let mut bytes = Vec::with_capacity(vrs.len());
        for (i, (size, p)) in sizes.iter().zip(ptrs).enumerate() {
            // SAFETY: `slice` checks NULL (a size of 0 with NULL is an empty value); the
            // contract makes `values[i]` hold `valueSizes[i]` bytes.
            match unsafe { slice(*p, *size) } {
                Some(b) => bytes.push(b),
                None => {
                    return inst.error(&format!(
                        "{F}: values[{i}] is NULL with valueSizes[{i}] = {size}; nothing set"
                    ));
                }
            }
        }
        inst.set_binaries(F, vrs, &bytes)
    })
}

pub unsafe fn get_boolean<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Boolean,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetBoolean";
    // Written as bytes 0 and 1: the importer's array is C `bool` (one byte).
    let read = |inst: &mut Instance<M>, vrs: &[u32], out: &mut [u8]| {
        crate::fmi2::api::get_booleans(inst, F, vrs, out, u8::from)
    };
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter::<M, u8>(F, c, vr, nvr, values as *mut u8, n_values, read) }
}

pub unsafe fn set_boolean<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Boolean,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3SetBoolean";
    // Read as bytes: any non-zero byte is true (a C caller may pass other values).
    let write = |inst: &mut Instance<M>, vrs: &[u32], values: &[u8]| {
        let values: Vec<bool> = values.iter().map(|b| *b != 0).collect();
        inst.set_values(F, vrs, &values)
    };
    // SAFETY: this function's contract is `setter`'s.
    unsafe {
        setter::<M, u8>(
            F,
            Call::SetDiscreteValues,
            c,
            vr,
            nvr,
            values as *const u8,
            n_values,
            write,
        )
    }
}

pub unsafe fn get_string<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3String,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetString";
    let read = |inst: &mut Instance<M>, vrs: &[u32], out: &mut [fmi3String]| inst.get_strings(vrs, out);
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter::<M, _>(F, c, vr, nvr, values, n_values, read) }
}

pub unsafe fn set_string<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3String,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3SetString";
    let write = |inst: &mut Instance<M>, vrs: &[u32], values: &[fmi3String]| {
        // SAFETY: the contract makes each string NUL-terminated.
        match unsafe { crate::fmi2::api::texts(values) } {
            Ok(texts) => inst.set_strings(vrs, &texts),
            Err(i) => inst.error(&format!("{F}: values[{i}] is NULL; nothing set")),
        }
    };
    // SAFETY: this function's contract is `setter`'s.
    unsafe { setter::<M, _>(F, Call::SetDiscreteValues, c, vr, nvr, values, n_values, write) }
}
