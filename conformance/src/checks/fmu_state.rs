//! FMU state for every packaged FMU: get/set/free and serialize/deserialize round-trips continue
//! bit-identically, the serialized form is versioned, position-independent and checked, and a
//! state serialized in one process restores in another.
//!
//! FMU state is optional in FMI 2.0: on an FMU that does not declare canGetAndSetFMUstate (and
//! canSerializeFMUstate, for the serialized form) these checks are skipped. The layout of the
//! serialized state is checked only on this exporter's FMUs; on another exporter's, a damaged
//! state must be refused where its length is wrong, and must not crash otherwise.

use crate::Fmu;
use crate::fmi2::*;
use crate::instance::{Instance, excitation, status_name, step_size};
use crate::outcome::{convention, limitation, skip};
use crate::state::{FORMAT_VERSION, parse, reseal};
use std::ptr;

/// Skips the check unless the FMU declares canGetAndSetFMUstate.
fn needs_get_set(fmu: &Fmu) {
    if !fmu.cs().can_get_and_set_fmu_state {
        skip("the FMU does not declare canGetAndSetFMUstate (optional in FMI 2.0)");
    }
}

/// Skips the check unless the FMU declares canGetAndSetFMUstate and canSerializeFMUstate.
fn needs_serialize(fmu: &Fmu) {
    needs_get_set(fmu);
    if !fmu.cs().can_serialize_fmu_state {
        skip("the FMU does not declare canSerializeFMUstate (optional in FMI 2.0)");
    }
}

/// An excited, initialized instance after `k` steps.
fn advanced(fmu: &Fmu, k: usize) -> Instance<'_> {
    let mut inst = Instance::new(fmu);
    let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
    assert_eq!(inst.set_real(&vrs, &vals), fmi2OK);
    inst.initialize();
    for _ in 0..k {
        assert_eq!(inst.step(step_size(fmu)), fmi2OK, "{}", inst.log_text());
    }
    inst
}

fn continue_for(inst: &mut Instance, m: usize) -> Vec<Vec<u64>> {
    let h = step_size(inst.fmu);
    (0..m)
        .map(|_| {
            assert_eq!(inst.step(h), fmi2OK, "{}: {}", inst.fmu.id, inst.log_text());
            inst.observe()
        })
        .collect()
}

pub fn every_fmu_declares_it_can_get_set_and_serialize_its_state(fmu: &Fmu) {
    if !fmu.own_state_format() && !fmu.can_snapshot() {
        skip(
            "canGetAndSetFMUstate and canSerializeFMUstate are optional in FMI 2.0 (this exporter's FMUs declare both)",
        );
    }
    assert!(fmu.cs().can_get_and_set_fmu_state, "{}: canGetAndSetFMUstate", fmu.id);
    assert!(fmu.cs().can_serialize_fmu_state, "{}: canSerializeFMUstate", fmu.id);
}

