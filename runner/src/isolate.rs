//! Isolation: each component in a child process of its own (Linux).
//!
//! An FMU that crashes (a segmentation fault, `abort()`), exits or hangs takes its own process
//! down, not the runner or the Dask worker it runs in: the call fails with an error naming the
//! component, the FMI function and the time (fmi2Fatal: the next run starts every component's
//! process anew).
//!
//! The child is `rustfmu-runner serve-component` (the runner's own binary): it loads the FMU the
//! parent unpacked, instantiates it (co-simulation, FMI 2.0 or 3.0, or model exchange integrated
//! by [`crate::me`]) and answers the calls of an [`InstanceCS`] it gets through a shared memory
//! file in /dev/shm (removed as soon as the child has it open). The FMUs' log messages travel back
//! with each answer and reach the parent's `log` logger as an in-process FMU's would.
//!
//! What keeps a step cheap (`bench/src/bin/isolation-cost.rs` measures it):
//! - calls that answer nothing but a status (the setters, fmi2DoStep, input derivatives) are not
//!   waited for: the setters travel with the next call that answers values, fmi2DoStep is sent at
//!   once so the components step in parallel in their processes while the master goes on. A
//!   failure of such a call comes back with the next call, reported as the call that failed (its
//!   function and time: [`Fmi2Error::Deferred`]); the calls sent after it are not made.
//! - both sides spin briefly on the shared memory before they sleep on a futex.
//!
//! The wire format is a few flat arrays of u32/f64 per call, written in place; a hand-written
//! codec (no serde): nothing is allocated per call on either side but the answer's values.

use crate::Error;
use std::path::{Path, PathBuf};
use std::time::Duration;

#[cfg(target_os = "linux")]
pub use linux::{Isolated, SystemInfo, SystemProcess, crumb, crumb_time, serve, serve_system};

/// Where an isolated system's child is (nothing outside one; Linux only).
#[cfg(not(target_os = "linux"))]
#[inline]
pub fn crumb(_instance: usize, _method: &'static str) {}

/// The time of the calls that follow (an isolated system's child).
#[cfg(not(target_os = "linux"))]
#[inline]
pub fn crumb_time(_t: f64) {}

/// Isolation needs Linux (shared memory and futexes): elsewhere a system cannot be started.
#[cfg(not(target_os = "linux"))]
pub struct SystemProcess(SystemInfo);

/// What a system's child tells about the system it loaded.
#[cfg(not(target_os = "linux"))]
#[derive(Debug, Clone)]
pub struct SystemInfo {
    pub name: String,
    pub evaluation_order: Vec<String>,
    pub components: Vec<(String, String)>,
    pub outputs: Vec<String>,
    pub parameters: Vec<String>,
}

#[cfg(not(target_os = "linux"))]
impl SystemProcess {
    pub fn spawn(_iso: Isolation, ssp: &Path, _jacobi: bool) -> Result<SystemProcess, Error> {
        Err(Error::unsupported(
            None,
            None,
            format!("{}: isolation (child processes) runs on Linux only", ssp.display()),
        ))
    }
    pub fn info(&self) -> &SystemInfo {
        &self.0
    }
    pub fn run(&mut self, _opts: &crate::RunOptions) -> Result<crate::RunResult, crate::sim::Failure> {
        unreachable!("never spawned")
    }
}

/// How much of the system a child process holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Granularity {
    /// Each component in a process of its own: one FMU cannot touch another's memory.
    Component,
    /// The whole system (every FMU and the master) in one process per run of it: the runner
    /// lives on, a crash is reported at the component, function and time it happened in.
    System,
}

/// How the components of a system are isolated.
#[derive(Debug, Clone)]
pub struct Isolation {
    /// The `rustfmu-runner` binary that serves a component ([`find_worker`]).
    pub worker: PathBuf,
    /// The longest a single call may take before its process is killed (None: no limit).
    pub timeout: Option<Duration>,
}

/// The runner binary a child process runs: `explicit`, else $RUSTFMU_RUNNER, else
/// `rustfmu-runner` beside this program, in `also` (a Python environment's scripts folder), or
/// on PATH.
pub fn find_worker(explicit: Option<&Path>, also: &[PathBuf]) -> Result<PathBuf, Error> {
    let name = format!("rustfmu-runner{}", std::env::consts::EXE_SUFFIX);
    if let Some(p) = explicit {
        return if p.is_file() {
            Ok(p.to_path_buf())
        } else {
            Err(Error::usage(format!(
                "isolation: the worker {} is not a file (the rustfmu-runner binary)",
                p.display()
            )))
        };
    }
    let mut tried = Vec::new();
    let mut candidates: Vec<PathBuf> = Vec::new();
    if let Some(p) = std::env::var_os("RUSTFMU_RUNNER") {
        candidates.push(PathBuf::from(p));
    }
    if let Ok(exe) = std::env::current_exe()
        && let Some(dir) = exe.parent()
    {
        candidates.push(dir.join(&name));
    }
    candidates.extend(also.iter().map(|d| d.join(&name)));
    if let Some(path) = std::env::var_os("PATH") {
        candidates.extend(std::env::split_paths(&path).map(|d| d.join(&name)));
    }
    for c in candidates {
        if c.is_file() {
            return Ok(c);
        }
        tried.push(c.display().to_string());
    }
    Err(Error::usage(format!(
        "isolation needs the rustfmu-runner binary (each component runs in a child process of it): \
         set RUSTFMU_RUNNER to it, or put it on PATH (`cargo install --path runner`); looked at {}",
        tried.join(", ")
    )))
}

#[cfg(target_os = "linux")]
mod linux {
    use super::Isolation;
    use crate::fmi2::{Deferred, Fmi2Error, FmuState, InstanceCS};
    use crate::{Error, ErrorKind};
    use std::ffi::CString;
    use std::fs::OpenOptions;
    use std::path::{Path, PathBuf};
    use std::process::{Child, Command, Stdio};
    use std::sync::atomic::{AtomicPtr, AtomicU32, AtomicU64, Ordering::*};
    use std::time::{Duration, Instant};

    // The shared memory: a header, then the request and the answer areas. The file is sparse: only
    // the pages written are memory.
    const AREA: usize = 256 << 20;
    const REQ_OFF: usize = 4096;
    const RESP_OFF: usize = REQ_OFF + AREA;
    const SIZE: usize = RESP_OFF + AREA;
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
    struct Patience {
        limit: Duration,
        min: Duration,
        max: Duration,
    }

    impl Patience {
        const fn new(start_us: u64, max_us: u64) -> Patience {
            Patience {
                limit: Duration::from_micros(start_us),
                min: Duration::from_micros(1),
                max: Duration::from_micros(max_us),
            }
        }
        fn waited(&mut self, slept: bool) {
            self.limit = if slept {
                (self.limit / 2).max(self.min)
            } else {
                (self.limit * 2).min(self.max)
            };
        }
    }

    #[repr(C)]
    struct Header {
        /// The sequence number of the last batch of calls the parent published.
        req: AtomicU32,
        _a: [u32; 15],
        /// The sequence number of the last batch the child answered.
        done: AtomicU32,
        _b: [u32; 15],
        /// 1 while the child sleeps on `req`, the parent on `done`.
        child_sleeps: AtomicU32,
        parent_sleeps: AtomicU32,
        req_len: AtomicU32,
        resp_len: AtomicU32,
        /// The index of the call of the batch the child is in (what a crash is reported at).
        current: AtomicU32,
        /// A whole system's child: the FMI calls it made (a hang: this stops moving), the
        /// address of the instance called last and its method (32 bytes of its name), and the
        /// time the master is at.
        calls: AtomicU32,
        crumb_instance: AtomicU64,
        crumb_method: [AtomicU64; 4],
        crumb_time: AtomicU64,
    }

