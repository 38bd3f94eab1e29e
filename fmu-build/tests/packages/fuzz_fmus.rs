//! A time-boxed fuzzer of the packaged FMUs through their C API, all three loaded into this
//! process as a master loads them.
//!
//! Each case instantiates one FMU and makes a random sequence of calls: fmi2SetupExperiment with
//! arbitrary tolerance, start and stop times; arbitrary bit patterns (NaN payloads, subnormals,
//! ±f64::MAX, infinities) as inputs, parameters and start values, also through wrong value
//! references and types; steps of arbitrary size; arbitrary bytes as serialized states (random,
//! and real states with bytes changed, resealed with a correct checksum or not, and states of the
//! other FMUs); arbitrary pointers as FMU states (the other FMUs' live states, freed states,
//! pointers to garbage, made-up addresses); reset, terminate, and calls in every order.
//!
//! The property, checked after every call: no crash (the process lives; no fmi2Fatal), no hang
//! (every call returns within [`CALL_LIMIT`]), no non-finite value under fmi2OK (every Real
//! variable that fmi2GetReal returns with fmi2OK is finite), and every other status comes with a
//! logged message of that status.
//!
//! `RUSTFMU_FUZZ_SECONDS` (default 3) is the time box, `RUSTFMU_FUZZ_SEED` (64 hex digits) the
//! seed of a run to repeat (else `RUSTFMU_SEED`, the u64 tests/run.sh exports for every random
//! test of a run, else the clock); the test prints both and the number of cases
//! (`cargo test --release -p fmu-build --test packages fuzz_fmus -- --nocapture`).

use crate::common::{Fmu, Log};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestError, TestRng, TestRunner};
use rustfmu::__private::abi::*;
use rustfmu::description::VarType;
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// No single call may take longer (the slowest legitimate one, a step that gives up after the
/// integrator's 100 000 internal steps, takes about 0.1 s).
const CALL_LIMIT: Duration = Duration::from_secs(10);

/// The call in progress and since when, for the watchdog: a call that never returns cannot be
/// failed by the test itself, so the watchdog names it and aborts the process.
static IN_PROGRESS: Mutex<Option<(Instant, String)>> = Mutex::new(None);

fn watchdog(seed: String) {
    std::thread::spawn(move || {
        loop {
            std::thread::sleep(Duration::from_secs(1));
            if let Some((since, what)) = &*IN_PROGRESS.lock().unwrap()
                && since.elapsed() > 3 * CALL_LIMIT
            {
                eprintln!(
                    "fuzz: hang: {what} has not returned after {:?} (RUSTFMU_FUZZ_SEED={seed})",
                    since.elapsed()
                );
                std::process::abort();
            }
        }
    });
}

#[derive(Debug, Clone)]
enum Ptr {
    /// The n-th state this case's instance made and still holds.
    Own(usize),
    /// A live state of another FMU.
    Foreign(usize),
    /// A state this case freed.
    Freed(usize),
    /// A pointer to these bytes.
    Garbage(Vec<u8>),
    /// A made-up address (never read through by a correct FMU).
    Address(usize),
}

#[derive(Debug, Clone)]
enum Bytes {
    Random(Vec<u8>),
    /// The instance's own serialized state with bytes xor-ed, then the checksum recomputed or not.
    Mutated {
        flips: Vec<(usize, u8)>,
        reseal: bool,
    },
    /// Another FMU's serialized state.
    Foreign(usize),
}

#[derive(Debug, Clone)]
enum Op {
    /// A value for the n-th variable of that type (or of any type, if there is none).
    SetReal(usize, f64),
    SetInteger(usize, i32),
    SetBoolean(usize, i32),
    /// A Real through an arbitrary value reference.
    SetRealAt(u32, f64),
    /// A step of h from the FMU's time, or from an arbitrary point.
    Step(Option<f64>, f64),
    GetState,
    SetState(Ptr),
    FreeState(Ptr),
    SerializeState(Ptr),
    Deserialize(Bytes),
    Setup(Option<f64>, f64, Option<f64>),
    EnterInit,
    ExitInit,
    Terminate,
    Reset,
}