/// Verdict: failed where a state set back does not continue as the instance did from it (FMI
/// 2.0.5 §2.1.8: fmi2SetFMUstate "copies the content of the previously copied FMUstate back and
/// uses it as actual new FMU state. The FMUstate copy does still exist"), or where freeing a NULL
/// FMUstate is not ignored ("If a null pointer is provided, the call is ignored"). Warned: a NULL
/// fmi2FMUstate* to fmi2FreeFMUstate and a NULL state to fmi2SetFMUstate not refused, or crashing
/// (the importer's mistakes, which the standard leaves undefined), and an overwritten state not
/// reusing its memory ("typically reuses").
pub fn get_set_free_round_trip_continues_bit_identically(fmu: &Fmu) {
    needs_get_set(fmu);
    let mut inst = advanced(fmu, 10);
    let (st, mut saved) = inst.get_state();
    assert_eq!(st, fmi2OK);
    let at_save = inst.observe();
    let t = inst.time;
    let first = continue_for(&mut inst, 20);
    // Going back twice: the state is not consumed by fmi2SetFMUstate.
    for round in 0..2 {
        assert_eq!(inst.set_state(saved), fmi2OK, "{}: {}", fmu.id, inst.log_text());
        inst.time = t;
        assert_eq!(
            inst.observe(),
            at_save,
            "{}: values right after fmi2SetFMUstate",
            fmu.id
        );
        assert_eq!(
            continue_for(&mut inst, 20),
            first,
            "{}: continuation {round} differs",
            fmu.id
        );
    }
    // Re-using an existing FMUstate: fmi2GetFMUstate overwrites it in place.
    let (before, old_ptr) = (inst.observe(), saved);
    // Through the call log: `fmi2GetFMUstate into=1`.
    assert_eq!(
        inst.get_state_into(&mut saved),
        fmi2OK,
        "{}: {}",
        fmu.id,
        inst.log_text()
    );
    // FMI 2.0.5 §2.1.8: fmi2GetFMUstate "typically reuses the memory of this FMUstate": not
    // required, a warning.
    crate::outcome::warn_unless(saved == old_ptr, || {
        format!("{}: fmi2GetFMUstate on an existing FMUstate did not reuse it", fmu.id)
    });
    let t2 = inst.time;
    continue_for(&mut inst, 3);
    assert_eq!(inst.set_state(saved), fmi2OK);
    inst.time = t2;
    assert_eq!(inst.observe(), before, "{}: the overwritten state", fmu.id);
    assert_eq!(inst.free_state(&mut saved), fmi2OK);
    assert!(saved.is_null());
    // A pointer to a NULL FMUstate is ignored: FMI 2.0.5 §2.1.8, fmi2FreeFMUstate: "If a null
    // pointer is provided, the call is ignored. The function returns a null pointer in argument
    // FMUstate" (the argument FMUstate is the state the fmi2FMUstate* points to).
    assert_eq!(
        inst.free_state(&mut saved),
        fmi2OK,
        "{}: fmi2FreeFMUstate of a NULL FMUstate (FMI 2.0.5 §2.1.8: \"If a null pointer is provided, the call is ignored\")",
        fmu.id
    );
    // A NULL fmi2FMUstate* and a NULL FMUstate to set are the importer's mistakes: the standard
    // defines neither, so refusing them is good practice, and a crash or another answer a
    // warning (outcome::on_purpose). The Reference FMUs v0.0.41 dereference the NULL fmi2FMUstate*
    // in fmi2FreeFMUstate.
    crate::outcome::on_purpose(|| {
        // Through the call log (a failure after it leaves a reproducer with the call).
        let s = inst.free_state_pointer_null();
        crate::outcome::warn_unless(s == fmi2OK || s == fmi2Error, || {
            format!("{}: fmi2FreeFMUstate(c, NULL): {}", fmu.id, status_name(s))
        });
        let s = inst.set_state(ptr::null_mut());
        crate::outcome::warn_unless(s == fmi2Error, || {
            format!(
                "{}: fmi2SetFMUstate(c, NULL) answered {}, not refused",
                fmu.id,
                status_name(s)
            )
        });
    });
}

