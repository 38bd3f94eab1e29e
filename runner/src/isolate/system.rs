//! A whole system in one child process: [`SystemProcess`] (the parent's side, a run as
//! [`crate::Simulation::run`]) and [`serve_system`] (`rustfmu-runner serve-system`).

use super::options::{Isolation, SystemInfo};
use super::serve::watch_parent;
use super::wire::*;
use crate::Error;
use crate::common::Fmi2Error;
use crate::instance::InstanceCS;
use std::path::{Path, PathBuf};
use std::process::Child;
use std::sync::atomic::Ordering::*;
use std::time::{Duration, Instant};

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
    /// The components run with Event Mode ([`crate::Simulation::use_event_mode`]).
    event_mode: Vec<String>,
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
    /// Starts the child of the SSP file `ssp` (`jacobi`: that evaluation order; `event_mode`:
    /// the components it runs with Event Mode).
    pub fn spawn(iso: Isolation, ssp: &Path, jacobi: bool, event_mode: &[String]) -> Result<SystemProcess, Error> {
        let (child, shm) = Self::start(&iso, ssp, jacobi, event_mode)?;
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
            event_mode: event_mode.to_vec(),
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
    fn start(iso: &Isolation, ssp: &Path, jacobi: bool, event_mode: &[String]) -> Result<(Child, Shared), Error> {
        let fail = |m: String| Error::io(format!("{}: isolated: {m}", ssp.display()));
        let (file, path) = shm_file().map_err(fail)?;
        let shm = Shared {
            map: map(&file).map_err(fail)?,
        };
        // Batch 1: load the system (answered with its description).
        shm.header().req.store(1, SeqCst);
        let flag = jacobi.then_some("--jacobi");
        let mut options = vec![("--ssp", ssp.as_os_str())];
        options.extend(event_mode.iter().map(|c| ("--event-mode", c.as_ref())));
        let mut child = start_worker(&iso.worker, "serve-system", &options, &path, flag).map_err(fail)?;
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
            let (child, shm) = Self::start(&self.iso, &self.ssp, self.jacobi, &self.event_mode).map_err(failure)?;
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

/// `rustfmu-runner serve-system`: loads the SSP file (`event_mode`: the components run with
/// Event Mode) and runs it for the parent that started this process, until it says quit or goes
/// away. Returns the process's exit code.
pub fn serve_system(ssp: &Path, shm: &Path, jacobi: bool, event_mode: &[String]) -> i32 {
    let parent = watch_parent();
    let mut shm = match Shared::open(shm) {
        Ok(shm) => shm,
        Err(e) => {
            eprintln!("rustfmu-runner serve-system: {e}");
            return 2;
        }
    };
    let answer = |shm: &mut Shared, seq: u32, len: usize| {
        let h = shm.header();
        h.resp_len.store(len as u32, Relaxed);
        h.done.store(seq, SeqCst);
        if h.parent_sleeps.load(SeqCst) == 1 {
            futex_wake(&h.done);
        }
    };
    let sim = crate::Simulation::from_ssp(ssp).and_then(|mut sim| {
        if jacobi {
            sim.scheme = crate::Scheme::Jacobi;
        }
        event_mode.iter().try_for_each(|c| sim.use_event_mode(c))?;
        Ok(sim)
    });
    let mut sim = match sim {
        Ok(sim) => sim,
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
            if !h.child_sleep(done, parent) {
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
