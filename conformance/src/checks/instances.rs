//! Many instances of every packaged FMU: independent in one process, bit-identical when each
//! runs on its own thread, and the library can be unloaded after the last fmi2FreeInstance and
//! loaded again.

use crate::fmi2::*;
use crate::instance::{Instance, excitation, step_size};
use crate::{Api, Description, Fmu, Type, bits};
use std::ffi::CString;

/// The excitation of the suite scaled by `scale`, so that each instance runs differently, kept
/// inside each variable's [min, max] (a negative scale would otherwise set a height declared
/// `min = 0` below the floor, which a correct model refuses).
fn excite_scaled(inst: &mut Instance, scale: f64) {
    let md = &inst.fmu.md;
    let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(inst.fmu)
        .into_iter()
        .map(|(vr, v)| {
            let var = md.of_type(Type::Real).find(|x| x.vr == vr);
            let x = v * scale;
            let x = var.and_then(|var| var.max).map_or(x, |m| x.min(m));
            let x = var.and_then(|var| var.min).map_or(x, |m| x.max(m));
            (vr, x)
        })
        .unzip();
    assert_eq!(inst.set_real(&vrs, &vals), fmi2OK, "{}", inst.log_text());
}

fn solo(fmu: &Fmu, scale: f64, steps: usize) -> Vec<Vec<u64>> {
    let mut inst = Instance::new(fmu);
    excite_scaled(&mut inst, scale);
    inst.initialize();
    let h = step_size(fmu);
    let mut out = Vec::with_capacity(steps);
    for _ in 0..steps {
        if !continues(&mut inst, h) {
            break;
        }
        out.push(inst.observe());
    }
    out
}

/// One step of `h`: true when it completed, false when the model ended the simulation in it
/// (fmi2Discard with fmi2Terminated, Stair at its last count); anything else fails the check.
fn continues(inst: &mut Instance, h: f64) -> bool {
    let s = inst.step(h);
    if s == fmi2OK {
        true
    } else if s == fmi2Discard && inst.terminated() == (fmi2OK, fmi2True) {
        false
    } else {
        panic!(
            "fmi2DoStep at t = {}: {s} (not OK, and not the end of the simulation)",
            inst.time
        )
    }
}

const SCALES: [f64; 6] = [0.5, 0.8, 1.0, 1.2, -0.7, 0.3];

pub fn interleaved_instances_do_not_affect_each_other(fmu: &Fmu) {
    let steps = 50;
    let mut insts: Vec<Instance> = SCALES
        .iter()
        .map(|s| {
            let mut i = Instance::new(fmu);
            excite_scaled(&mut i, *s);
            i.initialize();
            i
        })
        .collect();
    let mut got = vec![vec![]; insts.len()];
    let mut ended = vec![false; insts.len()];
    let h = step_size(fmu);
    for _ in 0..steps {
        for (i, inst) in insts.iter_mut().enumerate() {
            if ended[i] || !continues(inst, h) {
                ended[i] = true;
                continue;
            }
            got[i].push(inst.observe());
        }
        // An instance freed and a new one made in between changes nothing either.
        drop(Instance::new(fmu));
    }
    for (i, s) in SCALES.iter().enumerate() {
        assert_eq!(
            got[i],
            solo(fmu, *s, steps),
            "{}: instance {i} (scale {s}) differs from a run alone",
            fmu.id
        );
    }
    // (A model with no Real input or exact start value to excite, Stair, runs the same in all.)
    if !excitation(fmu).is_empty() {
        assert_ne!(got[0], got[1], "{}: differently excited instances must differ", fmu.id);
    }
}

pub fn instances_on_their_own_threads_match_sequential_runs_bit_for_bit(fmu: &Fmu) {
    let steps = 200;
    let sequential: Vec<_> = SCALES.iter().map(|s| solo(fmu, *s, steps)).collect();
    let threaded: Vec<_> = std::thread::scope(|scope| {
        let handles: Vec<_> = SCALES
            .iter()
            .map(|s| scope.spawn(move || solo(fmu, *s, steps)))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a thread panicked"))
            .collect()
    });
    assert_eq!(
        threaded, sequential,
        "{}: threaded runs differ from sequential ones",
        fmu.id
    );
}

