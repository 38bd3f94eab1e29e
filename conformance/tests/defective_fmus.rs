//! Proof that the suite still bites (issue 51): FMUs with one deliberate defect each, FMI 2.0 and
//! 3.0, are failed by the default verdicts, by the check that names the defect, and the same FMU
//! without the defect has no failure (so each failure is the defect's, not the fixture's).
//!
//! The fixtures are `c/defects.c` (why a pass-through shim over this workspace's Dahlquist: see
//! its head), compiled here with `cc` with one `-DDEFECT_...` flag, its library put in place of
//! the binary of `target/fmu/Dahlquist.fmu` and `target/fmu/fmi3/Dahlquist.fmu`. They are checked
//! as another exporter's FMU (`--as-foreign`): what a vendor who runs `cargo fmu check` gets.
#![cfg(all(target_os = "linux", target_arch = "x86_64"))]

use fmi_conformance::archive::PrivateDir;
use fmi_conformance::outcome::Outcome;
use fmi_conformance::runner::{Report, RunOptions, run};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// The FMU a fixture wraps, of FMI version `v` (2 or 3): its path and the folder of its binary.
fn dahlquist(v: u32) -> (PathBuf, &'static str) {
    match v {
        2 => (fmi_conformance::fmu_dir().join("Dahlquist.fmu"), "linux64"),
        _ => (fmi_conformance::fmi3::fmu3_dir().join("Dahlquist.fmu"), "x86_64-linux"),
    }
}

fn entry(fmu: &Path, name: &str) -> Vec<u8> {
    let mut zip = zip::ZipArchive::new(std::fs::File::open(fmu).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (cargo run --release -p fmu-build makes the workspace's FMUs)",
            fmu.display()
        )
    }))
    .unwrap();
    let mut bytes = vec![];
    zip.by_name(name)
        .unwrap_or_else(|e| panic!("{}: {name}: {e}", fmu.display()))
        .read_to_end(&mut bytes)
        .unwrap();
    bytes
}

/// The value of `attribute="..."` in the model description.
fn attribute(xml: &str, attribute: &str) -> String {
    let at = xml.find(&format!("{attribute}=\"")).expect(attribute) + attribute.len() + 2;
    xml[at..at + xml[at..].find('"').unwrap()].to_string()
}

/// `Dahlquist.fmu` of FMI version `v` with `c/defects.c` compiled with `defines` as its binary,
/// in `dir`.
fn fixture(dir: &Path, v: u32, name: &str, defines: &[String]) -> PathBuf {
    fixture_with(dir, v, name, defines, |xml| xml)
}

/// [`fixture`] with its model description changed by `description`.
fn fixture_with(
    dir: &Path,
    v: u32,
    name: &str,
    defines: &[String],
    description: impl FnOnce(String) -> String,
) -> PathBuf {
    let (original, platform) = dahlquist(v);
    let binary = format!("binaries/{platform}/Dahlquist.so");
    // The model the shim forwards to: a copy of the original binary (FMI 2.0 and 3.0 in one).
    let inner = dir.join(format!("inner-{v}-{name}.so"));
    std::fs::write(&inner, entry(&original, &binary)).unwrap();
    let so = dir.join(format!("{name}-{v}.so"));
    let out = Command::new("cc")
        .args(["-shared", "-fPIC", "-O1", "-Wall", "-Wextra", "-Werror"])
        .arg(format!("-DINNER=\"{}\"", inner.display()))
        .args(defines)
        .arg("-o")
        .arg(&so)
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/c/defects.c"))
        .arg("-ldl")
        .output()
        .expect("cc (tests/setup-env.sh installs it)");
    assert!(out.status.success(), "cc: {}", String::from_utf8_lossy(&out.stderr));
    let fmu = dir.join(format!("{name}-{v}.fmu"));
    let mut w = zip::ZipWriter::new(std::fs::File::create(&fmu).unwrap());
    let opts = zip::write::SimpleFileOptions::default();
    w.start_file("modelDescription.xml", opts).unwrap();
    let xml = String::from_utf8(entry(&original, "modelDescription.xml")).unwrap();
    w.write_all(description(xml).as_bytes()).unwrap();
    w.start_file(binary, opts).unwrap();
    w.write_all(&std::fs::read(&so).unwrap()).unwrap();
    w.finish().unwrap();
    fmu
}

/// Every check on the fixture, as another exporter's FMU (fewer random sequences: the defects
/// show in the first ones).
fn check(fmu: &Path, temp: &Path) -> Report {
    let mut o = RunOptions::new(env!("CARGO_BIN_EXE_fmu-check"), vec!["__worker".into()]);
    o.temp_dir = Some(temp.to_path_buf());
    o.timeout = Duration::from_secs(120);
    o.random_sequences = 200;
    o.as_foreign = true;
    run(fmu, &o)
}

/// The defect `name` (`-DDEFECT_<name>`, `None` for the good variant) in both versions: each
/// `(version, check, text)` of `expected` failed with `text` in its message.
fn defect(name: &str, define: Option<&str>, expected: &[(u32, &str, &str)]) {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    for v in [2, 3] {
        let defines: Vec<String> = match define {
            // The binary instantiates with the description's own token, whatever it is given.
            Some("TOKEN") => {
                let xml = String::from_utf8(entry(&dahlquist(v).0, "modelDescription.xml")).unwrap();
                let token = attribute(&xml, if v == 2 { "guid" } else { "instantiationToken" });
                vec![format!("-DDEFECT_TOKEN=\"{token}\"")]
            }
            Some(d) => vec![format!("-DDEFECT_{d}")],
            None => vec![],
        };
        let fmu = fixture(dir.path(), v, name, &defines);
        let report = check(&fmu, dir.path());
        assert!(report.load_error.is_none(), "{report}");
        for (_, check, text) in expected.iter().filter(|e| e.0 == v) {
            let c = report
                .checks
                .iter()
                .find(|c| c.name == *check)
                .unwrap_or_else(|| panic!("no check {check} in the report of {name}, FMI {v}.0:\n{report}"));
            match &c.outcome {
                Outcome::Fail(m) => assert!(
                    m.contains(text),
                    "{name}, FMI {v}.0: {check} failed, but its message does not say '{text}': {m}"
                ),
                other => panic!("{name}, FMI {v}.0: expected {check} to fail, got {other:?}\n{report}"),
            }
        }
        if define.is_none() {
            assert_eq!(report.failed(), 0, "the good variant, FMI {v}.0, failed:\n{report}");
        }
    }
}

