//! The typed description: what the derive writes, how it is encoded into a binary at compile
//! time, and the GUID that follows its content.

use rustfmu::Variables;
use rustfmu::description::{self, Bound, Causality, FmiVersion, Initial, Interfaces, Start, VarType, Variability};
use rustfmu::prelude::*;

/// `Small` and its twin that differs only in the start value of `u` (the GUID test compares them).
macro_rules! small_model {
    ($(#[doc = $doc:tt])* $name:ident, u_start = $u_start:tt) => {
        $(#[doc = $doc])*
        #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
        #[fmu(identifier = "Small", unit(name = "furlong/fortnight", m = 1, s = -1, factor = 1.663e-4))]
        #[fmu(log_category(name = "logSolver", description = "what the solver does"))]
        pub struct $name {
            /// input, with a description
            /// over two lines
            #[variable(vr = 0, input, start = $u_start, unit = "furlong/fortnight")]
            pub u: f64,
            /// output
            #[variable(vr = 1, output, depends = [u])]
            pub y: f64,
            /// a positive gain
            #[variable(vr = 2, parameter, tunable, start = 2.0, min > 0.0, max = 10.0)]
            pub k: f64,
            /// a mode
            #[variable(vr = 3, parameter, start = Mode::Fast)]
            pub mode: Mode,
            /// a label
            #[variable(vr = 4, parameter, start = "hello")]
            pub label: String,
            /// a counter
            #[variable(vr = 5, output, initial = exact, start = 0, min = 0)]
            pub n: i32,
            /// not a variable: internal state
            pub memory: Vec<f64>,
        }
    };
}

small_model!(
    /// A small model.
    Small, u_start = 0.0
);

/// How fast.
#[derive(FmuEnum, Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Mode {
    /// slowly
    Slow = 1,
    /// quickly
    #[fmu(name = "FAST")]
    Fast,
}

/// Field names and FMI names: `depends` may name either; the description holds FMI names.
#[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Renamed {
    /// input
    #[variable(vr = 0, name = "u.in", input)]
    pub u_in: f64,
    /// output
    #[variable(vr = 1, name = "y.out", output, depends = [u_in])]
    pub y_out: f64,
}

#[test]
fn depends_holds_fmi_names_whether_a_field_or_a_name_is_written() {
    assert_eq!(
        Renamed::DESCRIPTION.by_name("y.out").unwrap().depends_on,
        Some(&["u.in"][..])
    );
}

small_model!(
    /// The same model with another start value of `u`.
    SmallOtherStart, u_start = 1.0
);

const CS: Interfaces = Interfaces::CO_SIMULATION;

fn encoded<M: Variables>() -> Vec<u8> {
    description::encode_to_vec(&M::DESCRIPTION, CS)
}

#[test]
fn the_const_encoder_and_the_run_time_one_agree() {
    const D: description::ModelDescription = Small::DESCRIPTION;
    const N: usize = description::encoded_len(&D, CS);
    const BYTES: [u8; N] = description::encode(&D, CS);
    assert_eq!(&BYTES[..], &encoded::<Small>()[..]);
}

