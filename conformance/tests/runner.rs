//! The runner's crash isolation, on FMU binaries that crash, abort and hang on purpose
//! (`c/bad_fmu.c`), and the `fmu-check` binary end to end.

use fmi_conformance::Version;
use fmi_conformance::archive::PrivateDir;
use fmi_conformance::checks::checks_of;
use fmi_conformance::outcome::Outcome;
use fmi_conformance::runner::{Report, RunOptions, run};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

const BAD_MD: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="Bad" guid="{bad}" generationTool="bad_fmu.c">
  <CoSimulation modelIdentifier="Bad" canHandleVariableCommunicationStepSize="true"/>
  <ModelVariables>
    <ScalarVariable name="y" valueReference="0" causality="output"><Real/></ScalarVariable>
  </ModelVariables>
  <ModelStructure><Outputs><Unknown index="1" dependencies=""/></Outputs></ModelStructure>
</fmiModelDescription>
"#;

/// `Bad.fmu` with `c/bad_fmu.c` compiled in mode `mode`, in `dir`.
fn bad_fmu(dir: &Path, mode: u32) -> PathBuf {
    let so = dir.join(format!("bad{mode}.so"));
    let src = concat!(env!("CARGO_MANIFEST_DIR"), "/c/bad_fmu.c");
    let out = Command::new("cc")
        .args(["-shared", "-fPIC", "-O1", &format!("-DMODE={mode}"), "-o"])
        .arg(&so)
        .arg(src)
        .output()
        .expect("cc (tests/setup-env.sh installs it)");
    assert!(out.status.success(), "cc: {}", String::from_utf8_lossy(&out.stderr));
    let fmu = dir.join(format!("Bad{mode}.fmu"));
    let mut w = zip::ZipWriter::new(std::fs::File::create(&fmu).unwrap());
    let opts = zip::write::SimpleFileOptions::default();
    w.start_file("modelDescription.xml", opts).unwrap();
    w.write_all(BAD_MD.as_bytes()).unwrap();
    w.start_file("binaries/linux64/Bad.so", opts).unwrap();
    w.write_all(&std::fs::read(&so).unwrap()).unwrap();
    w.finish().unwrap();
    fmu
}

fn options(temp: &Path, filter: &str) -> RunOptions {
    let mut o = RunOptions::new(env!("CARGO_BIN_EXE_fmu-check"), vec!["__worker".into()]);
    o.filter = Some(filter.into());
    o.temp_dir = Some(temp.to_path_buf());
    o.timeout = Duration::from_secs(60);
    o
}

fn failure<'a>(report: &'a Report, name: &str) -> &'a str {
    let c = report
        .checks
        .iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no {name} in the report:\n{report}"));
    match &c.outcome {
        Outcome::Fail(m) => m,
        other => panic!("{name}: expected a failure, got {other:?}\n{report}"),
    }
}

/// The run's private folder is gone afterwards, even when workers crashed in it.
fn assert_cleaned(temp: &Path) {
    let left: Vec<_> = std::fs::read_dir(temp).unwrap().flatten().map(|e| e.path()).collect();
    let left: Vec<_> = left
        .into_iter()
        .filter(|p| p.extension().is_none_or(|x| x != "fmu" && x != "so"))
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

#[test]
fn a_segfault_fails_its_check_with_the_signal_and_the_run_goes_on() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    let fmu = bad_fmu(dir.path(), 1);
    let report = run(&fmu, &options(dir.path(), "state machine"));
    assert_eq!(report.checks.len(), 5, "{report}");
    let m = failure(&report, "terminate_twice_is_refused_with_a_message");
    assert!(m.contains("killed by signal 11 (SIGSEGV)"), "{m}");
    assert!(m.contains("while doing: fmi2Instantiate("), "no breadcrumb: {m}");
    // The checks that do not instantiate still ran, in their own processes, and passed.
    let passed: Vec<&str> = report
        .checks
        .iter()
        .filter(|c| c.outcome == Outcome::Pass)
        .map(|c| c.name.as_str())
        .collect();
    assert!(passed.contains(&"version_and_platform_are_the_standards"), "{report}");
    assert!(!report.success());
    assert!(report.to_string().ends_with(&report.totals()));
    assert_cleaned(dir.path());
}

#[test]
fn an_abort_fails_its_check_with_the_signal_and_the_end_of_stderr() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    let fmu = bad_fmu(dir.path(), 2);
    let report = run(&fmu, &options(dir.path(), "terminate_twice"));
    let m = failure(&report, "terminate_twice_is_refused_with_a_message");
    assert!(m.contains("killed by signal 6 (SIGABRT)"), "{m}");
    assert!(m.contains("bad FMU: giving up with abort()"), "no stderr tail: {m}");
    assert_cleaned(dir.path());
}

