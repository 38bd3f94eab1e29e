//! Configuration Mode (FMI 3.0, 3.2/4.2): where structural parameters are set, and what the
//! instance does when they change. What their values mean for the arrays and the state vector
//! (lengths, the integrator's mask) is the step's: `crate::step::structural`.

use super::instance::Instance;
use super::machine::State;
use super::{OK, Status};
use crate::description::{Causality, Variability, Variable};
use crate::model::CoSimulation;
use crate::value::Value;

// The lengths as the C layers ask for them.
pub use crate::step::structural::{count_of, number_of_states};

impl<M: CoSimulation> Instance<M> {
    /// fmi3EnterConfigurationMode: from Instantiated into Configuration Mode (fixed and tunable
    /// structural parameters may be set), from Step Mode (co-simulation) or Event Mode (model
    /// exchange) into Reconfiguration Mode (tunable ones). The state check ran.
    pub fn enter_configuration_mode(&mut self, function: &str) -> Status {
        let next = match self.sim.state {
            State::Instantiated => State::ConfigurationMode,
            State::StepComplete if !self.model_exchange => State::ReconfigurationMode,
            State::EventMode if self.model_exchange => State::ReconfigurationMode,
            state => {
                return self.error(&format!(
                    "{function}: not in state {} of {}: Reconfiguration Mode is entered from Step Mode in \
                     co-simulation and from Event Mode in model exchange",
                    self.terms.state_name(state),
                    if self.model_exchange {
                        "model exchange"
                    } else {
                        "co-simulation"
                    }
                ));
            }
        };
        self.reconfigured_from = self.sim.state;
        self.sim.state = next;
        OK
    }

    /// fmi3ExitConfigurationMode: back to the state Configuration Mode was entered from. After a
    /// reconfiguration the model's `parameters_changed` sees the new sizes (it may refuse them:
    /// then the parameters are as before and the call fails), the integrator restarts, and the
    /// derivatives and outputs are computed anew.
    pub fn exit_configuration_mode(&mut self, function: &str) -> Status {
        let state = self.sim.state;
        self.sim.state = self.reconfigured_from;
        self.sim.stale_derivatives = true;
        self.sim.stale_outputs = true;
        if state == State::ReconfigurationMode {
            let status = self.reconfigured(function);
            if status != OK {
                return status;
            }
        }
        OK
    }

    fn reconfigured(&mut self, function: &str) -> Status {
        let Some(before) = self.before_configuration.take() else {
            return OK;
        };
        let (sim, ctx) = self.sim_and_context();
        let outcome = sim.model.parameters_changed(&ctx).and_then(|()| {
            crate::step::oversized_binary(&sim.model).map_or(Ok(()), |what| Err(format!("it left {what}")))
        });
        if let Err(why) = outcome {
            self.sim.model = *before;
            return self.error(&format!(
                "{function}: the new structural parameters were refused: {why}; they are as before"
            ));
        }
        self.sim.solver.restart();
        OK
    }

    /// Whether `decl` may be set in Configuration or Reconfiguration Mode: a structural parameter
    /// (in Reconfiguration Mode a tunable one). Only those.
    pub(crate) fn settable_in_configuration(&self, decl: &Variable) -> bool {
        decl.causality == Causality::StructuralParameter
            && match self.sim.state {
                State::ConfigurationMode => true,
                State::ReconfigurationMode => decl.variability == Variability::Tunable,
                _ => false,
            }
    }

    /// Before a structural parameter is set: its value fits every array it sizes.
    pub(crate) fn check_structural(&self, function: &str, decl: &Variable, value: Value) -> Result<(), Status> {
        if decl.causality != Causality::StructuralParameter {
            return Ok(());
        }
        let Value::UInt64(n) = value else { return Ok(()) };
        for v in M::DESCRIPTION.variables {
            for (s, cap) in v.fmi3.sized_by.iter().zip(v.fmi3.dimensions) {
                if *s == decl.value_reference && n > *cap as u64 {
                    return Err(self.error(&format!(
                        "{function}: {n} for '{}' (vr {}) is more than the {cap} elements '{}' holds along that \
                         dimension; refused, value unchanged",
                        decl.name, decl.value_reference, v.name
                    )));
                }
            }
        }
        Ok(())
    }

    /// Keeps the model as it is before the first structural parameter of a reconfiguration is
    /// set (for `parameters_changed` to refuse the new sizes).
    pub(crate) fn keep_before_configuration(&mut self) {
        if self.sim.state == State::ReconfigurationMode && self.before_configuration.is_none() {
            self.before_configuration = Some(Box::new(self.sim.model.clone()));
        }
    }
}
