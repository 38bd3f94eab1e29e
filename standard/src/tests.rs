//! The whole table, written out cell by cell from the standard's text (FMI 2.0 section 2.2.7,
//! the tables of variability × causality and of `initial`; FMI 3.0 section 2.4.7.4 for
//! `structuralParameter`), and every combination checked against the functions.

use super::*;

/// One cell: causality, variability, the legal `initial`s ("" where `initial` is not defined
/// or the combination is illegal), the default `initial` ("-" for none), whether legal.
/// Letters of the standard's table: A-E as in [`legal_initial`]; "x" illegal.
const TABLE: &[(&str, &str, &str, &str, char)] = &[
    // parameter: fixed and tunable only (B)
    ("parameter", "constant", "", "-", 'x'),
    ("parameter", "fixed", "exact", "exact", 'B'),
    ("parameter", "tunable", "exact", "exact", 'B'),
    ("parameter", "discrete", "", "-", 'x'),
    ("parameter", "continuous", "", "-", 'x'),
    // calculatedParameter: fixed and tunable only (C)
    ("calculatedParameter", "constant", "", "-", 'x'),
    ("calculatedParameter", "fixed", "calculated approx", "calculated", 'C'),
    ("calculatedParameter", "tunable", "calculated approx", "calculated", 'C'),
    ("calculatedParameter", "discrete", "", "-", 'x'),
    ("calculatedParameter", "continuous", "", "-", 'x'),
    // structuralParameter (FMI 3.0): as parameter (B)
    ("structuralParameter", "constant", "", "-", 'x'),
    ("structuralParameter", "fixed", "exact", "exact", 'B'),
    ("structuralParameter", "tunable", "exact", "exact", 'B'),
    ("structuralParameter", "discrete", "", "-", 'x'),
    ("structuralParameter", "continuous", "", "-", 'x'),
    // input: discrete and continuous, no initial (D)
    ("input", "constant", "", "-", 'x'),
    ("input", "fixed", "", "-", 'x'),
    ("input", "tunable", "", "-", 'x'),
    ("input", "discrete", "", "-", 'D'),
    ("input", "continuous", "", "-", 'D'),
    // output: constant (A), discrete and continuous (E)
    ("output", "constant", "exact", "exact", 'A'),
    ("output", "fixed", "", "-", 'x'),
    ("output", "tunable", "", "-", 'x'),
    ("output", "discrete", "calculated exact approx", "calculated", 'E'),
    ("output", "continuous", "calculated exact approx", "calculated", 'E'),
    // local: constant (A), fixed and tunable (C), discrete and continuous (E)
    ("local", "constant", "exact", "exact", 'A'),
    ("local", "fixed", "calculated approx", "calculated", 'C'),
    ("local", "tunable", "calculated approx", "calculated", 'C'),
    ("local", "discrete", "calculated exact approx", "calculated", 'E'),
    ("local", "continuous", "calculated exact approx", "calculated", 'E'),
    // independent: continuous only, no initial (D)
    ("independent", "constant", "", "-", 'x'),
    ("independent", "fixed", "", "-", 'x'),
    ("independent", "tunable", "", "-", 'x'),
    ("independent", "discrete", "", "-", 'x'),
    ("independent", "continuous", "", "-", 'D'),
];

fn cell(c: Causality, v: Variability) -> (&'static str, &'static str, char) {
    let (_, _, initials, default, case) = TABLE
        .iter()
        .find(|(tc, tv, ..)| *tc == c.name() && *tv == v.name())
        .unwrap_or_else(|| panic!("no cell for {c} × {v}"));
    (initials, default, *case)
}

#[test]
fn the_table_has_every_combination_once() {
    assert_eq!(TABLE.len(), Causality::ALL.len() * Variability::ALL.len());
    for c in Causality::ALL {
        for v in Variability::ALL {
            let n = TABLE
                .iter()
                .filter(|(tc, tv, ..)| *tc == c.name() && *tv == v.name())
                .count();
            assert_eq!(n, 1, "{c} × {v}");
        }
    }
}

#[test]
fn legal_variability_is_the_table() {
    for c in Causality::ALL {
        for v in Variability::ALL {
            let (_, _, case) = cell(c, v);
            assert_eq!(legal_variability(c, v), case != 'x', "{c} × {v}");
        }
    }
}

#[test]
fn legal_initial_is_the_table() {
    for c in Causality::ALL {
        for v in Variability::ALL {
            let (initials, _, _) = cell(c, v);
            for i in Initial::ALL {
                let listed = initials.split_whitespace().any(|n| n == i.name());
                assert_eq!(legal_initial(c, v, i), listed, "{c} × {v} × initial {i}");
            }
        }
    }
}

#[test]
fn default_initial_is_the_table_and_legal() {
    for c in Causality::ALL {
        for v in Variability::ALL {
            let (_, default, case) = cell(c, v);
            if case == 'x' {
                continue;
            }
            let expected = Initial::from_name(default);
            assert_eq!(default_initial(c, v), expected, "{c} × {v}");
            if let Some(i) = expected {
                assert!(legal_initial(c, v, i), "the default of {c} × {v} is legal");
            }
        }
    }
}

