//! What both importers (FMI 2.0 and 3.0), the model-exchange integrator and an isolated instance
//! share, below all of them: the error of a call ([`Fmi2Error`], FMI 2.0's statuses, which every
//! instance answers with), the FMU states an instance took ([`FmuState`], `Slots`), a folder
//! an FMU is unpacked into (`Scratch`), and the forwarding of a method to the instance it is
//! one of (`dispatch!`).

use std::ffi::c_void;
use std::path::{Path, PathBuf};

/// A status other than fmi2OK and fmi2Warning (which count as success).
#[derive(Debug, Clone, PartialEq)]
pub enum Fmi2Error {
    Discard,
    Error,
    Fatal,
    Pending,
    /// A status code the standard does not define.
    Unknown(u32),
    /// The importer's own failure (a NULL state, a missing function): the message.
    Importer(String),
    /// An isolated component's process is gone (crashed, exited, killed after a timeout): how.
    Died(String),
    /// A call of an isolated component that failed and is reported by a later call
    /// ([`crate::isolate`]: the calls that answer only a status are not waited for).
    Deferred(Box<Deferred>),
    /// Not a failure: the instance asks to end the simulation, at its last successful time, s
    /// (FMI 2.0.5 4.2.3: fmi2DoStep's fmi2Discard with fmi2GetBooleanStatus(fmi2Terminated)
    /// true, "the slave wants to terminate the simulation"; FMI 3.0.2 4.2.1: fmi3DoStep's or
    /// fmi3UpdateDiscreteStates' `terminateSimulation`; a model exchange FMU's
    /// `terminateSimulation`). The run ends there ([`crate::ErrorKind::Terminated`]).
    Terminate(f64),
}

/// A call that failed, reported by the call after it: which, and when.
#[derive(Debug, Clone, PartialEq)]
pub struct Deferred {
    /// The FMI 2.0 name of the call that failed (fmi2DoStep, fmi2SetReal, ...).
    pub function: &'static str,
    /// The time it was made at (a step's start; a set: the end of the step before).
    pub time: Option<f64>,
    pub error: Fmi2Error,
}

impl std::fmt::Display for Fmi2Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fmi2Error::Discard => write!(f, "fmi2Discard"),
            Fmi2Error::Error => write!(f, "fmi2Error"),
            Fmi2Error::Fatal => write!(f, "fmi2Fatal"),
            Fmi2Error::Pending => write!(f, "fmi2Pending"),
            Fmi2Error::Unknown(s) => write!(f, "status {s}"),
            Fmi2Error::Importer(m) | Fmi2Error::Died(m) => write!(f, "{m}"),
            Fmi2Error::Terminate(t) => write!(f, "asked to terminate the simulation at t = {t} s"),
            Fmi2Error::Deferred(d) => match d.time {
                Some(t) => write!(f, "{} at t = {t} s: {}", d.function, d.error),
                None => write!(f, "{}: {}", d.function, d.error),
            },
        }
    }
}

/// Loads the FMU binary at `path` (both importers), after the libraries it expects the
/// importer to have loaded ([`crate::libpython`]: a PythonFMU binary's libpython, said on
/// standard error when loaded).
pub(crate) fn load_binary(path: &Path) -> Result<libloading::Library, String> {
    const OPTION: Option<&str> = Some("--preload-lib");
    let say = |sentence: Option<String>| {
        if let Some(s) = sentence.filter(|s| !s.is_empty()) {
            eprintln!("rustfmu-runner: {s}");
        }
    };
    say(crate::libpython::before(path, OPTION).map_err(|e| format!("cannot load {}: {e}", path.display()))?);
    // SAFETY: loading runs the library's initializers: an FMU binary's, trusted as the
    // importer trusts the FMU it was given.
    match unsafe { libloading::Library::new(path) } {
        Ok(lib) => Ok(lib),
        Err(e) => {
            let e = e.to_string();
            match crate::libpython::after_failure(path, &e, OPTION) {
                Ok(Some(sentence)) => {
                    say(Some(sentence));
                    // SAFETY: as above.
                    unsafe { libloading::Library::new(path) }.map_err(|e| e.to_string())
                }
                Ok(None) => Err(e),
                Err(why) => Err(why),
            }
            .map_err(|e| format!("cannot load {}: {e}", path.display()))
        }
    }
}

