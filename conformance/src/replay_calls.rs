//! The replay of a named check's reproducer ([`crate::calllog`]): every call written with all of
//! its arguments, made again literally (no model of the state machine decides anything), on an
//! instance driven through the suite's own wrappers, so that the guard after every buffer the FMU
//! is given is checked as it was in the check. Such a file's first line names the instance
//! (`fmi2Instantiate instanceName=...`, `fmi3InstantiateCoSimulation instanceName=...`): that is
//! how [`crate::replay::run::replay`] tells it from a random sequence's reproducer.
//!
//! Each call is printed with its status, the values a getter returned and the messages the FMU
//! logged. A difference (exit 1): a status the line does not expect, values other than the
//! line's `expect=[...]` (within `within=`), a guard after a buffer overwritten (a getter that
//! wrote past nValues), or one of the wrappers' own assertions (a message logged under another
//! instance's environment, ...).

use crate::calllog::{decode, unhex};
use crate::fmi2::*;
use crate::fmi3::types::fmi3FMUState;
use crate::guard::{Guarded, STATE_RULE3};
use crate::instance::{Args, Instance};
use crate::instance_calls::{Derivative, kind_of};
use crate::replay::fmi3::replays_values_of;
use crate::replay::{Expected, Line, ReplayReport, list, real, replay_line};
use crate::{Fmu, Fmu3};
use std::collections::BTreeMap;

/// A line's `expect=[...] within=W`, compared with what the call gave.
fn compare(l: &Line, got: &[f64]) -> Result<(), String> {
    let Some(want) = (if l.has("expect") {
        l.list::<f64>("expect")?
    } else {
        None
    }) else {
        return Ok(());
    };
    let within: f64 = l.parse_or("within", 0.0)?;
    let same = want.len() == got.len() && want.iter().zip(got).all(|(w, g)| w == g || (w - g).abs() <= within);
    if same {
        Ok(())
    } else {
        Err(format!(
            "line {}: {} gave {}, the check expected {} (within {})",
            l.number,
            l.function,
            list(got.iter().map(|x| real(*x))),
            list(want.iter().map(|x| real(*x))),
            real(within)
        ))
    }
}

fn text(l: &Line, key: &str) -> Result<Option<String>, String> {
    match l.raw(key)? {
        "NULL" => Ok(None),
        w => decode(w).map(Some).map_err(|e| l.error(e)),
    }
}

/// The FMU states of a replay by their number in the file.
struct States<T>(BTreeMap<usize, T>);

impl<T: Copy> States<T> {
    fn get(&self, l: &Line, null: T) -> Result<T, String> {
        if l.raw("state")? == "NULL" {
            return Ok(null);
        }
        let n: usize = l.parse("state")?;
        self.0
            .get(&n)
            .copied()
            .ok_or_else(|| l.error(format!("state={n}: no call before made FMU state {n}")))
    }
}

/// Prints and checks one call: its line, then `details` (values, outputs), then the log.
struct Printer<'o> {
    out: &'o mut dyn FnMut(&str),
    report: ReplayReport,
}

impl<'o> Printer<'o> {
    /// A printer that has said what it replays.
    fn start(out: &'o mut dyn FnMut(&str), lines: &[Line], fmu: &str, version: &str) -> Printer<'o> {
        let mut p = Printer {
            out,
            report: ReplayReport::default(),
        };
        p.print(format!(
            "replaying {} calls of a named check on {fmu} (FMI {version}), each as the file writes it",
            lines.len() - 1
        ));
        next_line(lines, 0);
        p
    }

    /// Replays the lines after the first (the instance, made) by `one`, up to the first difference.
    fn replay_each(&mut self, lines: &[Line], mut one: impl FnMut(&Line, &mut Printer) -> Result<(), String>) {
        let first = &lines[0];
        self.print(format!("{:>4} {} -> an instance", first.number, first.function));
        for l in &lines[1..] {
            // A crash in the FMU names the line it died in (a replay in a worker process,
            // `crate::runner::replay_in_worker`).
            next_line(std::slice::from_ref(l), 0);
            // A wrapper's assertion (a guard overwritten, ...) is a difference at this line.
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| one(l, self)))
                .unwrap_or_else(|payload| Err(format!("line {}: {}: {}", l.number, l.function, panic_text(&*payload))));
            if let Err(d) = r {
                self.report.difference = Some(d);
                break;
            }
        }
        next_line(&[], 0);
    }

    fn print(&mut self, text: String) {
        (self.out)(&text);
        self.report.lines.push(text);
    }

    /// Err: the difference that ends the replay (a status the line does not expect, then
    /// `values` other than the line's `expect=`).
    fn call(
        &mut self,
        l: &Line,
        status: u32,
        details: Vec<String>,
        log: Vec<String>,
        values: Option<Vec<f64>>,
    ) -> Result<(), String> {
        let expected = l.expected.unwrap_or(Expected::ANY);
        self.print(replay_line(l, &l.function, status, expected));
        for d in details {
            self.print(format!("       {d}"));
        }
        for m in log {
            self.print(format!("       log {m}"));
        }
        if !expected.contains(status) {
            return Err(format!(
                "line {}: {} answered {}, the file expects {expected}",
                l.number,
                l.function,
                crate::replay::status_word(status)
            ));
        }
        match values {
            Some(v) => compare(l, &v),
            None => Ok(()),
        }
    }
}

