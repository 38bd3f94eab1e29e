//! The FMI 2.0 runtime, generic over the model: not part of the documented API.
//!
//! Layers, with arrows pointing one way: a model ([`crate::Model`], declared with
//! `#[derive(Model)]`) knows nothing of FMI; [`instance`] runs the standard's state machine
//! around it; [`api`] is the C boundary; [`export`](crate::export_fmi2) puts the symbols in an
//! FMU crate.

pub mod abi;
pub mod api;
pub mod export;
pub mod instance;
pub mod logging;
pub mod resources;
pub mod snapshots;
pub mod state;
