//! FMI 3.0 FMU states: get/set and serialize round trips, damaged states, and a state restored
//! in another process.

use super::*;
use crate::guard::{Guarded, STATE_RULE3};

// ---------------------------------------------------------------------------------------------
// FMU state

fn snapshot_only(fmu: &Fmu3, me: bool) -> bool {
    if !fmu.can_snapshot(me) {
        info(format!(
            "{}: canGetAndSetFMUState/canSerializeFMUState not both declared",
            if me { "ME" } else { "CS" }
        ));
        return false;
    }
    true
}

pub fn fmi3_fmu_state_get_set_and_serialize_round_trips_continue_bit_identically(fmu: &Fmu3) {
    let h = fmu.step_size();
    let mut tested = 0;
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) || !snapshot_only(fmu, me) {
            continue;
        }
        tested += 1;
        let api = &fmu.api;
        let mut a = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        excite(&a);
        a.initialize();
        for _ in 0..10 {
            a.step(h);
        }
        let t_saved = a.time;
        // get/set through a pointer
        let mut st: fmi3FMUState = null_mut();
        assert_eq!(a.get_state(&mut st), fmi3OK);
        let bytes = a.snapshot();
        let reference: Vec<Vec<u64>> = (0..10)
            .map(|_| {
                a.step(h);
                a.observe()
            })
            .collect();
        assert_eq!(a.set_state(st), fmi3OK, "{}: fmi3SetFMUState: {}", fmu.id, a.log_text());
        a.time = t_saved;
        let again: Vec<Vec<u64>> = (0..10)
            .map(|_| {
                a.step(h);
                a.observe()
            })
            .collect();
        assert!(
            again == reference,
            "{}: after fmi3SetFMUState the run differs ({})",
            fmu.id,
            if me { "ME" } else { "CS" }
        );
        // Another instance of the same FMU continues from that state like the first (as FMI 2.0
        // importers use it: a state is a copy of the FMU's state, not of one instance).
        let mut other = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        // (Recorded without its arguments, not replayable: a state another instance made.)
        assert_eq!(
            other.set_state(st),
            fmi3OK,
            "{}: fmi3SetFMUState with a state of another instance of the same FMU: {}",
            fmu.id,
            other.log_text()
        );
        other.time = t_saved;
        let from_other: Vec<Vec<u64>> = (0..10)
            .map(|_| {
                other.step(h);
                other.observe()
            })
            .collect();
        assert!(
            from_other == reference,
            "{}: another instance set to the state continues differently",
            fmu.id
        );
        drop(other);
        // Overwriting a state with fmi3GetFMUState on the same pointer.
        assert_eq!(a.get_state(&mut st), fmi3OK);
        assert_eq!(a.free_state(&mut st), fmi3OK);
        assert!(st.is_null(), "{}: fmi3FreeFMUState left the pointer non-NULL", fmu.id);
        // serialize / deserialize into a new instance
        let mut b = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        assert_eq!(
            b.restore(&bytes),
            fmi3OK,
            "{}: restoring a serialized state in a new instance: {}",
            fmu.id,
            b.log_text()
        );
        b.time = t_saved;
        // The bytes: a warning (FMI 3.0.2 promises nothing of them, and a state holding addresses
        // differs on every serialization); what the restored instance does decides, below.
        crate::outcome::warn_unless(b.snapshot() == bytes, || {
            format!(
                "{}: the state serialized after restoring differs from the one restored (addresses in it? it cannot be compared or cached)",
                fmu.id
            )
        });
        let other: Vec<Vec<u64>> = (0..10)
            .map(|_| {
                b.step(h);
                b.observe()
            })
            .collect();
        assert!(
            other == reference,
            "{}: a new instance with the deserialized state continues differently ({})",
            fmu.id,
            if me { "ME" } else { "CS" }
        );
        // size and serialize with a too small buffer
        let mut st: fmi3FMUState = null_mut();
        assert_eq!(a.get_state(&mut st), fmi3OK);
        let n = bytes.len().saturating_sub(1);
        let mut small = Guarded::new(n, 0u8);
        let p = small.as_mut_ptr();
        a.state_args(st, vec![("size", crate::calllog::Val::U64(n as u64))]);
        // SAFETY: a live instance; `p` holds `n` bytes (and the guard after them).
        let s = a.call("fmi3SerializeFMUState", |c| unsafe {
            (api.serialize_fmu_state)(c, st, p, n)
        });
        // Refused or not, nothing may be written past the buffer the call names.
        small.into_values(
            || format!("fmi3SerializeFMUState into a buffer one byte too small (size = {n})"),
            STATE_RULE3,
        );
        assert_eq!(
            s,
            fmi3Error,
            "{}: fmi3SerializeFMUState into a buffer one byte too small: {}",
            fmu.id,
            status_name(s)
        );
        assert_eq!(a.free_state(&mut st), fmi3OK);
    }
    if tested == 0 {
        skip_not_declared("canGetAndSetFMUState and canSerializeFMUState");
    }
}

