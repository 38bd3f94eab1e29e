//! Issue 52, item 2: what the model writes into a Binary is checked against its `maxSize` right
//! after the model's code ran (initialization, the equations when an output is read, a step, an
//! event's update), and the call that ran it fails with the variable's name and both sizes; the
//! model keeps its last good values, so `fmi3GetBinary` never hands out more than `maxSize`
//! bytes and an FMU state taken afterwards is one the FMU accepts again.

use common::assert_names;
use rustfmu::__private::abi3::*;
use rustfmu::testing::Log;

use std::ptr::null;

#[macro_use]
mod common;

mod model {
    use rustfmu::prelude::*;

    /// A frame of `n` bytes (computed from the input), and a latch of `m` bytes written at events.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    #[fmu(fmi3_only)]
    pub struct Frames {
        /// how many bytes the equations write into the frame
        #[variable(vr = 1, input, discrete, start = 4)]
        pub n: u8,
        /// the frame: n bytes 0xAB
        #[variable(vr = 2, output, discrete, max_size = 4, depends = [n])]
        pub frame: Vec<u8>,
        /// how many bytes an event writes into the latch
        #[variable(vr = 3, input, discrete, start = 0)]
        pub m: u8,
        /// the latch: m bytes 1, written at events
        #[variable(vr = 4, output, discrete, max_size = 2, depends = [m])]
        pub latch: Vec<u8>,
    }

    impl Model for Frames {
        fn calculate(&mut self, _t: f64) {
            self.frame = vec![0xAB; usize::from(self.n)];
        }
        fn update(&mut self, _event: &mut Event) -> Result<(), String> {
            self.latch = vec![1; usize::from(self.m)];
            Ok(())
        }
    }

    impl CoSimulation for Frames {}

    rustfmu::export_fmi3!(Frames);
}
use model::__rustfmu_fmi3_exports::*;

fmi3_instances!("frames");

fn set_u8(c: fmi3Instance, vr: u32, value: u8) -> fmi3Status {
    // SAFETY: one value.
    unsafe { fmi3SetUInt8(c, &vr, 1, &value, 1) }
}

/// fmi3GetBinary of one variable: the status and, under OK, the bytes.
fn get_binary(c: fmi3Instance, vr: u32) -> (fmi3Status, Option<Vec<u8>>) {
    let (mut size, mut p) = (0usize, null::<u8>());
    // SAFETY: one value reference, one size and one pointer slot; the bytes are copied before
    // the next call on the instance.
    unsafe {
        let status = fmi3GetBinary(c, &vr, 1, &mut size, &mut p, 1);
        let bytes = (status == fmi3OK).then(|| std::slice::from_raw_parts(p, size).to_vec());
        (status, bytes)
    }
}

/// The refusal names the function, and the variable with its length and maxSize.
fn assert_too_long(log: &Log, function: &str, variable: &str, bytes: usize, max_size: usize) {
    assert_names(log, function);
    assert_names(
        log,
        &format!("{variable} holds {bytes} bytes, more than its maxSize = {max_size}"),
    );
}

/// The instance's FMU state, serialized and deserialized again (as an importer keeps it), is
/// accepted by fmi3SetFMUState.
fn state_round_trips(c: fmi3Instance, log: &Log) {
    let bytes = serialized_state(c, log);
    set_serialized_state(c, &bytes, log);
}

fmi3_serialized_states!();

#[test]
fn a_frame_within_its_max_size_is_read_and_its_state_round_trips() {
    let (c, log) = initialized();
    assert_eq!(get_binary(c, 2), (fmi3OK, Some(vec![0xAB; 4])));
    assert_eq!(set_u8(c, 1, 3), fmi3OK);
    assert_eq!(get_binary(c, 2), (fmi3OK, Some(vec![0xAB; 3])));
    state_round_trips(c, log);
    assert_eq!(get_binary(c, 2), (fmi3OK, Some(vec![0xAB; 3])));
    // SAFETY: a live instance.
    unsafe { fmi3FreeInstance(c) };
}

