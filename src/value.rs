//! Values at the C API, and the Rust types a model's variables may have.

use crate::description::{Bound, EnumType, VarType};

/// A value of a numeric or Boolean variable as it crosses the C API (Enumerations travel as
/// Integers). Strings and Binaries go their own way ([`crate::Variables::get_string`],
/// [`crate::Variables::get_binary`]). `Real` is FMI 3.0's Float64 and `Integer` its Int32; the
/// other numeric types are FMI 3.0's only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    Real(f64),
    Integer(i32),
    Boolean(bool),
    Float32(f32),
    Int8(i8),
    UInt8(u8),
    Int16(i16),
    UInt16(u16),
    UInt32(u32),
    Int64(i64),
    UInt64(u64),
}

impl Value {
    /// The C API type that carries this value.
    pub fn api_type(&self) -> VarType {
        match self {
            Value::Real(_) => VarType::Real,
            Value::Integer(_) => VarType::Integer,
            Value::Boolean(_) => VarType::Boolean,
            Value::Float32(_) => VarType::Float32,
            Value::Int8(_) => VarType::Int8,
            Value::UInt8(_) => VarType::UInt8,
            Value::Int16(_) => VarType::Int16,
            Value::UInt16(_) => VarType::UInt16,
            Value::UInt32(_) => VarType::UInt32,
            Value::Int64(_) => VarType::Int64,
            Value::UInt64(_) => VarType::UInt64,
        }
    }

    /// The value as a number, for messages and plots (Booleans have none; a 64-bit integer
    /// beyond 2^53 rounds: range checks use [`Value::within`]).
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Value::Real(x) => Some(*x),
            Value::Float32(x) => Some(f64::from(*x)),
            Value::Boolean(_) => None,
            other => other.as_i128().map(|n| n as f64),
        }
    }

    /// An integer value exactly (Enumerations are Integers).
    pub fn as_i128(&self) -> Option<i128> {
        Some(match *self {
            Value::Integer(n) => n.into(),
            Value::Int8(n) => n.into(),
            Value::UInt8(n) => n.into(),
            Value::Int16(n) => n.into(),
            Value::UInt16(n) => n.into(),
            Value::UInt32(n) => n.into(),
            Value::Int64(n) => n.into(),
            Value::UInt64(n) => n.into(),
            _ => return None,
        })
    }

    /// Whether a floating-point value is finite (other values always are).
    pub fn is_finite(&self) -> bool {
        match self {
            Value::Real(x) => x.is_finite(),
            Value::Float32(x) => x.is_finite(),
            _ => true,
        }
    }

    /// Whether the value lies within `min` and `max`. Integers are compared exactly (the
    /// bounds of an integer variable are integers, checked at compile time to be exact in f64).
    pub fn within(&self, min: Option<Bound>, max: Option<Bound>) -> bool {
        if let Some(n) = self.as_i128() {
            let above = |b: Bound| {
                let v = b.value as i128;
                if b.exclusive { n > v } else { n >= v }
            };
            let below = |b: Bound| {
                let v = b.value as i128;
                if b.exclusive { n < v } else { n <= v }
            };
            return min.is_none_or(above) && max.is_none_or(below);
        }
        match self.as_f64() {
            Some(x) => min.is_none_or(|b| b.admits_above(x)) && max.is_none_or(|b| b.admits_below(x)),
            None => true,
        }
    }
}

/// A Rust type a variable may have: `f64` (Real, FMI 3.0 Float64), `i32` (Integer, Int32),
/// `bool` (Boolean), `String` (String), a fieldless enum with `#[derive(FmuEnum)]`
/// (Enumeration); and, FMI 3.0 only, `f32` (Float32), `i8`, `u8`, `i16`, `u16`, `u32`, `i64`,
/// `u64` (Int8 .. UInt64) and `Vec<u8>` (Binary).
pub trait FmiType: Sized {
    const TYPE: VarType;
    /// The enumeration type, for Enumeration variables.
    const ENUMERATION: Option<&'static EnumType> = None;
    fn to_value(&self) -> Option<Value>;
    fn from_value(v: Value) -> Option<Self>;
    fn as_str(&self) -> Option<&str> {
        None
    }
    fn from_str(_s: &str) -> Option<Self> {
        None
    }
    fn as_bytes(&self) -> Option<&[u8]> {
        None
    }
    fn from_bytes(_b: &[u8]) -> Option<Self> {
        None
    }
}

/// The numeric and Boolean types (FMI 2.0's and FMI 3.0's): one impl each, a `Value` of its
/// own variant.
macro_rules! numeric {
    ($($t:ty => $variant:ident),* $(,)?) => {$(
        impl FmiType for $t {
            const TYPE: VarType = VarType::$variant;
            fn to_value(&self) -> Option<Value> {
                Some(Value::$variant(*self))
            }
            fn from_value(v: Value) -> Option<Self> {
                match v {
                    Value::$variant(x) => Some(x),
                    _ => None,
                }
            }
        }
    )*};
}

numeric!(
    f64 => Real,
    i32 => Integer,
    bool => Boolean,
    f32 => Float32,
    i8 => Int8,
    u8 => UInt8,
    i16 => Int16,
    u16 => UInt16,
    u32 => UInt32,
    i64 => Int64,
    u64 => UInt64,
);

/// Binary: the bytes.
impl FmiType for Vec<u8> {
    const TYPE: VarType = VarType::Binary;
    fn to_value(&self) -> Option<Value> {
        None
    }
    fn from_value(_v: Value) -> Option<Self> {
        None
    }
    fn as_bytes(&self) -> Option<&[u8]> {
        Some(self)
    }
    fn from_bytes(b: &[u8]) -> Option<Self> {
        Some(b.to_vec())
    }
}

impl FmiType for String {
    const TYPE: VarType = VarType::String;
    fn to_value(&self) -> Option<Value> {
        None
    }
    fn from_value(_v: Value) -> Option<Self> {
        None
    }
    fn as_str(&self) -> Option<&str> {
        Some(self)
    }
    fn from_str(s: &str) -> Option<Self> {
        Some(s.to_owned())
    }
}

/// A fieldless enum usable as an Enumeration variable; implemented by `#[derive(FmuEnum)]`.
pub trait FmuEnum: Copy + Sized + 'static {
    const TYPE: &'static EnumType;
    /// The first item: the value of a calculated Enumeration before the model computes it.
    const FIRST: Self;
    fn code(self) -> i32;
    fn from_code(code: i32) -> Option<Self>;
}