#[test]
fn the_good_variant_of_the_fixtures_has_no_failure() {
    defect("good", None, &[]);
}

#[test]
fn a_getter_writing_one_value_past_n_values_is_failed() {
    defect(
        "GET_PAST",
        Some("GET_PAST"),
        &[
            (
                2,
                "getters_write_no_value_past_the_array_they_are_given",
                "fmi2GetReal with nvr = ",
            ),
            (
                3,
                "fmi3_getters_write_no_value_past_the_array_they_are_given",
                "fmi3GetFloat64 with nValues",
            ),
            (
                2,
                "a_tunable_parameter_set_between_steps_takes_effect_at_the_next_step",
                "fmi2GetReal with nvr",
            ),
            (
                2,
                "a_tunable_parameter_set_between_steps_takes_effect_at_the_next_step",
                "wrote past the end",
            ),
            (
                3,
                "fmi3_start_values_are_readable_in_instantiated",
                "fmi3GetFloat64 with nValues",
            ),
            (
                3,
                "fmi3_start_values_are_readable_in_instantiated",
                "wrote past the end",
            ),
        ],
    );
}

#[test]
fn a_do_step_answering_ok_without_advancing_time_is_failed() {
    defect(
        "STEP_STUCK",
        Some("STEP_STUCK"),
        &[
            (2, "do_step_advances_time_by_the_step", "after 1 fmi2DoStep"),
            (3, "fmi3_do_step_advances_time_by_the_step", "after 1 fmi3DoStep"),
        ],
    );
}

/// One defect, one failure (issue 51): the checks that meet the stuck time on their way (the
/// status functions', the time variable's, the output arguments') note it and leave the verdict
/// to the check named for it, which fails.
#[test]
fn a_do_step_answering_ok_without_advancing_time_fails_only_the_check_named_for_it() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    for (v, named, others) in [
        (
            2,
            "do_step_advances_time_by_the_step",
            &["status_functions_report_the_last_successful_time_and_no_termination_request"][..],
        ),
        (
            3,
            "fmi3_do_step_advances_time_by_the_step",
            &[
                "fmi3_the_time_variable_reads_the_current_time_and_cannot_be_set",
                "fmi3_do_step_output_arguments_are_truthful",
            ][..],
        ),
    ] {
        let fmu = fixture(dir.path(), v, "STEP_STUCK", &["-DDEFECT_STEP_STUCK".to_string()]);
        let mut o = RunOptions::new(env!("CARGO_BIN_EXE_fmu-check"), vec!["__worker".into()]);
        o.temp_dir = Some(dir.path().to_path_buf());
        o.as_foreign = true;
        o.filter = Some("calls".into());
        o.random_sequences = 1;
        let report = run(&fmu, &o);
        let outcome = |name: &str| {
            &report
                .checks
                .iter()
                .find(|c| c.name == name)
                .unwrap_or_else(|| panic!("no check {name}:\n{report}"))
                .outcome
        };
        assert!(
            matches!(outcome(named), Outcome::Fail(_)),
            "FMI {v}.0: {named}:\n{report}"
        );
        for other in others {
            assert!(
                !matches!(outcome(other), Outcome::Fail(_)),
                "FMI {v}.0: {other} failed the stuck time too (counted twice):\n{report}"
            );
        }
    }
}

#[test]
fn a_serialized_state_longer_than_its_announced_size_is_failed() {
    defect(
        "STATE_OVERRUN",
        Some("STATE_OVERRUN"),
        &[
            (
                2,
                "serialized_state_fits_its_announced_size",
                "fmi2SerializeFMUstate with size = ",
            ),
            (
                3,
                "fmi3_serialized_state_fits_its_announced_size",
                "fmi3SerializeFMUState with size = ",
            ),
            (
                2,
                "serialize_deserialize_round_trip_continues_bit_identically",
                "fmi2SerializeFMUstate with size = ",
            ),
            (
                2,
                "serialize_deserialize_round_trip_continues_bit_identically",
                "16 byte(s) of the guard",
            ),
            (
                3,
                "fmi3_fmu_state_get_set_and_serialize_round_trips_continue_bit_identically",
                "fmi3SerializeFMUState with size = ",
            ),
        ],
    );
}

#[test]
fn model_exchange_following_other_equations_than_co_simulation_is_failed() {
    defect(
        "ME_EQUATIONS",
        Some("ME_EQUATIONS"),
        &[
            (
                2,
                "model_exchange_states_and_derivatives_are_declared_consistent_and_deterministic",
                "fmi2GetDerivatives",
            ),
            (
                3,
                "fmi3_model_exchange_states_and_derivatives_are_consistent",
                "fmi3GetContinuousStateDerivatives",
            ),
        ],
    );
}

#[test]
fn a_state_that_restores_to_something_else_is_failed() {
    defect(
        "RESTORE",
        Some("RESTORE"),
        &[
            (
                2,
                "get_set_free_round_trip_continues_bit_identically",
                "after fmi2SetFMUstate",
            ),
            (
                3,
                "fmi3_fmu_state_get_set_and_serialize_round_trips_continue_bit_identically",
                "",
            ),
        ],
    );
}

#[test]
fn a_crash_in_free_instance_is_failed_with_the_call_it_crashed_in() {
    defect(
        "FREE_CRASH",
        Some("FREE_CRASH"),
        &[
            (
                2,
                "free_instance_frees_an_instance_in_every_state_without_crashing",
                "SIGSEGV",
            ),
            (
                2,
                "free_instance_frees_an_instance_in_every_state_without_crashing",
                "fmi2FreeInstance",
            ),
            (
                3,
                "fmi3_free_instance_frees_an_instance_in_every_state_without_crashing",
                "SIGSEGV",
            ),
            (
                3,
                "fmi3_free_instance_frees_an_instance_in_every_state_without_crashing",
                "fmi3FreeInstance",
            ),
            (2, "ten_thousand_instantiate_free_cycles_leave_memory_flat", "SIGSEGV"),
            (
                2,
                "ten_thousand_instantiate_free_cycles_leave_memory_flat",
                "fmi2FreeInstance",
            ),
            (
                3,
                "fmi3_ten_thousand_instantiate_free_cycles_leave_memory_flat",
                "SIGSEGV",
            ),
            (
                3,
                "fmi3_ten_thousand_instantiate_free_cycles_leave_memory_flat",
                "fmi3FreeInstance",
            ),
        ],
    );
}

