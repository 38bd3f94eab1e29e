//! The derive's logic without a compiler: a declaration parsed from source text (so that every
//! token has a line and a column), expanded, and the generated tokens or the one error checked:
//! what it says and, with `--features span-tests` (spans with line and column outside a
//! compiler), where it points.

use crate::model::{self, Expansion};
#[cfg(feature = "span-tests")]
use proc_macro2::LineColumn;
use proc_macro2::TokenStream;
use quote::quote;

#[cfg(feature = "span-tests")]
/// Where `needle` (its `nth` occurrence, from 0) starts in `src`, as proc-macro2 counts it
/// (lines from 1, columns from 0 in characters).
fn position(src: &str, needle: &str, nth: usize) -> LineColumn {
    let at = src
        .match_indices(needle)
        .nth(nth)
        .unwrap_or_else(|| panic!("`{needle}` (#{nth}) is not in the source"))
        .0;
    let before = &src[..at];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().unwrap_or("").chars().count();
    LineColumn { line, column }
}

pub(crate) fn expand(src: &str) -> Expansion {
    model::expand_parts(syn::parse_str(src).expect("the test's source parses"))
}

pub(crate) fn generated(src: &str) -> String {
    let e = expand(src);
    if let Some(error) = e.error {
        panic!("unexpected error: {error}");
    }
    e.generated.expect("code").to_string()
}

/// The one error `src` gives.
pub(crate) fn error(src: &str) -> syn::Error {
    let e = expand(src);
    let error = e.error.expect("the declaration is wrong");
    let all: Vec<_> = error.clone().into_iter().collect();
    assert_eq!(all.len(), 1, "exactly one error: {all:?}");
    if let Some(code) = &e.generated {
        assert!(
            !code.to_string().contains("compile_error"),
            "the generated code adds no error"
        );
    }
    error
}

/// Asserts that `src` gives one error containing `message` and (checked with span-tests)
/// starting at the `nth` occurrence of `needle`.
#[track_caller]
fn assert_error(src: &str, message: &str, needle: &str, nth: usize) {
    let e = error(src);
    let text = e.to_string();
    assert!(text.contains(message), "message: {text}\nexpected: {message}");
    #[cfg(feature = "span-tests")]
    assert_eq!(
        e.span().start(),
        position(src, needle, nth),
        "the error's span ({text})"
    );
    let _ = (needle, nth);
}

/// A model around one field declaration.
fn model(field: &str) -> String {
    format!("struct M {{\n{field}\n}}\n")
}

const LEGAL: &str = r#"
/// A model.
struct Plant {
    /// Force.
    #[variable(vr = 0, input, unit = "N")]
    u: f64,
    /// Position.
    #[variable(vr = 1, output, derivative_of = v)]
    x: f64,
    #[variable(vr = 2, local, initial = exact, start = 1.5)]
    v: f64,
    #[variable(vr = 3, parameter, tunable, start = 2.0, min = 0.0, max <= 10.0)]
    k: f64,
    #[variable(vr = 7, output)]
    count: i32,
    #[variable(vr = 8, calculated_parameter)]
    c: f64,
    scratch: Vec<f64>,
}
"#;

