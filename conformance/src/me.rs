//! Model exchange (FMI 2.0 chapter 3) as an importer drives it: the model-exchange state
//! machine and the states in which the standard allows each function (section 3.2.3; the masks
//! of the Reference FMUs, which follow the standard), the model-exchange calls on an
//! [`Instance`], a small explicit-Euler integrator, and, on this exporter's FMUs, the state
//! machine read from (and forged into) the serialized FMU state.
//!
//! The state bytes of the model-exchange states are not assumed: they are learned from the FMU
//! by reaching each state with the standard's calls and reading the byte ([`StateCodes`]).
//! Only Error and Fatal, which no call reaches, are taken to keep their co-simulation numbers
//! (6 and 7) when the shared states (Instantiated 0, InitializationMode 1, Terminated 5) keep
//! theirs, and that guess is tested on the FMU before it is used.

use crate::api::MeApi;
use crate::calllog::Val;
use crate::fmi2::*;
use crate::guard::{GETTER_RULE2, Guarded};
use crate::instance::{Args, Instance, Status, excitation, status_name};
use crate::outcome::{skip, skip_not_declared};
use crate::{Fmu, state};
pub use MeState::*;

crate::standard::state_machine!(
    /// A state of the model-exchange state machine (discriminants 0 to 6, in this order).
    MeState,
    ME_STATES: [
        Instantiated,
        InitializationMode,
        EventMode,
        ContinuousTimeMode,
        Terminated,
        Error,
        Fatal,
    ]
);

/// The states an importer reaches on any FMU by the standard's calls alone.
pub const ME_REACHABLE: [MeState; 5] = [
    Instantiated,
    InitializationMode,
    EventMode,
    ContinuousTimeMode,
    Terminated,
];

/// Every model-exchange state but Fatal (the last).
const ALL_BUT_FATAL: &[MeState] = ME_STATES.split_at(6).0;
/// Every model-exchange state but Instantiated (the first) and Fatal.
const GETTERS: &[MeState] = ALL_BUT_FATAL.split_at(1).1;

/// The functions of the co-simulation interface only: an instance of fmuType
/// fmi2ModelExchange must refuse them in every state (`fmi-standard`'s list).
pub use fmi_standard::functions::FMI2_CS_ONLY_FUNCTIONS as CS_ONLY;

/// Where `function` may be called in a model-exchange instance (FMI 2.0 section 3.2.3). The
/// functions of co-simulation only: nowhere.
pub fn allowed_states(function: &str) -> &'static [MeState] {
    match function {
        "fmi2SetDebugLogging"
        | "fmi2Reset"
        | "fmi2GetFMUstate"
        | "fmi2SetFMUstate"
        | "fmi2FreeFMUstate"
        | "fmi2SerializedFMUstateSize"
        | "fmi2SerializeFMUstate"
        | "fmi2DeSerializeFMUstate" => ALL_BUT_FATAL,
        "fmi2SetupExperiment" | "fmi2EnterInitializationMode" => &[Instantiated],
        "fmi2ExitInitializationMode" => &[InitializationMode],
        "fmi2Terminate" => &[EventMode, ContinuousTimeMode],
        "fmi2GetReal" | "fmi2GetInteger" | "fmi2GetBoolean" | "fmi2GetString" | "fmi2GetDirectionalDerivative" => {
            GETTERS
        }
        // In ContinuousTimeMode only continuous Real inputs (the calls pick the variables).
        "fmi2SetReal" => &[Instantiated, InitializationMode, EventMode, ContinuousTimeMode],
        "fmi2SetInteger" | "fmi2SetBoolean" | "fmi2SetString" => &[Instantiated, InitializationMode, EventMode],
        "fmi2EnterEventMode" => &[EventMode, ContinuousTimeMode],
        "fmi2NewDiscreteStates" => &[EventMode],
        "fmi2EnterContinuousTimeMode" => &[EventMode],
        "fmi2CompletedIntegratorStep" => &[ContinuousTimeMode],
        "fmi2SetTime" => &[EventMode, ContinuousTimeMode],
        "fmi2SetContinuousStates" => &[ContinuousTimeMode],
        "fmi2GetEventIndicators" | "fmi2GetContinuousStates" => GETTERS,
        "fmi2GetDerivatives" => &[EventMode, ContinuousTimeMode, Terminated, Error],
        "fmi2GetNominalsOfContinuousStates" => &[Instantiated, EventMode, ContinuousTimeMode, Terminated, Error],
        f if CS_ONLY.contains(&f) => &[],
        other => panic!("{other} is not a function with a model-exchange state"),
    }
}

