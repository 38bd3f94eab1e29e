//! 10,000 instantiate/free cycles per FMU leave memory flat. Alone in its test binary (one
//! test), so no other test allocates in the process while the resident set size is measured
//! (the check is `fmi2_conformance::checks::memory`).
//!
//! Thin callers: each test runs its check on every FMU of target/fmu, strictly (a skip or a
//! part left untested fails: these are this exporter's FMUs).

use fmi2_conformance::checks::on_every_fmu;

#[test]
fn ten_thousand_instantiate_free_cycles_leave_memory_flat() {
    on_every_fmu("ten_thousand_instantiate_free_cycles_leave_memory_flat");
}
