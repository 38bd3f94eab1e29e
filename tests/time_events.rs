//! Issue 49: time events fire once, at their scheduled time, whatever clock the importer keeps.
//!
//! FMU Compliance Checker keeps its communication time as `t += h`, as many masters do: with
//! h = 0.02 a step ends at 4.99999999999998, a few round-offs before the time event at 5. The
//! runtime handled the event at the end of that step but told the model `Event::time() =
//! 4.99999999999998`; Stair scheduled `floor(time) + 1 = 5` again, and the next step fired it a
//! second time. These tests drive a sampled model (a time event every `ts`, `k·ts` exactly, or
//! Stair's `floor(time) + 1`) through the C API as importers do — FMI 2.0 and 3.0 co-simulation
//! (3.0 without event mode, with event mode, with event mode and early return) and model
//! exchange — with times summed up (`t += h`), computed (`n·h`), steps of 1/3, pseudo-random
//! steps, and steps that end exactly on, one ulp before and one ulp after an event; and compare
//! every step with the exact schedule.

use rustfmu::testing::thread_log as log2;

mod model {
    use rustfmu::prelude::*;

    /// Samples every `ts` seconds: counts the samples, keeps the time of the last, and counts
    /// the samples that were not at `k·ts` (the k-th sample) — a double-fired event is one.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    pub struct Sampler {
        /// Samples so far (k)
        #[variable(vr = 0, output, discrete, initial = exact, start = 0)]
        pub samples: i32,
        /// Time of the last sample
        #[variable(vr = 1, output, discrete, initial = exact, start = 0.0, unit = "s")]
        pub last_sample: f64,
        /// Samples whose time was not k·ts
        #[variable(vr = 2, output, discrete, initial = exact, start = 0)]
        pub off_schedule: i32,
        /// Sample period
        #[variable(vr = 3, parameter, fixed, start = 0.1, min > 0.0, unit = "s")]
        pub ts: f64,
        /// How the next sample is scheduled: 0 at (k + 1)·ts, 1 as Stair does, at
        /// floor(time) + 1 (ts = 1)
        #[variable(vr = 4, parameter, fixed, start = 0, min = 0, max = 1)]
        pub mode: i32,
        /// A clock that runs with time (x' = 1), so the integrator runs between the events
        #[variable(vr = 5, output, continuous, initial = exact, start = 0.0, unit = "s", depends = [])]
        pub x: f64,
        /// dx/dt
        #[variable(vr = 6, name = "der(x)", local, derivative_of = x, depends = [], initial_depends = [])]
        pub der_x: f64,
    }

    impl Model for Sampler {
        fn derivatives<D: Real>(&self, _t: D, v: &mut SamplerContinuous<D>) {
            v.der_x = v.x * 0.0 + 1.0;
        }

        fn update(&mut self, event: &mut Event) -> Result<(), String> {
            if event.time_event() {
                self.samples += 1;
                self.last_sample = event.time();
                if event.time() != f64::from(self.samples) * self.ts {
                    self.off_schedule += 1;
                }
            }
            if event.initial() || event.time_event() {
                match self.mode {
                    0 => event.schedule(f64::from(self.samples + 1) * self.ts),
                    _ => event.schedule(event.time().floor() + 1.0),
                }
            }
            Ok(())
        }
    }

    impl CoSimulation for Sampler {}

    rustfmu::export_fmu!(Sampler);
}

mod fmi2 {
    pub use super::model::__rustfmu_fmi2_exports::*;
    pub use rustfmu::__private::abi::*;
}
mod fmi3 {
    pub use super::model::__rustfmu_fmi3_exports::*;
    pub use rustfmu::__private::abi3::*;
}

const SAMPLES: u32 = 0;
const LAST_SAMPLE: u32 = 1;
const OFF_SCHEDULE: u32 = 2;
const TS: u32 = 3;
const MODE: u32 = 4;