/// The model-exchange functions of the FMU, or skips the check: as "not declared" when the FMU
/// has no `<ModelExchange>`, as a limitation of the suite when its model-exchange binary is
/// another one than the co-simulation binary. Fails when the FMU declares Model Exchange and
/// its binary does not export the functions.
pub fn needs_me(fmu: &Fmu) -> &MeApi {
    let Some(me) = &fmu.md.me else {
        skip_not_declared("<ModelExchange> (the FMU is for co-simulation only)")
    };
    if me.model_identifier != fmu.md.model_identifier() {
        skip(format!(
            "the Model Exchange modelIdentifier '{}' differs from the co-simulation one '{}': this suite loads one binary",
            me.model_identifier,
            fmu.md.model_identifier()
        ));
    }
    match &fmu.api.me {
        Ok(api) => api,
        Err(e) => panic!(
            "{}: the FMU declares <ModelExchange>, but its binary lacks functions of the interface: {e}",
            fmu.id
        ),
    }
}

/// Whether the FMU declares that a model-exchange instance can get, set and serialize its
/// state (the flags of `<ModelExchange>`).
pub fn can_snapshot_me(fmu: &Fmu) -> bool {
    fmu.md
        .me
        .as_ref()
        .is_some_and(|m| m.can_get_and_set_fmu_state && m.can_serialize_fmu_state)
}

/// The model-exchange functions that fill a vector of Reals.
pub const VECTOR_GETTERS: [&str; 4] = [
    "fmi2GetContinuousStates",
    "fmi2GetDerivatives",
    "fmi2GetEventIndicators",
    "fmi2GetNominalsOfContinuousStates",
];

/// What fmi2CompletedIntegratorStep answered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Completed {
    pub status: Status,
    pub enter_event_mode: bool,
    pub terminate_simulation: bool,
}

impl<'a> Instance<'a> {
    /// A model-exchange instance with valid arguments; panics with the FMU's log if refused.
    pub fn new_me(fmu: &'a Fmu) -> Instance<'a> {
        let args = Args {
            fmu_type: fmi2ModelExchange,
            ..Args::valid(fmu)
        };
        Instance::with(fmu, &args)
            .unwrap_or_else(|log| panic!("{}: fmi2Instantiate(fmi2ModelExchange) refused: {log:#?}", fmu.id))
    }

    pub(crate) fn me(&self) -> &'a MeApi {
        self.fmu
            .api
            .me
            .as_ref()
            .unwrap_or_else(|e| panic!("{}: no model-exchange functions: {e}", self.fmu.id))
    }

    /// The number of continuous states (of `<Derivatives>`).
    pub fn nx(&self) -> usize {
        self.fmu.md.number_of_continuous_states()
    }

    /// `numberOfEventIndicators`.
    pub fn ni(&self) -> usize {
        self.fmu.md.number_of_event_indicators
    }

    /// fmi2SetTime; the tracked time follows when the FMU answers fmi2OK.
    pub fn set_time(&mut self, t: f64) -> Status {
        let i = self.record("fmi2SetTime", vec![("time", Val::F64(t))]);
        // SAFETY: a live instance.
        let s = self.answered(i, unsafe { (self.me().set_time)(self.c, t) });
        if s == fmi2OK {
            self.time = t;
        }
        s
    }

    pub fn set_continuous_states(&mut self, x: &[f64]) -> Status {
        let i = self.record("fmi2SetContinuousStates", vec![("x", Val::F64s(x.to_vec()))]);
        // SAFETY: an array of nx elements.
        self.answered(i, unsafe {
            (self.me().set_continuous_states)(self.c, x.as_ptr(), x.len())
        })
    }

