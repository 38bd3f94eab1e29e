//! The FMI 2.0 random calls as lines of a reproducer ([`crate::replay`]) and back, the
//! reproducer a failing sequence leaves, and the replay of one.
//!
//! A value reference is written as the number the call passed (a variable picked by index is
//! resolved); the arguments are the call's, under the standard's names where it has one.

use super::co_simulation::{CATEGORIES, Op, When, execute_with, function_of};
use super::model_exchange::{MeOp, me_execute_with, me_function_of};
use super::{Vr, resolve};
use crate::Fmu;
use crate::replay::write::Recorded;
use crate::replay::{Expected, Line, ReplayReport, list, real, replay_line};
use proptest::test_runner::TestCaseError;

fn vrs(fmu: &Fmu, v: &[Vr]) -> String {
    list(v.iter().map(|x| resolve(fmu, *x)))
}

fn pairs<T: std::fmt::Display + Copy>(fmu: &Fmu, values: &[(Vr, T)], show: impl Fn(T) -> String, null: bool) -> String {
    let v = list(values.iter().map(|(x, _)| resolve(fmu, *x)));
    if null {
        format!("vr={v} values=NULL")
    } else {
        format!("vr={v} values={}", list(values.iter().map(|(_, x)| show(*x))))
    }
}

/// The line of a co-simulation call (without its expectation).
pub(super) fn cs_line(fmu: &Fmu, op: &Op) -> String {
    let args = match op {
        Op::SetDebugLogging { on, categories, null } if *null && !categories.is_empty() => {
            format!("loggingOn={on} nCategories={} categories=NULL", categories.len())
        }
        Op::SetDebugLogging { on, categories, .. } => format!(
            "loggingOn={on} categories={}",
            list(categories.iter().map(|i| CATEGORIES[*i].to_string_lossy()))
        ),
        Op::Setup { tolerance, start, stop } => {
            let mut a = String::new();
            if let Some(t) = tolerance {
                a += &format!("tolerance={} ", real(*t));
            }
            a += &format!("startTime={}", real(*start));
            if let Some(e) = stop {
                a += &format!(" stopTime={}", real(*e));
            }
            a
        }
        Op::GetReal { vrs: v, null } => format!("vr={}{}", vrs(fmu, v), if *null { " values=NULL" } else { "" }),
        Op::GetInteger { vrs: v } | Op::GetBoolean { vrs: v } | Op::GetString { vrs: v } | Op::SetString { vrs: v } => {
            format!("vr={}", vrs(fmu, v))
        }
        Op::SetReal { values, null } => pairs(fmu, values, real, *null),
        Op::SetInteger { values } | Op::SetBoolean { values } => pairs(fmu, values, |x| x.to_string(), false),
        Op::GetState { slot } | Op::SetState { slot } | Op::FreeState { slot } | Op::Serialize { slot } => {
            format!("slot={slot}")
        }
        Op::Deserialize { to, damage, truncate } => {
            let mut a = format!("slot={to}");
            if let Some((at, x)) = damage {
                a += &format!(" damageAt={at} damageXor={x}");
            }
            if let Some(n) = truncate {
                a += &format!(" truncateTo={n}");
            }
            a
        }
        Op::DoStep { when, h } => format!(
            "currentCommunicationPoint={} communicationStepSize={}",
            match when {
                When::Now => "now".to_string(),
                When::NowTimes(f) => format!("now*{}", real(*f)),
                When::At(t) => real(*t),
            },
            real(*h)
        ),
        Op::Status { kind, .. } => format!("kind={kind}"),
        Op::DirectionalDerivative { n } | Op::InputDerivatives { n } | Op::OutputDerivatives { n } => format!("n={n}"),
        Op::EnterInit | Op::ExitInit | Op::Terminate | Op::Reset | Op::CancelStep => String::new(),
    };
    join(function_of(op), &args)
}

fn join(function: &str, args: &str) -> String {
    if args.is_empty() {
        function.to_string()
    } else {
        format!("{function} {args}")
    }
}

fn raw_vrs(l: &Line, key: &str) -> Result<Vec<Vr>, String> {
    Ok(l.list::<u32>(key)?
        .unwrap_or_default()
        .into_iter()
        .map(Vr::Raw)
        .collect())
}

