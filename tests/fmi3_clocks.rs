//! Issue 25: FMI 3.0 clocks (FMI 3.0, 2.2.9) in Model Exchange and in Co-Simulation with event
//! mode: input clocks of every intervalVariability, clocked inputs and outputs, the interval
//! and shift functions, and the refusals the standard asks for. A model exported here with
//! `export_fmi3!`: `count` counts the ticks of `tick` (constant, 0.1 s), `sum` adds the clocked
//! input `u` at each tick of `sample` (fixed: the parameter `Ts`); a tunable clock with a default
//! interval, a countdown clock the model times, and a triggered clock; and a triggered output
//! clock `crossed` that ticks where the state `level` (rising at 1/s) crosses 100 (an event
//! indicator), counting the crossings in the variable it clocks.

use rustfmu::__private::abi3::*;
use rustfmu::testing::{Log, fmi3};

mod model {
    use rustfmu::prelude::*;

    /// Clocks of every kind.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    #[fmu(fmi3_only)]
    pub struct Clocked {
        /// Ticks every 0.1 s
        #[variable(vr = 1, input, clock(constant, interval = 0.1))]
        pub tick: Clock,
        /// Ticks every Ts
        #[variable(vr = 2, input, clock(fixed, interval = Ts))]
        pub sample: Clock,
        /// Sample period
        #[variable(vr = 3, name = "Ts", parameter, fixed, start = 0.25, unit = "s", min > 0.0)]
        pub ts: f64,
        /// Ticks every 0.5 s unless the importer sets another interval, from 0.05
        #[variable(vr = 4, input, clock(tunable, interval = 0.5, shift = 0.05, can_be_deactivated))]
        pub slow: Clock,
        /// The model says when it ticks next: 0.3 s after each tick
        #[variable(vr = 5, input, clock(countdown))]
        pub alarm: Clock,
        /// Ticks when the importer says
        #[variable(vr = 6, input, clock(triggered))]
        pub trigger: Clock,
        /// Ticks of `tick` so far
        #[variable(vr = 10, output, discrete, clocks = [tick], depends = [])]
        pub count: i32,
        /// A clocked input
        #[variable(vr = 11, input, discrete, clocks = [sample], start = 0.0)]
        pub u: f64,
        /// The sum of u over the ticks of `sample`
        #[variable(vr = 12, output, discrete, clocks = [sample], depends = [u])]
        pub sum: f64,
        /// Ticks of `alarm` and `trigger`
        #[variable(vr = 13, output, discrete, clocks = [alarm, trigger])]
        pub alarms: i32,
        /// A level rising at 1/s
        #[variable(vr = 20, output, continuous, initial = exact, start = 0.0, depends = [level])]
        pub level: f64,
        /// Its rate
        #[variable(vr = 21, name = "der(level)", local, continuous, derivative_of = level, depends = [])]
        pub der_level: f64,
        /// level - 100: its change of sign is a state event
        #[variable(vr = 22, local, continuous, event_indicator, depends = [level])]
        pub above: f64,
        /// Ticks where the level rises through 100
        #[variable(vr = 23, output, clock(triggered), depends = [level])]
        pub crossed: Clock,
        /// Crossings so far
        #[variable(vr = 24, output, discrete, clocks = [crossed])]
        pub crossings: i32,
        /// The level was above 100 at the last event.
        pub was_above: bool,
    }

    impl Model for Clocked {
        fn derivatives<D: Real>(&self, _t: D, v: &mut ClockedContinuous<D>) {
            v.der_level = v.level * 0.0 + 1.0;
        }

        fn outputs<D: Real>(&self, _t: D, v: &mut ClockedContinuous<D>) {
            v.above = v.level - 100.0;
        }

        fn initialize(&mut self, _ctx: &Context) -> Result<(), String> {
            self.alarm.set_interval(0.3);
            Ok(())
        }

