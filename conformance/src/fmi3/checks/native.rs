//! The FMI 3.0 binary as a native library: the functions it exports, and a C host that runs it
//! (co-simulation and model exchange) under valgrind's memcheck.

use super::*;

// ---------------------------------------------------------------------------------------------
// Native: symbols

/// Verdict: every function of fmi3Functions.h must be exported (a failure otherwise: FMI 3.0.2
/// §2.2, the C API: every function of fmi3Functions.h); other symbols, a partial FMI 2.0 set and fmi3 names the
/// standard does not define are portability and hygiene advice, warnings (they can clash with the
/// importer's or another FMU's symbols).
pub fn fmi3_the_binary_exports_every_fmi3_function_and_no_others(fmu: &Fmu3) {
    let so = fmu.so.to_str().unwrap();
    let out = match std::process::Command::new("nm")
        .args(["-D", "--defined-only", so])
        .output()
    {
        Ok(o) => o,
        Err(_) => skip("nm is not installed (tests/setup-env.sh installs it)"),
    };
    assert!(
        out.status.success(),
        "nm -D {so}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let names: Vec<&str> = text.lines().filter_map(|l| l.split_whitespace().nth(2)).collect();
    let linker = ["_init", "_fini", "_edata", "_end", "__bss_start"];
    let foreign: Vec<&&str> = names
        .iter()
        .filter(|n| !n.starts_with("fmi3") && !n.starts_with("fmi2") && !linker.contains(n))
        .collect();
    crate::outcome::warn_unless(foreign.is_empty(), || {
        format!(
            "{}: exports symbols that are not FMI functions: {foreign:?} (they can clash with the importer's or another FMU's symbols)",
            fmu.id
        )
    });
    // A binary may implement FMI 2.0 too (rustfmu's `export_fmu!` binaries serve both
    // versions): then its co-simulation functions (34), with model exchange 44.
    let fmi2 = names.iter().filter(|n| n.starts_with("fmi2")).count();
    crate::outcome::warn_unless([0, 34, 44].contains(&fmi2), || {
        format!(
            "{}: exports {fmi2} fmi2 names: FMI 2.0 whole (34 functions of co-simulation, 44 with model \
             exchange) or none",
            fmu.id
        )
    });
    let missing: Vec<&&str> = crate::fmi3::api::FUNCTIONS
        .iter()
        .filter(|f| !names.contains(f))
        .collect();
    assert!(
        missing.is_empty(),
        "{}: does not export {missing:?} (FMI 3.0 section 2.3: every function of fmi3Functions.h)",
        fmu.id
    );
    let extra: Vec<&&str> = names
        .iter()
        .filter(|n| n.starts_with("fmi3") && !crate::fmi3::api::FUNCTIONS.contains(n))
        .collect();
    crate::outcome::warn_unless(extra.is_empty(), || {
        format!(
            "{}: exports fmi3 symbols the standard does not define: {extra:?}",
            fmu.id
        )
    });
    info(format!(
        "{} fmi3 functions{}, nothing else",
        crate::fmi3::api::FUNCTIONS.len(),
        if fmi2 > 0 {
            format!(" and FMI 2.0's {fmi2}")
        } else {
            String::new()
        }
    ));
}

// ---------------------------------------------------------------------------------------------
// The C host

/// Verdict: memory errors fail (undefined behaviour in the importer's process); leaks are
/// warnings ([`crate::checks::native::warn_of_leaks`]). A step that answered fmi3OK without early
/// return but ended away from t + h is noted, its verdict left to
/// `fmi3_do_step_advances_time_by_the_step` (which steps 1 ms too, as this host does).
pub fn fmi3_a_c_host_runs_co_simulation_and_model_exchange_clean_under_valgrind(fmu: &Fmu3) {
    cs_only(fmu);
    let src = fmu.scratch.join("host3.c");
    std::fs::write(&src, include_str!("../../../c/host3.c")).unwrap();
    std::fs::write(fmu.scratch.join("dl.h"), include_str!("../../../c/dl.h")).unwrap();
    let exe = fmu.scratch.join("c-host3");
    let cc = std::process::Command::new("cc")
        .args(["-std=gnu11", "-O1", "-g", "-Wall", "-Wextra", "-Werror", "-o"])
        .arg(&exe)
        .arg(&src)
        .arg("-ldl")
        .output();
    let cc = match cc {
        Ok(o) => o,
        Err(_) => skip("cc is not installed (tests/setup-env.sh installs it)"),
    };
    assert!(
        cc.status.success(),
        "compiling c/host3.c: {}",
        String::from_utf8_lossy(&cc.stderr)
    );
    // nx counts every element of the state arrays; the host reads the Float64 scalars and the
    // Float64 arrays (`vr:n`: n values, the structural parameters at their starts).
    let n_states = if fmu.md.me.is_some() {
        fmu.n_states_declared().to_string()
    } else {
        "-1".into()
    };
    let read: Vec<&Variable> = fmu
        .md
        .of_type(Type::Float64)
        .chain(
            fmu.md
                .variables
                .iter()
                .filter(|v| v.ty == Type::Float64 && v.array && v.clocks.is_empty()),
        )
        .collect();
    let vrs: Vec<String> = read
        .iter()
        .map(|v| {
            if v.array {
                format!("{}:{}", v.vr, fmu.element_count(v))
            } else {
                v.vr.to_string()
            }
        })
        .collect();
    let mut args = vec![
        fmu.so.to_string_lossy().into_owned(),
        fmu.md.token.clone(),
        fmu.resource_path(),
        "1000".into(),
        format!("{:?}", fmu.step_size().min(1e-3)),
        n_states,
        vrs.join(","),
    ];
    args.extend(excitation(fmu).iter().map(|(v, x)| {
        let x: Vec<String> = x.iter().map(|x| format!("{x:?}")).collect();
        format!("{}={}", v.vr, x.join(","))
    }));
    // An FMU with clocks: co-simulation with eventModeUsed (FMI 3.0, 4.2.1).
    let event_mode = |c: &mut std::process::Command| {
        if fmu.has_clocks() {
            c.env("HOST_EVENT_MODE", "1");
        }
    };
    let mut plain = std::process::Command::new(&exe);
    event_mode(&mut plain);
    let plain = plain.args(&args).output().unwrap();
    let stdout = String::from_utf8_lossy(&plain.stdout).into_owned();
    assert!(
        plain.status.success(),
        "{}: the C host failed: {}{stdout}",
        fmu.id,
        String::from_utf8_lossy(&plain.stderr)
    );
    // A step that answered fmi3OK without early return but ended away from t + h (beyond
    // rounding): the host noted it and went on, for valgrind to see every call; reported last.
    let time_note = String::from_utf8_lossy(&plain.stderr)
        .lines()
        .find(|l| l.starts_with("lastSuccessfulTime:"))
        .map(|l| format!("{}: the C host's run: {l} ({LAST_SUCCESSFUL_TIME})", fmu.id));
    // The same numbers as this importer.
    let final_line = stdout
        .lines()
        .find(|l| l.starts_with("final "))
        .unwrap_or_else(|| panic!("no final line: {stdout}"));
    let got: Vec<u64> = final_line
        .split_whitespace()
        .skip(1)
        .map(|x| u64::from_str_radix(x, 16).unwrap())
        .collect();
    // The C host prints the Float64 values, every element of the arrays.
    let want = float64s_after(fmu, &read, false, 1000, fmu.step_size().min(1e-3));
    assert_eq!(
        got, want,
        "{}: the C host's co-simulation run differs from this importer's",
        fmu.id
    );
    if fmu.md.me.is_some() {
        let line = stdout
            .lines()
            .find(|l| l.starts_with("me-final "))
            .unwrap_or_else(|| panic!("no me-final line: {stdout}"));
        let got: Vec<u64> = line
            .split_whitespace()
            .skip(1)
            .map(|x| u64::from_str_radix(x, 16).unwrap())
            .collect();
        let want = float64s_after(fmu, &read, true, 1000, fmu.step_size().min(1e-3));
        assert_eq!(
            got, want,
            "{}: the C host's explicit-Euler ME run differs from this importer's",
            fmu.id
        );
    }
    if std::process::Command::new("valgrind")
        .arg("--version")
        .output()
        .is_err()
    {
        if let Some(note) = time_note {
            panic!("{note}");
        }
        skip("valgrind is not installed (tests/setup-env.sh installs it)");
    }
    let mut valgrind = std::process::Command::new("valgrind");
    event_mode(&mut valgrind);
    let out = valgrind
        .args([
            "--error-exitcode=1",
            "--leak-check=full",
            "--show-leak-kinds=definite,indirect,possible",
            // Leaks do not set the exit code: they are warnings (checks::native::warn_of_leaks).
            "--errors-for-leak-kinds=none",
            "--quiet",
        ])
        .arg(&exe)
        .args(&args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}: valgrind memcheck: {}{}",
        fmu.id,
        String::from_utf8_lossy(&out.stderr),
        String::from_utf8_lossy(&out.stdout)
    );
    crate::checks::native::warn_of_leaks(&fmu.id, &String::from_utf8_lossy(&out.stderr));
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        stdout,
        "{}: results under valgrind differ",
        fmu.id
    );
    if let Some(note) = time_note {
        info(format!(
            "{note}; judged by fmi3_do_step_advances_time_by_the_step (one defect, one failure)"
        ));
    }
    info("C host: 1000 co-simulation steps and an explicit-Euler ME run, memcheck clean");
}

/// Why a step answered fmi3OK without early return must end at t + h (up to rounding, which
/// the host allows: a millionth of the step).
const LAST_SUCCESSFUL_TIME: &str = "FMI 3.0.2, fmi3DoStep: with fmi3OK and earlyReturn = false the FMU computed \
     the whole communication step, and lastSuccessfulTime is currentCommunicationPoint + communicationStepSize, \
     deviating only by rounding; a step it did not complete is answered with fmi3Discard or an early return";

/// The run of [`run`] (excitation, initialization, `steps` steps of `h`), then every value of
/// the Float64 variables `read` (their bit patterns).
fn float64s_after(fmu: &Fmu3, read: &[&Variable], me: bool, steps: usize, h: f64) -> Vec<u64> {
    let mut i = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
    excite(&i);
    i.initialize();
    for _ in 0..steps {
        i.step(h);
    }
    let (s, values) = i.get_f64_of(read);
    assert_eq!(
        s,
        fmi3OK,
        "{}: fmi3GetFloat64 of the Float64 variables: {}",
        fmu.id,
        i.log_text()
    );
    crate::bits(&values)
}
