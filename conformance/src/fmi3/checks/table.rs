//! The FMI 3.0 state table as data: for every function that takes an instance, what the
//! standard says a valid call answers in each state of co-simulation (section 4.2) and model
//! exchange (section 3.2). One row per function ([`TABLE`]); the call each row makes is
//! dispatched from its function id ([`F::call`]). Used by the state-table checks and the check
//! of a NULL instance ([`super::state_machine`]).

use super::directional_derivatives::{knowns, unknowns};
use super::*;
use crate::calllog::Val;
use crate::guard::{GETTER_RULE3, Guarded};
use State::*;

/// What the standard says of a call in a state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Expect {
    /// Allowed: fmi3OK (or fmi3Warning).
    Ok,
    /// Not allowed: fmi3Error.
    Error,
    /// Allowed by the state machine but refusable because the FMU lacks the capability (no
    /// clocks, no structural parameters, no output derivatives, no dependencies API), or a
    /// cell the standard leaves open: anything but fmi3Fatal and a crash.
    Either,
}

impl Expect {
    /// Whether `status` is what this cell allows.
    pub fn allows(self, status: fmi3Status) -> bool {
        match self {
            Expect::Ok => status == fmi3OK || status == fmi3Warning,
            Expect::Error => status == fmi3Error,
            Expect::Either => [fmi3OK, fmi3Warning, fmi3Error, fmi3Discard].contains(&status),
        }
    }
}

/// A set of states, one bit each.
type States = u8;

const fn bit(s: State) -> States {
    1 << s as u8
}
const I: States = bit(Instantiated);
const IM: States = bit(InitializationMode);
const EM: States = bit(EventMode);
const CT: States = bit(ContinuousTimeMode);
const SM: States = bit(StepMode);
const T: States = bit(Terminated);
const ALL: States = I | IM | EM | CT | SM | T;

/// The cells of one interface's row: the states where a call is allowed, those where it may
/// also be refused ([`Expect::Either`]); in every other state it is refused.
#[derive(Debug, Clone, Copy)]
pub struct Cells {
    ok: States,
    either: States,
}

/// Allowed in these states.
const fn ok(states: States) -> Cells {
    Cells { ok: states, either: 0 }
}
/// Allowed in `ok`, open in `either`.
const fn ok_either(ok: States, either: States) -> Cells {
    Cells { ok, either }
}
/// Open in these states.
const fn either(states: States) -> Cells {
    Cells { ok: 0, either: states }
}
/// Refused in every state.
const NEVER: Cells = ok(0);
/// Open in every state.
const OPEN: Cells = either(ALL);

/// Getters: FMI 3.0.2's table allows fmi3Get{VariableType} in Instantiated too ("get variable
/// start values", fmi-standard #2174; which variables:
/// [`super::calls::fmi3_start_values_are_readable_in_instantiated`]).
const GETTERS: Cells = ok(ALL);
/// fmi3SetFloat64.
const SET_FLOAT: Cells = ok(I | IM | EM | CT | SM);
/// The other setters: the standard's table lets ContinuousTimeMode set continuous-time inputs
/// only, which are Float: with no variable the call is open there.
const SETTERS: Cells = ok_either(I | IM | EM | SM, CT);
/// The derivatives' functions.
const DERIVATIVES: Cells = ok(IM | EM | CT | SM | T);
/// The vectors of model exchange (states, derivatives, event indicators, nominals).
const ME_VECTOR: Cells = ok(IM | EM | CT | T);
/// fmi3GetNumberOf* (Model Exchange only): the allowed calls of Instantiated and Event Mode list
/// them; those of Initialization Mode and Terminated do not, but the Reference FMUs allow them
/// in every state: open there, as in Continuous-Time Mode.
const NUMBER_OF: Cells = ok_either(I | EM, ALL & !(I | EM));

/// One function's row: its cells in co-simulation and in model exchange.
#[derive(Debug, Clone, Copy)]
pub struct Row {
    pub f: F,
    pub cs: Cells,
    pub me: Cells,
}

impl Row {
    /// What the standard says of a valid call in `state` of an instance of that interface.
    pub fn expect(&self, state: State, me: bool) -> Expect {
        let cells = if me { self.me } else { self.cs };
        if cells.ok & bit(state) != 0 {
            Expect::Ok
        } else if cells.either & bit(state) != 0 {
            Expect::Either
        } else {
            Expect::Error
        }
    }
}