    /// One of [`VECTOR_GETTERS`] (`name`) with `n` values.
    pub fn get_vector_n(&self, name: &'static str, n: usize) -> (Status, Vec<f64>) {
        self.get_vector(name, self.vector_getter(name), n)
    }

    /// The function of one of [`VECTOR_GETTERS`] (`name`).
    pub(crate) fn vector_getter(
        &self,
        name: &str,
    ) -> unsafe extern "C" fn(fmi2Component, *mut fmi2Real, usize) -> fmi2Status {
        let me = self.me();
        match name {
            "fmi2GetContinuousStates" => me.get_continuous_states,
            "fmi2GetDerivatives" => me.get_derivatives,
            "fmi2GetEventIndicators" => me.get_event_indicators,
            "fmi2GetNominalsOfContinuousStates" => me.get_nominals_of_continuous_states,
            other => panic!("{other} is not a model-exchange vector getter"),
        }
    }

    fn get_vector(
        &self,
        name: &'static str,
        f: unsafe extern "C" fn(fmi2Component, *mut fmi2Real, usize) -> fmi2Status,
        n: usize,
    ) -> (Status, Vec<f64>) {
        let i = self.record(name, vec![("n", Val::U64(n as u64))]);
        let mut v = Guarded::new(n, f64::NAN);
        // SAFETY: an array of n elements (and the guard after it).
        let s = self.answered(i, unsafe { f(self.c, v.as_mut_ptr(), n) });
        let v = v.into_values(|| format!("{name} with n = {n}"), GETTER_RULE2);
        (s, v)
    }

    pub fn get_continuous_states(&self) -> (Status, Vec<f64>) {
        self.get_vector("fmi2GetContinuousStates", self.me().get_continuous_states, self.nx())
    }

    pub fn get_derivatives(&self) -> (Status, Vec<f64>) {
        self.get_vector("fmi2GetDerivatives", self.me().get_derivatives, self.nx())
    }

    pub fn get_event_indicators(&self) -> (Status, Vec<f64>) {
        self.get_vector("fmi2GetEventIndicators", self.me().get_event_indicators, self.ni())
    }

    pub fn get_nominals(&self) -> (Status, Vec<f64>) {
        self.get_vector(
            "fmi2GetNominalsOfContinuousStates",
            self.me().get_nominals_of_continuous_states,
            self.nx(),
        )
    }

    pub fn enter_event_mode(&mut self) -> Status {
        let i = self.record("fmi2EnterEventMode", vec![]);
        // SAFETY: a live instance.
        self.answered(i, unsafe { (self.me().enter_event_mode)(self.c) })
    }

    pub fn enter_continuous_time_mode(&mut self) -> Status {
        let i = self.record("fmi2EnterContinuousTimeMode", vec![]);
        // SAFETY: a live instance.
        self.answered(i, unsafe { (self.me().enter_continuous_time_mode)(self.c) })
    }

    /// fmi2NewDiscreteStates with an eventInfo that holds values no FMU writes (so that a
    /// field the FMU does not fill shows).
    pub fn new_discrete_states(&mut self) -> (Status, fmi2EventInfo) {
        let i = self.record("fmi2NewDiscreteStates", vec![]);
        let mut info = fmi2EventInfo {
            newDiscreteStatesNeeded: 77,
            terminateSimulation: 77,
            nominalsOfContinuousStatesChanged: 77,
            valuesOfContinuousStatesChanged: 77,
            nextEventTimeDefined: 77,
            nextEventTime: f64::NAN,
        };
        // SAFETY: a valid out pointer.
        let s = self.answered(i, unsafe { (self.me().new_discrete_states)(self.c, &mut info) });
        (s, info)
    }

