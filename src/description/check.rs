//! Checks of the declared values at compile time (the derive's generated code calls
//! [`check_values`] in a `const` item).

use super::*;

/// What [`check_values`] finds wrong.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ValueError {
    /// min is not a finite number
    MinNotFinite,
    /// max is not a finite number
    MaxNotFinite,
    /// min is above max
    MinAboveMax,
    /// an Integer's min must be an integer within i32
    IntegerMin,
    /// an Integer's max must be an integer within i32
    IntegerMax,
    /// the start value is not a finite number
    StartNotFinite,
    /// the start value is below min
    StartBelowMin,
    /// the start value is above max
    StartAboveMax,
    /// nominal must be finite and > 0
    Nominal,
    /// the start value is no item of the enumeration
    StartNotAnItem,
    /// an integer's min must be an integer of its type, within ±2^53
    IntegerTypeMin,
    /// an integer's max must be an integer of its type, within ±2^53
    IntegerTypeMax,
}

impl ValueError {
    /// The same words as the compile error of `#[derive(Model)]`.
    pub const fn message(self) -> &'static str {
        match self {
            ValueError::MinNotFinite => "min is not a finite number",
            ValueError::MaxNotFinite => "max is not a finite number",
            ValueError::MinAboveMax => "min is above max",
            ValueError::IntegerMin => "an Integer's min must be an integer within i32",
            ValueError::IntegerMax => "an Integer's max must be an integer within i32",
            ValueError::StartNotFinite => "the start value is not a finite number",
            ValueError::StartBelowMin => "the start value is below min",
            ValueError::StartAboveMax => "the start value is above max",
            ValueError::Nominal => "nominal must be finite and > 0",
            ValueError::StartNotAnItem => "the start value is no item of the enumeration",
            ValueError::IntegerTypeMin => "an integer's min must be an integer of its type, within ±2^53",
            ValueError::IntegerTypeMax => "an integer's max must be an integer of its type, within ±2^53",
        }
    }
}

/// Checks of a declaration that need its values; `#[derive(Model)]` evaluates this for every
/// variable at compile time, so a violation is a compile error naming the variable.
pub const fn check_values(v: &Variable) -> Result<(), ValueError> {
    const fn finite(x: f64) -> bool {
        x.is_finite()
    }
    if let Some(b) = v.min
        && !finite(b.value)
    {
        return Err(ValueError::MinNotFinite);
    }
    if let Some(b) = v.max
        && !finite(b.value)
    {
        return Err(ValueError::MaxNotFinite);
    }
    if let (Some(l), Some(h)) = (v.min, v.max)
        && l.value > h.value
    {
        return Err(ValueError::MinAboveMax);
    }
    if matches!(v.var_type, VarType::Integer | VarType::Enumeration) {
        if let Some(l) = v.min
            && l.value != (l.value as i32) as f64
        {
            return Err(ValueError::IntegerMin);
        }
        if let Some(h) = v.max
            && h.value != (h.value as i32) as f64
        {
            return Err(ValueError::IntegerMax);
        }
    }
    // The other integer types: integral bounds within the type's range and exact in f64
    // (the runtime compares integers with them exactly).
    if let (true, Some((lo, hi))) = (
        v.var_type.is_integer() && !matches!(v.var_type, VarType::Integer),
        v.var_type.integer_range(),
    ) {
        const EXACT: f64 = 9007199254740992.0; // 2^53
        const fn fits(x: f64, lo: i128, hi: i128) -> bool {
            // (an integral value within ±2^53 converts to i128 and back unchanged)
            x.abs() <= EXACT && (x as i128) as f64 == x && (x as i128) >= lo && (x as i128) <= hi
        }
        if let Some(l) = v.min
            && !fits(l.value, lo, hi)
        {
            return Err(ValueError::IntegerTypeMin);
        }
        if let Some(h) = v.max
            && !fits(h.value, lo, hi)
        {
            return Err(ValueError::IntegerTypeMax);
        }
    }
    // A scalar's start, or each element's of an array.
    let starts: &[Start] = match &v.start {
        Start::Array(items) => items,
        one => core::slice::from_ref(one),
    };
    let mut k = 0;
    while k < starts.len() {
        let x = match starts[k] {
            Start::Int64(n) => Some(n as f64),
            Start::UInt64(n) => Some(n as f64),
            Start::Real(x) => {
                if !finite(x) {
                    return Err(ValueError::StartNotFinite);
                }
                Some(x)
            }
            Start::Integer(n) => Some(n as f64),
            _ => None,
        };
        if let Some(x) = x {
            if let Some(l) = v.min
                && !(if l.exclusive { x > l.value } else { x >= l.value })
            {
                return Err(ValueError::StartBelowMin);
            }
            if let Some(h) = v.max
                && !(if h.exclusive { x < h.value } else { x <= h.value })
            {
                return Err(ValueError::StartAboveMax);
            }
        }
        k += 1;
    }
    if let Some(n) = v.nominal
        && !(finite(n) && n > 0.0)
    {
        return Err(ValueError::Nominal);
    }
    if let (Some(e), Start::Integer(code)) = (v.enumeration, v.start) {
        let mut i = 0;
        while i < e.items.len() {
            if e.items[i].value == code {
                return Ok(());
            }
            i += 1;
        }
        return Err(ValueError::StartNotAnItem);
    }
    Ok(())
}