/// `vr=[..] values=[..]` (or `values=NULL`): the pairs and whether the values are NULL.
fn raw_pairs<T: std::str::FromStr + Default + Clone>(l: &Line) -> Result<(Vec<(Vr, T)>, bool), String>
where
    T::Err: std::fmt::Display,
{
    let v = raw_vrs(l, "vr")?;
    let (values, null) = match l.list::<T>("values")? {
        Some(x) => (x, false),
        None => (vec![T::default(); v.len()], true),
    };
    if values.len() != v.len() {
        return Err(l.error(format!("{} values for {} value references", values.len(), v.len())));
    }
    Ok((v.into_iter().zip(values).collect(), null))
}

const STATUS_FUNCTIONS: [&str; 5] = [
    "fmi2GetStatus",
    "fmi2GetRealStatus",
    "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus",
    "fmi2GetStringStatus",
];

/// The co-simulation call of a line.
pub(super) fn cs_op(l: &Line) -> Result<Op, String> {
    let slot = || -> Result<usize, String> {
        let s: usize = l.parse("slot")?;
        if s < super::SLOTS {
            Ok(s)
        } else {
            Err(l.error(format!("slot={s}: 0 to {}", super::SLOTS - 1)))
        }
    };
    let opt = |key: &str| -> Result<Option<f64>, String> { if l.has(key) { l.parse(key).map(Some) } else { Ok(None) } };
    Ok(match l.function.as_str() {
        "fmi2SetDebugLogging" => {
            let on = l.parse("loggingOn")?;
            match l.list::<String>("categories")? {
                None => Op::SetDebugLogging {
                    on,
                    categories: vec![0; l.parse("nCategories")?],
                    null: true,
                },
                Some(names) => Op::SetDebugLogging {
                    on,
                    categories: names
                        .iter()
                        .map(|n| {
                            CATEGORIES
                                .iter()
                                .position(|c| c.to_string_lossy() == *n)
                                .ok_or_else(|| l.error(format!("category {n}: one of {CATEGORIES:?}")))
                        })
                        .collect::<Result<_, _>>()?,
                    null: false,
                },
            }
        }
        "fmi2SetupExperiment" => Op::Setup {
            tolerance: opt("tolerance")?,
            start: l.parse("startTime")?,
            stop: opt("stopTime")?,
        },
        "fmi2EnterInitializationMode" => Op::EnterInit,
        "fmi2ExitInitializationMode" => Op::ExitInit,
        "fmi2Terminate" => Op::Terminate,
        "fmi2Reset" => Op::Reset,
        "fmi2GetReal" => Op::GetReal {
            vrs: raw_vrs(l, "vr")?,
            null: l.args.get("values").is_some_and(|v| v == "NULL"),
        },
        "fmi2GetInteger" => Op::GetInteger { vrs: raw_vrs(l, "vr")? },
        "fmi2GetBoolean" => Op::GetBoolean { vrs: raw_vrs(l, "vr")? },
        "fmi2GetString" => Op::GetString { vrs: raw_vrs(l, "vr")? },
        "fmi2SetString" => Op::SetString { vrs: raw_vrs(l, "vr")? },
        "fmi2SetReal" => {
            let (values, null) = raw_pairs::<f64>(l)?;
            Op::SetReal { values, null }
        }
        "fmi2SetInteger" => Op::SetInteger {
            values: raw_pairs(l)?.0,
        },
        "fmi2SetBoolean" => Op::SetBoolean {
            values: raw_pairs(l)?.0,
        },
        "fmi2GetFMUstate" => Op::GetState { slot: slot()? },
        "fmi2SetFMUstate" => Op::SetState { slot: slot()? },
        "fmi2FreeFMUstate" => Op::FreeState { slot: slot()? },
        "fmi2SerializeFMUstate" => Op::Serialize { slot: slot()? },
        "fmi2DeSerializeFMUstate" => Op::Deserialize {
            to: slot()?,
            damage: if l.has("damageAt") {
                Some((l.parse("damageAt")?, l.parse("damageXor")?))
            } else {
                None
            },
            truncate: if l.has("truncateTo") {
                Some(l.parse("truncateTo")?)
            } else {
                None
            },
        },
        "fmi2DoStep" => {
            let point = l.raw("currentCommunicationPoint")?;
            let when =
                match point.strip_prefix("now") {
                    Some("") => When::Now,
                    Some(f) => When::NowTimes(f.strip_prefix('*').and_then(|f| f.parse().ok()).ok_or_else(|| {
                        l.error(format!("currentCommunicationPoint={point}: now, now*FACTOR or a time"))
                    })?),
                    None => When::At(l.parse("currentCommunicationPoint")?),
                };
            Op::DoStep {
                when,
                h: l.parse("communicationStepSize")?,
            }
        }
        "fmi2CancelStep" => Op::CancelStep,
        f if STATUS_FUNCTIONS.contains(&f) => Op::Status {
            which: STATUS_FUNCTIONS.iter().position(|x| *x == f).unwrap_or(0) as u8,
            kind: l.parse("kind")?,
        },
        "fmi2GetDirectionalDerivative" => Op::DirectionalDerivative { n: l.parse("n")? },
        "fmi2SetRealInputDerivatives" => Op::InputDerivatives { n: l.parse("n")? },
        "fmi2GetRealOutputDerivatives" => Op::OutputDerivatives { n: l.parse("n")? },
        f => return Err(l.error(format!("{f} is no call of the FMI 2.0 co-simulation sequences"))),
    })
}

