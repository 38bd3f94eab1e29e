//! The values of an FMI 3.0 variable of any type but Clock, scalar or array ([`Values`]): what
//! the runner gets and sets with fmi3Get{Type} / fmi3Set{Type} (`nValues` = the buffer's length),
//! connects, binds as a parameter and records. Below the importers, so that an FMI 3.0 instance,
//! a model-exchange one and an isolated one share it.
//!
//! A buffer is made once (its type and length fixed when the system is built, [`Values::zeros`])
//! and filled in place at every call: a String or Binary element keeps its bytes' capacity, so a
//! communication step allocates nothing once the values stop growing.

use md_reader::fmi3::Type;

/// The values of one or more FMI 3.0 variables of one type, in their serialization order
/// (an array's elements in row-major order, FMI 3.0, 2.2.6.1).
#[derive(Debug, Clone, PartialEq)]
pub enum Values {
    Float32(Vec<f32>),
    Float64(Vec<f64>),
    Int8(Vec<i8>),
    UInt8(Vec<u8>),
    Int16(Vec<i16>),
    UInt16(Vec<u16>),
    Int32(Vec<i32>),
    UInt32(Vec<u32>),
    /// Int64, and Enumeration (fmi3GetInt64 / fmi3SetInt64, FMI 3.0, 2.2.6.2).
    Int64(Vec<i64>),
    UInt64(Vec<u64>),
    Boolean(Vec<bool>),
    /// Each element's bytes with their terminating NUL (what fmi3SetString is given).
    String(Vec<Vec<u8>>),
    Binary(Vec<Vec<u8>>),
}

/// Applies `$body` to the vector of whichever numeric variant `$v` is (`$x` bound to it);
/// `$other` for String and Binary.
macro_rules! numeric {
    ($v:expr, $x:ident => $body:expr, $s:ident => $other:expr) => {
        match $v {
            Values::Float32($x) => $body,
            Values::Float64($x) => $body,
            Values::Int8($x) => $body,
            Values::UInt8($x) => $body,
            Values::Int16($x) => $body,
            Values::UInt16($x) => $body,
            Values::Int32($x) => $body,
            Values::UInt32($x) => $body,
            Values::Int64($x) => $body,
            Values::UInt64($x) => $body,
            Values::Boolean($x) => $body,
            Values::String($s) | Values::Binary($s) => $other,
        }
    };
}

impl Values {
    /// `n` values of `ty`: zeros, false, empty strings and binaries (None: a Clock).
    pub fn zeros(ty: Type, n: usize) -> Option<Values> {
        Some(match ty {
            Type::Float32 => Values::Float32(vec![0.0; n]),
            Type::Float64 => Values::Float64(vec![0.0; n]),
            Type::Int8 => Values::Int8(vec![0; n]),
            Type::UInt8 => Values::UInt8(vec![0; n]),
            Type::Int16 => Values::Int16(vec![0; n]),
            Type::UInt16 => Values::UInt16(vec![0; n]),
            Type::Int32 => Values::Int32(vec![0; n]),
            Type::UInt32 => Values::UInt32(vec![0; n]),
            Type::Int64 | Type::Enumeration => Values::Int64(vec![0; n]),
            Type::UInt64 => Values::UInt64(vec![0; n]),
            Type::Boolean => Values::Boolean(vec![false; n]),
            Type::String => Values::String(vec![vec![0]; n]),
            Type::Binary => Values::Binary(vec![Vec::new(); n]),
            Type::Clock => return None,
        })
    }

