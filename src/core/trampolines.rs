//! The generator of the exported C functions. Each version's export macro
//! ([`export_fmi2!`](crate::export_fmi2), [`export_fmi3!`](crate::export_fmi3)) lists its
//! functions as a table, one row per function: its C name, its parameters as the standard's
//! header names them, and the runtime function it forwards to. [`__rustfmu_extern_c!`] writes
//! the `#[no_mangle] unsafe extern "C"` definitions, so that the one `unsafe` block each of them
//! has is written here once, with its `SAFETY:` line. Inside it, a row converts the importer's
//! instance handle once (`component(c)`, [`crate::core::guard::component`]): the runtime
//! functions take the component, so that none of them converts the handle again.

/// Writes one `#[no_mangle] pub unsafe extern "C" fn` per row:
/// `name(param: Type, ...) -> Return => runtime_call(param, ...);`. Not part of the API.
#[doc(hidden)]
#[macro_export]
macro_rules! __rustfmu_extern_c {
    ($($name:ident($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? => $target:expr;)*) => {
        $(
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn $name($($arg: $ty),*) $(-> $ret)? {
                // SAFETY: the importer's arguments, unchanged. Calling this function, it promises
                // what the standard asks of them (an instance handle this library made, or NULL;
                // arrays as long as their counts; NUL-terminated strings; writable outputs): all
                // the row's runtime function requires (`# Safety` of fmi2::api, fmi3::api, shared),
                // and all that `component` requires of the instance handle.
                unsafe { $target }
            }
        )*
    };
}