/// The line of a model-exchange call (without its expectation).
pub(super) fn me_line(fmu: &Fmu, op: &MeOp) -> String {
    let null = |n: bool, key: &str| if n { format!("{key}=NULL") } else { String::new() };
    let args = match op {
        MeOp::SetDebugLogging { on } => format!("loggingOn={on}"),
        MeOp::Setup { start } => format!("startTime={}", real(*start)),
        MeOp::GetReal { vrs: v, null } => format!("vr={}{}", vrs(fmu, v), if *null { " values=NULL" } else { "" }),
        MeOp::SetReal { values, null } => pairs(fmu, values, real, *null),
        MeOp::SetInteger { values } | MeOp::SetBoolean { values } => pairs(fmu, values, |x| x.to_string(), false),
        MeOp::GetState { slot } | MeOp::SetState { slot } | MeOp::FreeState { slot } => format!("slot={slot}"),
        MeOp::Reserialize { slot, truncate } => match truncate {
            Some(n) => format!("slot={slot} truncateTo={n}"),
            None => format!("slot={slot}"),
        },
        MeOp::NewDiscreteStates { null: n } => null(*n, "eventInfo"),
        MeOp::CompletedIntegratorStep { null: n } => null(*n, "enterEventMode"),
        MeOp::SetTime { dt } => format!("time=now+{}", real(*dt)),
        MeOp::SetContinuousStates { dx, dn, null } => {
            if *null {
                format!("x=NULL nx=n{dn:+}")
            } else {
                format!("x=start+{} nx=n{dn:+}", real(*dx))
            }
        }
        MeOp::GetVector { dn, null, .. } => format!("n=n{dn:+}{}", if *null { " values=NULL" } else { "" }),
        MeOp::EnterInit
        | MeOp::ExitInit
        | MeOp::Terminate
        | MeOp::Reset
        | MeOp::EnterEventMode
        | MeOp::EnterContinuousTimeMode
        | MeOp::DoStep
        | MeOp::DirectionalDerivative => String::new(),
    };
    join(me_function_of(op), &args)
}

const VECTOR_FUNCTIONS: [&str; 4] = [
    "fmi2GetContinuousStates",
    "fmi2GetDerivatives",
    "fmi2GetEventIndicators",
    "fmi2GetNominalsOfContinuousStates",
];

/// `n=n+1` / `nx=n-1` / `n=n+0`: the count's offset from the FMU's.
fn offset(l: &Line, key: &str) -> Result<i8, String> {
    let v = l.raw(key)?;
    v.strip_prefix('n')
        .map(|d| d.strip_prefix('+').unwrap_or(d))
        .and_then(|d| d.parse().ok())
        .ok_or_else(|| l.error(format!("{key}={v}: n, n+K or n-K")))
}