/// `Function: co-simulation cells, model-exchange cells;` per row: the function ids ([`F`],
/// the C name without `fmi3`) and [`TABLE`].
macro_rules! state_table {
    ($($(#[$doc:meta])* $f:ident: $cs:expr, $me:expr;)*) => {
        /// A function of the table, by its C name without `fmi3`.
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub enum F {
            $($(#[$doc])* $f,)*
        }

        impl F {
            /// The C name: `fmi3` and the id.
            pub fn name(self) -> &'static str {
                match self {
                    $(F::$f => concat!("fmi3", stringify!($f)),)*
                }
            }
        }

        /// Every function that takes an instance, in every state: the FMI 3.0 state table.
        pub const TABLE: &[Row] = &[$(Row { f: F::$f, cs: $cs, me: $me },)*];
    };
}

state_table! {
    // function                       co-simulation            model exchange
    SetDebugLogging:                  ok(ALL),                 ok(ALL);
    EnterInitializationMode:          ok(I),                   ok(I);
    ExitInitializationMode:           ok(IM),                  ok(IM);
    /// CS without event mode: never; ME: from continuous-time mode.
    EnterEventMode:                   NEVER,                   ok(CT);
    Terminate:                        ok(EM | CT | SM),        ok(EM | CT | SM);
    Reset:                            ok(ALL),                 ok(ALL);
    GetFloat64:                       GETTERS,                 GETTERS;
    GetInt32:                         GETTERS,                 GETTERS;
    GetInt64:                         GETTERS,                 GETTERS;
    GetBoolean:                       GETTERS,                 GETTERS;
    GetString:                        GETTERS,                 GETTERS;
    GetFloat32:                       GETTERS,                 GETTERS;
    GetInt8:                          GETTERS,                 GETTERS;
    GetUInt8:                         GETTERS,                 GETTERS;
    GetInt16:                         GETTERS,                 GETTERS;
    GetUInt16:                        GETTERS,                 GETTERS;
    GetUInt32:                        GETTERS,                 GETTERS;
    GetUInt64:                        GETTERS,                 GETTERS;
    GetBinary:                        GETTERS,                 GETTERS;
    SetFloat64:                       SET_FLOAT,               SET_FLOAT;
    SetInt32:                         SETTERS,                 SETTERS;
    SetInt64:                         SETTERS,                 SETTERS;
    SetBoolean:                       SETTERS,                 SETTERS;
    SetString:                        SETTERS,                 SETTERS;
    SetFloat32:                       SETTERS,                 SETTERS;
    SetInt8:                          SETTERS,                 SETTERS;
    SetUInt8:                         SETTERS,                 SETTERS;
    SetInt16:                         SETTERS,                 SETTERS;
    SetUInt16:                        SETTERS,                 SETTERS;
    SetUInt32:                        SETTERS,                 SETTERS;
    SetUInt64:                        SETTERS,                 SETTERS;
    SetBinary:                        SETTERS,                 SETTERS;
    GetClock:                         OPEN,                    OPEN;
    SetClock:                         OPEN,                    OPEN;
    GetNumberOfVariableDependencies:  OPEN,                    OPEN;
    GetVariableDependencies:          OPEN,                    OPEN;
    /// fmi3GetFMUState, then fmi3FreeFMUState of the state taken.
    GetFMUState:                      ok(ALL),                 ok(ALL);
    /// fmi3FreeFMUState of a NULL state.
    FreeFMUState:                     ok(ALL),                 ok(ALL);
    GetDirectionalDerivative:         DERIVATIVES,             DERIVATIVES;
    GetAdjointDerivative:             DERIVATIVES,             DERIVATIVES;
    /// Allowed by the state machine in Instantiated, EventMode and StepMode, but only for an
    /// FMU with structural parameters.
    EnterConfigurationMode:           either(I | EM | SM),     either(I | EM | SM);
    ExitConfigurationMode:            NEVER,                   NEVER;
    GetIntervalDecimal:               OPEN,                    OPEN;
    GetIntervalFraction:              OPEN,                    OPEN;
    GetShiftDecimal:                  OPEN,                    OPEN;
    GetShiftFraction:                 OPEN,                    OPEN;
    SetIntervalDecimal:               OPEN,                    OPEN;
    SetIntervalFraction:              OPEN,                    OPEN;
    SetShiftDecimal:                  OPEN,                    OPEN;
    SetShiftFraction:                 OPEN,                    OPEN;
    /// EventMode (ME); in CS it belongs to Step Mode without event mode: left open.
    EvaluateDiscreteStates:           either(SM),              ok(EM);
    UpdateDiscreteStates:             NEVER,                   ok(EM);
    EnterContinuousTimeMode:          NEVER,                   ok(EM);
    CompletedIntegratorStep:          NEVER,                   ok(CT);
    /// Continuous-Time Mode; Event Mode's list of allowed calls has no fmi3SetTime, but the
    /// Reference FMUs allow it there: open.
    SetTime:                          NEVER,                   ok_either(CT, EM);
    /// Event Mode: not in the 3.0 list of allowed calls, but the 3.0.2 maintenance release
    /// allows setting continuous states in more states: open.
    SetContinuousStates:              NEVER,                   ok_either(CT, EM);
    GetContinuousStateDerivatives:    NEVER,                   ME_VECTOR;
    GetEventIndicators:               NEVER,                   ME_VECTOR;
    GetContinuousStates:              NEVER,                   ME_VECTOR;
    GetNominalsOfContinuousStates:    NEVER,                   ME_VECTOR;
    GetNumberOfEventIndicators:       NEVER,                   NUMBER_OF;
    GetNumberOfContinuousStates:      NEVER,                   NUMBER_OF;
    /// Only from EventMode of a CS instance with event mode: never here.
    EnterStepMode:                    NEVER,                   NEVER;
    GetOutputDerivatives:             either(SM | T),          NEVER;
    DoStep:                           ok(SM),                  NEVER;
    ActivateModelPartition:           NEVER,                   NEVER;
}

impl F {
    /// A valid call of this function on the instance (NULL arrays of length 0 where the
    /// function takes value references and there is nothing to pass); its status. One arm per
    /// function of the standard, as the state table above has one row per function: kept whole
    /// (not split below ~150 lines) so that each function's valid call reads beside the others.
    pub fn call(self, i: &Inst) -> fmi3Status {
        let api = i.api();
        let name = self.name();
        /// `i.call(name, |c| <a call>)`, every call of this table being valid.
        macro_rules! valid {
            (|$c:ident| $call:expr) => {
                // SAFETY: a function of the library `i.fmu` keeps loaded, with the standard's
                // signature, called with pointers to live locals of the lengths passed (or NULL
                // with a length of 0), on this live instance (or NULL, which the FMU must refuse).
                i.call(name, |$c| unsafe { $call })
            };
        }
        /// This getter or setter (of values, clocks, intervals or shifts) of no variable: NULL
        /// arrays of length 0.
        macro_rules! none {
            () => {
                i.with_no_variable(name)
                    .unwrap_or_else(|| panic!("{name} takes no variable"))
            };
        }
        /// A getter of one readable variable of that type.
        macro_rules! get {
            ($f:ident, $ty:expr, $t:ty) => {{
                let v = readable(i.fmu, $ty);
                if v.is_empty() {
                    return none!();
                }
                i.args(vec![
                    ("vr", Val::U32s(v.clone())),
                    ("nValues", Val::U64(v.len() as u64)),
                ]);
                let mut out = Guarded::<$t>::new(v.len(), Default::default());
                let p = out.as_mut_ptr();
                let s = valid!(|c| (api.$f)(c, v.as_ptr(), v.len(), p, v.len()));
                out.into_values(|| format!("{name} with nValues = {}", v.len()), GETTER_RULE3);
                s
            }};
        }
        macro_rules! unary {
            ($f:ident) => {
                i.unary(name, api.$f)
            };
        }
        /// A model-exchange vector of `n` values.
        macro_rules! vector {
            ($f:ident, $n:expr) => {
                i.vector(name, api.$f, $n).0
            };
        }
        // nContinuousStates and nEventIndicators count every element of the state and indicator
        // arrays (the structural parameters at their starts).
        let n_states = i.fmu.n_states_declared();
        match self {
            F::SetDebugLogging => i.set_debug_logging(false, 0, None),
            F::EnterInitializationMode => {
                i.args(vec![("startTime", Val::F64(0.0))]);
                valid!(|c| (api.enter_initialization_mode)(c, false, 0.0, 0.0, false, 0.0))
            }
            F::ExitInitializationMode => unary!(exit_initialization_mode),
            F::EnterEventMode => unary!(enter_event_mode),
            F::Terminate => unary!(terminate),
            F::Reset => unary!(reset),
            F::GetFloat64 => get!(get_float64, Type::Float64, f64),
            F::GetInt32 => get!(get_int32, Type::Int32, i32),
            F::GetInt64 => get!(get_int64, Type::Enumeration, i64),
            F::GetBoolean => get!(get_boolean, Type::Boolean, u8),
            F::GetString => {
                let v = readable(i.fmu, Type::String);
                if v.is_empty() {
                    return none!();
                }
                i.args(vec![
                    ("vr", Val::U32s(v.clone())),
                    ("nValues", Val::U64(v.len() as u64)),
                ]);
                let mut out = vec![null(); v.len()];
                let n = out.len();
                valid!(
                    |c| crate::guard::fill(&mut out, "fmi3GetString", "nValues", crate::guard::GETTER_RULE3, |p| {
                        (api.get_string)(c, v.as_ptr(), v.len(), p, n)
                    })
                )
            }
            F::GetFloat32 => none!(),
            F::GetInt8 => none!(),
            F::GetUInt8 => none!(),
            F::GetInt16 => none!(),
            F::GetUInt16 => none!(),
            F::GetUInt32 => none!(),
            F::GetUInt64 => none!(),
            F::GetBinary => none!(),
            F::SetFloat64 => none!(),
            F::SetInt32 => none!(),
            F::SetInt64 => none!(),
            F::SetBoolean => none!(),
            F::SetString => none!(),
            F::SetFloat32 => none!(),
            F::SetInt8 => none!(),
            F::SetUInt8 => none!(),
            F::SetInt16 => none!(),
            F::SetUInt16 => none!(),
            F::SetUInt32 => none!(),
            F::SetUInt64 => none!(),
            F::SetBinary | F::GetClock | F::SetClock => none!(),
            F::GetNumberOfVariableDependencies => {
                i.number_of_dependencies(first_of(i.fmu, Type::Float64).unwrap_or(0)).0
            }
            F::GetVariableDependencies => i.dependencies(first_of(i.fmu, Type::Float64).unwrap_or(0), 0).0,
            F::GetFMUState => {
                let mut st: fmi3FMUState = null_mut();
                let s = i.get_state(&mut st);
                if s == fmi3OK {
                    assert_eq!(
                        i.free_state(&mut st),
                        fmi3OK,
                        "{}: fmi3FreeFMUState of a state just taken",
                        i.fmu.id
                    );
                }
                s
            }
            F::FreeFMUState => i.free_state(&mut null_mut()),
            F::GetDirectionalDerivative => derivative_call(i, false),
            F::GetAdjointDerivative => derivative_call(i, true),
            F::EnterConfigurationMode => unary!(enter_configuration_mode),
            F::ExitConfigurationMode => unary!(exit_configuration_mode),
            F::GetIntervalDecimal
            | F::GetIntervalFraction
            | F::GetShiftDecimal
            | F::GetShiftFraction
            | F::SetIntervalDecimal
            | F::SetIntervalFraction
            | F::SetShiftDecimal
            | F::SetShiftFraction => none!(),
            F::EvaluateDiscreteStates => unary!(evaluate_discrete_states),
            F::UpdateDiscreteStates => {
                let mut f = [0u8; 5];
                let mut t = 0.0;
                valid!(|c| crate::guard::fill_outputs(
                    "fmi3UpdateDiscreteStates",
                    &mut f,
                    &mut t,
                    |[a, b, cc, d, e], t| (api.update_discrete_states)(c, a, b, cc, d, e, t)
                ))
            }
            F::EnterContinuousTimeMode => unary!(enter_continuous_time_mode),
            F::CompletedIntegratorStep => {
                let (mut a, mut b) = (0u8, 0u8);
                i.args(vec![]);
                valid!(|c| crate::guard::fill_integrator_step3(&mut a, &mut b, |qa, qb| (api
                    .completed_integrator_step)(
                    c, true, qa, qb
                )))
            }
            F::SetTime => {
                i.args(vec![("time", Val::F64(0.0))]);
                valid!(|c| (api.set_time)(c, 0.0))
            }
            F::SetContinuousStates => {
                let x = vec![0.0; n_states];
                i.args(vec![("values", Val::F64s(x.clone()))]);
                valid!(|c| (api.set_continuous_states)(c, x.as_ptr(), n_states))
            }
            F::GetContinuousStateDerivatives => vector!(get_continuous_state_derivatives, n_states),
            F::GetEventIndicators => vector!(get_event_indicators, i.fmu.n_event_indicators_declared()),
            F::GetContinuousStates => vector!(get_continuous_states, n_states),
            F::GetNominalsOfContinuousStates => vector!(get_nominals_of_continuous_states, n_states),
            F::GetNumberOfEventIndicators => {
                let mut n = 0;
                valid!(|c| crate::guard::fill_one(
                    &mut n,
                    "fmi3GetNumberOfEventIndicators",
                    "one size_t",
                    crate::guard::COUNT_RULE3,
                    |q| (api.get_number_of_event_indicators)(c, q)
                ))
            }
            F::GetNumberOfContinuousStates => {
                let mut n = 0;
                valid!(|c| crate::guard::fill_one(
                    &mut n,
                    "fmi3GetNumberOfContinuousStates",
                    "one size_t",
                    crate::guard::COUNT_RULE3,
                    |q| (api.get_number_of_continuous_states)(c, q)
                ))
            }
            F::EnterStepMode => unary!(enter_step_mode),
            F::GetOutputDerivatives => {
                let v = vr_list(i.fmu, Type::Float64);
                i.get_output_derivatives(&v, &vec![1i32; v.len()]).0
            }
            F::DoStep => {
                let (mut f, mut t) = ([0u8; 3], 0.0);
                let h = i.fmu.step_size();
                i.args(vec![
                    ("currentCommunicationPoint", Val::F64(0.0)),
                    ("communicationStepSize", Val::F64(h)),
                ]);
                valid!(
                    |c| crate::guard::fill_outputs("fmi3DoStep", &mut f, &mut t, |[a, b, d], t| {
                        (api.do_step)(c, 0.0, h, true, a, b, d, t)
                    })
                )
            }
            F::ActivateModelPartition => i.activate_model_partition(0, 0.0),
        }
    }
}

fn first_of(fmu: &Fmu3, ty: Type) -> Option<u32> {
    fmu.md
        .of_type(ty)
        .find(|v| v.causality == Causality::Output)
        .or_else(|| fmu.md.of_type(ty).next())
        .map(|v| v.vr)
}

fn vr_list(fmu: &Fmu3, ty: Type) -> Vec<u32> {
    first_of(fmu, ty).into_iter().collect()
}

/// The Derivative call with valid arguments: one unknown (a derivative in ME, else an output),
/// one known (a state in ME, else a continuous input), or none; nSeed and nSensitivity count
/// their elements (an array's every element).
fn derivative_call(i: &Inst, adjoint: bool) -> fmi3Status {
    let (u_var, k_var) = derivative_pair(i.fmu, i.me);
    let elements = |v: &[&Variable]| v.iter().map(|v| i.fmu.element_count(v)).sum::<usize>();
    let (nu, nk) = (elements(&u_var), elements(&k_var));
    let u: Vec<u32> = u_var.iter().map(|v| v.vr).collect();
    let k: Vec<u32> = k_var.iter().map(|v| v.vr).collect();
    let seed = vec![1.0; if adjoint { nu } else { nk }];
    let mut sens = vec![0.0; if adjoint { nk } else { nu }];
    i.derivative(adjoint, &u, &k, &seed, &mut sens)
}

fn derivative_pair(fmu: &Fmu3, me: bool) -> (Vec<&Variable>, Vec<&Variable>) {
    let (u, k) = (unknowns(fmu, me), knowns(fmu, me));
    if u.is_empty() || k.is_empty() {
        return (vec![], vec![]);
    }
    (vec![u[0]], vec![k[0]])
}

/// What the getters' rows read: one variable with a start value (readable in every state the
/// getters are allowed in, Instantiated included), or none.
fn readable(fmu: &Fmu3, ty: Type) -> Vec<u32> {
    with_start(fmu, ty).map(|v| v.vr).take(1).collect()
}
