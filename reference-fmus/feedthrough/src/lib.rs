//! The Reference-FMUs' Feedthrough (modelica/Reference-FMUs, `Feedthrough/`, v0.0.41) written
//! with rustfmu: the same model identifier, variable names, types, value references,
//! causalities, variabilities and start values. Every output equals its input, for every
//! variable type of FMI 3.0 (Float32 .. UInt64, Boolean, String, Binary, Enumeration); two
//! Float64 parameters are only stored. (Before v0.0.41 the Reference had a `String_parameter`
//! at value reference 29 and the Binary and Enumeration variables at 30 .. 33; v0.0.41 has
//! `String_input` (29) and `String_output` (30), which moved them to 31 .. 34.)
//!
//! FMI 2.0 gets what FMI 2.0 has, as the Reference-FMUs' own FMI 2.0 Feedthrough: the Float64,
//! Int32, Boolean, String and Enumeration variables. The others (and `time`, which FMI 2.0 does
//! not list) are `fmi3_only`.

use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// The enumeration of `Enumeration_input` and `Enumeration_output` (`Option` in the model
/// description, as theirs).
#[derive(FmuEnum, Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[fmu(name = "Option")]
pub enum Choice {
    /// First option
    #[fmu(name = "Option 1")]
    Option1 = 1,
    /// Second option
    #[fmu(name = "Option 2")]
    Option2 = 2,
}

/// A model to test different variable types
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[allow(non_snake_case)]
pub struct Feedthrough {
    /// Simulation time
    #[variable(vr = 0, independent, fmi3_only)]
    pub time: f64,

    #[variable(vr = 1, input, continuous, start = 0.0, fmi3_only)]
    pub Float32_continuous_input: f32,
    #[variable(vr = 2, output, continuous, depends = [Float32_continuous_input], initial_depends = [Float32_continuous_input], fmi3_only)]
    pub Float32_continuous_output: f32,
    #[variable(vr = 3, input, discrete, start = 0.0, fmi3_only)]
    pub Float32_discrete_input: f32,
    #[variable(vr = 4, output, discrete, depends = [Float32_discrete_input], initial_depends = [Float32_discrete_input], fmi3_only)]
    pub Float32_discrete_output: f32,

    #[variable(vr = 5, parameter, fixed, start = 0.0)]
    pub Float64_fixed_parameter: f64,
    #[variable(vr = 6, parameter, tunable, start = 0.0)]
    pub Float64_tunable_parameter: f64,
    #[variable(vr = 7, input, continuous, start = 0.0)]
    pub Float64_continuous_input: f64,
    #[variable(vr = 8, output, continuous, depends = [Float64_continuous_input], initial_depends = [Float64_continuous_input])]
    pub Float64_continuous_output: f64,
    #[variable(vr = 9, input, discrete, start = 0.0)]
    pub Float64_discrete_input: f64,
    #[variable(vr = 10, output, discrete, depends = [Float64_discrete_input], initial_depends = [Float64_discrete_input])]
    pub Float64_discrete_output: f64,

    #[variable(vr = 11, input, discrete, start = 0, fmi3_only)]
    pub Int8_input: i8,
    #[variable(vr = 12, output, discrete, depends = [Int8_input], initial_depends = [Int8_input], fmi3_only)]
    pub Int8_output: i8,
    #[variable(vr = 13, input, discrete, start = 0, fmi3_only)]
    pub UInt8_input: u8,
    #[variable(vr = 14, output, discrete, depends = [UInt8_input], initial_depends = [UInt8_input], fmi3_only)]
    pub UInt8_output: u8,
    #[variable(vr = 15, input, discrete, start = 0, fmi3_only)]
    pub Int16_input: i16,
    #[variable(vr = 16, output, discrete, depends = [Int16_input], initial_depends = [Int16_input], fmi3_only)]
    pub Int16_output: i16,
    #[variable(vr = 17, input, discrete, start = 0, fmi3_only)]
    pub UInt16_input: u16,
    #[variable(vr = 18, output, discrete, depends = [UInt16_input], initial_depends = [UInt16_input], fmi3_only)]
    pub UInt16_output: u16,
    #[variable(vr = 19, input, discrete, start = 0)]
    pub Int32_input: i32,
    #[variable(vr = 20, output, discrete, depends = [Int32_input], initial_depends = [Int32_input])]
    pub Int32_output: i32,
    #[variable(vr = 21, input, discrete, start = 0, fmi3_only)]
    pub UInt32_input: u32,
    #[variable(vr = 22, output, discrete, depends = [UInt32_input], initial_depends = [UInt32_input], fmi3_only)]
    pub UInt32_output: u32,
    #[variable(vr = 23, input, discrete, start = 0, fmi3_only)]
    pub Int64_input: i64,
    #[variable(vr = 24, output, discrete, depends = [Int64_input], initial_depends = [Int64_input], fmi3_only)]
    pub Int64_output: i64,
    #[variable(vr = 25, input, discrete, start = 0, fmi3_only)]
    pub UInt64_input: u64,
    #[variable(vr = 26, output, discrete, depends = [UInt64_input], initial_depends = [UInt64_input], fmi3_only)]
    pub UInt64_output: u64,

    #[variable(vr = 27, input, discrete, start = false)]
    pub Boolean_input: bool,
    #[variable(vr = 28, output, discrete, depends = [Boolean_input], initial_depends = [Boolean_input])]
    pub Boolean_output: bool,

    #[variable(vr = 29, input, discrete, start = "Set me!")]
    pub String_input: String,
    #[variable(vr = 30, output, discrete, depends = [String_input], initial_depends = [String_input])]
    pub String_output: String,

    #[variable(vr = 31, input, discrete, start = b"foo", fmi3_only)]
    pub Binary_input: Vec<u8>,
    #[variable(vr = 32, output, discrete, depends = [Binary_input], initial_depends = [Binary_input], fmi3_only)]
    pub Binary_output: Vec<u8>,

    #[variable(vr = 33, input, discrete, start = Choice::Option1)]
    pub Enumeration_input: Choice,
    #[variable(vr = 34, output, discrete, depends = [Enumeration_input], initial_depends = [Enumeration_input])]
    pub Enumeration_output: Choice,
}

impl Model for Feedthrough {
    /// Every output is its input, whenever the outputs are asked for.
    fn calculate(&mut self, _t: f64) {
        self.Float32_continuous_output = self.Float32_continuous_input;
        self.Float32_discrete_output = self.Float32_discrete_input;
        self.Float64_discrete_output = self.Float64_discrete_input;
        self.Int8_output = self.Int8_input;
        self.UInt8_output = self.UInt8_input;
        self.Int16_output = self.Int16_input;
        self.UInt16_output = self.UInt16_input;
        self.Int32_output = self.Int32_input;
        self.UInt32_output = self.UInt32_input;
        self.Int64_output = self.Int64_input;
        self.UInt64_output = self.UInt64_input;
        self.Boolean_output = self.Boolean_input;
        self.String_output.clone_from(&self.String_input);
        self.Binary_output.clone_from(&self.Binary_input);
        self.Enumeration_output = self.Enumeration_input;
    }

    /// The continuous Float64 output, through the equations (so its directional derivative
    /// with respect to the input is exact: 1).
    fn outputs<D: Real>(&self, _t: D, v: &mut FeedthroughContinuous<D>) {
        v.Float64_continuous_output = v.Float64_continuous_input;
    }
}

impl CoSimulation for Feedthrough {}

rustfmu::export_fmu!(Feedthrough);
