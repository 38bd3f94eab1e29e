//! The SSP runner: what it reads, what it refuses (with the component and connector named), and
//! runs of the project's SSP files (tests/run.sh builds them before the Rust tests; the tests
//! that need them say so when they are missing).

// rustfmu_runner::Error is large (it carries the details of a failure), on the cold path only.
#![allow(clippy::result_large_err)]

use rustfmu_runner::ssp::{Connection, parse_ssd};
use rustfmu_runner::{ErrorKind, Override, RunOptions, Simulation, Value};
use std::io::Write;
use std::path::{Path, PathBuf};

const SSD_HEAD: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
  xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
  xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="T">"#;

fn ssd(body: &str) -> String {
    format!(
        "{SSD_HEAD}<ssd:System name=\"Sys\">{body}</ssd:System><ssd:DefaultExperiment startTime=\"0\" stopTime=\"2.5\"/></ssd:SystemStructureDescription>"
    )
}

const TWO_LAGS: &str = r#"<ssd:Elements>
  <ssd:Component name="a" source="resources/Lag.fmu" type="application/x-fmu-sharedlibrary">
    <ssd:Connectors><ssd:Connector name="y" kind="output"><ssc:Real unit="m"/></ssd:Connector></ssd:Connectors>
    <ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version="1.0" name="p"><ssv:Parameters>
      <ssv:Parameter name="T"><ssv:Real value="0.25"/></ssv:Parameter>
      <ssv:Parameter name="n"><ssv:Integer value="3"/></ssv:Parameter>
      <ssv:Parameter name="on"><ssv:Boolean value="true"/></ssv:Parameter>
    </ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings>
  </ssd:Component>
  <ssd:Component name="b" source="resources/Lag.fmu">
    <ssd:Connectors><ssd:Connector name="u" kind="input"><ssc:Real unit="m"/></ssd:Connector></ssd:Connectors>
    <ssd:ParameterBindings><ssd:ParameterBinding source="b.ssv"/></ssd:ParameterBindings>
  </ssd:Component>
</ssd:Elements>"#;

#[test]
fn an_ssd_with_inline_and_file_parameter_sets_is_read() {
    let xml = ssd(&format!(
        r#"{TWO_LAGS}<ssd:Connections><ssd:Connection startElement="a" startConnector="y" endElement="b" endConnector="u"/></ssd:Connections>"#
    ));
    let ssv = r#"<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="b">
        <ssv:Parameters><ssv:Parameter name="T"><ssv:Real value="1e-2"/></ssv:Parameter></ssv:Parameters></ssv:ParameterSet>"#;
    let mut read = |name: &str| {
        assert_eq!(name, "b.ssv");
        Ok(ssv.to_owned())
    };
    let s = parse_ssd(&xml, &mut read).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.name, "Sys");
    assert_eq!(s.stop_time, Some(2.5));
    assert_eq!(s.components.len(), 2);
    assert_eq!(s.components[0].source, "resources/Lag.fmu");
    assert_eq!(
        s.components[0].parameters,
        vec![
            ("T".to_owned(), Value::Real(0.25)),
            ("n".to_owned(), Value::Integer(3)),
            ("on".to_owned(), Value::Boolean(true))
        ]
    );
    assert_eq!(s.components[1].parameters, vec![("T".to_owned(), Value::Real(1e-2))]);
    assert_eq!(
        s.connections,
        vec![Connection {
            start: ("a".into(), "y".into()),
            end: ("b".into(), "u".into())
        }]
    );
}

fn refused(body: &str) -> rustfmu_runner::Error {
    let mut read = |_: &str| Ok("<ssv:ParameterSet xmlns:ssv=\"x\"/>".to_owned());
    parse_ssd(&ssd(body), &mut read).expect_err("the runner must refuse this SSD")
}

#[test]
fn the_systems_own_connectors_are_read_with_what_they_connect() {
    let mut read = |_: &str| Ok("<ssv:ParameterSet xmlns:ssv=\"x\"/>".to_owned());
    let s = parse_ssd(
        &ssd(&format!(
            r#"<ssd:Connectors><ssd:Connector name="cmd" kind="input"><ssc:Real unit="m"/></ssd:Connector>
            <ssd:Connector name="out" kind="output"/></ssd:Connectors>{TWO_LAGS}
            <ssd:Connections><ssd:Connection startConnector="cmd" endElement="a" endConnector="u"/>
            <ssd:Connection startConnector="cmd" endElement="b" endConnector="u"/>
            <ssd:Connection startElement="b" startConnector="y" endConnector="out"/></ssd:Connections>"#
        )),
        &mut read,
    )
    .expect("an SSD with system connectors");
    assert!(s.connections.is_empty());
    let names: Vec<(&str, &str, Option<&str>)> = s
        .connectors
        .iter()
        .map(|c| (c.name.as_str(), c.kind.as_str(), c.unit.as_deref()))
        .collect();
    assert_eq!(names, vec![("cmd", "input", Some("m")), ("out", "output", None)]);
    assert_eq!(
        s.connectors[0].links,
        vec![("a".to_owned(), "u".to_owned()), ("b".to_owned(), "u".to_owned())]
    );
    assert_eq!(s.connectors[1].links, vec![("b".to_owned(), "y".to_owned())]);
}

