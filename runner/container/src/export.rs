//! The generator of the container's exported C functions, as the runtime's
//! (`rustfmu::core::trampolines`): [`fmi2`](crate::fmi2) and [`fmi3`](crate::fmi3) list their
//! functions as a table, one row per function — its C name, its parameters as the standard's
//! header names them, and what it does — and [`exports!`] writes the `#[no_mangle] unsafe extern
//! "C"` definitions.

/// Writes one `#[no_mangle] pub unsafe extern "C" fn` per row:
/// `name(param: Type, ...) -> Return => body;`. In the body, `F` is the function's C name (what
/// its messages call it). The body converts each raw pointer once, through the crate's
/// [`slice`](crate::slice), [`slice_mut`](crate::slice_mut), [`text`](crate::text) and
/// [`with`](crate::with), or in an `unsafe` block of its own with its `SAFETY:` line.
macro_rules! exports {
    ($($name:ident($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? => $body:expr;)*) => {
        $(
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn $name($($arg: $ty),*) $(-> $ret)? {
                #[allow(dead_code)]
                const F: &str = stringify!($name);
                $body
            }
        )*
    };
}
pub(crate) use exports;
