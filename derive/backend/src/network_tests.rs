//! `#[fmu(can_network(..))]`: the terminal it writes, the MIME type it gives, and each rule of
//! FMI-LS-BUS 1.0.0 it enforces as one error naming the rule.

use crate::tests::{error, generated};

/// A CAN network node; `change` rewrites one piece of it.
fn node(change: &[(&str, &str)]) -> String {
    let mut src = r#"
#[fmu(fmi3_only, can_network(name = "Powertrain", rx_clock = rx_clock, rx_data = rx_data, tx_clock = tx_clock,
      tx_data = tx_data, bus_notifications = notifications))]
struct Node {
    #[variable(vr = 1002, name = "Powertrain.Rx_Clock", input, clock(triggered))]
    rx_clock: Clock,
    #[variable(vr = 1001, name = "Powertrain.Rx_Data", input, discrete, clocks = [rx_clock], max_size = 64)]
    rx_data: Vec<u8>,
    #[variable(vr = 1004, name = "Powertrain.Tx_Clock", input, clock(countdown))]
    tx_clock: Clock,
    #[variable(vr = 1003, name = "Powertrain.Tx_Data", output, discrete, clocks = [tx_clock], max_size = 64)]
    tx_data: Vec<u8>,
    #[variable(vr = 1005, name = "BusNotifications", parameter, fixed, start = false)]
    notifications: bool,
}
"#
    .to_string();
    for (from, to) in change {
        assert!(src.contains(from), "{from}");
        src = src.replacen(from, to, 1);
    }
    src
}

#[test]
fn a_can_network_writes_the_bus_terminal_its_configuration_terminal_and_the_mime_types() {
    let code = generated(&node(&[]));
    for piece in [
        r#"name : "Powertrain" , kind : "org.fmi-ls-bus.network-terminal" , matching_rule : "org.fmi-ls-bus.transceiver""#,
        r#"variable : "Powertrain.Rx_Clock" , member : "Rx_Clock" , kind : "signal""#,
        r#"variable : "Powertrain.Tx_Data" , member : "Tx_Data" , kind : "signal""#,
        r#"name : "Configuration" , kind : "org.fmi-ls-bus.network-terminal.configuration" , matching_rule : "bus""#,
        r#"variable : "BusNotifications" , member : "BusNotifications""#,
        r#"mime_type : "application/org.fmi-standard.fmi-ls-bus.can; version=\"1.0.0\"""#,
    ] {
        assert!(code.contains(piece), "{piece}\nnot in\n{code}");
    }
    assert_eq!(
        code.matches("fmi-ls-bus.can; version").count(),
        2,
        "both data variables"
    );
    // Without bus_notifications: no Configuration terminal ("Empty Configuration Terminals can be omitted").
    let bare = generated(&node(&[(", bus_notifications = notifications", "")]));
    assert!(!bare.contains("Configuration"));
}