/// Verdict: warned, never failed (but for a crash outside the damaged calls): a damaged buffer
/// or another FMU's state is the importer's mistake, whose detection FMI 3.0.2 leaves to the FMU
/// (§2.2.4: fmi3Error "when detecting illegal arguments"); a crash on one is a warning too.
pub fn fmi3_damaged_serialized_states_and_states_of_other_fmus_are_refused(fmu: &Fmu3) {
    let me = fmu.md.cs.is_none();
    if !fmu.can_snapshot(me) {
        skip_not_declared("canGetAndSetFMUState and canSerializeFMUState");
    }
    let mut a = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
    excite(&a);
    a.initialize();
    a.step(fmu.step_size());
    let bytes = a.snapshot();
    let before = a.observe();
    // Damage of the length is refused whatever the format; damage only a checksum (or the
    // token in the state) can find is required to be refused of this exporter's format, and of
    // another exporter's only not to crash nor change the instance (its format may have none).
    let own = fmu.own_state_format();
    if !own {
        limitation(
            "bit flips, zeros of the right length and states of other FMUs may be accepted (another exporter's state may carry no checksum or token): they must not crash",
        );
    }
    let attempt = |what: &str, b: &[u8], strict: bool| {
        let mut st: fmi3FMUState = null_mut();
        let s = crate::outcome::on_purpose(|| a.deserialize(b, &mut st));
        if s == fmi3OK {
            let _ = a.free_state(&mut st);
        }
        // A damaged buffer is the importer's mistake (FMI 3.0.2 §2.2.6.4 defines deserializing
        // what fmi3SerializeFMUState wrote): not detected, a warning.
        crate::outcome::warn_unless(s == fmi3Error || (!strict && s == fmi3OK), || {
            format!(
                "{}: fmi3DeserializeFMUState of {what}: expected fmi3Error{}, got {} (an importer's mistake not detected)",
                fmu.id,
                if strict { "" } else { " (or fmi3OK)" },
                status_name(s)
            )
        });
    };
    let try_bytes = |what: &str, b: &[u8]| attempt(what, b, true);
    let try_checksum = |what: &str, b: &[u8]| attempt(what, b, own);
    try_bytes("an empty buffer", &[]);
    try_bytes("the state without its last byte", &bytes[..bytes.len() - 1]);
    try_bytes("the state without its first half", &bytes[bytes.len() / 2..]);
    let mut longer = bytes.clone();
    longer.push(0);
    try_bytes("the state with a byte appended", &longer);
    try_checksum("zeros of the state's size", &vec![0u8; bytes.len()]);
    for at in [0, bytes.len() / 3, bytes.len() / 2, bytes.len() - 1] {
        let mut b = bytes.clone();
        b[at] ^= 0x5a;
        try_checksum(&format!("the state with byte {at} of {} changed", bytes.len()), &b);
    }
    // NULL buffer with a size
    let s = crate::outcome::on_purpose(|| a.deserialize_null(bytes.len()));
    if s != fmi3Error {
        crate::calllog::warning_requires(crate::replay::Expected::ERROR);
    }
    crate::outcome::warn_unless(s == fmi3Error, || {
        format!(
            "{}: fmi3DeserializeFMUState(NULL, {}): {} (an importer's mistake not detected)",
            fmu.id,
            bytes.len(),
            status_name(s)
        )
    });
    crate::outcome::warn_unless(a.observe() == before, || {
        format!(
            "{}: refused states changed the instance (robustness beyond FMI 3.0.2 §2.2.4)",
            fmu.id
        )
    });
    // States of the other packaged FMUs (3.0 files next to this one, and the 2.0 file of the
    // same model one folder up, as `cargo fmu build` places them).
    let mut others = 0;
    let dir = fmu.archive.parent().map(|p| p.to_path_buf()).unwrap_or_default();
    let mut candidates: Vec<std::path::PathBuf> = std::fs::read_dir(&dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "fmu") && *p != fmu.archive)
        .collect();
    candidates.sort();
    let root = crate::unpack_root().unwrap_or_else(|e| panic!("{e}"));
    for other in candidates.iter().take(3) {
        let Ok(o) = Fmu3::load(other, &root) else {
            continue;
        };
        let ome = o.md.cs.is_none();
        if !o.can_snapshot(ome) {
            continue;
        }
        let mut oi = if ome { Inst::me(&o) } else { Inst::cs(&o) };
        oi.initialize();
        let ob = oi.snapshot();
        try_checksum(&format!("a state of the FMU {}", o.id), &ob);
        others += 1;
    }
    if let Some(parent) = dir.parent() {
        let two = parent.join(format!("{}.fmu", fmu.id));
        if two.exists()
            && let Ok(f2) = crate::Fmu::load(&two, &root)
            && f2.can_snapshot()
        {
            let mut i2 = crate::Instance::new(&f2);
            let b2 = i2.snapshot();
            drop(i2);
            try_checksum("the state of the FMI 2.0 binary of the same model", &b2);
            others += 1;
        }
    }
    info(format!("states of {others} other FMUs refused"));
}

