//! Events through the FMI 2.0 C API of a model exported into this test binary: the event
//! indicators and fmi2NewDiscreteStates in Model Exchange, state and time events inside
//! fmi2DoStep, and the refusals (a model that refuses an event, schedules a time event that is
//! not later, asks for rounds without end, or ends the simulation).

use rustfmu::__private::abi::*;
use rustfmu::testing::thread_log as log;

mod model {
    use rustfmu::prelude::*;

    /// A tank drained at 1 per second and refilled by 1 where its level x reaches 0.5 (a state
    /// event), with a time event every `period` that counts ticks.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    pub struct Refill {
        /// Level x
        #[variable(vr = 0, output, initial = exact, start = 1.0, depends = [x])]
        pub x: f64,
        /// dx/dt = -1
        #[variable(vr = 1, name = "der(x)", local, derivative_of = x, depends = [], initial_depends = [])]
        pub der_x: f64,
        /// x - 0.5: the refill where it reaches 0
        #[variable(vr = 2, local, event_indicator, depends = [x])]
        pub z: f64,
        /// Refills so far
        #[variable(vr = 3, output, discrete, initial = exact, start = 0)]
        pub refills: i32,
        /// Ticks so far
        #[variable(vr = 4, output, discrete, initial = exact, start = 0)]
        pub ticks: i32,
        /// Time between ticks
        #[variable(vr = 5, parameter, tunable, start = 0.3, min > 0.0)]
        pub period: f64,
        /// What the update does wrong: 0 nothing, 1 refuses, 2 schedules now, 3 asks for rounds
        /// without end, 4 ends the simulation at the first refill
        #[variable(vr = 6, parameter, tunable, start = 0, min = 0, max = 4)]
        pub misbehave: i32,
    }

    impl Model for Refill {
        fn derivatives<D: Real>(&self, _t: D, v: &mut RefillContinuous<D>) {
            v.der_x = v.x * 0.0 - 1.0;
        }
        fn outputs<D: Real>(&self, _t: D, v: &mut RefillContinuous<D>) {
            v.z = v.x - 0.5;
        }
        fn update(&mut self, event: &mut Event) -> Result<(), String> {
            match self.misbehave {
                1 if !event.initial() => return Err("the refill valve is stuck".into()),
                2 if !event.initial() => event.schedule(event.time()),
                3 if !event.initial() => event.iterate(),
                _ => {}
            }
            if self.x <= 0.5 {
                self.x += 1.0;
                self.refills += 1;
                if self.misbehave == 4 {
                    event.terminate("the first refill");
                }
            }
            if event.time_event() {
                self.ticks += 1;
            }
            if (event.initial() || event.time_event()) && (self.misbehave != 2 || event.initial()) {
                event.schedule(event.time() + self.period);
            }
            Ok(())
        }
    }

    impl CoSimulation for Refill {}

    rustfmu::export_fmi2!(Refill);

    /// A model that offers Co-Simulation only.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    #[fmu(co_simulation_only)]
    pub struct OnlyCs {
        /// y
        #[variable(vr = 0, output, discrete, initial = exact, start = 0.0)]
        pub y: f64,
    }
    impl Model for OnlyCs {}
    impl CoSimulation for OnlyCs {}
}
use model::__rustfmu_fmi2_exports::*;

/// An instance of `kind` with `misbehave` set, initialized (Model Exchange: in Event Mode).
fn instance(kind: fmi2Type, misbehave: i32) -> fmi2Component {
    let c = rustfmu::testing::fmi2::instance(fmi2Instantiate, GUID, kind, c"refill", log());
    // SAFETY: a live instance; one reference, one value.
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(fmi2SetInteger(c, &6, 1, &misbehave), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
        c
    }
}

fn info() -> fmi2EventInfo {
    fmi2EventInfo {
        newDiscreteStatesNeeded: 7,
        terminateSimulation: 7,
        nominalsOfContinuousStatesChanged: 7,
        valuesOfContinuousStatesChanged: 7,
        nextEventTimeDefined: 7,
        nextEventTime: f64::NAN,
    }
}

fn new_discrete_states(c: fmi2Component) -> (fmi2Status, fmi2EventInfo) {
    let mut i = info();
    // SAFETY: a live instance, a writable event info.
    let s = unsafe { fmi2NewDiscreteStates(c, &mut i) };
    (s, i)
}

fn get_real(c: fmi2Component, vr: u32) -> f64 {
    let mut x = f64::NAN;
    // SAFETY: one reference, one slot.
    assert_eq!(unsafe { fmi2GetReal(c, &vr, 1, &mut x) }, fmi2OK);
    x
}

