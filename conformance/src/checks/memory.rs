//! 10,000 instantiate/free cycles per FMU leave memory flat. Alone in its process (its own test
//! binary; a worker process of its own under the runner), so no other check allocates in the
//! process while the resident set size is measured.

use crate::Fmu;
use crate::fmi2::*;
use crate::instance::{Instance, excitation, step_size};
use crate::outcome::{info, limitation};

/// Resident set size in bytes (/proc/self/statm, field 2, in pages).
fn rss() -> usize {
    let statm = std::fs::read_to_string("/proc/self/statm")
        .unwrap_or_else(|e| panic!("/proc/self/statm: {e}: the resident set cannot be measured here"));
    let pages: usize = statm
        .split_whitespace()
        .nth(1)
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("/proc/self/statm has no resident-set field: {statm:?}"));
    // 4 KiB pages on the supported platforms (x86-64 and AArch64 Linux with default kernels).
    pages * 4096
}

/// One cycle of what an importer does with an instance: instantiate, run a few steps, take,
/// serialize, restore and free an FMU state, make a refused call (its message allocates),
/// free.
fn cycle(fmu: &Fmu, full: bool) {
    let mut inst = Instance::new(fmu);
    if full {
        let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
        assert_eq!(inst.set_real(&vrs, &vals), fmi2OK);
        inst.initialize();
        assert_eq!(inst.step(step_size(fmu)), fmi2OK);
        if fmu.can_snapshot() {
            let bytes = inst.snapshot();
            inst.restore(&bytes);
        }
        let s = inst.do_step(-1.0, -1.0);
        assert_eq!(
            s,
            fmi2Error,
            "{}: a step of h = -1 (made so that the FMU logs a refusal) answered {}",
            fmu.id,
            crate::instance::status_name(s)
        );
        inst.log();
        assert_eq!(inst.terminate(), fmi2OK);
    }
}

pub fn ten_thousand_instantiate_free_cycles_leave_memory_flat(fmu: &Fmu) {
    if !fmu.can_snapshot() {
        limitation("the FMU cannot serialize its state: the cycles take and restore no FMU state");
    }
    cycles_leave_memory_flat(&fmu.id, |full| cycle(fmu, full));
}

/// 500 cycles to warm up, then 10,000 of `cycle(false)` (instantiate/free) and of `cycle(true)`
/// (instantiate, run, FMU state, free): the resident set may grow by 320 KiB at most each time
/// (a leak of 32 bytes per cycle would exceed it). Shared by the FMI 2.0 and 3.0 checks.
pub fn cycles_leave_memory_flat(id: &str, mut cycle: impl FnMut(bool)) {
    const CYCLES: usize = 10_000;
    const SLACK: usize = 320 * 1024;
    for full in [false, true] {
        for _ in 0..500 {
            cycle(full);
        }
        let before = rss();
        for _ in 0..CYCLES {
            cycle(full);
        }
        let after = rss();
        let what = if full {
            "instantiate/run/state/free"
        } else {
            "instantiate/free"
        };
        info(format!("{CYCLES} {what} cycles: RSS {before} -> {after} bytes"));
        assert!(
            after <= before + SLACK,
            "{id}: RSS grew by {} bytes over {CYCLES} {what} cycles (allowed {SLACK})",
            after - before
        );
    }
}