    /// The number of values.
    pub fn len(&self) -> usize {
        numeric!(self, x => x.len(), s => s.len())
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The FMI 3.0 type name of the values (Enumeration's are "Int64").
    pub fn type_name(&self) -> &'static str {
        match self {
            Values::Float32(_) => "Float32",
            Values::Float64(_) => "Float64",
            Values::Int8(_) => "Int8",
            Values::UInt8(_) => "UInt8",
            Values::Int16(_) => "Int16",
            Values::UInt16(_) => "UInt16",
            Values::Int32(_) => "Int32",
            Values::UInt32(_) => "UInt32",
            Values::Int64(_) => "Int64",
            Values::UInt64(_) => "UInt64",
            Values::Boolean(_) => "Boolean",
            Values::String(_) => "String",
            Values::Binary(_) => "Binary",
        }
    }

    /// Value `i` as a number of a recorded row (a Boolean as 0 or 1; an Int64 or UInt64 beyond
    /// 2^53 rounded to the nearest f64); None for String and Binary, which are not numbers.
    pub fn number(&self, i: usize) -> Option<f64> {
        Some(match self {
            Values::Float32(x) => f64::from(x[i]),
            Values::Float64(x) => x[i],
            Values::Int8(x) => f64::from(x[i]),
            Values::UInt8(x) => f64::from(x[i]),
            Values::Int16(x) => f64::from(x[i]),
            Values::UInt16(x) => f64::from(x[i]),
            Values::Int32(x) => f64::from(x[i]),
            Values::UInt32(x) => f64::from(x[i]),
            Values::Int64(x) => x[i] as f64,
            Values::UInt64(x) => x[i] as f64,
            Values::Boolean(x) => f64::from(u8::from(x[i])),
            Values::String(_) | Values::Binary(_) => return None,
        })
    }

    /// Makes these values equal to `other` (same type and length, checked when the system is
    /// built): numbers copied, strings and binaries into the capacity they have.
    pub fn copy_from(&mut self, other: &Values) {
        macro_rules! copy {
            ($($v:ident),*) => {
                match (self, other) {
                    $((Values::$v(a), Values::$v(b)) => a.copy_from_slice(b),)*
                    (Values::String(a), Values::String(b)) | (Values::Binary(a), Values::Binary(b)) => {
                        for (x, y) in a.iter_mut().zip(b) {
                            x.clear();
                            x.extend_from_slice(y);
                        }
                    }
                    (a, b) => unreachable!("a {} buffer given {} values", a.type_name(), b.type_name()),
                }
            };
        }
        copy!(
            Float32, Float64, Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, Boolean
        );
    }

    /// `n` values of `ty` from text: numbers and Booleans separated by white space as an array's
    /// `start` attribute writes them (FMI 3.0, 2.4.7.5; `true`/`false`/`1`/`0`), one String as
    /// it is, a Binary as hexadecimal digits (two per byte, as its `start`; one Binary).
    pub fn parse(ty: Type, n: usize, text: &str) -> Result<Values, String> {
        let mut v = Values::zeros(ty, n).ok_or("a Clock has no value to set")?;
        if let Values::String(s) | Values::Binary(s) = &mut v {
            if n != 1 {
                return Err(format!(
                    "{n} {} elements: give String and Binary arrays element by element",
                    ty.name()
                ));
            }
            s[0] = if ty == Type::String {
                let mut b = text.as_bytes().to_vec();
                if b.contains(&0) {
                    return Err("a String with a NUL".into());
                }
                b.push(0);
                b
            } else {
                hex(text)?
            };
            return Ok(v);
        }
        let words: Vec<&str> = text.split_whitespace().collect();
        if words.len() != n {
            return Err(format!(
                "{} value(s) given, the variable has {n} ({} separated by spaces)",
                words.len(),
                ty.name()
            ));
        }
        fn fill<T: std::str::FromStr>(out: &mut [T], words: &[&str], what: &str) -> Result<(), String> {
            for (o, w) in out.iter_mut().zip(words) {
                *o = w.parse().map_err(|_| format!("'{w}' is not {what}"))?;
            }
            Ok(())
        }
        let what = match ty {
            Type::Float32 | Type::Float64 => "a number".to_string(),
            _ => format!("an {} (within its range)", ty.name()),
        };
        match &mut v {
            Values::Boolean(b) => {
                for (o, w) in b.iter_mut().zip(&words) {
                    *o = match *w {
                        "true" | "1" => true,
                        "false" | "0" => false,
                        _ => return Err(format!("'{w}' is not a Boolean (true, false, 1, 0)")),
                    };
                }
            }
            Values::String(_) | Values::Binary(_) => unreachable!("returned above"),
            other => numeric!(other, x => fill(x, &words, &what)?, _s => ()),
        }
        Ok(v)
    }

    /// `n` String or Binary values of `ty`, one an element of `items` (SSV 2.0 `ssv:Value`s): a
    /// String as it is, a Binary as hexadecimal digits.
    pub fn from_items(ty: Type, n: usize, items: &[String]) -> Result<Values, String> {
        if !matches!(ty, Type::String | Type::Binary) {
            return Err(format!("ssv:Value elements for a {} variable", ty.name()));
        }
        if items.len() != n {
            return Err(format!(
                "{} value(s) given, the variable has {n} (one ssv:Value an element)",
                items.len()
            ));
        }
        let each = |item: &String| -> Result<Vec<u8>, String> {
            match ty {
                Type::String => {
                    let mut b = item.as_bytes().to_vec();
                    if b.contains(&0) {
                        return Err(format!("the String {item:?} has a NUL"));
                    }
                    b.push(0);
                    Ok(b)
                }
                _ => hex(item),
            }
        };
        let list = items.iter().map(each).collect::<Result<Vec<_>, String>>()?;
        Ok(if ty == Type::String {
            Values::String(list)
        } else {
            Values::Binary(list)
        })
    }

    /// One value of `ty` from a number (an SSV Real or Integer, an override): a Float32 rounded,
    /// an integer type's range checked.
    pub fn from_number(ty: Type, x: f64, integral: Option<i64>) -> Result<Values, String> {
        let int = |what: &str| -> Result<i128, String> {
            match integral {
                Some(i) => Ok(i128::from(i)),
                None if x.fract() == 0.0 && x.is_finite() => Ok(x as i128),
                None => Err(format!("{x} is not an integer ({what})")),
            }
        };
        macro_rules! ranged {
            ($v:ident, $t:ty) => {{
                let i = int(stringify!($v))?;
                Values::$v(vec![
                    <$t>::try_from(i).map_err(|_| format!("{i} is out of the {} range", stringify!($v)))?,
                ])
            }};
        }
        Ok(match ty {
            Type::Float32 => Values::Float32(vec![x as f32]),
            Type::Float64 => Values::Float64(vec![x]),
            Type::Int8 => ranged!(Int8, i8),
            Type::UInt8 => ranged!(UInt8, u8),
            Type::Int16 => ranged!(Int16, i16),
            Type::UInt16 => ranged!(UInt16, u16),
            Type::Int32 => ranged!(Int32, i32),
            Type::UInt32 => ranged!(UInt32, u32),
            Type::Int64 | Type::Enumeration => ranged!(Int64, i64),
            Type::UInt64 => ranged!(UInt64, u64),
            Type::Boolean => match int("Boolean")? {
                0 => Values::Boolean(vec![false]),
                1 => Values::Boolean(vec![true]),
                i => return Err(format!("{i} is not a Boolean (0 or 1)")),
            },
            Type::String | Type::Binary | Type::Clock => {
                return Err(format!("a number for a {} variable", ty.name()));
            }
        })
    }
}

/// The types in the order of their wire codes ([`Values::code`]): md-reader's [`Type::ALL`] up to
/// Binary (Enumeration and Clock travel as the values they hold).
const CODES: &[Type] = Type::ALL.split_at(13).0;

/// Applies `$body` to each numeric vector `$x` of `$v` with `$t` its element type; `$bool` for
/// Boolean, `$other` for String and Binary (`$s`).
macro_rules! by_element {
    ($v:expr, $x:ident: $t:ident => $body:expr, $b:ident => $bool:expr, $s:ident => $other:expr) => {
        match $v {
            Values::Float32($x) => {
                type $t = f32;
                $body
            }
            Values::Float64($x) => {
                type $t = f64;
                $body
            }
            Values::Int8($x) => {
                type $t = i8;
                $body
            }
            Values::UInt8($x) => {
                type $t = u8;
                $body
            }
            Values::Int16($x) => {
                type $t = i16;
                $body
            }
            Values::UInt16($x) => {
                type $t = u16;
                $body
            }
            Values::Int32($x) => {
                type $t = i32;
                $body
            }
            Values::UInt32($x) => {
                type $t = u32;
                $body
            }
            Values::Int64($x) => {
                type $t = i64;
                $body
            }
            Values::UInt64($x) => {
                type $t = u64;
                $body
            }
            Values::Boolean($b) => $bool,
            Values::String($s) | Values::Binary($s) => $other,
        }
    };
}

/// The values as bytes between the runner and a component's child process
/// ([`crate::isolate`]): a type code and a count, then each value (a number in its native bytes,
/// a Boolean one byte, a String or Binary its length as 4 native bytes first).
impl Values {
    /// The wire code of the values' type.
    pub(crate) fn code(&self) -> u8 {
        let name = self.type_name();
        CODES
            .iter()
            .position(|t| t.name() == name)
            .expect("every type has a code") as u8
    }

