//! Where the runner's integration tests find their FMUs: ours in the workspace's `target/fmu`
//! (built by `cargo fmu build`), the C Reference-FMUs in `../shared/independent`.
//! (`mod support;` in each test file that needs it; not every file uses every function.)
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// The workspace's root folder.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

/// `target/fmu/<name>.fmu` (FMI 2.0) or `target/fmu/fmi3/<name>.fmu`, honouring
/// CARGO_TARGET_DIR; fails saying how to build it.
pub fn ours(name: &str, fmi3: bool) -> PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .map_or(
            root().join("target"),
            |t| if t.is_absolute() { t } else { root().join(t) },
        );
    let folder = if fmi3 { "fmu/fmi3" } else { "fmu" };
    let p = target.join(folder).join(format!("{name}.fmu"));
    assert!(
        p.exists(),
        "{} is missing: build it with `cargo fmu build` (`cargo run --release -p fmu-build`)",
        p.display()
    );
    p
}

/// The C Reference-FMUs' `name` of FMI `version` ("2.0" or "3.0").
pub fn theirs(version: &str, name: &str) -> PathBuf {
    let p = root().join(format!("../shared/independent/reference-fmus/{version}/{name}.fmu"));
    assert!(
        p.exists(),
        "{} is missing (the C Reference-FMUs v0.0.41 of shared/independent)",
        p.display()
    );
    p
}

// Systems of FMI 3.0 clocks (scheduled.rs, isolated_clocks.rs).

use rustfmu_runner::fmu::Fmu;
use rustfmu_runner::isolate::Isolation;
use rustfmu_runner::ssp::Connection;
use rustfmu_runner::{RunResult, Simulation, Value};
use std::io::Write;

fn connect(pairs: &[(&str, &str, &str, &str)]) -> Vec<Connection> {
    pairs
        .iter()
        .map(|(a, x, b, y)| Connection {
            start: (a.to_string(), x.to_string()),
            end: (b.to_string(), y.to_string()),
        })
        .collect()
}

/// A system of `components` (name, FMU file) with `connections` and `parameters`.
pub fn system(
    components: &[(&str, &Path)],
    connections: &[(&str, &str, &str, &str)],
    parameters: Vec<(String, String, Value)>,
) -> Simulation {
    system_isolated(components, connections, parameters, None)
}

/// [`system`], each component in a child process of its own with `isolation`.
pub fn system_isolated(
    components: &[(&str, &Path)],
    connections: &[(&str, &str, &str, &str)],
    parameters: Vec<(String, String, Value)>,
    isolation: Option<Isolation>,
) -> Simulation {
    let fmus = components
        .iter()
        .map(|(c, p)| Fmu::from_path(c, p).unwrap_or_else(|e| panic!("{e}")))
        .collect();
    let names = components
        .iter()
        .enumerate()
        .map(|(i, (c, _))| (c.to_string(), i))
        .collect();
    Simulation::new_with("S", fmus, names, &connect(connections), parameters, isolation)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The first row where `a` and `b` differ (time or any value, bit for bit), or None.
pub fn first_difference(a: &RunResult, b: &RunResult) -> Option<String> {
    assert_eq!(a.names, b.names);
    if a.time.len() != b.time.len() {
        return Some(format!(
            "{} rows against {}: {:?} / {:?}",
            a.time.len(),
            b.time.len(),
            a.time,
            b.time
        ));
    }
    let m = a.names.len();
    (0..a.time.len()).find_map(|k| {
        let (ra, rb) = (&a.values[k * m..(k + 1) * m], &b.values[k * m..(k + 1) * m]);
        (a.time[k].to_bits() != b.time[k].to_bits() || ra.iter().zip(rb).any(|(x, y)| x.to_bits() != y.to_bits()))
            .then(|| format!("row {k}: t = {} {ra:?} against t = {} {rb:?}", a.time[k], b.time[k]))
    })
}

/// The counters of our Clocks (and the C Reference-FMUs' Clocks).
pub const COUNTERS: [&str; 6] = [
    "inClock1Ticks",
    "inClock2Ticks",
    "inClock3Ticks",
    "totalInClockTicks",
    "result2",
    "output3",
];

/// An SSP 2.0 file of two of our Clocks, `a` and `b`, with `implementation`: a's output clock
/// triggers b's inClock2, whose partition adds b.input2 (a's output3) to b.result2.
pub fn two_clocks_ssp(dir: &str, implementation: &str) -> PathBuf {
    let component = |name: &str, connectors: &str| {
        format!(
            r#"<ssd:Component name="{name}" source="resources/Clocks.fmu" type="application/x-fmu-sharedlibrary" implementation="{implementation}"><ssd:Connectors>{connectors}</ssd:Connectors></ssd:Component>"#
        )
    };
    let a = component(
        "a",
        r#"<ssd:Connector name="outClock" kind="output"><ssc:Clock/></ssd:Connector><ssd:Connector name="output3" kind="output"><ssc:Int32/></ssd:Connector>"#,
    );
    let b = component(
        "b",
        r#"<ssd:Connector name="inClock2" kind="input"><ssc:Clock/></ssd:Connector><ssd:Connector name="input2" kind="input"><ssc:Int32/></ssd:Connector>"#,
    );
    let ssd = format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
  xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" version="2.0" name="TwoClocks">
<ssd:System name="TwoClocks"><ssd:Elements>{a}{b}</ssd:Elements><ssd:Connections>
<ssd:Connection startElement="a" startConnector="outClock" endElement="b" endConnector="inClock2"/>
<ssd:Connection startElement="a" startConnector="output3" endElement="b" endConnector="input2"/>
</ssd:Connections></ssd:System></ssd:SystemStructureDescription>"#
    );
    archive(dir, "TwoClocks", &ssd, &[("Clocks", &ours("Clocks", true))])
}