/// The other process is a worker ([`crate::worker`], mode `state-child`): it unpacks and loads
/// the FMU afresh, instantiates the same interface, restores the state, re-serializes it, and
/// continues; its bytes and every observation after each step must be those of this process.
pub fn fmi3_a_state_serialized_here_restores_in_another_process_and_continues_identically(fmu: &Fmu3) {
    let worker = crate::worker().unwrap_or_else(|| {
        panic!("no worker executable set (fmi_conformance::set_worker): the other process cannot be started")
    });
    let mut checked = 0;
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) || !fmu.can_snapshot(me) {
            continue;
        }
        let h = fmu.step_size();
        let mut inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        excite(&inst);
        inst.initialize();
        for _ in 0..10 {
            inst.step(h);
        }
        let bytes = inst.snapshot();
        let t = inst.time;
        let expected: Vec<Vec<u64>> = (0..20)
            .map(|_| {
                inst.step(h);
                inst.observe()
            })
            .collect();
        let file = fmu.scratch.join(format!("state-{}.bin", if me { "me" } else { "cs" }));
        std::fs::write(&file, &bytes).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let out = std::process::Command::new(&worker.exe)
            .args(&worker.args_prefix)
            .arg("state-child")
            .arg(&fmu.archive)
            .arg(&file)
            .args([
                "20".to_string(),
                h.to_string(),
                (if me { "me" } else { "cs" }).to_string(),
                t.to_string(),
            ])
            .stdin(std::process::Stdio::null())
            .output()
            .unwrap_or_else(|e| panic!("cannot run the worker {}: {e}", worker.exe.display()));
        let _ = std::fs::remove_file(&file);
        let what = if me { "Model Exchange" } else { "Co-Simulation" };
        assert!(
            out.status.success(),
            "{}: {what}: the other process failed ({}): {}",
            fmu.id,
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        let parse_hex = |l: &str| -> Vec<u64> {
            l.split_whitespace()
                .map(|x| u64::from_str_radix(x, 16).unwrap_or(u64::MAX))
                .collect()
        };
        let mut lines = stdout.lines();
        let reserialized: Vec<u8> = parse_hex(lines.next().unwrap_or(""))
            .into_iter()
            .map(|b| b as u8)
            .collect();
        crate::outcome::warn_unless(reserialized == bytes, || {
            format!(
                "{}: {what}: the other process re-serializes the state to other bytes (FMI 3.0.2 promises nothing of them; judged by the steps below)",
                fmu.id
            )
        });
        let got: Vec<Vec<u64>> = lines.map(parse_hex).collect();
        assert_eq!(
            got.len(),
            expected.len(),
            "{}: {what}: steps reported by the other process",
            fmu.id
        );
        assert_eq!(
            got, expected,
            "{}: {what}: the other process continues differently",
            fmu.id
        );
        checked += 1;
    }
    if checked == 0 {
        skip_not_declared("canGetAndSetFMUState and canSerializeFMUState");
    }
}

/// The serialized FMU state, taken after initialization and after 10 steps in each declared
/// interface that can serialize it, fits the size fmi3SerializedFMUStateSize announced:
/// fmi3SerializeFMUState writes no byte past it (the guard after the buffer, `src/guard.rs`).
///
/// Verdict: a byte written past the size is a failure: FMI 3.0.2, Getting and Setting the
/// Complete FMU State (fmi3SerializeFMUState copies the state into the byte vector
/// serializedState of length size that the importer provides, size being
/// fmi3SerializedFMUStateSize's answer). Skipped where the FMU does not declare
/// canGetAndSetFMUState and canSerializeFMUState.
pub fn fmi3_serialized_state_fits_its_announced_size(fmu: &Fmu3) {
    let interfaces: Vec<bool> = [false, true].into_iter().filter(|me| fmu.can_snapshot(*me)).collect();
    if interfaces.is_empty() {
        skip_not_declared("canGetAndSetFMUState and canSerializeFMUState");
    }
    for me in interfaces {
        let mut inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        excite(&inst);
        inst.initialize();
        for k in [0, 10] {
            for _ in 0..k {
                inst.step(fmu.step_size());
            }
            // Guarded: a byte past `size` fails here, naming the call.
            if let Err(e) = inst.try_snapshot() {
                panic!("{}: the FMU state after {k} steps: {e}", fmu.id);
            }
        }
    }
}