/// A binary that instantiates whatever GUID / instantiationToken it is given is warned, not
/// failed (FMI 2.0.5 §2.1.5 and FMI 3.0.2 §2.3.1 let the FMU use the token to check its
/// description, and require no refusal: the verdicts in the two checks' documentation), and
/// nothing else in the checks of instantiation fails for it.
#[test]
fn a_binary_that_does_not_check_the_token_of_its_description_is_warned_not_failed() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    for (v, name, says) in [
        (
            2,
            "instantiate_refuses_a_wrong_null_or_empty_guid_with_a_message",
            "fmi2Instantiate with GUID Some(\"{00000000-0000-0000-0000-000000000000}\") returned an instance",
        ),
        (
            3,
            "fmi3_instantiate_refuses_a_wrong_or_null_token_or_name_and_event_mode_with_null",
            "with a wrong instantiationToken returned an instance",
        ),
    ] {
        let xml = String::from_utf8(entry(&dahlquist(v).0, "modelDescription.xml")).unwrap();
        let token = attribute(&xml, if v == 2 { "guid" } else { "instantiationToken" });
        let fmu = fixture(dir.path(), v, "TOKEN", &[format!("-DDEFECT_TOKEN=\"{token}\"")]);
        let mut o = RunOptions::new(env!("CARGO_BIN_EXE_fmu-check"), vec!["__worker".into()]);
        o.temp_dir = Some(dir.path().to_path_buf());
        o.as_foreign = true;
        o.filter = Some("instantiate".into());
        let report = run(&fmu, &o);
        assert!(report.load_error.is_none(), "{report}");
        let c = report
            .checks
            .iter()
            .find(|c| c.name == name)
            .unwrap_or_else(|| panic!("no check {name}:\n{report}"));
        match &c.outcome {
            Outcome::Warn(m) => assert!(m.contains(says), "FMI {v}.0: {name} warned without '{says}': {m}"),
            other => panic!("FMI {v}.0: expected {name} to warn, got {other:?}\n{report}"),
        }
        assert_eq!(
            report.failed(),
            0,
            "FMI {v}.0: the checks of instantiation failed:\n{report}"
        );
    }
}

/// A crash in the preflight (here: fmi2FreeInstance of the instance whose state it serializes,
/// checked as this exporter's FMU so that the preflight serializes one) is no reason to skip:
/// the checks run and fail with the call.
#[test]
fn a_crash_in_the_preflight_fails_the_checks_instead_of_skipping_them() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    let fmu = fixture(dir.path(), 2, "FREE_CRASH", &["-DDEFECT_FREE_CRASH".into()]);
    let mut o = RunOptions::new(env!("CARGO_BIN_EXE_fmu-check"), vec!["__worker".into()]);
    o.temp_dir = Some(dir.path().to_path_buf());
    o.filter = Some("FMU state".into());
    let report = run(&fmu, &o);
    assert!(
        report
            .about
            .iter()
            .any(|l| l.contains("the preflight") && l.contains("SIGSEGV") && l.contains("fmi2FreeInstance")),
        "{report}"
    );
    assert_eq!(report.skipped(), 0, "{report}");
    assert!(report.failed() > 0, "{report}");
}

/// A description that disagrees with its binary: it declares a variable (value reference 99, a
/// local Real/Float64) the binary does not know, so that the binary refuses it. The good binary.
/// Failed by the check named for it, and by the state-machine and reset checks on their way.
#[test]
fn a_description_declaring_a_variable_the_binary_refuses_is_failed() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    for (v, declaration, names) in [
        (
            2,
            r#"<ScalarVariable name="extra" valueReference="99" causality="local" variability="continuous"><Real/></ScalarVariable>"#,
            [
                "the_binary_knows_every_variable_its_description_declares",
                "every_function_in_every_state_answers_as_the_standard_says",
            ],
        ),
        (
            3,
            r#"<Float64 name="extra" valueReference="99" causality="local" variability="continuous"/>"#,
            [
                "fmi3_the_binary_knows_every_variable_its_description_declares",
                "fmi3_reset_from_every_state_then_a_rerun_is_bit_identical",
            ],
        ),
    ] {
        let fmu = fixture_with(dir.path(), v, "EXTRA", &[], |xml| {
            xml.replace("</ModelVariables>", &format!("  {declaration}\n  </ModelVariables>"))
        });
        let report = check(&fmu, dir.path());
        for name in names {
            let c = report.checks.iter().find(|c| c.name == name).expect(name);
            match &c.outcome {
                Outcome::Fail(m) => assert!(
                    m.contains("fmi2GetReal") || m.contains("value reference 99"),
                    "FMI {v}.0: {name} failed, but not for the variable: {m}"
                ),
                other => panic!("FMI {v}.0: expected {name} to fail, got {other:?}\n{report}"),
            }
        }
        let named = report.checks.iter().find(|c| c.name == names[0]).unwrap();
        let Outcome::Fail(m) = &named.outcome else {
            unreachable!()
        };
        assert!(m.contains("'extra' (value reference 99)"), "FMI {v}.0: {m}");
    }
}

