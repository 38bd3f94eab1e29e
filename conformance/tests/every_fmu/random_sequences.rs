//! Random call sequences through the C API of every packaged FMU, checked against a shadow
//! model of the state machine (the checks are `fmi_conformance::checks::random_sequences`;
//! `PROPTEST_CASES` sequences per FMU, default 2000).
//!
//! Thin callers: each test runs its check on every FMU of target/fmu, strictly (a skip or a
//! part left untested fails: these are this exporter's FMUs).
//!
//! The sequences come from one seed per test process, `$RUSTFMU_SEED` or drawn
//! (`fmi_conformance::seed`): each random test writes it to stderr before it starts, past the
//! test harness's capture, so that the log of a CI run shows it even when the test process dies
//! inside an FMU; a failure message names it too.

use fmi_conformance::checks::on_every_fmu;
use std::io::Write;

/// Writes the seed of the random test `test` to stderr (not captured by the test harness).
pub fn announce_seed(test: &str) {
    let line = format!("{test}: {}\n", fmi_conformance::seed_note());
    let _ = std::io::stderr().write_all(line.as_bytes());
}

#[test]
fn random_call_sequences_keep_every_fmu_conformant() {
    announce_seed("random_call_sequences_keep_every_fmu_conformant");
    on_every_fmu("random_call_sequences_keep_every_fmu_conformant");
}

#[test]
fn regressions_found_by_random_sequences() {
    on_every_fmu("regressions_found_by_random_sequences");
}

#[test]
fn random_model_exchange_call_sequences_keep_every_fmu_conformant() {
    announce_seed("random_model_exchange_call_sequences_keep_every_fmu_conformant");
    on_every_fmu("random_model_exchange_call_sequences_keep_every_fmu_conformant");
}

/// A reproducer written from a random sequence replays on the same FMU as written (every status
/// as the file expects), and a copy whose first "-> OK" says "-> Error" instead fails the replay
/// at that line, naming it: on every FMU of target/fmu and target/fmu/fmi3, both interfaces.
#[test]
fn a_reproducer_replays_as_written_and_a_changed_expectation_fails_the_replay() {
    use fmi_conformance::{Fmu, Fmu3, all};
    let dir = std::env::temp_dir().join(format!("replay-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut cases: Vec<(String, std::path::PathBuf, String)> = vec![];
    for fmu in all::<Fmu>() {
        for me in [false, true] {
            if me && fmu.md.me.is_none() {
                continue;
            }
            let text = fmi_conformance::checks::random_sequences::reproducer_of_a_random_sequence(fmu, me, 7);
            cases.push((format!("{} FMI 2.0 me={me}", fmu.id), fmu.archive.clone(), text));
        }
    }
    for fmu in all::<Fmu3>() {
        for me in [false, true] {
            if me && fmu.md.me.is_none() || !me && fmu.md.cs.is_none() {
                continue;
            }
            let text = fmi_conformance::fmi3::checks::random_sequences::reproducer_of_a_random_sequence(fmu, me, 7);
            cases.push((format!("{} FMI 3.0 me={me}", fmu.id), fmu.archive.clone(), text));
        }
    }
    for (i, (what, archive, text)) in cases.iter().enumerate() {
        let file = dir.join(format!("{i}.txt"));
        std::fs::write(&file, text).unwrap();
        let report = fmi_conformance::replay::run::replay(&file, archive, &mut |_| {}).unwrap();
        assert_eq!(
            report.difference,
            None,
            "{what}: the replay of\n{text}\ndiffers:\n{}",
            report.lines.join("\n")
        );
        assert!(report.lines.len() > 1, "{what}: no call replayed:\n{text}");
        let Some(at) = text.find(" -> OK\n") else {
            panic!("{what}: no call the file expects OK of:\n{text}")
        };
        let changed = format!("{} -> Error\n{}", &text[..at], &text[at + " -> OK\n".len()..]);
        let number = text[..at].lines().count();
        std::fs::write(&file, &changed).unwrap();
        let report = fmi_conformance::replay::run::replay(&file, archive, &mut |_| {}).unwrap();
        let difference = report
            .difference
            .unwrap_or_else(|| panic!("{what}: the changed file replays without a difference:\n{changed}"));
        assert!(
            difference.contains(&format!("line {number}:")) && difference.contains("the file expects Error"),
            "{what}: the difference should name line {number}: {difference}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
