//! Numerical methods the models step with, and the linear-systems tools the controller is
//! designed with.

pub mod lqr;
pub mod lti;
pub mod wide;