/// Names the line a replay makes next (`lines[k]`; past the end: the instance's end) in the
/// breadcrumb, so that a crash in the FMU says which line it died in (a replay in a worker
/// process, [`crate::runner::replay_in_worker`]).
pub fn next_line(lines: &[Line], k: usize) {
    match lines.get(k) {
        Some(l) => crate::outcome::breadcrumb_context(&format!("line {} ({})", l.number, l.function)),
        None => crate::outcome::breadcrumb_context("after the last line replayed, freeing the instance"),
    }
}

/// A message the FMU logged, as the replay prints it.
fn log_line(status: impl std::fmt::Display, category: &str, message: &str) -> String {
    format!("[{status}] {category}: {message}")
}

/// Replays a named check's FMI 2.0 reproducer (first line `fmi2Instantiate instanceName=...`).
pub fn replay2(fmu: &Fmu, lines: &[Line], out: &mut dyn FnMut(&str)) -> Result<ReplayReport, String> {
    let first = &lines[0];
    let own = |l: &Line, key: &str, own: String| -> Result<Option<String>, String> {
        Ok(match text(l, key)? {
            Some(t) if t == "own" => Some(own),
            t => t,
        })
    };
    let args = Args {
        name: text(first, "instanceName")?,
        fmu_type: match first.raw("fmuType")? {
            "CoSimulation" => fmi2CoSimulation,
            "ModelExchange" => fmi2ModelExchange,
            t => return Err(first.error(format!("fmuType={t}: CoSimulation or ModelExchange"))),
        },
        guid: own(first, "guid", fmu.md.guid.clone())?,
        resources: own(first, "resourceLocation", fmu.resource_uri())?,
        logging_on: first.parse_or("loggingOn", false)?,
    };
    let mut p = Printer::start(out, lines, &fmu.id, "2.0");
    let mut inst = match Instance::with(fmu, &args) {
        Ok(i) => i,
        Err(log) => {
            p.report.difference = Some(format!("line {}: fmi2Instantiate returned NULL: {log:?}", first.number));
            return Ok(p.report);
        }
    };
    let mut states = States::<fmi2FMUstate>(BTreeMap::new());
    p.replay_each(lines, |l, p| replay2_line(&mut inst, &mut states, l, p));
    Ok(p.report)
}

/// A panic's message.
fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "a panic without a message".into())
}

fn vrs(l: &Line) -> Result<Vec<u32>, String> {
    Ok(l.list::<u32>("vr")?.unwrap_or_default())
}