        fn update(&mut self, _event: &mut Event) -> Result<(), String> {
            if self.tick.is_active() {
                self.count += 1;
            }
            if self.sample.is_active() {
                self.sum += self.u;
            }
            if self.alarm.is_active() {
                self.alarms += 1;
                self.alarm.set_interval(0.3);
            }
            if self.trigger.is_active() {
                self.alarms += 100;
            }
            let above = self.level >= 100.0;
            if above && !self.was_above {
                self.crossed.tick();
                self.crossings += 1;
            }
            self.was_above = above;
            Ok(())
        }
    }

    impl CoSimulation for Clocked {}

    rustfmu::export_fmi3!(Clocked);
}
use model::__rustfmu_fmi3_exports::*;

fn last(l: &Log) -> String {
    l.last()
}

/// A model-exchange instance, initialized at t = 0: in Event Mode.
fn model_exchange() -> (fmi3Instance, &'static Log) {
    let l = Log::leak();
    let c = fmi3::Instantiation {
        logging_on: true,
        ..fmi3::Instantiation::new("clocked")
    }
    .model_exchange(fmi3InstantiateModelExchange, TOKEN, l);
    assert!(!c.is_null());
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0), fmi3OK);
    }
    (c, l)
}

fn exit_init(c: fmi3Instance) {
    // SAFETY: a live instance.
    assert_eq!(unsafe { fmi3ExitInitializationMode(c) }, fmi3OK);
}

/// fmi3UpdateDiscreteStates until done.
fn update(c: fmi3Instance) -> (bool, f64) {
    let (mut again, mut term, mut nom, mut val, mut def, mut next) = (true, false, false, false, false, 0.0);
    while again {
        // SAFETY: a live instance; locals.
        let s = unsafe { fmi3UpdateDiscreteStates(c, &mut again, &mut term, &mut nom, &mut val, &mut def, &mut next) };
        assert_eq!(s, fmi3OK);
    }
    (def, next)
}

fn get_i32(c: fmi3Instance, vr: u32) -> (fmi3Status, i32) {
    let mut x = 0;
    // SAFETY: a live instance; locals.
    (unsafe { fmi3GetInt32(c, &vr, 1, &mut x, 1) }, x)
}

fn get_f64(c: fmi3Instance, vr: u32) -> (fmi3Status, f64) {
    let mut x = 0.0;
    // SAFETY: a live instance; locals.
    (unsafe { fmi3GetFloat64(c, &vr, 1, &mut x, 1) }, x)
}

fn set_clock(c: fmi3Instance, vr: u32, on: bool) -> fmi3Status {
    // SAFETY: a live instance; locals.
    unsafe { fmi3SetClock(c, &vr, 1, &on) }
}

fn interval(c: fmi3Instance, vr: u32) -> (fmi3Status, f64, u32) {
    let (mut h, mut q) = (0.0, 99);
    // SAFETY: a live instance; locals.
    (unsafe { fmi3GetIntervalDecimal(c, &vr, 1, &mut h, &mut q) }, h, q)
}

const UNCHANGED: u32 = 1;
const CHANGED: u32 = 2;

/// Every refusal (fmi3Error) ends an instance's run: each one here gets a fresh instance, in
/// Initialization Mode (`init`) or in the Event Mode after it; the message must say `why`.
fn refused(init: bool, why: &str, call: impl FnOnce(fmi3Instance) -> fmi3Status) {
    let (c, l) = model_exchange();
    if !init {
        exit_init(c);
    }
    assert_eq!(call(c), fmi3Error, "expected a refusal saying '{why}'");
    assert!(last(l).contains(why), "'{}' does not say '{why}'", last(l));
    // SAFETY: a live instance.
    unsafe { fmi3FreeInstance(c) };
}

