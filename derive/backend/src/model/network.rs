//! `#[fmu(can_network(..))]`: an FMI-LS-BUS 1.0.0 CAN network terminal (Low Cut) on a model
//! struct. The declaration names the four variables a Bus Terminal is made of; the derive writes
//! the terminal the layered standard prescribes (kind, matching rule, member names, the nested
//! Configuration terminal), gives the two Binary variables the standard's CAN MIME type, and
//! refuses, at the variable, every declaration the standard's "Variables" and "Terminal
//! Definitions" sections do not allow.

use super::decl::{Kind, Var, by_name};
use super::grammar::name_or_ident;
use super::model_attr::{ModelAttr, NetworkAttr, TerminalAttr};
use fmi_standard::{Causality, Variability};
use proc_macro2::Span;
use syn::meta::ParseNestedMeta;
use syn::spanned::Spanned;
use syn::{Error, LitStr, Result};

/// FMI-LS-BUS 1.0.0, "MIME Types": the Tx/Rx data variables of a CAN network (CAN, CAN FD, CAN
/// XL). The same string is `rustfmu_ls_bus::CAN_MIME_TYPE`.
pub(crate) const CAN_MIME_TYPE: &str = "application/org.fmi-standard.fmi-ls-bus.can; version=\"1.0.0\"";
/// "Bus Terminal": `terminalKind` and `matchingRule` of a network terminal.
pub(crate) const NETWORK_KIND: &str = "org.fmi-ls-bus.network-terminal";
const NETWORK_RULE: &str = "org.fmi-ls-bus.transceiver";
/// "Configuration Terminal": its name, kind and matching rule.
const CONFIGURATION_KIND: &str = "org.fmi-ls-bus.network-terminal.configuration";

/// `can_network(name = "..", rx_clock = .., rx_data = .., tx_clock = .., tx_data = ..,
/// bus_notifications = .., description = "..")`: the network and its terminal.
pub(crate) fn can_network(m: &mut ModelAttr, meta: &ParseNestedMeta) -> Result<()> {
    let span = meta.path.span();
    let (mut name, mut description) = (None, String::new());
    let mut roles: [Option<(String, Span)>; 5] = Default::default();
    const ROLES: [&str; 5] = ["rx_clock", "rx_data", "tx_clock", "tx_data", "bus_notifications"];
    meta.parse_nested_meta(|c| {
        if c.path.is_ident("name") {
            name = Some(c.value()?.parse::<LitStr>()?.value());
        } else if c.path.is_ident("description") {
            description = c.value()?.parse::<LitStr>()?.value();
        } else if let Some(i) = ROLES.iter().position(|r| c.path.is_ident(r)) {
            if roles[i].is_some() {
                return Err(c.error(format!("`{}` is given twice", ROLES[i])));
            }
            roles[i] = Some(name_or_ident(c.value()?)?);
        } else {
            return Err(c.error(
                "a can_network has `name`, `rx_clock`, `rx_data`, `tx_clock`, `tx_data`, `bus_notifications` \
                 (optional) and `description`",
            ));
        }
        Ok(())
    })?;
    let name = name.ok_or_else(|| {
        Error::new(
            span,
            "a can_network needs `name = \"...\"` (the network's name, e.g. \"Powertrain\")",
        )
    })?;
    let [rx_clock, rx_data, tx_clock, tx_data, bus_notifications] = roles;
    let need = |role: Option<(String, Span)>, key: &str| {
        role.ok_or_else(|| {
            Error::new(
                span,
                format!(
                    "can_network '{name}' needs `{key} = field`: FMI-LS-BUS 1.0.0 (Bus Terminal) makes Rx_Clock, \
                     Rx_Data, Tx_Clock and Tx_Data members of every network terminal"
                ),
            )
        })
    };
    let network = NetworkAttr {
        span,
        rx_clock: need(rx_clock, "rx_clock")?,
        rx_data: need(rx_data, "rx_data")?,
        tx_clock: need(tx_clock, "tx_clock")?,
        tx_data: need(tx_data, "tx_data")?,
        bus_notifications,
        name: name.clone(),
    };
    if m.terminals.iter().any(|t| t.name == name) {
        return Err(Error::new(span, format!("terminal '{name}' is declared twice")));
    }
    let signal = |(v, s): &(String, Span), member: &str| (v.clone(), member.to_string(), "signal".to_string(), *s);
    let configuration = network.bus_notifications.as_ref().map(|b| TerminalAttr {
        name: "Configuration".into(),
        kind: CONFIGURATION_KIND.into(),
        matching_rule: "bus".into(),
        description: String::new(),
        members: vec![signal(b, "BusNotifications")],
        terminals: Vec::new(),
    });
    m.terminals.push(TerminalAttr {
        name,
        kind: NETWORK_KIND.into(),
        matching_rule: NETWORK_RULE.into(),
        description,
        members: vec![
            signal(&network.rx_clock, "Rx_Clock"),
            signal(&network.rx_data, "Rx_Data"),
            signal(&network.tx_clock, "Tx_Clock"),
            signal(&network.tx_data, "Tx_Data"),
        ],
        terminals: configuration.into_iter().collect(),
    });
    m.networks.push(network);
    Ok(())
}