#[test]
fn an_output_triggered_tx_clock_is_legal_too() {
    let code = generated(&node(&[
        (
            r#"name = "Powertrain.Tx_Clock", input, clock(countdown)"#,
            r#"name = "Powertrain.Tx_Clock", output, clock(triggered)"#,
        ),
        (
            "clocks = [tx_clock], max_size = 64",
            "clocks = [tx_clock], max_size = 64, depends = []",
        ),
    ]));
    // Tx_Data depends on nothing: an output clock is no known (FMI 3.0, 2.4.8: "the dependencies
    // of clocked variables on their input Clocks").
    assert!(code.contains(r#"name : "Powertrain.Tx_Data""#), "{code}");
    assert!(
        !code.contains(r#"depends : Some (& ["Powertrain.Tx_Clock"])"#),
        "{code}"
    );
}

#[test]
fn each_rule_of_the_layered_standard_is_one_error_that_names_it() {
    let cases: [(&[(&str, &str)], &str); 10] = [
        (
            &[("input, clock(triggered)", "input, clock(countdown)")],
            "\"The input Clocks (Rx_Clock) shall be triggered Clocks\"",
        ),
        (
            &[("input, clock(countdown)", "input, clock(triggered)")],
            "must be an input time-based clock",
        ),
        (
            &[("Rx_Data\", input, discrete", "Rx_Data\", output, discrete")],
            "must be `input, discrete`",
        ),
        (
            &[("clocks = [rx_clock], max_size = 64", "max_size = 64")],
            "must be clocked by 'Powertrain.Rx_Clock'",
        ),
        (
            &[(
                "clocks = [tx_clock], max_size = 64)]",
                "clocks = [tx_clock], max_size = 64, mime_type = \"application/octet-stream\")]",
            )],
            "leave mime_type out",
        ),
        (
            &[("start = false", "start = true")],
            "\"The default value of this parameter shall be false\"",
        ),
        (&[("fmi3_only, ", "")], "FMI-LS-BUS is a layered standard of FMI 3.0"),
        (
            &[("tx_data = tx_data", "tx_data = nothing")],
            "tx_data 'nothing' is no variable of the model",
        ),
        (&[("rx_clock = rx_clock, ", "")], "needs `rx_clock = field`"),
        (&[("name = \"Powertrain\", ", "")], "needs `name = \"...\"`"),
    ];
    for (change, words) in cases {
        let e = error(&node(change)).to_string();
        assert!(e.contains(words), "{change:?}: {e}");
    }
}

#[test]
fn a_variable_in_two_bus_terminals_is_refused() {
    let src = node(&[(
        "bus_notifications = notifications))]",
        "bus_notifications = notifications), can_network(name = \"Body\", rx_clock = rx_clock, rx_data = rx_data, \
         tx_clock = tx_clock, tx_data = tx_data))]",
    )]);
    let e = error(&src).to_string();
    assert!(
        e.contains("The use of the same variable within different Bus Terminals is not allowed"),
        "{e}"
    );
}

#[test]
fn terminals_nest_in_terminals() {
    let src = r#"
#[fmu(fmi3_only, terminal(name = "outer", kind = "k", member(variable = a), terminal(name = "inner", matching_rule = "bus", member(variable = b))))]
struct M {
    #[variable(vr = 1, input)]
    a: f64,
    #[variable(vr = 2, input)]
    b: f64,
}
"#;
    let code = generated(src);
    assert!(
        code.contains(r#"terminals : & [:: rustfmu :: description :: Terminal { name : "inner""#)
            || code.contains(r#"name : "inner""#),
        "{code}"
    );
    let e = error(&src.replace("member(variable = b)", "member(variable = c)")).to_string();
    assert!(
        e.contains("terminal 'inner': member variable 'c' is no variable of the model"),
        "{e}"
    );
}

#[test]
fn a_bus_simulation_announces_its_notifications_as_the_standard_says() {
    let bus = |notifications: &str| {
        node(&[
            ("#[fmu(fmi3_only, ", "#[fmu(fmi3_only, bus_simulation, "),
            (
                r#"name = "BusNotifications", parameter, fixed, start = false"#,
                notifications,
            ),
        ])
    };
    let code = generated(&bus(r#"name = "BusNotifications", output, constant, start = true"#));
    assert!(code.contains("bus_simulation : true"), "{code}");
    generated(&bus(r#"name = "BusNotifications", calculated_parameter, fixed"#));
    let e = error(&bus(r#"name = "BusNotifications", parameter, fixed, start = false"#)).to_string();
    assert!(
        e.contains("of a bus simulation must be a bool `calculated_parameter, fixed` or `output, constant`"),
        "{e}"
    );
    assert!(generated(&node(&[])).contains("bus_simulation : false"));
    let lonely = "#[fmu(fmi3_only, bus_simulation)]\nstruct B {\n#[variable(vr = 1, input)]\nu: f64,\n}\n";
    let e = error(lonely).to_string();
    assert!(
        e.contains("a bus simulation FMU has a can_network(..) for each network FMU"),
        "{e}"
    );
}
