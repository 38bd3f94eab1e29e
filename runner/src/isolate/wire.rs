//! The wire protocol between the runner and a child process: the shared memory (a header of
//! atomics, a request and an answer area), the futexes, the call codes and the flat codec of
//! their arguments, the crumbs a system's child leaves before each call.

use crate::common::Fmi2Error;
use std::ffi::CString;
use std::fs::OpenOptions;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicPtr, AtomicU32, AtomicU64, Ordering::*};
use std::time::Duration;

// The shared memory: a header, then the request and the answer areas. The file is sparse: only
// the pages written are memory.
pub(super) const AREA: usize = 256 << 20;
pub(super) const REQ_OFF: usize = 4096;
pub(super) const RESP_OFF: usize = REQ_OFF + AREA;
pub(super) const SIZE: usize = RESP_OFF + AREA;
/// How long the parent spins on the shared memory for an answer before it sleeps on the
/// futex, and how long a child yields its core waiting for the next call before it sleeps.
/// PendulumMotors (four processes on two cores; `cargo run --release -p rustfmu-bench --bin
/// isolation-cost`): a child that spins takes the cores the others need (18 s per run with
/// 200 us of spinning), one that sleeps at once pays a futex wake per call (2.7 s); yielding
/// 50 us while the parent spins up to 1 ms: 0.43 s.
/// Waiting for the other side: spin (the parent) or yield the core (a child) for up to a
/// limit (50 µs at first, at most 200 µs), then sleep on the futex. The limit adapts (as an
/// adaptive mutex's): a wait that ended within it doubles it, one that had to sleep halves
/// it. On an idle machine a round trip is a few µs and a sleeping process takes ~30-100 µs to
/// wake; on a loaded one the other side is often not running and spinning takes the core it
/// needs. PendulumMotors, 4 FMUs in 4 processes on 2 cores, per 10 s run against in-process
/// (`cargo run --release -p rustfmu-bench --bin isolation-cost`): fixed limits of 1 ms
/// (parent) and 50 µs (children) 28x idle but 8000x while a build ran; futex only 60-130x
/// idle; these 40-71x idle and 48-70x beside two CPU-bound processes (one run of six 433x).
#[derive(Clone, Copy)]
pub(super) struct Patience {
    pub(super) limit: Duration,
    pub(super) min: Duration,
    pub(super) max: Duration,
}

impl Patience {
    pub(super) const fn new(start_us: u64, max_us: u64) -> Patience {
        Patience {
            limit: Duration::from_micros(start_us),
            min: Duration::from_micros(1),
            max: Duration::from_micros(max_us),
        }
    }
    pub(super) fn waited(&mut self, slept: bool) {
        self.limit = if slept {
            (self.limit / 2).max(self.min)
        } else {
            (self.limit * 2).min(self.max)
        };
    }
}

#[repr(C)]
pub(super) struct Header {
    /// The sequence number of the last batch of calls the parent published.
    pub(super) req: AtomicU32,
    _a: [u32; 15],
    /// The sequence number of the last batch the child answered.
    pub(super) done: AtomicU32,
    _b: [u32; 15],
    /// 1 while the child sleeps on `req`, the parent on `done`.
    pub(super) child_sleeps: AtomicU32,
    pub(super) parent_sleeps: AtomicU32,
    pub(super) req_len: AtomicU32,
    pub(super) resp_len: AtomicU32,
    /// The index of the call of the batch the child is in (what a crash is reported at).
    pub(super) current: AtomicU32,
    /// A whole system's child: the FMI calls it made (a hang: this stops moving), the
    /// address of the instance called last and its method (32 bytes of its name), and the
    /// time the master is at.
    pub(super) calls: AtomicU32,
    pub(super) crumb_instance: AtomicU64,
    pub(super) crumb_method: [AtomicU64; 4],
    pub(super) crumb_time: AtomicU64,
}

impl Header {
    /// A child with nothing to do: sleeps on `req` (up to 100 ms) while it is still the batch
    /// `done`; false when the parent `parent` is gone (the child then exits).
    pub(super) fn child_sleep(&self, done: u32, parent: u32) -> bool {
        self.child_sleeps.store(1, SeqCst);
        if self.req.load(SeqCst) == done {
            futex_wait(&self.req, done, Duration::from_millis(100));
        }
        self.child_sleeps.store(0, SeqCst);
        std::os::unix::process::parent_id() == parent
    }
}

/// Where the instances' names are (a system's child; `addr u64, v3 u8, len u32, name`).
pub(super) const NAMES_OFF: usize = 1024;

