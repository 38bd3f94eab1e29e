//! FMI 3.0: instantiate/free cycles leave memory flat.

use super::*;

/// One cycle of what an importer does with an instance of each interface: instantiate and free;
/// in full, also set the inputs, initialize, step, take, serialize and restore a state, and make
/// a refused call (its message allocates).
fn cycle(fmu: &Fmu3, full: bool) {
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) {
            continue;
        }
        let mut inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        if full {
            excite(&inst);
            inst.initialize();
            inst.step(fmu.step_size());
            if fmu.can_snapshot(me) {
                let bytes = inst.snapshot();
                assert_eq!(
                    inst.restore(&bytes),
                    fmi3OK,
                    "{}: restoring a state: {}",
                    fmu.id,
                    inst.log_text()
                );
            }
            let s = inst.set_f64(&[fmu.md.unknown_vr()], &[0.0]);
            assert_eq!(
                s,
                fmi3Error,
                "{}: fmi3SetFloat64 of an unknown value reference: {}",
                fmu.id,
                status_name(s)
            );
            inst.sink.take();
        }
    }
}

/// 10,000 cycles of each kind leave the resident set flat (alone in its process: a worker of
/// its own under the runner, a test binary of its own in the workspace); the measuring loop is
/// the FMI 2.0 check's.
pub fn fmi3_ten_thousand_instantiate_free_cycles_leave_memory_flat(fmu: &Fmu3) {
    if !fmu.can_snapshot(fmu.md.cs.is_none()) {
        limitation("the FMU cannot serialize its state: the cycles take and restore no FMU state");
    }
    crate::checks::memory::cycles_leave_memory_flat(&fmu.id, |full| cycle(fmu, full));
}
