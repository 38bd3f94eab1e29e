//! fmi2DoStep, fmi2SetReal and fmi2GetReal of the Pendulum FMU allocate nothing on the heap.
//!
//! The Pendulum FMU crate is linked into this test binary (its rlib), so the `fmi2*` functions
//! called here are the same code the packaged `.so` exports, and every allocation they make goes
//! through this binary's global allocator, which counts the allocations of the thread that armed it.

use pendulum_fmu::Pendulum;
use pendulum_fmu::*;
use rustfmu::__private::abi::*;
use rustfmu::Variables;
use rustfmu::testing::allocations_in;
use std::ffi::CString;

#[global_allocator]
static ALLOCATOR: rustfmu::testing::CountingAllocator = rustfmu::testing::CountingAllocator;

/// The value reference of a Pendulum variable, from its declaration.
fn vr(name: &str) -> u32 {
    Pendulum::DESCRIPTION
        .by_name(name)
        .unwrap_or_else(|| panic!("the Pendulum has no variable '{name}'"))
        .value_reference
}

/// An initialized Pendulum instance, tilted so that it swings.
fn swinging_pendulum(callbacks: &fmi2CallbackFunctions) -> fmi2Component {
    let name = CString::new("alloc-test").unwrap();
    let guid = CString::new(pendulum_fmu::__rustfmu_fmi2_exports::GUID).unwrap();
    // SAFETY: valid NUL-terminated strings and callbacks that outlive the instance.
    unsafe {
        let c = fmi2Instantiate(
            name.as_ptr(),
            fmi2CoSimulation,
            guid.as_ptr(),
            c"file:///tmp".as_ptr(),
            callbacks,
            fmi2False,
            fmi2False,
        );
        assert!(!c.is_null(), "fmi2Instantiate returned NULL");
        assert_eq!(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        let (vrs, start) = ([vr("alpha1_0"), vr("alpha2_0")], [0.1, 0.15]);
        assert_eq!(fmi2SetReal(c, vrs.as_ptr(), 2, start.as_ptr()), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
        c
    }
}

fn callbacks() -> fmi2CallbackFunctions {
    *rustfmu::testing::silent_callbacks()
}

#[test]
fn counting_allocator_sees_an_allocation() {
    let n = allocations_in(|| {
        std::hint::black_box(vec![1u8; 16]);
    });
    assert_eq!(n, 1, "the counting allocator should see exactly the one Vec, saw {n}");
}

#[test]
fn do_step_set_real_get_real_make_no_heap_allocation() {
    let cb = callbacks();
    let c = swinging_pendulum(&cb);
    let inputs = [vr("M1"), vr("M2")];
    let outputs = ["alpha1", "omega1", "alpha2", "omega2", "energy", "x1", "y1", "x2", "y2"].map(vr);
    let mut values = [0.0; 9];
    let h = 1e-3;
    let mut statuses = Vec::with_capacity(3000);
    let n = allocations_in(|| {
        for k in 0..1000 {
            let t = k as f64 * h;
            let u = [0.01 * (k % 7) as f64, -0.02];
            // SAFETY: c is a live instance; the arrays hold as many elements as passed.
            unsafe {
                statuses.push(fmi2SetReal(c, inputs.as_ptr(), 2, u.as_ptr()));
                statuses.push(fmi2DoStep(c, t, h, fmi2True));
                statuses.push(fmi2GetReal(c, outputs.as_ptr(), outputs.len(), values.as_mut_ptr()));
            }
        }
    });
    assert!(statuses.iter().all(|s| *s == fmi2OK), "a call did not return fmi2OK");
    assert!(
        values[0].abs() > 0.1,
        "the pendulum should have fallen: alpha1 = {}",
        values[0]
    );
    assert_eq!(
        n, 0,
        "1000 x (fmi2SetReal, fmi2DoStep, fmi2GetReal) made {n} heap allocations"
    );
    // SAFETY: c was returned by fmi2Instantiate and is freed once.
    unsafe { fmi2FreeInstance(c) };
}

#[test]
fn changing_a_tunable_tolerance_between_steps_makes_no_heap_allocation() {
    let cb = callbacks();
    let c = swinging_pendulum(&cb);
    let rtol = [Pendulum::start().rtol, 1e-8];
    let vr_rtol = [vr("rtol")];
    let mut status = fmi2OK;
    let n = allocations_in(|| {
        for k in 0..100 {
            // SAFETY: c is a live instance; one value reference, one value.
            unsafe {
                status = status.max(fmi2SetReal(c, vr_rtol.as_ptr(), 1, &rtol[k % 2]));
                status = status.max(fmi2DoStep(c, k as f64 * 1e-3, 1e-3, fmi2True));
            }
        }
    });
    assert_eq!(status, fmi2OK, "a call did not return fmi2OK");
    assert_eq!(
        n, 0,
        "100 x (fmi2SetReal of rtol, fmi2DoStep) made {n} heap allocations"
    );
    // SAFETY: as above.
    unsafe { fmi2FreeInstance(c) };
}

#[test]
fn the_count_sees_inside_fmi2_do_step_when_call_logging_allocates() {
    // With logCalls on, fmi2DoStep formats a message: the count must see it, or the zero above
    // would prove nothing about fmi2DoStep.
    let cb = callbacks();
    let c = swinging_pendulum(&cb);
    let category = [c"logCalls".as_ptr()];
    // SAFETY: c is a live instance; one category name, NUL-terminated.
    let status = unsafe { fmi2SetDebugLogging(c, fmi2True, 1, category.as_ptr()) };
    assert_eq!(status, fmi2OK);
    // SAFETY: as above.
    let n = allocations_in(|| assert_eq!(unsafe { fmi2DoStep(c, 0.0, 1e-3, fmi2True) }, fmi2OK));
    assert!(
        n > 0,
        "fmi2DoStep with logCalls on formats a log message, yet 0 allocations were counted"
    );
    // SAFETY: as above.
    unsafe { fmi2FreeInstance(c) };
}
