//! 10,000 instantiate/free cycles per FMU leave memory flat, FMI 2.0 and 3.0. Alone in its test
//! binary, and its two tests one after the other (a lock), so no other test allocates in the
//! process while the resident set size is measured (the checks are
//! `fmi_conformance::checks::memory` and its FMI 3.0 port, `fmi_conformance::fmi3::checks::memory`).
//!
//! Thin callers: each test runs its check on every FMU of target/fmu, strictly (a skip or a
//! part left untested fails: these are this exporter's FMUs).

use fmi_conformance::checks::on_every_fmu;
use std::sync::Mutex;

/// Held by each test for its whole run: the tests of a binary run on threads of one process.
static ALONE: Mutex<()> = Mutex::new(());

#[test]
fn ten_thousand_instantiate_free_cycles_leave_memory_flat() {
    let _alone = ALONE.lock().unwrap_or_else(|e| e.into_inner());
    on_every_fmu("ten_thousand_instantiate_free_cycles_leave_memory_flat");
}

#[test]
fn fmi3_ten_thousand_instantiate_free_cycles_leave_memory_flat() {
    let _alone = ALONE.lock().unwrap_or_else(|e| e.into_inner());
    on_every_fmu("fmi3_ten_thousand_instantiate_free_cycles_leave_memory_flat");
}