/// A defect the random call sequences find leaves a reproducer (issue 51: "`cargo fmu replay`
/// reproducing one"): the `doStep` that answers OK without advancing answers OK in Instantiated
/// too, where the standard's state machine has fmi2Error/fmi3Error (judged under `--strict`). The
/// file the failing check names, replayed
/// (`fmu-check --replay`, as `cargo fmu replay`), exits 1 on the defective FMU at that call, and 0
/// on the FMU it wraps, which refuses the call.
#[test]
fn a_random_sequence_that_fails_leaves_a_reproducer_that_replays_the_failure() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    for (v, name) in [
        (2, "random_call_sequences_keep_every_fmu_conformant"),
        (3, "fmi3_random_call_sequences_never_crash_and_keep_status_consistent"),
    ] {
        let fmu = fixture(dir.path(), v, "STEP_STUCK", &["-DDEFECT_STEP_STUCK".to_string()]);
        let mut o = RunOptions::new(env!("CARGO_BIN_EXE_fmu-check"), vec!["__worker".into()]);
        o.temp_dir = Some(dir.path().to_path_buf());
        o.random_sequences = 200;
        o.as_foreign = true;
        // A call the state machine does not allow, accepted, is judged under --strict (by default
        // a warning: FMI 3.0.2 §2.2.4 requires fmi3Error "when detecting" it; issue 51).
        o.strict = true;
        o.filter = Some(name.into());
        o.reproducers = Some(dir.path().join(format!("reproducers-{v}")));
        let report = run(&fmu, &o);
        let c = report.checks.iter().find(|c| c.name == name).expect("the check ran");
        let Outcome::Fail(message) = &c.outcome else {
            panic!("FMI {v}: {name} should fail on the stuck doStep:\n{report}")
        };
        let file = message
            .split("reproducer (the failing sequence, one call a line): ")
            .nth(1)
            .and_then(|rest| rest.split(';').next())
            .map(PathBuf::from)
            .unwrap_or_else(|| panic!("FMI {v}: the failure names no reproducer: {message}"));
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(
            text.contains("DoStep") && text.contains("# answered OK"),
            "FMI {v}:\n{text}"
        );
        let replay = |fmu: &Path| {
            Command::new(env!("CARGO_BIN_EXE_fmu-check"))
                .arg("--replay")
                .arg(&file)
                .arg(fmu)
                .output()
                .unwrap()
        };
        let out = replay(&fmu);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(
            out.status.code(),
            Some(1),
            "FMI {v}: the replay on the defective FMU:\n{stdout}"
        );
        assert!(stdout.contains("DIFFERS: the file expects Error"), "FMI {v}:\n{stdout}");
        let out = replay(&dahlquist(v).0);
        assert_eq!(
            out.status.code(),
            Some(0),
            "FMI {v}: the replay on the FMU without the defect:\n{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// A one-value output argument written past its value (fmi2GetRealStatus writes a second
/// fmi2Real after `value`, fmi3GetNumberOfContinuousStates a second size_t): the guard after
/// every buffer the suite hands an FMU, single values included, catches it.
#[test]
fn an_output_argument_written_past_its_one_value_is_failed() {
    defect(
        "ONE_PAST",
        Some("ONE_PAST"),
        &[
            (
                2,
                "getters_write_no_value_past_the_array_they_are_given",
                "fmi2GetRealStatus, given one value, wrote past the end",
            ),
            (
                3,
                "fmi3_getters_write_no_value_past_the_array_they_are_given",
                "fmi3GetNumberOfContinuousStates, given one size_t, wrote past the end",
            ),
            (
                2,
                "status_functions_report_the_last_successful_time_and_no_termination_request",
                "fmi2GetRealStatus, given one value, wrote past the end",
            ),
            (
                3,
                "fmi3_model_exchange_states_and_derivatives_are_consistent",
                "fmi3GetNumberOfContinuousStates, given one size_t, wrote past the end",
            ),
        ],
    );
}

/// A description of Scheduled Execution only (as the Reference-FMUs' Clocks, v0.0.41): the FMU is
/// loaded (md-reader reads it), the checks that drive co-simulation or model exchange are skipped
/// naming the declarations, and those that need neither run (issue 51 item 5). Our Dahlquist
/// 3.0 with `<ScheduledExecution>` in place of its two interface elements (its binary exports
/// every fmi3 function).
#[test]
fn a_description_of_scheduled_execution_only_is_checked_with_its_co_simulation_and_model_exchange_checks_skipped() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    let fmu = fixture_with(dir.path(), 3, "SE_ONLY", &[], |xml| {
        xml.lines()
            .filter(|l| !l.trim_start().starts_with("<CoSimulation"))
            .map(|l| {
                if l.trim_start().starts_with("<ModelExchange") {
                    r#"  <ScheduledExecution modelIdentifier="Dahlquist"/>"#.to_string()
                } else {
                    l.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join("\n")
    });
    let mut o = RunOptions::new(env!("CARGO_BIN_EXE_fmu-check"), vec!["__worker".into()]);
    o.temp_dir = Some(dir.path().to_path_buf());
    o.filter = Some("calls".into());
    let report = run(&fmu, &o);
    assert!(report.load_error.is_none(), "{report}");
    let outcome = |name: &str| &report.checks.iter().find(|c| c.name == name).expect(name).outcome;
    assert!(matches!(outcome("fmi3_get_version_is_3_0"), Outcome::Pass), "{report}");
    for name in [
        "fmi3_do_step_advances_time_by_the_step",
        "fmi3_getters_write_no_value_past_the_array_they_are_given",
    ] {
        match outcome(name) {
            Outcome::Skip(why) => assert!(why.contains("<ScheduledExecution> only"), "{name}: {why}"),
            other => panic!("{name}: expected a skip naming the declarations, got {other:?}\n{report}"),
        }
    }
}

/// The file a failure message names as its reproducer.
fn reproducer_of(message: &str) -> PathBuf {
    let paths = fmi_conformance::replay::write::reproducer_paths(message);
    assert_eq!(paths.len(), 1, "one reproducer in: {message}");
    paths[0].clone()
}

/// `fmu-check --replay file fmu` (as `cargo fmu replay`): exit code and what it printed.
fn replay(file: &Path, fmu: &Path) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_fmu-check"))
        .arg("--replay")
        .arg(file)
        .arg(fmu)
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.code(), text)
}

/// Issue 51 item 3: a named check that fails leaves a reproducer, the calls of the instance it
/// failed on, which replays the failure on the defective FMU (exit 1, saying what differs: a
/// guard overwritten, a value other than the check expected, a status other than the standard
/// requires) and not on the FMU it wraps (exit 0); the same check passing on that FMU leaves no
/// file. Nine defects, FMI 2.0 and 3.0.
#[test]
fn a_failing_named_check_leaves_a_reproducer_that_replays_the_failure_and_a_passing_one_none() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    for (defect, v, name, differs) in [
        (
            "GET_PAST",
            2,
            "getters_write_no_value_past_the_array_they_are_given",
            "fmi2GetReal with nvr = ",
        ),
        (
            "GET_PAST",
            3,
            "fmi3_getters_write_no_value_past_the_array_they_are_given",
            "fmi3GetFloat64 with nValues",
        ),
        (
            "STEP_STUCK",
            2,
            "do_step_advances_time_by_the_step",
            "the check expected",
        ),
        (
            "STEP_STUCK",
            3,
            "fmi3_do_step_advances_time_by_the_step",
            "the check expected",
        ),
        // A check that called the C functions directly before the call log took them.
        (
            "ME_EQUATIONS",
            2,
            "model_exchange_states_and_derivatives_are_declared_consistent_and_deterministic",
            "fmi2GetDerivatives gave",
        ),
        (
            "ONE_PAST",
            2,
            "status_functions_report_the_last_successful_time_and_no_termination_request",
            "fmi2GetRealStatus, given one value, wrote past the end",
        ),
        (
            "ONE_PAST",
            3,
            "fmi3_model_exchange_states_and_derivatives_are_consistent",
            "fmi3GetNumberOfContinuousStates, given one size_t, wrote past the end",
        ),
        // Checks whose failing call was made on the C functions directly before the call log
        // took it (issue 51 item 1): a getter with no values and NULL arrays, a NULL component,
        // a status getter of another kind, fmi3SetDebugLogging.
        (
            "EMPTY_REFUSED",
            2,
            "zero_values_with_null_arrays_are_fine_and_null_arrays_with_values_are_refused",
            "fmi2GetInteger answered Error, the file expects OK",
        ),
        (
            "EMPTY_REFUSED",
            3,
            "fmi3_bad_arguments_are_refused_with_a_message_and_change_nothing",
            "fmi3GetFloat64 answered Error, the file expects OK",
        ),
        (
            "NULL_COMPONENT",
            2,
            "a_null_component_is_refused_by_every_function",
            "fmi2DoStep answered OK, the file expects Error",
        ),
        (
            "STATUS_KIND",
            2,
            "status_functions_report_the_last_successful_time_and_no_termination_request",
            "fmi2GetBooleanStatus answered OK, the file expects Discard",
        ),
        (
            "LOGGING",
            3,
            "fmi3_set_debug_logging_refuses_unknown_categories",
            "fmi3SetDebugLogging answered OK, the file expects Error",
        ),
    ] {
        let fmu = fixture(dir.path(), v, defect, &[format!("-DDEFECT_{defect}")]);
        let run_one = |fmu: &Path, reproducers: &Path| {
            let mut o = RunOptions::new(env!("CARGO_BIN_EXE_fmu-check"), vec!["__worker".into()]);
            o.temp_dir = Some(dir.path().to_path_buf());
            o.as_foreign = true;
            o.filter = Some(name.into());
            o.reproducers = Some(reproducers.to_path_buf());
            let report = run(fmu, &o);
            let c = report
                .checks
                .iter()
                .find(|c| c.name == name)
                .unwrap_or_else(|| panic!("no check {name}:\n{report}"));
            c.outcome.clone()
        };
        let reproducers = dir.path().join(format!("reproducers-{defect}-{v}"));
        let Outcome::Fail(message) = run_one(&fmu, &reproducers) else {
            panic!("{defect}, FMI {v}.0: {name} should fail")
        };
        let file = reproducer_of(&message);
        assert!(file.starts_with(&reproducers), "{}", file.display());
        let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        assert!(
            text.contains(&format!("# check: {name}")) && text.contains("# failure: "),
            "{defect}, FMI {v}.0: the file names the check and its failure:\n{text}"
        );
        let (code, out) = replay(&file, &fmu);
        assert_eq!(
            code,
            Some(1),
            "{defect}, FMI {v}.0: the replay on the defective FMU:\n{out}\n{text}"
        );
        assert!(
            out.contains("the failure reproduces") && out.contains(differs),
            "{defect}, FMI {v}.0: the replay says what differs ('{differs}'):\n{out}"
        );
        let (code, out) = replay(&file, &dahlquist(v).0);
        assert_eq!(
            code,
            Some(0),
            "{defect}, FMI {v}.0: the replay on the FMU without the defect:\n{out}\n{text}"
        );
        // The check passes on the FMU without the defect: no file.
        let clean = dir.path().join(format!("clean-{defect}-{v}"));
        let outcome = run_one(&dahlquist(v).0, &clean);
        assert!(
            !matches!(outcome, Outcome::Fail(_)),
            "FMI {v}.0: {name} on Dahlquist: {outcome:?}"
        );
        let written: Vec<_> = std::fs::read_dir(&clean)
            .map(|d| d.flatten().collect())
            .unwrap_or_default();
        assert!(written.is_empty(), "a passing check wrote {written:?}");
    }
}

/// The C Reference-FMUs' Clocks (v0.0.41, Scheduled Execution only; `../shared/independent`)
/// gives its countdown clock inClock3 the interval 0 at 4 s (fmi3IntervalChanged from inside
/// clockUpdate): an interval FMI 3.0.2 §2.2.9 allows ("T_interval,i >= 0"), which the scheduler
/// runs at once, not a failure (the check failed it until 2026-12-07).
#[test]
fn a_countdown_clock_given_the_interval_zero_ticks_at_once_and_is_not_failed() {
    let clocks = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/independent/reference-fmus/3.0/Clocks.fmu");
    assert!(
        clocks.exists(),
        "{} is missing (the C Reference-FMUs v0.0.41 of shared/independent)",
        clocks.display()
    );
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    let name = "fmi3_scheduled_execution_activates_the_partitions_at_their_clocks_and_signals_the_clock_updates";
    let mut o = RunOptions::new(env!("CARGO_BIN_EXE_fmu-check"), vec!["__worker".into()]);
    o.temp_dir = Some(dir.path().to_path_buf());
    o.timeout = Duration::from_secs(300);
    o.filter = Some(name.into());
    let report = run(&clocks, &o);
    assert!(report.load_error.is_none(), "{report}");
    let c = report
        .checks
        .iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no check {name}:\n{report}"));
    assert!(
        !matches!(c.outcome, Outcome::Fail(_) | Outcome::Skip(_)),
        "{name} on the C Clocks: {:?}\n{report}",
        c.outcome
    );
}

/// Issue 51 item 1: every kind of line the call log now records for the probes of NULL arguments
/// and the FMI 3.0 calls once recorded without their arguments (strings, binaries, clocks,
/// intervals, dependencies, fmi3SetDebugLogging, fmi3GetFloat64 with NULL arrays) replays, line by
/// line, on this workspace's FMUs: each file replays to exit 0 as written, and to exit 1 with one
/// expectation changed (so the replay made the call and compared its status).
#[test]
fn every_kind_of_recorded_probe_line_replays_on_our_fmus() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    let fmi2 = dahlquist(2).0;
    let fmi3 = fmi_conformance::fmi3::fmu3_dir();
    let cases: [(&str, PathBuf, &str, &str); 3] = [
        (
            "fmi2",
            fmi2,
            "fmi2Instantiate instanceName=replay fmuType=CoSimulation guid=own resourceLocation=own loggingOn=false
fmi2SetupExperiment startTime=0.0 stopTime=NULL -> OK
fmi2EnterInitializationMode -> OK
fmi2ExitInitializationMode -> OK
fmi2GetReal vr=NULL nvr=0 value=NULL -> OK
fmi2SetString vr=NULL nvr=0 value=NULL -> OK
fmi2GetInteger vr=NULL nvr=1 -> Error
fmi2SetReal vr=[0] nvr=1 value=NULL -> Error
fmi2GetRealStatus kind=fmi2Terminated -> Discard
fmi2GetBooleanStatus kind=99 -> Discard
fmi2GetRealStatus kind=fmi2LastSuccessfulTime value=NULL -> Error
fmi2SetDebugLogging loggingOn=true nCategories=2 categories=NULL -> Error
fmi2SetDebugLogging loggingOn=true nCategories=2 categories=[logEvents,NULL] -> Error
fmi2FreeFMUstate statePointer=NULL -> OK|Error
fmi2DeSerializeFMUstate bytes=NULL size=16 -> Error
fmi2DeSerializeFMUstate bytes=hex:00 statePointer=NULL -> Error
fmi2DoStep component=NULL -> Error
fmi2GetStringStatus component=NULL -> Error
",
            "fmi2GetBooleanStatus kind=99 -> Discard",
        ),
        (
            "fmi3 strings, binaries, probes",
            fmi3.join("Feedthrough.fmu"),
            "fmi3InstantiateCoSimulation instanceName=replay eventModeUsed=false earlyReturnAllowed=false intermediateUpdate=false
fmi3EnterInitializationMode startTime=0.0 -> OK
fmi3ExitInitializationMode -> OK
fmi3GetString vr=[30] nValues=1 -> OK
fmi3GetBinary vr=[32] nValues=1 -> OK
fmi3GetFloat64 vr=NULL nValueReferences=0 values=NULL nValues=0 -> OK
fmi3SetDebugLogging loggingOn=true nCategories=0 categories=NULL -> OK
fmi3GetNumberOfVariableDependencies dependent=8 -> any
fmi3GetFloat64 vr=NULL nValueReferences=1 nValues=1 -> Error
fmi3SetFloat64 vr=[7] nValueReferences=1 values=NULL nValues=1 -> Error
fmi3SetDebugLogging loggingOn=true nCategories=1 categories=[noSuchCategory] -> Error
",
            "fmi3GetString vr=[30] nValues=1 -> OK",
        ),
        (
            "fmi3 clocks",
            fmi3.join("Clocks.fmu"),
            "fmi3InstantiateCoSimulation instanceName=replay eventModeUsed=true earlyReturnAllowed=false intermediateUpdate=false
fmi3EnterInitializationMode startTime=0.0 -> OK
fmi3ExitInitializationMode -> OK
fmi3SetClock vr=[1002] values=[1] -> OK
fmi3GetClock vr=[1005] -> OK
fmi3GetIntervalDecimal vr=[1001] -> OK
fmi3GetShiftDecimal vr=[1001] -> OK
fmi3UpdateDiscreteStates -> OK
",
            "fmi3GetClock vr=[1005] -> OK",
        ),
    ];
    for (what, fmu, text, changed) in cases {
        let file = dir.path().join(format!("{}.txt", what.replace(' ', "_")));
        std::fs::write(&file, text).unwrap();
        let (code, out) = replay(&file, &fmu);
        assert_eq!(code, Some(0), "{what}: the replay as written:\n{out}");
        // Every line was made (each printed with its status).
        let made = out.lines().filter(|l| l.contains(" -> ")).count();
        assert_eq!(made, text.lines().count(), "{what}: a line a call:\n{out}");
        let wrong = text.replace(
            changed,
            &changed.replace("-> OK", "-> Error").replace("-> Discard", "-> OK"),
        );
        assert_ne!(wrong, text);
        std::fs::write(&file, &wrong).unwrap();
        let (code, out) = replay(&file, &fmu);
        assert_eq!(code, Some(1), "{what}: the replay with '{changed}' changed:\n{out}");
        assert!(out.contains("the failure reproduces"), "{what}:\n{out}");
    }
}

