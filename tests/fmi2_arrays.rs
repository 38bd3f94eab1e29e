//! Issue 25: what FMI 2.0 gets of an array. FMI 2.0 has no arrays; the standard's structured
//! naming (FMI 2.0, 2.2.9) lists an array as its elements, scalars named `gains[1,2]` (indices
//! from 1). A `[T; N]` / `[[T; M]; N]` field of an FMI 2.0 type is in both descriptions: one
//! variable with `<Dimension>`s in FMI 3.0, its elements with the value references vr, vr + 1,
//! .. (row-major) in FMI 2.0. Tested through the C API of a model exported here with
//! `export_fmu!` (one binary, both versions).

use rustfmu::__private::abi::*;
use rustfmu::description::{self, FmiVersion, Interfaces, Start, VarType};

use rustfmu::testing::{fmi2, thread_log as log};

mod model {
    use rustfmu::prelude::*;

    /// Arrays of the FMI 2.0 types.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    pub struct Grid {
        /// a gain matrix
        #[variable(vr = 10, parameter, tunable, start = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]], min = -10.0, max = 10.0)]
        pub gains: [[f64; 3]; 2],
        /// counts
        #[variable(vr = 20, input, discrete, start = [1, 2, 3], max = 100)]
        pub counts: [i32; 3],
        /// flags
        #[variable(vr = 30, input, discrete, start = [true, false])]
        pub flags: [bool; 2],
        /// an offset
        #[variable(vr = 40, parameter, tunable, start = 0.5)]
        pub offset: f64,
        /// the gains' row sums plus the offset, where the row's flag is set
        #[variable(vr = 50, output, discrete, depends = [flags], initial_depends = [gains, flags, offset])]
        pub sums: [f64; 2],
        /// the counts' total
        #[variable(vr = 60, output, discrete, depends = [counts], initial_depends = [counts])]
        pub total: i32,
    }

    impl Model for Grid {
        fn calculate(&mut self, _t: f64) {
            for (k, row) in self.gains.iter().enumerate() {
                self.sums[k] = if self.flags[k] {
                    row.iter().sum::<f64>() + self.offset
                } else {
                    0.0
                };
            }
            self.total = self.counts.iter().sum();
        }
    }

    impl CoSimulation for Grid {}

    rustfmu::export_fmu!(Grid);
}
use model::__rustfmu_fmi2_exports::*;
use model::Grid;

const V2: Interfaces = Interfaces {
    co_simulation: true,
    model_exchange: true,
    version: FmiVersion::V2,
    can_interpolate_inputs: false,
    scheduled_execution: false,
};

#[test]
fn the_fmi2_description_lists_each_element_as_a_scalar_of_structured_name() {
    let d = <Grid as rustfmu::Variables>::DESCRIPTION;
    let (two, _) = description::decode(&description::encode_to_vec(&d, V2)).unwrap();
    let names: Vec<(&str, u32)> = two.variables.iter().map(|v| (v.name, v.value_reference)).collect();
    assert_eq!(
        names,
        [
            ("gains[1,1]", 10),
            ("gains[1,2]", 11),
            ("gains[1,3]", 12),
            ("gains[2,1]", 13),
            ("gains[2,2]", 14),
            ("gains[2,3]", 15),
            ("counts[1]", 20),
            ("counts[2]", 21),
            ("counts[3]", 22),
            ("flags[1]", 30),
            ("flags[2]", 31),
            ("offset", 40),
            ("sums[1]", 50),
            ("sums[2]", 51),
            ("total", 60),
        ]
    );
    let g = two.by_name("gains[2,1]").unwrap();
    assert_eq!(g.start, Start::Real(4.0));
    assert!(!g.is_array() && g.var_type == VarType::Real);
    assert_eq!(g.min.map(|b| b.value), Some(-10.0));
    assert_eq!(two.by_name("flags[2]").unwrap().start, Start::Boolean(false));
    assert_eq!(two.by_name("counts[3]").unwrap().start, Start::Integer(3));
    // Dependencies on an array are dependencies on each of its elements.
    assert_eq!(
        two.by_name("sums[2]").unwrap().depends_on,
        Some(&["flags[1]", "flags[2]"][..])
    );
    assert_eq!(
        two.by_name("total").unwrap().initial_depends_on,
        Some(&["counts[1]", "counts[2]", "counts[3]"][..])
    );
    // FMI 3.0 keeps the arrays.
    let three = Interfaces {
        version: FmiVersion::V3,
        ..V2
    };
    let (three, _) = description::decode(&description::encode_to_vec(&d, three)).unwrap();
    assert_eq!(three.by_name("gains").unwrap().fmi3.dimensions, &[2, 3]);
    assert_eq!(three.by_name("sums").unwrap().depends_on, Some(&["flags"][..]));
    assert!(three.by_name("gains[1,1]").is_none());
    // The element names, as the runtime writes them in messages.
    assert_eq!(d.by_name("gains").unwrap().element_name(4), "gains[2,2]");
    assert_eq!(d.fmi2_element(15), Some((0, 5)));
    assert_eq!(d.fmi2_element(16), None);
}