#[test]
fn the_derive_describes_every_declaration() {
    let d = Small::DESCRIPTION;
    assert_eq!(d.model_identifier, "Small");
    assert_eq!(d.description, "A small model.");
    assert_eq!(d.variables.len(), 6, "the field without #[variable] is no variable");
    let u = d.by_name("u").unwrap();
    assert_eq!(
        (u.causality, u.variability, u.var_type),
        (Causality::Input, Variability::Continuous, VarType::Real)
    );
    assert_eq!(u.description, "input, with a description over two lines");
    assert_eq!(u.unit, "furlong/fortnight");
    let y = d.by_name("y").unwrap();
    assert_eq!(y.depends_on, Some(&["u"][..]));
    assert_eq!(y.start, Start::None, "a calculated output has no start value");
    let k = d.by_name("k").unwrap();
    assert_eq!(k.variability, Variability::Tunable);
    assert_eq!(
        k.min,
        Some(Bound {
            value: 0.0,
            exclusive: true
        })
    );
    assert_eq!(
        k.max,
        Some(Bound {
            value: 10.0,
            exclusive: false
        })
    );
    let mode = d.by_name("mode").unwrap();
    assert_eq!(
        (mode.var_type, mode.variability, mode.start),
        (VarType::Enumeration, Variability::Fixed, Start::Integer(2))
    );
    let e = mode.enumeration.unwrap();
    assert_eq!((e.name, e.description), ("Mode", "How fast."));
    let items: Vec<_> = e.items.iter().map(|i| (i.name, i.value, i.description)).collect();
    assert_eq!(items, [("Slow", 1, "slowly"), ("FAST", 2, "quickly")]);
    let label = d.by_name("label").unwrap();
    assert_eq!((label.var_type, label.start), (VarType::String, Start::String("hello")));
    let n = d.by_name("n").unwrap();
    assert_eq!(
        (n.var_type, n.variability, n.initial),
        (VarType::Integer, Variability::Discrete, Some(Initial::Exact))
    );
    assert_eq!(d.units.len(), 1);
    assert_eq!(d.units[0].base.factor, 1.663e-4);
    assert_eq!(d.log_categories[0].name, "logSolver");
    assert_eq!(
        d.internal_state, "memory: Vec<f64>",
        "the other fields are part of the FMU state"
    );
    let names: Vec<_> = d.all_log_categories().map(|c| c.name).collect();
    assert_eq!(names.first(), Some(&"logEvents"));
    assert_eq!(names.last(), Some(&"logSolver"));
}

#[test]
fn start_values_get_and_set_follow_the_declarations() {
    let mut m = Small::start();
    assert_eq!(
        (m.u, m.k, m.mode, m.label.as_str(), m.n),
        (0.0, 2.0, Mode::Fast, "hello", 0)
    );
    assert!(m.memory.is_empty());
    assert_eq!(m.get(2), Some(Value::Real(2.0)));
    assert_eq!(
        m.get(3),
        Some(Value::Integer(2)),
        "an Enumeration reads as its item's value"
    );
    assert!(m.set(3, Value::Integer(1)));
    assert_eq!(m.mode, Mode::Slow);
    assert!(!m.set(3, Value::Integer(7)), "no item has value 7");
    assert!(!m.set(2, Value::Integer(1)), "k is a Real");
    assert_eq!(m.get(4), None, "Strings are read with get_string");
    assert_eq!(m.get_string(4), Some("hello"));
    assert!(m.set_string(4, "bye"));
    assert_eq!(m.label, "bye");
    assert_eq!(m.get(99), None);
}

#[test]
fn encoding_round_trips_and_is_found_inside_a_binary() {
    let bytes = encoded::<Small>();
    let (d, interfaces) = description::decode(&bytes).unwrap();
    assert_eq!(d, Small::DESCRIPTION);
    assert_eq!(interfaces, CS);
    let mut binary = vec![0x7f, b'E', b'L', b'F'];
    binary.extend(std::iter::repeat_n(0xAB, 1000));
    binary.extend(&bytes);
    binary.extend(std::iter::repeat_n(0xCD, 1000));
    assert_eq!(description::find_encoded(&binary).unwrap(), &bytes[..]);
}

#[test]
fn a_binary_of_both_versions_carries_one_description_of_each() {
    // What `export_fmu!` embeds: the description marked FMI 2.0 and the one marked 3.0, with
    // MAGIC alone in between (a Windows DLL keeps rustfmu's own copy of the constant).
    let v2 = encoded::<Small>();
    let three = Interfaces {
        version: FmiVersion::V3,
        ..CS
    };
    let v3 = description::encode_to_vec(&Small::DESCRIPTION, three);
    let mut binary = vec![0xAB; 100];
    binary.extend(&v2);
    binary.extend(description::MAGIC);
    binary.extend([0u8; 16]);
    binary.extend(&v3);
    binary.extend([0xCD; 100]);
    let all = description::find_all_encoded(&binary).unwrap();
    assert_eq!(all, [&v2[..], &v3[..]]);
    assert_eq!(description::find_encoded_for(&binary, FmiVersion::V3).unwrap(), &v3[..]);
    assert_eq!(description::find_encoded_for(&binary, FmiVersion::V2).unwrap(), &v2[..]);
    assert_ne!(description::guid_string(&v2), description::guid_string(&v3));
    // One version only (`export_fmi2!` alone): the other is refused with what the library has.
    let e = description::find_encoded_for(&v2, FmiVersion::V3).unwrap_err();
    assert!(
        e.contains("implements FMI 2.0 only") && e.contains("export_fmu!"),
        "{e}"
    );
    // MAGIC with nothing valid after it: the reason, not a description.
    let mut stray = description::MAGIC.to_vec();
    stray.extend([0u8; 16]);
    let e = description::find_all_encoded(&stray).unwrap_err();
    assert!(e.contains("format version 0"), "{e}");
}

