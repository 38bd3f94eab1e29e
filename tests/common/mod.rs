//! What the root tests of FMI 3.0 models exported into their own test binary share, beside the
//! host of `rustfmu::testing` (which instantiates through a function it is given): the instances
//! every such test makes of its model, and the check of the last message. `mod common;` in a test
//! file; each test binary uses what it needs of it.

#![allow(dead_code, unused_macros)] // each test binary uses a part

use rustfmu::testing::Log;

/// Asserts that the last message of `log` contains `what`; a failure shows the message.
pub fn assert_names(log: &Log, what: &str) {
    let last = log.last();
    assert!(
        last.contains(what),
        "expected a message with {what:?}, the log says: {last}"
    );
}

/// `cs()` and `me()`, a Co-Simulation and a Model Exchange instance (named `$name`, or `$cs` and
/// `$me`) of the model the test binary exports with `export_fmi3!` (its `fmi3Instantiate*`
/// functions and `TOKEN`, which must be in scope), each with a log of its own; `init(c)`,
/// Initialization Mode entered and left with the default arguments; and `initialized()`, both. A macro, where a function would do elsewhere:
/// every test binary has its own exported `fmi3*` functions, and these call them.
macro_rules! fmi3_instances {
    ($name:literal) => {
        fmi3_instances!($name, $name);
    };
    ($cs:literal, $me:literal) => {
        fn cs() -> (fmi3Instance, &'static rustfmu::testing::Log) {
            rustfmu::testing::fmi3::instance(fmi3InstantiateCoSimulation, TOKEN, $cs)
        }

        #[allow(dead_code)] // not every test binary uses model exchange
        fn me() -> (fmi3Instance, &'static rustfmu::testing::Log) {
            rustfmu::testing::fmi3::me_instance(fmi3InstantiateModelExchange, TOKEN, $me)
        }

        /// A Co-Simulation instance after initialization (in Step Mode).
        #[allow(dead_code)] // not every test binary starts one so
        fn initialized() -> (fmi3Instance, &'static rustfmu::testing::Log) {
            let (c, log) = cs();
            init(c);
            (c, log)
        }

        fn init(c: fmi3Instance) {
            // SAFETY: a live instance.
            unsafe {
                assert_eq!(
                    fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0),
                    fmi3OK
                );
                assert_eq!(fmi3ExitInitializationMode(c), fmi3OK);
            }
        }
    };
}

/// `serialized_state(c, log)`, the instance's FMU state now as the bytes an importer keeps, and
/// `set_serialized_state(c, bytes, log)`, the instance set to the state they hold, through the
/// test binary's own `fmi3*` functions (as `fmi3_instances!`); each call must succeed, a failure
/// shows the last message.
macro_rules! fmi3_serialized_states {
    () => {
        fn serialized_state(c: fmi3Instance, log: &rustfmu::testing::Log) -> Vec<u8> {
            // SAFETY: for every call, a live instance, a buffer of the size passed.
            unsafe {
                let mut state: fmi3FMUState = std::ptr::null_mut();
                assert_eq!(fmi3GetFMUState(c, &mut state), fmi3OK, "{}", log.last());
                let mut size = 0usize;
                assert_eq!(fmi3SerializedFMUStateSize(c, state, &mut size), fmi3OK);
                let mut bytes = vec![0u8; size];
                assert_eq!(fmi3SerializeFMUState(c, state, bytes.as_mut_ptr(), size), fmi3OK);
                assert_eq!(fmi3FreeFMUState(c, &mut state), fmi3OK);
                bytes
            }
        }

        fn set_serialized_state(c: fmi3Instance, bytes: &[u8], log: &rustfmu::testing::Log) {
            // SAFETY: for every call, a live instance, a buffer of the size passed.
            unsafe {
                let mut restored: fmi3FMUState = std::ptr::null_mut();
                assert_eq!(
                    fmi3DeserializeFMUState(c, bytes.as_ptr(), bytes.len(), &mut restored),
                    fmi3OK,
                    "{}",
                    log.last()
                );
                assert_eq!(fmi3SetFMUState(c, restored), fmi3OK, "{}", log.last());
                assert_eq!(fmi3FreeFMUState(c, &mut restored), fmi3OK);
            }
        }
    };
}
