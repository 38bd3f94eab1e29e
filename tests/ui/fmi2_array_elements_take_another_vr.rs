use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// FMI 2.0 lists the array as gains[1,1] .. gains[2,2] with the value references 1 .. 4
    #[variable(vr = 1, parameter, fixed, start = [[1.0, 2.0], [3.0, 4.0]])]
    pub gains: [[f64; 2]; 2],
    /// ... so 3 is taken
    #[variable(vr = 3, parameter, fixed, start = 0.0)]
    pub offset: f64,
}

fn main() {}