#[derive(Debug, Clone)]
struct Case {
    fmu: usize,
    setup: (Option<f64>, f64, Option<f64>),
    start: Vec<Op>,
    ops: Vec<Op>,
}

/// Every bit pattern, and the values where formulas break.
fn any_f64() -> impl Strategy<Value = f64> {
    let special = prop::sample::select(vec![
        0.0,
        -0.0,
        f64::MAX,
        -f64::MAX,
        1.7e308,
        -1.7e308,
        f64::MIN_POSITIVE,
        -f64::MIN_POSITIVE,
        5e-324,
        -5e-324,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
        f64::from_bits(0x7ff0_0000_0000_0001),
        f64::from_bits(0xfff8_dead_beef_0001),
        1e-300,
        1e300,
        1e-20,
        1.0,
        -1.0,
    ]);
    prop_oneof![
        3 => any::<u64>().prop_map(f64::from_bits),
        3 => special,
        3 => -10.0..10.0f64,
        1 => (-300i32..300, any::<bool>()).prop_map(|(e, neg)| if neg { -(10f64.powi(e)) } else { 10f64.powi(e) }),
    ]
}

fn step_size() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => prop::sample::select(vec![1e-3, 1e-4, 1e-2, 0.1, 1.0, 1e-9]),
        1 => any_f64(),
    ]
}

fn ptr() -> impl Strategy<Value = Ptr> {
    prop_oneof![
        3 => (0..4usize).prop_map(Ptr::Own),
        2 => (0..6usize).prop_map(Ptr::Foreign),
        2 => (0..4usize).prop_map(Ptr::Freed),
        2 => prop::collection::vec(any::<u8>(), 16..256).prop_map(Ptr::Garbage),
        1 => any::<usize>().prop_map(Ptr::Address),
    ]
}

fn bytes() -> impl Strategy<Value = Bytes> {
    prop_oneof![
        1 => prop::collection::vec(any::<u8>(), 0..300).prop_map(Bytes::Random),
        4 => (prop::collection::vec((any::<usize>(), 1..=255u8), 1..4), any::<bool>())
            .prop_map(|(flips, reseal)| Bytes::Mutated { flips, reseal }),
        1 => (0..3usize).prop_map(Bytes::Foreign),
    ]
}

fn set() -> impl Strategy<Value = Op> {
    prop_oneof![
        6 => (any::<usize>(), any_f64()).prop_map(|(i, x)| Op::SetReal(i, x)),
        1 => (any::<usize>(), prop_oneof![-2..6i32, any::<i32>()]).prop_map(|(i, x)| Op::SetInteger(i, x)),
        1 => (any::<usize>(), prop_oneof![Just(0), Just(1), any::<i32>()]).prop_map(|(i, x)| Op::SetBoolean(i, x)),
        1 => (any::<u32>(), any_f64()).prop_map(|(vr, x)| Op::SetRealAt(vr, x)),
    ]
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        8 => set(),
        10 => (prop::option::weighted(0.1, any_f64()), step_size()).prop_map(|(t, h)| Op::Step(t, h)),
        2 => Just(Op::GetState),
        2 => ptr().prop_map(Op::SetState),
        1 => ptr().prop_map(Op::FreeState),
        1 => ptr().prop_map(Op::SerializeState),
        3 => bytes().prop_map(Op::Deserialize),
        1 => (prop::option::of(any_f64()), any_f64(), prop::option::of(any_f64()))
            .prop_map(|(tol, t0, stop)| Op::Setup(tol, t0, stop)),
        1 => Just(Op::EnterInit),
        1 => Just(Op::ExitInit),
        1 => Just(Op::Terminate),
        1 => Just(Op::Reset),
    ]
}

fn case() -> impl Strategy<Value = Case> {
    let setup = (
        prop::option::weighted(0.3, any_f64()),
        prop_oneof![4 => Just(0.0), 1 => any_f64()],
        prop::option::weighted(0.2, any_f64()),
    );
    (
        0..3usize,
        setup,
        prop::collection::vec(set(), 0..6),
        prop::collection::vec(op(), 1..40),
    )
        .prop_map(|(fmu, setup, start, ops)| Case { fmu, setup, start, ops })
}

/// What the other FMUs contribute: a live state and its serialized form each.
struct Pool {
    states: Vec<(usize, fmi2FMUstate)>,
    serialized: Vec<(usize, Vec<u8>)>,
}