/// A short run through a separately loaded library, by raw calls: Real values after each step.
fn raw_run(api: &Api, md: &Description, resources: &str, steps: usize) -> Result<Vec<u64>, String> {
    let guid = CString::new(md.guid.as_str()).unwrap();
    let res = CString::new(resources).unwrap();
    let sink = crate::logger::LogSink::default();
    let callbacks = crate::logger::callbacks(sink.env());
    let vrs = md.vrs_of_type(Type::Real);
    let mut values = vec![0.0; vrs.len()];
    let mut out = vec![];
    // SAFETY: the standard's calling sequence on a live instance with valid arguments.
    unsafe {
        let c = api.instantiate_cs(c"unload", &guid, &res, &callbacks);
        if c.is_null() {
            return Err(format!("fmi2Instantiate: {:?}", sink.take()));
        }
        let mut s = (api.setup_experiment)(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
        s = s.max((api.enter_initialization_mode)(c));
        s = s.max((api.exit_initialization_mode)(c));
        for n in 0..steps {
            s = s.max((api.do_step)(c, n as f64 * 0.01, 0.01, fmi2True));
            s = s.max(crate::guard::fill(
                &mut values,
                "fmi2GetReal",
                "nvr",
                crate::guard::GETTER_RULE2,
                |p| (api.get_real)(c, vrs.as_ptr(), vrs.len(), p),
            ));
            out.extend(bits(&values));
        }
        s = s.max((api.terminate)(c));
        (api.free_instance)(c);
        if s != fmi2OK {
            return Err(format!("worst status {s}: {:?}", sink.take()));
        }
    }
    Ok(out)
}

/// Whether the library at `path` is loaded in this process (Linux: mapped, in /proc/self/maps).
#[cfg(not(windows))]
fn mapped(path: &std::path::Path) -> bool {
    let maps = std::fs::read_to_string("/proc/self/maps").unwrap();
    maps.contains(&*path.to_string_lossy())
}

/// Whether the library at `path` is loaded in this process (Windows: GetModuleHandleW finds it).
#[cfg(windows)]
fn mapped(path: &std::path::Path) -> bool {
    use std::os::windows::ffi::OsStrExt;
    unsafe extern "system" {
        fn GetModuleHandleW(name: *const u16) -> *mut std::ffi::c_void;
    }
    let wide: Vec<u16> = path.as_os_str().encode_wide().chain([0]).collect();
    // SAFETY: a NUL-terminated UTF-16 path; the handle is only compared with NULL.
    !unsafe { GetModuleHandleW(wide.as_ptr()) }.is_null()
}

pub fn the_library_can_be_unloaded_after_the_last_free_and_loaded_again(fmu: &Fmu) {
    // A copy of its own, so that the suite's loaded library does not keep it in memory.
    let copy = fmu
        .scratch
        .join(format!("unload-{}.{}", fmu.id, crate::LIBRARY_EXTENSION));
    std::fs::copy(&fmu.so, &copy).unwrap();
    let resources = fmu.resource_uri();
    let api = Api::load(&copy).unwrap();
    let first = raw_run(&api, &fmu.md, &resources, 20).unwrap();
    assert!(mapped(&copy));
    api.unload().unwrap_or_else(|e| panic!("{}: dlclose: {e}", fmu.id));
    assert!(
        !mapped(&copy),
        "{}: the library stays mapped after dlclose (a thread-local destructor or a leaked thread keeps it)",
        fmu.id
    );
    // Loaded again: the same results, nothing left over from the first load.
    let api = Api::load(&copy).unwrap();
    let second = raw_run(&api, &fmu.md, &resources, 20).unwrap();
    assert_eq!(first, second, "{}: a run after reloading differs", fmu.id);
    api.unload().unwrap();
    let _ = std::fs::remove_file(&copy);
    // The suite's own library is unaffected.
    let mut inst = Instance::new(fmu);
    inst.initialize();
    assert_eq!(inst.step(0.01), fmi2OK);
}
