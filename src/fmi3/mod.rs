//! The FMI 3.0 runtime: the C boundary and the exported symbols of FMI 3.0, over the same
//! instance core as FMI 2.0 ([`crate::fmi2::instance`], which runs the FMI 3.0 state machine
//! when instantiated through these functions). Not part of the documented API.

pub mod abi;
pub mod api;
pub mod export;
