//! Numerical methods the models step with.

pub mod ode;