#[test]
fn a_damaged_encoding_is_refused_with_a_message() {
    let bytes = encoded::<Small>();
    for cut in [10, 40, bytes.len() - 1] {
        let e = description::decode(&bytes[..cut]).unwrap_err();
        assert!(!e.is_empty());
    }
    let e = description::find_encoded(b"no description here").unwrap_err();
    assert!(e.contains("export_fmi2"), "{e}");
}

#[test]
fn the_guid_follows_the_content() {
    let a = description::guid_string(&encoded::<Small>());
    let b = description::guid_string(&encoded::<SmallOtherStart>());
    assert_ne!(a, b, "another start value must give another GUID");
    assert_eq!(a, description::guid_string(&encoded::<Small>()));
    assert_eq!(a.len(), 38);
    assert_eq!(&a[15..16], "5", "a version-5 (name-based, SHA-1) UUID: {a}");
}

/// A network node of FMI-LS-BUS (`can_network`): its terminal with the nested Configuration
/// terminal goes through the encoding and back, and only the FMI 3.0 encoding carries it.
#[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
#[fmu(
    fmi3_only,
    can_network(
        name = "CAN",
        rx_clock = rx_clock,
        rx_data = rx_data,
        tx_clock = tx_clock,
        tx_data = tx_data,
        bus_notifications = notifications
    )
)]
pub struct Node {
    #[variable(vr = 1, input, clock(triggered))]
    pub rx_clock: Clock,
    #[variable(vr = 2, input, discrete, clocks = [rx_clock], max_size = 64)]
    pub rx_data: Vec<u8>,
    #[variable(vr = 3, output, clock(triggered))]
    pub tx_clock: Clock,
    #[variable(vr = 4, output, discrete, clocks = [tx_clock], max_size = 64, depends = [])]
    pub tx_data: Vec<u8>,
    #[variable(vr = 5, parameter, fixed, start = false)]
    pub notifications: bool,
}
impl Model for Node {}
impl CoSimulation for Node {}

#[test]
fn nested_terminals_round_trip_through_the_fmi3_encoding() {
    let three = Interfaces {
        version: FmiVersion::V3,
        ..CS
    };
    let bytes = description::encode_to_vec(&Node::DESCRIPTION, three);
    let (d, _) = description::decode(&bytes).unwrap();
    assert_eq!(d.terminals, Node::DESCRIPTION.terminals);
    let [bus] = d.terminals else {
        panic!("{:?}", d.terminals)
    };
    assert_eq!(
        (bus.kind, bus.matching_rule),
        ("org.fmi-ls-bus.network-terminal", "org.fmi-ls-bus.transceiver")
    );
    let [config] = bus.terminals else {
        panic!("{:?}", bus.terminals)
    };
    assert_eq!(
        (config.name, config.kind, config.matching_rule),
        ("Configuration", "org.fmi-ls-bus.network-terminal.configuration", "bus")
    );
    assert_eq!(config.members[0].member, "BusNotifications");
    let rx = Node::DESCRIPTION
        .variables
        .iter()
        .find(|v| v.name == "rx_data")
        .unwrap();
    assert_eq!(rx.fmi3.mime_type, rustfmu::ls_bus::CAN_MIME_TYPE);
}