fn replay2_line(
    inst: &mut Instance,
    states: &mut States<fmi2FMUstate>,
    l: &Line,
    p: &mut Printer,
) -> Result<(), String> {
    let mut details = vec![];
    let mut values: Option<Vec<f64>> = None;
    let probe = |list: &[&'static str]| crate::instance_calls::named(list, &l.function);
    let s = match l.function.as_str() {
        // The probes of a NULL component (no other argument is written: they are the check's).
        _ if l.raw("component").ok() == Some("NULL") => {
            if l.function == "fmi2FreeInstance" {
                inst.free_instance_null();
                fmi2OK
            } else {
                let f = probe(&crate::instance_calls::NULL_COMPONENT_PROBES)
                    .or_else(|| probe(crate::instance_calls::ME_NULL_COMPONENT_PROBES))
                    .ok_or_else(|| l.error("not a function the check of a NULL component calls"))?;
                inst.null_component(f)
            }
        }
        // A getter or setter with its arrays as given (NULL with nvr > 0, nvr = 0).
        _ if l.has("nvr") => {
            let f = probe(&crate::instance_calls::ARRAY_PROBES).ok_or_else(|| {
                l.error("nvr= is written for the getters and setters of Real, Integer, Boolean, String")
            })?;
            let vr = l.list::<u32>("vr")?;
            let nvr: usize = l.parse("nvr")?;
            if vr.as_ref().is_some_and(|v| v.len() < nvr) {
                return Err(l.error("vr holds fewer value references than nvr"));
            }
            inst.array_probe(f, vr.as_deref(), nvr, l.raw("value").ok() != Some("NULL"))
        }
        "fmi2SetupExperiment" => {
            let stop = if l.raw("stopTime")? == "NULL" {
                None
            } else {
                Some(l.parse("stopTime")?)
            };
            inst.setup(l.parse("startTime")?, stop)
        }
        "fmi2EnterInitializationMode" => inst.enter_init(),
        "fmi2ExitInitializationMode" => inst.exit_init(),
        "fmi2Terminate" => inst.terminate(),
        "fmi2Reset" => inst.reset(),
        "fmi2DoStep" => inst.do_step(l.parse("currentCommunicationPoint")?, l.parse("communicationStepSize")?),
        "fmi2GetReal" => {
            let (s, v) = inst.get_real(&vrs(l)?);
            details.push(format!("values {}", list(v.iter().map(|x| real(*x)))));
            values = Some(v);
            s
        }
        "fmi2GetInteger" | "fmi2GetBoolean" => {
            let (s, v) = if l.function == "fmi2GetInteger" {
                inst.get_integer(&vrs(l)?)
            } else {
                inst.get_boolean(&vrs(l)?)
            };
            details.push(format!("values {}", list(&v)));
            values = Some(v.iter().map(|x| f64::from(*x)).collect());
            s
        }
        "fmi2SetReal" => inst.set_real(&vrs(l)?, &l.list::<f64>("values")?.unwrap_or_default()),
        "fmi2SetInteger" => inst.set_integer(&vrs(l)?, &l.list::<i32>("values")?.unwrap_or_default()),
        "fmi2SetBoolean" => {
            let v: Vec<bool> = l
                .list::<i32>("values")?
                .unwrap_or_default()
                .iter()
                .map(|x| *x != 0)
                .collect();
            inst.set_boolean(&vrs(l)?, &v)
        }
        "fmi2DeSerializeFMUstate" if l.raw("bytes")? == "NULL" || l.has("statePointer") => {
            if l.raw("bytes")? == "NULL" {
                inst.deserialize_raw(None, l.parse("size")?, !l.has("statePointer"))
            } else {
                let bytes = unhex(l.raw("bytes")?).map_err(|e| l.error(e))?;
                inst.deserialize_raw(Some(&bytes), bytes.len(), false)
            }
        }
        "fmi2FreeFMUstate" if l.has("statePointer") => inst.free_state_pointer_null(),
        "fmi2GetFMUstate" if l.has("into") => {
            let into: usize = l.parse("into")?;
            let mut st = *states
                .0
                .get(&into)
                .ok_or_else(|| l.error(format!("into={into}: no call before made FMU state {into}")))?;
            let s = inst.get_state_into(&mut st);
            states.0.insert(into, st);
            if l.has("state") {
                states.0.insert(l.parse("state")?, st);
            }
            details.push(format!("FMUstate {st:?}"));
            s
        }
        "fmi2GetFMUstate" | "fmi2DeSerializeFMUstate" => {
            let (s, st) = if l.function == "fmi2GetFMUstate" {
                inst.get_state()
            } else {
                let bytes = unhex(l.raw("bytes")?).map_err(|e| l.error(e))?;
                inst.deserialize(&bytes)
            };
            if l.has("state") && l.raw("state")? != "NULL" {
                states.0.insert(l.parse("state")?, st);
            }
            details.push(format!("FMUstate {st:?}"));
            s
        }
        "fmi2SetFMUstate" => inst.set_state(states.get(l, std::ptr::null_mut())?),
        "fmi2FreeFMUstate" => {
            let mut st = states.get(l, std::ptr::null_mut())?;
            let s = inst.free_state(&mut st);
            details.push(format!("FMUstate after the call {st:?}"));
            s
        }
        "fmi2SerializedFMUstateSize" => {
            let (s, size) = inst.serialized_size(states.get(l, std::ptr::null_mut())?);
            details.push(format!("size {size}"));
            s
        }
        "fmi2SerializeFMUstate" => {
            let (s, bytes) = inst.serialize_into(states.get(l, std::ptr::null_mut())?, l.parse("size")?);
            details.push(format!("{} bytes", bytes.len()));
            // Compared only where the line expects bytes (a refusal that wrote into the buffer).
            values = Some(bytes.iter().map(|b| f64::from(*b)).collect());
            s
        }
        "fmi2GetRealStatus" => match l.raw("kind")? {
            "fmi2LastSuccessfulTime" if !l.has("value") => {
                let (s, t) = inst.last_successful_time();
                details.push(format!("value {}", real(t)));
                values = Some(vec![t]);
                s
            }
            k => {
                let null = l.raw("value").ok() == Some("NULL");
                let (s, v) = inst.real_status(kind_of(k).map_err(|e| l.error(e))?, (!null).then_some(-1.0));
                if !null {
                    details.push(format!("value {} (-1.0 before the call)", real(v)));
                    values = Some(vec![v]);
                }
                s
            }
        },
        "fmi2GetBooleanStatus" => match l.raw("kind")? {
            "fmi2Terminated" => {
                let (s, b) = inst.terminated();
                details.push(format!("value {b}"));
                s
            }
            k => {
                let (s, b) = inst.boolean_status(kind_of(k).map_err(|e| l.error(e))?);
                details.push(format!("value {b} (-1 before the call)"));
                values = Some(vec![f64::from(b)]);
                s
            }
        },
        "fmi2SetDebugLogging" if l.has("nCategories") => {
            let categories: Option<Vec<Option<String>>> = match l.list::<String>("categories")? {
                None => None,
                Some(cs) => Some(
                    cs.iter()
                        .map(|c| if c == "NULL" { Ok(None) } else { decode(c).map(Some) })
                        .collect::<Result<_, _>>()
                        .map_err(|e| l.error(e))?,
                ),
            };
            let refs: Option<Vec<Option<&str>>> =
                categories.as_ref().map(|cs| cs.iter().map(Option::as_deref).collect());
            let n: usize = l.parse("nCategories")?;
            if refs.as_ref().is_some_and(|r| r.len() < n) {
                return Err(l.error("fewer categories than nCategories"));
            }
            inst.set_debug_logging_raw(l.parse("loggingOn")?, n, refs.as_deref())
        }
        "fmi2SetDebugLogging" => {
            let names: Vec<String> = l
                .list::<String>("categories")?
                .unwrap_or_default()
                .iter()
                .map(|c| decode(c))
                .collect::<Result<_, _>>()
                .map_err(|e| l.error(e))?;
            let refs: Vec<&str> = names.iter().map(String::as_str).collect();
            inst.set_debug_logging(l.parse("loggingOn")?, &refs)
        }
        "fmi2GetStatus" => {
            let (s, v) = inst.get_status(kind_of(l.raw("kind")?).map_err(|e| l.error(e))?);
            details.push(format!("value {v}"));
            s
        }
        "fmi2GetIntegerStatus" => {
            let (s, v) = inst.get_integer_status(kind_of(l.raw("kind")?).map_err(|e| l.error(e))?);
            details.push(format!("value {v}"));
            s
        }
        "fmi2GetStringStatus" => {
            let (s, v) = inst.get_string_status(kind_of(l.raw("kind")?).map_err(|e| l.error(e))?);
            details.push(format!("value {v:?}"));
            s
        }
        "fmi2CancelStep" => inst.cancel_step(),
        "fmi2GetString" => {
            let (s, v) = inst.get_string(&vrs(l)?);
            details.push(format!("values {v:?}"));
            s
        }
        "fmi2SetString" => {
            let texts: Vec<String> = l
                .list::<String>("values")?
                .unwrap_or_default()
                .iter()
                .map(|t| decode(t))
                .collect::<Result<_, _>>()
                .map_err(|e| l.error(e))?;
            inst.set_string(&vrs(l)?, &texts)
        }
        "fmi2GetDirectionalDerivative" => {
            let unknowns = l.list::<u32>("unknowns")?;
            let knowns = l.list::<u32>("knowns")?;
            let seed = l.list::<f64>("seed")?;
            let d = Derivative {
                unknowns: unknowns.as_deref(),
                n_unknown: l.parse("nUnknown")?,
                knowns: knowns.as_deref(),
                n_known: l.parse("nKnown")?,
                seed: seed.as_deref(),
                output: !l.has("dvUnknown"),
            };
            // The wrapper passes the arrays as they are: none may be shorter than its count.
            let short = |a: Option<usize>, n: usize| a.is_some_and(|a| a < n);
            if short(d.unknowns.map(<[u32]>::len), d.n_unknown)
                || short(d.knowns.map(<[u32]>::len), d.n_known)
                || short(d.seed.map(<[f64]>::len), d.n_known)
            {
                return Err(l.error("an array shorter than its count (nUnknown, nKnown)"));
            }
            let (s, v) = inst.directional_derivative(d);
            details.push(format!("values {}", list(v.iter().map(|x| real(*x)))));
            values = Some(v);
            s
        }
        "fmi2SetRealInputDerivatives" => inst.set_real_input_derivatives(
            &vrs(l)?,
            &l.list::<i32>("order")?.unwrap_or_default(),
            &l.list::<f64>("values")?.unwrap_or_default(),
        ),
        "fmi2GetRealOutputDerivatives" => {
            let (s, v) = inst.get_real_output_derivatives(&vrs(l)?, &l.list::<i32>("order")?.unwrap_or_default());
            details.push(format!("values {}", list(v.iter().map(|x| real(*x)))));
            values = Some(v);
            s
        }
        "fmi2SetTime" => inst.set_time(l.parse("time")?),
        "fmi2SetContinuousStates" if l.raw("x")? == "NULL" => inst.set_continuous_states_null(l.parse("nx")?),
        "fmi2SetContinuousStates" => inst.set_continuous_states(&l.list::<f64>("x")?.unwrap_or_default()),
        "fmi2GetContinuousStates"
        | "fmi2GetDerivatives"
        | "fmi2GetEventIndicators"
        | "fmi2GetNominalsOfContinuousStates"
            if l.has("values") =>
        {
            let name = crate::me::VECTOR_GETTERS
                .iter()
                .find(|n| **n == l.function)
                .expect("one of the vector getters");
            if l.raw("values")? != "NULL" {
                return Err(l.error("values: NULL or left out (the FMU writes them)"));
            }
            inst.get_vector_null(name, l.parse("n")?)
        }
        "fmi2NewDiscreteStates" if l.has("eventInfo") => inst.new_discrete_states_null(),
        "fmi2CompletedIntegratorStep" if l.has("enterEventMode") || l.has("terminateSimulation") => {
            inst.completed_integrator_step_null(l.has("enterEventMode"))
        }
        "fmi2GetContinuousStates"
        | "fmi2GetDerivatives"
        | "fmi2GetEventIndicators"
        | "fmi2GetNominalsOfContinuousStates" => {
            let name = crate::me::VECTOR_GETTERS
                .iter()
                .find(|n| **n == l.function)
                .expect("one of the vector getters");
            let (s, v) = inst.get_vector_n(name, l.parse("n")?);
            details.push(format!("values {}", list(v.iter().map(|x| real(*x)))));
            values = Some(v);
            s
        }
        "fmi2EnterEventMode" => inst.enter_event_mode(),
        "fmi2EnterContinuousTimeMode" => inst.enter_continuous_time_mode(),
        "fmi2NewDiscreteStates" => {
            let (s, e) = inst.new_discrete_states();
            details.push(format!(
                "newDiscreteStatesNeeded {} terminateSimulation {} nominalsOfContinuousStatesChanged {} \
                 valuesOfContinuousStatesChanged {} nextEventTimeDefined {} nextEventTime {}",
                e.newDiscreteStatesNeeded,
                e.terminateSimulation,
                e.nominalsOfContinuousStatesChanged,
                e.valuesOfContinuousStatesChanged,
                e.nextEventTimeDefined,
                real(e.nextEventTime)
            ));
            s
        }
        "fmi2CompletedIntegratorStep" => {
            let c = inst.completed_integrator_step();
            details.push(format!(
                "enterEventMode {} terminateSimulation {}",
                c.enter_event_mode, c.terminate_simulation
            ));
            c.status
        }
        f => return Err(l.error(format!("{f} is not a call the replay of a named check makes (FMI 2.0)"))),
    };
    let log = inst.log();
    let log = log
        .iter()
        .map(|e| log_line(crate::instance::status_name(e.status), &e.category, &e.text));
    p.call(l, s, details, log.collect(), values)
}

/// Replays a named check's FMI 3.0 reproducer (first line `fmi3InstantiateCoSimulation
/// instanceName=...` or `fmi3InstantiateModelExchange instanceName=...`).
pub fn replay3(fmu: &Fmu3, lines: &[Line], out: &mut dyn FnMut(&str)) -> Result<ReplayReport, String> {
    let first = &lines[0];
    let me = first.function == "fmi3InstantiateModelExchange";
    let name = text(first, "instanceName")?.unwrap_or_default();
    let event_mode: bool = first.parse_or("eventModeUsed", false)?;
    let early: bool = first.parse_or("earlyReturnAllowed", false)?;
    let intermediate: bool = first.parse_or("intermediateUpdate", false)?;
    let mut p = Printer::start(out, lines, &fmu.id, "3.0");
    let mut inst = match crate::fmi3::Inst::try_new_full(fmu, me, &name, (event_mode, early), intermediate) {
        Ok(i) => i,
        Err(e) => {
            p.report.difference = Some(format!("line {}: {e}", first.number));
            return Ok(p.report);
        }
    };
    // The file holds every call the check made, those of Event Mode too.
    inst.auto_events = false;
    let mut states = States::<fmi3FMUState>(BTreeMap::new());
    p.replay_each(lines, |l, p| replay3_line(&mut inst, &mut states, l, p));
    Ok(p.report)
}

fn replay3_line(
    inst: &mut crate::fmi3::Inst,
    states: &mut States<fmi3FMUState>,
    l: &Line,
    p: &mut Printer,
) -> Result<(), String> {
    use crate::fmi3::Type;
    let fmu = inst.fmu;
    let api = &fmu.api;
    let before = inst.sink.entries.lock().unwrap_or_else(|e| e.into_inner()).len();
    let mut details = vec![];
    let mut values: Option<Vec<f64>> = None;
    let f = l.function.as_str();
    let n = || -> Result<usize, String> { l.parse("n") };
    let s = match f {
        "fmi3EnterInitializationMode" => inst.enter_init(l.parse("startTime")?),
        "fmi3ExitInitializationMode" => inst.unary(f, api.exit_initialization_mode),
        "fmi3EnterEventMode" => inst.unary(f, api.enter_event_mode),
        "fmi3EnterContinuousTimeMode" => inst.unary(f, api.enter_continuous_time_mode),
        "fmi3EnterStepMode" => inst.unary(f, api.enter_step_mode),
        "fmi3EnterConfigurationMode" => inst.unary(f, api.enter_configuration_mode),
        "fmi3ExitConfigurationMode" => inst.unary(f, api.exit_configuration_mode),
        "fmi3Terminate" => inst.unary(f, api.terminate),
        "fmi3Reset" => inst.unary(f, api.reset),
        "fmi3EvaluateDiscreteStates" => inst.unary(f, api.evaluate_discrete_states),
        // A getter or setter of no variable (the state table's): every array NULL, counts 0.
        _ if l.has("nValueReferences") && !matches!(f, "fmi3GetFloat64" | "fmi3SetFloat64") => {
            if l.raw("vr")? != "NULL" || l.parse::<usize>("nValueReferences")? != 0 {
                return Err(l.error("nValueReferences= is written for no variable: vr=NULL nValueReferences=0"));
            }
            inst.with_no_variable(f)
                .ok_or_else(|| l.error("not a getter or setter the replay calls with no variable"))?
        }
        "fmi3GetOutputDerivatives" => {
            let order = l.list::<i32>("order")?.unwrap_or_default();
            let vr = vrs(l)?;
            if order.len() != vr.len() {
                return Err(l.error("order: one for each value reference"));
            }
            let (s, v) = inst.get_output_derivatives(&vr, &order);
            details.push(format!("values {}", list(v.iter().map(|x| real(*x)))));
            values = Some(v);
            s
        }
        "fmi3ActivateModelPartition" => {
            inst.activate_model_partition(l.parse("clockReference")?, l.parse("activationTime")?)
        }
        "fmi3UpdateDiscreteStates" => {
            let mut flags = [0u8; 5];
            let mut next = 0.0;
            // SAFETY: a live instance; five flags and a time, each with a guard after it.
            let s = inst.call(f, |c| unsafe {
                crate::guard::fill_outputs(f, &mut flags, &mut next, |[a, b, cc, d, e], t| {
                    (api.update_discrete_states)(c, a, b, cc, d, e, t)
                })
            });
            details.push(format!(
                "discreteStatesNeedUpdate {} terminateSimulation {} nominalsOfContinuousStatesChanged {} \
                 valuesOfContinuousStatesChanged {} nextEventTimeDefined {} nextEventTime {}",
                flags[0],
                flags[1],
                flags[2],
                flags[3],
                flags[4],
                real(next)
            ));
            s
        }
        "fmi3GetNumberOfContinuousStates" | "fmi3GetNumberOfEventIndicators" => {
            let g = if f == "fmi3GetNumberOfContinuousStates" {
                api.get_number_of_continuous_states
            } else {
                api.get_number_of_event_indicators
            };
            let mut k = usize::MAX;
            // SAFETY: a live instance; one size_t with a guard after it.
            let s = inst.call(f, |c| unsafe {
                crate::guard::fill_one(&mut k, f, "one size_t", crate::guard::COUNT_RULE3, |q| g(c, q))
            });
            details.push(format!("value {k}"));
            s
        }
        "fmi3GetContinuousStates"
        | "fmi3GetContinuousStateDerivatives"
        | "fmi3GetEventIndicators"
        | "fmi3GetNominalsOfContinuousStates" => {
            let g = match f {
                "fmi3GetContinuousStates" => api.get_continuous_states,
                "fmi3GetContinuousStateDerivatives" => api.get_continuous_state_derivatives,
                "fmi3GetEventIndicators" => api.get_event_indicators,
                _ => api.get_nominals_of_continuous_states,
            };
            if l.has("values") {
                if l.raw("values")? != "NULL" {
                    return Err(l.error("values: NULL or left out (the FMU writes them)"));
                }
                inst.vector_null(f, g, n()?)
            } else {
                let (s, v) = inst.vector(f, g, n()?);
                details.push(format!("values {}", list(v.iter().map(|x| real(*x)))));
                values = Some(v);
                s
            }
        }
        "fmi3SetTime" => {
            let t: f64 = l.parse("time")?;
            // SAFETY: a live instance.
            inst.call(f, |c| unsafe { (api.set_time)(c, t) })
        }
        "fmi3SetContinuousStates" => {
            let x = l.list::<f64>("values")?.unwrap_or_default();
            // SAFETY: a live instance; `x.len()` values.
            inst.call(f, |c| unsafe { (api.set_continuous_states)(c, x.as_ptr(), x.len()) })
        }
        "fmi3CompletedIntegratorStep" => {
            let (mut enter, mut term) = (7u8, 7u8);
            // SAFETY: a live instance; two one-byte outputs, each with a guard after it.
            let s = inst.call(f, |c| unsafe {
                crate::guard::fill_one(&mut enter, f, "one value", crate::guard::OUTPUT_ARGUMENTS_RULE3, |qa| {
                    crate::guard::fill_one(&mut term, f, "one value", crate::guard::OUTPUT_ARGUMENTS_RULE3, |qb| {
                        (api.completed_integrator_step)(c, true, qa, qb)
                    })
                })
            });
            details.push(format!("enterEventMode {enter} terminateSimulation {term}"));
            s
        }
        "fmi3DoStep" if l.has("outputs") => {
            if l.raw("outputs")? != "NULL" {
                return Err(l.error("outputs: NULL or left out"));
            }
            inst.do_step_null_outputs(l.parse("currentCommunicationPoint")?, l.parse("communicationStepSize")?)
        }
        "fmi3DeserializeFMUState" if l.raw("bytes").is_ok_and(|b| b == "NULL") => {
            inst.deserialize_null(l.parse("size")?)
        }
        "fmi3DoStep" => {
            inst.time = l.parse("currentCommunicationPoint")?;
            let (s, flags, last) = inst.do_step(l.parse("communicationStepSize")?);
            details.push(format!(
                "eventHandlingNeeded {} terminateSimulation {} earlyReturn {} lastSuccessfulTime {}",
                flags[0],
                flags[1],
                flags[2],
                real(last)
            ));
            values = Some(vec![last]);
            s
        }
        "fmi3GetFMUState" | "fmi3DeserializeFMUState" => {
            let mut st: fmi3FMUState = std::ptr::null_mut();
            let into = if l.has("into") {
                Some(l.parse::<usize>("into")?)
            } else {
                None
            };
            let s = if f == "fmi3GetFMUState" {
                if let Some(n) = into {
                    st = *states
                        .0
                        .get(&n)
                        .ok_or_else(|| l.error(format!("into={n}: no call before made FMU state {n}")))?;
                }
                inst.get_state(&mut st)
            } else {
                inst.deserialize(&unhex(l.raw("bytes")?).map_err(|e| l.error(e))?, &mut st)
            };
            if let Some(n) = into {
                states.0.insert(n, st);
            }
            if l.has("state") && l.raw("state")? != "NULL" {
                states.0.insert(l.parse("state")?, st);
            }
            details.push(format!("FMUState {st:?}"));
            s
        }
        "fmi3SetFMUState" => inst.set_state(states.get(l, std::ptr::null_mut())?),
        "fmi3FreeFMUState" => {
            let mut st = states.get(l, std::ptr::null_mut())?;
            let s = inst.free_state(&mut st);
            details.push(format!("FMUState after the call {st:?}"));
            s
        }
        "fmi3SerializedFMUStateSize" => {
            let st = states.get(l, std::ptr::null_mut())?;
            let mut size = 0usize;
            // SAFETY: a live instance, a state it made; one size_t with a guard after it.
            let s = inst.call(f, |c| unsafe {
                crate::guard::fill_state_size3(&mut size, f, |q| (api.serialized_fmu_state_size)(c, st, q))
            });
            details.push(format!("size {size}"));
            s
        }
        "fmi3SerializeFMUState" => {
            let st = states.get(l, std::ptr::null_mut())?;
            let size: usize = l.parse("size")?;
            let mut g = Guarded::new(size, 0u8);
            let q = g.as_mut_ptr();
            // SAFETY: a live instance, a state it made; `size` bytes and the guard after them.
            let s = inst.call(f, |c| unsafe { (api.serialize_fmu_state)(c, st, q, size) });
            let bytes = g.into_values(|| format!("fmi3SerializeFMUState with size = {size}"), STATE_RULE3);
            details.push(format!("{} bytes", bytes.len()));
            s
        }
        "fmi3GetDirectionalDerivative" | "fmi3GetAdjointDerivative" if l.has("nSeed") => {
            let seed = l.list::<f64>("seed")?;
            let n_seed: usize = l.parse("nSeed")?;
            if seed.as_ref().is_some_and(|x| x.len() < n_seed) {
                return Err(l.error("seed holds fewer values than nSeed"));
            }
            inst.derivative_probe(
                f == "fmi3GetAdjointDerivative",
                &l.list::<u32>("unknowns")?.unwrap_or_default(),
                &l.list::<u32>("knowns")?.unwrap_or_default(),
                seed.as_deref(),
                n_seed,
                l.parse("nSensitivity")?,
            )
        }
        "fmi3GetDirectionalDerivative" | "fmi3GetAdjointDerivative" => {
            let unknowns = l.list::<u32>("unknowns")?.unwrap_or_default();
            let knowns = l.list::<u32>("knowns")?.unwrap_or_default();
            let seed = l.list::<f64>("seed")?.unwrap_or_default();
            let mut sensitivity = vec![0.0; l.parse("nSensitivity")?];
            let s = inst.derivative(
                f == "fmi3GetAdjointDerivative",
                &unknowns,
                &knowns,
                &seed,
                &mut sensitivity,
            );
            details.push(format!("sensitivity {}", list(sensitivity.iter().map(|x| real(*x)))));
            values = Some(sensitivity);
            s
        }
        "fmi3GetString" => {
            let vr = vrs(l)?;
            let n: usize = l.parse("nValues")?;
            let mut out = Guarded::new(n, std::ptr::null::<std::ffi::c_char>());
            let q = out.as_mut_ptr();
            // SAFETY: a live instance; `vr.len()` value references, `n` values and the guard after them.
            let s = inst.call(f, |c| unsafe { (api.get_string)(c, vr.as_ptr(), vr.len(), q, n) });
            let out = out.into_values(
                || format!("fmi3GetString with nValues = {n}"),
                crate::guard::GETTER_RULE3,
            );
            let gave = s == crate::fmi3::types::fmi3OK || s == crate::fmi3::types::fmi3Warning;
            let texts: Vec<Option<String>> = out
                .iter()
                .map(|p| {
                    (gave && !p.is_null()).then(|| {
                        // SAFETY: a string the FMU returned, valid until its next call.
                        unsafe { std::ffi::CStr::from_ptr(*p) }.to_string_lossy().into_owned()
                    })
                })
                .collect();
            details.push(format!("values {texts:?}"));
            s
        }
        "fmi3GetClock" => {
            let vr = vrs(l)?;
            let mut out = Guarded::new(vr.len(), 7u8);
            let q = out.as_mut_ptr();
            // SAFETY: a live instance; `vr.len()` value references and values, the guard after them.
            let s = inst.call(f, |c| unsafe { (api.get_clock)(c, vr.as_ptr(), vr.len(), q) });
            let out = out.into_values(
                || format!("fmi3GetClock with nValues = {}", vr.len()),
                crate::guard::CLOCK_RULE3,
            );
            details.push(format!("values {}", list(&out)));
            values = Some(out.iter().map(|x| f64::from(*x)).collect());
            s
        }
        "fmi3SetClock" => {
            let vr = vrs(l)?;
            let on: Vec<bool> = l
                .list::<i64>("values")?
                .unwrap_or_default()
                .iter()
                .map(|x| *x != 0)
                .collect();
            if on.len() != vr.len() {
                return Err(l.error("values: one for each value reference"));
            }
            // SAFETY: a live instance; `vr.len()` value references and values.
            inst.call(f, |c| unsafe { (api.set_clock)(c, vr.as_ptr(), vr.len(), on.as_ptr()) })
        }
        "fmi3GetIntervalDecimal" => {
            let vr = vrs(l)?;
            let mut h = Guarded::new(vr.len(), f64::NAN);
            let mut q = Guarded::new(vr.len(), 99u32);
            let (ph, pq) = (h.as_mut_ptr(), q.as_mut_ptr());
            // SAFETY: a live instance; `vr.len()` value references, intervals and qualifiers, each
            // array with a guard after it.
            let s = inst.call(f, |c| unsafe {
                (api.get_interval_decimal)(c, vr.as_ptr(), vr.len(), ph, pq)
            });
            let h = h.into_values(
                || "fmi3GetIntervalDecimal (intervals)".into(),
                crate::guard::CLOCK_RULE3,
            );
            let q = q.into_values(
                || "fmi3GetIntervalDecimal (qualifiers)".into(),
                crate::guard::CLOCK_RULE3,
            );
            details.push(format!(
                "intervals {} qualifiers {}",
                list(h.iter().map(|x| real(*x))),
                list(&q)
            ));
            values = Some(h);
            s
        }
        "fmi3GetShiftDecimal" => {
            let vr = vrs(l)?;
            let mut out = Guarded::new(vr.len(), f64::NAN);
            let q = out.as_mut_ptr();
            // SAFETY: a live instance; `vr.len()` value references and values, the guard after them.
            let s = inst.call(f, |c| unsafe { (api.get_shift_decimal)(c, vr.as_ptr(), vr.len(), q) });
            let out = out.into_values(|| "fmi3GetShiftDecimal".into(), crate::guard::CLOCK_RULE3);
            details.push(format!("values {}", list(out.iter().map(|x| real(*x)))));
            values = Some(out);
            s
        }
        // fmi3GetFloat64 and fmi3SetFloat64 with their arrays as given (NULL, a wrong nValues).
        "fmi3GetFloat64" | "fmi3SetFloat64" if l.has("nValueReferences") => {
            let vr = l.list::<u32>("vr")?;
            let n_vr: usize = l.parse("nValueReferences")?;
            let n_values: usize = l.parse("nValues")?;
            if vr.as_ref().is_some_and(|v| v.len() < n_vr) {
                return Err(l.error("vr holds fewer value references than nValueReferences"));
            }
            let set = f == "fmi3SetFloat64";
            let given = if l.has("values") {
                l.list::<f64>("values")?
            } else {
                Some(vec![0.0; n_values])
            };
            if set && given.as_ref().is_some_and(|x| x.len() < n_values) {
                return Err(l.error("values holds fewer values than nValues"));
            }
            inst.float64_probe(set, vr.as_deref(), n_vr, given.as_deref(), n_values)
        }
        "fmi3SetDebugLogging" => {
            let categories: Option<Vec<String>> = match l.list::<String>("categories")? {
                None => None,
                Some(cs) => Some(
                    cs.iter()
                        .map(|c| decode(c))
                        .collect::<Result<_, _>>()
                        .map_err(|e| l.error(e))?,
                ),
            };
            let n: usize = l.parse("nCategories")?;
            if categories.as_ref().is_some_and(|c| c.len() < n) {
                return Err(l.error("fewer categories than nCategories"));
            }
            inst.set_debug_logging(l.parse("loggingOn")?, n, categories.as_deref())
        }
        "fmi3GetBinary" => {
            let (s, sizes, bytes) = inst.get_binary(&vrs(l)?, l.parse("nValues")?);
            details.push(format!(
                "valueSizes {} values {}",
                list(&sizes),
                list(bytes.into_iter().map(crate::calllog::Val::Bytes))
            ));
            s
        }
        "fmi3GetNumberOfVariableDependencies" => {
            let (s, n) = inst.number_of_dependencies(l.parse("dependent")?);
            details.push(format!("nDependencies {n}"));
            s
        }
        "fmi3GetVariableDependencies" => {
            let (s, (e_dep, ind, e_ind, kinds)) = inst.dependencies(l.parse("dependent")?, l.parse("nDependencies")?);
            details.push(format!(
                "elementIndicesOfDependent {} independents {} elementIndicesOfIndependents {} dependencyKinds {}",
                list(&e_dep),
                list(&ind),
                list(&e_ind),
                list(&kinds)
            ));
            values = Some(ind.iter().map(|x| f64::from(*x)).collect());
            s
        }
        "fmi3GetFloat64" if !l.has("bytes") => {
            let (s, v) = inst.get_f64_n(&vrs(l)?, l.parse("nValues")?);
            details.push(format!("values {}", list(v.iter().map(|x| real(*x)))));
            values = Some(v);
            s
        }
        "fmi3SetFloat64" if !l.has("bytes") => inst.set_f64(&vrs(l)?, &l.list::<f64>("values")?.unwrap_or_default()),
        _ if f.starts_with("fmi3Get") || f.starts_with("fmi3Set") => {
            let vr = *vrs(l)?
                .first()
                .ok_or_else(|| l.error("needs vr=[one value reference]"))?;
            let own = fmu.md.variables.iter().find(|v| v.vr == vr);
            // A getter of another type than the variable's (an importer's mistake, on purpose):
            // the getter the line names, into values of its own type.
            let other = f
                .strip_prefix("fmi3Get")
                .filter(|t| replays_values_of(t) && own.is_none_or(|v| crate::fmi3::accessor(v.ty) != *t))
                .and_then(|t| Type::ALL.iter().copied().find(|ty| ty.name() == t));
            if let Some(ty) = other {
                let (s, bytes) = inst.get_as(ty, vr, l.parse("nValues")?);
                details.push(format!("bytes {}", crate::calllog::Val::Bytes(bytes)));
                s
            } else {
                let v = own.ok_or_else(|| l.error(format!("no variable has value reference {vr}")))?;
                if format!("fmi3Get{}", crate::fmi3::accessor(v.ty)) != f
                    && format!("fmi3Set{}", crate::fmi3::accessor(v.ty)) != f
                {
                    return Err(l.error(format!("value reference {vr} is a {:?}", v.ty)));
                }
                if f.starts_with("fmi3Get") {
                    let (s, bytes) = inst.get_raw_n(v, l.parse("nValues")?);
                    if matches!(v.ty, Type::Float64 | Type::Float32) {
                        let x = crate::fmi3::floats(v.ty, &bytes);
                        details.push(format!("values {}", list(x.iter().map(|x| real(*x)))));
                        values = Some(x);
                    } else {
                        details.push(format!("bytes {}", crate::calllog::Val::Bytes(bytes)));
                    }
                    s
                } else {
                    let bytes = unhex(l.raw("bytes")?).map_err(|e| l.error(e))?;
                    inst.set_raw(v, &bytes)
                }
            }
        }
        _ => return Err(l.error(format!("{f} is not a call the replay of a named check makes (FMI 3.0)"))),
    };
    let log = inst.sink.entries.lock().unwrap_or_else(|e| e.into_inner())[before..]
        .iter()
        .map(|e| log_line(crate::fmi3::types::status_name(e.status), &e.category, &e.message))
        .collect();
    p.call(l, s, details, log, values)
}