#[test]
fn a_hang_fails_its_check_after_the_timeout() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    let fmu = bad_fmu(dir.path(), 3);
    let mut opts = options(dir.path(), "terminate_twice");
    opts.timeout = Duration::from_secs(2);
    let clock = Instant::now();
    let report = run(&fmu, &opts);
    assert!(clock.elapsed() < Duration::from_secs(20), "{:?}", clock.elapsed());
    let m = failure(&report, "terminate_twice_is_refused_with_a_message");
    assert!(m.contains("timed out after 2 s and was killed"), "{m}");
    assert_cleaned(dir.path());
}

#[test]
fn a_crash_after_the_result_still_fails_the_check() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    let fmu = bad_fmu(dir.path(), 4);
    let report = run(&fmu, &options(dir.path(), "version_and_platform"));
    let m = failure(&report, "version_and_platform_are_the_standards");
    assert!(
        m.contains("the check ended (passed), but then its process was killed by signal 11"),
        "{m}"
    );
    assert_cleaned(dir.path());
}

#[test]
fn an_fmu_without_a_binary_for_this_platform_is_reported_and_every_check_skipped() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    let fmu = dir.path().join("NoBinary.fmu");
    let mut w = zip::ZipWriter::new(std::fs::File::create(&fmu).unwrap());
    w.start_file("modelDescription.xml", zip::write::SimpleFileOptions::default())
        .unwrap();
    w.write_all(BAD_MD.as_bytes()).unwrap();
    w.finish().unwrap();
    let report = run(&fmu, &options(dir.path(), "calls"));
    let e = report.load_error.clone().expect("a load error");
    assert!(e.contains("no binaries/linux64/Bad.so"), "{e}");
    assert!(report.checks.iter().all(|c| matches!(c.outcome, Outcome::Skip(_))));
    assert_eq!(report.failed(), 1);
    assert!(!report.success());
}