/// The function `name` of the binary `lib` (loaded from `path`), or why there is none.
///
/// # Safety
/// `T` is the type of that function (the standard's header gives it).
pub(crate) unsafe fn symbol<T: Copy>(lib: &libloading::Library, path: &Path, name: &str) -> Result<T, String> {
    // SAFETY: the caller's promise: `T` is the function's type.
    unsafe { lib.get::<T>(format!("{name}\0").as_bytes()) }
        .map(|s| *s)
        .map_err(|e| format!("{}: no function {name} ({e})", path.display()))
}

/// The function `name` of the binary `lib`, if it exports it.
///
/// # Safety
/// As [`symbol`].
pub(crate) unsafe fn optional<T: Copy>(lib: &libloading::Library, name: &str) -> Option<T> {
    // SAFETY: as in `symbol`.
    unsafe { lib.get::<T>(format!("{name}\0").as_bytes()) }.ok().map(|s| *s)
}

/// The lengths of a call's value references and values, which must agree.
pub(crate) fn lengths(vrs: usize, values: usize) -> Result<(), Fmi2Error> {
    if vrs == values {
        Ok(())
    } else {
        Err(Fmi2Error::Importer(format!("{vrs} value references, {values} values")))
    }
}

/// The arguments of a directional derivative (fmi2GetDirectionalDerivative,
/// fmi3GetDirectionalDerivative): `out` = J `seed`, J = d(`unknowns`)/d(`knowns`).
pub struct Directional<'a> {
    pub unknowns: &'a [u32],
    pub knowns: &'a [u32],
    pub seed: &'a [f64],
    pub out: &'a mut [f64],
}

impl Directional<'_> {
    /// The seed as long as the knowns and the output as the unknowns, each pair checked by
    /// `lengths` (the caller's message).
    pub(crate) fn check_lengths(&self, lengths: fn(usize, usize) -> Result<(), Fmi2Error>) -> Result<(), Fmi2Error> {
        lengths(self.knowns.len(), self.seed.len())?;
        lengths(self.unknowns.len(), self.out.len())
    }

    /// The C arguments: the unknowns and their number, the knowns and their number, the seed
    /// (as many as the knowns, once checked) and the output (as many as the unknowns).
    pub(crate) fn c_args(&mut self) -> (*const u32, usize, *const u32, usize, *const f64, *mut f64) {
        (
            self.unknowns.as_ptr(),
            self.unknowns.len(),
            self.knowns.as_ptr(),
            self.knowns.len(),
            self.seed.as_ptr(),
            self.out.as_mut_ptr(),
        )
    }
}

/// An FMU state of an [`InstanceCS`](crate::instance::InstanceCS) (an index into its states).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FmuState(pub(crate) usize);

/// The FMU states an instance took (its C pointers; None: freed), handed out as [`FmuState`]
/// indices; the same for FMI 2.0 and 3.0 instances.
#[derive(Default)]
pub(crate) struct Slots(Vec<Option<*mut c_void>>);

impl Slots {
    /// A new state's index (a freed slot reused).
    pub(crate) fn keep(&mut self, s: *mut c_void) -> Result<FmuState, Fmi2Error> {
        if s.is_null() {
            return Err(Fmi2Error::Importer("the FMU gave a NULL FMU state".into()));
        }
        match self.0.iter().position(Option::is_none) {
            Some(i) => {
                self.0[i] = Some(s);
                Ok(FmuState(i))
            }
            None => {
                self.0.push(Some(s));
                Ok(FmuState(self.0.len() - 1))
            }
        }
    }

    /// The C pointer of `s`, if it is one of these states.
    pub(crate) fn raw(&self, s: &FmuState) -> Result<*mut c_void, Fmi2Error> {
        self.0
            .get(s.0)
            .copied()
            .flatten()
            .ok_or_else(|| Fmi2Error::Importer(format!("FMU state {} is not one of this instance's", s.0)))
    }

    pub(crate) fn replace(&mut self, s: &FmuState, raw: *mut c_void) {
        self.0[s.0] = Some(raw);
    }

    /// Forgets `s` (freed by the caller).
    pub(crate) fn forget(&mut self, s: &FmuState) {
        self.0[s.0] = None;
    }

    /// Every live state, to free them all.
    pub(crate) fn live(&mut self) -> impl Iterator<Item = &mut *mut c_void> {
        self.0.iter_mut().filter_map(|s| s.as_mut())
    }
}

