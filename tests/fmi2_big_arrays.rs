//! Issue 52, item 3, FMI 2.0: arrays of more than 32 elements along a dimension (serde derives up
//! to 32; the FMU state serializes the model) in a model exported for both versions with
//! `export_fmu!`: a 100-element weight vector, a 2 × 40 matrix, 40 integer inputs and an
//! internal (undeclared) buffer of 64. FMI 2.0 sees their elements with the value references
//! vr .. vr + n - 1; the FMU state, serialized and deserialized, carries every element.

use rustfmu::__private::abi::*;

use rustfmu::testing::{fmi2, thread_log as log};

mod model {
    use rustfmu::prelude::*;

    /// y = u (sum of w + sum of g), total = sum of counts.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    pub struct Mixer {
        /// input
        #[variable(vr = 1, input, start = 1.0)]
        pub u: f64,
        /// output
        #[variable(vr = 2, output, depends = [u], initial_depends = [u, w, g])]
        pub y: f64,
        /// the sum of the counts
        #[variable(vr = 3, output, discrete, depends = [counts], initial_depends = [counts])]
        pub total: i32,
        /// weights
        #[variable(vr = 100, parameter, tunable, start = [0.01; 100])]
        #[serde(with = "rustfmu::BigArray")]
        pub w: [f64; 100],
        /// a matrix whose rows are longer than 32
        #[variable(vr = 200, parameter, tunable)]
        #[serde(with = "rustfmu::BigMatrix")]
        pub g: [[f64; 40]; 2],
        /// counts
        #[variable(vr = 300, input, discrete)]
        #[serde(with = "rustfmu::BigArray")]
        pub counts: [i32; 40],
        /// the last 64 inputs seen at a step's end (internal state)
        #[serde(with = "rustfmu::BigArray")]
        pub history: [f64; 64],
    }

    impl Model for Mixer {
        fn outputs<D: Real>(&self, _t: D, v: &mut MixerContinuous<D>) {
            let sum: f64 = self.w.iter().chain(self.g.iter().flatten()).sum();
            v.y = v.u * sum;
        }
        fn calculate(&mut self, _t: f64) {
            self.total = self.counts.iter().sum();
        }
    }

    impl CoSimulation for Mixer {
        fn do_step(&mut self, t: f64, h: f64, ctx: &mut Context) -> Result<(), StepFailure> {
            self.history.rotate_right(1);
            self.history[0] = self.u;
            ctx.integrate(self, t, h)
        }
    }

    rustfmu::export_fmu!(Mixer);
}
use model::__rustfmu_fmi2_exports::*;

fn last() -> String {
    log().last()
}

fn reals(c: fmi2Component, vrs: &[u32]) -> Vec<f64> {
    let mut out = vec![f64::NAN; vrs.len()];
    // SAFETY: as many slots as references.
    let status = unsafe { fmi2GetReal(c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) };
    assert_eq!(status, fmi2OK, "{}", last());
    out
}

fn set_reals(c: fmi2Component, vrs: &[u32], values: &[f64]) {
    assert_eq!(vrs.len(), values.len());
    // SAFETY: as many values as references.
    let status = unsafe { fmi2SetReal(c, vrs.as_ptr(), vrs.len(), values.as_ptr()) };
    assert_eq!(status, fmi2OK, "{}", last());
}

#[test]
fn the_elements_of_long_arrays_are_fmi2_scalars_and_the_state_carries_them() {
    let c = fmi2::cs_instance(fmi2Instantiate, GUID, c"mixer", log());
    let w: Vec<u32> = (100..200).collect();
    let g: Vec<u32> = (200..280).collect();
    let counts: Vec<u32> = (300..340).collect();
    // SAFETY: for every call, a live instance, arrays of the lengths passed.
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(reals(c, &w), vec![0.01; 100]);
        let g_values: Vec<f64> = (0..80).map(|k| k as f64).collect();
        set_reals(c, &g, &g_values);
        let ones = [1; 40];
        assert_eq!(fmi2SetInteger(c, counts.as_ptr(), 40, ones.as_ptr()), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK, "{}", last());
        // y = u (100 × 0.01 + 0 + 1 + .. + 79)
        let sum = 1.0 + 79.0 * 80.0 / 2.0;
        assert!((reals(c, &[2])[0] - sum).abs() < 1e-9, "{}", reals(c, &[2])[0]);
        let mut total = 0;
        assert_eq!(fmi2GetInteger(c, &3, 1, &mut total), fmi2OK);
        assert_eq!(total, 40);

        for (k, u) in [2.0, 3.0].into_iter().enumerate() {
            set_reals(c, &[1], &[u]);
            assert_eq!(fmi2DoStep(c, 0.1 * k as f64, 0.1, fmi2True), fmi2OK, "{}", last());
        }
        let mut state: fmi2FMUstate = std::ptr::null_mut();
        assert_eq!(fmi2GetFMUstate(c, &mut state), fmi2OK, "{}", last());
        let mut size = 0usize;
        assert_eq!(fmi2SerializedFMUstateSize(c, state, &mut size), fmi2OK);
        let mut bytes = vec![0u8; size];
        assert_eq!(fmi2SerializeFMUstate(c, state, bytes.as_mut_ptr().cast(), size), fmi2OK);
        assert_eq!(fmi2FreeFMUstate(c, &mut state), fmi2OK);

        // Change every array, then restore the deserialized state.
        set_reals(c, &[199, 279], &[5.0, -5.0]);
        assert_eq!(fmi2SetInteger(c, &339, 1, &7), fmi2OK);
        set_reals(c, &[1], &[4.0]);
        assert_eq!(fmi2DoStep(c, 0.2, 0.1, fmi2True), fmi2OK, "{}", last());
        let mut restored: fmi2FMUstate = std::ptr::null_mut();
        assert_eq!(
            fmi2DeSerializeFMUstate(c, bytes.as_ptr().cast(), size, &mut restored),
            fmi2OK,
            "{}",
            last()
        );
        assert_eq!(fmi2SetFMUstate(c, restored), fmi2OK, "{}", last());
        assert_eq!(fmi2FreeFMUstate(c, &mut restored), fmi2OK);
        assert_eq!(reals(c, &w), vec![0.01; 100]);
        assert_eq!(reals(c, &g), g_values);
        let mut last_count = 0;
        assert_eq!(fmi2GetInteger(c, &339, 1, &mut last_count), fmi2OK);
        assert_eq!(last_count, 1);
        assert!((reals(c, &[2])[0] - 3.0 * sum).abs() < 1e-9);
        fmi2FreeInstance(c);
    }
}

#[test]
fn the_internal_buffer_of_64_is_part_of_the_state() {
    use rustfmu::Variables;
    let mut m = model::Mixer::start();
    m.history[63] = 42.0;
    m.history[0] = -1.0;
    let bytes = postcard::to_allocvec(&m).unwrap();
    let back: model::Mixer = postcard::from_bytes(&bytes).unwrap();
    assert_eq!(back.history, m.history);
    assert_eq!(back.g, m.g);
}