    /// `n` zero values of the type of wire code `code` (None: no such code).
    pub(crate) fn of_code(code: u8, n: usize) -> Option<Values> {
        Values::zeros(*CODES.get(usize::from(code))?, n)
    }

    /// Each value's bytes to `put`, in order.
    pub(crate) fn put<E>(&self, put: &mut impl FnMut(&[u8]) -> Result<(), E>) -> Result<(), E> {
        by_element!(self,
            x: T => x.iter().try_for_each(|v| put(&T::to_ne_bytes(*v))),
            b => b.iter().try_for_each(|v| put(&[u8::from(*v)])),
            s => s.iter().try_for_each(|v| {
                put(&(v.len() as u32).to_ne_bytes())?;
                put(v)
            })
        )
    }

    /// Its values read from `take(k)` (the next k bytes), as [`Values::put`] wrote them.
    pub(crate) fn take<'a>(&mut self, take: &mut impl FnMut(usize) -> &'a [u8]) {
        by_element!(self,
            x: T => x.iter_mut().for_each(|v| {
                *v = T::from_ne_bytes(take(std::mem::size_of::<T>()).try_into().expect("sized"));
            }),
            b => b.iter_mut().for_each(|v| *v = take(1)[0] != 0),
            s => s.iter_mut().for_each(|v| {
                let n = u32::from_ne_bytes(take(4).try_into().expect("sized")) as usize;
                v.clear();
                v.extend_from_slice(take(n));
            })
        )
    }
}

