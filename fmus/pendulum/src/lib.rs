//! The Pendulum FMU: `binaries/linux64/Pendulum.so`.
rustfmu::export_fmi2_cosimulation!(rustfmu::fmus::pendulum::Pendulum);