fn get_integer(c: fmi2Component, vr: u32) -> i32 {
    let mut x = -1;
    // SAFETY: one reference, one slot.
    assert_eq!(unsafe { fmi2GetInteger(c, &vr, 1, &mut x) }, fmi2OK);
    x
}

/// Model Exchange to t with the level set to x, then into Event Mode.
fn to_event_at(c: fmi2Component, t: f64, x: f64) {
    // SAFETY: a live instance; one state.
    unsafe {
        assert_eq!(fmi2SetTime(c, t), fmi2OK);
        assert_eq!(fmi2SetContinuousStates(c, &x, 1), fmi2OK);
        assert_eq!(fmi2EnterEventMode(c), fmi2OK);
    }
}

fn logged(c: fmi2Component, words: &[&str]) {
    let texts = log().take_texts();
    assert!(
        texts.iter().any(|(_, m)| words.iter().all(|w| m.contains(w))),
        "no message with {words:?}: {texts:?}"
    );
    let _ = c;
}

#[test]
fn model_exchange_reports_indicators_time_events_and_changed_states() {
    let c = instance(fmi2ModelExchange, 0);
    let (s, i) = new_discrete_states(c);
    assert_eq!(s, fmi2OK);
    assert_eq!(
        (i.nextEventTimeDefined, i.nextEventTime),
        (fmi2True, 0.3),
        "the first tick"
    );
    assert_eq!(
        (
            i.newDiscreteStatesNeeded,
            i.terminateSimulation,
            i.valuesOfContinuousStatesChanged
        ),
        (0, 0, 0)
    );
    // SAFETY: a live instance.
    assert_eq!(unsafe { fmi2EnterContinuousTimeMode(c) }, fmi2OK);
    let mut z = [f64::NAN; 2];
    // SAFETY: the arrays are as long as passed.
    unsafe {
        assert_eq!(fmi2GetEventIndicators(c, z.as_mut_ptr(), 1), fmi2OK);
        assert_eq!(z[0], 0.5, "x - 0.5 at x = 1");
        assert_eq!(fmi2GetEventIndicators(c, z.as_mut_ptr(), 2), fmi2Error);
    }
    logged(c, &["ni = 2", "1 event indicators"]);
    // The time event at 0.3: a tick, no refill, the next tick at 0.6.
    to_event_at(c, 0.3, 0.7);
    let (s, i) = new_discrete_states(c);
    assert_eq!(s, fmi2OK);
    assert_eq!((i.valuesOfContinuousStatesChanged, i.nextEventTime), (0, 0.6));
    assert_eq!((get_integer(c, 4), get_integer(c, 3)), (1, 0));
    // SAFETY: a live instance.
    assert_eq!(unsafe { fmi2EnterContinuousTimeMode(c) }, fmi2OK);
    // The state event where x reaches 0.5: the refill, the states changed, the tick still pending.
    to_event_at(c, 0.5, 0.5);
    let (s, i) = new_discrete_states(c);
    assert_eq!(s, fmi2OK);
    assert_eq!((i.valuesOfContinuousStatesChanged, i.nextEventTime), (fmi2True, 0.6));
    assert_eq!((get_real(c, 0), get_integer(c, 3), get_integer(c, 4)), (1.5, 1, 1));
    assert_eq!(get_real(c, 2), 1.0, "the indicator after the refill");
    // SAFETY: a live instance.
    unsafe { fmi2FreeInstance(c) };
}

#[test]
fn a_refused_event_is_an_error_that_changes_nothing() {
    let c = instance(fmi2ModelExchange, 1);
    assert_eq!(new_discrete_states(c).0, fmi2OK, "the initial event is accepted");
    // SAFETY: a live instance.
    assert_eq!(unsafe { fmi2EnterContinuousTimeMode(c) }, fmi2OK);
    to_event_at(c, 0.5, 0.5);
    assert_eq!(new_discrete_states(c).0, fmi2Error);
    logged(
        c,
        &[
            "fmi2NewDiscreteStates",
            "the refill valve is stuck",
            "as before the event",
        ],
    );
    assert_eq!((get_real(c, 0), get_integer(c, 3)), (0.5, 0), "nothing refilled");
    // SAFETY: a live instance.
    unsafe { fmi2FreeInstance(c) };
}