/// How the importer computes its communication points.
#[derive(Debug, Clone, Copy)]
enum Clock {
    /// t += h, as FMU Compliance Checker and many masters do.
    Summed(f64),
    /// t = n·h, as fmusim does.
    Multiplied(f64),
    /// Pseudo-random step sizes in (0.2 h, 1.8 h), summed (a fixed seed: the same every run).
    Random(f64),
}

impl Clock {
    /// The communication points after the start, up to `stop`.
    fn points(self, stop: f64) -> Vec<f64> {
        let mut out = Vec::new();
        match self {
            Clock::Summed(h) => {
                let mut t = 0.0;
                while t + h <= stop + 1e-9 {
                    t += h;
                    out.push(t);
                }
            }
            Clock::Multiplied(h) => {
                let mut n = 1.0;
                while n * h <= stop + 1e-9 {
                    out.push(n * h);
                    n += 1.0;
                }
            }
            Clock::Random(h) => {
                // splitmix64, seeded once: a reproducible sequence of steps.
                let mut state = 0x9E37_79B9_7F4A_7C15u64;
                let mut t = 0.0;
                loop {
                    state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
                    let mut z = state;
                    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                    z ^= z >> 31;
                    let u = (z >> 11) as f64 / (1u64 << 53) as f64;
                    t += h * (0.2 + 1.6 * u);
                    if t > stop {
                        break;
                    }
                    out.push(t);
                }
            }
        }
        out
    }
}

/// The exact schedule: sample k at k·ts.
fn schedule(ts: f64, k: i32) -> f64 {
    f64::from(k) * ts
}

/// What one importer loop saw after each communication point: (the point, samples, last
/// sample, samples off schedule).
type Seen = Vec<(f64, i32, f64, i32)>;

/// Checks a run against the exact schedule: after each communication point `t` the samples are
/// those due up to `t` (a sample within the runtime's round-off window before `t`, or after it,
/// may count at this point or the next, never at both); each sample at k·ts exactly; none twice.
fn check(what: &str, ts: f64, seen: &Seen) {
    let mut before = 0;
    let mut t_before = 0.0;
    for &(t, samples, last, off) in seen {
        // The window is generous (1e-9 of the step, as the runtime's), so that only a sample
        // within round-off of a communication point may count on either side of it.
        let window = 1e-9 * (t - t_before).abs().max(1e-3);
        let surely = (1..).take_while(|&k| schedule(ts, k) < t - window).count() as i32;
        let maybe = (1..).take_while(|&k| schedule(ts, k) <= t + window).count() as i32;
        assert!(
            (surely..=maybe).contains(&samples),
            "{what}: at t = {t:?}: {samples} samples, the schedule has {surely}..={maybe}"
        );
        assert!(
            samples >= before,
            "{what}: at t = {t:?} the samples went back: {before} -> {samples}"
        );
        assert_eq!(
            off, 0,
            "{what}: at t = {t:?}: {off} samples not at k·ts (a time event fired twice)"
        );
        if samples > 0 {
            assert_eq!(
                last.to_bits(),
                schedule(ts, samples).to_bits(),
                "{what}: at t = {t:?}: sample {samples} at {last:?}, scheduled at {:?}",
                schedule(ts, samples)
            );
        }
        before = samples;
        t_before = t;
    }
    let (t_end, samples, _, _) = *seen.last().expect("a run of at least one step");
    let due = (1..).take_while(|&k| schedule(ts, k) <= t_end + 1e-9).count() as i32;
    assert!(
        samples == due || samples == due - 1,
        "{what}: {samples} samples by t = {t_end:?}, {due} scheduled"
    );
}

// ---------------------------------------------------------------------------------------------
// FMI 2.0

/// The last message logged on this thread.
fn last2() -> String {
    log2().texts().last().map(|(_, m)| m.clone()).unwrap_or_default()
}

