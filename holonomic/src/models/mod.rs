//! Physics and control, as the paper writes them. Plain Rust: no FMI, no unsafe.

pub mod can_messages;
pub mod controller;
pub mod dc_motor;
pub mod pendulum;