#[test]
fn fmu_check_reports_a_packaged_fmu_and_exits_with_the_verdict() {
    let fmu = fmi_conformance::all::<fmi_conformance::Fmu>()
        .first()
        .expect("a packaged FMU")
        .archive
        .clone();
    let exe = env!("CARGO_BIN_EXE_fmu-check");
    let out = Command::new(exe)
        .arg(&fmu)
        .args(["--filter", "version_and_platform"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        stdout.contains("PASS  state machine / version_and_platform_are_the_standards"),
        "{stdout}"
    );
    assert!(stdout.contains("made by this exporter"), "{stdout}");
    assert!(
        stdout.trim_end().ends_with("1 passed, 0 failed, 0 warned, 0 skipped"),
        "{stdout}"
    );

    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    let bad = bad_fmu(dir.path(), 1);
    let out = Command::new(exe)
        .arg(&bad)
        .args(["--filter", "terminate_twice"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("FAIL  state machine / terminate_twice_is_refused_with_a_message"),
        "{stdout}"
    );
    assert!(stdout.contains("SIGSEGV"), "{stdout}");
    assert!(stdout.contains("another exporter's FMU"), "{stdout}");
    assert!(
        stdout.trim_end().ends_with("0 passed, 1 failed, 0 warned, 0 skipped"),
        "{stdout}"
    );

    let out = Command::new(exe)
        .args(["--filter", "nothing matches this"])
        .arg(&fmu)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

/// Checks `fmu` with `--as-foreign` and 200 random sequences: every one of the `n_checks` checks
/// passes (partly, at least one), none fails, warns or is skipped but for what the FMU does not declare
/// (Model Exchange, directional derivatives), and the report says it was taken for another
/// exporter's.
fn every_check_passes_as_another_exporters(fmu: &Path, n_checks: usize) {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    let mut opts = options(dir.path(), "");
    opts.filter = None;
    opts.as_foreign = true;
    opts.random_sequences = 200;
    let report = run(fmu, &opts);
    let skipped = report
        .checks
        .iter()
        .filter(
            |c| matches!(&c.outcome, Outcome::Skip(why) if !why.starts_with(fmi_conformance::outcome::NOT_DECLARED)),
        )
        .count();
    assert_eq!((report.failed(), report.warned(), skipped), (0, 0, 0), "{report}");
    assert_eq!(report.checks.len(), n_checks);
    assert!(report.partial() > 0, "{report}");
    assert!(
        report.about.iter().any(|l| l.contains("another exporter's FMU")),
        "{report}"
    );
    assert_cleaned(dir.path());
}

/// The checks' paths for another exporter's FMU, on a conformant FMU (the first packaged one).
#[test]
fn every_check_passes_on_a_packaged_fmu_checked_as_another_exporters() {
    let fmu = &fmi_conformance::all::<fmi_conformance::Fmu>()
        .first()
        .expect("a packaged FMU")
        .archive;
    every_check_passes_as_another_exporters(fmu, checks_of(Version::Fmi2).count());
}

/// The same for an FMI 3.0 file: `--as-foreign` reaches the FMI 3.0 checks too (the damaged
/// states' checksum-only damage becomes "refused or accepted, never a crash").
#[test]
fn every_fmi3_check_passes_on_a_packaged_fmi3_fmu_checked_as_another_exporters() {
    let fmu = &fmi_conformance::all::<fmi_conformance::Fmu3>()
        .first()
        .expect("a packaged FMI 3.0 FMU")
        .archive;
    every_check_passes_as_another_exporters(fmu, checks_of(Version::Fmi3).count());
}

/// What a JUnit file holds, read back with an XML parser: test suites, test cases, and the test
/// cases with a `<failure>`, a `<skipped>` and a `verdict` property `warned`.
#[derive(Debug, Default, PartialEq)]
struct JUnit {
    suites: usize,
    cases: usize,
    failures: usize,
    skipped: usize,
    warned: usize,
    /// The `tests`, `failures` and `skipped` attributes of `<testsuites>`.
    declared: (usize, usize, usize),
}

fn read_junit(path: &Path) -> JUnit {
    use quick_xml::events::Event;
    let text = std::fs::read_to_string(path).unwrap();
    let mut reader = quick_xml::Reader::from_str(&text);
    let mut j = JUnit::default();
    let attr = |e: &quick_xml::events::BytesStart, name: &str| -> String {
        e.attributes()
            .map(|a| a.expect("a well-formed attribute"))
            .find(|a| a.key.as_ref() == name.as_bytes())
            .map(|a| a.unescape_value().expect("an escaped value").into_owned())
            .unwrap_or_default()
    };
    loop {
        match reader
            .read_event()
            .unwrap_or_else(|e| panic!("{}: not XML: {e}", path.display()))
        {
            Event::Start(e) | Event::Empty(e) => match e.name().as_ref() {
                b"testsuites" => {
                    let n = |k| attr(&e, k).parse::<usize>().unwrap();
                    j.declared = (n("tests"), n("failures"), n("skipped"));
                }
                b"testsuite" => j.suites += 1,
                b"testcase" => j.cases += 1,
                b"failure" => j.failures += 1,
                b"skipped" => j.skipped += 1,
                b"property" if attr(&e, "name") == "verdict" && attr(&e, "value") == "warned" => j.warned += 1,
                _ => {}
            },
            Event::Eof => break,
            _ => {}
        }
    }
    j
}

/// The counts of the report's last line, `N passed, N failed, N warned, N skipped`.
fn totals(stdout: &str) -> [usize; 4] {
    let line = stdout.trim_end().lines().last().unwrap_or_default();
    let n: Vec<usize> = line
        .split(", ")
        .map(|part| part.split(' ').next().unwrap().parse().unwrap())
        .collect();
    n.try_into().unwrap_or_else(|_| panic!("not a totals line: {line}"))
}

/// Issue 51: `--junit FILE` and `--json FILE`. A run of the state-machine checks on a packaged
/// FMU (all pass) and one of a check on an FMU that segfaults (it fails): each JUnit file, read
/// back with an XML parser, has a test suite per group and a test case per check, and as many
/// failures, skips and warned cases as the report's last line says.
#[test]
fn the_junit_file_of_a_run_reads_back_with_the_reports_counts() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    let good = fmi_conformance::all::<fmi_conformance::Fmu>()
        .first()
        .expect("a packaged FMU")
        .archive
        .clone();
    let bad = bad_fmu(dir.path(), 1);
    for (fmu, filter, groups) in [(&good, "state machine", 1), (&bad, "terminate_twice", 1)] {
        let (xml, json) = (dir.path().join("junit.xml"), dir.path().join("report.json"));
        let out = Command::new(env!("CARGO_BIN_EXE_fmu-check"))
            .arg(fmu)
            .args(["--filter", filter, "--junit"])
            .arg(&xml)
            .arg("--json")
            .arg(&json)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        let [passed, failed, warned, skipped] = totals(&stdout);
        let j = read_junit(&xml);
        let cases = passed + failed + warned + skipped;
        assert!(cases > 0, "{stdout}");
        assert_eq!(
            j,
            JUnit {
                suites: groups,
                cases,
                failures: failed,
                skipped,
                warned,
                declared: (cases, failed, skipped),
            },
            "{}:\n{stdout}",
            std::fs::read_to_string(&xml).unwrap()
        );
        let json = std::fs::read_to_string(&json).unwrap();
        assert!(
            json.contains(&format!(
                "\"totals\": {{\"passed\": {passed}, \"failed\": {failed}, \"warned\": {warned}, \"skipped\": {skipped}}}"
            )),
            "{json}"
        );
        assert_eq!(json.matches("\"verdict\": ").count(), cases, "{json}");
    }
}