pub(super) struct Shared {
    pub(super) map: memmap2::MmapMut,
}

impl Shared {
    /// The child's side: the shared memory file the parent made, mapped (the file itself is
    /// closed again; the parent removes it once the child answered).
    pub(super) fn open(path: &Path) -> Result<Shared, String> {
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .map_err(|e| format!("cannot open {}: {e}", path.display()))?;
        Ok(Shared { map: map(&file)? })
    }

    pub(super) fn header(&self) -> &Header {
        // SAFETY: the mapping is SIZE bytes, page aligned; Header is atomics only.
        unsafe { &*(self.map.as_ptr() as *const Header) }
    }
    pub(super) fn req(&mut self) -> &mut [u8] {
        &mut self.map[REQ_OFF..REQ_OFF + AREA]
    }
    pub(super) fn resp(&mut self) -> &mut [u8] {
        &mut self.map[RESP_OFF..RESP_OFF + AREA]
    }
}

pub(super) fn futex_wait(word: &AtomicU32, expected: u32, timeout: Duration) {
    let ts = libc::timespec {
        tv_sec: timeout.as_secs() as libc::time_t,
        tv_nsec: timeout.subsec_nanos() as libc::c_long,
    };
    // SAFETY: a futex word of a shared mapping (not FUTEX_PRIVATE: two processes use it).
    unsafe {
        libc::syscall(
            libc::SYS_futex,
            word.as_ptr(),
            libc::FUTEX_WAIT,
            expected,
            &ts as *const libc::timespec,
        );
    }
}

pub(super) fn futex_wake(word: &AtomicU32) {
    // SAFETY: as futex_wait.
    unsafe {
        libc::syscall(libc::SYS_futex, word.as_ptr(), libc::FUTEX_WAKE, i32::MAX);
    }
}

// The calls.
pub(super) const SET_DEBUG_LOGGING: u8 = 0;
pub(super) const SETUP_EXPERIMENT: u8 = 1;
pub(super) const ENTER_INIT: u8 = 2;
pub(super) const EXIT_INIT: u8 = 3;
pub(super) const TERMINATE: u8 = 4;
pub(super) const RESET: u8 = 5;
pub(super) const DO_STEP: u8 = 6;
pub(super) const GET_REAL: u8 = 7;
pub(super) const GET_INTEGER: u8 = 8;
pub(super) const GET_BOOLEAN: u8 = 9;
pub(super) const GET_STRING: u8 = 10;
pub(super) const SET_REAL: u8 = 11;
pub(super) const SET_INTEGER: u8 = 12;
pub(super) const SET_BOOLEAN: u8 = 13;
pub(super) const SET_STRING: u8 = 14;
pub(super) const GET_STATE: u8 = 15;
pub(super) const UPDATE_STATE: u8 = 16;
pub(super) const SET_STATE: u8 = 17;
pub(super) const FREE_STATE: u8 = 18;
pub(super) const SERIALIZE: u8 = 19;
pub(super) const DESERIALIZE: u8 = 20;
pub(super) const OUTPUT_DERIVATIVES: u8 = 21;
pub(super) const INPUT_DERIVATIVES: u8 = 22;
pub(super) const DIRECTIONAL: u8 = 23;
/// FMI 3.0 values of any type and shape ([`crate::values::Values`]).
pub(super) const GET_TYPED: u8 = 24;
pub(super) const SET_TYPED: u8 = 25;
/// FMI 3.0 clocks and Event Mode: the master's calls of an instance's clocks
/// ([`crate::instance::InstanceCS`]: settle, next_tick, ...), each made in the child by its
/// importer, which makes the FMI calls (fmi3EnterEventMode, fmi3SetClock, fmi3GetClock,
/// fmi3UpdateDiscreteStates, fmi3GetIntervalDecimal, fmi3EnterStepMode) exactly as in process.
pub(super) const SETTLE: u8 = 26;
pub(super) const NEXT_TICK: u8 = 27;
pub(super) const TICK_NOW: u8 = 28;
pub(super) const EARLY_RETURN: u8 = 29;
pub(super) const CLOCK_ACTIVE: u8 = 30;
pub(super) const TRIGGER: u8 = 31;
pub(super) const POLL_OUTPUT_CLOCKS: u8 = 32;
pub(super) const CLOCK_SNAPSHOT: u8 = 33;
pub(super) const RESTORE_CLOCKS: u8 = 34;
/// fmi3EnterConfigurationMode (argument 1) or fmi3ExitConfigurationMode (0).
pub(super) const CONFIGURATION: u8 = 35;
/// Scheduled Execution: fmi3ActivateModelPartition of the clocks that tick at the time given,
/// with what their clockUpdate callbacks announce (answered: whether one was activated).
pub(super) const ACTIVATE: u8 = 36;
/// The first batch: instantiate (the answer: ok, or the error's message).
pub(super) const HELLO: u8 = 98;
pub(super) const QUIT: u8 = 99;

