//! The conformance suite's tests in one test binary: each module was a test file of its own, and
//! each test binary of this crate costs about 35 s of release build with thin LTO on 2 cores
//! (cargo's --timings); one binary for ten files saves about five minutes of CI. The memory check
//! (it measures this process's resident set) and the runner's crash-isolation tests (their
//! time-outs) stay binaries of their own, so nothing else runs beside them.

mod archive;
mod calls;
mod directional_derivatives;
mod fmi3;
mod fmu_state;
mod instances;
mod model_exchange;
mod native;
mod random_sequences;
mod state_machine;