    /// Where the instances' names are (a system's child; `addr u64, v3 u8, len u32, name`).
    const NAMES_OFF: usize = 1024;

    struct Shared {
        map: memmap2::MmapMut,
    }

    impl Shared {
        fn header(&self) -> &Header {
            // SAFETY: the mapping is SIZE bytes, page aligned; Header is atomics only.
            unsafe { &*(self.map.as_ptr() as *const Header) }
        }
        fn req(&mut self) -> &mut [u8] {
            &mut self.map[REQ_OFF..REQ_OFF + AREA]
        }
        fn resp(&mut self) -> &mut [u8] {
            &mut self.map[RESP_OFF..RESP_OFF + AREA]
        }
    }

    fn futex_wait(word: &AtomicU32, expected: u32, timeout: Duration) {
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

    fn futex_wake(word: &AtomicU32) {
        // SAFETY: as futex_wait.
        unsafe {
            libc::syscall(libc::SYS_futex, word.as_ptr(), libc::FUTEX_WAKE, i32::MAX);
        }
    }

    // The calls.
    const SET_DEBUG_LOGGING: u8 = 0;
    const SETUP_EXPERIMENT: u8 = 1;
    const ENTER_INIT: u8 = 2;
    const EXIT_INIT: u8 = 3;
    const TERMINATE: u8 = 4;
    const RESET: u8 = 5;
    const DO_STEP: u8 = 6;
    const GET_REAL: u8 = 7;
    const GET_INTEGER: u8 = 8;
    const GET_BOOLEAN: u8 = 9;
    const GET_STRING: u8 = 10;
    const SET_REAL: u8 = 11;
    const SET_INTEGER: u8 = 12;
    const SET_BOOLEAN: u8 = 13;
    const SET_STRING: u8 = 14;
    const GET_STATE: u8 = 15;
    const UPDATE_STATE: u8 = 16;
    const SET_STATE: u8 = 17;
    const FREE_STATE: u8 = 18;
    const SERIALIZE: u8 = 19;
    const DESERIALIZE: u8 = 20;
    const OUTPUT_DERIVATIVES: u8 = 21;
    const INPUT_DERIVATIVES: u8 = 22;
    const DIRECTIONAL: u8 = 23;
    /// The first batch: instantiate (the answer: ok, or the error's message).
    const HELLO: u8 = 98;
    const QUIT: u8 = 99;

    /// Writes a batch into a byte area.
    struct W<'a> {
        buf: &'a mut [u8],
        at: usize,
    }

    impl W<'_> {
        fn bytes(&mut self, b: &[u8]) -> Result<(), Fmi2Error> {
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
        fn u8(&mut self, x: u8) -> Result<(), Fmi2Error> {
            self.bytes(&[x])
        }
        fn u32(&mut self, x: u32) -> Result<(), Fmi2Error> {
            self.bytes(&x.to_ne_bytes())
        }
        fn f64(&mut self, x: f64) -> Result<(), Fmi2Error> {
            self.bytes(&x.to_ne_bytes())
        }
        fn u32s(&mut self, xs: &[u32]) -> Result<(), Fmi2Error> {
            self.u32(xs.len() as u32)?;
            xs.iter().try_for_each(|x| self.u32(*x))
        }
        fn i32s(&mut self, xs: &[i32]) -> Result<(), Fmi2Error> {
            self.u32(xs.len() as u32)?;
            xs.iter().try_for_each(|x| self.u32(*x as u32))
        }
        fn f64s(&mut self, xs: &[f64]) -> Result<(), Fmi2Error> {
            self.u32(xs.len() as u32)?;
            xs.iter().try_for_each(|x| self.f64(*x))
        }
        fn blob(&mut self, b: &[u8]) -> Result<(), Fmi2Error> {
            self.u32(b.len() as u32)?;
            self.bytes(b)
        }
        fn err(&mut self, e: &Fmi2Error) -> Result<(), Fmi2Error> {
            match e {
                Fmi2Error::Discard => self.u8(0),
                Fmi2Error::Error => self.u8(1),
                Fmi2Error::Fatal => self.u8(2),
                Fmi2Error::Pending => self.u8(3),
                Fmi2Error::Unknown(s) => {
                    self.u8(4)?;
                    self.u32(*s)
                }
                other => {
                    self.u8(5)?;
                    self.blob(other.to_string().as_bytes())
                }
            }
        }
    }