#[test]
fn system_connectors_the_runner_cannot_use_are_refused_naming_them() {
    // Undeclared.
    let e = refused(&format!(
        r#"{TWO_LAGS}<ssd:Connections><ssd:Connection startConnector="cmd" endElement="b" endConnector="u"/></ssd:Connections>"#
    ));
    assert!(
        e.message.contains("<system>.cmd -> b.u") && e.message.contains("has no connector 'cmd'"),
        "{e}"
    );
    // Of the wrong kind, and an output fed twice.
    let e = refused(&format!(
        r#"<ssd:Connectors><ssd:Connector name="cmd" kind="parameter"/></ssd:Connectors>{TWO_LAGS}
        <ssd:Connections><ssd:Connection startConnector="cmd" endElement="b" endConnector="u"/></ssd:Connections>"#
    ));
    assert_eq!(e.kind, ErrorKind::Unsupported);
    assert!(e.message.contains("is of kind 'parameter'"), "{e}");
    let e = refused(&format!(
        r#"<ssd:Connectors><ssd:Connector name="out" kind="output"/></ssd:Connectors>{TWO_LAGS}
        <ssd:Connections><ssd:Connection startElement="a" startConnector="y" endConnector="out"/>
        <ssd:Connection startElement="b" startConnector="y" endConnector="out"/></ssd:Connections>"#
    ));
    assert!(e.message.contains("fed by more than one connection"), "{e}");
    // From the system to itself.
    let e = refused(&format!(
        r#"<ssd:Connectors><ssd:Connector name="i" kind="input"/><ssd:Connector name="o" kind="output"/></ssd:Connectors>{TWO_LAGS}
        <ssd:Connections><ssd:Connection startConnector="i" endConnector="o"/></ssd:Connections>"#
    ));
    assert!(e.message.contains("passes a value through itself"), "{e}");
}

