//! The writers of `modelDescription.xml`: bounds, the FMI 3.0 schema order, value references,
//! arrays sized by structural parameters.

use super::*;
use rustfmu::description::{Causality, Initial, NOT_SIZED, Start, VarType, Variability, Variable};

const fn var(name: &'static str, vr: u32, min: Option<Bound>, max: Option<Bound>) -> Variable {
    Variable {
        start: Start::Integer(5),
        min,
        max,
        ..v3(name, vr, VarType::Integer, Causality::Parameter, Variability::Fixed)
    }
}

const VARS: &[Variable] = &[
    var(
        "inclusive",
        0,
        Some(Bound {
            value: 1.0,
            exclusive: false,
        }),
        Some(Bound {
            value: 9.0,
            exclusive: false,
        }),
    ),
    var(
        "exclusive",
        1,
        Some(Bound {
            value: 0.0,
            exclusive: true,
        }),
        Some(Bound {
            value: 10.0,
            exclusive: true,
        }),
    ),
];

/// Nothing but the integer bounds of `VARS`; the alias tests start from it too.
pub(super) const D: ModelDescription = ModelDescription {
    model_identifier: "Bounds",
    description: "",
    author: "",
    version: "0",
    copyright: "",
    license: "",
    generation_tool: "test",
    default_experiment: None,
    units: &[],
    log_categories: &[],
    variables: VARS,
    internal_state: "",
    event_indicators: &[],
    terminals: &[],
    bus_simulation: false,
};