/// The model-exchange call of a line.
pub(super) fn me_op(l: &Line) -> Result<MeOp, String> {
    let slot = || -> Result<usize, String> {
        let s: usize = l.parse("slot")?;
        if s < super::SLOTS {
            Ok(s)
        } else {
            Err(l.error(format!("slot={s}: 0 to {}", super::SLOTS - 1)))
        }
    };
    let is_null = |key: &str| l.args.get(key).is_some_and(|v| v == "NULL");
    let after = |key: &str, prefix: &str| -> Result<f64, String> {
        let v = l.raw(key)?;
        v.strip_prefix(prefix)
            .and_then(|d| d.parse().ok())
            .ok_or_else(|| l.error(format!("{key}={v}: {prefix}VALUE")))
    };
    Ok(match l.function.as_str() {
        "fmi2SetDebugLogging" => MeOp::SetDebugLogging {
            on: l.parse("loggingOn")?,
        },
        "fmi2SetupExperiment" => MeOp::Setup {
            start: l.parse("startTime")?,
        },
        "fmi2EnterInitializationMode" => MeOp::EnterInit,
        "fmi2ExitInitializationMode" => MeOp::ExitInit,
        "fmi2Terminate" => MeOp::Terminate,
        "fmi2Reset" => MeOp::Reset,
        "fmi2GetReal" => MeOp::GetReal {
            vrs: raw_vrs(l, "vr")?,
            null: is_null("values"),
        },
        "fmi2SetReal" => {
            let (values, null) = raw_pairs::<f64>(l)?;
            MeOp::SetReal { values, null }
        }
        "fmi2SetInteger" => MeOp::SetInteger {
            values: raw_pairs(l)?.0,
        },
        "fmi2SetBoolean" => MeOp::SetBoolean {
            values: raw_pairs(l)?.0,
        },
        "fmi2GetFMUstate" => MeOp::GetState { slot: slot()? },
        "fmi2SetFMUstate" => MeOp::SetState { slot: slot()? },
        "fmi2FreeFMUstate" => MeOp::FreeState { slot: slot()? },
        "fmi2SerializeFMUstate" => MeOp::Reserialize {
            slot: slot()?,
            truncate: if l.has("truncateTo") {
                Some(l.parse("truncateTo")?)
            } else {
                None
            },
        },
        "fmi2EnterEventMode" => MeOp::EnterEventMode,
        "fmi2NewDiscreteStates" => MeOp::NewDiscreteStates {
            null: is_null("eventInfo"),
        },
        "fmi2EnterContinuousTimeMode" => MeOp::EnterContinuousTimeMode,
        "fmi2CompletedIntegratorStep" => MeOp::CompletedIntegratorStep {
            null: is_null("enterEventMode"),
        },
        "fmi2SetTime" => MeOp::SetTime {
            dt: after("time", "now+")?,
        },
        "fmi2SetContinuousStates" => {
            let null = is_null("x");
            MeOp::SetContinuousStates {
                dx: if null { 0.0 } else { after("x", "start+")? },
                dn: offset(l, "nx")?,
                null,
            }
        }
        f if VECTOR_FUNCTIONS.contains(&f) => MeOp::GetVector {
            which: VECTOR_FUNCTIONS.iter().position(|x| *x == f).unwrap_or(0) as u8,
            dn: offset(l, "n")?,
            null: is_null("values"),
        },
        "fmi2DoStep" => MeOp::DoStep,
        "fmi2GetDirectionalDerivative" => MeOp::DirectionalDerivative,
        f => return Err(l.error(format!("{f} is no call of the FMI 2.0 model-exchange sequences"))),
    })
}

/// The lines the calls of a failing sequence left, with what the standard required of each and
/// what the FMU answered (the sequence run once more, recorded).
pub(super) fn record_cs(fmu: &Fmu, logging_on: bool, ops: &[Op]) -> Vec<Recorded> {
    let mut calls = vec![];
    // A panic of the sequence's own assertions ends the record where it happened.
    let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        execute_with(fmu, logging_on, ops, &mut |_, op, status, expected, _| {
            calls.push(Recorded {
                call: cs_line(fmu, op),
                expected,
                status,
            });
            Ok(())
        })
    }));
    calls
}

pub(super) fn record_me(fmu: &Fmu, ops: &[MeOp]) -> Vec<Recorded> {
    let mut calls = vec![];
    let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        me_execute_with(fmu, ops, &mut |_, op, status, expected, _| {
            calls.push(Recorded {
                call: me_line(fmu, op),
                expected,
                status,
            });
            Ok(())
        })
    }));
    calls
}

/// Writes the reproducer of a failing sequence; the sentence for the failure message.
pub(super) fn write(
    fmu: &Fmu,
    check: &str,
    interface: &str,
    instantiate: &str,
    calls: &[Recorded],
    failure: &str,
) -> String {
    let about = [
        format!("FMU: {} (model {}, FMI 2.0 {interface})", fmu.archive.display(), fmu.id),
        format!("check: {check}; {}", crate::seed_note()),
    ];
    let text = crate::replay::write::reproducer_text(&about, instantiate, calls, failure);
    let written = crate::replay::write::write_reproducer(&format!("{}-fmi2-{interface}", fmu.id), &text);
    crate::replay::write::reproducer_note(written, &fmu.archive)
}

