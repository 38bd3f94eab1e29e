//! Display units and aliases (issue 52, item 7): what `display_unit(..)`, `display_unit = ".."`
//! and `alias(..)` generate, and each wrong declaration's one error at its place.

use crate::tests::error;

/// The generated code, without spaces (the tokens' text).
fn generated(src: &str) -> String {
    crate::tests::generated(src).replace(' ', "")
}

/// Asserts that `src` gives one error containing `message`.
#[track_caller]
fn assert_error(src: &str, message: &str) {
    let text = error(src).to_string();
    assert!(text.contains(message), "message: {text}\nexpected: {message}");
}

/// The Reference-FMUs' BouncingBall's `h`: an alias in feet.
const BALL: &str = r#"
#[fmu(display_unit(unit = "m", name = "ft", factor = 3.280839895))]
struct Ball {
    /// Position of the ball
    #[variable(vr = 1, output, continuous, initial = exact, start = 1.0, unit = "m",
               alias(name = "h_ft", description = "Position in feet", display_unit = "ft"))]
    h: f64,
    /// Angle
    #[variable(vr = 2, output, unit = "rad", display_unit = "deg", alias = "phi_rad")]
    phi: f64,
}
"#;

#[test]
fn display_units_and_aliases_are_in_the_generated_description() {
    let code = generated(BALL);
    // The declared display unit under its unit, the built-in one the angle shows.
    assert!(
        code.contains(
            "display_units:&[::rustfmu::description::DisplayUnit{name:\"ft\",factor:3.280839895f64,offset:0f64,inverse:false}]"
        ),
        "{code}"
    );
    assert!(
        code.contains("::rustfmu::description::DisplayUnit{name:\"deg\",factor:57.29577951308232f64"),
        "{code}"
    );
    assert!(
        code.contains(
            "aliases:&[::rustfmu::description::Alias{name:\"h_ft\",description:\"Positioninfeet\",display_unit:\"ft\"}]"
        ),
        "{code}"
    );
    assert!(code.contains("display_unit:\"deg\",aliases:&[::rustfmu::description::Alias{name:\"phi_rad\",description:\"\",display_unit:\"\"}]"), "{code}");
}

#[test]
fn a_built_in_display_unit_nobody_uses_is_left_out() {
    let code = generated(
        "struct M {\n#[variable(vr = 0, output, unit = \"rad\")]\nphi: f64,\n#[variable(vr = 1, output, unit = \"rad/s\", display_unit = \"rpm\")]\nw: f64,\n}",
    );
    assert!(!code.contains("name:\"deg\""), "deg is used by no variable: {code}");
    assert!(code.contains("name:\"rpm\""), "{code}");
    assert!(!code.contains("name:\"deg/s\""), "{code}");
}

#[test]
fn an_unknown_display_unit_names_the_unit_and_how_to_declare_it() {
    assert_error(
        "struct M {\n#[variable(vr = 0, output, unit = \"m\", display_unit = \"furlong\")]\nx: f64,\n}",
        "'x': display unit 'furlong' is not declared for unit 'm' (it has none yet): declare it on the struct with \
         #[fmu(display_unit(unit = \"m\", name = \"furlong\", factor = .., offset = ..))]",
    );
}

#[test]
fn a_display_unit_of_another_quantity_is_refused() {
    assert_error(
        "struct M {\n#[variable(vr = 0, output, unit = \"m\", display_unit = \"deg\")]\nx: f64,\n}",
        "'x': display unit 'deg' is a display unit of 'rad', not of 'm' (the variable's unit; it has none yet): a \
         display unit shows a value of its own unit's quantity",
    );
    // Also on an alias.
    assert_error(
        "#[fmu(display_unit(unit = \"m\", name = \"ft\", factor = 3.28))]\nstruct M {\n#[variable(vr = 0, output, unit = \"rad\", alias(name = \"y\", display_unit = \"ft\"))]\nx: f64,\n}",
        "'x': display unit 'ft' is a display unit of 'm', not of 'rad' (the variable's unit; its display units are deg)",
    );
}