/// An FMI 2.0 instance of `kind`, its period and mode set, initialized.
fn instance2(kind: fmi2::fmi2Type, ts: f64, mode: i32) -> fmi2::fmi2Component {
    use fmi2::*;
    let c = rustfmu::testing::fmi2::instance(fmi2Instantiate, GUID, kind, c"sampler", log2());
    // SAFETY: a live instance; one reference, one value.
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
        assert_eq!(fmi2SetReal(c, &TS, 1, &ts), fmi2OK);
        assert_eq!(fmi2SetInteger(c, &MODE, 1, &mode), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
        c
    }
}

fn read2(c: fmi2::fmi2Component, t: f64) -> (f64, i32, f64, i32) {
    use fmi2::*;
    let (mut samples, mut off, mut last) = (0, 0, f64::NAN);
    // SAFETY: a live instance, one slot each.
    unsafe {
        assert_eq!(fmi2GetInteger(c, &SAMPLES, 1, &mut samples), fmi2OK);
        assert_eq!(fmi2GetInteger(c, &OFF_SCHEDULE, 1, &mut off), fmi2OK);
        assert_eq!(fmi2GetReal(c, &LAST_SAMPLE, 1, &mut last), fmi2OK);
    }
    (t, samples, last, off)
}

/// FMI 2.0 co-simulation over the communication points.
fn run_cs2(ts: f64, mode: i32, points: &[f64]) -> Seen {
    use fmi2::*;
    let c = instance2(fmi2CoSimulation, ts, mode);
    let mut t = 0.0;
    let mut seen = Seen::new();
    for &next in points {
        // SAFETY: a live instance.
        let status = unsafe { fmi2DoStep(c, t, next - t, fmi2True) };
        assert_eq!(status, fmi2OK, "fmi2DoStep({t:?}, {:?}): {}", next - t, last2());
        t = next;
        seen.push(read2(c, t));
    }
    // SAFETY: a live instance, freed once.
    unsafe { fmi2FreeInstance(c) };
    seen
}

fn new_discrete_states2(c: fmi2::fmi2Component) -> fmi2::fmi2EventInfo {
    use fmi2::*;
    let mut info = fmi2EventInfo {
        newDiscreteStatesNeeded: fmi2True,
        terminateSimulation: fmi2False,
        nominalsOfContinuousStatesChanged: fmi2False,
        valuesOfContinuousStatesChanged: fmi2False,
        nextEventTimeDefined: fmi2False,
        nextEventTime: 0.0,
    };
    while info.newDiscreteStatesNeeded == fmi2True {
        // SAFETY: a live instance, a writable event info.
        assert_eq!(unsafe { fmi2NewDiscreteStates(c, &mut info) }, fmi2OK, "{}", last2());
    }
    info
}

/// How a model-exchange importer meets a time event.
#[derive(Debug, Clone, Copy)]
enum MeLoop {
    /// Its step ends at nextEventTime exactly where that comes first (fmpy, fmuCheck).
    StopsAtEvent,
    /// It keeps its own points and enters Event Mode at the first at or after nextEventTime.
    AfterEvent,
    /// It enters Event Mode where its time is within 1e-12 of nextEventTime, before it too.
    Tolerant,
}

/// Whether a model-exchange importer that keeps time `t` enters Event Mode for `te`; `again`:
/// it was in Event Mode at `t` already (the tolerant importer enters early once, then waits
/// for its time to reach the event: FMI 3.0, 2.3.5, has the FMU handle a time event in Event
/// Mode "at or after nextEventTime").
fn reached(how: MeLoop, t: f64, te: Option<f64>, again: bool) -> bool {
    match (how, te) {
        (_, None) => false,
        (MeLoop::Tolerant, Some(te)) if !again => t >= te - 1e-12,
        (_, Some(te)) => t >= te,
    }
}

