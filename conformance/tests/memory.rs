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

/// The measuring loop itself, on cycles that leak 64 bytes each: refused, whatever the noise.
#[test]
fn the_measuring_loop_fails_a_cycle_that_leaks_64_bytes() {
    let _alone = ALONE.lock().unwrap_or_else(|e| e.into_inner());
    let failed = std::panic::catch_unwind(|| {
        fmi_conformance::checks::memory::cycles_leave_memory_flat("Leaky", |_| {
            // Touched, so that the pages are resident.
            std::hint::black_box(Box::leak(vec![1u8; 64].into_boxed_slice()));
        })
    });
    let message = failed.expect_err("a 64-byte leak per cycle passed the memory check");
    let text = message.downcast_ref::<String>().cloned().unwrap_or_default();
    assert!(text.contains("Leaky: RSS grew by"), "{text}");
}

/// ... and passes cycles whose process grows once (here 1 MiB touched at one cycle of the
/// measured run, as an allocator arena or the dynamic loader may): a leak repeats, this does not.
#[test]
fn the_measuring_loop_passes_a_one_time_growth() {
    let _alone = ALONE.lock().unwrap_or_else(|e| e.into_inner());
    let mut n = 0usize;
    fmi_conformance::checks::memory::cycles_leave_memory_flat("OnceGrown", |_| {
        n += 1;
        if n == 5_000 {
            std::hint::black_box(Box::leak(vec![1u8; 1 << 20].into_boxed_slice()));
        }
    });
}
