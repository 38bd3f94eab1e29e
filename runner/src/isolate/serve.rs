//! The child's side of one isolated component (`rustfmu-runner serve-component`): the FMU
//! loaded and instantiated, each call of a batch answered, the FMUs' messages sent back.

use super::options::Interface;
use super::wire::*;
use crate::common::{Directional, Fmi2Error, FmuState};
use crate::fmu_log::{FmuMessages, Status};
use crate::instance::InstanceCS;
use std::ffi::CString;
use std::path::Path;
use std::sync::atomic::Ordering::*;
use std::time::{Duration, Instant};

// ---------------------------------------------------------------------------------------------
// The child's side.

/// The FMUs' messages of the current batch: (level, instance, text).
static MESSAGES: std::sync::Mutex<Vec<(u8, String, String)>> = std::sync::Mutex::new(Vec::new());

/// Collects an FMU's message for the batch's answer, its level as the wire carries it.
fn collect(instance: &str, status: Status, message: &std::fmt::Arguments) {
    let level = match status {
        Status::Ok => 0,
        Status::Warning => 1,
        Status::Discard => 2,
        Status::Error => 3,
    };
    if let Ok(mut m) = MESSAGES.lock() {
        m.push((level, instance.to_owned(), message.to_string()));
    }
}

static COLLECTOR: FmuMessages = FmuMessages(collect);