/// Hexadecimal digits, two per byte (a Binary's `start`, FMI 3.0, 2.4.7.5).
fn hex(text: &str) -> Result<Vec<u8>, String> {
    let t = text.trim();
    let t = t.strip_prefix("0x").unwrap_or(t);
    if !t.len().is_multiple_of(2) {
        return Err(format!("'{text}' is not hexadecimal bytes (an odd number of digits)"));
    }
    (0..t.len())
        .step_by(2)
        .map(|i| {
            u8::from_str_radix(t.get(i..i + 2).unwrap_or("?"), 16)
                .map_err(|_| format!("'{text}' is not hexadecimal bytes (two digits a byte)"))
        })
        .collect()
}

impl std::fmt::Display for Values {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let items: Vec<String> = match self {
            Values::String(s) => s
                .iter()
                .map(|b| format!("{:?}", String::from_utf8_lossy(b.strip_suffix(&[0]).unwrap_or(b))))
                .collect(),
            Values::Binary(s) => s
                .iter()
                .map(|b| b.iter().map(|x| format!("{x:02x}")).collect())
                .collect(),
            other => (0..other.len())
                .map(|i| match other {
                    Values::Float32(x) => format!("{}", x[i]),
                    Values::Int64(x) => format!("{}", x[i]),
                    Values::UInt64(x) => format!("{}", x[i]),
                    Values::Boolean(x) => format!("{}", x[i]),
                    o => format!("{}", o.number(i).unwrap_or(f64::NAN)),
                })
                .collect(),
        };
        f.write_str(&items.join(" "))
    }
}
