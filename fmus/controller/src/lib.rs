//! The Controller FMU: `binaries/linux64/Controller.so`.
rustfmu::export_fmi2_cosimulation!(rustfmu::fmus::controller::Controller);