/// Replays the lines of a reproducer (the first one `fmi2Instantiate`) on `fmu`.
pub fn replay(fmu: &Fmu, lines: &[Line], out: &mut dyn FnMut(&str)) -> Result<ReplayReport, String> {
    let first = &lines[0];
    let logging_on = first.parse_or("loggingOn", false)?;
    let me = match first.raw("fmuType")? {
        "CoSimulation" => false,
        "ModelExchange" => true,
        t => return Err(first.error(format!("fmuType={t}: CoSimulation or ModelExchange"))),
    };
    let calls = &lines[1..];
    let mut report = ReplayReport::default();
    let mut print = |report: &mut ReplayReport, text: String| {
        out(&text);
        report.lines.push(text);
    };
    print(
        &mut report,
        format!(
            "replaying {} calls on {} (FMI 2.0 {})",
            calls.len(),
            fmu.id,
            if me { "model exchange" } else { "co-simulation" }
        ),
    );
    let mut check = |i: usize, call: String, status: u32, standard: Expected, log: &[crate::LogEntry]| {
        let line = &calls[i];
        let expected = line.expected.unwrap_or(standard);
        print(&mut report, replay_line(line, &call, status, expected));
        for e in log {
            print(
                &mut report,
                format!(
                    "       log [{}] {}: {}",
                    crate::instance::status_name(e.status),
                    e.category,
                    e.text
                ),
            );
        }
        if !expected.contains(status) {
            return Err(TestCaseError::fail(format!(
                "line {}: {call} answered {}, the file expects {expected}",
                line.number,
                crate::replay::status_word(status)
            )));
        }
        crate::replay_calls::next_line(calls, i + 1);
        Ok(())
    };
    crate::replay_calls::next_line(calls, 0);
    let result = if me {
        if fmu.md.me.is_none() {
            return Err(format!("{} does not declare <ModelExchange>", fmu.id));
        }
        let ops = calls.iter().map(me_op).collect::<Result<Vec<_>, _>>()?;
        if let Some(l) = calls
            .iter()
            .zip(&ops)
            .find(|(_, op)| !super::model_exchange::me_declared(fmu, op))
        {
            return Err(l
                .0
                .error("a call the FMU does not declare (canGetAndSetFMUstate, canSerializeFMUstate)"));
        }
        me_execute_with(fmu, &ops, &mut |i, op, s, e, log| check(i, me_line(fmu, op), s, e, log))
    } else {
        let ops = calls.iter().map(cs_op).collect::<Result<Vec<_>, _>>()?;
        if let Some(l) = calls
            .iter()
            .zip(&ops)
            .find(|(_, op)| !super::co_simulation::declared(fmu, op))
        {
            return Err(l
                .0
                .error("a call the FMU does not declare (canGetAndSetFMUstate, canSerializeFMUstate)"));
        }
        execute_with(fmu, logging_on, &ops, &mut |i, op, s, e, log| {
            check(i, cs_line(fmu, op), s, e, log)
        })
    };
    report.difference = result.err().map(|e| match e {
        TestCaseError::Fail(reason) | TestCaseError::Reject(reason) => reason.message().to_string(),
    });
    Ok(report)
}

/// A reproducer of one random sequence (co-simulation, or `me`: model exchange) drawn from
/// `seed`, written as a failing sequence's would be: for tests of the replay on an FMU the
/// sequence passes on.
pub fn reproducer_of_a_random_sequence(fmu: &Fmu, me: bool, seed: u64) -> String {
    use proptest::strategy::{Strategy, ValueTree};
    use proptest::test_runner::{Config, RngSeed, TestRunner};
    let mut runner = TestRunner::new(Config {
        rng_seed: RngSeed::Fixed(seed),
        ..Config::default()
    });
    let about = [format!(
        "FMU: {} (a test's sequence, seed {seed})",
        fmu.archive.display()
    )];
    let (instantiate, calls) = if me {
        let tree = proptest::collection::vec(super::model_exchange::me_op(), 20..60).new_tree(&mut runner);
        let ops = tree.map(|t| t.current()).unwrap_or_default();
        ("fmi2Instantiate fmuType=ModelExchange", record_me(fmu, &ops))
    } else {
        let tree = proptest::collection::vec(super::co_simulation::op(), 20..60).new_tree(&mut runner);
        let ops = tree.map(|t| t.current()).unwrap_or_default();
        (
            "fmi2Instantiate fmuType=CoSimulation loggingOn=true",
            record_cs(fmu, true, &ops),
        )
    };
    crate::replay::write::reproducer_text(&about, instantiate, &calls, "none (the sequence of a test)")
}