fn pool(fmus: &[Fmu]) -> Pool {
    let mut states = Vec::new();
    let mut serialized = Vec::new();
    for (k, fmu) in fmus.iter().enumerate() {
        let (c, _) = fmu.instance(false);
        // SAFETY: c is a live instance of fmu; it lives (with its states) to the end of the test.
        unsafe {
            assert_eq!((fmu.enter_init)(c), fmi2OK);
            assert_eq!((fmu.exit_init)(c), fmi2OK);
            assert_eq!((fmu.do_step)(c, 0.0, 1e-3, fmi2True), fmi2OK);
            for _ in 0..2 {
                let mut s: fmi2FMUstate = std::ptr::null_mut();
                assert_eq!((fmu.get_state)(c, &mut s), fmi2OK);
                states.push((k, s));
            }
        }
        serialized.push((k, fmu.serialized(c)));
    }
    Pool { states, serialized }
}

/// Counts for the report.
#[derive(Default)]
struct Tally {
    cases: [u64; 3],
    calls: BTreeMap<&'static str, [u64; 5]>,
}

/// One case's instance and what it holds.
struct Run<'a> {
    fmu: &'a Fmu,
    c: fmi2Component,
    log: &'static Log,
    own: Vec<fmi2FMUstate>,
    freed: Vec<fmi2FMUstate>,
    garbage: Vec<Box<[u8]>>,
    reals: Vec<u32>,
    tally: &'a RefCell<Tally>,
    /// The operation being made, for the watchdog's message.
    current: Op,
}

fn status_name(s: fmi2Status) -> &'static str {
    ["fmi2OK", "fmi2Warning", "fmi2Discard", "fmi2Error", "fmi2Fatal"]
        .get(s as usize)
        .copied()
        .unwrap_or("(not a status)")
}