#[test]
fn transformations_unit_conversions_and_nested_systems_are_refused() {
    let e = refused(&format!(
        r#"{TWO_LAGS}<ssd:Connections><ssd:Connection startElement="a" startConnector="y" endElement="b" endConnector="u">
        <ssc:LinearTransformation factor="2"/></ssd:Connection></ssd:Connections>"#
    ));
    assert!(
        e.message.contains("a.y -> b.u") && e.message.contains("LinearTransformation"),
        "{e}"
    );
    assert_eq!((e.component.as_deref(), e.variable.as_deref()), (Some("b"), Some("u")));

    let body = TWO_LAGS.replacen(
        r#"<ssc:Real unit="m"/></ssd:Connector></ssd:Connectors>
    <ssd:ParameterBindings><ssd:ParameterBinding source"#,
        r#"<ssc:Real unit="mm"/></ssd:Connector></ssd:Connectors>
    <ssd:ParameterBindings><ssd:ParameterBinding source"#,
        1,
    );
    let e = refused(&format!(
        r#"{body}<ssd:Connections><ssd:Connection startElement="a" startConnector="y" endElement="b" endConnector="u"/></ssd:Connections>"#
    ));
    assert!(
        e.message.contains("unit conversion from 'm' to 'mm'") && e.message.contains("a.y -> b.u"),
        "{e}"
    );

    let e = refused(r#"<ssd:Elements><ssd:System name="Inner"/></ssd:Elements>"#);
    assert!(e.message.contains("subsystem 'Inner'"), "{e}");

    // implementation="ModelExchange" is read (the runner integrates the component); an
    // implementation SSP does not define is refused.
    let mut read = |_: &str| Ok("<ssv:ParameterSet xmlns:ssv=\"x\"/>".to_owned());
    let s = parse_ssd(
        &ssd(r#"<ssd:Elements><ssd:Component name="m" source="resources/M.fmu" implementation="ModelExchange"/></ssd:Elements>"#),
        &mut read,
    )
    .expect("implementation=ModelExchange is read");
    assert!(s.components[0].model_exchange);
    let e = refused(
        r#"<ssd:Elements><ssd:Component name="m" source="resources/M.fmu" implementation="ScheduledExecution"/></ssd:Elements>"#,
    );
    assert!(
        e.message.contains("component 'm'") && e.message.contains("ScheduledExecution"),
        "{e}"
    );
}

/// An SSP archive with one component whose FMU's modelDescription.xml is `md`.
fn archive_with(md: &str, dir: &Path) -> PathBuf {
    let mut fmu = Vec::new();
    {
        let mut z = zip::ZipWriter::new(std::io::Cursor::new(&mut fmu));
        z.start_file("modelDescription.xml", zip::write::SimpleFileOptions::default())
            .unwrap();
        z.write_all(md.as_bytes()).unwrap();
        z.finish().unwrap();
    }
    let path = dir.join("one.ssp");
    let mut z = zip::ZipWriter::new(std::fs::File::create(&path).unwrap());
    let opts = zip::write::SimpleFileOptions::default();
    z.start_file("SystemStructure.ssd", opts).unwrap();
    z.write_all(
        ssd(r#"<ssd:Elements><ssd:Component name="plant3" source="resources/M3.fmu"/></ssd:Elements>"#).as_bytes(),
    )
    .unwrap();
    z.start_file("resources/M3.fmu", opts).unwrap();
    z.write_all(&fmu).unwrap();
    z.finish().unwrap();
    path
}

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rustfmu-runner-test-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The error of a system whose one component has the description `md` (in a folder of its own,
/// `dir`), which must be refused (`why`).
fn refused_with(md: &str, dir: &str, why: &str) -> rustfmu_runner::Error {
    Simulation::from_ssp(&archive_with(md, &tmpdir(dir))).err().expect(why)
}

#[test]
fn an_fmu_the_runner_cannot_import_is_refused_naming_the_component() {
    // FMI 3.0 is read, but this one has no binary for the platform.
    let e = refused_with(
        r#"<?xml version="1.0"?><fmiModelDescription fmiVersion="3.0" modelName="M3" instantiationToken="x"><CoSimulation modelIdentifier="M3"/><ModelVariables/></fmiModelDescription>"#,
        "fmi3",
        "an FMU without a binary must be refused",
    );
    assert!(
        e.message.contains("component 'plant3'") && e.message.contains("no binary for this platform"),
        "{e}"
    );
    let e = refused_with(
        r#"<?xml version="1.0"?><fmiModelDescription fmiVersion="4.0" modelName="M3" instantiationToken="x"><CoSimulation modelIdentifier="M3"/></fmiModelDescription>"#,
        "fmi4",
        "an FMI 4.0 FMU must be refused",
    );
    assert_eq!(e.kind, ErrorKind::Unsupported);
    assert!(
        e.message.contains("component 'plant3'") && e.message.contains("FMI 4.0"),
        "{e}"
    );
    let dir = tmpdir("fmi3");
    let e = match Simulation::from_ssp(&dir.join("missing.ssp")) {
        Err(e) => e,
        Ok(_) => panic!("a missing file must be refused"),
    };
    assert!(
        e.message.contains("missing.ssp") && e.message.contains("cannot open"),
        "{e}"
    );
    std::fs::remove_dir_all(dir).ok();
}

/// `target/fmu/<name>.ssp` (honours CARGO_TARGET_DIR).
fn packaged(name: &str) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf();
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .map_or(root.join("target"), |t| if t.is_absolute() { t } else { root.join(t) });
    let p = target.join("fmu").join(format!("{name}.ssp"));
    assert!(
        p.exists(),
        "{} is missing: run `cargo run --release -p fmu-build` first",
        p.display()
    );
    p
}

fn motors() -> Simulation {
    Simulation::from_ssp(&packaged("PendulumMotors")).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn the_motor_loop_is_evaluated_plant_controller_motors_and_holds_the_pendulum() {
    let mut sim = motors();
    assert_eq!(sim.evaluation_order(), ["pendulum", "controller", "motor1", "motor2"]);
    let mut opts = RunOptions::new(10.0, 1e-3);
    opts.record = vec![
        "pendulum.alpha1".into(),
        "pendulum.alpha2".into(),
        "controller.mode".into(),
    ];
    let mut points = 0;
    let r = sim
        .run(&opts, &mut |_, _| points += 1)
        .unwrap_or_else(|f| panic!("{f}"));
    assert_eq!(points, 10_001);
    assert_eq!(r.time.len(), 10_001);
    assert_eq!(r.time[10_000], 10.0);
    let a1 = r.column(0);
    assert_eq!(a1[0], 0.1, "the SSD's alpha1_0 = 0.1 rad");
    assert!(
        a1[10_000].abs() < 1e-3,
        "held within 1e-3 rad after 10 s: {}",
        a1[10_000]
    );
    assert_eq!(
        r.column(2)[0],
        3.0,
        "the SSD's mode = 3 (LQR + PID), an Integer recorded"
    );
    // A second run on the same instances (fmi2Reset) computes the same numbers.
    let again = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    assert_eq!(again.values, r.values);
}

#[test]
fn overrides_apply_per_run_and_a_stop_condition_ends_it() {
    let mut sim = motors();
    let mut opts = RunOptions::new(5.0, 1e-3);
    opts.record = vec!["pendulum.alpha1".into()];
    opts.overrides = vec![("pendulum.alpha1_0".into(), Override::Text("0.2".into()))];
    let r = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    assert_eq!(r.values[0], 0.2);
    // Far out, PID only: the pendulum falls and the run stops where |alpha1| > pi/2.
    opts.overrides = vec![
        ("pendulum.alpha1_0".into(), Override::Real(1.2)),
        ("controller.mode".into(), Override::Integer(2)),
    ];
    opts.stop_when_above = vec![("pendulum.alpha1".into(), std::f64::consts::FRAC_PI_2)];
    let r = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    assert!(r.stopped && r.time.len() < 5001, "expected a fall before 5 s");
    assert!(r.values.last().unwrap().abs() > std::f64::consts::FRAC_PI_2);
    // The next run is the nominal one again: overrides do not stick.
    opts.overrides.clear();
    opts.stop_when_above.clear();
    let r = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    assert_eq!(r.values[0], 0.1);
}

#[test]
fn an_unknown_variable_or_component_is_named_with_what_exists() {
    let mut sim = motors();
    let mut opts = RunOptions::new(0.01, 1e-3);
    // The failure of a run with the one override `key` = `value` (`why` it must fail).
    let mut refused = |key: &str, value: Override, why: &str| {
        opts.overrides = vec![(key.into(), value)];
        sim.run(&opts, &mut |_, _| {}).expect_err(why)
    };
    let f = refused(
        "pendulum.alpha9_0",
        Override::Real(0.2),
        "an unknown variable must be refused",
    );
    assert_eq!(f.error.kind, ErrorKind::Variable);
    assert!(
        f.error
            .message
            .contains("component 'pendulum' (Pendulum): no variable 'alpha9_0'")
            && f.error.message.contains("alpha1_0"),
        "{f}"
    );
    let f = refused(
        "pendulun.alpha1_0",
        Override::Real(0.2),
        "an unknown component must be refused",
    );
    assert!(
        f.error.message.contains("no component 'pendulun'") && f.error.message.contains("motor1"),
        "{f}"
    );
    let f = refused(
        "controller.mode",
        Override::Text("LQR".into()),
        "an item name is not an integer",
    );
    assert!(
        f.error.message.contains("controller.mode") && f.error.message.contains("item's value"),
        "{f}"
    );
}

#[test]
fn an_fmu_refusing_a_value_fails_the_run_naming_component_variable_and_function() {
    let mut sim = motors();
    let mut opts = RunOptions::new(0.1, 1e-3);
    opts.record = vec!["pendulum.alpha1".into()];
    opts.overrides = vec![("pendulum.m1".into(), Override::Real(-1.0))];
    let f = sim
        .run(&opts, &mut |_, _| {})
        .expect_err("m1 = -1 kg must be refused by the FMU");
    assert_eq!(f.error.kind, ErrorKind::Fmi);
    assert_eq!(f.error.component.as_deref(), Some("pendulum"));
    assert_eq!(f.error.variable.as_deref(), Some("m1"));
    assert_eq!(f.error.function.as_deref(), Some("fmi2SetReal"));
    assert!(
        f.error.message.contains("component 'pendulum'") && f.error.message.contains("m1 = -1"),
        "{f}"
    );
    assert!(f.partial.time.is_empty());
    // The simulation is usable again after the failure.
    opts.overrides.clear();
    let r = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    assert_eq!(r.time.len(), 101);
}

#[test]
fn gauss_seidel_and_jacobi_differ_on_the_controller_loop() {
    let mut sim = Simulation::from_ssp(&packaged("PendulumLQR")).unwrap_or_else(|e| panic!("{e}"));
    let mut opts = RunOptions::new(1.0, 2e-3);
    opts.record = vec!["pendulum.alpha1".into()];
    let gs = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    sim.scheme = rustfmu_runner::Scheme::Jacobi;
    let j = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    assert_eq!(
        gs.values[..2],
        j.values[..2],
        "the same up to the first step of the delayed controller"
    );
    assert_ne!(gs.values.last(), j.values.last());
}

// The values of FMI 3.0 variables of every type (runner/src/values.rs).
#[test]
fn an_fmi3_array_start_is_read_in_order_and_its_length_checked() {
    use md_reader::fmi3::Type;
    use rustfmu_runner::values::Values;
    assert_eq!(
        Values::parse(Type::Float64, 3, "1 0 2.5").unwrap(),
        Values::Float64(vec![1.0, 0.0, 2.5])
    );
    assert!(
        Values::parse(Type::Float64, 3, "1 0")
            .unwrap_err()
            .contains("2 value(s) given")
    );
    assert!(Values::parse(Type::UInt8, 1, "256").unwrap_err().contains("UInt8"));
    assert_eq!(
        Values::parse(Type::Binary, 1, "666f6f").unwrap(),
        Values::Binary(vec![b"foo".to_vec()])
    );
    assert_eq!(
        Values::parse(Type::String, 1, "a b").unwrap(),
        Values::String(vec![b"a b\0".to_vec()])
    );
}

#[test]
fn an_fmi3_number_is_range_checked_for_each_integer_type() {
    use md_reader::fmi3::Type;
    use rustfmu_runner::values::Values;
    assert_eq!(
        Values::from_number(Type::Int8, 0.0, Some(-128)).unwrap(),
        Values::Int8(vec![-128])
    );
    assert!(Values::from_number(Type::Int8, 0.0, Some(128)).is_err());
    assert!(Values::from_number(Type::UInt64, 0.0, Some(-1)).is_err());
    assert!(Values::from_number(Type::Int16, 1.5, None).is_err());
    assert_eq!(
        Values::from_number(Type::Float32, 0.1, None).unwrap(),
        Values::Float32(vec![0.1f32])
    );
}

// ---- SSP 2.0: structural parameters set by the system, arrays of ssv:Value elements ----------

/// The C Reference-FMUs' FMI 3.0 `name` (shared/independent).
fn reference3(name: &str) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf();
    let p = root.join(format!("../shared/independent/reference-fmus/3.0/{name}.fmu"));
    assert!(p.exists(), "{} is missing (the C Reference-FMUs)", p.display());
    p
}

/// An SSP 2.0 archive `file` in `dir`: `body` the system's content, `fmus` (resource name, path).
fn archive2(dir: &Path, file: &str, body: &str, fmus: &[(&str, PathBuf)]) -> PathBuf {
    let xml = format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
  xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
  xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="2.0" name="T"><ssd:System name="Sys">{body}</ssd:System></ssd:SystemStructureDescription>"#
    );
    let path = dir.join(file);
    let mut z = zip::ZipWriter::new(std::fs::File::create(&path).unwrap());
    let opts = zip::write::SimpleFileOptions::default();
    z.start_file("SystemStructure.ssd", opts).unwrap();
    z.write_all(xml.as_bytes()).unwrap();
    for (name, fmu) in fmus {
        z.start_file(format!("resources/{name}"), opts).unwrap();
        z.write_all(&std::fs::read(fmu).unwrap()).unwrap();
    }
    z.finish().unwrap();
    path
}

/// A component of the Reference StateSpace with the inline parameter values `params`
/// (`ssv:Parameter` elements).
fn state_space(name: &str, connectors: &str, params: &str) -> String {
    format!(
        r#"<ssd:Component name="{name}" source="resources/StateSpace.fmu" type="application/x-fmu-sharedlibrary">{connectors}<ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version="2.0" name="p"><ssv:Parameters>{params}</ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings></ssd:Component>"#
    )
}

fn uint64(name: &str, v: u64) -> String {
    format!(r#"<ssv:Parameter name="{name}"><ssv:UInt64 value="{v}"/></ssv:Parameter>"#)
}

fn float64s(name: &str, v: &str, dims: &[usize]) -> String {
    let d: String = dims.iter().map(|n| format!(r#"<ssc:Dimension size="{n}"/>"#)).collect();
    format!(r#"<ssv:Parameter name="{name}"><ssv:Float64 value="{v}"/>{d}</ssv:Parameter>"#)
}

/// This project's FMI 3.0 StateSpace (the Reference-FMUs' re-make: their names, value
/// references and start values), packaged by `cargo fmu build`.
fn our_state_space() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf();
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .map_or(root.join("target"), |t| if t.is_absolute() { t } else { root.join(t) });
    let p = target.join("fmu/fmi3/StateSpace.fmu");
    assert!(p.exists(), "{} is missing: run `cargo fmu build` first", p.display());
    p
}

/// Two StateSpaces of `fmu`, s1.y into s2.u, s1 of sizes (m, n, r) = (2, 2, 2) and s2 of
/// (`m2`, 4, 2): every array sized by the values the system gives, not the start values (3).
fn two_state_spaces(dir: &Path, m2: u64, fmu: PathBuf) -> PathBuf {
    let y = r#"<ssd:Connectors><ssd:Connector name="y" kind="output"><ssc:Float64/><ssc:Dimension sizeConnector="r"/></ssd:Connector><ssd:Connector name="r" kind="structuralParameter"><ssc:UInt64/></ssd:Connector></ssd:Connectors>"#;
    let u = r#"<ssd:Connectors><ssd:Connector name="u" kind="input"><ssc:Float64/><ssc:Dimension sizeConnector="m"/></ssd:Connector><ssd:Connector name="m" kind="structuralParameter"><ssc:UInt64/></ssd:Connector></ssd:Connectors>"#;
    let s1 = [
        uint64("m", 2),
        uint64("n", 2),
        uint64("r", 2),
        float64s("A", "-1 0 0 -2", &[2, 2]),
        float64s("B", "1 0 0 1", &[2, 2]),
        float64s("C", "1 0 0 1", &[2, 2]),
        float64s("D", "1 0 0 1", &[2, 2]),
        float64s("x0", "0 0", &[2]),
        float64s("u", "1 2", &[2]),
    ]
    .concat();
    let m = m2 as usize;
    let eye = |r: usize, c: usize, x: f64| -> String {
        (0..r * c)
            .map(|k| if k / c == k % c { x.to_string() } else { "0".into() })
            .collect::<Vec<_>>()
            .join(" ")
    };
    let s2 = [
        uint64("n", 4),
        uint64("r", 2),
        uint64("m", m2),
        float64s("A", &eye(4, 4, -1.0), &[4, 4]),
        float64s("B", &eye(4, m, 1.0), &[4, m]),
        float64s("C", &eye(2, 4, 1.0), &[2, 4]),
        float64s("D", &eye(2, m, 0.5), &[2, m]),
    ]
    .concat();
    let body = format!(
        r#"<ssd:Elements>{}{}</ssd:Elements><ssd:Connections><ssd:Connection startElement="s1" startConnector="y" endElement="s2" endConnector="u"/></ssd:Connections>"#,
        state_space("s1", y, &s1),
        state_space("s2", u, &s2)
    );
    archive2(dir, &format!("ss{m2}.ssp"), &body, &[("StateSpace.fmu", fmu)])
}

#[test]
fn structural_parameters_the_system_sets_size_connections_parameters_and_records() {
    let dir = tmpdir("structural");
    let mut sim = Simulation::from_ssp(&two_state_spaces(&dir, 2, our_state_space())).unwrap_or_else(|e| panic!("{e}"));
    let mut opts = RunOptions::new(0.5, 0.25);
    opts.record = vec!["s1.y".into(), "s2.y".into(), "s2.x".into()];
    let r = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    // The columns: y of 2 (r = 2), x of 4 (n = 4), not the start values' 3.
    assert_eq!(
        r.names,
        [
            "s1.y[1]", "s1.y[2]", "s2.y[1]", "s2.y[2]", "s2.x[1]", "s2.x[2]", "s2.x[3]", "s2.x[4]"
        ]
    );
    // t = 0: y1 = x1 + u1 = (1, 2) (x0 = 0, C = D = I); y2 = 0.5 y1 (x2 = 0).
    assert_eq!(&r.values[..4], &[1.0, 2.0, 0.5, 1.0]);
    // s2's states driven by y1 through B = [I; 0]: the last two stay 0.
    let last = &r.values[r.values.len() - 8..];
    assert!(
        last[4] > 0.0 && last[5] > 0.0 && last[6] == 0.0 && last[7] == 0.0,
        "{last:?}"
    );
    // A second run configures the reset instances again.
    let again = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    assert_eq!(again.values, r.values);
    // An override of a structural parameter keeps the size the system was built with.
    opts.overrides = vec![("s2.n".into(), Override::Integer(3))];
    let Err(e) = sim.run(&opts, &mut |_, _| {}) else {
        panic!("a size the run changes is refused")
    };
    assert!(
        e.error.message.contains("s2.n") && e.error.message.contains("(4 in this system)"),
        "{}",
        e.error.message
    );
    opts.overrides = vec![("s2.n".into(), Override::Integer(4))];
    let same = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    assert_eq!(same.values, r.values);
    // The C Reference-FMUs' StateSpace (v0.0.41) refuses every structural parameter in
    // Configuration Mode (its fmi3SetUInt64 takes the value before checking nValues; fixed
    // upstream since): the run fails naming the call, the value and what the FMU said.
    let mut theirs =
        Simulation::from_ssp(&two_state_spaces(&dir, 2, reference3("StateSpace"))).unwrap_or_else(|e| panic!("{e}"));
    let Err(e) = theirs.run(&opts, &mut |_, _| {}) else {
        panic!("theirs refuses m")
    };
    assert!(
        e.error.message.contains("component 's1': fmi3SetUInt64 (m = 2)")
            && e.error.message.contains("Expected nValues >= 2 but was 1"),
        "{}",
        e.error.message
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn model_exchange_components_whose_structural_parameters_the_system_sets_integrate_their_states() {
    // The two StateSpaces of sizes (2, 2, 2) and (2, 4, 2) run as model exchange: the runner
    // integrates the number of states fmi3GetNumberOfContinuousStates gives after
    // Configuration Mode (2 and 4), not the start values' 3.
    let dir = tmpdir("structural-me");
    let ssp = two_state_spaces(&dir, 2, our_state_space());
    let mut opts = RunOptions::new(2.0, 0.1);
    opts.record = vec!["s1.y".into(), "s2.y".into(), "s2.x".into()];
    let cs = Simulation::from_ssp(&ssp)
        .unwrap_or_else(|e| panic!("{e}"))
        .run(&opts, &mut |_, _| {})
        .unwrap_or_else(|f| panic!("{f}"));
    let mut sim = Simulation::from_ssp(&ssp).unwrap_or_else(|e| panic!("{e}"));
    for c in ["s1", "s2"] {
        sim.use_model_exchange(c).unwrap_or_else(|e| panic!("{e}"));
        assert!(sim.is_model_exchange(c));
    }
    let me = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    assert_eq!((&me.names, &me.time), (&cs.names, &cs.time));
    let width = me.names.len();
    for (k, (a, b)) in me.values.chunks(width).zip(cs.values.chunks(width)).enumerate() {
        let t = me.time[k];
        // s1 (A = diag(-1, -2), B = C = D = I, u = (1, 2), x0 = 0): y = x + u exactly.
        let y1 = [2.0 - (-t).exp(), 3.0 - (-2.0 * t).exp()];
        for j in 0..2 {
            assert!(
                (a[j] - y1[j]).abs() < 1e-5,
                "t = {t}: s1.y[{}] {} against {}",
                j + 1,
                a[j],
                y1[j]
            );
        }
        // s2 (4 states) against the same system in co-simulation.
        for j in 0..width {
            assert!(
                (a[j] - b[j]).abs() < 1e-5 * (1.0 + b[j].abs()),
                "t = {t}: {} {} (model exchange) against {} (co-simulation)",
                me.names[j],
                a[j],
                b[j]
            );
        }
        // The last two of s2's four states are not driven (B = [I; 0]).
        assert_eq!((a[6], a[7]), (0.0, 0.0), "t = {t}");
    }
    assert!(
        me.values[me.values.len() - 4] > 0.5,
        "{:?}",
        &me.values[me.values.len() - 8..]
    );
    // A second run configures the reset instances again, with the same rows.
    let again = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    assert_eq!(again.values, me.values);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn a_connection_of_arrays_the_system_sizes_differently_names_both_ends_dimensions() {
    let dir = tmpdir("structural-mismatch");
    let e = Simulation::from_ssp(&two_state_spaces(&dir, 3, reference3("StateSpace")))
        .err()
        .expect("2 outputs into 3 inputs");
    assert!(
        e.message
            .contains("connection s1.y -> s2.u: s1.y is Float64[2] and s2.u is Float64[3]")
            && e.message.contains("s1.y [r = 2], s2.u [m = 3]"),
        "{e}"
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn ssv_value_elements_are_read_and_set() {
    // Arrays of ssv:Value elements, read in order (and an empty one).
    let xml = r#"<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
  xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
  xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="2.0" name="T"><ssd:System name="Sys"><ssd:Elements>
  <ssd:Component name="a" source="resources/A.fmu"><ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version="2.0" name="p"><ssv:Parameters>
    <ssv:Parameter name="s"><ssv:String><ssv:Value value="one two"/><ssv:Value value=""/><ssv:Value value="&lt;3&gt;"/></ssv:String><ssc:Dimension size="3"/></ssv:Parameter>
    <ssv:Parameter name="e"><ssv:Enumeration name="Option"><ssv:Value value="Option 2"/><ssv:Value value="Option 1"/></ssv:Enumeration><ssc:Dimension size="2"/></ssv:Parameter>
    <ssv:Parameter name="b"><ssv:Binary><ssv:Value value="0aFF"/></ssv:Binary></ssv:Parameter>
    <ssv:Parameter name="none"><ssv:String/><ssc:Dimension size="0"/></ssv:Parameter>
    <ssv:Parameter name="x"><ssv:String value="scalar"/></ssv:Parameter>
  </ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings></ssd:Component>
</ssd:Elements></ssd:System></ssd:SystemStructureDescription>"#;
    let s = parse_ssd(xml, &mut |f: &str| panic!("no file {f}")).unwrap_or_else(|e| panic!("{e}"));
    let items = |ty: &str, v: &[&str]| Value::Items {
        ty: ty.into(),
        items: v.iter().map(|x| x.to_string()).collect(),
    };
    assert_eq!(
        s.components[0].parameters,
        vec![
            ("s".to_owned(), items("String", &["one two", "", "<3>"])),
            ("e".to_owned(), items("Enumeration", &["Option 2", "Option 1"])),
            ("b".to_owned(), items("Binary", &["0aFF"])),
            ("none".to_owned(), items("String", &[])),
            ("x".to_owned(), Value::String("scalar".into())),
        ]
    );
    // A Binary ssv:Value that is no hexBinary is refused, naming the parameter.
    let bad = xml.replace("0aFF", "0aF");
    let Err(e) = parse_ssd(&bad, &mut |f: &str| panic!("no file {f}")) else {
        panic!("an odd hexBinary")
    };
    assert!(
        e.message.contains("parameter 'b'") && e.message.contains("'0aF'"),
        "{e}"
    );

    // Set: the Reference Feedthrough's Enumeration, String and Binary inputs from one ssv:Value
    // each (SSP 2.0: "for scalar and one element array parameters the Value element CAN be
    // used"); the Enumeration by its item's name, seen at its output.
    let dir = tmpdir("ssv-values");
    let body = r#"<ssd:Elements><ssd:Component name="f" source="resources/Feedthrough.fmu" type="application/x-fmu-sharedlibrary"><ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version="2.0" name="p"><ssv:Parameters>
      <ssv:Parameter name="Enumeration_input"><ssv:Enumeration name="Option"><ssv:Value value="Option 2"/></ssv:Enumeration></ssv:Parameter>
      <ssv:Parameter name="String_input"><ssv:String><ssv:Value value="a string"/></ssv:String></ssv:Parameter>
      <ssv:Parameter name="Binary_input"><ssv:Binary><ssv:Value value="0102ff"/></ssv:Binary></ssv:Parameter>
    </ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings></ssd:Component></ssd:Elements>"#;
    let path = archive2(&dir, "f.ssp", body, &[("Feedthrough.fmu", reference3("Feedthrough"))]);
    let mut sim = Simulation::from_ssp(&path).unwrap_or_else(|e| panic!("{e}"));
    let mut opts = RunOptions::new(0.1, 0.1);
    opts.record = vec!["f.Enumeration_output".into()];
    let r = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    assert_eq!(r.values, [2.0, 2.0]);
    // An item the Enumeration does not have, and two values for a scalar, are refused.
    let e = Simulation::from_ssp(&archive2(
        &dir,
        "g.ssp",
        &body.replace(r#"value="Option 2""#, r#"value="Option 3""#),
        &[("Feedthrough.fmu", reference3("Feedthrough"))],
    ))
    .err()
    .expect("no item 'Option 3'");
    assert!(
        e.message.contains("Option 3") && e.message.contains("Option 1, Option 2"),
        "{e}"
    );
    let e = Simulation::from_ssp(&archive2(
        &dir,
        "h.ssp",
        &body.replace(
            r#"<ssv:Value value="0102ff"/>"#,
            r#"<ssv:Value value="01"/><ssv:Value value="02"/>"#,
        ),
        &[("Feedthrough.fmu", reference3("Feedthrough"))],
    ))
    .err()
    .expect("two Binary values for a scalar");
    assert!(
        e.message.contains("Binary_input") && e.message.contains("2 value(s) given, the variable has 1"),
        "{e}"
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn an_array_takes_the_sizes_its_structural_parameters_have_in_force() {
    use md_reader::fmi3::Type;
    use rustfmu_runner::fmi3::Var3;
    // A (n x m), n (vr 2) and m (vr 1) structural parameters of start 3, one fixed dimension.
    let a = Var3 {
        name: "A".into(),
        vr: 4,
        ty: Type::Float64,
        causality: md_reader::Causality::Parameter,
        shape: vec![3, 3, 2],
        dims: vec![Some((2, "n".into())), Some((1, "m".into())), None],
        start: None,
        unit: None,
        declared_type: None,
    };
    assert_eq!(
        (a.count(), a.kind(), a.dimensions()),
        (18, "Float64[3,3,2]".into(), "[n = 3,m = 3,2]".into())
    );
    // n set to 4, m not set (its start value stays), an unrelated value reference ignored.
    let b = a.sized(&[(2, 4), (7, 9)]);
    assert_eq!(b.shape, [4, 3, 2]);
    assert_eq!(
        (b.count(), b.kind(), b.dimensions()),
        (24, "Float64[4,3,2]".into(), "[n = 4,m = 3,2]".into())
    );
    // A size of 0: an empty array.
    assert_eq!(a.sized(&[(1, 0)]).count(), 0);
    // A scalar has no dimensions.
    let s = Var3 {
        shape: Vec::new(),
        dims: Vec::new(),
        ..a.clone()
    };
    assert_eq!((s.sized(&[(2, 4)]).count(), s.dimensions()), (1, String::new()));
}

#[test]
fn string_and_binary_values_are_made_from_ssv_value_items() {
    use md_reader::fmi3::Type;
    use rustfmu_runner::values::Values;
    let items = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    assert_eq!(
        Values::from_items(Type::String, 2, &items(&["a b", ""])),
        Ok(Values::String(vec![b"a b\0".to_vec(), b"\0".to_vec()]))
    );
    assert_eq!(
        Values::from_items(Type::Binary, 2, &items(&["00ff", ""])),
        Ok(Values::Binary(vec![vec![0, 255], Vec::new()]))
    );
    let e = Values::from_items(Type::String, 3, &items(&["a", "b"])).unwrap_err();
    assert!(e.contains("2 value(s) given, the variable has 3"), "{e}");
    let e = Values::from_items(Type::Binary, 1, &items(&["0g"])).unwrap_err();
    assert!(e.contains("'0g' is not hexadecimal bytes"), "{e}");
    let e = Values::from_items(Type::Float64, 1, &items(&["1"])).unwrap_err();
    assert!(e.contains("for a Float64 variable"), "{e}");
}