/// Verdict: judged by behaviour. FMI 2.0.5 §2.1.8: fmi2GetFMUstate "makes a copy of the internal
/// FMU state and returns a pointer to this copy", and fmi2SetFMUstate "copies the content of the
/// previously copied FMUstate back": restored after the instance moved on and was reset, the
/// state continues as the instance did from it (a failure otherwise). Its serialized bytes
/// differing from before is a warning (a state holding addresses serializes differently each
/// time; the standard promises nothing of the bytes).
pub fn a_saved_state_is_a_complete_copy_independent_of_the_instance(fmu: &Fmu) {
    needs_serialize(fmu);
    let mut inst = advanced(fmu, 5);
    let t_saved = inst.time;
    let (_, mut saved) = inst.get_state();
    let bytes = inst.serialize(saved).unwrap();
    let from_saved = continue_for(&mut inst, 5);
    assert_eq!(inst.reset(), fmi2OK);
    crate::outcome::warn_unless(inst.serialize(saved).unwrap() == bytes, || {
        format!(
            "{}: the saved state serializes differently after the instance moved on (addresses in it, or it shares memory with the instance)",
            fmu.id
        )
    });
    assert_eq!(inst.set_state(saved), fmi2OK, "{}: {}", fmu.id, inst.log_text());
    inst.time = t_saved;
    assert_eq!(
        continue_for(&mut inst, 5),
        from_saved,
        "{}: restored after the instance moved on and was reset, the state continues differently from the instance it was taken of (FMI 2.0.5 §2.1.8: fmi2GetFMUstate makes a copy of the internal FMU state)",
        fmu.id
    );
    assert_eq!(inst.reset(), fmi2OK);
    // And another instance can continue from it exactly like the first would have.
    let mut other = Instance::new(fmu);
    assert_eq!(other.set_state(saved), fmi2OK, "{}: {}", fmu.id, other.log_text());
    assert_eq!(inst.set_state(saved), fmi2OK);
    (inst.time, other.time) = (t_saved, t_saved);
    assert_eq!(
        continue_for(&mut other, 10),
        continue_for(&mut inst, 10),
        "{}: two instances from one state",
        fmu.id
    );
    assert_eq!(inst.free_state(&mut saved), fmi2OK);
}

pub fn serialize_deserialize_round_trip_continues_bit_identically(fmu: &Fmu) {
    needs_serialize(fmu);
    let mut inst = advanced(fmu, 10);
    let bytes = inst.snapshot();
    let t = inst.time;
    let first = continue_for(&mut inst, 20);
    inst.restore(&bytes);
    inst.time = t;
    assert_eq!(
        continue_for(&mut inst, 20),
        first,
        "{}: continuation after deserializing",
        fmu.id
    );
    // Into an existing FMUstate.
    let (_, mut existing) = inst.get_state();
    // SAFETY: `bytes.len()` readable bytes, an FMUstate of this FMU.
    let s = unsafe {
        crate::guard::fill_state2(&mut existing, "fmi2DeSerializeFMUstate", |q| {
            (fmu.api.deserialize_fmu_state)(inst.c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), q)
        })
    };
    assert_eq!(s, fmi2OK);
    crate::outcome::warn_unless(inst.serialize(existing).unwrap() == bytes, || {
        format!(
            "{}: deserialized into an existing FMUstate, the state serializes to other bytes (FMI 2.0.5 promises nothing of the bytes; determinism helps importers that compare states)",
            fmu.id
        )
    });
    assert_eq!(inst.set_state(existing), fmi2OK, "{}: {}", fmu.id, inst.log_text());
    inst.time = t;
    assert_eq!(
        continue_for(&mut inst, 20),
        first,
        "{}: continuation after deserializing into an existing FMUstate (FMI 2.0.5 §2.1.8)",
        fmu.id
    );
    assert_eq!(inst.free_state(&mut existing), fmi2OK);
}

/// Verdict: warned, never failed: FMI 2.0.5 §2.1.8 asks of a serialized state only that it
/// restores (judged by behaviour in the other FMU-state checks). Equal states serializing to
/// different bytes (addresses in the state) is portability advice: such a state cannot be
/// compared, cached or restored in another process reliably. `--strict` makes it a failure.
pub fn the_serialized_state_holds_no_pointers_and_is_versioned(fmu: &Fmu) {
    needs_serialize(fmu);
    // Two instances at different addresses in the same state serialize to the same bytes.
    let (mut a, mut b) = (advanced(fmu, 7), advanced(fmu, 7));
    let (sa, sb) = (a.snapshot(), b.snapshot());
    if sa != sb {
        crate::outcome::warned(format!(
            "{}: two instances in equal states serialize to different bytes ({} of {} differ): addresses in the state? It cannot then be restored in another process reliably",
            fmu.id,
            sa.iter().zip(&sb).filter(|(x, y)| x != y).count() + sa.len().abs_diff(sb.len()),
            sa.len()
        ));
    }
    if convention(fmu, "this exporter's versioned state format with the GUID") {
        let layout = parse(&sa).unwrap_or_else(|e| panic!("{}: {e}", fmu.id));
        assert_eq!(
            &sa[layout.guid_at..layout.guid_at + layout.guid_len],
            fmu.md.guid.as_bytes()
        );
    }
    // Both instances keep their own FMU states: serialize one through the other.
    let (_, mut s) = a.get_state();
    assert_eq!(b.serialize(s).unwrap(), sa);
    assert_eq!(a.free_state(&mut s), fmi2OK);
}