impl Run<'_> {
    /// Makes one call and checks the property around it.
    fn call(
        &mut self,
        name: &'static str,
        f: impl FnOnce(&mut Self) -> fmi2Status,
    ) -> Result<fmi2Status, TestCaseError> {
        self.log.take_texts();
        let started = Instant::now();
        *IN_PROGRESS.lock().unwrap() = Some((started, format!("{} {name} in {:?}", self.fmu.name, self.current)));
        let s = f(self);
        let took = started.elapsed();
        *IN_PROGRESS.lock().unwrap() = None;
        let log = self.log.take_texts();
        if let Some(n) = self
            .tally
            .borrow_mut()
            .calls
            .entry(name)
            .or_default()
            .get_mut(s as usize)
        {
            *n += 1;
        }
        prop_assert!(took < CALL_LIMIT, "{} {name} took {took:?}", self.fmu.name);
        prop_assert!(
            s <= fmi2Error,
            "{} {name} returned {}: {log:?}",
            self.fmu.name,
            status_name(s)
        );
        if s != fmi2OK {
            prop_assert!(
                log.iter().any(|(logged, _)| *logged == s),
                "{} {name} returned {} without a message of that status: {log:?}",
                self.fmu.name,
                status_name(s)
            );
        }
        self.outputs_are_finite(name)?;
        Ok(s)
    }

    /// Every Real variable, when fmi2GetReal answers fmi2OK, is finite.
    fn outputs_are_finite(&mut self, after: &str) -> Result<(), TestCaseError> {
        let mut values = vec![0.0; self.reals.len()];
        // SAFETY: a live instance; as many references as slots.
        let s = unsafe { (self.fmu.get_real)(self.c, self.reals.as_ptr(), self.reals.len(), values.as_mut_ptr()) };
        let log = self.log.take_texts();
        if s == fmi2OK {
            let bad: Vec<String> = self
                .fmu
                .md
                .variables
                .iter()
                .filter(|v| v.var_type == VarType::Real)
                .zip(&values)
                .filter(|(_, x)| !x.is_finite())
                .map(|(v, x)| format!("{} = {x}", v.name))
                .collect();
            prop_assert!(
                bad.is_empty(),
                "{} after {after}: fmi2GetReal returned fmi2OK with {bad:?}",
                self.fmu.name
            );
        } else {
            prop_assert!(
                log.iter().any(|(logged, _)| *logged == s),
                "{}: fmi2GetReal after {after} returned {} without a message: {log:?}",
                self.fmu.name,
                status_name(s)
            );
        }
        Ok(())
    }

    fn pointer(&mut self, p: &Ptr, pool: &Pool, k: usize) -> fmi2FMUstate {
        match p {
            Ptr::Own(i) if !self.own.is_empty() => self.own[i % self.own.len()],
            Ptr::Freed(i) if !self.freed.is_empty() => self.freed[i % self.freed.len()],
            Ptr::Foreign(i) => {
                let others: Vec<fmi2FMUstate> = pool.states.iter().filter(|(f, _)| *f != k).map(|(_, s)| *s).collect();
                others[i % others.len()]
            }
            Ptr::Garbage(bytes) => {
                let mut b = bytes.clone().into_boxed_slice();
                let p = b.as_mut_ptr() as fmi2FMUstate;
                self.garbage.push(b);
                p
            }
            Ptr::Address(a) => *a as fmi2FMUstate,
            Ptr::Own(_) | Ptr::Freed(_) => 0x40usize as fmi2FMUstate,
        }
    }

    /// The variable of type `ty` the index picks (any variable if there is none of that type).
    fn pick(&self, i: usize, ty: VarType) -> u32 {
        let vars = &self.fmu.md.variables;
        let typed: Vec<u32> = vars
            .iter()
            .filter(|v| v.var_type == ty || (ty == VarType::Integer && v.var_type == VarType::Enumeration))
            .map(|v| v.value_reference)
            .collect();
        if typed.is_empty() {
            vars[i % vars.len()].value_reference
        } else {
            typed[i % typed.len()]
        }
    }

    fn time(&self) -> f64 {
        let mut t = 0.0;
        // SAFETY: a live instance; one slot.
        let s = unsafe { (self.fmu.real_status)(self.c, fmi2LastSuccessfulTime, &mut t) };
        self.log.take_texts();
        if s == fmi2OK { t } else { 0.0 }
    }

    fn op(&mut self, op: &Op, pool: &Pool, k: usize) -> Result<(), TestCaseError> {
        let (fmu, c) = (self.fmu, self.c);
        self.current = op.clone();
        // One block for the whole match: every FMI call below is made in it, through a closure
        // that `call` runs at once.
        // SAFETY: c is a live instance of fmu, arrays hold as many elements as passed, and the
        // FMU-state pointers are opaque values the FMU must check.
        unsafe {
            match op {
                Op::SetReal(i, x) => {
                    let vr = self.pick(*i, VarType::Real);
                    self.call("fmi2SetReal", |_| (fmu.set_real)(c, &vr, 1, x))?;
                }
                Op::SetRealAt(vr, x) => {
                    self.call("fmi2SetReal", |_| (fmu.set_real)(c, vr, 1, x))?;
                }
                Op::SetInteger(i, x) => {
                    let vr = self.pick(*i, VarType::Integer);
                    self.call("fmi2SetInteger", |_| (fmu.set_integer)(c, &vr, 1, x))?;
                }
                Op::SetBoolean(i, x) => {
                    let vr = self.pick(*i, VarType::Boolean);
                    self.call("fmi2SetBoolean", |_| (fmu.set_boolean)(c, &vr, 1, x))?;
                }
                Op::Step(t, h) => {
                    let t = t.unwrap_or_else(|| self.time());
                    self.call("fmi2DoStep", |_| (fmu.do_step)(c, t, *h, fmi2True))?;
                }
                Op::GetState => {
                    let mut s: fmi2FMUstate = std::ptr::null_mut();
                    if self.call("fmi2GetFMUstate", |_| (fmu.get_state)(c, &mut s))? == fmi2OK {
                        self.own.push(s);
                    }
                }
                Op::SetState(p) => {
                    let s = self.pointer(p, pool, k);
                    self.call("fmi2SetFMUstate", |_| (fmu.set_state)(c, s))?;
                }
                Op::FreeState(p) => {
                    let mut s = self.pointer(p, pool, k);
                    let before = s;
                    if self.call("fmi2FreeFMUstate", |_| (fmu.free_state)(c, &mut s))? == fmi2OK {
                        prop_assert!(
                            self.own.contains(&before),
                            "{}: fmi2FreeFMUstate freed {before:?}, which is not its own live state",
                            fmu.name
                        );
                        self.own.retain(|o| *o != before);
                        self.freed.push(before);
                    }
                }
                Op::SerializeState(p) => {
                    let s = self.pointer(p, pool, k);
                    let mut n = 0usize;
                    let sized = self.call("fmi2SerializedFMUstateSize", |_| (fmu.state_size)(c, s, &mut n))?;
                    let mut buf = vec![0u8; if sized == fmi2OK { n } else { 64 }];
                    let len = buf.len();
                    self.call("fmi2SerializeFMUstate", |_| {
                        (fmu.serialize)(c, s, buf.as_mut_ptr() as *mut fmi2Byte, len)
                    })?;
                }
                Op::Deserialize(b) => {
                    let bytes = match b {
                        Bytes::Random(v) => v.clone(),
                        Bytes::Foreign(i) => {
                            let others: Vec<&Vec<u8>> = pool
                                .serialized
                                .iter()
                                .filter(|(f, _)| *f != k)
                                .map(|(_, b)| b)
                                .collect();
                            others[i % others.len()].clone()
                        }
                        Bytes::Mutated { flips, reseal } => {
                            let mut own = std::ptr::null_mut();
                            let mut v = Vec::new();
                            // A snapshot of the instance as it is now, taken without the checks.
                            {
                                let mut n = 0;
                                if (fmu.get_state)(c, &mut own) == fmi2OK && (fmu.state_size)(c, own, &mut n) == fmi2OK
                                {
                                    v = vec![0u8; n];
                                    (fmu.serialize)(c, own, v.as_mut_ptr() as *mut fmi2Byte, n);
                                }
                                (fmu.free_state)(c, &mut own);
                            }
                            self.log.take_texts();
                            if !v.is_empty() {
                                for (at, x) in flips {
                                    let n = v.len();
                                    v[at % n] ^= x;
                                }
                                if *reseal && v.len() > 4 {
                                    let n = v.len() - 4;
                                    let crc = crc32fast::hash(&v[..n]);
                                    v[n..].copy_from_slice(&crc.to_le_bytes());
                                }
                            }
                            v
                        }
                    };
                    let mut s: fmi2FMUstate = std::ptr::null_mut();
                    let status = self.call("fmi2DeSerializeFMUstate", |_| {
                        (fmu.deserialize)(c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), &mut s)
                    })?;
                    if status == fmi2OK {
                        self.own.push(s);
                        // A state that was accepted must also be usable.
                        self.call("fmi2SetFMUstate", |_| (fmu.set_state)(c, s))?;
                    }
                }
                Op::Setup(tol, t0, stop) => {
                    let (td, tv) = (tol.is_some() as fmi2Boolean, tol.unwrap_or(0.0));
                    let (sd, sv) = (stop.is_some() as fmi2Boolean, stop.unwrap_or(0.0));
                    self.call("fmi2SetupExperiment", |_| (fmu.setup)(c, td, tv, *t0, sd, sv))?;
                }
                Op::EnterInit => {
                    self.call("fmi2EnterInitializationMode", |_| (fmu.enter_init)(c))?;
                }
                Op::ExitInit => {
                    self.call("fmi2ExitInitializationMode", |_| (fmu.exit_init)(c))?;
                }
                Op::Terminate => {
                    self.call("fmi2Terminate", |_| (fmu.terminate)(c))?;
                }
                Op::Reset => {
                    self.call("fmi2Reset", |_| (fmu.reset)(c))?;
                }
            }
        }
        Ok(())
    }
}