    /// fmi2CompletedIntegratorStep(noSetFMUStatePriorToCurrentPoint = false: the checks may go
    /// back to an earlier FMU state).
    pub fn completed_integrator_step(&mut self) -> Completed {
        let i = self.record(
            "fmi2CompletedIntegratorStep",
            vec![("noSetFMUStatePriorToCurrentPoint", Val::Bool(false))],
        );
        let (mut enter, mut terminate) = (77, 77);
        // SAFETY: valid out pointers.
        let status = self.answered(i, unsafe {
            (self.me().completed_integrator_step)(self.c, fmi2False, &mut enter, &mut terminate)
        });
        Completed {
            status,
            enter_event_mode: enter == fmi2True,
            terminate_simulation: terminate == fmi2True,
        }
    }

    /// fmi2NewDiscreteStates until no new discrete states are needed (at most 100 times);
    /// panics unless every call answers fmi2OK with a sensible eventInfo.
    pub fn event_iteration(&mut self) -> fmi2EventInfo {
        for _ in 0..100 {
            let (s, info) = self.new_discrete_states();
            assert_eq!(
                s,
                fmi2OK,
                "{}: fmi2NewDiscreteStates at t = {}: {}",
                self.fmu.id,
                self.time,
                self.log_text()
            );
            check_event_info(self.fmu, &info, self.time);
            if info.newDiscreteStatesNeeded == fmi2False || info.terminateSimulation == fmi2True {
                return info;
            }
        }
        panic!(
            "{}: fmi2NewDiscreteStates still needs new discrete states after 100 calls at t = {}",
            self.fmu.id, self.time
        )
    }

    /// The excitation of [`excitation`] (in state Instantiated), setup at t = 0, initialization,
    /// the event iteration, and fmi2EnterContinuousTimeMode: the instance is then in
    /// ContinuousTimeMode. Panics unless every call answers fmi2OK. Returns the last eventInfo.
    pub fn me_initialize(&mut self) -> fmi2EventInfo {
        let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(self.fmu).into_iter().unzip();
        assert_eq!(
            self.set_real(&vrs, &vals),
            fmi2OK,
            "{}: {}",
            self.fmu.id,
            self.log_text()
        );
        self.me_initialize_at_start()
    }

    /// [`Self::me_initialize`] with every input at its start value.
    pub fn me_initialize_at_start(&mut self) -> fmi2EventInfo {
        self.me_to_event_mode();
        let info = self.event_iteration();
        assert_eq!(
            self.enter_continuous_time_mode(),
            fmi2OK,
            "{}: fmi2EnterContinuousTimeMode: {}",
            self.fmu.id,
            self.log_text()
        );
        info
    }

    /// Setup at t = 0, fmi2EnterInitializationMode, fmi2ExitInitializationMode: the instance is
    /// then in EventMode. Panics unless every call answers fmi2OK.
    pub fn me_to_event_mode(&mut self) {
        let s = [self.setup(0.0, None), self.enter_init(), self.exit_init()];
        assert_eq!(
            s,
            [fmi2OK; 3],
            "{}: model-exchange initialization failed: {}",
            self.fmu.id,
            self.log_text()
        );
    }

    /// The state-machine state of a model-exchange instance, read from its serialized FMU state
    /// (only on this exporter's FMUs, [`Fmu::me_state_codes`]).
    pub fn me_state(&mut self) -> MeState {
        let codes = match self.fmu.me_state_codes() {
            Ok(c) => *c,
            Err(e) => panic!("{}: the model-exchange state cannot be read: {e}", self.fmu.id),
        };
        let b = state::state_byte(&self.snapshot()).unwrap_or_else(|e| panic!("{}: {e}", self.fmu.id));
        codes.state(b).unwrap_or_else(|| {
            panic!(
                "{}: state byte {b} is no model-exchange state (learned: {codes:?})",
                self.fmu.id
            )
        })
    }

    /// Puts a model-exchange instance into `target` by restoring a forged copy of its own
    /// state (made and freed by a helper instance, so that this works for Fatal too).
    pub fn force_me_state(&mut self, target: MeState) {
        let codes = match self.fmu.me_state_codes() {
            Ok(c) => *c,
            Err(e) => panic!("{}: the model-exchange state cannot be forged: {e}", self.fmu.id),
        };
        let byte = codes
            .byte(target)
            .unwrap_or_else(|| panic!("{}: no state byte known for {target:?}", self.fmu.id));
        let bytes = state::forge_byte(&self.snapshot(), byte);
        self.restore_forged(Instance::new_me(self.fmu), &bytes);
    }
}