/// A damaged buffer handed to fmi2DeSerializeFMUstate is the importer's mistake: FMI 2.0.5
/// §2.1.8 defines deserialization of what fmi2SerializeFMUstate wrote and nothing else, so not
/// refusing it (or crashing on it: [`crate::outcome::on_purpose`]) is a warning.
fn assert_refused(inst: &mut Instance, bytes: &[u8], what: &str) {
    let before = inst.fingerprint();
    let (s, p) = crate::outcome::on_purpose(|| inst.deserialize(bytes));
    let log = inst.log();
    if s != fmi2Error {
        crate::outcome::warn(format!(
            "{}: {what} was accepted by fmi2DeSerializeFMUstate (damage not detected)",
            inst.fmu.id
        ));
        return;
    }
    crate::outcome::warn_unless(p.is_null(), || {
        format!("{}: {what}: a refused deserialization wrote a state", inst.fmu.id)
    });
    crate::outcome::warn_unless(inst.says(&log, fmi2Error, &["fmi2DeSerializeFMUstate"]), || {
        format!("{}: {what}: refused without a message: {log:?}", inst.fmu.id)
    });
    inst.warn_if_changed(&before, s, what);
}

/// For damage that only a checksum can find, on another exporter's FMU (whose format may have
/// none): refused as [`assert_refused`] requires, or accepted; either way without a crash.
fn refused_or_accepted(inst: &mut Instance, bytes: &[u8], what: &str) {
    if inst.fmu.own_state_format() {
        return assert_refused(inst, bytes, what);
    }
    let before = inst.fingerprint();
    let (s, mut p) = crate::outcome::on_purpose(|| inst.deserialize(bytes));
    if s == fmi2OK {
        assert_eq!(inst.free_state(&mut p), fmi2OK, "{}: {what}: freeing it", inst.fmu.id);
        inst.log();
        crate::outcome::warn_unless(inst.fingerprint() == before, || {
            format!(
                "{}: {what}: deserializing it (not set) changed the instance",
                inst.fmu.id
            )
        });
    } else {
        assert_refused(inst, bytes, what);
    }
}