fn run_case(fmus: &[Fmu], pool: &Pool, tally: &RefCell<Tally>, case: &Case) -> Result<(), TestCaseError> {
    let fmu = &fmus[case.fmu];
    tally.borrow_mut().cases[case.fmu] += 1;
    let (c, log) = fmu.instance(false);
    let reals = fmu
        .md
        .variables
        .iter()
        .filter(|v| v.var_type == VarType::Real)
        .map(|v| v.value_reference)
        .collect();
    let mut run = Run {
        fmu,
        c,
        log,
        own: Vec::new(),
        freed: Vec::new(),
        garbage: Vec::new(),
        reals,
        tally,
        current: Op::EnterInit,
    };
    let (tol, t0, stop) = case.setup;
    let mut result = run.op(&Op::Setup(tol, t0, stop), pool, case.fmu);
    for op in [Op::EnterInit]
        .iter()
        .chain(&case.start)
        .chain([&Op::ExitInit])
        .chain(&case.ops)
    {
        if result.is_err() {
            break;
        }
        result = run.op(op, pool, case.fmu);
    }
    // SAFETY: the instance's own live states, then the instance, freed once each.
    unsafe {
        for mut s in std::mem::take(&mut run.own) {
            (fmu.free_state)(c, &mut s);
        }
        (fmu.free_instance)(c);
    }
    result
}