/// The first lines of a reproducer on Dahlquist, as the checks' instances start: FMI 2.0
/// co-simulation initialized, model exchange in Continuous-Time Mode (`event`: left in Event
/// Mode), FMI 3.0 co-simulation in Step Mode, model exchange in Continuous-Time Mode.
fn head(v: u32, me: bool, event: bool) -> String {
    match (v, me) {
        (2, false) => "fmi2Instantiate instanceName=replay fmuType=CoSimulation guid=own resourceLocation=own loggingOn=false
fmi2SetupExperiment startTime=0.0 stopTime=NULL -> OK
fmi2EnterInitializationMode -> OK
fmi2ExitInitializationMode -> OK
"
        .into(),
        (2, true) => format!(
            "fmi2Instantiate instanceName=replay fmuType=ModelExchange guid=own resourceLocation=own loggingOn=false
fmi2SetupExperiment startTime=0.0 stopTime=NULL -> OK
fmi2EnterInitializationMode -> OK
fmi2ExitInitializationMode -> OK
fmi2NewDiscreteStates -> OK
{}",
            if event { "" } else { "fmi2EnterContinuousTimeMode -> OK\n" }
        ),
        (_, false) => "fmi3InstantiateCoSimulation instanceName=replay eventModeUsed=false earlyReturnAllowed=false intermediateUpdate=false
fmi3EnterInitializationMode startTime=0.0 -> OK
fmi3ExitInitializationMode -> OK
"
        .into(),
        (_, true) => "fmi3InstantiateModelExchange instanceName=replay
fmi3EnterInitializationMode startTime=0.0 -> OK
fmi3ExitInitializationMode -> OK
fmi3UpdateDiscreteStates -> OK
fmi3EnterContinuousTimeMode -> OK
"
        .into(),
    }
}