pub fn damaged_serialized_states_are_refused_with_a_message(fmu: &Fmu) {
    needs_serialize(fmu);
    let mut inst = advanced(fmu, 3);
    let good = inst.snapshot();
    let own = fmu.own_state_format();
    if own {
        let l = parse(&good).unwrap();
        let mut v = good.clone();
        v[l.version_at..l.version_at + 4].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
        reseal(&mut v, &l);
        assert_refused(&mut inst, &v, "a newer format version");

        let mut g = good.clone();
        g[l.guid_at + 1] ^= 0x01;
        reseal(&mut g, &l);
        assert_refused(&mut inst, &g, "another FMU's GUID");
    } else {
        limitation(
            "a serialized state of another format version or GUID is not tried (the layout of another exporter's state is unknown)",
        );
        limitation(
            "bit flips and random bytes of the right length may be accepted (another exporter's state may have no checksum): they must not crash",
        );
    }

    let mut m = good.clone();
    m[0] = m[0].wrapping_add(1);
    refused_or_accepted(&mut inst, &m, "wrong magic bytes (first byte changed)");

    for len in 0..good.len() {
        assert_refused(
            &mut inst,
            &good[..len],
            &format!("truncated to {len} of {} bytes", good.len()),
        );
    }
    let mut long = good.clone();
    long.push(0);
    assert_refused(&mut inst, &long, "a trailing byte");

    // Every single-bit flip anywhere: caught by the checksum (or an earlier check).
    for i in 0..good.len() {
        let mut f = good.clone();
        f[i] ^= 1 << (i % 8);
        refused_or_accepted(&mut inst, &f, &format!("a bit flipped in byte {i}"));
    }

    // Random bytes of random lengths (a fixed xorshift sequence, so failures reproduce).
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    for _ in 0..200 {
        let len = (next() % (2 * good.len() as u64)) as usize;
        let r: Vec<u8> = (0..len).map(|_| next() as u8).collect();
        if len == good.len() {
            refused_or_accepted(&mut inst, &r, &format!("{len} random bytes"));
        } else {
            assert_refused(&mut inst, &r, &format!("{len} random bytes"));
        }
        if !own {
            continue;
        }
        let l = parse(&good).unwrap();
        // The same, behind a valid header: the payload decoder must refuse it.
        let mut h = good[..l.payload_at - 4].to_vec();
        h.extend_from_slice(&(r.len() as u32).to_le_bytes());
        h.extend_from_slice(&r);
        let crc = crc32fast::hash(&h);
        h.extend_from_slice(&crc.to_le_bytes());
        let (s, mut p) = inst.deserialize(&h);
        if s == fmi2OK {
            // Random bytes that happen to decode are a valid state of some kind: setting it
            // must still not crash, and the instance must stay usable.
            let _ = inst.set_state(p);
            assert_eq!(inst.free_state(&mut p), fmi2OK);
            assert_eq!(inst.reset(), fmi2OK);
            inst.restore(&good);
        } else {
            assert_eq!(s, fmi2Error);
        }
        inst.log();
    }

    // NULL bytes with a size, NULL out pointer: the importer's mistakes (a warning; a crash in
    // them too: outcome::on_purpose), through the call log.
    let s = crate::outcome::on_purpose(|| inst.deserialize_raw(None, 16, true));
    crate::outcome::warn_unless(s == fmi2Error, || format!("{}: NULL serializedState accepted", fmu.id));
    let s = crate::outcome::on_purpose(|| inst.deserialize_raw(Some(&good[..]), good.len(), false));
    crate::outcome::warn_unless(s == fmi2Error, || format!("{}: NULL FMUstate* accepted", fmu.id));
    // A buffer of the wrong size for fmi2SerializeFMUstate.
    let (_, mut st) = inst.get_state();
    let n = good.len() - 1;
    // Refused or not, nothing may be written past the buffer the call names (Instance::
    // serialize_into fails the check where the guard after it changed).
    let (s, small) = crate::outcome::on_purpose(|| inst.serialize_into(st, n));
    crate::outcome::warn_unless(s == fmi2Error, || {
        format!("{}: fmi2SerializeFMUstate into a too small buffer: not refused", fmu.id)
    });
    // Writing into the buffer and then refusing leaves the importer garbage: a failure (the
    // reproducer's line expects the buffer as it was given, zeros).
    if s == fmi2Error && small.iter().any(|b| *b != 0) {
        crate::calllog::expect_values(&vec![0.0; n], 0.0);
    }
    assert!(
        small.iter().all(|b| *b == 0) || s != fmi2Error,
        "{}: wrote into a too small buffer and then refused it",
        fmu.id
    );
    assert_eq!(inst.free_state(&mut st), fmi2OK);
    inst.log();
    let s = inst.step(step_size(fmu));
    crate::outcome::warn_unless(s == fmi2OK, || {
        format!(
            "{}: a step after the refused damaged states answered {} (going on after fmi2Error is beyond FMI 2.0.5 §2.1.3)",
            fmu.id,
            status_name(s)
        )
    });
}