#[test]
fn intervals_and_shifts_are_answered_per_interval_variability() {
    let (c, _) = model_exchange();
    assert_eq!(interval(c, 1), (fmi3OK, 0.1, UNCHANGED));
    // A fixed clock whose interval is a parameter: "changed" when first read, then unchanged.
    assert_eq!(interval(c, 2), (fmi3OK, 0.25, CHANGED));
    assert_eq!(interval(c, 2), (fmi3OK, 0.25, UNCHANGED));
    assert_eq!(interval(c, 4), (fmi3OK, 0.5, UNCHANGED));
    let (mut s, vr) = (-1.0, 4);
    // SAFETY: a live instance; locals.
    assert_eq!(unsafe { fmi3GetShiftDecimal(c, &vr, 1, &mut s) }, fmi3OK);
    assert_eq!(s, 0.05);
    // The importer sets the tunable clock's interval and shift in Initialization Mode.
    // SAFETY: a live instance; locals.
    unsafe {
        assert_eq!(fmi3SetIntervalDecimal(c, &vr, 1, &0.2), fmi3OK);
        assert_eq!(fmi3SetShiftDecimal(c, &vr, 1, &0.0), fmi3OK);
        assert_eq!(fmi3GetShiftDecimal(c, &vr, 1, &mut s), fmi3OK);
    }
    assert_eq!(s, 0.0);
    assert_eq!(interval(c, 4), (fmi3OK, 0.2, UNCHANGED));
    exit_init(c);
    // The countdown clock: given in initialize, "changed" once, then unchanged.
    assert_eq!(interval(c, 5), (fmi3OK, 0.3, CHANGED));
    assert_eq!(interval(c, 5), (fmi3OK, 0.3, UNCHANGED));
    // SAFETY: a live instance.
    unsafe { fmi3FreeInstance(c) };
    // A constant clock's and a parameter's interval are not the importer's to set.
    refused(
        true,
        "only fixed and tunable clocks with an intervalDecimal",
        // SAFETY: the fresh live instance `refused` passes; the outputs are locals.
        |c| unsafe { fmi3SetIntervalDecimal(c, &1, 1, &0.2) },
    );
    // SAFETY: the fresh live instance `refused` passes; the outputs are locals.
    refused(true, "parameter 'Ts'", |c| unsafe {
        fmi3SetIntervalDecimal(c, &2, 1, &0.2)
    });
    // SAFETY: the fresh live instance `refused` passes; the outputs are locals.
    refused(true, "a finite time > 0", |c| unsafe {
        fmi3SetIntervalDecimal(c, &4, 1, &-1.0)
    });
    // SAFETY: the fresh live instance `refused` passes; the outputs are locals.
    refused(false, "not allowed in state", |c| unsafe {
        fmi3SetShiftDecimal(c, &4, 1, &0.0)
    });
    // Not a clock, a triggered clock's interval, an aperiodic clock's shift, fractions.
    refused(true, "not a Clock", |c| interval(c, 3).0);
    refused(true, "triggered clock", |c| interval(c, 6).0);
    // SAFETY: the fresh live instance `refused` passes; the outputs are locals.
    refused(true, "only periodic clocks", |c| unsafe {
        let mut s = 0.0;
        fmi3GetShiftDecimal(c, &5, 1, &mut s)
    });
    // SAFETY: the fresh live instance `refused` passes; the outputs are locals.
    refused(true, "supportsFraction = false", |c| unsafe {
        let (mut n, mut r, mut q) = (0u64, 0u64, 0u32);
        fmi3GetIntervalFraction(c, &1, 1, &mut n, &mut r, &mut q)
    });
}

