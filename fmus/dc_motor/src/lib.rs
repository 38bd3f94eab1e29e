//! The DCMotor FMU: `binaries/linux64/DCMotor.so`.
rustfmu::export_fmi2_cosimulation!(rustfmu::fmus::dc_motor::DcMotor);