#[test]
fn a_legal_declaration_expands_with_its_value_references_and_causalities() {
    let code = generated(LEGAL);
    for (vr, causality, variability) in [
        (0u32, "Input", "Continuous"),
        (1, "Output", "Continuous"),
        (2, "Local", "Continuous"),
        (3, "Parameter", "Tunable"),
        (7, "Output", "Discrete"),
        (8, "CalculatedParameter", "Fixed"),
    ] {
        let vr = quote!(#vr).to_string();
        let expected = format!(
            "value_reference : {vr} , var_type : < {ty} as :: rustfmu :: FmiType > :: TYPE , \
             causality : :: rustfmu :: description :: Causality :: {causality} , \
             variability : :: rustfmu :: description :: Variability :: {variability} ,",
            ty = if vr == "7u32" { "i32" } else { "f64" }
        );
        assert!(code.contains(&expected), "{expected}\nnot in\n{code}");
    }
    // The value reference -> index match, in declaration order.
    assert!(code.contains("3u32 => :: core :: option :: Option :: Some (3usize)"));
    assert!(code.contains("model_identifier : \"Plant\""));
    assert!(code.contains("description : \"A model.\""));
    // The state and its derivative.
    assert!(code.contains("const STATES : & 'static [u32] = & [2u32]"), "{code}");
    assert!(code.contains("const DERIVATIVES : & 'static [u32] = & [1u32]"));
    // A field without #[variable] is internal state, started from Default.
    assert!(code.contains("scratch : :: core :: default :: Default :: default ()"));
    assert!(code.contains("internal_state : \"scratch: Vec<f64>\""), "{code}");
}

#[test]
fn start_values_follow_the_standard() {
    let code = generated(LEGAL);
    // An input has a start value (0.0 if none is written), an exact local and a parameter
    // theirs, a calculated output and a calculated parameter none.
    let start_of = |name: &str| {
        let from = code.find(&format!("name : \"{name}\"")).expect("declared");
        let rest = &code[from..];
        let s = rest.find("start : ").expect("start") + "start : ".len();
        rest[s..rest[s..].find(" , unit").expect("unit follows") + s].to_string()
    };
    assert_eq!(start_of("u"), ":: rustfmu :: description :: Start :: Real (0.0)");
    assert_eq!(start_of("v"), ":: rustfmu :: description :: Start :: Real (1.5)");
    assert_eq!(start_of("k"), ":: rustfmu :: description :: Start :: Real (2.0)");
    assert_eq!(start_of("x"), ":: rustfmu :: description :: Start :: None");
    assert_eq!(start_of("c"), ":: rustfmu :: description :: Start :: None");
    assert_eq!(start_of("count"), ":: rustfmu :: description :: Start :: None");
    // The bounds, inclusive and not.
    assert!(code.contains("min : :: core :: option :: Option :: Some (:: rustfmu :: description :: Bound { value : (0.0) as f64 , exclusive : false , })"));
    assert!(
        code.contains("initial : :: core :: option :: Option :: Some (:: rustfmu :: description :: Initial :: Exact)")
    );
}

#[test]
fn an_illegal_causality_variability_is_one_error_at_the_variability() {
    let src = model("    #[variable(vr = 0, parameter, continuous)]\n    p: f64,");
    assert_error(
        &src,
        "causality Parameter with variability Continuous is not allowed (FMI 2.0, section 2.2.7)",
        "continuous",
        0,
    );
    let src = model("    #[variable(vr = 0, input, fixed)]\n    u: f64,");
    assert_error(
        &src,
        "causality Input with variability Fixed is not allowed",
        "fixed",
        0,
    );
}

#[test]
fn an_illegal_initial_is_one_error_at_the_initial() {
    let src = model("    #[variable(vr = 1, parameter, initial = calculated)]\n    p: f64,");
    assert_error(
        &src,
        "initial = calculated is not allowed with causality Parameter and variability Fixed (FMI 2.0, section 2.2.7)",
        "calculated",
        0,
    );
    let src = model("    #[variable(vr = 1, input, initial = exact, start = 1.0)]\n    u: f64,");
    assert_error(&src, "initial = exact is not allowed with causality Input", "exact", 0);
}

#[test]
fn a_missing_value_reference_is_one_error_at_the_attribute() {
    let src = model("    #[variable(input)]\n    u: f64,");
    assert_error(
        &src,
        "every variable needs a value reference: `vr = N`",
        "#[variable",
        0,
    );
}

#[test]
fn a_missing_causality_is_one_error_at_the_attribute() {
    let src = model("    #[variable(vr = 0)]\n    u: f64,");
    assert_error(&src, "every variable needs a causality", "#[variable", 0);
}

#[test]
fn a_duplicate_value_reference_is_one_error_at_the_second_field() {
    let src = model("    #[variable(vr = 4, input)]\n    a: f64,\n    #[variable(vr = 4, output)]\n    b: f64,");
    assert_error(
        &src,
        "value reference 4 is used twice (first by 'a'); value references are unique in a model",
        "b: f64",
        0,
    );
}

#[test]
fn a_duplicate_name_is_one_error_at_the_second_field() {
    let src = model(
        "    #[variable(vr = 0, input)]\n    a: f64,\n    #[variable(vr = 1, output, name = \"a\")]\n    b: f64,",
    );
    assert_error(&src, "the name 'a' is declared twice (first on field `a`)", "b: f64", 0);
}

#[test]
fn a_continuous_integer_is_one_error_at_the_variability() {
    let src = model("    #[variable(vr = 0, output, continuous)]\n    n: i32,");
    assert_error(
        &src,
        "only Float64 (f64) and Float32 (f32) variables may be continuous",
        "continuous",
        0,
    );
}

#[test]
fn an_unsupported_type_is_one_error_at_the_type() {
    for ty in ["usize", "i128", "char"] {
        let src = model(&format!("    #[variable(vr = 0, input)]\n    x: {ty},"));
        assert_error(&src, &format!("{ty} is not an FMI type: use f64 (Float64/Real)"), ty, 0);
    }
    // The FMI 3.0 types, arrays of them too: FMI 3.0 only, by declaration. (An array of an
    // FMI 2.0 type is in both: FMI 2.0 lists its elements.)
    for ty in ["f32", "u8", "i64", "Vec<u8>", "[u16; 2]"] {
        let src = model(&format!("    #[variable(vr = 0, input)]\n    x: {ty},"));
        assert_error(
            &src,
            "which FMI 2.0 does not have: declare the variable `fmi3_only`",
            "x",
            0,
        );
    }
    let src = model("    #[variable(vr = 0, input)]\n    x: [[[f64; 2]; 2]; 2],");
    assert_error(&src, "arrays have one or two dimensions", "[[[f64", 0);
    let src = model("    #[variable(vr = 0, input)]\n    x: Vec<f64>,");
    assert_error(&src, "a Vec variable is a Binary: Vec<u8>", "Vec", 0);
}

#[test]
fn an_enumeration_without_start_is_one_error_at_the_field() {
    let src = model("    #[variable(vr = 0, parameter)]\n    mode: Mode,");
    assert_error(
        &src,
        "an Enumeration variable needs `start = Enum::Item` (its value before initialization)",
        "mode",
        0,
    );
}

#[test]
fn a_bound_with_the_wrong_operator_is_one_error_at_the_operator() {
    let src = model("    #[variable(vr = 0, input, min < 0.0)]\n    u: f64,");
    assert_error(
        &src,
        "expected `min = x` (x is legal), `min >= x` or `min > x` (x is not)",
        "<",
        0,
    );
    let src = model("    #[variable(vr = 0, input, max >= 1.0)]\n    u: f64,");
    assert_error(
        &src,
        "expected `max = x` (x is legal), `max <= x` or `max < x` (x is not)",
        ">=",
        0,
    );
}

#[test]
fn a_start_on_a_calculated_output_is_one_error_at_the_start_value() {
    let src = model("    #[variable(vr = 0, output, start = 3.0)]\n    y: f64,");
    assert_error(
        &src,
        "an output with initial = calculated has no start value (FMI 2.0, section 2.2.7); declare initial = exact or approx to give one",
        "3.0",
        0,
    );
    let src = model("    #[variable(vr = 0, independent, start = 0.0)]\n    t: f64,");
    assert_error(&src, "the independent variable has no start value", "0.0", 0);
}

#[test]
fn a_declaration_given_twice_or_unknown_is_one_error_at_its_key() {
    let src = model("    #[variable(vr = 0, input, output)]\n    u: f64,");
    assert_error(
        &src,
        "two causalities: Input and Output; a variable has one",
        "output",
        0,
    );
    let src = model("    #[variable(vr = 0, vr = 1, input)]\n    u: f64,");
    assert_error(&src, "`vr` is given twice", "vr", 1);
    let src = model("    #[variable(vr = 0, input, unti = \"m\")]\n    u: f64,");
    assert_error(&src, "unknown declaration `unti`; known: vr, name,", "unti", 0);
    let src = model("    #[variable(vr = 0, input)]\n    #[variable(vr = 1, input)]\n    u: f64,");
    assert_error(&src, "one #[variable(...)] per field", "#[variable", 1);
}

#[test]
fn type_mismatched_attributes_are_one_error_at_the_field() {
    let src = model("    #[variable(vr = 0, parameter, nominal = 2.0)]\n    n: i32,");
    assert_error(
        &src,
        "only Float64 (f64) and Float32 (f32) variables have a nominal value",
        "n: i32",
        0,
    );
    let src = model("    #[variable(vr = 0, parameter, unit = \"m\")]\n    n: i32,");
    assert_error(
        &src,
        "only Float64 (f64) and Float32 (f32) variables have a unit",
        "n: i32",
        0,
    );
    let src = model("    #[variable(vr = 0, input, min = 0)]\n    b: bool,");
    assert_error(
        &src,
        "min and max are for numeric (float and integer) and Enumeration variables",
        "b: bool",
        0,
    );
    let src = model("    #[variable(vr = 0, independent)]\n    t: i32,");
    assert_error(&src, "the independent variable (time) is a Real (f64)", "t: i32", 0);
}

#[test]
fn model_wide_mistakes_are_one_error_and_the_code_is_still_generated() {
    // `depends` on something that is neither an input nor a state: the error points at the name,
    // and the impls are generated anyway, so that the compiler adds no "trait bound not
    // satisfied" errors after it (issue 23).
    let src = model(
        "    #[variable(vr = 0, parameter)]\n    p: f64,\n    #[variable(vr = 1, output, depends = [p])]\n    y: f64,",
    );
    assert_error(
        &src,
        "'y' depends on 'p', which is neither an input nor a continuous state",
        "p]",
        0,
    );
    assert!(expand(&src).generated.is_some());
    // `initial_depends` on a variable that is known at initialization, or naming one that is not
    // (issue 23: the dependencies of InitialUnknowns).
    let src = model(
        "    #[variable(vr = 0, input, start = 0.0)]\n    u: f64,\n    #[variable(vr = 1, output, initial_depends = [u])]\n    y: f64,\n    #[variable(vr = 2, parameter, start = 1.0, initial_depends = [u])]\n    p: f64,",
    );
    assert_error(
        &src,
        "only the unknowns of Initialization Mode (outputs, states and derivatives that are calculated or approx, calculated parameters; not clocked variables) declare `initial_depends`",
        "p: f64",
        0,
    );
    let src = model(
        "    #[variable(vr = 0, input, start = 0.0)]\n    u: f64,\n    #[variable(vr = 1, output, initial_depends = [z])]\n    y: f64,\n    #[variable(vr = 2, output, initial_depends = [y])]\n    z: f64,",
    );
    assert_error(
        &src,
        "'y' initially depends on 'z', which is not known in Initialization Mode",
        "z]",
        0,
    );
    // An undeclared unit: the generator cannot get past it (it has no base units), the error
    // comes alone.
    let src = model("    #[variable(vr = 0, input, unit = \"furlong\")]\n    u: f64,");
    assert_error(&src, "unit 'furlong' is not declared", "\"furlong\"", 0);
    assert!(expand(&src).generated.is_none());
    // A derivative of an input.
    let src = model(
        "    #[variable(vr = 0, input)]\n    u: f64,\n    #[variable(vr = 1, local, derivative_of = u)]\n    du: f64,",
    );
    assert_error(
        &src,
        "'u' has causality Input: a continuous state is an output or a local",
        "u)]",
        0,
    );
}

#[test]
fn a_model_is_a_plain_struct_with_variables() {
    assert_error("enum E { A }", "#[derive(Model)] is for structs", "E", 0);
    assert_error(
        "struct S(f64);",
        "#[derive(Model)] needs a struct with named fields",
        "S",
        0,
    );
    assert_error(
        "struct S<T> { #[variable(vr = 0, input)] x: T }",
        "a model struct cannot be generic",
        "<T>",
        0,
    );
    assert_error(
        "struct S { x: f64 }",
        "a model declares at least one #[variable(...)]",
        "S",
        0,
    );
    assert_error(
        "#[fmu(identifier = \"2fast\")] struct S { #[variable(vr = 0, input)] x: f64 }",
        "the model identifier names the binary",
        "\"2fast\"",
        0,
    );
}

#[test]
fn the_entry_point_turns_a_mistake_into_compile_error() {
    let input: TokenStream = quote! {
        struct M {
            #[variable(vr = 0, parameter, continuous)]
            p: f64,
        }
    };
    let out = crate::derive_model(input).to_string();
    assert!(out.starts_with(":: core :: compile_error !"), "{out}");
    assert!(out.contains("causality Parameter with variability Continuous is not allowed"));
    let out = crate::derive_model(quote!(
        fn not_an_item() {}
    ))
    .to_string();
    assert!(out.contains("compile_error"), "{out}");
}

#[test]
fn an_fmu_enum_expands_to_its_items() {
    let input = quote! {
        /// Operating mode.
        enum Mode {
            /// Off.
            Off = 1,
            On,
            #[fmu(name = "Fast mode")]
            Fast = 5,
        }
    };
    let out = crate::derive_fmu_enum(input).to_string();
    assert!(
        out.contains("name : \"Mode\" , description : \"Operating mode.\""),
        "{out}"
    );
    assert!(
        out.contains("EnumItem { name : \"Off\" , value : 1i32 , description : \"Off.\" }"),
        "{out}"
    );
    assert!(out.contains("EnumItem { name : \"On\" , value : 2i32"));
    assert!(out.contains("EnumItem { name : \"Fast mode\" , value : 5i32"));
    assert!(out.contains("5i32 => :: core :: option :: Option :: Some (Mode :: Fast)"));
}

#[test]
fn fmu_enum_mistakes_are_errors() {
    let check = |src: &str, message: &str, needle: &str| {
        let input: syn::DeriveInput = syn::parse_str(src).expect("parses");
        let e = crate::enums::expand(input).expect_err("a mistake");
        assert!(e.to_string().contains(message), "{e}");
        #[cfg(feature = "span-tests")]
        assert_eq!(e.span().start(), position(src, needle, 0), "{e}");
        let _ = needle;
    };
    check("enum E { A, B }", "give the first item its value (`Item = 1`)", "A");
    check("enum E { A = 1, B = 1 }", "value 1 is used twice (first by A)", "B");
    check("enum E { A = 1, B(i32) }", "Enumeration items carry no data", "B");
    check("struct E;", "#[derive(FmuEnum)] is for fieldless enums", "E");
    check("enum E { A = 3000000000 }", "an item's value must fit an i32", "A");
}