#[test]
fn clocked_variables_change_at_their_ticks_only_in_model_exchange() {
    let (c, _) = model_exchange();
    exit_init(c);
    // Event Mode at t = 0: the first ticks of `tick` and `sample`.
    assert_eq!(set_clock(c, 1, true), fmi3OK);
    assert_eq!(set_clock(c, 2, true), fmi3OK);
    let vr = 11;
    // SAFETY: a live instance; locals.
    assert_eq!(unsafe { fmi3SetFloat64(c, &vr, 1, &2.0, 1) }, fmi3OK);
    // Reading a clocked output evaluates the tick; fmi3UpdateDiscreteStates gives that round.
    assert_eq!(get_i32(c, 10), (fmi3OK, 1));
    assert_eq!(get_f64(c, 12), (fmi3OK, 2.0));
    let (defined, _) = update(c);
    assert!(!defined, "time-based ticks are the importer's to schedule");
    // The clocks are inactive after the update.
    let mut clock = true;
    // SAFETY: a live instance; locals.
    assert_eq!(unsafe { fmi3GetClock(c, &1, 1, &mut clock) }, fmi3OK);
    assert!(!clock);
    let next_event = |c: fmi3Instance, t: f64| {
        // SAFETY: a live instance.
        unsafe {
            assert_eq!(fmi3EnterContinuousTimeMode(c), fmi3OK);
            assert_eq!(fmi3SetTime(c, t), fmi3OK);
            assert_eq!(fmi3EnterEventMode(c), fmi3OK);
        }
    };
    // t = 0.1: `tick` only.
    next_event(c, 0.1);
    assert_eq!(set_clock(c, 1, true), fmi3OK);
    update(c);
    // t = 0.25: `sample` with u = 3: the sum 2 + 3.
    next_event(c, 0.25);
    assert_eq!(set_clock(c, 2, true), fmi3OK);
    // SAFETY: a live instance; locals.
    assert_eq!(unsafe { fmi3SetFloat64(c, &vr, 1, &3.0, 1) }, fmi3OK);
    update(c);
    // The triggered clock ticks when told (at any time), the countdown one at 0.3, which
    // gives its next interval there.
    next_event(c, 0.27);
    assert_eq!(set_clock(c, 6, true), fmi3OK);
    assert_eq!(get_i32(c, 13), (fmi3OK, 100));
    update(c);
    next_event(c, 0.3);
    assert_eq!(set_clock(c, 5, true), fmi3OK);
    assert_eq!(get_i32(c, 13), (fmi3OK, 101));
    update(c);
    assert_eq!(interval(c, 5), (fmi3OK, 0.3, CHANGED));
    // t = 0.5: both periodic clocks tick; u was not set since 0.25 (3): the sum 8, the count 3
    // (ticks at 0, 0.1, 0.5: the importer skipped 0.2 .. 0.4, the FMU counts what it is given).
    next_event(c, 0.5);
    assert_eq!(set_clock(c, 1, true), fmi3OK);
    assert_eq!(set_clock(c, 2, true), fmi3OK);
    assert_eq!(get_f64(c, 12), (fmi3OK, 8.0));
    assert_eq!(get_i32(c, 10), (fmi3OK, 3));
    update(c);
    // SAFETY: a live instance.
    unsafe { fmi3FreeInstance(c) };

    // The refusals, each on a fresh instance in the Event Mode after initialization.
    refused(false, "clocked by 'tick', which is not active", |c| get_i32(c, 10).0);
    // SAFETY: the fresh live instance `refused` passes; the outputs are locals.
    refused(false, "clocked by 'sample', which is not active", |c| unsafe {
        fmi3SetFloat64(c, &11, 1, &1.0, 1)
    });
    // A clocked input set after its tick was evaluated (an output it feeds read first): accepted,
    // and the tick evaluated again with it, once (FMI 3.0.2 §3.2.1: inputs set and outputs read
    // "interchangeably according to the model structure"; a set re-initializes what depends on it).
    let (c, _) = model_exchange();
    exit_init(c);
    assert_eq!(set_clock(c, 2, true), fmi3OK);
    // SAFETY: a live instance; locals.
    assert_eq!(unsafe { fmi3SetFloat64(c, &11, 1, &2.0, 1) }, fmi3OK);
    assert_eq!(get_f64(c, 12), (fmi3OK, 2.0), "the tick evaluated with u = 2");
    // SAFETY: a live instance; locals.
    assert_eq!(unsafe { fmi3SetFloat64(c, &11, 1, &5.0, 1) }, fmi3OK);
    assert_eq!(
        get_f64(c, 12),
        (fmi3OK, 5.0),
        "evaluated again with u = 5, not added to the first (7)"
    );
    update(c);
    // SAFETY: a live instance.
    unsafe { fmi3FreeInstance(c) };
    refused(false, "set the clocks, then the clocked inputs", |c| {
        assert_eq!(set_clock(c, 2, true), fmi3OK);
        assert_eq!(get_f64(c, 12).0, fmi3OK);
        set_clock(c, 1, true)
    });
    refused(false, "canBeDeactivated = false", |c| set_clock(c, 1, false));
    // t = 0 is no tick of `slow` (shift 0.05).
    refused(false, "ticks at 0.05 + k * 0.5", |c| set_clock(c, 4, true));
    // SAFETY: the fresh live instance `refused` passes; the outputs are locals.
    refused(false, "not allowed in state", |c| unsafe {
        assert_eq!(fmi3EnterContinuousTimeMode(c), fmi3OK);
        set_clock(c, 1, true)
    });
    // A deactivatable clock may be set inactive.
    let (c, _) = model_exchange();
    exit_init(c);
    assert_eq!(set_clock(c, 4, false), fmi3OK);
    // SAFETY: a live instance.
    unsafe { fmi3FreeInstance(c) };
}