/// A child's watchdog: the process ends (`_exit`, even inside a hanging FMU call) within
/// 100 ms of its parent's end. Not PR_SET_PDEATHSIG: that fires when the parent *thread*
/// that started the child ends, and a Dask worker's task threads come and go while the
/// System lives on. Returns the parent's pid.
pub(super) fn watch_parent() -> u32 {
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
// ~250 lines: the child's loop, one arm per call code of the wire ([`super::wire`]), each a few
// lines that decode the arguments in place, call the instance and encode the answer into the
// same reused buffers; the arms stay beside each other so that the codes are read in one place.
pub fn serve(dir: &Path, component: &str, label: &str, interface: Interface, shm: &Path) -> i32 {
    let parent = watch_parent();
    let _ = log::set_logger(&COLLECTOR);
    log::set_max_level(log::LevelFilter::Trace);
    let mut shm = match Shared::open(shm) {
        Ok(shm) => shm,
        Err(e) => {
            eprintln!("rustfmu-runner serve-component: {e}");
            return 2;
        }
    };
    let mut done = 0u32;
    let mut inst: Option<InstanceCS> = None;
    let mut fmu: Option<crate::fmu::Fmu> = None;
    let (mut vrs, mut vrs2, mut reals, mut ints) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut strings: Vec<CString> = Vec::new();
    let mut typed: Vec<crate::values::Values> = Vec::new();
    // The clocks' snapshot kept to take a step back, and its number.
    let mut snapshot: Option<(u32, crate::fmi3::ClockState)> = None;
    let mut snapshots = 0u32;
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
                if !h.child_sleep(done, parent) {
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
                    let f =
                        crate::fmu::Fmu::from_dir(component, label, dir).map_err(|e| Fmi2Error::Importer(e.message))?;
                    let i = match interface {
                        Interface::CoSimulation => f.instantiate(component),
                        Interface::ModelExchange => f.instantiate_me(component),
                        Interface::EventMode => f.instantiate_events(component),
                        Interface::ScheduledExecution => f.instantiate_scheduled(component),
                    }
                    .map_err(|e| Fmi2Error::Importer(e.message))?;
                    let clocks = matches!(&i, InstanceCS::V3(i) if i.has_clock_state());
                    values.push(clocks as u8);
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
                    CONFIGURATION => inst.configuration_mode(r.u8() != 0),
                    DO_STEP => {
                        let (t, h, nsp) = (r.f64(), r.f64(), r.u8() != 0);
                        inst.do_step(t, h, nsp)?;
                        if let InstanceCS::V3(i) = inst
                            && i.has_clock_state()
                        {
                            values.extend(i.early_return().unwrap_or(f64::NAN).to_ne_bytes());
                        }
                        Ok(())
                    }
                    SETTLE => {
                        inst.settle(r.f64())?;
                        values.extend(inst.next_tick()?.unwrap_or(f64::NAN).to_ne_bytes());
                        Ok(())
                    }
                    NEXT_TICK => {
                        values.extend(inst.next_tick()?.unwrap_or(f64::NAN).to_ne_bytes());
                        Ok(())
                    }
                    EARLY_RETURN => {
                        values.extend(inst.take_early_return()?.unwrap_or(f64::NAN).to_ne_bytes());
                        Ok(())
                    }
                    TICK_NOW => inst.tick_now(r.f64()),
                    TRIGGER => {
                        let (vr, t) = (r.u32(), r.f64());
                        inst.trigger(vr, t)
                    }
                    POLL_OUTPUT_CLOCKS => inst.poll_output_clocks(r.f64()),
                    ACTIVATE => {
                        values.push(inst.activate_scheduled(r.f64())? as u8);
                        Ok(())
                    }
                    CLOCK_ACTIVE => {
                        values.push(inst.clock_active(r.u32())? as u8);
                        Ok(())
                    }
                    CLOCK_SNAPSHOT => {
                        let InstanceCS::V3(i) = inst else {
                            return Err(Fmi2Error::Importer(
                                "isolation: clocks of an instance without them".into(),
                            ));
                        };
                        snapshots = snapshots.wrapping_add(1);
                        snapshot = i.clock_snapshot().map(|c| (snapshots, c));
                        values.extend(snapshots.to_ne_bytes());
                        Ok(())
                    }
                    RESTORE_CLOCKS => {
                        let n = r.u32();
                        match (&mut *inst, &snapshot) {
                            (InstanceCS::V3(i), Some((kept, c))) if *kept == n => {
                                i.restore_clocks(c);
                                Ok(())
                            }
                            _ => Err(Fmi2Error::Importer(format!(
                                "isolation: the clocks' snapshot {n} is not the one kept (the child keeps the last)"
                            ))),
                        }
                    }
                    GET_REAL => answer(&mut r, &mut vrs, &mut reals, &mut values, |v, o| inst.get_real(v, o)),
                    OUTPUT_DERIVATIVES => answer(&mut r, &mut vrs, &mut reals, &mut values, |v, o| {
                        inst.get_output_derivatives(v, o)
                    }),
                    GET_INTEGER => answer(&mut r, &mut vrs, &mut ints, &mut values, |v, o| inst.get_integer(v, o)),
                    GET_BOOLEAN => answer(&mut r, &mut vrs, &mut ints, &mut values, |v, o| inst.get_boolean(v, o)),
                    GET_STRING => answer(&mut r, &mut vrs, &mut strings, &mut values, |v, o| {
                        inst.get_string(v, o)
                    }),
                    SET_REAL => set(&mut r, &mut vrs, &mut reals, |v, x| inst.set_real(v, x)),
                    INPUT_DERIVATIVES => set(&mut r, &mut vrs, &mut reals, |v, x| inst.set_input_derivatives(v, x)),
                    SET_INTEGER => set(&mut r, &mut vrs, &mut ints, |v, x| inst.set_integer(v, x)),
                    SET_BOOLEAN => set(&mut r, &mut vrs, &mut ints, |v, x| inst.set_boolean(v, x)),
                    SET_STRING => set(&mut r, &mut vrs, &mut strings, |v, x| inst.set_string(v, x)),
                    GET_TYPED | SET_TYPED => {
                        r.u32s_into(&mut vrs);
                        let (code, n) = (r.u8(), r.u32() as usize);
                        // A buffer per type and length, made at the first call that needs it.
                        let k = match typed.iter().position(|t| t.code() == code && t.len() == n) {
                            Some(k) => k,
                            None => {
                                typed.push(
                                    crate::values::Values::of_code(code, n)
                                        .ok_or_else(|| Fmi2Error::Importer(format!("isolation: type code {code}")))?,
                                );
                                typed.len() - 1
                            }
                        };
                        let buf = &mut typed[k];
                        if op == GET_TYPED {
                            if r.u8() != 0 {
                                buf.take(&mut |k| r.bytes(k));
                            }
                            inst.get_typed(&vrs, buf)?;
                            buf.put(&mut |b| {
                                values.extend_from_slice(b);
                                Ok::<(), Fmi2Error>(())
                            })
                        } else {
                            buf.take(&mut |k| r.bytes(k));
                            inst.set_typed(&vrs, buf)
                        }
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
                        inst.get_directional_derivative(Directional {
                            unknowns: &vrs,
                            knowns: &vrs2,
                            seed: &seed,
                            out: &mut reals,
                        })?;
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

/// A value as the wire carries it: a number in its native bytes, a string with its length first
/// (the values of a set: their count first).
trait Value: Clone + Default {
    /// Into the answer of a get.
    fn put(&self, values: &mut Vec<u8>);
    /// The values of a set, read into `out`.
    fn read_into(r: &mut R<'_>, out: &mut Vec<Self>);
}

impl Value for f64 {
    fn put(&self, values: &mut Vec<u8>) {
        values.extend(self.to_ne_bytes());
    }
    fn read_into(r: &mut R<'_>, out: &mut Vec<f64>) {
        r.f64s_into(out);
    }
}

impl Value for i32 {
    fn put(&self, values: &mut Vec<u8>) {
        values.extend(self.to_ne_bytes());
    }
    fn read_into(r: &mut R<'_>, out: &mut Vec<i32>) {
        r.i32s_into(out);
    }
}

impl Value for CString {
    fn put(&self, values: &mut Vec<u8>) {
        values.extend((self.as_bytes().len() as u32).to_ne_bytes());
        values.extend(self.as_bytes());
    }
    fn read_into(r: &mut R<'_>, out: &mut Vec<CString>) {
        let k = r.u32();
        out.clear();
        out.extend((0..k).map(|_| r.cstring()));
    }
}

/// A get: its value references read into `vrs`, `out` as many default values, which `get`
/// overwrites, then written to the answer's `values` (the buffers are kept from call to call).
fn answer<T: Value>(
    r: &mut R<'_>,
    vrs: &mut Vec<u32>,
    out: &mut Vec<T>,
    values: &mut Vec<u8>,
    get: impl FnOnce(&[u32], &mut [T]) -> Result<(), Fmi2Error>,
) -> Result<(), Fmi2Error> {
    r.u32s_into(vrs);
    out.clear();
    out.resize(vrs.len(), T::default());
    get(vrs, out)?;
    out.iter().for_each(|x| x.put(values));
    Ok(())
}

/// A set: its value references read into `vrs`, its values into `values`, then `set`.
fn set<T: Value>(
    r: &mut R<'_>,
    vrs: &mut Vec<u32>,
    values: &mut Vec<T>,
    set: impl FnOnce(&[u32], &[T]) -> Result<(), Fmi2Error>,
) -> Result<(), Fmi2Error> {
    r.u32s_into(vrs);
    T::read_into(r, values);
    set(vrs, values)
}
