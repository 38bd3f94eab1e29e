//! What `#[fmu(...)]` on the model struct says, as the rest of the derive reads it: the model's
//! attribute, its terminals and its FMI-LS-BUS networks. Parsed by [`super::fmu_attr`] (and
//! [`super::network`] for `can_network(..)`), which both write these types and neither imports the
//! other's.

use crate::units::{self, Base};
use proc_macro2::Span;
use syn::LitStr;

/// `#[fmu(...)]` on the struct.
#[derive(Default)]
pub(crate) struct ModelAttr {
    pub identifier: Option<LitStr>,
    pub description: Option<String>,
    /// `co_simulation_only` / `model_exchange_only`: (model exchange, co-simulation) offered.
    pub interfaces: Option<(bool, bool, Span)>,
    /// `fmi3_only`: the model has no FMI 2.0 export.
    pub fmi3_only: Option<Span>,
    /// `scheduled_execution`: the FMU offers FMI 3.0 Scheduled Execution too.
    pub scheduled_execution: Option<Span>,
    pub units: Vec<(String, Base, Span)>,
    /// `display_unit(unit = .., name = .., factor = .., offset = .., inverse)`: (unit, name,
    /// conversion, span).
    pub display_units: Vec<(String, String, units::Display, Span)>,
    pub categories: Vec<(String, String, Span)>,
    pub terminals: Vec<TerminalAttr>,
    /// `bus_simulation`: an FMI-LS-BUS bus simulation FMU (its networks' rules are a bus
    /// simulation's; the manifest says so).
    pub bus_simulation: Option<Span>,
    /// `can_network(..)`: FMI-LS-BUS CAN networks (each also one of `terminals`).
    pub networks: Vec<NetworkAttr>,
}

/// `terminal(name = .., kind = .., matching_rule = .., description = .., member(..), ..)`.
pub(crate) struct TerminalAttr {
    pub name: String,
    pub kind: String,
    pub matching_rule: String,
    pub description: String,
    /// (variable, memberName, variableKind, span of the variable)
    pub members: Vec<(String, String, String, Span)>,
    /// Nested `terminal(..)`s.
    pub terminals: Vec<TerminalAttr>,
}

/// One `can_network(..)`: the variables of its roles, by field or FMI name, with their spans.
pub(crate) struct NetworkAttr {
    pub name: String,
    pub span: Span,
    pub rx_clock: (String, Span),
    pub rx_data: (String, Span),
    pub tx_clock: (String, Span),
    pub tx_data: (String, Span),
    pub bus_notifications: Option<(String, Span)>,
}