/// Fails unless an eventInfo is sensible: every Boolean fmi2True or fmi2False, no termination
/// requested (these checks run models that never ask for it), a next event time that is
/// defined is finite and not before `now`.
pub fn check_event_info(fmu: &Fmu, info: &fmi2EventInfo, now: f64) {
    let booleans = [
        ("newDiscreteStatesNeeded", info.newDiscreteStatesNeeded),
        ("terminateSimulation", info.terminateSimulation),
        (
            "nominalsOfContinuousStatesChanged",
            info.nominalsOfContinuousStatesChanged,
        ),
        ("valuesOfContinuousStatesChanged", info.valuesOfContinuousStatesChanged),
        ("nextEventTimeDefined", info.nextEventTimeDefined),
    ];
    for (name, b) in booleans {
        assert!(
            b == fmi2True || b == fmi2False,
            "{}: fmi2NewDiscreteStates at t = {now}: eventInfo.{name} = {b}: not set to fmi2True or fmi2False ({info:?})",
            fmu.id
        );
    }
    // terminateSimulation = fmi2True is the model ending the simulation (FMI 2.0, 3.2.2:
    // fmi2NewDiscreteStates "terminateSimulation ... the simulation should be terminated"): legal;
    // the run stops there ([`Euler::terminated`]).
    if info.nextEventTimeDefined == fmi2True {
        assert!(
            info.nextEventTime.is_finite() && info.nextEventTime >= now,
            "{}: fmi2NewDiscreteStates at t = {now}: nextEventTimeDefined with nextEventTime {} (not finite or in the past)",
            fmu.id,
            info.nextEventTime
        );
    }
}

/// An explicit-Euler integration of a model-exchange instance in ContinuousTimeMode, with the
/// events an importer must handle: time events (nextEventTime), state events (a sign change
/// of an event indicator) and step events (enterEventMode of fmi2CompletedIntegratorStep). The
/// C host (`c/host.c`) runs the same algorithm, so that both give bit-identical results.
#[derive(Debug, Clone)]
pub struct Euler {
    pub h: f64,
    pub next_event: Option<f64>,
    indicators: Vec<f64>,
    /// Events handled so far.
    pub events: usize,
    /// The model asked to end the simulation (fmi2CompletedIntegratorStep or
    /// fmi2NewDiscreteStates with terminateSimulation): the run ends there, the instance in
    /// EventMode or ContinuousTimeMode (fmi2Terminate is legal from both).
    pub terminated: bool,
}

impl Euler {
    /// For an instance in ContinuousTimeMode, after the event iteration that gave `info`.
    pub fn new(inst: &Instance, h: f64, info: &fmi2EventInfo) -> Euler {
        let (s, indicators) = inst.get_event_indicators();
        assert_eq!(
            s,
            fmi2OK,
            "{}: fmi2GetEventIndicators: {}",
            inst.fmu.id,
            inst.log_text()
        );
        Euler {
            h,
            next_event: (info.nextEventTimeDefined == fmi2True).then_some(info.nextEventTime),
            indicators,
            events: 0,
            terminated: info.terminateSimulation == fmi2True,
        }
    }

