//! Values at the C API, and the Rust types a model's variables may have.

use crate::description::{EnumType, VarType};

/// A value of a numeric or Boolean variable as it crosses the C API (Enumerations travel as
/// Integers). Strings go their own way ([`crate::Variables::get_string`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    Real(f64),
    Integer(i32),
    Boolean(bool),
}

impl Value {
    /// The C API type that carries this value.
    pub fn api_type(&self) -> VarType {
        match self {
            Value::Real(_) => VarType::Real,
            Value::Integer(_) => VarType::Integer,
            Value::Boolean(_) => VarType::Boolean,
        }
    }

    /// The value as a number, for range checks (Booleans have none).
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Value::Real(x) => Some(*x),
            Value::Integer(n) => Some(*n as f64),
            Value::Boolean(_) => None,
        }
    }
}

/// A Rust type a variable may have: `f64` (Real), `i32` (Integer), `bool` (Boolean), `String`
/// (String), or a fieldless enum with `#[derive(FmuEnum)]` (Enumeration).
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
}

impl FmiType for f64 {
    const TYPE: VarType = VarType::Real;
    fn to_value(&self) -> Option<Value> {
        Some(Value::Real(*self))
    }
    fn from_value(v: Value) -> Option<Self> {
        match v {
            Value::Real(x) => Some(x),
            _ => None,
        }
    }
}

impl FmiType for i32 {
    const TYPE: VarType = VarType::Integer;
    fn to_value(&self) -> Option<Value> {
        Some(Value::Integer(*self))
    }
    fn from_value(v: Value) -> Option<Self> {
        match v {
            Value::Integer(x) => Some(x),
            _ => None,
        }
    }
}

impl FmiType for bool {
    const TYPE: VarType = VarType::Boolean;
    fn to_value(&self) -> Option<Value> {
        Some(Value::Boolean(*self))
    }
    fn from_value(v: Value) -> Option<Self> {
        match v {
            Value::Boolean(x) => Some(x),
            _ => None,
        }
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
    fn code(self) -> i32;
    fn from_code(code: i32) -> Option<Self>;
}