/// FMI 2.0 model exchange over the communication points (explicit Euler, nothing to integrate
/// but the clock x), the importer's time as `how` says.
fn run_me2(ts: f64, mode: i32, points: &[f64], how: MeLoop) -> Seen {
    use fmi2::*;
    let c = instance2(fmi2ModelExchange, ts, mode);
    let mut info = new_discrete_states2(c);
    // SAFETY: a live instance.
    assert_eq!(unsafe { fmi2EnterContinuousTimeMode(c) }, fmi2OK);
    let mut t;
    let mut seen = Seen::new();
    for &point in points {
        loop {
            let te = (info.nextEventTimeDefined == fmi2True).then_some(info.nextEventTime);
            let next = match (how, te) {
                (MeLoop::StopsAtEvent, Some(te)) if te <= point => te,
                _ => point,
            };
            // SAFETY: a live instance.
            assert_eq!(unsafe { fmi2SetTime(c, next) }, fmi2OK, "{}", last2());
            t = next;
            let (mut enter, mut terminate) = (fmi2False, fmi2False);
            // SAFETY: a live instance, two writable flags.
            let status = unsafe { fmi2CompletedIntegratorStep(c, fmi2True, &mut enter, &mut terminate) };
            assert_eq!(status, fmi2OK);
            // Every event due by now, one Event Mode each (several fall into one long step).
            let mut again = false;
            while reached(
                how,
                t,
                (info.nextEventTimeDefined == fmi2True).then_some(info.nextEventTime),
                again,
            ) {
                again = true;
                // SAFETY: a live instance.
                assert_eq!(unsafe { fmi2EnterEventMode(c) }, fmi2OK);
                info = new_discrete_states2(c);
                // SAFETY: a live instance.
                assert_eq!(unsafe { fmi2EnterContinuousTimeMode(c) }, fmi2OK);
            }
            if next == point {
                break;
            }
        }
        seen.push(read2(c, t));
    }
    // SAFETY: a live instance, freed once.
    unsafe { fmi2FreeInstance(c) };
    seen
}

// ---------------------------------------------------------------------------------------------
// FMI 3.0

type Log3 = &'static rustfmu::testing::Log;

fn last3(log: Log3) -> String {
    log.last()
}

/// How an FMI 3.0 co-simulation importer is instantiated.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Cs3 {
    /// eventModeUsed = false: the FMU handles every event.
    NoEventMode,
    /// eventModeUsed = true, earlyReturnAllowed = false: the events inside a step are the FMU's,
    /// one at the step's end is the importer's (eventHandlingNeeded).
    EventMode,
    /// eventModeUsed = true, earlyReturnAllowed = true: the step returns at each event.
    EarlyReturn,
    /// As `EventMode`, but the importer never enters the Event Mode a step asks for (against
    /// the standard): the event left at a step's end happens at the next step's start.
    EventModeIgnored,
}

fn instance3(cs: Option<Cs3>, ts: f64, mode: i32) -> (fmi3::fmi3Instance, Log3) {
    use fmi3::*;
    let log: Log3 = rustfmu::testing::Log::leak();
    let how = rustfmu::testing::fmi3::Instantiation {
        event_mode_used: cs.is_some_and(|cs| cs != Cs3::NoEventMode),
        early_return_allowed: cs == Some(Cs3::EarlyReturn),
        ..rustfmu::testing::fmi3::Instantiation::new("sampler")
    };
    let c = match cs {
        Some(_) => how.co_simulation(fmi3InstantiateCoSimulation, TOKEN, log, None),
        None => how.model_exchange(fmi3InstantiateModelExchange, TOKEN, log),
    };
    assert!(!c.is_null(), "{:?}", log.messages());
    // SAFETY: a live instance, one value each.
    unsafe {
        assert_eq!(fmi3SetFloat64(c, &TS, 1, &ts, 1), fmi3OK);
        assert_eq!(fmi3SetInt32(c, &MODE, 1, &mode, 1), fmi3OK);
        assert_eq!(fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0), fmi3OK);
        assert_eq!(fmi3ExitInitializationMode(c), fmi3OK, "{}", last3(log));
    }
    (c, log)
}