#[test]
fn a_time_event_scheduled_for_now_is_refused() {
    let c = instance(fmi2ModelExchange, 2);
    assert_eq!(new_discrete_states(c).0, fmi2OK);
    // SAFETY: a live instance.
    assert_eq!(unsafe { fmi2EnterContinuousTimeMode(c) }, fmi2OK);
    to_event_at(c, 0.3, 0.7);
    assert_eq!(new_discrete_states(c).0, fmi2Error);
    logged(c, &["scheduled the next time event at t = 0.3", "not after"]);
    // SAFETY: a live instance.
    unsafe { fmi2FreeInstance(c) };
}

#[test]
fn co_simulation_locates_the_state_event_and_steps_onto_the_time_events() {
    let c = instance(fmi2CoSimulation, 0);
    // SAFETY: a live instance.
    assert_eq!(unsafe { fmi2DoStep(c, 0.0, 1.0, fmi2True) }, fmi2OK);
    // x = 1 - t, refilled to 1.5 where it reaches 0.5 at t = 0.5: x(1) = 1.
    assert!((get_real(c, 0) - 1.0).abs() < 1e-12, "x(1) = {}", get_real(c, 0));
    // Ticks at 0.3, 0.6, 0.9.
    assert_eq!((get_integer(c, 3), get_integer(c, 4)), (1, 3));
    // SAFETY: a live instance.
    assert_eq!(unsafe { fmi2DoStep(c, 1.0, 0.6, fmi2True) }, fmi2OK);
    // The second refill at t = 1.5, where the fifth tick is too (both events, at one time).
    assert!((get_real(c, 0) - 1.4).abs() < 1e-12, "x(1.6) = {}", get_real(c, 0));
    assert_eq!((get_integer(c, 3), get_integer(c, 4)), (2, 5));
    // SAFETY: a live instance.
    unsafe { fmi2FreeInstance(c) };
}

#[test]
fn an_event_iteration_without_end_discards_the_step() {
    let c = instance(fmi2CoSimulation, 3);
    // SAFETY: a live instance.
    assert_eq!(unsafe { fmi2DoStep(c, 0.0, 1.0, fmi2True) }, fmi2Discard);
    logged(c, &["did not settle after 100 rounds"]);
    let mut t = f64::NAN;
    // SAFETY: a live instance, one slot.
    assert_eq!(unsafe { fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &mut t) }, fmi2OK);
    assert!((t - 0.3).abs() < 1e-12, "the first event, at the tick: {t}");
    // SAFETY: a live instance.
    unsafe { fmi2FreeInstance(c) };
}

#[test]
fn ending_the_simulation_in_a_step_discards_it_with_fmi2_terminated() {
    let c = instance(fmi2CoSimulation, 4);
    // SAFETY: a live instance.
    assert_eq!(unsafe { fmi2DoStep(c, 0.0, 1.0, fmi2True) }, fmi2Discard);
    logged(c, &["the model ended the simulation", "the first refill"]);
    let (mut t, mut ended) = (f64::NAN, fmi2False);
    // SAFETY: a live instance, one slot each.
    unsafe {
        assert_eq!(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &mut t), fmi2OK);
        assert_eq!(fmi2GetBooleanStatus(c, fmi2Terminated, &mut ended), fmi2OK);
    }
    assert!((t - 0.5).abs() < 1e-9 && ended == fmi2True, "{t}, {ended}");
    // SAFETY: a live instance.
    unsafe { fmi2FreeInstance(c) };
}

#[test]
fn a_co_simulation_only_model_offers_no_model_exchange() {
    use rustfmu::Variables;
    use rustfmu::description::{FmiVersion, Interfaces, decode, encode_to_vec};
    let why = rustfmu::fmi2::api::offered::<model::OnlyCs>(true).expect("refused");
    assert!(
        why.contains("offers no Model Exchange") && why.contains("co_simulation_only"),
        "{why}"
    );
    assert_eq!(rustfmu::fmi2::api::offered::<model::OnlyCs>(false), None);
    let interfaces = Interfaces {
        co_simulation: model::OnlyCs::CO_SIMULATION,
        model_exchange: model::OnlyCs::MODEL_EXCHANGE,
        version: FmiVersion::V2,
        can_interpolate_inputs: false,
        scheduled_execution: false,
    };
    let (_, decoded) = decode(&encode_to_vec(&model::OnlyCs::DESCRIPTION, interfaces)).unwrap();
    assert!(decoded.co_simulation && !decoded.model_exchange);
}

#[test]
fn the_description_names_the_event_indicator() {
    use rustfmu::Variables;
    assert_eq!(model::Refill::DESCRIPTION.event_indicators, &["z"]);
    assert_eq!(<model::Refill as Variables>::INDICATORS, &[2]);
}