#[test]
fn start_values_are_required_exactly_for_inputs_exact_and_approx() {
    for c in Causality::ALL {
        for v in Variability::ALL {
            if !legal_variability(c, v) {
                continue;
            }
            // Undeclared initial: the default decides.
            let expected =
                c == Causality::Input || matches!(default_initial(c, v), Some(Initial::Exact | Initial::Approx));
            assert_eq!(has_start(c, v, None), expected, "{c} × {v}");
            for i in Initial::ALL.into_iter().filter(|i| legal_initial(c, v, *i)) {
                assert_eq!(has_start(c, v, Some(i)), i != Initial::Calculated, "{c} × {v} × {i}");
                assert_eq!(effective_initial(c, v, Some(i)), Some(i));
            }
        }
    }
    assert!(has_start(Causality::Input, Variability::Continuous, None));
    assert!(!has_start(Causality::Independent, Variability::Continuous, None));
    assert!(!has_start(Causality::Output, Variability::Continuous, None));
    assert!(has_start(Causality::Parameter, Variability::Fixed, None));
}

#[test]
fn default_variability_is_legal_and_fits_the_type() {
    for c in Causality::ALL {
        for kind in [TypeKind::Real, TypeKind::Other] {
            let v = default_variability(c, kind);
            assert!(legal_variability(c, v), "{c} defaults to {v}");
            if c != Causality::Independent {
                // The independent variable is a Real: a non-Real one is an error of its own.
                assert!(legal_variability_for_type(kind, v), "{c} of {kind:?} defaults to {v}");
            }
        }
    }
    for (causality, kind, variability) in [
        (Causality::Parameter, TypeKind::Real, Variability::Fixed),
        (Causality::Output, TypeKind::Real, Variability::Continuous),
        (Causality::Output, TypeKind::Other, Variability::Discrete),
        (Causality::Local, TypeKind::Other, Variability::Discrete),
    ] {
        assert_eq!(
            default_variability(causality, kind),
            variability,
            "{causality} of {kind:?}"
        );
    }
}

#[test]
fn only_reals_are_continuous() {
    for v in Variability::ALL {
        assert!(legal_variability_for_type(TypeKind::Real, v));
        assert_eq!(
            legal_variability_for_type(TypeKind::Other, v),
            v != Variability::Continuous
        );
    }
}

#[test]
fn names_and_codes_round_trip() {
    for (n, c) in Causality::ALL.into_iter().enumerate() {
        assert_eq!(c.code() as usize, n);
        assert_eq!(Causality::from_code(c.code()), Some(c));
        assert_eq!(Causality::from_name(c.name()), Some(c));
    }
    for (n, v) in Variability::ALL.into_iter().enumerate() {
        assert_eq!(v.code() as usize, n);
        assert_eq!(Variability::from_code(v.code()), Some(v));
        assert_eq!(Variability::from_name(v.name()), Some(v));
    }
    for (n, i) in Initial::ALL.into_iter().enumerate() {
        assert_eq!(i.code() as usize, n);
        assert_eq!(Initial::from_code(i.code()), Some(i));
        assert_eq!(Initial::from_name(i.name()), Some(i));
    }
    assert_eq!(Causality::from_code(7), None);
    assert_eq!(Variability::from_code(5), None);
    assert_eq!(Initial::from_code(3), None);
    assert_eq!(Causality::from_name("Parameter"), None);
    // The codes of the encoded description (src/description.rs): fixed forever.
    assert_eq!(
        [
            Causality::Parameter,
            Causality::Independent,
            Causality::StructuralParameter
        ]
        .map(Causality::code),
        [0, 5, 6]
    );
    assert!(
        Causality::ALL
            .iter()
            .filter(|c| !c.in_fmi2())
            .eq([&Causality::StructuralParameter])
    );
}

#[test]
fn without_leaves_out_the_named_functions_and_keeps_the_order() {
    use crate::functions::{FMI2_COMMON_FUNCTIONS, FMI2_VALUE_FUNCTIONS, without};
    const LEFT: [&str; 23] = without(
        FMI2_COMMON_FUNCTIONS,
        &["fmi2GetVersion", "fmi2Reset", "fmi2NotAFunction"],
    );
    let mut kept = FMI2_COMMON_FUNCTIONS
        .iter()
        .filter(|f| **f != "fmi2GetVersion" && **f != "fmi2Reset");
    assert!(LEFT.iter().all(|f| Some(f) == kept.next()) && kept.next().is_none());
    // The getters and setters stand in the common functions as one run, after fmi2Reset.
    let at = FMI2_COMMON_FUNCTIONS.iter().position(|f| *f == "fmi2Reset").unwrap() + 1;
    assert_eq!(FMI2_COMMON_FUNCTIONS[at..at + 8], FMI2_VALUE_FUNCTIONS);
    assert_eq!(FMI2_COMMON_FUNCTIONS.len(), 25);
}