/// Issue 51 items 1 and 2: each kind of line the call log now records for the probes once made
/// on the C functions directly or through `Inst::call` without their arguments (a getter of
/// another type, fmi3DoStep with NULL outputs, fmi3DeserializeFMUState of NULL bytes, a
/// model-exchange vector into NULL or of another length, a NULL seed, fmi2SetContinuousStates of
/// NULL, fmi2CompletedIntegratorStep and fmi2NewDiscreteStates with a NULL output, a
/// model-exchange function on a NULL component, fmi2GetFMUstate into an existing state,
/// fmi2FreeInstance(NULL)) round-trips: a file of that line, as the check writes it, replays to
/// exit 0 on Dahlquist and to exit 1 on the fixture `DEFECT_PROBES` (fmi2FreeInstance(NULL): the
/// replay dies in the call, as the check's worker would).
#[test]
fn each_new_kind_of_probe_line_replays_to_exit_1_on_its_defect_and_0_on_our_fmu() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    // (version, model exchange, Event Mode, the lines after the head, what the replay on the
    // defect says differs)
    let cases: &[(u32, bool, bool, &str, &str)] = &[
        (
            2,
            true,
            false,
            "fmi2GetDerivatives n=1 values=NULL -> Error\n",
            "fmi2GetDerivatives answered OK",
        ),
        (
            2,
            true,
            false,
            "fmi2SetContinuousStates x=NULL nx=1 -> Error\n",
            "fmi2SetContinuousStates answered OK",
        ),
        (
            2,
            true,
            false,
            "fmi2CompletedIntegratorStep noSetFMUStatePriorToCurrentPoint=false enterEventMode=NULL -> Error\n",
            "fmi2CompletedIntegratorStep answered OK",
        ),
        (
            2,
            true,
            false,
            "fmi2CompletedIntegratorStep noSetFMUStatePriorToCurrentPoint=false terminateSimulation=NULL -> Error\n",
            "fmi2CompletedIntegratorStep answered OK",
        ),
        (
            2,
            true,
            true,
            "fmi2NewDiscreteStates eventInfo=NULL -> Error\n",
            "fmi2NewDiscreteStates answered OK",
        ),
        (
            2,
            true,
            false,
            "fmi2SetContinuousStates component=NULL -> Error\n",
            "fmi2SetContinuousStates answered OK",
        ),
        (
            2,
            false,
            false,
            "fmi2GetFMUstate state=1 -> OK\nfmi2DoStep currentCommunicationPoint=0.0 communicationStepSize=0.1 -> OK\nfmi2GetFMUstate into=1 -> OK\nfmi2SetFMUstate state=1 -> OK\nfmi2FreeFMUstate state=1 -> OK\n",
            "fmi2GetFMUstate answered Error",
        ),
        (
            3,
            false,
            false,
            "fmi3GetInt32 vr=[1] nValues=1 -> Error\n",
            "fmi3GetInt32 answered OK",
        ),
        (
            3,
            false,
            false,
            "fmi3GetInt32 vr=[3] nValues=1 -> Error\n",
            "fmi3GetInt32 answered OK",
        ),
        (
            3,
            false,
            false,
            "fmi3DoStep currentCommunicationPoint=0.0 communicationStepSize=0.1 outputs=NULL -> OK|Error\n",
            "fmi3DoStep answered Discard",
        ),
        (
            3,
            false,
            false,
            "fmi3DeserializeFMUState bytes=NULL size=16 -> Error\n",
            "fmi3DeserializeFMUState answered OK",
        ),
        (
            3,
            true,
            false,
            "fmi3GetContinuousStateDerivatives n=1 values=NULL -> Error\n",
            "fmi3GetContinuousStateDerivatives answered OK",
        ),
        (
            3,
            true,
            false,
            "fmi3GetContinuousStates n=2 -> Error\n",
            "fmi3GetContinuousStates answered OK",
        ),
        (
            3,
            true,
            false,
            "fmi3GetDirectionalDerivative unknowns=[2] knowns=[1] seed=NULL nSeed=1 nSensitivity=1 -> Error\n",
            "fmi3GetDirectionalDerivative answered OK",
        ),
        (
            3,
            true,
            false,
            "fmi3GetDirectionalDerivative unknowns=[2] knowns=[1] seed=[1.0,1.0] nSeed=2 nSensitivity=1 -> Error\n",
            "",
        ),
    ];
    let defective = [2, 3].map(|v| fixture(dir.path(), v, "PROBES", &["-DDEFECT_PROBES".to_string()]));
    for (i, (v, me, event, lines, differs)) in cases.iter().enumerate() {
        let text = format!("{}{lines}", head(*v, *me, *event));
        let file = dir.path().join(format!("probe-{i}.txt"));
        std::fs::write(&file, &text).unwrap();
        let (code, out) = replay(&file, &dahlquist(*v).0);
        assert_eq!(code, Some(0), "our Dahlquist, FMI {v}.0:\n{text}\n{out}");
        let made = out.lines().filter(|l| l.contains(" -> ")).count();
        assert_eq!(made, text.lines().count(), "a line a call:\n{out}");
        if differs.is_empty() {
            // A probe the fixture answers as the model does (a wrong nSeed is forwarded).
            continue;
        }
        let (code, out) = replay(&file, &defective[*v as usize - 2]);
        assert_eq!(code, Some(1), "DEFECT_PROBES, FMI {v}.0:\n{text}\n{out}");
        assert!(
            out.contains("the failure reproduces") && out.contains(differs),
            "DEFECT_PROBES, FMI {v}.0: the replay says '{differs}':\n{out}"
        );
    }
    // fmi2FreeInstance(NULL), which the standard makes a no-op: the defect crashes in it. The
    // replay runs in a worker process, as the check does: the crash is reported with the line and
    // the signal, exit 1.
    let text = format!("{}fmi2FreeInstance component=NULL -> OK\n", head(2, false, false));
    let line = text.lines().count();
    let file = dir.path().join("free-null.txt");
    std::fs::write(&file, &text).unwrap();
    let (code, out) = replay(&file, &dahlquist(2).0);
    assert_eq!(code, Some(0), "our Dahlquist:\n{out}");
    let (code, out) = replay(&file, &defective[0]);
    assert_eq!(code, Some(1), "DEFECT_PROBES: fmi2FreeInstance(NULL):\n{out}");
    assert!(
        out.contains("the failure reproduces: the FMU crashed")
            && out.contains(&format!(
                "line {line} (fmi2FreeInstance): fmi2FreeInstance component=NULL"
            ))
            && out.contains("SIGSEGV"),
        "DEFECT_PROBES: the replay names the line and the signal:\n{out}"
    );
    // The calls before it were printed as they were made.
    assert!(out.contains("fmi2ExitInitializationMode -> OK"), "{out}");
}