/// Writes a batch into a byte area.
pub(super) struct W<'a> {
    pub(super) buf: &'a mut [u8],
    pub(super) at: usize,
}

impl W<'_> {
    pub(super) fn bytes(&mut self, b: &[u8]) -> Result<(), Fmi2Error> {
        let end = self.at + b.len();
        if end > self.buf.len() {
            return Err(Fmi2Error::Importer(format!(
                "isolation: more than {} MiB in one call (the shared memory's size)",
                AREA >> 20
            )));
        }
        self.buf[self.at..end].copy_from_slice(b);
        self.at = end;
        Ok(())
    }
    pub(super) fn u8(&mut self, x: u8) -> Result<(), Fmi2Error> {
        self.bytes(&[x])
    }
    pub(super) fn u32(&mut self, x: u32) -> Result<(), Fmi2Error> {
        self.bytes(&x.to_ne_bytes())
    }
    pub(super) fn f64(&mut self, x: f64) -> Result<(), Fmi2Error> {
        self.bytes(&x.to_ne_bytes())
    }
    pub(super) fn u32s(&mut self, xs: &[u32]) -> Result<(), Fmi2Error> {
        self.u32(xs.len() as u32)?;
        xs.iter().try_for_each(|x| self.u32(*x))
    }
    pub(super) fn i32s(&mut self, xs: &[i32]) -> Result<(), Fmi2Error> {
        self.u32(xs.len() as u32)?;
        xs.iter().try_for_each(|x| self.u32(*x as u32))
    }
    pub(super) fn f64s(&mut self, xs: &[f64]) -> Result<(), Fmi2Error> {
        self.u32(xs.len() as u32)?;
        xs.iter().try_for_each(|x| self.f64(*x))
    }
    pub(super) fn blob(&mut self, b: &[u8]) -> Result<(), Fmi2Error> {
        self.u32(b.len() as u32)?;
        self.bytes(b)
    }
    pub(super) fn err(&mut self, e: &Fmi2Error) -> Result<(), Fmi2Error> {
        match e {
            Fmi2Error::Discard => self.u8(0),
            Fmi2Error::Error => self.u8(1),
            Fmi2Error::Fatal => self.u8(2),
            Fmi2Error::Pending => self.u8(3),
            Fmi2Error::Unknown(s) => {
                self.u8(4)?;
                self.u32(*s)
            }
            Fmi2Error::Terminate(t) => {
                self.u8(6)?;
                self.f64(*t)
            }
            other => {
                self.u8(5)?;
                self.blob(other.to_string().as_bytes())
            }
        }
    }
}

/// Reads a batch.
pub(super) struct R<'a> {
    pub(super) buf: &'a [u8],
    pub(super) at: usize,
}

impl<'a> R<'a> {
    pub(super) fn bytes(&mut self, n: usize) -> &'a [u8] {
        let b = &self.buf[self.at..self.at + n];
        self.at += n;
        b
    }
    pub(super) fn u8(&mut self) -> u8 {
        self.bytes(1)[0]
    }
    pub(super) fn u32(&mut self) -> u32 {
        u32::from_ne_bytes(self.bytes(4).try_into().unwrap())
    }
    pub(super) fn f64(&mut self) -> f64 {
        f64::from_ne_bytes(self.bytes(8).try_into().unwrap())
    }
    pub(super) fn u32s_into(&mut self, out: &mut Vec<u32>) {
        let n = self.u32() as usize;
        out.clear();
        out.extend((0..n).map(|_| self.u32()));
    }
    pub(super) fn i32s_into(&mut self, out: &mut Vec<i32>) {
        let n = self.u32() as usize;
        out.clear();
        out.extend((0..n).map(|_| self.u32() as i32));
    }
    pub(super) fn f64s_into(&mut self, out: &mut Vec<f64>) {
        let n = self.u32() as usize;
        out.clear();
        out.extend((0..n).map(|_| self.f64()));
    }
    pub(super) fn blob(&mut self) -> &'a [u8] {
        let n = self.u32() as usize;
        self.bytes(n)
    }
    pub(super) fn cstring(&mut self) -> CString {
        CString::new(self.blob()).unwrap_or_default()
    }
    pub(super) fn err(&mut self) -> Fmi2Error {
        match self.u8() {
            0 => Fmi2Error::Discard,
            1 => Fmi2Error::Error,
            2 => Fmi2Error::Fatal,
            3 => Fmi2Error::Pending,
            4 => Fmi2Error::Unknown(self.u32()),
            6 => Fmi2Error::Terminate(self.f64()),
            _ => Fmi2Error::Importer(String::from_utf8_lossy(self.blob()).into_owned()),
        }
    }
}

