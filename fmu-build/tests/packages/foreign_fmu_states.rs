//! Two packaged FMUs loaded into one process, as a master loads them: an FMU state made by one
//! is refused by the other (fmi2Error with a message), and the refusing instance is unchanged
//! and still works. Needs `target/fmu/{Pendulum,Controller,DCMotor}.fmu`
//! (`cargo run --release -p fmu-build -- build --workspace`).

use crate::common::{Fmu, Log};
use rustfmu::__private::abi::*;

/// An initialized instance of `fmu` after 10 steps of 1 ms, and its log.
fn running(fmu: &Fmu) -> (fmi2Component, &'static Log) {
    let (c, log) = fmu.instance(false);
    // SAFETY: c is a live instance of fmu.
    unsafe {
        assert_eq!((fmu.setup)(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
        assert_eq!((fmu.enter_init)(c), fmi2OK);
        assert_eq!((fmu.exit_init)(c), fmi2OK);
        for k in 0..10 {
            assert_eq!((fmu.do_step)(c, k as f64 * 1e-3, 1e-3, fmi2True), fmi2OK);
        }
    }
    (c, log)
}

/// `from`'s state handed to every state function of `to`: refused, logged, nothing changed.
fn refused_by_the_other(from: &Fmu, to: &Fmu) {
    let (a, _) = running(from);
    let (b, log) = running(to);
    let what = format!("{}'s state handed to {}", from.name, to.name);
    // SAFETY: a and b are live instances of their FMUs; the foreign state is passed only as an
    // importer would pass it, and `to` must not read through it.
    unsafe {
        let mut foreign: fmi2FMUstate = std::ptr::null_mut();
        assert_eq!((from.get_state)(a, &mut foreign), fmi2OK);
        let before = to.serialized(b);
        assert_eq!((to.set_state)(b, foreign), fmi2Error, "fmi2SetFMUstate: {what}");
        let mut n = 0;
        assert_eq!(
            (to.state_size)(b, foreign, &mut n),
            fmi2Error,
            "fmi2SerializedFMUstateSize: {what}"
        );
        let mut freed = foreign;
        assert_eq!((to.free_state)(b, &mut freed), fmi2Error, "fmi2FreeFMUstate: {what}");
        assert_eq!(
            freed, foreign,
            "{what}: the refused free changed the importer's pointer"
        );
        let mut into = foreign;
        assert_eq!((to.get_state)(b, &mut into), fmi2Error, "fmi2GetFMUstate into {what}");
        let log = log.take_texts();
        let refusals = log
            .iter()
            .filter(|(s, t)| *s == fmi2Error && t.contains("not a live state of this FMU"))
            .count();
        assert_eq!(refusals, 4, "{what}: every refusal says why: {log:?}");
        // Unchanged, and it still works.
        assert_eq!(to.serialized(b), before, "{what}: the refusing instance changed");
        for k in 10..20 {
            assert_eq!(
                (to.do_step)(b, k as f64 * 1e-3, 1e-3, fmi2True),
                fmi2OK,
                "{what}: step {k}"
            );
        }
        // The state is still its maker's, intact.
        assert_eq!((from.set_state)(a, foreign), fmi2OK);
        assert_eq!((from.free_state)(a, &mut foreign), fmi2OK);
        (from.free_instance)(a);
        (to.free_instance)(b);
    }
}

#[test]
fn a_state_of_another_fmu_in_the_same_process_is_refused() {
    let (pendulum, controller, motor) = (Fmu::load("Pendulum"), Fmu::load("Controller"), Fmu::load("DCMotor"));
    // The reproductions crashed 8 of 10 runs (Pendulum -> Controller) and 10 of 10
    // (DCMotor -> Pendulum): ten rounds of each, and the reverse directions.
    for _ in 0..10 {
        refused_by_the_other(&pendulum, &controller);
        refused_by_the_other(&motor, &pendulum);
        refused_by_the_other(&controller, &motor);
        refused_by_the_other(&controller, &pendulum);
    }
}