/// Issue 51 item 1: the checks' own valid calls once recorded without their arguments (a
/// comment in the reproducer) are lines the replay makes: fmi3GetOutputDerivatives, the state
/// table's getters and setters of no variable (every array NULL), fmi3ActivateModelPartition,
/// fmi3EvaluateDiscreteStates, fmi3GetFMUState into an existing state. Each file (FMI 3.0
/// Dahlquist) replays to exit 0 as written, and to exit 1 with the expectation of its last line
/// changed (so the replay made that call and compared its status).
#[test]
fn each_kind_of_line_of_the_checks_own_calls_replays() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    // (model exchange, the lines after the head, the last line's expectation changed to)
    let cases: &[(bool, &str, &str)] = &[
        (
            false,
            "fmi3DoStep currentCommunicationPoint=0.0 communicationStepSize=0.1 -> OK\nfmi3GetOutputDerivatives vr=[1] order=[1] -> OK\n",
            "Error",
        ),
        (
            false,
            "fmi3ActivateModelPartition clockReference=0 activationTime=0.0 -> Error\n",
            "OK",
        ),
        (
            false,
            "fmi3GetUInt16 vr=NULL nValueReferences=0 values=NULL nValues=0 -> OK\n",
            "Error",
        ),
        (
            false,
            "fmi3SetBinary vr=NULL nValueReferences=0 values=NULL nValues=0 -> OK\n",
            "Error",
        ),
        (
            false,
            "fmi3GetFloat64 vr=NULL nValueReferences=0 values=NULL nValues=0 -> OK\n",
            "Error",
        ),
        (
            false,
            "fmi3GetIntervalFraction vr=NULL nValueReferences=0 values=NULL nValues=0 -> any\n",
            "Fatal",
        ),
        (
            false,
            "fmi3SetShiftDecimal vr=NULL nValueReferences=0 values=NULL nValues=0 -> any\n",
            "Fatal",
        ),
        (
            false,
            "fmi3GetFMUState state=1 -> OK\nfmi3DoStep currentCommunicationPoint=0.0 communicationStepSize=0.1 -> OK\nfmi3SetFMUState state=1 -> OK\nfmi3GetFMUState into=1 -> OK\nfmi3FreeFMUState state=1 -> OK\n",
            "Error",
        ),
        (true, "fmi3EvaluateDiscreteStates -> any\n", "Fatal"),
        (
            true,
            "fmi3SetTime time=0.5 -> OK\nfmi3CompletedIntegratorStep -> OK\n",
            "Error",
        ),
    ];
    let fmu = dahlquist(3).0;
    for (i, (me, lines, wrong)) in cases.iter().enumerate() {
        let text = format!("{}{lines}", head(3, *me, false));
        let file = dir.path().join(format!("own-{i}.txt"));
        std::fs::write(&file, &text).unwrap();
        let (code, out) = replay(&file, &fmu);
        assert_eq!(code, Some(0), "as written:\n{text}\n{out}");
        let made = out.lines().filter(|l| l.contains(" -> ")).count();
        assert_eq!(made, text.lines().count(), "a line a call:\n{out}");
        let last = text.trim_end().lines().last().unwrap();
        let changed = format!("{} -> {wrong}", last.rsplit_once(" -> ").unwrap().0);
        let wrong_text = text.replace(last, &changed);
        std::fs::write(&file, &wrong_text).unwrap();
        let (code, out) = replay(&file, &fmu);
        assert_eq!(code, Some(1), "with '{changed}':\n{out}");
        assert!(out.contains("the failure reproduces"), "{out}");
    }
}