/// The FMI 2.0 name of a call, for messages.
pub(super) fn function_of(op: u8) -> &'static str {
    match op {
        SET_DEBUG_LOGGING => "fmi2SetDebugLogging",
        SETUP_EXPERIMENT => "fmi2SetupExperiment",
        ENTER_INIT => "fmi2EnterInitializationMode",
        EXIT_INIT => "fmi2ExitInitializationMode",
        TERMINATE => "fmi2Terminate",
        RESET => "fmi2Reset",
        DO_STEP => "fmi2DoStep",
        GET_REAL => "fmi2GetReal",
        GET_INTEGER => "fmi2GetInteger",
        GET_BOOLEAN => "fmi2GetBoolean",
        GET_STRING => "fmi2GetString",
        SET_REAL => "fmi2SetReal",
        SET_INTEGER => "fmi2SetInteger",
        SET_BOOLEAN => "fmi2SetBoolean",
        SET_STRING => "fmi2SetString",
        GET_STATE => "fmi2GetFMUstate",
        UPDATE_STATE => "fmi2GetFMUstate",
        SET_STATE => "fmi2SetFMUstate",
        FREE_STATE => "fmi2FreeFMUstate",
        SERIALIZE => "fmi2SerializeFMUstate",
        DESERIALIZE => "fmi2DeSerializeFMUstate",
        OUTPUT_DERIVATIVES => "fmi2GetRealOutputDerivatives",
        INPUT_DERIVATIVES => "fmi2SetRealInputDerivatives",
        DIRECTIONAL => "fmi2GetDirectionalDerivative",
        GET_TYPED => "fmi3Get{Type}",
        SET_TYPED => "fmi3Set{Type}",
        CONFIGURATION => "fmi3EnterConfigurationMode/fmi3ExitConfigurationMode",
        SETTLE => "fmi3UpdateDiscreteStates",
        NEXT_TICK | CLOCK_ACTIVE | CLOCK_SNAPSHOT | RESTORE_CLOCKS => "fmi3GetClock",
        TICK_NOW | TRIGGER => "fmi3SetClock",
        EARLY_RETURN => "fmi3DoStep",
        POLL_OUTPUT_CLOCKS => "fmi3GetClock",
        ACTIVATE => "fmi3ActivateModelPartition",
        HELLO => "fmi2Instantiate",
        _ => "fmi2FreeInstance",
    }
}

/// Starts the worker `worker` doing `verb` with its `options` (name, value), `--shm shm` and
/// `flag` where there is one, its stdin closed; if it cannot start, the shared file `shm` is
/// removed and the message says why.
pub(super) fn start_worker(
    worker: &Path,
    verb: &str,
    options: &[(&str, &std::ffi::OsStr)],
    shm: &Path,
    flag: Option<&str>,
) -> Result<std::process::Child, String> {
    let mut cmd = std::process::Command::new(worker);
    cmd.arg(verb);
    for (name, value) in options {
        cmd.arg(name).arg(value);
    }
    cmd.arg("--shm").arg(shm).stdin(std::process::Stdio::null());
    cmd.args(flag);
    // The libraries loaded before the FMUs here (--preload-lib), loaded there too.
    if let Some(libs) = crate::libpython::for_child() {
        cmd.env(crate::libpython::ENV, libs);
    }
    cmd.spawn().map_err(|e| {
        let _ = std::fs::remove_file(shm);
        format!("cannot start {}: {e}", worker.display())
    })
}

