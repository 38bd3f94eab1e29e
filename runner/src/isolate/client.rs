//! [`Isolated`]: a component's instance in a child process, the parent's side of the wire
//! ([`super::wire`]): calls batched, the ones that answer only a status not waited for.

use super::options::{Interface, Isolation};
use super::wire::*;
use crate::common::{Deferred, Directional, Fmi2Error, FmuState};
use crate::{Error, ErrorKind};
use std::ffi::CString;
use std::path::Path;
use std::process::Child;
use std::sync::atomic::Ordering::*;
use std::time::{Duration, Instant};

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
    /// FMI 3.0: the child's importer keeps clocks for the instance (input clocks it ticks, or
    /// Event Mode). Its reads are then made as asked, none ahead (a read of a clocked variable
    /// counts as its tick's evaluation), and its steps are waited for (a step's end opens an
    /// Event Mode, whose failures and requests to terminate are the step's).
    clocks: bool,
    /// Answers that came with a call's, valid until the next call: the next tick after an
    /// Event Mode ended, where the last step returned early (None: not known).
    tick: Option<Option<f64>>,
    early: Option<Option<f64>>,
}

/// A time the wire carries as f64, NaN for none.
fn time_or_none(x: f64) -> Option<f64> {
    (!x.is_nan()).then_some(x)
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

impl Isolated {
    /// Starts the child process of `component` (its FMU unpacked in `dir`) and instantiates it
    /// there (`me`: model exchange, integrated by the runner in the child).
    pub fn spawn(
        iso: &Isolation,
        component: &str,
        label: &str,
        dir: &Path,
        interface: Interface,
    ) -> Result<Isolated, Error> {
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
        let options = [
            ("--dir", dir.as_os_str()),
            ("--name", component.as_ref()),
            ("--label", label.as_ref()),
        ];
        let flag = match interface {
            Interface::CoSimulation => None,
            Interface::ModelExchange => Some("--model-exchange"),
            Interface::EventMode => Some("--event-mode"),
            Interface::ScheduledExecution => Some("--scheduled-execution"),
        };
        let child = start_worker(&iso.worker, "serve-component", &options, &path, flag).map_err(&fail)?;
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
            clocks: false,
            tick: None,
            early: None,
        };
        // The child opens the file before it answers: then it can go.
        let mut clocks = false;
        let r = iso_inst.call(
            HELLO,
            None,
            |_| Ok(()),
            |r| {
                clocks = r.u8() != 0;
                Ok(())
            },
        );
        iso_inst.clocks = clocks;
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
            GET_REAL
                | GET_INTEGER
                | GET_BOOLEAN
                | GET_STRING
                | GET_TYPED
                | OUTPUT_DERIVATIVES
                | DIRECTIONAL
                | SERIALIZE
        ) {
            self.cache_valid = false;
        }
        self.tick = None;
        self.early = None;
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
        // A child that dies before it starts the batch dies in its first call.
        h.current.store(0, Relaxed);
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
                        "did not return within {} s: it was killed",
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
    /// `last` reads the values of its last call. `waited`: the last call is the caller's (its
    /// failure is its own); else it was posted, and its failure comes as the one before.
    fn collect(&mut self, waited: bool, last: impl FnOnce(&mut R) -> Result<(), Fmi2Error>) -> Result<(), Fmi2Error> {
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
            if waited && i + 1 == calls.len() {
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
        self.collect(false, |_| Ok(()))
    }

    /// Sends what is written and waits for it: a failure of a call before now.
    pub fn sync(&mut self) -> Result<(), Fmi2Error> {
        self.flush_wait()?;
        if !self.pending.is_empty() {
            self.publish()?;
            self.collect(false, |_| Ok(()))?;
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
        self.collect(true, answer)
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

    pub fn setup_experiment(&mut self, tolerance: Option<f64>, start: f64, stop: Option<f64>) -> Result<(), Fmi2Error> {
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
        let args = |w: &mut W| {
            w.f64(t)?;
            w.f64(h)?;
            w.u8(no_set_prior as u8)
        };
        if self.clocks {
            // Answered with where it returned early (taken by take_early_return).
            let mut early = None;
            let r = self.call(DO_STEP, Some(t), args, |r| {
                early = time_or_none(r.f64());
                Ok(())
            });
            self.time = Some(early.unwrap_or(t + h));
            r?;
            self.early = Some(early);
            return Ok(());
        }
        self.post(DO_STEP, Some(t), true, args)?;
        self.time = Some(t + h);
        Ok(())
    }

    /// An Event Mode ends at `t` in the child's importer (fmi3UpdateDiscreteStates, the
    /// intervals read, fmi3EnterStepMode), answered with the next tick.
    pub fn settle(&mut self, t: f64) -> Result<(), Fmi2Error> {
        if !self.clocks {
            return Ok(());
        }
        let mut next = None;
        self.call(
            SETTLE,
            Some(t),
            |w| w.f64(t),
            |r| {
                next = time_or_none(r.f64());
                Ok(())
            },
        )?;
        self.tick = Some(next);
        Ok(())
    }

    /// The next tick of its time-based clocks (what [`Isolated::settle`] answered, if nothing
    /// was called since).
    pub fn next_tick(&mut self) -> Result<Option<f64>, Fmi2Error> {
        if !self.clocks {
            return Ok(None);
        }
        if let Some(next) = self.tick {
            return Ok(next);
        }
        self.clock_time(NEXT_TICK, |_| Ok(()))
    }

    /// A call answered with a time or none.
    fn clock_time(
        &mut self,
        op: u8,
        args: impl FnOnce(&mut W) -> Result<(), Fmi2Error>,
    ) -> Result<Option<f64>, Fmi2Error> {
        let mut at = None;
        self.call(op, self.time, args, |r| {
            at = time_or_none(r.f64());
            Ok(())
        })?;
        Ok(at)
    }

    /// Where its last step returned early, taken (what the step answered: taken in the child with
    /// the next call).
    pub fn take_early_return(&mut self) -> Result<Option<f64>, Fmi2Error> {
        if !self.clocks {
            return Ok(None);
        }
        match self.early.take() {
            Some(None) => Ok(None),
            Some(Some(at)) => {
                self.post(EARLY_RETURN, self.time, false, |_| Ok(()))?;
                Ok(Some(at))
            }
            None => self.clock_time(EARLY_RETURN, |_| Ok(())),
        }
    }

    /// The clocks due at `t` tick.
    pub fn tick_now(&mut self, t: f64) -> Result<(), Fmi2Error> {
        if !self.clocks {
            return Ok(());
        }
        self.call(TICK_NOW, Some(t), |w| w.f64(t), |_| Ok(()))
    }

    /// Its input clock `vr` ticks at `t`.
    pub fn trigger(&mut self, vr: u32, t: f64) -> Result<(), Fmi2Error> {
        self.call(
            TRIGGER,
            Some(t),
            |w| {
                w.u32(vr)?;
                w.f64(t)
            },
            |_| Ok(()),
        )
    }

    /// Its output clocks read (once an Event Mode).
    pub fn poll_output_clocks(&mut self, t: f64) -> Result<(), Fmi2Error> {
        if !self.clocks {
            return Ok(());
        }
        self.call(POLL_OUTPUT_CLOCKS, Some(t), |w| w.f64(t), |_| Ok(()))
    }

    /// Scheduled Execution: the partitions of the clocks that tick at `t` activated in the child
    /// (once the inputs are set); whether one was.
    pub fn activate_scheduled(&mut self, t: f64) -> Result<bool, Fmi2Error> {
        if !self.clocks {
            return Ok(false);
        }
        let mut any = false;
        self.call(
            ACTIVATE,
            Some(t),
            |w| w.f64(t),
            |r| {
                any = r.u8() != 0;
                Ok(())
            },
        )?;
        Ok(any)
    }

    /// Whether its clock `vr` ticks now.
    pub fn clock_active(&mut self, vr: u32) -> Result<bool, Fmi2Error> {
        if !self.clocks {
            return Ok(false);
        }
        let mut on = false;
        self.call(
            CLOCK_ACTIVE,
            self.time,
            |w| w.u32(vr),
            |r| {
                on = r.u8() != 0;
                Ok(())
            },
        )?;
        Ok(on)
    }

    /// The importer's side of its clocks kept in the child (the last one kept: the master keeps
    /// one per instance), answered with its number.
    pub fn clock_snapshot(&mut self) -> Result<Option<u32>, Fmi2Error> {
        if !self.clocks {
            return Ok(None);
        }
        let mut n = 0;
        self.call(
            CLOCK_SNAPSHOT,
            self.time,
            |_| Ok(()),
            |r| {
                n = r.u32();
                Ok(())
            },
        )?;
        Ok(Some(n))
    }

    /// Its clocks as the snapshot `n` kept them, sent with the next call.
    pub fn restore_clocks(&mut self, n: u32) -> Result<(), Fmi2Error> {
        self.post(RESTORE_CLOCKS, self.time, false, |w| w.u32(n))
    }

    pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), Fmi2Error> {
        Self::lengths(vrs.len(), out.len())?;
        if self.clocks {
            return self.get_values(GET_REAL, vrs, out, |r| r.f64());
        }
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

    /// A get (`op`) of the values of `vrs` into `out`, each read from the answer by `read`.
    fn get_values<T>(
        &mut self,
        op: u8,
        vrs: &[u32],
        out: &mut [T],
        read: impl Fn(&mut R) -> T,
    ) -> Result<(), Fmi2Error> {
        Self::lengths(vrs.len(), out.len())?;
        self.call(
            op,
            self.time,
            |w| w.u32s(vrs),
            |r| {
                out.iter_mut().for_each(|x| *x = read(r));
                Ok(())
            },
        )
    }

    /// A set (`op`) of `n` values of `vrs`, posted (sent with the next call that answers values):
    /// the value references, then the values `write` writes.
    fn set_values(
        &mut self,
        op: u8,
        vrs: &[u32],
        n: usize,
        write: impl FnOnce(&mut W) -> Result<(), Fmi2Error>,
    ) -> Result<(), Fmi2Error> {
        Self::lengths(vrs.len(), n)?;
        self.post(op, self.time, false, |w| {
            w.u32s(vrs)?;
            write(w)
        })
    }

    /// FMI 3.0 values of any type and shape, `out`'s type and length asked for. With clocks,
    /// `out`'s values go along: a clocked variable read between its ticks, never read or set
    /// before, leaves them as they are (`fmi3/typed.rs`).
    pub fn get_typed(&mut self, vrs: &[u32], out: &mut crate::values::Values) -> Result<(), Fmi2Error> {
        let (code, n, clocks) = (out.code(), out.len() as u32, self.clocks);
        // A call (as `call`), its arguments and its answer written and read in turn.
        self.flush_wait()?;
        let was: &crate::values::Values = out;
        self.push(GET_TYPED, self.time, |w| {
            w.u32s(vrs)?;
            w.u8(code)?;
            w.u32(n)?;
            w.u8(clocks as u8)?;
            if clocks {
                was.put(&mut |b| w.bytes(b))?;
            }
            Ok(())
        })?;
        self.publish()?;
        self.collect(true, |r| {
            out.take(&mut |k| r.bytes(k));
            Ok(())
        })
    }

    /// FMI 3.0 values of any type and shape, posted as the other setters are.
    pub fn configuration_mode(&mut self, enter: bool) -> Result<(), Fmi2Error> {
        self.call(CONFIGURATION, None, |w| w.u8(enter as u8), |_| Ok(()))
    }

    pub fn set_typed(&mut self, vrs: &[u32], values: &crate::values::Values) -> Result<(), Fmi2Error> {
        self.post(SET_TYPED, self.time, false, |w| {
            w.u32s(vrs)?;
            w.u8(values.code())?;
            w.u32(values.len() as u32)?;
            values.put(&mut |b| w.bytes(b))
        })
    }

    pub fn get_integer(&mut self, vrs: &[u32], out: &mut [i32]) -> Result<(), Fmi2Error> {
        self.get_values(GET_INTEGER, vrs, out, |r| r.u32() as i32)
    }

    pub fn get_boolean(&mut self, vrs: &[u32], out: &mut [i32]) -> Result<(), Fmi2Error> {
        self.get_values(GET_BOOLEAN, vrs, out, |r| r.u32() as i32)
    }

    pub fn get_string(&mut self, vrs: &[u32], out: &mut [CString]) -> Result<(), Fmi2Error> {
        self.get_values(GET_STRING, vrs, out, |r| r.cstring())
    }

    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), Fmi2Error> {
        self.set_values(SET_REAL, vrs, values.len(), |w| w.f64s(values))
    }

    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), Fmi2Error> {
        self.set_values(SET_INTEGER, vrs, values.len(), |w| w.i32s(values))
    }

    pub fn set_boolean(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), Fmi2Error> {
        self.set_values(SET_BOOLEAN, vrs, values.len(), |w| w.i32s(values))
    }

    pub fn set_string(&mut self, vrs: &[u32], values: &[CString]) -> Result<(), Fmi2Error> {
        self.set_values(SET_STRING, vrs, values.len(), |w| {
            w.u32(values.len() as u32)?;
            values.iter().try_for_each(|s| w.blob(s.as_bytes()))
        })
    }

    fn state_call(&mut self, op: u8, s: Option<&FmuState>) -> Result<FmuState, Fmi2Error> {
        let idx = s.map_or(u32::MAX, |s| s.0 as u32);
        self.state_answer(op, |w| w.u32(idx))
    }

    /// A call (`op`, its arguments written by `args`) answered with an FMU state of the child's.
    fn state_answer(
        &mut self,
        op: u8,
        args: impl FnOnce(&mut W) -> Result<(), Fmi2Error>,
    ) -> Result<FmuState, Fmi2Error> {
        let mut got = 0;
        self.call(op, self.time, args, |r| {
            got = r.u32() as usize;
            Ok(())
        })?;
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
        self.state_answer(DESERIALIZE, |w| w.blob(bytes))
    }

    pub fn get_output_derivatives(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), Fmi2Error> {
        self.get_values(OUTPUT_DERIVATIVES, vrs, out, |r| r.f64())
    }

    pub fn set_input_derivatives(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), Fmi2Error> {
        self.set_values(INPUT_DERIVATIVES, vrs, values.len(), |w| w.f64s(values))
    }

    pub fn get_directional_derivative(&mut self, d: Directional) -> Result<(), Fmi2Error> {
        d.check_lengths(Self::lengths)?;
        self.call(
            DIRECTIONAL,
            self.time,
            |w| {
                w.u32s(d.unknowns)?;
                w.u32s(d.knowns)?;
                w.f64s(d.seed)
            },
            |r| {
                d.out.iter_mut().for_each(|x| *x = r.f64());
                Ok(())
            },
        )
    }
}