    /// One step from the instance's time; panics unless every call answers fmi2OK.
    pub fn step(&mut self, inst: &mut Instance) {
        let id = &inst.fmu.id;
        let t = inst.time;
        let (s1, x) = inst.get_continuous_states();
        let (s2, dx) = inst.get_derivatives();
        assert_eq!([s1, s2], [fmi2OK; 2], "{id}: at t = {t}: {}", inst.log_text());
        let mut t1 = t + self.h;
        let time_event = self.next_event.is_some_and(|te| te <= t1);
        if time_event {
            t1 = self.next_event.unwrap().max(t);
        }
        let x1: Vec<f64> = x.iter().zip(&dx).map(|(x, d)| x + (t1 - t) * d).collect();
        assert_eq!(
            inst.set_time(t1),
            fmi2OK,
            "{id}: fmi2SetTime({t1}): {}",
            inst.log_text()
        );
        assert_eq!(
            inst.set_continuous_states(&x1),
            fmi2OK,
            "{id}: fmi2SetContinuousStates at t = {t1}: {}",
            inst.log_text()
        );
        let done = inst.completed_integrator_step();
        assert_eq!(
            done.status,
            fmi2OK,
            "{id}: fmi2CompletedIntegratorStep at t = {t1}: {}",
            inst.log_text()
        );
        if done.terminate_simulation {
            self.terminated = true;
            self.next_event = None;
            return;
        }
        let (s, z) = inst.get_event_indicators();
        assert_eq!(
            s,
            fmi2OK,
            "{id}: fmi2GetEventIndicators at t = {t1}: {}",
            inst.log_text()
        );
        let state_event = z.iter().zip(&self.indicators).any(|(a, b)| (*a > 0.0) != (*b > 0.0));
        self.indicators = z;
        if time_event || state_event || done.enter_event_mode {
            self.events += 1;
            assert_eq!(
                inst.enter_event_mode(),
                fmi2OK,
                "{id}: fmi2EnterEventMode at t = {t1}: {}",
                inst.log_text()
            );
            let info = inst.event_iteration();
            if info.terminateSimulation == fmi2True {
                self.terminated = true;
                self.next_event = None;
                return;
            }
            assert_eq!(
                inst.enter_continuous_time_mode(),
                fmi2OK,
                "{id}: fmi2EnterContinuousTimeMode at t = {t1}: {}",
                inst.log_text()
            );
            self.next_event = (info.nextEventTimeDefined == fmi2True).then_some(info.nextEventTime);
            let (s, z) = inst.get_event_indicators();
            assert_eq!(
                s,
                fmi2OK,
                "{id}: fmi2GetEventIndicators at t = {t1}: {}",
                inst.log_text()
            );
            self.indicators = z;
        }
    }
}

/// The state bytes of the model-exchange states in this exporter's serialized FMU state, by
/// [`MeState`] (`None`: not known).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StateCodes {
    pub bytes: [Option<u8>; 7],
}

impl StateCodes {
    pub fn byte(&self, s: MeState) -> Option<u8> {
        self.bytes[s as usize]
    }

    pub fn state(&self, b: u8) -> Option<MeState> {
        ME_STATES.into_iter().find(|s| self.bytes[*s as usize] == Some(b))
    }

    /// Whether Error and Fatal are known (and can be forged).
    pub fn knows_error_and_fatal(&self) -> bool {
        self.bytes[Error as usize].is_some() && self.bytes[Fatal as usize].is_some()
    }
}

impl Fmu {
    /// The state bytes of the model-exchange states, learned once from the FMU; an error says
    /// why they cannot be (another exporter's FMU, no Model Exchange, a call that failed).
    pub fn me_state_codes(&self) -> &Result<StateCodes, String> {
        self.me_codes.get_or_init(|| learn_codes(self))
    }
}