/// A folder this process made (an FMU unpacked), removed with everything in it when dropped.
pub(crate) struct Scratch(pub(crate) PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A fresh folder under the system's temporary folder.
pub(crate) fn scratch() -> Result<Scratch, String> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let base = std::env::temp_dir();
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    for _ in 0..100 {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let dir = base.join(format!("rustfmu-runner-{}-{nanos:x}-{n}", std::process::id()));
        match std::fs::create_dir(&dir) {
            Ok(()) => return Ok(Scratch(dir)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(format!("cannot make a folder in {}: {e}", base.display())),
        }
    }
    Err(format!("cannot make a fresh folder in {}", base.display()))
}

/// Methods forwarded, each to the method of the same name of the instance an enum holds
/// (`dispatch!(Enum { V2, V3 } fn name(&mut self, arg: T) -> R; ...)`), or of a field
/// (`dispatch!(Struct.field fn ...)`); optionally a `hook` called first with the address of the
/// receiver and the method's name (an isolated system's crumbs).
macro_rules! dispatch {
    ($ty:ident . $field:ident $( $(#[$doc:meta])* fn $name:ident(&mut self $(, $arg:ident: $argty:ty)*) -> $ret:ty; )*) => {
        impl $ty {
            $(
                $(#[$doc])*
                pub fn $name(&mut self $(, $arg: $argty)*) -> $ret {
                    self.$field.$name($($arg),*)
                }
            )*
        }
    };
    ($enum:ident $variants:tt hook $hook:path; $($methods:tt)*) => {
        $crate::common::dispatch!(@impl $enum $variants [$hook] $($methods)*);
    };
    ($enum:ident $variants:tt $($methods:tt)*) => {
        $crate::common::dispatch!(@impl $enum $variants [] $($methods)*);
    };
    (@impl $enum:ident $variants:tt $hook:tt $( $(#[$doc:meta])* fn $name:ident(&mut self $(, $arg:ident: $ty:ty)*) -> $ret:ty; )*) => {
        impl $enum {
            $(
                $(#[$doc])*
                pub fn $name(&mut self $(, $arg: $ty)*) -> $ret {
                    $crate::common::dispatch!(@hook $hook, self, $enum, $name);
                    $crate::common::dispatch!(@match self, $enum, $name, ($($arg),*), $variants)
                }
            )*
        }
    };
    (@hook [], $self:ident, $enum:ident, $name:ident) => {};
    (@hook [$hook:path], $self:ident, $enum:ident, $name:ident) => {
        $hook($self as *const $enum as usize, stringify!($name))
    };
    (@match $self:ident, $enum:ident, $name:ident, $args:tt, { $( $(#[$vattr:meta])* $variant:ident ),* $(,)? }) => {
        match $self {
            $( $(#[$vattr])* $enum::$variant(i) => i.$name $args, )*
        }
    };
}
pub(crate) use dispatch;

/// [`dispatch!`] with, after the methods the invocation lists, those every instance has for its
/// values (`values;`), and for its FMU states too (`values_and_states;`): listed once here for
/// [`InstanceCS`](crate::instance::InstanceCS) and the model-exchange instance.
macro_rules! dispatch_with {
    (values_and_states; $($head:tt)*) => {
        $crate::common::dispatch_with! {
            values;
            $($head)*
            /// A new FMU state of this instance.
            fn get_fmu_state(&mut self) -> Result<$crate::common::FmuState, $crate::common::Fmi2Error>;
            /// The existing state `s` overwritten with the current one.
            fn update_fmu_state(&mut self, s: &$crate::common::FmuState) -> Result<(), $crate::common::Fmi2Error>;
            fn set_fmu_state(&mut self, s: &$crate::common::FmuState) -> Result<(), $crate::common::Fmi2Error>;
            /// Frees `s` (then no state of this instance).
            fn free_fmu_state(&mut self, s: $crate::common::FmuState) -> Result<(), $crate::common::Fmi2Error>;
            fn serialize_fmu_state(&mut self, s: &$crate::common::FmuState) -> Result<Vec<u8>, $crate::common::Fmi2Error>;
            fn deserialize_fmu_state(&mut self, bytes: &[u8]) -> Result<$crate::common::FmuState, $crate::common::Fmi2Error>;
        }
    };
    (values; $($head:tt)*) => {
        $crate::common::dispatch! {
            $($head)*
            fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), $crate::common::Fmi2Error>;
            fn get_integer(&mut self, vrs: &[u32], out: &mut [i32]) -> Result<(), $crate::common::Fmi2Error>;
            fn get_boolean(&mut self, vrs: &[u32], out: &mut [i32]) -> Result<(), $crate::common::Fmi2Error>;
            fn get_string(&mut self, vrs: &[u32], out: &mut [std::ffi::CString]) -> Result<(), $crate::common::Fmi2Error>;
            fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), $crate::common::Fmi2Error>;
            fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), $crate::common::Fmi2Error>;
            fn set_boolean(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), $crate::common::Fmi2Error>;
            fn set_string(&mut self, vrs: &[u32], values: &[std::ffi::CString]) -> Result<(), $crate::common::Fmi2Error>;
            /// FMI 3.0: variables of any type but Clock, arrays whole ([`crate::values::Values`]).
            fn get_typed(&mut self, vrs: &[u32], out: &mut $crate::values::Values) -> Result<(), $crate::common::Fmi2Error>;
            fn set_typed(&mut self, vrs: &[u32], values: &$crate::values::Values) -> Result<(), $crate::common::Fmi2Error>;
            /// FMI 3.0: fmi3EnterConfigurationMode (`enter`) or fmi3ExitConfigurationMode.
            fn configuration_mode(&mut self, enter: bool) -> Result<(), $crate::common::Fmi2Error>;
            fn get_directional_derivative(&mut self, d: $crate::common::Directional<'_>) -> Result<(), $crate::common::Fmi2Error>;
            fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Result<(), $crate::common::Fmi2Error>;
            fn enter_initialization_mode(&mut self) -> Result<(), $crate::common::Fmi2Error>;
            fn terminate(&mut self) -> Result<(), $crate::common::Fmi2Error>;
        }
    };
}
pub(crate) use dispatch_with;

/// The calls both importers make alike, inside `impl Instance2` and `impl Instance3`: the
/// function from the version's `Api` (`instance: ...`: `self.api()`) or model-exchange `MeApi`
/// (`me: ...`: `self.me()?`), called on the instance (and the caller's vector), its status
/// through the version's `check`. Where the versions differ (fmi2CompletedIntegratorStep,
/// fmi2NewDiscreteStates / fmi3UpdateDiscreteStates, the initialization), each importer writes
/// its own.
macro_rules! calls {
    (instance: $($name:ident),* $(,)?) => {
        $(
            pub fn $name(&mut self) -> Result<(), Fmi2Error> {
                // SAFETY: a live instance.
                check(unsafe { (self.api().$name)(self.c) })
            }
        )*
    };
    (me: $($name:ident),* $(,)?) => {
        $(
            pub fn $name(&mut self) -> Result<(), Fmi2Error> {
                let f = self.me()?.$name;
                // SAFETY: a live model-exchange instance.
                check(unsafe { f(self.c) })
            }
        )*
    };
    (me vectors: $($name:ident),* $(,)?) => {
        $(
            pub fn $name(&mut self, x: &mut [f64]) -> Result<(), Fmi2Error> {
                let f = self.me()?.$name;
                // SAFETY: a live model-exchange instance; `x` is writable for x.len() values.
                check(unsafe { f(self.c, x.as_mut_ptr(), x.len()) })
            }
        )*
    };
    (me time, states and indicators) => {
        pub fn set_time(&mut self, t: f64) -> Result<(), Fmi2Error> {
            let f = self.me()?.set_time;
            // SAFETY: a live model-exchange instance.
            check(unsafe { f(self.c, t) })
        }

        pub fn set_continuous_states(&mut self, x: &[f64]) -> Result<(), Fmi2Error> {
            let f = self.me()?.set_continuous_states;
            // SAFETY: a live model-exchange instance; `x` holds x.len() states.
            check(unsafe { f(self.c, x.as_ptr(), x.len()) })
        }

        /// None asked for (no event indicators): no call.
        pub fn get_event_indicators(&mut self, z: &mut [f64]) -> Result<(), Fmi2Error> {
            if z.is_empty() {
                return Ok(());
            }
            let f = self.me()?.get_event_indicators;
            // SAFETY: a live model-exchange instance; `z` is writable for z.len() values.
            check(unsafe { f(self.c, z.as_mut_ptr(), z.len()) })
        }
    };
}
pub(crate) use calls;
