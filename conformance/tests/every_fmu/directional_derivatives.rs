//! Directional derivatives against finite differences, where the FMU provides them, for every
//! packaged FMU (the checks are `fmi_conformance::checks::directional_derivatives`).
//!
//! Thin callers: each test runs its check on every FMU of target/fmu, strictly (a part left
//! untested fails; a skip only where the FMU does not declare providesDirectionalDerivative).

use fmi_conformance::checks::on_every_fmu;

#[test]
fn co_simulation_directional_derivatives_match_finite_differences() {
    on_every_fmu("co_simulation_directional_derivatives_match_finite_differences");
}

#[test]
fn model_exchange_directional_derivatives_match_finite_differences() {
    on_every_fmu("model_exchange_directional_derivatives_match_finite_differences");
}

#[test]
fn directional_derivatives_refuse_unknown_references_and_null_arrays() {
    on_every_fmu("directional_derivatives_refuse_unknown_references_and_null_arrays");
}
