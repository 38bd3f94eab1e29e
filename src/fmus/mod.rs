//! Each FMU's declarations: its variables, and how its model steps. `fmu-build` finds them in
//! [`ALL`]; each is exported by a one-line crate under `fmus/`.

pub mod controller;
pub mod dc_motor;
pub mod pendulum;

use crate::fmi2::FmuEntry;

/// Every FMU this project builds.
pub const ALL: &[FmuEntry] = &[
    FmuEntry::of::<pendulum::Pendulum>("pendulum-fmu", "pendulum_fmu"),
    FmuEntry::of::<controller::Controller>("controller-fmu", "controller_fmu"),
    FmuEntry::of::<dc_motor::DcMotor>("dc-motor-fmu", "dc_motor_fmu"),
];