#[test]
fn integer_bounds_are_written_as_the_integers_inside_the_range() {
    let xml = fmi2(&D, Interfaces::CO_SIMULATION, "{guid}").unwrap();
    assert!(xml.contains(r#"<Integer min="1" max="9" start="5"/>"#), "{xml}");
    // > 0 and < 10: 1 ..= 9 (not 0 and 10, which the runtime refuses).
    let exclusive = xml.split("name=\"exclusive\"").nth(1).unwrap();
    assert!(
        exclusive.contains(r#"<Integer min="1" max="9" start="5"/>"#),
        "{exclusive}"
    );
}

#[test]
fn an_exclusive_real_bound_is_written_as_the_nearest_legal_value() {
    assert_eq!(
        bound_value(
            Bound {
                value: 0.0,
                exclusive: true
            },
            true
        ),
        5e-324
    );
    assert_eq!(
        bound_value(
            Bound {
                value: 1.0,
                exclusive: true
            },
            false
        ),
        1.0f64.next_down()
    );
    assert_eq!(
        bound_value(
            Bound {
                value: 1.0,
                exclusive: false
            },
            false
        ),
        1.0
    );
}

// ---- FMI 3.0 ------------------------------------------------------------------------

use rustfmu::description::{BaseUnit, DefaultExperiment, EnumItem, EnumType, Unit};

/// A base unit of no dimension, factor 1 and no offset: the tests' units are this with their
/// exponents set.
pub(super) const NO_DIMENSION: BaseUnit = BaseUnit {
    kg: 0,
    m: 0,
    s: 0,
    a: 0,
    k: 0,
    mol: 0,
    cd: 0,
    rad: 0,
    factor: 1.0,
    offset: 0.0,
};

const MODE: EnumType = EnumType {
    name: "Mode",
    description: "How it runs",
    items: &[
        EnumItem {
            name: "off",
            value: 0,
            description: "Off",
        },
        EnumItem {
            name: "on",
            value: 1,
            description: "",
        },
    ],
};

/// A variable with nothing but its name, value reference, type, causality and variability (the
/// tests' variables are this with what they need changed).
pub(super) const fn v3(
    name: &'static str,
    vr: u32,
    var_type: VarType,
    causality: Causality,
    variability: Variability,
) -> Variable {
    Variable {
        name,
        value_reference: vr,
        var_type,
        causality,
        variability,
        initial: None,
        start: Start::None,
        unit: "",
        display_unit: "",
        aliases: &[],
        description: "",
        min: None,
        max: None,
        nominal: None,
        depends_on: None,
        initial_depends_on: None,
        derivative_of: None,
        enumeration: None,
        fmi3: rustfmu::description::Fmi3Extras::NONE,
    }
}

const LAG_VARS: &[Variable] = &[
    Variable {
        start: Start::Real(0.5),
        unit: "s",
        description: "Input u",
        ..v3("u", 0, VarType::Real, Causality::Input, Variability::Continuous)
    },
    Variable {
        initial: Some(Initial::Exact),
        start: Start::Real(1.0),
        nominal: Some(2.0),
        depends_on: Some(&["y"]),
        initial_depends_on: None,
        ..v3("y", 7, VarType::Real, Causality::Output, Variability::Continuous)
    },
    Variable {
        depends_on: Some(&["y", "u"]),
        initial_depends_on: None,
        derivative_of: Some("y"),
        ..v3("der(y)", 3, VarType::Real, Causality::Local, Variability::Continuous)
    },
    Variable {
        depends_on: Some(&[]),
        initial_depends_on: None,
        ..v3("z", 9, VarType::Real, Causality::Output, Variability::Continuous)
    },
    Variable {
        start: Start::String("a <b> & \"c\""),
        ..v3("label", 4, VarType::String, Causality::Parameter, Variability::Fixed)
    },
    Variable {
        start: Start::Boolean(true),
        ..v3("flag", 5, VarType::Boolean, Causality::Parameter, Variability::Tunable)
    },
    Variable {
        start: Start::Integer(1),
        enumeration: Some(&MODE),
        ..v3(
            "mode",
            6,
            VarType::Enumeration,
            Causality::Parameter,
            Variability::Fixed,
        )
    },
    Variable {
        start: Start::Integer(3),
        min: Some(Bound {
            value: 0.0,
            exclusive: true,
        }),
        max: Some(Bound {
            value: 10.0,
            exclusive: false,
        }),
        ..v3("n", 2, VarType::Integer, Causality::Parameter, Variability::Fixed)
    },
    v3(
        "k",
        8,
        VarType::Real,
        Causality::CalculatedParameter,
        Variability::Fixed,
    ),
];

const LAG: ModelDescription = ModelDescription {
    model_identifier: "Lag",
    description: "A lag",
    author: "me",
    version: "1.0",
    copyright: "",
    license: "MIT",
    generation_tool: "test",
    default_experiment: Some(DefaultExperiment {
        start_time: Some(0.0),
        stop_time: Some(1.0),
        tolerance: None,
        step_size: Some(0.01),
    }),
    units: &[Unit {
        name: "s",
        base: BaseUnit { s: 1, ..NO_DIMENSION },
        display_units: &[],
    }],
    log_categories: &[],
    variables: LAG_VARS,
    internal_state: "",
    event_indicators: &[],
    terminals: &[],
    bus_simulation: false,
};

fn lag3() -> String {
    fmi3(&LAG, Interfaces::BOTH_FMI3, "{token}").unwrap()
}

/// The text of the element that has `name="<name>"`.
fn element<'a>(xml: &'a str, name: &str) -> &'a str {
    let at = xml
        .find(&format!("name=\"{name}\""))
        .unwrap_or_else(|| panic!("no {name} in {xml}"));
    let start = xml[..at].rfind('<').unwrap();
    let end = at + xml[at..].find("/>").unwrap() + 2;
    &xml[start..end]
}

#[test]
fn fmi3_root_interfaces_and_the_order_of_the_schema() {
    let xml = lag3();
    assert!(xml.starts_with("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<fmiModelDescription fmiVersion=\"3.0\" modelName=\"Lag\" instantiationToken=\"{token}\" description=\"A lag\" author=\"me\" version=\"1.0\" license=\"MIT\" generationTool=\"test\" variableNamingConvention=\"structured\">"), "{xml}");
    assert!(
        !xml.contains("guid=") && !xml.contains("numberOfEventIndicators"),
        "{xml}"
    );
    assert!(xml.contains(r#"<ModelExchange modelIdentifier="Lag" canGetAndSetFMUState="true" canSerializeFMUState="true" providesDirectionalDerivatives="true" providesAdjointDerivatives="true"/>"#), "{xml}");
    assert!(xml.contains(r#"<CoSimulation modelIdentifier="Lag" canHandleVariableCommunicationStepSize="true" canGetAndSetFMUState="true" canSerializeFMUState="true" providesDirectionalDerivatives="true" providesAdjointDerivatives="true" maxOutputDerivativeOrder="1" providesIntermediateUpdate="true" mightReturnEarlyFromDoStep="true" canReturnEarlyAfterIntermediateUpdate="true" hasEventMode="true"/>"#), "{xml}");
    let order = [
        "<ModelExchange ",
        "<CoSimulation ",
        "<UnitDefinitions>",
        "<TypeDefinitions>",
        "<LogCategories>",
        "<DefaultExperiment ",
        "<ModelVariables>",
        "<ModelStructure>",
    ];
    let at: Vec<usize> = order
        .iter()
        .map(|e| xml.find(e).unwrap_or_else(|| panic!("no {e}")))
        .collect();
    assert!(at.windows(2).all(|w| w[0] < w[1]), "{xml}");
    assert!(xml.contains("Messages that come with fmi3Error"), "{xml}");
    assert!(!xml.contains("fmi2"), "{xml}");
    assert!(
        xml.contains(r#"<DefaultExperiment startTime="0.0" stopTime="1.0" stepSize="0.01"/>"#),
        "{xml}"
    );
}

#[test]
fn fmi3_variables_time_first_derivative_by_value_reference_string_start_child() {
    let xml = lag3();
    let vars = &xml[xml.find("<ModelVariables>").unwrap()..xml.find("</ModelVariables>").unwrap()];
    // time: one above the highest declared value reference (9), listed first.
    let first = vars.lines().nth(1).unwrap().trim();
    assert_eq!(
        first,
        r#"<Float64 name="time" valueReference="10" description="Simulation time" causality="independent" variability="continuous"/>"#
    );
    assert_eq!(
        element(vars, "u"),
        r#"<Float64 name="u" valueReference="0" description="Input u" causality="input" variability="continuous" unit="s" start="0.5"/>"#
    );
    assert_eq!(
        element(vars, "y"),
        r#"<Float64 name="y" valueReference="7" causality="output" variability="continuous" initial="exact" nominal="2.0" start="1.0"/>"#
    );
    // derivative names the state's value reference (7), not its index.
    assert_eq!(
        element(vars, "der(y)"),
        r#"<Float64 name="der(y)" valueReference="3" causality="local" variability="continuous" derivative="7"/>"#
    );
    assert!(
        vars.contains("<String name=\"label\" valueReference=\"4\" causality=\"parameter\" variability=\"fixed\">\n      <Start value=\"a &lt;b&gt; &amp; &quot;c&quot;\"/>\n    </String>"),
        "{vars}"
    );
    assert_eq!(
        element(vars, "flag"),
        r#"<Boolean name="flag" valueReference="5" causality="parameter" variability="tunable" start="true"/>"#
    );
    assert_eq!(
        element(vars, "mode"),
        r#"<Enumeration name="mode" valueReference="6" causality="parameter" variability="fixed" declaredType="Mode" start="1"/>"#
    );
    // > 0 and <= 10: 1 ..= 10, as integers.
    assert_eq!(
        element(vars, "n"),
        r#"<Int32 name="n" valueReference="2" causality="parameter" variability="fixed" min="1" max="10" start="3"/>"#
    );
    assert_eq!(
        element(vars, "k"),
        r#"<Float64 name="k" valueReference="8" causality="calculatedParameter" variability="fixed"/>"#
    );
    assert!(xml.contains("<TypeDefinitions>\n    <EnumerationType name=\"Mode\" description=\"How it runs\">\n      <Item name=\"off\" value=\"0\" description=\"Off\"/>\n      <Item name=\"on\" value=\"1\"/>\n    </EnumerationType>\n  </TypeDefinitions>"), "{xml}");
}

#[test]
fn fmi3_model_structure_by_value_reference() {
    let xml = lag3();
    let ms = &xml[xml.find("<ModelStructure>").unwrap()..];
    let expected = r#"<ModelStructure>
    <Output valueReference="7" dependencies="7" dependenciesKind="dependent"/>
    <Output valueReference="9" dependencies="" dependenciesKind=""/>
    <ContinuousStateDerivative valueReference="3" dependencies="0 7" dependenciesKind="dependent dependent"/>
    <InitialUnknown valueReference="3"/>
    <InitialUnknown valueReference="9"/>
    <InitialUnknown valueReference="8"/>
  </ModelStructure>
</fmiModelDescription>
"#;
    assert_eq!(ms, expected);
}

#[test]
fn a_declared_independent_variable_replaces_time() {
    const VARS: &[Variable] = &[
        v3("t", 0, VarType::Real, Causality::Independent, Variability::Continuous),
        Variable {
            start: Start::Real(1.0),
            ..v3("p", 1, VarType::Real, Causality::Parameter, Variability::Fixed)
        },
    ];
    let d = ModelDescription { variables: VARS, ..LAG };
    let xml = fmi3(&d, Interfaces::BOTH_FMI3, "{token}").unwrap();
    assert!(!xml.contains("name=\"time\""), "{xml}");
    assert!(
        xml.contains(r#"<Float64 name="t" valueReference="0" causality="independent" variability="continuous"/>"#),
        "{xml}"
    );
    assert!(xml.contains("variableNamingConvention=\"flat\""), "{xml}");
}

// ---- arrays sized by structural parameters (FMI 3.0) ---------------------------------

/// A UInt64 structural parameter of start `start`, at most 3.
const fn size(name: &'static str, vr: u32, start: u64) -> Variable {
    Variable {
        start: Start::UInt64(start),
        min: Some(Bound {
            value: 0.0,
            exclusive: false,
        }),
        max: Some(Bound {
            value: 3.0,
            exclusive: false,
        }),
        ..v3(
            name,
            vr,
            VarType::UInt64,
            Causality::StructuralParameter,
            Variability::Tunable,
        )
    }
}

/// 1 ..= 12, the start of a capacity of 3 x 4 (row-major: row i holds 4i+1 ..= 4i+4).
const TWELVE: &[Start] = &{
    let mut starts = [Start::Real(0.0); 12];
    let mut i = 0;
    while i < 12 {
        starts[i] = Start::Real((i + 1) as f64);
        i += 1;
    }
    starts
};

/// A parameter array of capacity `dims` sized by `sized_by`, start [`TWELVE`]'s first.
const fn sized(name: &'static str, vr: u32, dims: &'static [u32], sized_by: &'static [u32]) -> Variable {
    Variable {
        start: Start::Array(TWELVE),
        fmi3: rustfmu::description::Fmi3Extras {
            only: true,
            dimensions: dims,
            sized_by,
            ..rustfmu::description::Fmi3Extras::NONE
        },
        ..v3(name, vr, VarType::Real, Causality::Parameter, Variability::Tunable)
    }
}

const SIZED_VARS: &[Variable] = &[
    size("m", 1, 2),
    size("n", 2, 3),
    // [m, n] of capacity [3, 4]: the first 2 rows, the first 3 columns of each.
    sized("A", 3, &[3, 4], &[1, 2]),
    // [n, 4] of capacity [3, 4]: the first 3 rows, all 4 columns.
    sized("B", 4, &[3, 4], &[2, NOT_SIZED]),
    // [m] of capacity 3 (the start: TWELVE's first 3).
    Variable {
        start: Start::Array(TWELVE.split_at(3).0),
        ..sized("u", 5, &[3], &[1])
    },
    // An output: no start.
    Variable {
        start: Start::None,
        causality: Causality::Output,
        variability: Variability::Continuous,
        ..sized("y", 6, &[3], &[2])
    },
];

fn sized3(vars: &'static [Variable]) -> Result<String, String> {
    let d = ModelDescription { variables: vars, ..LAG };
    fmi3(&d, Interfaces::BOTH_FMI3, "{token}")
}

/// The text of the array element that has `name="<name>"`, up to its end tag.
fn array_element<'a>(xml: &'a str, name: &str) -> &'a str {
    let at = xml
        .find(&format!("name=\"{name}\""))
        .unwrap_or_else(|| panic!("no {name} in {xml}"));
    let start = xml[..at].rfind('<').unwrap();
    let end = at + xml[at..].find("</Float64>").unwrap() + "</Float64>".len();
    &xml[start..end]
}

#[test]
fn a_sized_array_names_its_structural_parameters_and_starts_at_their_start_sizes() {
    let xml = sized3(SIZED_VARS).unwrap();
    assert_eq!(
        element(&xml, "m"),
        r#"<UInt64 name="m" valueReference="1" causality="structuralParameter" variability="tunable" min="0" max="3" start="2"/>"#
    );
    // 2 x 3 of the 3 x 4 storage, row-major: (0,0..3), (1,0..3).
    assert_eq!(
        array_element(&xml, "A"),
        "<Float64 name=\"A\" valueReference=\"3\" causality=\"parameter\" variability=\"tunable\" start=\"1.0 2.0 3.0 5.0 6.0 7.0\">\n      \
         <Dimension valueReference=\"1\"/>\n      <Dimension valueReference=\"2\"/>\n    </Float64>"
    );
    // A fixed length beside a sized one: <Dimension start>.
    assert_eq!(
        array_element(&xml, "B"),
        "<Float64 name=\"B\" valueReference=\"4\" causality=\"parameter\" variability=\"tunable\" \
         start=\"1.0 2.0 3.0 4.0 5.0 6.0 7.0 8.0 9.0 10.0 11.0 12.0\">\n      \
         <Dimension valueReference=\"2\"/>\n      <Dimension start=\"4\"/>\n    </Float64>"
    );
    assert!(array_element(&xml, "u").contains(r#"start="1.0 2.0">"#), "{xml}");
    assert!(!array_element(&xml, "y").contains("start="), "{xml}");
    // What validation reads back: every length set by a UInt64 structural parameter, and as
    // many start values as elements at the start lengths.
    let d = md_reader::fmi3::ModelDescription::parse(&xml).unwrap();
    assert_eq!(crate::validate::array_problems(&d), Vec::<String>::new());
}

#[test]
fn a_sized_array_needs_a_uint64_structural_parameter_within_its_capacity() {
    // Sized by a parameter that is no structural parameter.
    const NOT_STRUCTURAL: &[Variable] = &[
        Variable {
            causality: Causality::Parameter,
            ..size("m", 1, 2)
        },
        sized("A", 3, &[3, 4], &[1, NOT_SIZED]),
    ];
    let e = sized3(NOT_STRUCTURAL).unwrap_err();
    assert!(
        e.contains("'m' (vr 1), which is not a UInt64 structural parameter"),
        "{e}"
    );
    // A max beyond the capacity (3 rows).
    const BEYOND: &[Variable] = &[
        Variable {
            max: Some(Bound {
                value: 4.0,
                exclusive: false,
            }),
            ..size("m", 1, 2)
        },
        sized("A", 3, &[3, 4], &[1, NOT_SIZED]),
    ];
    let e = sized3(BEYOND).unwrap_err();
    assert!(e.contains("capacity 3 with max 4"), "{e}");
    // Start values for other than the capacity.
    const SHORT: &[Variable] = &[
        size("m", 1, 2),
        Variable {
            start: Start::Array(TWELVE.split_at(6).0),
            ..sized("A", 3, &[3, 4], &[1, NOT_SIZED])
        },
    ];
    let e = sized3(SHORT).unwrap_err();
    assert!(e.contains("6 start values for a capacity of 12 elements"), "{e}");
    // FMI 2.0 has no structural parameters.
    let d = ModelDescription {
        variables: SIZED_VARS,
        ..LAG
    };
    let e = fmi2(&d, Interfaces::BOTH, "{guid}").unwrap_err();
    assert!(e.contains("FMI 3.0's only"), "{e}");
}

#[test]
fn each_writer_takes_only_a_binary_of_its_version() {
    let e = fmi3(&LAG, Interfaces::BOTH, "{guid}").unwrap_err();
    assert!(e.contains("FMI 2.0, not 3.0"), "{e}");
    let e = fmi2(&LAG, Interfaces::BOTH_FMI3, "{guid}").unwrap_err();
    assert!(e.contains("FMI 3.0, not 2.0"), "{e}");
    // The same description in FMI 2.0: indices, no time.
    let xml2 = fmi2(&LAG, Interfaces::BOTH, "{guid}").unwrap();
    assert!(
        xml2.contains("derivative=\"2\"") && !xml2.contains("name=\"time\""),
        "{xml2}"
    );
    assert!(xml2.contains("Messages that come with fmi2Error"), "{xml2}");
}
