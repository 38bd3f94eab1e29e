//! modelDescription.xml: the committed files in modelDescription/ are what the declarations
//! generate, the GUID follows the content, and illegal declarations are refused.

use rustfmu::fmi2::variables::{Causality, Initial, Value, VarDecl, VarType, Variability};
use rustfmu::fmi2::xml::check_declarations;

#[test]
fn committed_model_descriptions_match_the_declarations() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("modelDescription");
    for entry in rustfmu::fmus::ALL {
        let id = entry.info.identifier;
        let generated = (entry.model_description)().unwrap_or_else(|e| panic!("{id}: {e}"));
        let path = dir.join(format!("{id}.xml"));
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            committed == generated,
            "{} differs from what {id}'s declarations generate: run `cargo run -p fmu-build -- xml` and commit",
            path.display()
        );
    }
}

#[test]
fn descriptions_are_deterministic_and_guids_distinct() {
    let mut guids = std::collections::BTreeSet::new();
    for entry in rustfmu::fmus::ALL {
        let a = (entry.model_description)().unwrap();
        assert_eq!(a, (entry.model_description)().unwrap());
        let guid = a
            .split("guid=\"")
            .nth(1)
            .and_then(|s| s.split('"').next())
            .unwrap()
            .to_string();
        assert!(guids.insert(guid), "two FMUs share a GUID");
    }
}

rustfmu::fmi2_variables! {
    /// A model for GUID tests.
    pub struct Small {
        /// input
        u: f64 = 0.0, vr = 0, Input, Continuous;
        /// output
        y: f64 = 0.0, vr = 1, Output, Continuous, depends = [u];
    }
}

rustfmu::fmi2_variables! {
    /// The same with another start value.
    pub struct SmallOtherStart {
        /// input
        u: f64 = 1.0, vr = 0, Input, Continuous;
        /// output
        y: f64 = 0.0, vr = 1, Output, Continuous, depends = [u];
    }
}

macro_rules! small_model {
    ($name:ident, $vars:ty) => {
        #[derive(Clone, serde::Serialize, serde::Deserialize)]
        struct $name($vars);
        impl rustfmu::fmi2::model::CoSimModel for $name {
            type Vars = $vars;
            const INFO: rustfmu::fmi2::model::ModelInfo = rustfmu::fmi2::model::ModelInfo {
                identifier: "Small",
                description: "test",
                author: "",
                version: "0",
                default_experiment: None,
                documentation_html: "",
            };
            fn new() -> Self {
                $name(Default::default())
            }
            fn vars(&self) -> &$vars {
                &self.0
            }
            fn vars_mut(&mut self) -> &mut $vars {
                &mut self.0
            }
            fn initialize(&mut self, _: f64, _: Option<f64>) -> Result<(), String> {
                Ok(())
            }
            fn do_step(&mut self, _: f64, _: f64) -> Result<(), rustfmu::fmi2::model::StepFailure> {
                self.0.y = self.0.u;
                Ok(())
            }
        }
    };
}
small_model!(A, Small);
small_model!(B, SmallOtherStart);

#[test]
fn guid_changes_when_a_start_value_changes() {
    let a = rustfmu::fmi2::xml::guid::<A>().unwrap();
    let b = rustfmu::fmi2::xml::guid::<B>().unwrap();
    assert_ne!(a, b, "a different start value must give a different GUID");
    let xml = rustfmu::fmi2::xml::model_description::<A>().unwrap();
    assert!(xml.contains(&format!("guid=\"{a}\"")));
    assert!(xml.contains("<Unknown index=\"2\" dependencies=\"1\"/>"), "{xml}");
}

fn decl(causality: Causality, variability: Variability, initial: Option<Initial>) -> VarDecl {
    VarDecl {
        name: "v",
        value_reference: 0,
        var_type: VarType::Real,
        causality,
        variability,
        initial,
        start: Value::Real(0.0),
        unit: "",
        description: "",
        min: None,
        max: None,
        depends_on: None,
    }
}

#[test]
fn illegal_causality_variability_initial_combinations_are_refused() {
    use Causality::*;
    use Variability::*;
    let bad = [
        decl(Parameter, Continuous, None),
        decl(Parameter, Fixed, Some(Initial::Calculated)),
        decl(Input, Fixed, None),
        decl(Input, Continuous, Some(Initial::Exact)),
        decl(CalculatedParameter, Tunable, Some(Initial::Exact)),
        decl(Independent, Continuous, Some(Initial::Exact)),
    ];
    for d in bad {
        assert!(
            check_declarations(&[d]).is_err(),
            "accepted {:?}/{:?}/{:?}",
            d.causality,
            d.variability,
            d.initial
        );
    }
    let good = [
        decl(Parameter, Fixed, None),
        decl(Parameter, Tunable, Some(Initial::Exact)),
        decl(Output, Continuous, Some(Initial::Exact)),
        decl(CalculatedParameter, Fixed, Some(Initial::Approx)),
        decl(Local, Continuous, None),
    ];
    for d in good {
        check_declarations(&[d]).unwrap();
    }
    let mut fractional_integer_bound = decl(Parameter, Fixed, None);
    (fractional_integer_bound.var_type, fractional_integer_bound.start) = (VarType::Integer, Value::Integer(1));
    fractional_integer_bound.min = Some(0.5);
    assert!(check_declarations(&[fractional_integer_bound]).is_err());
    let mut start_outside_bounds = decl(Parameter, Fixed, None);
    start_outside_bounds.min = Some(1.0);
    assert!(
        check_declarations(&[start_outside_bounds])
            .unwrap_err()
            .contains("outside")
    );
    let mut unknown_unit = decl(Output, Continuous, None);
    unknown_unit.unit = "furlong";
    assert!(check_declarations(&[unknown_unit]).unwrap_err().contains("furlong"));
}

#[test]
fn integer_bounds_are_written_as_integers() {
    let xml = rustfmu::fmus::ALL
        .iter()
        .find(|e| e.info.identifier == "Controller")
        .map(|e| (e.model_description)().unwrap())
        .expect("the Controller FMU is declared");
    assert!(
        xml.contains(r#"<Integer min="1" max="3" start="1"/>"#),
        "mode's bounds: {xml}"
    );
}