fn instance(name: &std::ffi::CStr) -> fmi2Component {
    fmi2::cs_instance(fmi2Instantiate, GUID, name, log())
}

fn last_error(_instance: &str) -> String {
    log().last()
}

fn reals(c: fmi2Component, vrs: &[u32]) -> Vec<f64> {
    let mut out = vec![f64::NAN; vrs.len()];
    // SAFETY: as many slots as references.
    let status = unsafe { fmi2GetReal(c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) };
    assert_eq!(status, fmi2OK);
    out
}

#[test]
fn the_fmi2_functions_read_and_write_elements_by_their_value_references() {
    let c = instance(c"grid");
    // SAFETY: c is a live instance; each call's arrays have its length.
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        // Elements and scalars in one call, in any order.
        assert_eq!(reals(c, &[15, 40, 10, 13]), [6.0, 0.5, 1.0, 4.0]);
        assert_eq!(fmi2SetReal(c, [11, 40].as_ptr(), 2, [-2.0, 1.0].as_ptr()), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
        assert_eq!(reals(c, &[50, 51]), [1.0 - 2.0 + 3.0 + 1.0, 0.0]);

        let mut counts = [0; 3];
        assert_eq!(fmi2GetInteger(c, [20, 21, 22].as_ptr(), 3, counts.as_mut_ptr()), fmi2OK);
        assert_eq!(counts, [1, 2, 3]);
        assert_eq!(fmi2SetInteger(c, [22].as_ptr(), 1, [30].as_ptr()), fmi2OK);
        assert_eq!(fmi2SetBoolean(c, [31].as_ptr(), 1, [fmi2True].as_ptr()), fmi2OK);
        // The step brings what `calculate` computes up to date (it did not, before this test).
        assert_eq!(fmi2DoStep(c, 0.0, 0.1, fmi2True), fmi2OK);
        let mut total = 0;
        assert_eq!(fmi2GetInteger(c, [60].as_ptr(), 1, &mut total), fmi2OK);
        assert_eq!(total, 1 + 2 + 30);
        assert_eq!(reals(c, &[51]), [4.0 + 5.0 + 6.0 + 1.0]);
        let mut flags = [fmi2False; 2];
        assert_eq!(fmi2GetBoolean(c, [30, 31].as_ptr(), 2, flags.as_mut_ptr()), fmi2OK);
        assert_eq!(flags, [fmi2True, fmi2True]);

        // All or nothing: one element out of its bounds refuses the whole call, named.
        let status = fmi2SetReal(c, [10, 14].as_ptr(), 2, [3.0, 11.0].as_ptr());
        assert_eq!(status, fmi2Error);
        assert!(last_error("grid").contains("gains[2,2]"), "{}", last_error("grid"));
        assert_eq!(reals(c, &[10, 14]), [1.0, 5.0], "nothing stored");
        assert_eq!(fmi2SetInteger(c, [21].as_ptr(), 1, [101].as_ptr()), fmi2Error);
        assert!(last_error("grid").contains("counts[2]"), "{}", last_error("grid"));

        // An element is of its array's type only; a reference past the array is no variable.
        let mut x = 0.0;
        assert_eq!(fmi2GetReal(c, [21].as_ptr(), 1, &mut x), fmi2Error);
        assert!(
            last_error("grid").contains("value reference 21 ('counts[2]') is an Integer variable, not a Real"),
            "{}",
            last_error("grid")
        );
        assert_eq!(fmi2GetReal(c, [16].as_ptr(), 1, &mut x), fmi2Error);
        assert!(
            last_error("grid").contains("value reference 16 is not a Real variable"),
            "{}",
            last_error("grid")
        );

        // The FMU state carries the elements.
        let mut state: fmi2FMUstate = std::ptr::null_mut();
        assert_eq!(fmi2GetFMUstate(c, &mut state), fmi2OK);
        assert_eq!(fmi2SetReal(c, [12].as_ptr(), 1, [9.0].as_ptr()), fmi2OK);
        assert_eq!(fmi2SetFMUstate(c, state), fmi2OK);
        assert_eq!(reals(c, &[12]), [3.0]);
        assert_eq!(fmi2FreeFMUstate(c, &mut state), fmi2OK);
        fmi2FreeInstance(c);
    }
}
