//! String and Enumeration variables and a model's own log category, through the C API of a
//! model exported into this test binary.

use rustfmu::__private::abi::*;
use rustfmu::testing::thread_log as log;
use std::ffi::{CStr, CString};

mod model {
    use rustfmu::prelude::*;

    /// How to greet.
    #[derive(FmuEnum, Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
    pub enum Style {
        /// plainly
        Plain = 1,
        /// loudly
        Loud = 3,
    }

    /// Greets.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    #[fmu(log_category(name = "logGreetings", description = "every greeting"))]
    pub struct Greeter {
        /// Whom to greet
        #[variable(vr = 0, input, start = "world")]
        pub name: String,
        /// The greeting
        #[variable(vr = 1, output)]
        pub greeting: String,
        /// The style
        #[variable(vr = 2, parameter, tunable, start = Style::Plain)]
        pub style: Style,
    }

    impl Model for Greeter {
        fn initialize(&mut self, ctx: &Context) -> Result<(), String> {
            // A greeting file among the resources, if the FMU was given its resources folder.
            if let Some(name) = ctx
                .resource_dir()
                .and_then(|d| std::fs::read_to_string(d.join("name.txt")).ok())
            {
                self.name = name.trim().to_string();
            }
            self.greet(ctx);
            Ok(())
        }
    }

    impl Greeter {
        fn greet(&mut self, ctx: &Context) {
            self.greeting = match self.style {
                Style::Plain => format!("hello, {}", self.name),
                Style::Loud => format!("HELLO, {}!", self.name.to_uppercase()),
            };
            ctx.log("logGreetings", &self.greeting);
        }
    }

    impl CoSimulation for Greeter {
        fn do_step(&mut self, _t: f64, _h: f64, ctx: &mut Context) -> Result<(), StepFailure> {
            self.greet(ctx);
            Ok(())
        }
    }

    rustfmu::export_fmi2!(Greeter);
}
use model::*;

fn instance(logging_on: bool) -> fmi2Component {
    instance_with_resources(logging_on, None)
}

fn instance_with_resources(logging_on: bool, resources: Option<&std::path::Path>) -> fmi2Component {
    let uri = resources.map(|d| CString::new(format!("file://{}", d.display())).unwrap());
    let c = rustfmu::testing::fmi2::Instantiation {
        resource_location: uri.as_deref(),
        logging_on,
        ..rustfmu::testing::fmi2::Instantiation::new(fmi2CoSimulation, c"greeter")
    }
    .call(fmi2Instantiate, model::__rustfmu_fmi2_exports::GUID, log());
    assert!(!c.is_null());
    c
}

fn get_string(c: fmi2Component, vr: u32) -> String {
    let mut p: fmi2String = std::ptr::null();
    // SAFETY: one reference, one slot.
    assert_eq!(unsafe { fmi2GetString(c, &vr, 1, &mut p) }, fmi2OK);
    // SAFETY: valid until the next call on c.
    unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
}

#[test]
fn strings_are_set_and_read_through_the_c_api() {
    let c = instance(false);
    // SAFETY: c is a live instance; arrays of one.
    unsafe {
        let who = c"Ada".as_ptr();
        assert_eq!(fmi2SetString(c, &0, 1, &who), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
        assert_eq!(get_string(c, 1), "hello, Ada");
        assert_eq!(get_string(c, 0), "Ada");
        let null: fmi2String = std::ptr::null();
        assert_eq!(fmi2SetString(c, &0, 1, &null), fmi2Error, "a NULL string is refused");
        assert_eq!(get_string(c, 0), "Ada", "and changes nothing");
        fmi2FreeInstance(c);
    }
}

#[test]
fn an_enumeration_takes_only_its_items() {
    let c = instance(false);
    // SAFETY: c is a live instance; arrays of one.
    unsafe {
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
        let mut style = 0;
        assert_eq!(fmi2GetInteger(c, &2, 1, &mut style), fmi2OK);
        assert_eq!(style, 1, "an Enumeration reads as its item's value");
        assert_eq!(fmi2SetInteger(c, &2, 1, &2), fmi2Error, "2 is no item of Style");
        assert_eq!(fmi2SetInteger(c, &2, 1, &3), fmi2OK);
        assert_eq!(fmi2DoStep(c, 0.0, 0.1, fmi2True), fmi2OK);
        assert_eq!(get_string(c, 1), "HELLO, WORLD!");
        let mut x = 0.0;
        assert_eq!(fmi2GetReal(c, &2, 1, &mut x), fmi2Error, "an Enumeration is no Real");
        fmi2FreeInstance(c);
    }
}

#[test]
fn a_model_logs_under_its_own_declared_category() {
    let c = instance(true);
    // SAFETY: c is a live instance.
    unsafe {
        let cats = [c"logGreetings".as_ptr()];
        assert_eq!(fmi2SetDebugLogging(c, fmi2True, 1, cats.as_ptr()), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
        let unknown = [c"logNothing".as_ptr()];
        assert_eq!(fmi2SetDebugLogging(c, fmi2True, 1, unknown.as_ptr()), fmi2Error);
        fmi2FreeInstance(c);
    }
    let log: Vec<(String, String)> = log().entries().into_iter().map(|e| (e.category, e.text)).collect();
    assert!(
        log.iter()
            .any(|(cat, text)| cat == "logGreetings" && text == "hello, world"),
        "expected the greeting under logGreetings, got {log:?}"
    );
    assert!(
        log.iter()
            .any(|(_, text)| text.contains("unknown log category 'logNothing'") && text.contains("logGreetings")),
        "the refusal names the declared categories: {log:?}"
    );
}

#[test]
fn a_model_reads_its_resources_from_the_folder_the_importer_names() {
    let dir = std::env::temp_dir().join(format!("rustfmu-resources-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("name.txt"), "Grace\n").unwrap();
    let c = instance_with_resources(false, Some(&dir));
    // SAFETY: c is a live instance.
    unsafe {
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
        assert_eq!(get_string(c, 1), "hello, Grace");
        fmi2FreeInstance(c);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