/// The other process is a worker ([`crate::worker`], mode `state-child`): it unpacks and loads
/// the FMU afresh, restores the state, and prints what it observes.
///
/// Verdict: judged by behaviour: the other process's 20 steps must equal this one's (a failure
/// otherwise: FMI 2.0.5 §2.1.8 defines serialization so that a state can be restored "in
/// another process"); the re-serialized bytes differing is a warning.
pub fn a_state_serialized_here_restores_in_another_process_and_continues_identically(fmu: &Fmu) {
    needs_serialize(fmu);
    let worker = crate::worker().unwrap_or_else(|| {
        panic!("no worker executable set (fmi_conformance::set_worker): the other process cannot be started")
    });
    let mut inst = advanced(fmu, 10);
    let t_saved = inst.time;
    let bytes = inst.snapshot();
    let expected = continue_for(&mut inst, 20);
    let file = fmu.scratch.join("state.bin");
    std::fs::write(&file, &bytes).unwrap();
    let out = std::process::Command::new(&worker.exe)
        .args(&worker.args_prefix)
        .arg("state-child")
        .arg(&fmu.archive)
        .arg(&file)
        .args(["20", &step_size(fmu).to_string(), &t_saved.to_string()])
        .stdin(std::process::Stdio::null())
        .output()
        .unwrap_or_else(|e| panic!("cannot run the worker {}: {e}", worker.exe.display()));
    let _ = std::fs::remove_file(&file);
    assert!(
        out.status.success(),
        "{}: the other process failed ({}): {}",
        fmu.id,
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    let mut lines = stdout.lines();
    let parse_hex = |l: &str| -> Vec<u64> {
        l.split_whitespace()
            .map(|x| u64::from_str_radix(x, 16).unwrap())
            .collect()
    };
    let reserialized: Vec<u8> = parse_hex(lines.next().unwrap()).into_iter().map(|b| b as u8).collect();
    crate::outcome::warn_unless(reserialized == bytes, || {
        format!(
            "{}: the other process re-serializes the state to other bytes (FMI 2.0.5 promises nothing of the bytes; judged by behaviour below)",
            fmu.id
        )
    });
    let got: Vec<Vec<u64>> = lines.map(parse_hex).collect();
    assert_eq!(got.len(), expected.len(), "{}: steps reported by the child", fmu.id);
    assert_eq!(
        got, expected,
        "{}: restored in another process, the state continues differently (FMI 2.0.5 §2.1.8: a serialized state restored with fmi2DeSerializeFMUstate and fmi2SetFMUstate continues as the instance it was taken of)",
        fmu.id
    );
}

/// The serialized FMU state, taken after initialization and after 10 steps, fits the size
/// fmi2SerializedFMUstateSize announced: fmi2SerializeFMUstate writes no byte past it (the
/// guard after the buffer, `src/guard.rs`).
///
/// Verdict: a byte written past the size is a failure: FMI 2.0.5 §2.1.8 (fmi2SerializeFMUstate
/// copies the state "into the byte vector serializedState of length size, that must be provided
/// by the environment", size being fmi2SerializedFMUstateSize's answer). Skipped where the FMU
/// does not declare canGetAndSetFMUstate and canSerializeFMUstate.
pub fn serialized_state_fits_its_announced_size(fmu: &Fmu) {
    if !fmu.can_snapshot() {
        crate::outcome::skip_not_declared("canGetAndSetFMUstate and canSerializeFMUstate");
    }
    for k in [0, 10] {
        let mut inst = advanced(fmu, k);
        let (s, st) = inst.get_state();
        assert_eq!(
            s,
            fmi2OK,
            "{}: fmi2GetFMUstate after {k} steps: {}",
            fmu.id,
            inst.log_text()
        );
        // Guarded: a byte past `size` fails here, naming the call.
        let bytes = inst.serialize(st);
        assert!(
            bytes.is_ok(),
            "{}: fmi2SerializeFMUstate after {k} steps answered {:?}: {}",
            fmu.id,
            bytes.err(),
            inst.log_text()
        );
    }
}
