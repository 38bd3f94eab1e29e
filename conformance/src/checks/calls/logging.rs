//! Logging: the categories importers look for, fmi2SetDebugLogging, the message text verbatim,
//! each instance's componentEnvironment.

#![allow(non_upper_case_globals)] // fmi2OK etc. are the standard's names, matched on

use super::refused;
use crate::Fmu;
use crate::fmi2::*;
use crate::instance::{Args, Instance, step_size};
use crate::outcome::convention;

pub fn the_log_categories_importers_look_for_are_declared(fmu: &Fmu) {
    for c in [
        "logStatusError",
        "logStatusWarning",
        "logStatusDiscard",
        "logStatusFatal",
        "logAll",
        "logEvents",
    ] {
        if !fmu.md.log_categories.iter().any(|d| d == c)
            && convention(
                fmu,
                "the log categories this exporter declares (logStatus*, logAll, logEvents)",
            )
        {
            panic!("{}: <LogCategories> lacks {c}", fmu.id);
        }
    }
}

pub(super) fn logged_run(fmu: &Fmu, logging_on: bool, debug: Option<(bool, &[&str])>) -> Vec<String> {
    let args = Args {
        logging_on,
        ..Args::valid(fmu)
    };
    let mut inst = Instance::with(fmu, &args).unwrap();
    if let Some((on, cats)) = debug {
        assert_eq!(inst.set_debug_logging(on, cats), fmi2OK, "{}", inst.log_text());
    }
    // What is logged from here on.
    inst.log();
    inst.initialize();
    assert_eq!(inst.step(step_size(fmu)), fmi2OK);
    inst.log().into_iter().map(|e| e.category).collect()
}

pub fn debug_logging_follows_logging_on_and_set_debug_logging(fmu: &Fmu) {
    assert_eq!(
        logged_run(fmu, false, None),
        Vec::<String>::new(),
        "{}: loggingOn = false",
        fmu.id
    );
    if !convention(
        fmu,
        "debug messages of a step under logEvents, and fmi2SetDebugLogging by this exporter's categories",
    ) {
        return;
    }
    let all_on = logged_run(fmu, true, None);
    assert!(
        all_on.iter().any(|c| c == "logEvents"),
        "{}: loggingOn = true: {all_on:?}",
        fmu.id
    );
    // nCategories = 0 means every category.
    let zero = logged_run(fmu, false, Some((true, &[])));
    assert_eq!(zero, all_on, "{}: fmi2SetDebugLogging(on, 0 categories)", fmu.id);
    let all = logged_run(fmu, false, Some((true, &["logAll"])));
    assert_eq!(all, all_on, "{}: fmi2SetDebugLogging(on, logAll)", fmu.id);
    let errors_only = logged_run(fmu, true, Some((true, &["logStatusError"])));
    assert_eq!(
        errors_only,
        Vec::<String>::new(),
        "{}: only logStatusError enabled",
        fmu.id
    );
    let events_only = logged_run(fmu, false, Some((true, &["logEvents"])));
    assert!(
        !events_only.is_empty() && events_only.iter().all(|c| c == "logEvents"),
        "{}: only logEvents enabled: {events_only:?}",
        fmu.id
    );
    let off = logged_run(fmu, true, Some((false, &[])));
    assert_eq!(off, Vec::<String>::new(), "{}: fmi2SetDebugLogging(off)", fmu.id);
}

pub fn set_debug_logging_refuses_unknown_categories_and_null_arrays(fmu: &Fmu) {
    let mut inst = Instance::new(fmu);
    let s = inst.set_debug_logging(true, &["logNoSuchThing"]);
    refused(&inst, "an unknown category", s, &["logNoSuchThing"]);
    // Categories NULL with nCategories = 2, then two entries of which one is NULL: the
    // importer's mistakes (a crash in them is a warning: outcome::on_purpose), through the call
    // log (a failure leaves a reproducer with them).
    let s = crate::outcome::on_purpose(|| inst.set_debug_logging_raw(true, 2, None));
    refused(&inst, "NULL categories", s, &["NULL"]);
    let s = crate::outcome::on_purpose(|| inst.set_debug_logging_raw(true, 2, Some(&[Some("logEvents"), None][..])));
    refused(&inst, "a NULL category", s, &["NULL"]);
}

pub fn a_percent_sign_in_a_message_reaches_the_logger_verbatim(fmu: &Fmu) {
    let args = Args {
        name: Some("inst %s %n %d %%".into()),
        ..Args::valid(fmu)
    };
    let mut inst = Instance::with(fmu, &args).unwrap();
    let s = inst.set_debug_logging(true, &["log%s%n%x%%"]);
    // Instance::log checks that the format is "%s" and the instance name came back intact.
    refused(&inst, "a category with '%'", s, &["'log%s%n%x%%'"]);
}

pub fn each_instance_logs_to_its_own_component_environment(fmu: &Fmu) {
    let mut a = Instance::new(fmu);
    let mut b = Instance::with(
        fmu,
        &Args {
            name: Some("second".into()),
            ..Args::valid(fmu)
        },
    )
    .unwrap();
    a.initialize();
    b.initialize();
    let (sa, sb) = (a.do_step(1.0, 0.1), b.do_step(2.0, 0.1));
    assert_eq!((sa, sb), (fmi2Error, fmi2Error));
    // Instance::log checks environment and name of every entry.
    let (la, lb) = (a.log(), b.log());
    assert!(a.says(&la, fmi2Error, &["= 1"]), "{}: {la:?}", fmu.id);
    assert!(b.says(&lb, fmi2Error, &["= 2"]), "{}: {lb:?}", fmu.id);
}
