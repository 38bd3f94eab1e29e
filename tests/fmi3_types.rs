//! Issue 25: the FMI 3.0 types without a 2.0 counterpart in a model of this test binary
//! (`#[fmu(fmi3_only)]`, exported with `export_fmi3!`): bounds of Int8, UInt64 and Float32
//! refused as the standard says (exact at 2^53 + 1), a Binary longer than its `maxSize`
//! refused, all or nothing over several values, and the messages say what and where.

use common::assert_names;
use rustfmu::__private::abi3::*;
use rustfmu::testing::Log;

use std::ptr::null;

#[macro_use]
mod common;

mod model {
    use rustfmu::prelude::*;

    /// Bounded values of the FMI 3.0 types.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    #[fmu(fmi3_only)]
    pub struct Bounded {
        /// a small count
        #[variable(vr = 1, input, discrete, start = 0, min = -10, max = 10)]
        pub small: i8,
        /// a large count, bounded just above 2^53
        #[variable(vr = 2, input, discrete, start = 0, max = 9007199254740992u64)]
        pub large: u64,
        /// a positive gain
        #[variable(vr = 3, input, continuous, start = 1.0, min > 0.0)]
        pub gain: f32,
        /// a short frame
        #[variable(
            vr = 4,
            input,
            discrete,
            start = b"ab",
            max_size = 4,
            mime_type = "application/x-can"
        )]
        pub frame: Vec<u8>,
        /// the frame's length
        #[variable(vr = 5, output, discrete, depends = [frame])]
        pub length: u16,
    }

    impl Model for Bounded {
        fn calculate(&mut self, _t: f64) {
            self.length = self.frame.len() as u16;
        }
    }

    impl CoSimulation for Bounded {}

    rustfmu::export_fmi3!(Bounded);
}
use model::__rustfmu_fmi3_exports::*;

fmi3_instances!("bounded");

fn last(log: &Log) -> String {
    log.last()
}

#[test]
fn integer_bounds_are_exact_and_refusals_change_nothing() {
    let (c, log) = initialized();
    // SAFETY: for every call, arrays of the lengths passed, a live instance.
    unsafe {
        assert_eq!(fmi3SetInt8(c, &1, 1, &-10, 1), fmi3OK);
        assert_eq!(fmi3SetInt8(c, &1, 1, &11, 1), fmi3Error);
        assert_names(log, "11 for 'small' (vr 1) is outside");
        let mut x = 0i8;
        assert_eq!(fmi3GetInt8(c, &1, 1, &mut x, 1), fmi3OK);
        assert_eq!(x, -10);
        fmi3FreeInstance(c);
    }
    let (c, log) = initialized();
    // SAFETY: for every call, arrays of the lengths passed, a live instance.
    unsafe {
        // 2^53 is the bound; 2^53 + 1 (which an f64 comparison would round onto it) is refused.
        assert_eq!(fmi3SetUInt64(c, &2, 1, &(1u64 << 53), 1), fmi3OK);
        assert_eq!(fmi3SetUInt64(c, &2, 1, &((1u64 << 53) + 1), 1), fmi3Error);
        // The undeclared lower end is the type's own (issue 52: "(-inf, 200]" for a UInt8).
        assert_names(
            log,
            "9007199254740993 for 'large' (vr 2) is outside [0, 9007199254740992]",
        );
        let mut x = 0u64;
        assert_eq!(fmi3GetUInt64(c, &2, 1, &mut x, 1), fmi3OK);
        assert_eq!(x, 1u64 << 53);
        fmi3FreeInstance(c);
    }
    let (c, log) = initialized();
    // SAFETY: for every call, arrays of the lengths passed, a live instance.
    unsafe {
        // all or nothing: a good value, then 0 (the bound is exclusive)
        let vrs = [3u32, 3];
        assert_eq!(fmi3SetFloat32(c, vrs.as_ptr(), 2, [2.0f32, 0.0].as_ptr(), 2), fmi3Error);
        assert!(
            last(log).contains("'gain' (vr 3) is outside (0, inf)") || last(log).contains("'gain' (vr 3) is outside"),
            "{}",
            last(log)
        );
        let mut g = 0f32;
        assert_eq!(fmi3GetFloat32(c, &3, 1, &mut g, 1), fmi3OK);
        assert_eq!(g, 1.0);
        fmi3FreeInstance(c);
    }
}

#[test]
fn a_binary_longer_than_its_max_size_is_refused() {
    let (c, log) = initialized();
    // SAFETY: for every call, arrays of the lengths passed, a live instance.
    unsafe {
        let four = [1u8, 0, 2, 3];
        let five = [1u8, 2, 3, 4, 5];
        let sizes = [4usize];
        assert_eq!(fmi3SetBinary(c, &4, 1, sizes.as_ptr(), &four.as_ptr(), 1), fmi3OK);
        let (mut size, mut p) = (0usize, null::<u8>());
        assert_eq!(fmi3GetBinary(c, &4, 1, &mut size, &mut p, 1), fmi3OK);
        assert_eq!(std::slice::from_raw_parts(p, size), &four);
        let mut n = 0u16;
        assert_eq!(fmi3GetUInt16(c, &5, 1, &mut n, 1), fmi3OK);
        assert_eq!(n, 4);
        assert_eq!(fmi3SetBinary(c, &4, 1, &5, &five.as_ptr(), 1), fmi3Error);
        assert_names(log, "5 bytes for 'frame' (vr 4) exceed its maxSize = 4");
        // NULL with a size is refused; NULL with size 0 is the empty value.
        fmi3FreeInstance(c);
    }
    let (c, log) = initialized();
    // SAFETY: for every call, arrays of the lengths passed, a live instance.
    unsafe {
        assert_eq!(fmi3SetBinary(c, &4, 1, &3, &null(), 1), fmi3Error);
        assert_names(log, "values[0] is NULL with valueSizes[0] = 3");
        fmi3FreeInstance(c);
    }
    let (c, _) = initialized();
    // SAFETY: for every call, arrays of the lengths passed, a live instance.
    unsafe {
        assert_eq!(fmi3SetBinary(c, &4, 1, &0, &null(), 1), fmi3OK);
        let mut n = 9u16;
        assert_eq!(fmi3GetUInt16(c, &5, 1, &mut n, 1), fmi3OK);
        assert_eq!(n, 0);
        fmi3FreeInstance(c);
    }
}

#[test]
fn the_description_has_the_fmi3_attributes() {
    use rustfmu::Variables;
    let d = model::Bounded::DESCRIPTION;
    let frame = d.by_name("frame").unwrap();
    assert_eq!(frame.fmi3.max_size, Some(4));
    assert_eq!(frame.fmi3.mime_type, "application/x-can");
    assert!(frame.fmi3.only);
    // The encoding carries them (decoded as cargo fmu decodes the binary).
    let interfaces = rustfmu::description::Interfaces::BOTH_FMI3;
    let encoded = rustfmu::description::encode_to_vec(&d, interfaces);
    let (decoded, _) = rustfmu::description::decode(&encoded).unwrap();
    assert_eq!(decoded.by_name("frame").unwrap().fmi3, frame.fmi3);
    assert_eq!(
        decoded.by_name("frame").unwrap().start,
        rustfmu::description::Start::Binary(b"ab")
    );
    assert_eq!(
        decoded.by_name("large").unwrap().var_type,
        rustfmu::description::VarType::UInt64
    );
}