fn read3(c: fmi3::fmi3Instance, t: f64) -> (f64, i32, f64, i32) {
    use fmi3::*;
    let (mut samples, mut off, mut last) = (0, 0, f64::NAN);
    // SAFETY: a live instance, one slot each.
    unsafe {
        assert_eq!(fmi3GetInt32(c, &SAMPLES, 1, &mut samples, 1), fmi3OK);
        assert_eq!(fmi3GetInt32(c, &OFF_SCHEDULE, 1, &mut off, 1), fmi3OK);
        assert_eq!(fmi3GetFloat64(c, &LAST_SAMPLE, 1, &mut last, 1), fmi3OK);
    }
    (t, samples, last, off)
}

/// fmi3UpdateDiscreteStates until it settles: nextEventTime, if defined.
fn update3(c: fmi3::fmi3Instance, log: Log3) -> Option<f64> {
    use fmi3::*;
    loop {
        let (mut again, mut terminate, mut nominals, mut values, mut defined, mut te) =
            (false, false, false, false, false, 0.0);
        // SAFETY: a live instance, six writable outputs.
        let status = unsafe {
            fmi3UpdateDiscreteStates(
                c,
                &mut again,
                &mut terminate,
                &mut nominals,
                &mut values,
                &mut defined,
                &mut te,
            )
        };
        assert_eq!(status, fmi3OK, "{}", last3(log));
        if !again {
            return defined.then_some(te);
        }
    }
}

/// What the importer saw, how many steps ended with eventHandlingNeeded, and in how many of
/// those Event Modes the sample happened (rather than inside the step before).
fn run_cs3(cs: Cs3, ts: f64, mode: i32, points: &[f64]) -> (Seen, usize, usize) {
    use fmi3::*;
    let (c, log) = instance3(Some(cs), ts, mode);
    if cs != Cs3::NoEventMode {
        update3(c, log);
        // SAFETY: a live instance.
        assert_eq!(unsafe { fmi3EnterStepMode(c) }, fmi3OK, "{}", last3(log));
    }
    let mut t = 0.0;
    let (mut handed, mut sampled_in_event_mode) = (0, 0);
    let mut seen = Seen::new();
    for &point in points {
        // With early return the step may end before the point: go on from where it ended.
        while t < point {
            let (mut event, mut terminate, mut early, mut last) = (false, false, false, f64::NAN);
            let status =
                // SAFETY: a live instance, four writable outputs.
                unsafe { fmi3DoStep(c, t, point - t, true, &mut event, &mut terminate, &mut early, &mut last) };
            assert_eq!(status, fmi3OK, "fmi3DoStep({t:?}, {:?}): {}", point - t, last3(log));
            assert!(!terminate);
            match cs {
                Cs3::NoEventMode => assert!(!event && !early, "without event mode: {event} {early}"),
                Cs3::EventMode | Cs3::EventModeIgnored => assert!(!early, "early return not allowed"),
                Cs3::EarlyReturn => assert_eq!(early, last < point, "earlyReturn {early} at {last:?}"),
            }
            if early {
                assert!(event, "an early return here is for an event");
                t = last;
            } else {
                // The importer keeps its own time (t += h), not lastSuccessfulTime.
                assert_eq!(
                    last.to_bits(),
                    point.to_bits(),
                    "lastSuccessfulTime {last:?}, step to {point:?}"
                );
                t = point;
            }
            if event && cs != Cs3::EventModeIgnored {
                handed += 1;
                let before = read3(c, t).1;
                // SAFETY: a live instance.
                assert_eq!(unsafe { fmi3EnterEventMode(c) }, fmi3OK, "{}", last3(log));
                update3(c, log);
                if read3(c, t).1 > before {
                    sampled_in_event_mode += 1;
                }
                // SAFETY: a live instance.
                assert_eq!(unsafe { fmi3EnterStepMode(c) }, fmi3OK, "{}", last3(log));
            }
        }
        seen.push(read3(c, t));
    }
    // SAFETY: a live instance, freed once.
    unsafe { fmi3FreeInstance(c) };
    (seen, handed, sampled_in_event_mode)
}