/// Issue 51 item 3: a check that only warns leaves a reproducer too, up to the call its first
/// warning followed, which expects what the standard requires there (fmi2Error, fmi3Error), so
/// that its replay exits 1 on the FMU that warned and 0 on one that refuses the mistake; under
/// `--strict` the warning is a failure with the same file. FMI 2.0 (a NULL array of model
/// exchange) and 3.0 (a getter of another type).
#[test]
fn a_check_that_only_warns_leaves_a_reproducer_of_its_first_warning() {
    let dir = PrivateDir::new_in(&std::env::temp_dir()).unwrap();
    for (v, name, last) in [
        (
            2,
            "model_exchange_bad_arguments_are_refused_with_a_message_and_change_nothing",
            "fmi2GetDerivatives n=1 values=NULL -> Error",
        ),
        (
            3,
            "fmi3_bad_arguments_are_refused_with_a_message_and_change_nothing",
            "fmi3GetInt32 vr=[",
        ),
    ] {
        let fmu = fixture(dir.path(), v, "PROBES", &["-DDEFECT_PROBES".to_string()]);
        for strict in [false, true] {
            let reproducers = dir.path().join(format!("warned-{v}-{strict}"));
            let mut o = RunOptions::new(env!("CARGO_BIN_EXE_fmu-check"), vec!["__worker".into()]);
            o.temp_dir = Some(dir.path().to_path_buf());
            o.as_foreign = true;
            o.strict = strict;
            o.filter = Some(name.into());
            o.reproducers = Some(reproducers.clone());
            let report = run(&fmu, &o);
            let c = report
                .checks
                .iter()
                .find(|c| c.name == name)
                .unwrap_or_else(|| panic!("no check {name}:\n{report}"));
            let message = match (&c.outcome, strict) {
                (Outcome::Warn(m), false) => m.clone(),
                (Outcome::Fail(m), true) => {
                    assert!(m.starts_with(fmi_conformance::outcome::STRICT_PREFIX), "{m}");
                    m.clone()
                }
                (other, _) => panic!("FMI {v}.0, strict {strict}: {name}: {other:?}\n{report}"),
            };
            let file = reproducer_of(&message);
            assert!(file.starts_with(&reproducers), "{}", file.display());
            let text = std::fs::read_to_string(&file).unwrap();
            assert!(
                text.contains(&format!("# check: {name}")) && text.contains("# warning: "),
                "FMI {v}.0: the file names the check and its warning:\n{text}"
            );
            let end = text.trim_end().lines().last().unwrap_or_default();
            // (after the expectation, a comment says what the FMU answered)
            let end = end.split(" #").next().unwrap_or_default().trim_end();
            assert!(
                end.starts_with(last) && end.ends_with("-> Error"),
                "FMI {v}.0: the file ends with the call the warning followed ('{last}...'), expecting the fmi2Error / fmi3Error the standard requires:\n{text}"
            );
            let (code, out) = replay(&file, &fmu);
            assert_eq!(code, Some(1), "FMI {v}.0: the replay on the defect:\n{out}\n{text}");
            let (code, out) = replay(&file, &dahlquist(v).0);
            assert_eq!(code, Some(0), "FMI {v}.0: the replay on Dahlquist:\n{out}\n{text}");
        }
    }
}
