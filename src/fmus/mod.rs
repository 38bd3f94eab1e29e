//! Each FMU's declarations: its variables, and how its model steps. `fmu-build` finds them in
//! [`ALL`]; each is exported by a one-line crate under `fmus/`.

pub mod pendulum;

use crate::fmi2::FmuEntry;

/// Every FMU this project builds.
pub const ALL: &[FmuEntry] = &[FmuEntry::of::<pendulum::Pendulum>("pendulum-fmu", "pendulum_fmu")];