fn seed() -> [u8; 32] {
    if let Ok(hex) = std::env::var("RUSTFMU_FUZZ_SEED") {
        let mut seed = [0u8; 32];
        for (i, b) in seed.iter_mut().enumerate() {
            *b = u8::from_str_radix(hex.get(2 * i..2 * i + 2).expect("64 hex digits"), 16).expect("hex");
        }
        return seed;
    }
    // The run's one seed (tests/run.sh exports it and prints it; the conformance suite's random
    // call sequences take it too).
    if let Ok(s) = std::env::var("RUSTFMU_SEED") {
        let s: u64 = s.trim().parse().expect("RUSTFMU_SEED: a u64");
        let mut seed = [0u8; 32];
        seed[..8].copy_from_slice(&s.to_le_bytes());
        return seed;
    }
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_nanos();
    let mut seed = [0u8; 32];
    seed[..16].copy_from_slice(&nanos.to_le_bytes());
    seed[16..20].copy_from_slice(&std::process::id().to_le_bytes());
    seed
}

#[test]
fn no_call_sequence_crashes_hangs_or_returns_a_non_finite_value_under_fmi2ok() {
    let seconds: f64 = std::env::var("RUSTFMU_FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3.0);
    let seed = seed();
    let seed_hex: String = seed.iter().map(|b| format!("{b:02x}")).collect();
    // Straight to stderr, past the harness's capture: in every log, even if an FMU kills the
    // process before the test ends.
    let _ = std::io::Write::write_all(
        &mut std::io::stderr(),
        format!("fuzz: seed {seed_hex} (repeat with RUSTFMU_FUZZ_SEED={seed_hex})\n").as_bytes(),
    );
    watchdog(seed_hex.clone());
    let fmus = [Fmu::load("Pendulum"), Fmu::load("Controller"), Fmu::load("DCMotor")];
    let pool = pool(&fmus);
    let tally = RefCell::new(Tally::default());
    let config = Config {
        failure_persistence: None,
        max_shrink_iters: 2000,
        ..Config::default()
    };
    let mut runner = TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &seed));
    let strategy = case();
    let deadline = Instant::now() + Duration::from_secs_f64(seconds);
    let started = Instant::now();
    while Instant::now() < deadline {
        let tree = strategy.new_tree(&mut runner).expect("a case");
        if let Err(e) = runner.run_one(tree, |case| run_case(&fmus, &pool, &tally, &case)) {
            let (why, case) = match e {
                TestError::Fail(why, case) => (why.to_string(), format!("{case:#?}")),
                TestError::Abort(why) => (why.to_string(), String::new()),
            };
            panic!("{why}\nminimal case: {case}\n(repeat with RUSTFMU_FUZZ_SEED={seed_hex})");
        }
    }
    let t = tally.borrow();
    let cases: u64 = t.cases.iter().sum();
    let calls: u64 = t.calls.values().flatten().sum();
    eprintln!(
        "fuzz: {cases} cases ({} Pendulum, {} Controller, {} DCMotor), {calls} calls in {:.1} s, seed {seed_hex}",
        t.cases[0],
        t.cases[1],
        t.cases[2],
        started.elapsed().as_secs_f64()
    );
    for (name, [ok, _, discard, error, _]) in &t.calls {
        eprintln!("  {name:30} {ok:8} OK {discard:8} Discard {error:8} Error");
    }
    assert!(cases > 0, "no case ran in {seconds} s");
}