/// An SSP file `<name>.ssp` in a folder of its own (`dir`) with `ssd` and `fmus` (resources/<name>.fmu).
pub fn archive(dir: &str, name: &str, ssd: &str, fmus: &[(&str, &Path)]) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rustfmu-runner-scheduled-{dir}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let path = d.join(format!("{name}.ssp"));
    let mut z = zip::ZipWriter::new(std::fs::File::create(&path).unwrap());
    let opts = zip::write::SimpleFileOptions::default();
    z.start_file("SystemStructure.ssd", opts).unwrap();
    z.write_all(ssd.as_bytes()).unwrap();
    for (n, f) in fmus {
        z.start_file(format!("resources/{n}.fmu"), opts).unwrap();
        z.write_all(&std::fs::read(f).unwrap()).unwrap();
    }
    z.finish().unwrap();
    path
}

/// The Pendulum (FMI 3.0) and the SampledController (`sample` every Ts = 10 ms), its loop closed
/// as in holonomic/systems.toml's PendulumLQR (each component isolated with `isolation`), and
/// the variables to record.
pub fn sampled_loop(isolation: Option<Isolation>) -> (Simulation, Vec<&'static str>) {
    let conns = [
        ("pendulum", "alpha1", "controller", "alpha1"),
        ("pendulum", "omega1", "controller", "omega1"),
        ("pendulum", "alpha2", "controller", "alpha2"),
        ("pendulum", "omega2", "controller", "omega2"),
        ("controller", "M1", "pendulum", "M1"),
        ("controller", "M2", "pendulum", "M2"),
    ];
    let params = vec![
        ("pendulum".into(), "alpha1_0".into(), Value::Real(0.1)),
        ("pendulum".into(), "alpha2_0".into(), Value::Real(-0.05)),
        ("controller".into(), "mode".into(), Value::Integer(1)),
    ];
    let sim = system_isolated(
        &[
            ("pendulum", &ours("Pendulum", true)),
            ("controller", &ours("SampledController", true)),
        ],
        &conns,
        params,
        isolation,
    );
    let record = vec![
        "pendulum.alpha1",
        "pendulum.omega1",
        "pendulum.alpha2",
        "pendulum.omega2",
        "controller.M1",
        "controller.M2",
        "pendulum.M1",
        "pendulum.M2",
    ];
    (sim, record)
}