#[test]
fn an_output_clock_ticks_at_the_event_the_model_says_and_its_variables_are_read_there() {
    let (c, _) = model_exchange();
    exit_init(c);
    // The initial event: `crossed` does not tick (fmi3GetClock runs the event's update).
    let mut on = true;
    // SAFETY: a live instance; locals.
    assert_eq!(unsafe { fmi3GetClock(c, &23, 1, &mut on) }, fmi3OK);
    assert!(!on);
    update(c);
    // The importer integrates to the crossing (here: sets the state there) and enters Event Mode.
    // SAFETY: a live instance; locals.
    unsafe {
        assert_eq!(fmi3EnterContinuousTimeMode(c), fmi3OK);
        assert_eq!(fmi3SetTime(c, 100.0), fmi3OK);
        assert_eq!(fmi3SetContinuousStates(c, &100.0, 1), fmi3OK);
        assert_eq!(fmi3EnterEventMode(c), fmi3OK);
        assert_eq!(fmi3GetClock(c, &23, 1, &mut on), fmi3OK);
    }
    assert!(on, "the output clock ticks at the crossing");
    assert_eq!(get_i32(c, 24), (fmi3OK, 1));
    update(c);
    // SAFETY: a live instance; locals.
    assert_eq!(unsafe { fmi3GetClock(c, &23, 1, &mut on) }, fmi3OK);
    assert!(!on, "inactive after fmi3UpdateDiscreteStates");
    // SAFETY: a live instance.
    unsafe { fmi3FreeInstance(c) };
    // The importer does not activate an output clock, and reads its variables where it ticks only.
    refused(false, "is an output clock", |c| set_clock(c, 23, true));
    refused(false, "clocked by 'crossed', which is not active", |c| get_i32(c, 24).0);
    // (An input set after the event was evaluated takes the evaluation back: the clocked input
    // `u` above; this model has no unclocked input.)
}

#[test]
fn an_fmu_state_taken_after_a_tick_was_evaluated_restores_to_one_tick() {
    let (c, _) = model_exchange();
    exit_init(c);
    assert_eq!(set_clock(c, 2, true), fmi3OK);
    // SAFETY: a live instance; locals.
    assert_eq!(unsafe { fmi3SetFloat64(c, &11, 1, &2.0, 1) }, fmi3OK);
    assert_eq!(get_f64(c, 12), (fmi3OK, 2.0), "the tick evaluated: sum = u");
    // The state between the evaluation and the update: restored, the tick is evaluated once more
    // from what it was evaluated from, not added a second time.
    let mut state: fmi3FMUState = std::ptr::null_mut();
    // SAFETY: a live instance; a local state handle.
    assert_eq!(unsafe { fmi3GetFMUState(c, &mut state) }, fmi3OK);
    update(c);
    // SAFETY: a live instance; the state it gave.
    assert_eq!(unsafe { fmi3SetFMUState(c, state) }, fmi3OK);
    assert_eq!(get_f64(c, 12), (fmi3OK, 2.0), "restored: one tick, not two");
    update(c);
    // SAFETY: a live instance; its state.
    unsafe {
        assert_eq!(fmi3FreeFMUState(c, &mut state), fmi3OK);
        fmi3FreeInstance(c);
    }
}