#[test]
fn a_display_unit_needs_a_float_with_a_unit() {
    assert_error(
        "struct M {\n#[variable(vr = 0, output, display_unit = \"deg\")]\nx: f64,\n}",
        "display unit 'deg' needs the variable's `unit`",
    );
    assert_error(
        "struct M {\n#[variable(vr = 0, output, display_unit = \"deg\")]\nx: i32,\n}",
        "only Float64 (f64) and Float32 (f32) variables (and their aliases) have a display unit",
    );
}

#[test]
fn an_alias_named_as_a_variable_or_another_alias_is_refused() {
    assert_error(
        "struct M {\n#[variable(vr = 0, output, alias = \"y\")]\nx: f64,\n#[variable(vr = 1, output)]\ny: f64,\n}",
        "alias 'y' of 'x' is the name of a variable: names are unique among variables and aliases",
    );
    assert_error(
        "struct M {\n#[variable(vr = 0, output, alias = \"z\")]\nx: f64,\n#[variable(vr = 1, output, alias(name = \"z\"))]\ny: f64,\n}",
        "alias 'z' of 'y' is already an alias of 'x': names are unique among variables and aliases",
    );
}

#[test]
fn display_unit_declarations_are_checked_on_the_struct() {
    assert_error(
        "#[fmu(display_unit(unit = \"furlong\", name = \"ft\", factor = 3.0))]\nstruct M {\n#[variable(vr = 0, output)]\nx: f64,\n}",
        "display unit 'ft' is of unit 'furlong', which is not declared",
    );
    assert_error(
        "#[fmu(display_unit(unit = \"rad\", name = \"deg\", factor = 57.3))]\nstruct M {\n#[variable(vr = 0, output)]\nx: f64,\n}",
        "display unit 'deg' of unit 'rad' is declared twice (or is built in)",
    );
    assert_error(
        "#[fmu(display_unit(unit = \"S\", name = \"Ohm\", factor = 1.0, inverse))]\nstruct M {\n#[variable(vr = 0, output)]\nx: f64,\n}",
        "display unit 'Ohm' is inverse, which FMI 2.0 has not",
    );
    assert_error(
        "#[fmu(display_unit(unit = \"m\", name = \"x\", factor = 2.0, offset = 1.0, inverse))]\nstruct M {\n#[variable(vr = 0, output)]\nx: f64,\n}",
        "an inverse display unit has no offset",
    );
    assert_error(
        "#[fmu(display_unit(unit = \"m\", name = \"ft\", scale = 3.0))]\nstruct M {\n#[variable(vr = 0, output)]\nx: f64,\n}",
        "unknown display unit attribute `scale`; known: unit, name, factor, offset, inverse",
    );
}

#[test]
fn an_inverse_display_unit_is_fine_in_an_fmi3_only_model() {
    let code = generated(
        "#[fmu(fmi3_only, display_unit(unit = \"m/s\", name = \"s/km\", factor = 1000.0, inverse))]\nstruct M {\n#[variable(vr = 0, output, unit = \"m/s\", display_unit = \"s/km\")]\nv: f64,\n}",
    );
    assert!(
        code.contains("name:\"s/km\",factor:1000f64,offset:0f64,inverse:true"),
        "{code}"
    );
}

#[test]
fn an_alias_of_an_array_is_refused() {
    assert_error(
        "#[fmu(fmi3_only)]\nstruct M {\n#[variable(vr = 0, output, alias = \"y\")]\nx: [f64; 2],\n}",
        "aliases are declared on scalar variables only",
    );
}

#[test]
fn an_unknown_alias_key_lists_the_known_ones() {
    assert_error(
        "struct M {\n#[variable(vr = 0, output, alias(name = \"y\", unit = \"m\"))]\nx: f64,\n}",
        "unknown alias declaration `unit`; known: name, description, display_unit",
    );
}