pub(super) fn shm_file() -> Result<(std::fs::File, PathBuf), String> {
    use std::sync::atomic::AtomicUsize;
    static N: AtomicUsize = AtomicUsize::new(0);
    let dir = Path::new("/dev/shm");
    let dir = if dir.is_dir() {
        dir.to_path_buf()
    } else {
        std::env::temp_dir()
    };
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    let path = dir.join(format!(
        "rustfmu-runner-{}-{}-{nanos}",
        std::process::id(),
        N.fetch_add(1, Relaxed)
    ));
    let file = OpenOptions::new()
        .read(true)
        .write(true)
        .create_new(true)
        .open(&path)
        .map_err(|e| format!("cannot create {}: {e}", path.display()))?;
    file.set_len(SIZE as u64)
        .map_err(|e| format!("cannot size {}: {e}", path.display()))?;
    Ok((file, path))
}

pub(super) fn map(file: &std::fs::File) -> Result<memmap2::MmapMut, String> {
    // SAFETY: a file of this runner's making, shared with its child only.
    unsafe { memmap2::MmapMut::map_mut(file) }.map_err(|e| format!("cannot map the shared memory: {e}"))
}

/// How a child process ended, in words.
pub(super) fn describe_exit(status: std::process::ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(code), _) => format!("exited with status {code}"),
        (None, Some(sig)) => {
            let name = match sig {
                libc::SIGSEGV => "SIGSEGV, a segmentation fault",
                libc::SIGABRT => "SIGABRT, an abort",
                libc::SIGBUS => "SIGBUS",
                libc::SIGFPE => "SIGFPE",
                libc::SIGILL => "SIGILL",
                libc::SIGKILL => "SIGKILL",
                libc::SIGTERM => "SIGTERM",
                _ => "a signal",
            };
            format!("died of signal {sig} ({name})")
        }
        _ => "ended".to_owned(),
    }
}

// A whole system in one child process.

/// The child's shared header, for the crumbs of [`crumb`] (null: not a system's child).
pub(super) static CRUMB: AtomicPtr<Header> = AtomicPtr::new(std::ptr::null_mut());

/// Before each call of an [`InstanceCS`](crate::instance::InstanceCS): which instance and method, in a system's child
/// (a relaxed store of a few words; nothing elsewhere).
#[inline]
pub fn crumb(instance: usize, method: &'static str) {
    let h = CRUMB.load(Relaxed);
    if h.is_null() {
        return;
    }
    // SAFETY: set once to the header of a mapping that lives as long as the process.
    let h = unsafe { &*h };
    h.crumb_instance.store(instance as u64, Relaxed);
    let mut words = [0u64; 4];
    for (i, b) in method.bytes().take(32).enumerate() {
        words[i / 8] |= u64::from(b) << (8 * (i % 8));
    }
    for (w, x) in h.crumb_method.iter().zip(words) {
        w.store(x, Relaxed);
    }
    h.calls.fetch_add(1, Release);
}

/// The communication point the master is at (a system's child).
#[inline]
pub fn crumb_time(t: f64) {
    let h = CRUMB.load(Relaxed);
    if !h.is_null() {
        // SAFETY: as in crumb.
        unsafe { &*h }.crumb_time.store(t.to_bits(), Relaxed);
    }
}

/// The FMI 2.0 function of an [`InstanceCS`] method.
pub(super) fn fmi_function(method: &str) -> &'static str {
    match method {
        "set_debug_logging" => "fmi2SetDebugLogging",
        "setup_experiment" => "fmi2SetupExperiment",
        "enter_initialization_mode" => "fmi2EnterInitializationMode",
        "exit_initialization_mode" => "fmi2ExitInitializationMode",
        "terminate" => "fmi2Terminate",
        "reset" => "fmi2Reset",
        "configuration_mode" => "fmi3EnterConfigurationMode/fmi3ExitConfigurationMode",
        "do_step" => "fmi2DoStep",
        "get_real" => "fmi2GetReal",
        "get_integer" => "fmi2GetInteger",
        "get_boolean" => "fmi2GetBoolean",
        "get_string" => "fmi2GetString",
        "set_real" => "fmi2SetReal",
        "set_integer" => "fmi2SetInteger",
        "set_boolean" => "fmi2SetBoolean",
        "set_string" => "fmi2SetString",
        "get_fmu_state" | "update_fmu_state" => "fmi2GetFMUstate",
        "set_fmu_state" => "fmi2SetFMUstate",
        "free_fmu_state" => "fmi2FreeFMUstate",
        "serialize_fmu_state" => "fmi2SerializeFMUstate",
        "deserialize_fmu_state" => "fmi2DeSerializeFMUstate",
        "get_output_derivatives" => "fmi2GetRealOutputDerivatives",
        "set_input_derivatives" => "fmi2SetRealInputDerivatives",
        "get_directional_derivative" => "fmi2GetDirectionalDerivative",
        _ => "an FMI function",
    }
}
