//! fmu-build's tests in one test binary: each module was a test file of its own, and each test
//! binary costs 20-40 s of release build with thin LTO on 2 cores (cargo --timings).

mod common;
mod fmi3_packages;
mod foreign_fmu_states;
mod fuzz_fmus;
mod targets;
mod windows_binaries;
