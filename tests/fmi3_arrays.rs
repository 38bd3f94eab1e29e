//! Issue 25: FMI 3.0 arrays (`[T; N]`, `[[T; M]; N]` fields) of several types, outside the
//! equations, in a model of this test binary exported with `export_fmi3!`: `<Dimension>`s and
//! row-major start values in the description; nValues counted per element; every element
//! checked before any is stored (bounds, all or nothing); the FMU state with arrays.

use common::assert_names;
use rustfmu::__private::abi3::*;
use rustfmu::testing::Log;

#[macro_use]
mod common;

mod model {
    use rustfmu::prelude::*;

    /// Arrays of several types, outside the equations.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    #[fmu(fmi3_only)]
    pub struct Table {
        /// a gain matrix
        #[variable(vr = 1, parameter, tunable, start = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]], min = -10.0, max = 10.0)]
        pub gains: [[f64; 3]; 2],
        /// counts
        #[variable(vr = 2, input, discrete, max = 100)]
        pub counts: [u16; 4],
        /// flags
        #[variable(vr = 3, input, discrete, start = [true, false])]
        pub flags: [bool; 2],
        /// the gains' row sums, times the flags
        #[variable(vr = 4, output, discrete, depends = [flags])]
        pub sums: [f32; 2],
        /// the counts' total
        #[variable(vr = 5, output, discrete, depends = [counts])]
        pub total: i64,
    }

    impl Model for Table {
        fn calculate(&mut self, _t: f64) {
            for (k, row) in self.gains.iter().enumerate() {
                self.sums[k] = if self.flags[k] {
                    row.iter().sum::<f64>() as f32
                } else {
                    0.0
                };
            }
            self.total = self.counts.iter().map(|c| i64::from(*c)).sum();
        }
    }

    impl CoSimulation for Table {}

    rustfmu::export_fmi3!(Table);
}
use model::__rustfmu_fmi3_exports::*;
use model::Table;

#[test]
fn the_description_has_the_dimensions_and_the_starts_row_major() {
    use rustfmu::description::Start;
    let d = <Table as rustfmu::Variables>::DESCRIPTION;
    let g = d.by_name("gains").unwrap();
    assert_eq!(g.fmi3.dimensions, &[2, 3]);
    assert_eq!(g.element_count(), 6);
    let Start::Array(items) = g.start else {
        panic!("{:?}", g.start)
    };
    assert_eq!(items, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0].map(Start::Real));
    let c = d.by_name("counts").unwrap();
    assert_eq!(c.start, Start::Array(&[Start::Int64(0); 4]));
    assert!(d.has_arrays());
}

fmi3_instances!("table");

fn last(log: &Log) -> String {
    log.last()
}

fn gains(c: fmi3Instance) -> [f64; 6] {
    let mut g = [0.0; 6];
    // SAFETY: one value reference, six values.
    assert_eq!(unsafe { fmi3GetFloat64(c, &1, 1, g.as_mut_ptr(), 6) }, fmi3OK);
    g
}

#[test]
fn arrays_are_read_and_written_element_by_element_with_n_values_counting_them() {
    let (c, log) = cs();
    // SAFETY: for every call, arrays of the lengths passed, a live instance.
    unsafe {
        // Start values in Instantiated, row-major.
        assert_eq!(gains(c), [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        // nValues must count every element.
        let mut g = [0.0; 6];
        assert_eq!(fmi3GetFloat64(c, &1, 1, g.as_mut_ptr(), 1), fmi3Error);
        assert_names(log, "nValues = 1, but the 1 value references have 6 values");
        fmi3FreeInstance(c);
    }
    let (c, log) = initialized();
    // SAFETY: for every call, arrays of the lengths passed, a live instance.
    unsafe {
        // Two arrays in one call: counts (4) then flags (2) are different types; counts and
        // gains' neighbours: u16 then the total.
        let counts = [1u16, 2, 3, 94];
        assert_eq!(
            fmi3SetUInt16(c, &2, 1, counts.as_ptr(), 4),
            fmi3OK,
            "{:?}",
            log.messages()
        );
        let mut total = 0i64;
        assert_eq!(fmi3GetInt64(c, &5, 1, &mut total, 1), fmi3OK);
        assert_eq!(total, 100);
        let flags = [false, true];
        assert_eq!(fmi3SetBoolean(c, &3, 1, flags.as_ptr(), 2), fmi3OK);
        let mut sums = [9f32; 2];
        assert_eq!(fmi3GetFloat32(c, &4, 1, sums.as_mut_ptr(), 2), fmi3OK);
        assert_eq!(sums, [0.0, 15.0]);
        // A tunable matrix: all six elements or none; element 4 beyond max is refused.
        let new = [0.5, 0.5, 0.5, 0.5, 11.0, 0.5];
        assert_eq!(fmi3SetFloat64(c, &1, 1, new.as_ptr(), 6), fmi3Error);
        assert!(
            last(log).contains("11 for 'gains' (vr 1) is outside"),
            "{:?}",
            log.messages()
        );
        assert_eq!(gains(c), [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        fmi3FreeInstance(c);
    }
    let (c, _) = initialized();
    // SAFETY: for every call, arrays of the lengths passed, a live instance.
    unsafe {
        let new = [0.5, 1.5, 2.5, -0.5, -1.5, -2.5];
        assert_eq!(fmi3SetFloat64(c, &1, 1, new.as_ptr(), 6), fmi3OK);
        assert_eq!(gains(c), new);
        let mut sums = [9f32; 2];
        assert_eq!(fmi3GetFloat32(c, &4, 1, sums.as_mut_ptr(), 2), fmi3OK);
        assert_eq!(sums, [4.5, 0.0]);
        // The FMU state carries the arrays.
        let mut state: fmi3FMUState = std::ptr::null_mut();
        assert_eq!(fmi3GetFMUState(c, &mut state), fmi3OK);
        let zeros = [0.0; 6];
        assert_eq!(fmi3SetFloat64(c, &1, 1, zeros.as_ptr(), 6), fmi3OK);
        assert_eq!(fmi3SetFMUState(c, state), fmi3OK);
        assert_eq!(gains(c), new);
        assert_eq!(fmi3FreeFMUState(c, &mut state), fmi3OK);
        fmi3FreeInstance(c);
    }
}