/// Gives the data variables of every network the CAN MIME type (where they declare none; one
/// that declares another is refused by [`check`]).
pub(crate) fn apply_mime_types(model: &ModelAttr, vars: &mut [Var]) {
    for n in &model.networks {
        for (role, _) in [&n.rx_data, &n.tx_data] {
            let at = vars
                .iter()
                .position(|v| v.name == *role)
                .or_else(|| vars.iter().position(|v| v.field == role));
            if let Some(v) = at.map(|i| &mut vars[i])
                && v.kind == Kind::Binary
                && v.mime_type.is_none()
            {
                v.mime_type = Some(LitStr::new(CAN_MIME_TYPE, v.span));
            }
        }
    }
}

/// The layered standard's rules on each network's variables (FMI-LS-BUS 1.0.0, "Variables",
/// "Rx Clocks", "Tx Clocks", "MIME Types", "Bus Terminal", "Bus Notification Parameter").
pub(crate) fn check(vars: &[Var], model: &ModelAttr) -> Result<()> {
    let mut used: Vec<(&str, &str)> = Vec::new();
    for n in &model.networks {
        let net = &n.name;
        let get = |(role, span): &(String, Span), key: &str| -> Result<&Var> {
            by_name(vars, role).ok_or_else(|| {
                Error::new(
                    *span,
                    format!("can_network '{net}': {key} '{role}' is no variable of the model"),
                )
            })
        };
        let bad = |v: &Var, key: &str, rule: &str| {
            Err(Error::new(
                v.span,
                format!("can_network '{net}': {key} '{}' {rule}", v.name),
            ))
        };
        let rx_clock = get(&n.rx_clock, "rx_clock")?;
        let rx_data = get(&n.rx_data, "rx_data")?;
        let tx_clock = get(&n.tx_clock, "tx_clock")?;
        let tx_data = get(&n.tx_data, "tx_data")?;
        let interval = |v: &Var| v.clock.as_ref().map(|c| c.variability.0.clone()).unwrap_or_default();
        if rx_clock.kind != Kind::Clock || rx_clock.causality != Causality::Input || interval(rx_clock) != "triggered" {
            return bad(
                rx_clock,
                "rx_clock",
                "must be an input clock(triggered): \"The input Clocks (Rx_Clock) shall be triggered Clocks\" \
                 (FMI-LS-BUS 1.0.0, Rx Clocks)",
            );
        }
        for (data, key, causality, clock) in [
            (rx_data, "rx_data", Causality::Input, rx_clock),
            (tx_data, "tx_data", Causality::Output, tx_clock),
        ] {
            if data.kind != Kind::Binary {
                return bad(
                    data,
                    key,
                    "must be a Binary variable (Vec<u8>): the bus operations travel in fmi3Binary",
                );
            }
            if data.causality != causality || data.variability != Variability::Discrete {
                return bad(
                    data,
                    key,
                    &format!(
                        "must be `{}, discrete` (FMI-LS-BUS 1.0.0, Variables: Rx_Data is an input, Tx_Data an output)",
                        if causality == Causality::Input {
                            "input"
                        } else {
                            "output"
                        }
                    ),
                );
            }
            if !data.clocks.iter().any(|(c, _)| clock.is_named(c)) {
                return bad(
                    data,
                    key,
                    &format!(
                        "must be clocked by '{}': `clocks = [{}]` (FMI-LS-BUS 1.0.0, Variables)",
                        clock.name, clock.field
                    ),
                );
            }
            if let Some(m) = &data.mime_type
                && m.value() != CAN_MIME_TYPE
            {
                return Err(Error::new(
                    m.span(),
                    format!(
                        "can_network '{net}': {key} '{}' has mimeType \"{}\"; a CAN network's data variables have \
                         {CAN_MIME_TYPE:?} (FMI-LS-BUS 1.0.0, MIME Types): leave mime_type out and the derive writes it",
                        data.name,
                        m.value()
                    ),
                ));
            }
        }
        let tx = interval(tx_clock);
        let time_based = tx_clock.causality == Causality::Input
            && matches!(tx.as_str(), "constant" | "fixed" | "tunable" | "changing" | "countdown");
        let triggered_output = tx_clock.causality == Causality::Output && tx == "triggered";
        if tx_clock.kind != Kind::Clock || !(time_based || triggered_output) {
            return bad(
                tx_clock,
                "tx_clock",
                "must be an input time-based clock (constant, fixed, tunable, changing or countdown) or an output \
                 clock(triggered) (FMI-LS-BUS 1.0.0, Tx Clocks)",
            );
        }
        if let Some(b) = &n.bus_notifications {
            let v = get(b, "bus_notifications")?;
            if model.bus_simulation.is_some() {
                // A bus simulation "shall indicate ... whether it provides bus notifications":
                // "causality = calculatedParameter and variability = fixed; or causality = output
                // and variability = constant" (FMI-LS-BUS 1.0.0, Bus Notification Parameter).
                let ok = v.kind == Kind::Boolean
                    && matches!(
                        (v.causality, v.variability),
                        (Causality::CalculatedParameter, Variability::Fixed)
                            | (Causality::Output, Variability::Constant)
                    );
                if !ok {
                    return bad(
                        v,
                        "bus_notifications",
                        "of a bus simulation must be a bool `calculated_parameter, fixed` or `output, constant` \
                         (FMI-LS-BUS 1.0.0, Bus Notification Parameter)",
                    );
                }
            } else {
                let start_false =
                    matches!(&v.start, Some(syn::Expr::Lit(syn::ExprLit { lit: syn::Lit::Bool(b), .. })) if !b.value);
                if v.kind != Kind::Boolean || v.causality != Causality::Parameter || !start_false {
                    return bad(
                        v,
                        "bus_notifications",
                        "must be a bool parameter with `start = false`: \"The default value of this parameter shall be \
                         false\" (FMI-LS-BUS 1.0.0, Bus Notification Parameter)",
                    );
                }
            }
        }
        // "The use of the same variable within different Bus Terminals is not allowed."
        for v in [rx_clock, rx_data, tx_clock, tx_data] {
            if let Some((_, other)) = used.iter().find(|(name, _)| *name == v.name) {
                return Err(Error::new(
                    n.span,
                    format!(
                        "can_network '{net}': '{}' is a member of network '{other}' too; \"The use of the same variable \
                         within different Bus Terminals is not allowed\" (FMI-LS-BUS 1.0.0, Bus Terminal)",
                        v.name
                    ),
                ));
            }
            used.push((&v.name, net));
        }
        if model.fmi3_only.is_none() {
            return Err(Error::new(
                n.span,
                format!(
                    "can_network '{net}': FMI-LS-BUS is a layered standard of FMI 3.0 (clocks, Binary variables): \
                     the model is #[fmu(fmi3_only)] (rustfmu::export_fmi3!)"
                ),
            ));
        }
    }
    if let Some(span) = model.bus_simulation
        && model.networks.is_empty()
    {
        return Err(Error::new(
            span,
            "bus_simulation: a bus simulation FMU has a can_network(..) for each network FMU it connects",
        ));
    }
    Ok(())
}
