//! fmi2SetReal, fmi2DoStep and fmi2GetReal of the Controller FMU allocate nothing on the heap,
//! now that the model has an array variable (its gain `K`, FMI 3.0 only): a call on scalars
//! keeps the scalar paths. The crate's rlib is linked in, so these are the exported functions.

use controller_fmu::*;
use rustfmu::__private::abi::*;
use rustfmu::testing::allocations_in;
use rustfmu::testing::fmi2::{Instantiation, silent_callbacks};

#[global_allocator]
static ALLOCATOR: rustfmu::testing::CountingAllocator = rustfmu::testing::CountingAllocator;

#[test]
fn set_real_do_step_get_real_make_no_heap_allocation() {
    let c = Instantiation {
        resource_location: Some(c"file:///tmp"),
        ..Instantiation::new(fmi2CoSimulation, c"alloc-test")
    }
    .call_with(
        fmi2Instantiate,
        controller_fmu::__rustfmu_fmi2_exports::GUID,
        silent_callbacks(),
    );
    assert!(!c.is_null());
    // SAFETY: a live instance; arrays of the lengths passed.
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
        let inputs = [0u32, 1, 2, 3];
        let outputs = [10u32, 11, 12, 13];
        let mut values = [0.0; 4];
        let mut statuses = Vec::with_capacity(3000);
        let h = 1e-3;
        let n = allocations_in(|| {
            for k in 0..1000 {
                let x = [0.01 * (k % 5) as f64, 0.0, -0.02, 0.001];
                statuses.push(fmi2SetReal(c, inputs.as_ptr(), 4, x.as_ptr()));
                statuses.push(fmi2DoStep(c, k as f64 * h, h, fmi2True));
                statuses.push(fmi2GetReal(c, outputs.as_ptr(), 4, values.as_mut_ptr()));
            }
        });
        assert!(statuses.iter().all(|s| *s == fmi2OK), "a call did not return fmi2OK");
        assert_ne!(values[0], 0.0, "the controller should act on the tilt");
        assert_eq!(
            n, 0,
            "1000 x (fmi2SetReal, fmi2DoStep, fmi2GetReal) made {n} heap allocations"
        );
        fmi2FreeInstance(c);
    }
}