fn learn_codes(fmu: &Fmu) -> Result<StateCodes, String> {
    if let Err(e) = fmu.state_format() {
        return Err(e.clone());
    }
    if !can_snapshot_me(fmu) {
        return Err("<ModelExchange> does not declare canGetAndSetFMUstate and canSerializeFMUstate".into());
    }
    if let Err(e) = &fmu.api.me {
        return Err(e.clone());
    }
    let args = Args {
        fmu_type: fmi2ModelExchange,
        ..Args::valid(fmu)
    };
    let mut inst = Instance::with(fmu, &args).map_err(|log| format!("fmi2Instantiate(fmi2ModelExchange): {log:?}"))?;
    let byte = |inst: &mut Instance| state::state_byte(&inst.snapshot());
    let mut codes = StateCodes { bytes: [None; 7] };
    codes.bytes[Instantiated as usize] = Some(byte(&mut inst)?);
    let ok = |what: &str, s: Status, inst: &Instance| {
        if s == fmi2OK {
            Ok(())
        } else {
            Err(format!("{what} answered {}: {}", status_name(s), inst.log_text()))
        }
    };
    let s = inst.setup(0.0, None);
    ok("fmi2SetupExperiment", s, &inst)?;
    // Each call, and the state it reaches, whose byte is read there.
    type Call<'i> = fn(&mut Instance<'i>) -> Status;
    let walk: [(&str, Call<'_>, MeState); 4] = [
        ("fmi2EnterInitializationMode", Instance::enter_init, InitializationMode),
        ("fmi2ExitInitializationMode", Instance::exit_init, EventMode),
        (
            "fmi2EnterContinuousTimeMode",
            Instance::enter_continuous_time_mode,
            ContinuousTimeMode,
        ),
        ("fmi2Terminate", Instance::terminate, Terminated),
    ];
    for (what, call, state) in walk {
        let s = call(&mut inst);
        ok(what, s, &inst)?;
        codes.bytes[state as usize] = Some(byte(&mut inst)?);
    }
    let known: Vec<u8> = codes.bytes.iter().flatten().copied().collect();
    if (1..known.len()).any(|i| known[..i].contains(&known[i])) {
        return Err(format!(
            "two model-exchange states have the same state byte ({codes:?}): the state is not observable"
        ));
    }
    // Error and Fatal: the co-simulation numbers, if the shared states keep theirs and the
    // guess behaves as Error does (fmi2GetReal allowed, fmi2EnterEventMode refused).
    let shared = [Instantiated, InitializationMode, Terminated].map(|s| codes.byte(s));
    if shared == [Some(0), Some(1), Some(5)] && !known.contains(&6) && !known.contains(&7) {
        let mut probe = StateCodes { ..codes };
        probe.bytes[Error as usize] = Some(6);
        probe.bytes[Fatal as usize] = Some(7);
        let mut p = Instance::with(fmu, &args).map_err(|log| format!("fmi2Instantiate: {log:?}"))?;
        let forged = state::forge_byte(&p.snapshot(), 6);
        let (st, mut s) = p.deserialize(&forged);
        if st == fmi2OK && p.set_state(s) == fmi2OK {
            let reals = fmu.md.vrs_of_type(crate::Type::Real);
            let get = p.get_real(&reals).0;
            let enter = p.enter_event_mode();
            p.log();
            if get == fmi2OK && enter == fmi2Error {
                codes = probe;
            }
        }
        if !s.is_null() {
            p.free_state(&mut s);
        }
        p.log();
    }
    inst.log();
    Ok(codes)
}

/// An instance of `fmu` in model-exchange state `s` (excited as [`excitation`] says): reached
/// by the standard's calls where an importer can get there (ContinuousTimeMode after the event
/// iteration), and by restoring a forged FMU state otherwise.
pub fn instance_in(fmu: &Fmu, s: MeState) -> Instance<'_> {
    let mut i = Instance::new_me(fmu);
    if s != Instantiated {
        let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
        assert_eq!(i.set_real(&vrs, &vals), fmi2OK, "{}: {}", fmu.id, i.log_text());
    }
    match s {
        Instantiated => {}
        InitializationMode => assert_eq!([i.setup(0.0, None), i.enter_init()], [fmi2OK; 2], "{}", i.log_text()),
        EventMode => i.me_to_event_mode(),
        _ => {
            i.me_to_event_mode();
            i.event_iteration();
            assert_eq!(i.enter_continuous_time_mode(), fmi2OK, "{}", i.log_text());
            match s {
                ContinuousTimeMode => {}
                Terminated => assert_eq!(i.terminate(), fmi2OK, "{}", i.log_text()),
                _ => i.force_me_state(s),
            }
        }
    }
    if s != Fatal && fmu.me_state_codes().is_ok() {
        assert_eq!(
            i.me_state(),
            s,
            "{}: could not put a model-exchange instance in {s:?}",
            fmu.id
        );
    }
    i.log();
    i
}

/// A small seeded generator (splitmix64), for reproducible random points.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
}
