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
        // A refusal of the importer's mistake is not required (a warning), and after fmi2Error
        // only fmi2Reset or fmi2FreeInstance are sure to be allowed (FMI 2.0.5 §2.1.3).
        crate::outcome::warn_unless(s == fmi2Error, || {
            format!(
                "{}: a step of h = -1 (made so that the FMU logs a refusal) answered {}",
                fmu.id,
                crate::instance::status_name(s)
            )
        });
        inst.log();
        if s != fmi2Error || fmu.own_state_format() {
            assert_eq!(inst.terminate(), fmi2OK);
        }
    }
}

/// Verdict: a leak is a warning (see [`cycles_leave_memory_flat`]); a crash or a refused legal
/// call in the cycles stays a failure.
pub fn ten_thousand_instantiate_free_cycles_leave_memory_flat(fmu: &Fmu) {
    if !fmu.can_snapshot() {
        limitation("the FMU cannot serialize its state: the cycles take and restore no FMU state");
    }
    cycles_leave_memory_flat(&fmu.id, |full| cycle(fmu, full));
}

/// 500 cycles to warm up, then 10,000 of `cycle(false)` (instantiate/free) and of `cycle(true)`
/// (instantiate, run, FMU state, free): the resident set may grow by 320 KiB at most each time
/// (a leak of 32 bytes per cycle would exceed it); a growth over that is measured once more
/// and fails only if it repeats (a leak does, a one-time growth of the allocator does not).
/// Shared by the FMI 2.0 and 3.0 checks.
///
/// An FMU whose cycle is slow (a container FMU unpacks and loads its components at every
/// fmi2Instantiate: about 30 ms) gets as many cycles as fit in `BUDGET` seconds per kind, at
/// least `FEWEST`, with the slack scaled down alike (never under 128 KiB, a few pages of
/// allocator noise); the pass is then partial and says how many cycles ran.
pub fn cycles_leave_memory_flat(id: &str, mut cycle: impl FnMut(bool)) {
    const CYCLES: usize = 10_000;
    const SLACK: usize = 320 * 1024;
    const BUDGET: f64 = 8.0;
    const FEWEST: usize = 100;
    for full in [false, true] {
        let started = std::time::Instant::now();
        for _ in 0..10 {
            cycle(full);
        }
        let each = started.elapsed().as_secs_f64() / 10.0;
        let cycles = if each * CYCLES as f64 > BUDGET {
            ((BUDGET / each) as usize).clamp(FEWEST, CYCLES)
        } else {
            CYCLES
        };
        let warm_up = 500 * cycles / CYCLES;
        for _ in 0..warm_up {
            cycle(full);
        }
        let slack = (SLACK * cycles / CYCLES).max(128 * 1024);
        let what = if full {
            "instantiate/run/state/free"
        } else {
            "instantiate/free"
        };
        let mut measure = || {
            let before = rss();
            for _ in 0..cycles {
                cycle(full);
            }
            let after = rss();
            info(format!("{cycles} {what} cycles: RSS {before} -> {after} bytes"));
            after.saturating_sub(before)
        };
        let grew = measure();
        // A leak grows the resident set again in every run of the cycles; the allocator or the
        // dynamic loader may grow it once (CI saw 54 pages once in 6002 container cycles, then
        // none). So a growth over the slack is measured once more, and fails only if it repeats.
        let grew = if grew > slack {
            let again = measure();
            info(format!(
                "the RSS grew by {grew} bytes, over the {slack} allowed: {cycles} more cycles grew it by {again}"
            ));
            again
        } else {
            grew
        };
        if cycles < CYCLES {
            limitation(format!(
                "a {what} cycle takes {:.1} ms: {cycles} cycles ran, not {CYCLES} (a leak under {} bytes per cycle goes unseen)",
                each * 1e3,
                slack / cycles
            ));
        }
        // A leak is a warning: FMI 2.0.5 §2.1.5 and FMI 3.0.2 §2.3.1 say fmi2FreeInstance /
        // fmi3FreeInstance frees the instance's memory, but a small leak breaks no call; it
        // matters to an importer that instantiates many times (parameter studies).
        crate::outcome::warn_unless(grew <= slack, || {
            format!(
                "{id}: RSS grew by {grew} bytes over {cycles} {what} cycles (allowed {slack}), in a second run of the cycles as in the first: a leak"
            )
        });
    }
}