/// FMI 3.0 model exchange, as [`run_me2`].
fn run_me3(ts: f64, mode: i32, points: &[f64], how: MeLoop) -> Seen {
    use fmi3::*;
    let (c, log) = instance3(None, ts, mode);
    let mut te = update3(c, log);
    // SAFETY: a live instance.
    assert_eq!(unsafe { fmi3EnterContinuousTimeMode(c) }, fmi3OK);
    let mut t;
    let mut seen = Seen::new();
    for &point in points {
        loop {
            let next = match (how, te) {
                (MeLoop::StopsAtEvent, Some(te)) if te <= point => te,
                _ => point,
            };
            // SAFETY: a live instance.
            assert_eq!(unsafe { fmi3SetTime(c, next) }, fmi3OK, "{}", last3(log));
            t = next;
            let (mut enter, mut terminate) = (false, false);
            // SAFETY: a live instance, two writable flags.
            let status = unsafe { fmi3CompletedIntegratorStep(c, true, &mut enter, &mut terminate) };
            assert_eq!(status, fmi3OK);
            let mut again = false;
            while reached(how, t, te, again) {
                again = true;
                // SAFETY: a live instance.
                assert_eq!(unsafe { fmi3EnterEventMode(c) }, fmi3OK);
                te = update3(c, log);
                // SAFETY: a live instance.
                assert_eq!(unsafe { fmi3EnterContinuousTimeMode(c) }, fmi3OK);
            }
            if next == point {
                break;
            }
        }
        seen.push(read3(c, t));
    }
    // SAFETY: a live instance, freed once.
    unsafe { fmi3FreeInstance(c) };
    seen
}

// ---------------------------------------------------------------------------------------------
// The runs

/// The step sizes of the issue, each as the three clocks.
fn clocks() -> Vec<Clock> {
    let mut out = Vec::new();
    for h in [0.01, 0.02, 0.03, 0.05, 0.1, 1.0 / 3.0] {
        out.extend([Clock::Summed(h), Clock::Multiplied(h), Clock::Random(h)]);
    }
    out
}

/// Every interface over `points`, checked against the schedule of (ts, mode).
fn every_interface(label: &str, ts: f64, mode: i32, points: &[f64]) {
    check(&format!("{label}: FMI 2.0 CS"), ts, &run_cs2(ts, mode, points));
    for cs in [
        Cs3::NoEventMode,
        Cs3::EventMode,
        Cs3::EarlyReturn,
        Cs3::EventModeIgnored,
    ] {
        let (seen, handed, _) = run_cs3(cs, ts, mode, points);
        check(&format!("{label}: FMI 3.0 CS {cs:?}"), ts, &seen);
        if cs == Cs3::NoEventMode {
            assert_eq!(handed, 0);
        }
    }
    for how in [MeLoop::StopsAtEvent, MeLoop::AfterEvent, MeLoop::Tolerant] {
        check(
            &format!("{label}: FMI 2.0 ME {how:?}"),
            ts,
            &run_me2(ts, mode, points, how),
        );
        check(
            &format!("{label}: FMI 3.0 ME {how:?}"),
            ts,
            &run_me3(ts, mode, points, how),
        );
    }
}

#[test]
fn stair_counts_each_second_once_at_every_step_size_and_clock() {
    // Stair's schedule (floor(time) + 1), 20 s: the counter that went 6, 7, 9 at h = 0.02.
    for clock in clocks() {
        every_interface(&format!("Stair, {clock:?}"), 1.0, 1, &clock.points(20.0));
    }
}