    /// Reads a batch.
    struct R<'a> {
        buf: &'a [u8],
        at: usize,
    }

    impl<'a> R<'a> {
        fn bytes(&mut self, n: usize) -> &'a [u8] {
            let b = &self.buf[self.at..self.at + n];
            self.at += n;
            b
        }
        fn u8(&mut self) -> u8 {
            self.bytes(1)[0]
        }
        fn u32(&mut self) -> u32 {
            u32::from_ne_bytes(self.bytes(4).try_into().unwrap())
        }
        fn f64(&mut self) -> f64 {
            f64::from_ne_bytes(self.bytes(8).try_into().unwrap())
        }
        fn u32s_into(&mut self, out: &mut Vec<u32>) {
            let n = self.u32() as usize;
            out.clear();
            out.extend((0..n).map(|_| self.u32()));
        }
        fn i32s_into(&mut self, out: &mut Vec<i32>) {
            let n = self.u32() as usize;
            out.clear();
            out.extend((0..n).map(|_| self.u32() as i32));
        }
        fn f64s_into(&mut self, out: &mut Vec<f64>) {
            let n = self.u32() as usize;
            out.clear();
            out.extend((0..n).map(|_| self.f64()));
        }
        fn blob(&mut self) -> &'a [u8] {
            let n = self.u32() as usize;
            self.bytes(n)
        }
        fn cstring(&mut self) -> CString {
            CString::new(self.blob()).unwrap_or_default()
        }
        fn err(&mut self) -> Fmi2Error {
            match self.u8() {
                0 => Fmi2Error::Discard,
                1 => Fmi2Error::Error,
                2 => Fmi2Error::Fatal,
                3 => Fmi2Error::Pending,
                4 => Fmi2Error::Unknown(self.u32()),
                _ => Fmi2Error::Importer(String::from_utf8_lossy(self.blob()).into_owned()),
            }
        }
    }

    /// The FMI 2.0 name of a call, for messages.
    fn function_of(op: u8) -> &'static str {
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
            HELLO => "fmi2Instantiate",
            _ => "fmi2FreeInstance",
        }
    }

    /// A component's instance in a child process.
    pub struct Isolated {
        component: String,
        shm: Shared,
        child: Child,
        timeout: Option<Duration>,
        /// The calls written to the request area and not yet published: (op, time).
        pending: Vec<(u8, Option<f64>)>,
        /// Bytes of `pending` in the request area (after the batch's call count).
        pending_len: usize,
        /// A published batch not yet waited for (its calls), and its sequence number.
        outstanding: Vec<(u8, Option<f64>)>,
        seq: u32,
        /// The time of the last step's end (a set's time in messages).
        time: Option<f64>,
        /// The process is gone: every call fails with this.
        dead: Option<String>,
        /// How long to spin for an answer before sleeping.
        patience: Patience,
        /// Read-ahead of Real values: what the last fmi2GetReal answered (value reference,
        /// value), valid until any call but a read; the value references read since the last
        /// step (`reads`) and in the step before (`ahead`), which the first read of a step asks
        /// for too. A system reads a component's connected outputs and then its recorded ones:
        /// one round trip instead of two where nothing is set or stepped between (the values an
        /// FMU gives depend on its inputs, parameters, states and time, none of which a read
        /// changes).
        cache: Vec<(u32, f64)>,
        cache_valid: bool,
        reads: Vec<u32>,
        ahead: Vec<u32>,
        ask: Vec<u32>,
    }

    impl Drop for Isolated {
        fn drop(&mut self) {
            if self.dead.is_none() && self.flush_wait().is_ok() {
                // fmi2FreeInstance in the child, then its exit.
                if self.push(QUIT, None, |_| Ok(())).is_ok() && self.publish().is_ok() {
                    let until = Instant::now() + Duration::from_secs(5);
                    while Instant::now() < until {
                        if let Ok(Some(_)) = self.child.try_wait() {
                            return;
                        }
                        std::thread::sleep(Duration::from_micros(200));
                    }
                }
            }
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }

    fn shm_file() -> Result<(std::fs::File, PathBuf), String> {
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

    fn map(file: &std::fs::File) -> Result<memmap2::MmapMut, String> {
        // SAFETY: a file of this runner's making, shared with its child only.
        unsafe { memmap2::MmapMut::map_mut(file) }.map_err(|e| format!("cannot map the shared memory: {e}"))
    }

    impl Isolated {
        /// Starts the child process of `component` (its FMU unpacked in `dir`) and instantiates it
        /// there (`me`: model exchange, integrated by the runner in the child).
        pub fn spawn(iso: &Isolation, component: &str, label: &str, dir: &Path, me: bool) -> Result<Isolated, Error> {
            let fail = |m: String| Error {
                component: Some(component.to_owned()),
                function: Some("fmi2Instantiate".into()),
                ..Error::new(
                    ErrorKind::Fmi,
                    format!("component '{component}' ({label}), isolated: {m}"),
                )
            };
            let (file, path) = shm_file().map_err(&fail)?;
            let map = map(&file).map_err(&fail)?;
            let mut cmd = Command::new(&iso.worker);
            cmd.arg("serve-component")
                .arg("--dir")
                .arg(dir)
                .arg("--name")
                .arg(component)
                .arg("--label")
                .arg(label)
                .arg("--shm")
                .arg(&path)
                .stdin(Stdio::null());
            if me {
                cmd.arg("--model-exchange");
            }
            let child = cmd.spawn();
            let child = match child {
                Ok(c) => c,
                Err(e) => {
                    let _ = std::fs::remove_file(&path);
                    return Err(fail(format!("cannot start {}: {e}", iso.worker.display())));
                }
            };
            let mut iso_inst = Isolated {
                component: component.to_owned(),
                shm: Shared { map },
                child,
                timeout: iso.timeout.map(|t| t.max(Duration::from_secs(10))),
                pending: Vec::new(),
                pending_len: 0,
                outstanding: Vec::new(),
                seq: 0,
                time: None,
                dead: None,
                patience: Patience::new(50, 200),
                cache: Vec::new(),
                cache_valid: false,
                reads: Vec::new(),
                ahead: Vec::new(),
                ask: Vec::new(),
            };
            // The child opens the file before it answers: then it can go.
            let r = iso_inst.call(HELLO, None, |_| Ok(()), |_| Ok(()));
            let _ = std::fs::remove_file(&path);
            iso_inst.timeout = iso.timeout;
            r.map_err(|e| {
                let e = match e {
                    Fmi2Error::Deferred(d) => d.error,
                    e => e,
                };
                fail(e.to_string())
            })?;
            Ok(iso_inst)
        }

        /// Appends a call to the batch being written.
        fn push(
            &mut self,
            op: u8,
            time: Option<f64>,
            args: impl FnOnce(&mut W) -> Result<(), Fmi2Error>,
        ) -> Result<(), Fmi2Error> {
            if !matches!(
                op,
                GET_REAL | GET_INTEGER | GET_BOOLEAN | GET_STRING | OUTPUT_DERIVATIVES | DIRECTIONAL | SERIALIZE
            ) {
                self.cache_valid = false;
            }
            let start = 4 + self.pending_len;
            let mut w = W {
                buf: self.shm.req(),
                at: start,
            };
            w.u8(op)?;
            args(&mut w)?;
            self.pending_len = w.at - 4;
            self.pending.push((op, time));
            Ok(())
        }

        /// Publishes the batch written (the child starts on it).
        fn publish(&mut self) -> Result<(), Fmi2Error> {
            let n = self.pending.len() as u32;
            self.shm.req()[..4].copy_from_slice(&n.to_ne_bytes());
            let h = self.shm.header();
            h.req_len.store((4 + self.pending_len) as u32, Relaxed);
            self.seq = self.seq.wrapping_add(1);
            h.req.store(self.seq, SeqCst);
            if h.child_sleeps.load(SeqCst) == 1 {
                futex_wake(&h.req);
            }
            self.outstanding = std::mem::take(&mut self.pending);
            self.pending_len = 0;
            Ok(())
        }

        /// Waits for the published batch; Err: the process died or hung.
        fn wait(&mut self) -> Result<(), Fmi2Error> {
            let begun = Instant::now();
            let mut checked = begun;
            let mut slept = false;
            loop {
                let h = self.shm.header();
                if h.done.load(Acquire) == self.seq {
                    self.patience.waited(slept);
                    return Ok(());
                }
                let waited = begun.elapsed();
                if waited < self.patience.limit {
                    std::hint::spin_loop();
                    continue;
                }
                slept = true;
                h.parent_sleeps.store(1, SeqCst);
                let done = h.done.load(SeqCst);
                if done != self.seq {
                    futex_wait(&h.done, done, Duration::from_millis(2));
                }
                h.parent_sleeps.store(0, SeqCst);
                if checked.elapsed() >= Duration::from_millis(2) || waited > Duration::from_millis(20) {
                    checked = Instant::now();
                    if self.shm.header().done.load(Acquire) == self.seq {
                        return Ok(());
                    }
                    if let Ok(Some(status)) = self.child.try_wait() {
                        return Err(self.died(describe_exit(status)));
                    }
                    if let Some(limit) = self.timeout
                        && waited > limit
                    {
                        let _ = self.child.kill();
                        let _ = self.child.wait();
                        return Err(self.died(format!(
                            "it did not return within {} s: its process was killed",
                            limit.as_secs_f64()
                        )));
                    }
                }
            }
        }

        /// The process is gone, in the call the child was in.
        fn died(&mut self, how: String) -> Fmi2Error {
            let i = self.shm.header().current.load(Acquire) as usize;
            let (op, time) = self.outstanding.get(i).copied().unwrap_or((QUIT, None));
            let message = format!(
                "the process of component '{}' (pid {}) {how}",
                self.component,
                self.child.id()
            );
            self.dead = Some(message.clone());
            self.outstanding.clear();
            self.pending.clear();
            self.pending_len = 0;
            Fmi2Error::Deferred(Box::new(Deferred {
                function: function_of(op),
                time,
                error: Fmi2Error::Died(message),
            }))
        }

        /// Waits for the outstanding batch (if any) and reads its answer's failure and messages;
        /// `last` reads the values of its last call.
        fn collect(&mut self, last: impl FnOnce(&mut R) -> Result<(), Fmi2Error>) -> Result<(), Fmi2Error> {
            if self.outstanding.is_empty() {
                return Ok(());
            }
            self.wait()?;
            let calls = std::mem::take(&mut self.outstanding);
            let len = self.shm.header().resp_len.load(Acquire) as usize;
            let buf = &self.shm.resp()[..len];
            let mut r = R { buf, at: 0 };
            // The FMUs' messages, to this process's logger as an in-process FMU's.
            for _ in 0..r.u32() {
                let level = match r.u8() {
                    1 => log::Level::Warn,
                    2 => log::Level::Trace,
                    3 => log::Level::Error,
                    _ => log::Level::Info,
                };
                let target = String::from_utf8_lossy(r.blob()).into_owned();
                let text = String::from_utf8_lossy(r.blob()).into_owned();
                log::logger().log(
                    &log::Record::builder()
                        .args(format_args!("{text}"))
                        .level(level)
                        .module_path(Some("logger"))
                        .target(&target)
                        .build(),
                );
            }
            let failed = r.u32();
            if failed != u32::MAX {
                let error = r.err();
                let i = failed as usize;
                if i + 1 == calls.len()
                    && !matches!(
                        calls[i].0,
                        DO_STEP | SET_REAL | SET_INTEGER | SET_BOOLEAN | SET_STRING | INPUT_DERIVATIVES
                    )
                {
                    return Err(error);
                }
                let (op, time) = calls.get(i).copied().unwrap_or((QUIT, None));
                return Err(Fmi2Error::Deferred(Box::new(Deferred {
                    function: function_of(op),
                    time,
                    error,
                })));
            }
            last(&mut r)
        }

        /// Waits for what was sent before (its failure is this call's), then sends nothing.
        fn flush_wait(&mut self) -> Result<(), Fmi2Error> {
            if let Some(m) = &self.dead {
                return Err(Fmi2Error::Died(m.clone()));
            }
            self.collect(|_| Ok(()))
        }

        /// Sends what is written and waits for it: a failure of a call before now.
        pub fn sync(&mut self) -> Result<(), Fmi2Error> {
            self.flush_wait()?;
            if !self.pending.is_empty() {
                self.publish()?;
                self.collect(|_| Ok(()))?;
            }
            Ok(())
        }

        /// A call that answers only a status, sent with the next call that answers (or at once).
        fn post(
            &mut self,
            op: u8,
            time: Option<f64>,
            now: bool,
            args: impl FnOnce(&mut W) -> Result<(), Fmi2Error>,
        ) -> Result<(), Fmi2Error> {
            self.flush_wait()?;
            self.push(op, time, args)?;
            if now {
                self.publish()?;
            }
            Ok(())
        }

        /// A call waited for: sent with the calls before it; `answer` reads its values.
        fn call(
            &mut self,
            op: u8,
            time: Option<f64>,
            args: impl FnOnce(&mut W) -> Result<(), Fmi2Error>,
            answer: impl FnOnce(&mut R) -> Result<(), Fmi2Error>,
        ) -> Result<(), Fmi2Error> {
            self.flush_wait()?;
            self.push(op, time, args)?;
            self.publish()?;
            self.collect(answer)
        }

        fn lengths(a: usize, b: usize) -> Result<(), Fmi2Error> {
            if a == b {
                Ok(())
            } else {
                Err(Fmi2Error::Importer(format!("{a} value references for {b} values")))
            }
        }

        pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Result<(), Fmi2Error> {
            self.call(
                SET_DEBUG_LOGGING,
                None,
                |w| {
                    w.u8(on as u8)?;
                    w.u32(categories.len() as u32)?;
                    categories.iter().try_for_each(|c| w.blob(c.as_bytes()))
                },
                |_| Ok(()),
            )
        }

        pub fn setup_experiment(
            &mut self,
            tolerance: Option<f64>,
            start: f64,
            stop: Option<f64>,
        ) -> Result<(), Fmi2Error> {
            self.time = Some(start);
            self.call(
                SETUP_EXPERIMENT,
                Some(start),
                |w| {
                    w.f64(tolerance.unwrap_or(f64::NAN))?;
                    w.f64(start)?;
                    w.f64(stop.unwrap_or(f64::NAN))
                },
                |_| Ok(()),
            )
        }

        pub fn enter_initialization_mode(&mut self) -> Result<(), Fmi2Error> {
            self.call(ENTER_INIT, self.time, |_| Ok(()), |_| Ok(()))
        }

        pub fn exit_initialization_mode(&mut self) -> Result<(), Fmi2Error> {
            self.call(EXIT_INIT, self.time, |_| Ok(()), |_| Ok(()))
        }

        pub fn terminate(&mut self) -> Result<(), Fmi2Error> {
            self.call(TERMINATE, self.time, |_| Ok(()), |_| Ok(()))
        }

        pub fn reset(&mut self) -> Result<(), Fmi2Error> {
            self.time = None;
            self.call(RESET, None, |_| Ok(()), |_| Ok(()))
        }

        pub fn do_step(&mut self, t: f64, h: f64, no_set_prior: bool) -> Result<(), Fmi2Error> {
            std::mem::swap(&mut self.ahead, &mut self.reads);
            self.reads.clear();
            self.post(DO_STEP, Some(t), true, |w| {
                w.f64(t)?;
                w.f64(h)?;
                w.u8(no_set_prior as u8)
            })?;
            self.time = Some(t + h);
            Ok(())
        }

        pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), Fmi2Error> {
            Self::lengths(vrs.len(), out.len())?;
            if self.dead.is_none() && self.outstanding.is_empty() && self.pending.is_empty() && self.cache_valid {
                let cached = |vr: &u32| self.cache.iter().find(|(v, _)| v == vr).map(|(_, x)| *x);
                if vrs.iter().all(|vr| cached(vr).is_some()) {
                    for (x, vr) in out.iter_mut().zip(vrs) {
                        *x = cached(vr).unwrap_or(f64::NAN);
                    }
                    return Ok(());
                }
            }
            for vr in vrs {
                if !self.reads.contains(vr) {
                    self.reads.push(*vr);
                }
            }
            // This read and what the step before read after it.
            let mut ask = std::mem::take(&mut self.ask);
            ask.clear();
            ask.extend_from_slice(vrs);
            ask.extend(self.ahead.iter().filter(|v| !vrs.contains(v)));
            let extra = ask.len() > vrs.len();
            let mut cache = std::mem::take(&mut self.cache);
            cache.clear();
            let r = self.call(
                GET_REAL,
                self.time,
                |w| w.u32s(&ask),
                |r| {
                    for vr in &ask {
                        cache.push((*vr, r.f64()));
                    }
                    Ok(())
                },
            );
            let r = match r {
                // A value reference of the read-ahead the FMU refuses now: the read alone.
                Err(Fmi2Error::Error) if extra => {
                    cache.clear();
                    self.call(
                        GET_REAL,
                        self.time,
                        |w| w.u32s(vrs),
                        |r| {
                            for vr in vrs {
                                cache.push((*vr, r.f64()));
                            }
                            Ok(())
                        },
                    )
                }
                r => r,
            };
            self.ask = ask;
            if r.is_ok() {
                for (x, (_, v)) in out.iter_mut().zip(&cache) {
                    *x = *v;
                }
            }
            self.cache_valid = r.is_ok();
            self.cache = cache;
            r
        }

        /// fmi2GetInteger or fmi2GetBoolean (`op`): 32-bit values.
        fn get_i32s(&mut self, op: u8, vrs: &[u32], out: &mut [i32]) -> Result<(), Fmi2Error> {
            Self::lengths(vrs.len(), out.len())?;
            self.call(
                op,
                self.time,
                |w| w.u32s(vrs),
                |r| {
                    out.iter_mut().for_each(|x| *x = r.u32() as i32);
                    Ok(())
                },
            )
        }

        pub fn get_integer(&mut self, vrs: &[u32], out: &mut [i32]) -> Result<(), Fmi2Error> {
            self.get_i32s(GET_INTEGER, vrs, out)
        }

        pub fn get_boolean(&mut self, vrs: &[u32], out: &mut [i32]) -> Result<(), Fmi2Error> {
            self.get_i32s(GET_BOOLEAN, vrs, out)
        }

        pub fn get_string(&mut self, vrs: &[u32], out: &mut [CString]) -> Result<(), Fmi2Error> {
            Self::lengths(vrs.len(), out.len())?;
            self.call(
                GET_STRING,
                self.time,
                |w| w.u32s(vrs),
                |r| {
                    out.iter_mut().for_each(|x| *x = r.cstring());
                    Ok(())
                },
            )
        }

        pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), Fmi2Error> {
            Self::lengths(vrs.len(), values.len())?;
            self.post(SET_REAL, self.time, false, |w| {
                w.u32s(vrs)?;
                w.f64s(values)
            })
        }

        pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), Fmi2Error> {
            Self::lengths(vrs.len(), values.len())?;
            self.post(SET_INTEGER, self.time, false, |w| {
                w.u32s(vrs)?;
                w.i32s(values)
            })
        }

        pub fn set_boolean(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), Fmi2Error> {
            Self::lengths(vrs.len(), values.len())?;
            self.post(SET_BOOLEAN, self.time, false, |w| {
                w.u32s(vrs)?;
                w.i32s(values)
            })
        }

        pub fn set_string(&mut self, vrs: &[u32], values: &[CString]) -> Result<(), Fmi2Error> {
            Self::lengths(vrs.len(), values.len())?;
            self.post(SET_STRING, self.time, false, |w| {
                w.u32s(vrs)?;
                w.u32(values.len() as u32)?;
                values.iter().try_for_each(|s| w.blob(s.as_bytes()))
            })
        }

        fn state_call(&mut self, op: u8, s: Option<&FmuState>) -> Result<FmuState, Fmi2Error> {
            let mut got = 0;
            let idx = s.map_or(u32::MAX, |s| s.0 as u32);
            self.call(
                op,
                self.time,
                |w| w.u32(idx),
                |r| {
                    got = r.u32() as usize;
                    Ok(())
                },
            )?;
            Ok(FmuState(got))
        }

        pub fn get_fmu_state(&mut self) -> Result<FmuState, Fmi2Error> {
            self.state_call(GET_STATE, None)
        }

        pub fn update_fmu_state(&mut self, s: &FmuState) -> Result<(), Fmi2Error> {
            self.state_call(UPDATE_STATE, Some(s)).map(|_| ())
        }

        pub fn set_fmu_state(&mut self, s: &FmuState) -> Result<(), Fmi2Error> {
            self.state_call(SET_STATE, Some(s)).map(|_| ())
        }

        pub fn free_fmu_state(&mut self, s: FmuState) -> Result<(), Fmi2Error> {
            self.state_call(FREE_STATE, Some(&s)).map(|_| ())
        }

        pub fn serialize_fmu_state(&mut self, s: &FmuState) -> Result<Vec<u8>, Fmi2Error> {
            let mut bytes = Vec::new();
            let idx = s.0 as u32;
            self.call(
                SERIALIZE,
                self.time,
                |w| w.u32(idx),
                |r| {
                    bytes = r.blob().to_vec();
                    Ok(())
                },
            )?;
            Ok(bytes)
        }

        pub fn deserialize_fmu_state(&mut self, bytes: &[u8]) -> Result<FmuState, Fmi2Error> {
            let mut got = 0;
            self.call(
                DESERIALIZE,
                self.time,
                |w| w.blob(bytes),
                |r| {
                    got = r.u32() as usize;
                    Ok(())
                },
            )?;
            Ok(FmuState(got))
        }

        pub fn get_output_derivatives(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), Fmi2Error> {
            Self::lengths(vrs.len(), out.len())?;
            self.call(
                OUTPUT_DERIVATIVES,
                self.time,
                |w| w.u32s(vrs),
                |r| {
                    out.iter_mut().for_each(|x| *x = r.f64());
                    Ok(())
                },
            )
        }

        pub fn set_input_derivatives(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), Fmi2Error> {
            Self::lengths(vrs.len(), values.len())?;
            self.post(INPUT_DERIVATIVES, self.time, false, |w| {
                w.u32s(vrs)?;
                w.f64s(values)
            })
        }

        pub fn get_directional_derivative(
            &mut self,
            unknowns: &[u32],
            knowns: &[u32],
            seed: &[f64],
            out: &mut [f64],
        ) -> Result<(), Fmi2Error> {
            Self::lengths(knowns.len(), seed.len())?;
            Self::lengths(unknowns.len(), out.len())?;
            self.call(
                DIRECTIONAL,
                self.time,
                |w| {
                    w.u32s(unknowns)?;
                    w.u32s(knowns)?;
                    w.f64s(seed)
                },
                |r| {
                    out.iter_mut().for_each(|x| *x = r.f64());
                    Ok(())
                },
            )
        }
    }

    /// How a child process ended, in words.
    fn describe_exit(status: std::process::ExitStatus) -> String {
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

    // ---------------------------------------------------------------------------------------------
    // The child's side.

    /// The FMUs' messages of the current batch: (level, instance, text).
    static MESSAGES: std::sync::Mutex<Vec<(u8, String, String)>> = std::sync::Mutex::new(Vec::new());

    struct Collector;

    impl log::Log for Collector {
        fn enabled(&self, _: &log::Metadata) -> bool {
            true
        }
        fn log(&self, record: &log::Record) {
            if record.module_path() != Some("logger") {
                return;
            }
            let level = match record.level() {
                log::Level::Warn => 1,
                log::Level::Trace => 2,
                log::Level::Error => 3,
                _ => 0,
            };
            if let Ok(mut m) = MESSAGES.lock() {
                m.push((level, record.target().to_owned(), record.args().to_string()));
            }
        }
        fn flush(&self) {}
    }

    static COLLECTOR: Collector = Collector;

    /// A child's watchdog: the process ends (`_exit`, even inside a hanging FMU call) within
    /// 100 ms of its parent's end. Not PR_SET_PDEATHSIG: that fires when the parent *thread*
    /// that started the child ends, and a Dask worker's task threads come and go while the
    /// System lives on. Returns the parent's pid.
    fn watch_parent() -> u32 {
        let parent = std::os::unix::process::parent_id();
        std::thread::spawn(move || {
            loop {
                std::thread::sleep(Duration::from_millis(100));
                if std::os::unix::process::parent_id() != parent {
                    // SAFETY: ends the process at once, without atexit handlers (an FMU's thread
                    // may hold what they would need).
                    unsafe { libc::_exit(3) };
                }
            }
        });
        parent
    }

    /// `rustfmu-runner serve-component`: serves one component for the parent that started it, until
    /// it says quit or goes away. Returns the process's exit code.
    pub fn serve(dir: &Path, component: &str, label: &str, me: bool, shm: &Path) -> i32 {
        let parent = watch_parent();
        let _ = log::set_logger(&COLLECTOR);
        log::set_max_level(log::LevelFilter::Trace);
        let file = match OpenOptions::new().read(true).write(true).open(shm) {
            Ok(f) => f,
            Err(e) => {
                eprintln!("rustfmu-runner serve-component: cannot open {}: {e}", shm.display());
                return 2;
            }
        };
        let mut shm = match map(&file) {
            Ok(map) => Shared { map },
            Err(e) => {
                eprintln!("rustfmu-runner serve-component: {e}");
                return 2;
            }
        };
        drop(file);
        let mut done = 0u32;
        let mut inst: Option<InstanceCS> = None;
        let mut fmu: Option<crate::fmu::Fmu> = None;
        let (mut vrs, mut vrs2, mut reals, mut ints) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut strings: Vec<CString> = Vec::new();
        let mut quit = false;
        let mut patience = Patience::new(50, 200);
        while !quit {
            // Wait for the next batch.
            let begun = Instant::now();
            let mut slept = false;
            loop {
                let h = shm.header();
                if h.req.load(Acquire) != done {
                    patience.waited(slept);
                    break;
                }
                let waited = begun.elapsed();
                if waited < patience.limit {
                    std::thread::yield_now();
                } else {
                    slept = true;
                    h.child_sleeps.store(1, SeqCst);
                    if h.req.load(SeqCst) == done {
                        futex_wait(&h.req, done, Duration::from_millis(100));
                    }
                    h.child_sleeps.store(0, SeqCst);
                    if std::os::unix::process::parent_id() != parent {
                        return 3;
                    }
                }
            }
            let seq = shm.header().req.load(Acquire);
            let len = shm.header().req_len.load(Acquire) as usize;
            // The batch is copied out: the answer is written while it is read (small: a step's calls).
            let batch = shm.req()[..len].to_vec();
            let mut r = R { buf: &batch, at: 0 };
            let n = r.u32();
            let mut failed: Option<(u32, Fmi2Error)> = None;
            // The answer's values (of the last call), written after the messages below.
            let mut values: Vec<u8> = Vec::new();
            for i in 0..n {
                shm.header().current.store(i, Release);
                let op = r.u8();
                values.clear();
                let result: Result<(), Fmi2Error> = (|| {
                    if op == HELLO {
                        let f = crate::fmu::Fmu::from_dir(component, label, dir)
                            .map_err(|e| Fmi2Error::Importer(e.message))?;
                        let i = if me {
                            f.instantiate_me(component)
                        } else {
                            f.instantiate(component)
                        }
                        .map_err(|e| Fmi2Error::Importer(e.message))?;
                        inst = Some(i);
                        fmu = Some(f);
                        return Ok(());
                    }
                    if op == QUIT {
                        inst = None;
                        fmu = None;
                        quit = true;
                        return Ok(());
                    }
                    let inst = inst
                        .as_mut()
                        .ok_or_else(|| Fmi2Error::Importer("not instantiated".into()))?;
                    let put_f64s =
                        |values: &mut Vec<u8>, xs: &[f64]| xs.iter().for_each(|x| values.extend(x.to_ne_bytes()));
                    match op {
                        SET_DEBUG_LOGGING => {
                            let on = r.u8() != 0;
                            let k = r.u32();
                            let cats: Vec<String> =
                                (0..k).map(|_| String::from_utf8_lossy(r.blob()).into_owned()).collect();
                            let cats: Vec<&str> = cats.iter().map(String::as_str).collect();
                            inst.set_debug_logging(on, &cats)
                        }
                        SETUP_EXPERIMENT => {
                            let (tol, start, stop) = (r.f64(), r.f64(), r.f64());
                            let opt = |x: f64| (!x.is_nan()).then_some(x);
                            inst.setup_experiment(opt(tol), start, opt(stop))
                        }
                        ENTER_INIT => inst.enter_initialization_mode(),
                        EXIT_INIT => inst.exit_initialization_mode(),
                        TERMINATE => inst.terminate(),
                        RESET => inst.reset(),
                        DO_STEP => {
                            let (t, h, nsp) = (r.f64(), r.f64(), r.u8() != 0);
                            inst.do_step(t, h, nsp)
                        }
                        GET_REAL | OUTPUT_DERIVATIVES => {
                            r.u32s_into(&mut vrs);
                            reals.clear();
                            reals.resize(vrs.len(), 0.0);
                            if op == GET_REAL {
                                inst.get_real(&vrs, &mut reals)?;
                            } else {
                                inst.get_output_derivatives(&vrs, &mut reals)?;
                            }
                            put_f64s(&mut values, &reals);
                            Ok(())
                        }
                        GET_INTEGER | GET_BOOLEAN => {
                            r.u32s_into(&mut vrs);
                            ints.clear();
                            ints.resize(vrs.len(), 0);
                            if op == GET_INTEGER {
                                inst.get_integer(&vrs, &mut ints)?;
                            } else {
                                inst.get_boolean(&vrs, &mut ints)?;
                            }
                            ints.iter().for_each(|x| values.extend(x.to_ne_bytes()));
                            Ok(())
                        }
                        GET_STRING => {
                            r.u32s_into(&mut vrs);
                            strings.clear();
                            strings.resize(vrs.len(), CString::default());
                            inst.get_string(&vrs, &mut strings)?;
                            for s in &strings {
                                values.extend((s.as_bytes().len() as u32).to_ne_bytes());
                                values.extend(s.as_bytes());
                            }
                            Ok(())
                        }
                        SET_REAL | INPUT_DERIVATIVES => {
                            r.u32s_into(&mut vrs);
                            r.f64s_into(&mut reals);
                            if op == SET_REAL {
                                inst.set_real(&vrs, &reals)
                            } else {
                                inst.set_input_derivatives(&vrs, &reals)
                            }
                        }
                        SET_INTEGER | SET_BOOLEAN => {
                            r.u32s_into(&mut vrs);
                            r.i32s_into(&mut ints);
                            if op == SET_INTEGER {
                                inst.set_integer(&vrs, &ints)
                            } else {
                                inst.set_boolean(&vrs, &ints)
                            }
                        }
                        SET_STRING => {
                            r.u32s_into(&mut vrs);
                            let k = r.u32();
                            strings.clear();
                            strings.extend((0..k).map(|_| r.cstring()));
                            inst.set_string(&vrs, &strings)
                        }
                        GET_STATE | UPDATE_STATE | SET_STATE | FREE_STATE => {
                            let idx = r.u32() as usize;
                            let s = FmuState(idx);
                            let got = match op {
                                GET_STATE => inst.get_fmu_state()?.0,
                                UPDATE_STATE => inst.update_fmu_state(&s).map(|_| idx)?,
                                SET_STATE => inst.set_fmu_state(&s).map(|_| idx)?,
                                _ => inst.free_fmu_state(s).map(|_| idx)?,
                            };
                            values.extend((got as u32).to_ne_bytes());
                            Ok(())
                        }
                        SERIALIZE => {
                            let s = FmuState(r.u32() as usize);
                            let bytes = inst.serialize_fmu_state(&s)?;
                            values.extend((bytes.len() as u32).to_ne_bytes());
                            values.extend(bytes);
                            Ok(())
                        }
                        DESERIALIZE => {
                            let bytes = r.blob();
                            let s = inst.deserialize_fmu_state(bytes)?;
                            values.extend((s.0 as u32).to_ne_bytes());
                            Ok(())
                        }
                        DIRECTIONAL => {
                            r.u32s_into(&mut vrs);
                            r.u32s_into(&mut vrs2);
                            let mut seed = Vec::new();
                            r.f64s_into(&mut seed);
                            reals.clear();
                            reals.resize(vrs.len(), 0.0);
                            inst.get_directional_derivative(&vrs, &vrs2, &seed, &mut reals)?;
                            put_f64s(&mut values, &reals);
                            Ok(())
                        }
                        other => Err(Fmi2Error::Importer(format!("isolation: unknown call {other}"))),
                    }
                })();
                if let Err(e) = result {
                    failed = Some((i, e));
                    break;
                }
            }
            // The answer: messages, failure, values.
            let messages = std::mem::take(&mut *MESSAGES.lock().unwrap_or_else(|e| e.into_inner()));
            let resp = shm.resp();
            let mut w = W { buf: resp, at: 0 };
            let _ = (|| -> Result<(), Fmi2Error> {
                w.u32(messages.len() as u32)?;
                for (level, target, text) in &messages {
                    w.u8(*level)?;
                    w.blob(target.as_bytes())?;
                    w.blob(text.as_bytes())?;
                }
                match &failed {
                    Some((i, e)) => {
                        w.u32(*i)?;
                        w.err(e)
                    }
                    None => {
                        w.u32(u32::MAX)?;
                        w.bytes(&values)
                    }
                }
            })();
            let at = w.at as u32;
            let h = shm.header();
            h.resp_len.store(at, Relaxed);
            done = seq;
            h.done.store(done, SeqCst);
            if h.parent_sleeps.load(SeqCst) == 1 {
                futex_wake(&h.done);
            }
        }
        0
    }

    // -----------------------------------------------------------------------------------------
    // A whole system in one child process.

    /// The child's shared header, for the crumbs of [`crumb`] (null: not a system's child).
    static CRUMB: AtomicPtr<Header> = AtomicPtr::new(std::ptr::null_mut());

    /// Before each call of an [`InstanceCS`]: which instance and method, in a system's child
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
    fn fmi_function(method: &str) -> &'static str {
        match method {
            "set_debug_logging" => "fmi2SetDebugLogging",
            "setup_experiment" => "fmi2SetupExperiment",
            "enter_initialization_mode" => "fmi2EnterInitializationMode",
            "exit_initialization_mode" => "fmi2ExitInitializationMode",
            "terminate" => "fmi2Terminate",
            "reset" => "fmi2Reset",
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

    /// What a system's child tells about the system it loaded.
    #[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
    pub struct SystemInfo {
        pub name: String,
        pub evaluation_order: Vec<String>,
        pub components: Vec<(String, String)>,
        pub outputs: Vec<String>,
        pub parameters: Vec<String>,
    }

    /// What a system's child answers a run with (the values follow as f64).
    #[derive(serde::Serialize, serde::Deserialize)]
    struct RunAnswer {
        error: Option<Error>,
        /// The result, or the partial one; `time` and `values` travel as raw f64 after this.
        result: crate::RunResult,
        n_time: usize,
        n_values: usize,
    }

    /// A request to a system's child.
    #[derive(serde::Serialize, serde::Deserialize)]
    enum SystemRequest {
        Run(crate::RunOptions),
        Quit,
    }

    /// A system whose FMUs and master run in a child process (`rustfmu-runner serve-system`):
    /// [`SystemProcess::run`] is [`crate::Simulation::run`] there. A child that dies or hangs
    /// fails the run with the component, function and time it was in; the next run starts a
    /// new one.
    pub struct SystemProcess {
        iso: Isolation,
        ssp: PathBuf,
        jacobi: bool,
        info: SystemInfo,
        live: Option<(Child, Shared, u32)>,
    }

    impl Drop for SystemProcess {
        fn drop(&mut self) {
            self.stop();
        }
    }

    fn json_into(shm: &mut [u8], value: &impl serde::Serialize) -> Result<usize, String> {
        let text = serde_json::to_vec(value).map_err(|e| e.to_string())?;
        if text.len() + 8 > shm.len() {
            return Err(format!("more than {} MiB to pass between processes", AREA >> 20));
        }
        shm[..8].copy_from_slice(&(text.len() as u64).to_ne_bytes());
        shm[8..8 + text.len()].copy_from_slice(&text);
        Ok(8 + text.len())
    }

    fn json_from<T: serde::de::DeserializeOwned>(shm: &[u8]) -> Result<(T, usize), String> {
        let n = u64::from_ne_bytes(shm[..8].try_into().unwrap()) as usize;
        let v = serde_json::from_slice(&shm[8..8 + n]).map_err(|e| e.to_string())?;
        Ok((v, 8 + n))
    }

    impl SystemProcess {
        /// Starts the child of the SSP file `ssp` (`jacobi`: that evaluation order).
        pub fn spawn(iso: Isolation, ssp: &Path, jacobi: bool) -> Result<SystemProcess, Error> {
            let (child, shm) = Self::start(&iso, ssp, jacobi)?;
            let (info, _) = json_from::<Result<SystemInfo, Error>>(&shm.map[RESP_OFF..]).map_err(|e| {
                Error::io(format!(
                    "{}: the system's process answered no description: {e}",
                    ssp.display()
                ))
            })?;
            let mut p = SystemProcess {
                iso,
                ssp: ssp.to_path_buf(),
                jacobi,
                info: SystemInfo {
                    name: String::new(),
                    evaluation_order: Vec::new(),
                    components: Vec::new(),
                    outputs: Vec::new(),
                    parameters: Vec::new(),
                },
                live: Some((child, shm, 1)),
            };
            p.info = info?;
            Ok(p)
        }

        /// The child started and its system loaded (the answer to batch 1 in the answer area).
        fn start(iso: &Isolation, ssp: &Path, jacobi: bool) -> Result<(Child, Shared), Error> {
            let fail = |m: String| Error::io(format!("{}: isolated: {m}", ssp.display()));
            let (file, path) = shm_file().map_err(fail)?;
            let shm = Shared {
                map: map(&file).map_err(fail)?,
            };
            // Batch 1: load the system (answered with its description).
            shm.header().req.store(1, SeqCst);
            let mut cmd = Command::new(&iso.worker);
            cmd.arg("serve-system")
                .arg("--ssp")
                .arg(ssp)
                .arg("--shm")
                .arg(&path)
                .stdin(Stdio::null());
            if jacobi {
                cmd.arg("--jacobi");
            }
            let mut child = cmd.spawn().map_err(|e| {
                let _ = std::fs::remove_file(&path);
                fail(format!("cannot start {}: {e}", iso.worker.display()))
            })?;
            let r = wait_done(&shm, &mut child, 1, None);
            let _ = std::fs::remove_file(&path);
            if let Err(how) = r {
                return Err(fail(format!("its process {how} while loading the system")));
            }
            Ok((child, shm))
        }

        pub fn info(&self) -> &SystemInfo {
            &self.info
        }

        fn stop(&mut self) {
            if let Some((mut child, mut shm, seq)) = self.live.take() {
                if let Ok(n) = json_into(shm.req(), &SystemRequest::Quit) {
                    publish_raw(&shm, seq + 1, n);
                    let until = Instant::now() + Duration::from_secs(5);
                    while Instant::now() < until {
                        if let Ok(Some(_)) = child.try_wait() {
                            return;
                        }
                        std::thread::sleep(Duration::from_micros(200));
                    }
                }
                let _ = child.kill();
                let _ = child.wait();
            }
        }

        /// One run in the child ([`crate::Simulation::run`]).
        pub fn run(&mut self, opts: &crate::RunOptions) -> Result<crate::RunResult, crate::sim::Failure> {
            let failure = |error: Error| crate::sim::Failure {
                error,
                partial: crate::RunResult {
                    names: opts.record.clone(),
                    ..Default::default()
                },
            };
            if self.live.is_none() {
                let (child, shm) = Self::start(&self.iso, &self.ssp, self.jacobi).map_err(failure)?;
                self.live = Some((child, shm, 1));
            }
            let (child, shm, seq) = self.live.as_mut().expect("started");
            let n = json_into(shm.req(), &SystemRequest::Run(opts.clone())).map_err(|e| failure(Error::usage(e)))?;
            *seq += 1;
            publish_raw(shm, *seq, n);
            if let Err(how) = wait_done(shm, child, *seq, self.iso.timeout) {
                // The component, function and time of the crumbs.
                let h = shm.header();
                let addr = h.crumb_instance.load(Acquire);
                let mut method = Vec::new();
                for w in &h.crumb_method {
                    method.extend(w.load(Acquire).to_le_bytes());
                }
                let method = String::from_utf8_lossy(&method).trim_end_matches('\0').to_owned();
                let t = f64::from_bits(h.crumb_time.load(Acquire));
                let (component, v3) = name_of(&shm.map[NAMES_OFF..REQ_OFF], addr).unwrap_or(("?".to_owned(), false));
                let function = crate::sim::fname(v3, fmi_function(&method));
                let pid = child.id();
                let _ = child.kill();
                let _ = child.wait();
                self.live = None;
                let error = Error::fmi(
                    &component,
                    function,
                    &Fmi2Error::Died(format!("the process of the system (pid {pid}) {how}")),
                    Some(t),
                    "",
                );
                return Err(failure(error));
            }
            let resp = &shm.map[RESP_OFF..];
            let (answer, at) = json_from::<RunAnswer>(resp).map_err(|e| failure(Error::io(e)))?;
            let at = at.div_ceil(8) * 8;
            let floats = |from: usize, n: usize| -> Vec<f64> {
                resp[from..from + 8 * n]
                    .chunks_exact(8)
                    .map(|c| f64::from_ne_bytes(c.try_into().unwrap()))
                    .collect()
            };
            let mut result = answer.result;
            result.time = floats(at, answer.n_time);
            result.values = floats(at + 8 * answer.n_time, answer.n_values);
            match answer.error {
                None => Ok(result),
                Some(error) => Err(crate::sim::Failure { error, partial: result }),
            }
        }
    }

    fn publish_raw(shm: &Shared, seq: u32, len: usize) {
        let h = shm.header();
        h.req_len.store(len as u32, Relaxed);
        h.req.store(seq, SeqCst);
        if h.child_sleeps.load(SeqCst) == 1 {
            futex_wake(&h.req);
        }
    }

    /// Waits for the child to answer batch `seq`; Err: how it died or hung. `hang`: the
    /// longest a single FMI call may take (from the crumbs' call count).
    fn wait_done(shm: &Shared, child: &mut Child, seq: u32, hang: Option<Duration>) -> Result<(), String> {
        let h = shm.header();
        let mut last_calls = h.calls.load(Acquire);
        let mut since = Instant::now();
        loop {
            if h.done.load(Acquire) == seq {
                return Ok(());
            }
            h.parent_sleeps.store(1, SeqCst);
            let done = h.done.load(SeqCst);
            if done != seq {
                futex_wait(&h.done, done, Duration::from_millis(5));
            }
            h.parent_sleeps.store(0, SeqCst);
            if h.done.load(Acquire) == seq {
                return Ok(());
            }
            if let Ok(Some(status)) = child.try_wait() {
                return Err(describe_exit(status));
            }
            let calls = h.calls.load(Acquire);
            if calls != last_calls {
                last_calls = calls;
                since = Instant::now();
            } else if let Some(limit) = hang
                && since.elapsed() > limit
            {
                return Err(format!(
                    "did not return within {} s: the process was killed",
                    limit.as_secs_f64()
                ));
            }
        }
    }

    /// The component whose instance is at `addr` in the child (its names table).
    fn name_of(table: &[u8], addr: u64) -> Option<(String, bool)> {
        let mut r = R { buf: table, at: 0 };
        let n = r.u32();
        for _ in 0..n {
            let a = u64::from_ne_bytes(r.bytes(8).try_into().ok()?);
            let v3 = r.u8() != 0;
            let name = String::from_utf8_lossy(r.blob()).into_owned();
            if a == addr {
                return Some((name, v3));
            }
        }
        None
    }

    /// `rustfmu-runner serve-system`: loads the SSP file and runs it for the parent that started
    /// this process, until it says quit or goes away. Returns the process's exit code.
    pub fn serve_system(ssp: &Path, shm: &Path, jacobi: bool) -> i32 {
        let parent = watch_parent();
        let file = match OpenOptions::new().read(true).write(true).open(shm) {
            Ok(f) => f,
            Err(e) => {
                eprintln!("rustfmu-runner serve-system: cannot open {}: {e}", shm.display());
                return 2;
            }
        };
        let mut shm = match map(&file) {
            Ok(map) => Shared { map },
            Err(e) => {
                eprintln!("rustfmu-runner serve-system: {e}");
                return 2;
            }
        };
        drop(file);
        let answer = |shm: &mut Shared, seq: u32, len: usize| {
            let h = shm.header();
            h.resp_len.store(len as u32, Relaxed);
            h.done.store(seq, SeqCst);
            if h.parent_sleeps.load(SeqCst) == 1 {
                futex_wake(&h.done);
            }
        };
        let sim = crate::Simulation::from_ssp(ssp);
        let mut sim = match sim {
            Ok(mut sim) => {
                if jacobi {
                    sim.scheme = crate::Scheme::Jacobi;
                }
                sim
            }
            Err(e) => {
                let n = json_into(shm.resp(), &Err::<SystemInfo, Error>(e)).unwrap_or(0);
                answer(&mut shm, 1, n);
                return 1;
            }
        };
        // The names of the instances by their addresses, for the parent's report of a crash.
        {
            let mut entries = Vec::new();
            for (i, (name, _)) in sim.components().iter().enumerate() {
                entries.push((name.to_string(), i));
            }
            let table = &mut shm.map[NAMES_OFF..REQ_OFF];
            let mut w = W { buf: table, at: 4 };
            let mut n = 0u32;
            for (name, i) in entries {
                let v3 = sim.is_fmi3(i);
                let addr = sim.instance_mut(i) as *const InstanceCS as u64;
                if w.bytes(&addr.to_ne_bytes())
                    .and_then(|_| w.u8(v3 as u8))
                    .and_then(|_| w.blob(name.as_bytes()))
                    .is_err()
                {
                    break;
                }
                n += 1;
            }
            table[..4].copy_from_slice(&n.to_ne_bytes());
        }
        CRUMB.store(shm.map.as_mut_ptr() as *mut Header, Release);
        let info = SystemInfo {
            name: sim.name.clone(),
            evaluation_order: sim.evaluation_order().iter().map(|s| s.to_string()).collect(),
            components: sim
                .components()
                .iter()
                .map(|(a, b)| (a.to_string(), b.to_string()))
                .collect(),
            outputs: sim.outputs(),
            parameters: sim.parameters().iter().map(|s| s.to_string()).collect(),
        };
        let n = json_into(shm.resp(), &Ok::<SystemInfo, Error>(info)).unwrap_or(0);
        answer(&mut shm, 1, n);
        let mut done = 1u32;
        loop {
            let h = shm.header();
            if h.req.load(Acquire) == done {
                h.child_sleeps.store(1, SeqCst);
                if h.req.load(SeqCst) == done {
                    futex_wait(&h.req, done, Duration::from_millis(100));
                }
                h.child_sleeps.store(0, SeqCst);
                if std::os::unix::process::parent_id() != parent {
                    return 3;
                }
                continue;
            }
            let seq = h.req.load(Acquire);
            let request = json_from::<SystemRequest>(&shm.map[REQ_OFF..]);
            let opts = match request {
                Ok((SystemRequest::Run(opts), _)) => opts,
                _ => return 0,
            };
            let (error, mut result) = match sim.run(&opts, &mut |_, _| {}) {
                Ok(r) => (None, r),
                Err(f) => (Some(f.error), f.partial),
            };
            let time = std::mem::take(&mut result.time);
            let values = std::mem::take(&mut result.values);
            let ans = RunAnswer {
                error,
                result,
                n_time: time.len(),
                n_values: values.len(),
            };
            let resp = shm.resp();
            let len = match json_into(resp, &ans) {
                Ok(at) => {
                    let at = at.div_ceil(8) * 8;
                    let need = at + 8 * (time.len() + values.len());
                    if need > resp.len() {
                        let too_big = RunAnswer {
                            error: Some(Error::usage(format!(
                                "the run's {} values are more than the {} MiB an isolated system passes back: record fewer variables or a shorter run",
                                time.len() + values.len(),
                                AREA >> 20
                            ))),
                            result: crate::RunResult::default(),
                            n_time: 0,
                            n_values: 0,
                        };
                        json_into(resp, &too_big).unwrap_or(0)
                    } else {
                        for (k, x) in time.iter().chain(values.iter()).enumerate() {
                            resp[at + 8 * k..at + 8 * k + 8].copy_from_slice(&x.to_ne_bytes());
                        }
                        need
                    }
                }
                Err(_) => 0,
            };
            done = seq;
            answer(&mut shm, done, len);
        }
    }
}
