//! Display units and aliases through the encoding (as `cargo fmu` reads them from a library) into
//! both files.

use super::*;
use rustfmu::description::{
    Alias, BaseUnit, Causality, DisplayUnit, Initial, Start, Unit, VarType, Variability, Variable, decode,
    encode_to_vec,
};

const M: BaseUnit = BaseUnit {
    m: 1,
    ..super::tests::NO_DIMENSION
};

const fn real(name: &'static str, vr: u32, causality: Causality, variability: Variability) -> Variable {
    Variable {
        unit: "m",
        ..super::tests::v3(name, vr, VarType::Real, causality, variability)
    }
}

const VARS: &[Variable] = &[
    Variable {
        initial: Some(Initial::Exact),
        start: Start::Real(1.0),
        description: "Position of the ball",
        aliases: &[Alias {
            name: "h_ft",
            description: "Position in feet",
            display_unit: "ft",
        }],
        ..real("h", 1, Causality::Output, Variability::Continuous)
    },
    Variable {
        start: Start::Real(2.5),
        display_unit: "ft",
        description: "Length",
        aliases: &[Alias {
            name: "l2",
            description: "",
            display_unit: "",
        }],
        ..real("l", 2, Causality::Local, Variability::Constant)
    },
];

const BALL: ModelDescription = ModelDescription {
    model_identifier: "Ball",
    version: "",
    units: &[Unit {
        name: "m",
        base: M,
        display_units: &[DisplayUnit {
            name: "ft",
            factor: 3.280839895,
            offset: 0.0,
            inverse: false,
        }],
    }],
    variables: VARS,
    ..super::tests::D
};

/// The description as `cargo fmu` gets it from a library of that version.
fn decoded(interfaces: Interfaces) -> (ModelDescription, Interfaces) {
    decode(&encode_to_vec(&BALL, interfaces)).unwrap()
}

#[test]
fn the_encoding_carries_display_units_and_aliases() {
    for interfaces in [Interfaces::BOTH, Interfaces::BOTH_FMI3] {
        let (d, back) = decoded(interfaces);
        assert_eq!(back, interfaces);
        assert_eq!(d.units, BALL.units);
        assert_eq!(d.variables, BALL.variables);
    }
    // Without display units and aliases, no trace of them: the encodings (and GUIDs) of the
    // models that declare none are those before they existed.
    const PLAIN_VARS: [Variable; 2] = [
        Variable {
            aliases: &[],
            ..VARS[0]
        },
        Variable {
            display_unit: "",
            aliases: &[],
            ..VARS[1]
        },
    ];
    const PLAIN_UNITS: [Unit; 1] = [Unit {
        display_units: &[],
        ..BALL.units[0]
    }];
    let plain = ModelDescription {
        units: &PLAIN_UNITS,
        variables: &PLAIN_VARS,
        ..BALL
    };
    let with = encode_to_vec(&BALL, Interfaces::BOTH);
    let without = encode_to_vec(&plain, Interfaces::BOTH);
    // The header (magic, format, payload length: 32 bytes) aside, the same bytes up to the
    // display units' block.
    assert!(with.len() > without.len());
    assert_eq!(
        &with[32..without.len()],
        &without[32..],
        "the encoding before the display units' block"
    );
}

/// Each of `parts` in the written `xml` (shown when one is missing).
fn assert_writes(xml: &str, parts: &[&str]) {
    for part in parts {
        assert!(xml.contains(part), "expected {part:?} in:\n{xml}");
    }
}

#[test]
fn fmi3_writes_the_display_unit_the_alias_and_the_variables_display_unit() {
    let (d, i) = decoded(Interfaces::BOTH_FMI3);
    let xml = fmi3(&d, i, "{token}").unwrap();
    assert_writes(
        &xml,
        &[
            "<Unit name=\"m\">\n      <BaseUnit m=\"1\"/>\n      <DisplayUnit name=\"ft\" factor=\"3.280839895\"/>\n    </Unit>",
            "initial=\"exact\" unit=\"m\" start=\"1.0\">\n      <Alias name=\"h_ft\" description=\"Position in feet\" displayUnit=\"ft\"/>\n    </Float64>",
            "unit=\"m\" displayUnit=\"ft\" start=\"2.5\">\n      <Alias name=\"l2\"/>",
        ],
    );
}

#[test]
fn fmi2_writes_each_alias_as_a_local_of_the_same_value_reference_after_the_variables() {
    let (d, i) = decoded(Interfaces::BOTH);
    let xml = fmi2(&d, i, "{guid}").unwrap();
    assert_writes(
        &xml,
        &[
            "<DisplayUnit name=\"ft\" factor=\"3.280839895\"/>",
            "<Real unit=\"m\" displayUnit=\"ft\" start=\"2.5\"/>",
            // After the two variables: indices 3 and 4, h's and l's value references; the constant's
            // alias carries the constant's value, the other no start.
            "<!-- index 3 -->\n    <ScalarVariable name=\"h_ft\" valueReference=\"1\" description=\"Position in feet\" \
             causality=\"local\" variability=\"continuous\">\n      <Real unit=\"m\" displayUnit=\"ft\"/>",
            "<!-- index 4 -->\n    <ScalarVariable name=\"l2\" valueReference=\"2\" description=\"Length\" \
             causality=\"local\" variability=\"constant\">\n      <Real unit=\"m\" start=\"2.5\"/>",
            // The outputs are the declared ones only.
            "<Outputs>\n      <Unknown index=\"1\"/>\n    </Outputs>",
        ],
    );
}

#[test]
fn wrong_display_units_and_aliases_are_refused_naming_them() {
    const CLASH: [Variable; 2] = [
        VARS[0],
        Variable {
            aliases: &[Alias {
                name: "h",
                description: "",
                display_unit: "",
            }],
            ..VARS[1]
        },
    ];
    let e = fmi3(
        &ModelDescription {
            variables: &CLASH,
            ..BALL
        },
        Interfaces::BOTH_FMI3,
        "t",
    )
    .unwrap_err();
    assert!(
        e.contains("alias 'h' of variable 'l' (vr 2): the name of another variable or alias"),
        "{e}"
    );
    const UNKNOWN: [Variable; 1] = [Variable {
        display_unit: "yd",
        ..VARS[1]
    }];
    let e = fmi2(
        &ModelDescription {
            variables: &UNKNOWN,
            ..BALL
        },
        Interfaces::BOTH,
        "g",
    )
    .unwrap_err();
    assert!(
        e.contains("display unit 'yd' is no display unit of the variable's unit 'm'"),
        "{e}"
    );
    const INVERSE: [Unit; 1] = [Unit {
        display_units: &[DisplayUnit {
            inverse: true,
            ..BALL.units[0].display_units[0]
        }],
        ..BALL.units[0]
    }];
    let d = ModelDescription {
        units: &INVERSE,
        ..BALL
    };
    let e = fmi2(&d, Interfaces::BOTH, "g").unwrap_err();
    assert!(
        e.contains("display unit 'ft' of unit 'm': inverse, which FMI 2.0 has not"),
        "{e}"
    );
    assert!(
        fmi3(&d, Interfaces::BOTH_FMI3, "t")
            .unwrap()
            .contains("inverse=\"true\"")
    );
}