#[test]
fn a_sampled_controller_samples_each_period_once_over_thousands_of_samples() {
    // k·0.01 for 30 s: 3,000 samples, every communication point near one.
    for clock in clocks() {
        every_interface(&format!("ts = 0.01, {clock:?}"), 0.01, 0, &clock.points(30.0));
    }
    // A period no step size divides: the events fall anywhere inside the steps.
    for clock in [Clock::Summed(0.02), Clock::Summed(1.0 / 3.0), Clock::Random(0.05)] {
        every_interface(&format!("ts = 0.07, {clock:?}"), 0.07, 0, &clock.points(30.0));
    }
}

#[test]
fn steps_that_end_on_an_event_one_ulp_before_it_and_one_ulp_after_it() {
    // Events at 1, 2, 3, ...: the points sit exactly on, just before and just after them.
    let mut points = Vec::new();
    for k in 1..=12 {
        let te = f64::from(k);
        points.push(match k % 3 {
            0 => te,
            1 => te.next_down(),
            _ => te.next_up(),
        });
        points.push(te + 0.5);
    }
    every_interface("ulps around 1 s", 1.0, 0, &points);
    every_interface("ulps around 1 s, Stair", 1.0, 1, &points);
    // The same at 0.1 s (0.30000000000000004 and its neighbours).
    let points: Vec<f64> = (1..=60)
        .flat_map(|k| {
            let te = f64::from(k) * 0.1;
            [te.next_down(), te, te.next_up(), te + 0.05]
        })
        .collect();
    every_interface("ulps around 0.1 s", 0.1, 0, &points);
}

#[test]
fn event_mode_without_early_return_ends_each_step_with_an_event_in_event_mode() {
    // Without early return the step cannot end before its end. An event inside it is handled
    // there (the FMI guide's "mitigative internal event handling"; the Reference-FMUs do so too)
    // and the step ends with eventHandlingNeeded, so that the importer's Event Mode sees the
    // discrete changes at the communication point (the FMI guide: "It will indicate the event as
    // usual through eventHandlingNeeded"); an event at the step's end (within round-off: t += h)
    // is left unhandled for that Event Mode (FMI 3.0, fmi3DoStep: "an event was encountered by
    // the FMU at lastSuccessfulTime"). Stair with h = 0.5: the seconds end every other step.
    let points = Clock::Summed(0.5).points(9.0);
    let (seen, handed, in_event_mode) = run_cs3(Cs3::EventMode, 1.0, 1, &points);
    check("Stair, h = 0.5, event mode", 1.0, &seen);
    assert_eq!(
        (handed, in_event_mode),
        (9, 9),
        "each second at a step's end, counted in Event Mode"
    );
    // h = 0.3: the seconds fall inside the steps (0.9 -> 1.2, ...), except 3, 6, 9 at their
    // ends (0.3 summed ten times is 3.0000000000000004: within round-off).
    let points = Clock::Summed(0.3).points(9.0);
    let (seen, handed, in_event_mode) = run_cs3(Cs3::EventMode, 1.0, 1, &points);
    check("Stair, h = 0.3, event mode", 1.0, &seen);
    assert_eq!(
        (handed, in_event_mode),
        (9, 3),
        "every step with a second ends in Event Mode; 3, 6 and 9 are counted there"
    );
    // Without event mode nothing is handed over; with early return every event, where it is.
    let (seen, handed, _) = run_cs3(Cs3::NoEventMode, 1.0, 1, &points);
    check("Stair, h = 0.3, no event mode", 1.0, &seen);
    assert_eq!(handed, 0);
    let (seen, handed, in_event_mode) = run_cs3(Cs3::EarlyReturn, 1.0, 1, &points);
    check("Stair, h = 0.3, early return", 1.0, &seen);
    assert_eq!((handed, in_event_mode), (9, 9));
}