#[test]
fn co_simulation_needs_event_mode_and_ticks_there() {
    let l = Log::leak();
    let instantiate = |event_mode_used: bool| {
        fmi3::Instantiation {
            logging_on: true,
            event_mode_used,
            ..fmi3::Instantiation::new("clocked")
        }
        .co_simulation(fmi3InstantiateCoSimulation, TOKEN, l, None)
    };
    assert!(instantiate(false).is_null(), "clocks need eventModeUsed");
    assert!(last(l).contains("eventModeUsed = true"), "{}", last(l));
    let c = instantiate(true);
    assert!(!c.is_null());
    let (mut event, mut term, mut early, mut at) = (false, false, false, 0.0);
    // SAFETY: a live instance; locals.
    unsafe {
        assert_eq!(fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0), fmi3OK);
        assert_eq!(fmi3ExitInitializationMode(c), fmi3OK);
    }
    let vr = 11;
    let mut t = 0.0;
    for k in 0..4 {
        // Event Mode at each tick of `sample` (0.25 s): u = k + 1.
        assert_eq!(set_clock(c, 2, true), fmi3OK);
        // SAFETY: a live instance; locals.
        assert_eq!(unsafe { fmi3SetFloat64(c, &vr, 1, &(k as f64 + 1.0), 1) }, fmi3OK);
        let expect: f64 = (1..=k + 1).map(f64::from).sum();
        assert_eq!(get_f64(c, 12), (fmi3OK, expect));
        update(c);
        // SAFETY: a live instance; locals.
        unsafe {
            assert_eq!(fmi3EnterStepMode(c), fmi3OK);
            assert_eq!(
                fmi3DoStep(c, t, 0.25, false, &mut event, &mut term, &mut early, &mut at),
                fmi3OK
            );
            t += 0.25;
            assert_eq!(fmi3EnterEventMode(c), fmi3OK);
        }
    }
    // SAFETY: a live instance.
    unsafe { fmi3FreeInstance(c) };
}

#[test]
fn the_description_declares_the_clocks() {
    use rustfmu::Variables;
    use rustfmu::description::IntervalVariability as I;
    let d = model::Clocked::DESCRIPTION;
    let clock = |n: &str| d.by_name(n).unwrap().fmi3.clock.unwrap();
    assert_eq!(clock("tick").interval_variability, I::Constant);
    assert_eq!(clock("tick").interval, Some(0.1));
    assert_eq!(clock("sample").interval_parameter, "Ts");
    assert_eq!((clock("slow").shift, clock("slow").can_be_deactivated), (0.05, true));
    assert_eq!(d.by_name("alarms").unwrap().fmi3.clocks, &["alarm", "trigger"]);
    // A clocked output depends on its clocks; clocked variables are no initial unknowns.
    assert_eq!(d.by_name("sum").unwrap().depends_on, Some(&["u", "sample"][..]));
    assert!(!d.is_initial_unknown(d.by_name("sum").unwrap()));
    // The encoding keeps all of it (the description cargo fmu writes the XML from).
    let interfaces = rustfmu::description::Interfaces::BOTH_FMI3;
    let bytes = rustfmu::description::encode_to_vec(&d, interfaces);
    let (back, _) = rustfmu::description::decode(&bytes).unwrap();
    for (a, b) in d.variables.iter().zip(back.variables) {
        assert_eq!(a.fmi3.clock, b.fmi3.clock, "{}", a.name);
        assert_eq!(a.fmi3.clocks, b.fmi3.clocks, "{}", a.name);
    }
}