#[test]
fn the_read_that_ran_the_equations_is_refused_and_never_hands_out_the_longer_frame() {
    let (c, log) = initialized();
    assert_eq!(set_u8(c, 1, 8), fmi3OK);
    let (status, bytes) = get_binary(c, 2);
    assert_eq!(status, fmi3Error, "fmi3GetBinary gave {bytes:?}");
    assert_too_long(log, "fmi3GetBinary", "'frame' (vr 2)", 8, 4);
    // The model kept its last good values: the FMU state taken now is one it accepts again
    // (FMI 3.0, 2.3.1: after fmi3Error the instance is Terminated, where states may be taken).
    state_round_trips(c, log);
    // Reset and back: the frame is as the start values make it.
    // SAFETY: a live instance.
    unsafe { assert_eq!(fmi3Reset(c), fmi3OK) };
    init(c);
    assert_eq!(get_binary(c, 2), (fmi3OK, Some(vec![0xAB; 4])));
    // SAFETY: a live instance.
    unsafe { fmi3FreeInstance(c) };
}

#[test]
fn the_step_that_wrote_the_longer_frame_is_refused() {
    let (c, log) = initialized();
    assert_eq!(get_binary(c, 2), (fmi3OK, Some(vec![0xAB; 4])));
    assert_eq!(set_u8(c, 1, 8), fmi3OK);
    let (mut event, mut terminate, mut early, mut reached) = (false, false, false, 0.0);
    // SAFETY: a live instance; the output arguments are locals.
    let status = unsafe { fmi3DoStep(c, 0.0, 0.5, true, &mut event, &mut terminate, &mut early, &mut reached) };
    assert_eq!(status, fmi3Error);
    assert_too_long(log, "fmi3DoStep", "'frame' (vr 2)", 8, 4);
    state_round_trips(c, log);
    // The state taken now holds the frame of before the step; it is never longer than 4.
    let (status, bytes) = get_binary(c, 2);
    assert!(bytes.as_ref().is_none_or(|b| b.len() <= 4), "{status}: {bytes:?}");
    // SAFETY: a live instance.
    unsafe { fmi3FreeInstance(c) };
}

#[test]
fn the_initialization_that_wrote_the_longer_frame_is_refused() {
    let (c, log) = cs();
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0), fmi3OK);
        assert_eq!(set_u8(c, 1, 5), fmi3OK);
        assert_eq!(fmi3ExitInitializationMode(c), fmi3Error);
        assert_too_long(log, "fmi3ExitInitializationMode", "'frame' (vr 2)", 5, 4);
        fmi3FreeInstance(c);
    }
}

#[test]
fn the_event_update_that_wrote_the_longer_latch_is_refused() {
    let (c, log) = me();
    // SAFETY: for every call, a live instance, output arguments that are locals.
    unsafe {
        assert_eq!(fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0), fmi3OK);
        assert_eq!(fmi3ExitInitializationMode(c), fmi3OK);
        let mut flags = [false; 5];
        let mut next = 0.0;
        let [discrete, terminate, nominals, values, defined] = &mut flags;
        assert_eq!(
            fmi3UpdateDiscreteStates(c, discrete, terminate, nominals, values, defined, &mut next),
            fmi3OK
        );
        assert_eq!(fmi3EnterContinuousTimeMode(c), fmi3OK);
        assert_eq!(fmi3EnterEventMode(c), fmi3OK);
        assert_eq!(set_u8(c, 3, 2), fmi3OK);
        let [discrete, terminate, nominals, values, defined] = &mut flags;
        assert_eq!(
            fmi3UpdateDiscreteStates(c, discrete, terminate, nominals, values, defined, &mut next),
            fmi3OK
        );
        assert_eq!(get_binary(c, 4), (fmi3OK, Some(vec![1; 2])));
        assert_eq!(set_u8(c, 3, 3), fmi3OK);
        let [discrete, terminate, nominals, values, defined] = &mut flags;
        assert_eq!(
            fmi3UpdateDiscreteStates(c, discrete, terminate, nominals, values, defined, &mut next),
            fmi3Error
        );
        assert_too_long(log, "fmi3UpdateDiscreteStates", "'latch' (vr 4)", 3, 2);
        // The model is as before the event: the latch of two bytes.
        state_round_trips(c, log);
        let (_, bytes) = get_binary(c, 4);
        assert!(bytes.as_ref().is_none_or(|b| b.len() <= 2), "{bytes:?}");
        fmi3FreeInstance(c);
    }
}
