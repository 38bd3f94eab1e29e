// docs/writing-an-fmu.md, "Numbers in the equations": an f64 on the left of a D does not
// compile; `D::from(self.t_high) - t` does (tests/real_arithmetic.rs).
use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct Room {
    /// Room temperature T
    #[variable(vr = 0, name = "T", output, initial = exact, start = 15.0, depends = [T])]
    pub t_room: f64,
    /// dT/dt
    #[variable(vr = 1, name = "der(T)", local, derivative_of = t_room, depends = [T])]
    pub der_t_room: f64,
    /// Set point
    #[variable(vr = 2, parameter, start = 21.0)]
    pub t_high: f64,
}

impl Model for Room {
    fn derivatives<D: Real>(&self, _t: D, v: &mut RoomContinuous<D>) {
        v.der_t_room = self.t_high - v.t_room;
    }
}

impl CoSimulation for Room {}

fn main() {}
