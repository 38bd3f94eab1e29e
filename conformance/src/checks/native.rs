//! Every packaged FMU in a host that is neither Python nor Rust (`c/host.c`, compiled here with
//! the system's `cc`), the same host under valgrind memcheck, and the binary's dynamic symbols.
//! A check whose tool (`cc`, `valgrind`, `nm`, `readelf`) is missing is skipped.

use crate::fmi2::*;
use crate::instance::{Instance, excitation};
use crate::outcome::{convention, limitation, skip};
use crate::{Fmu, Type, bits};
use std::path::PathBuf;
use std::process::Command;
use std::sync::Mutex;

/// Runs a tool; skips the check when the tool is not installed.
fn run_tool(name: &str, args: &[String]) -> std::process::Output {
    match Command::new(name)
        .args(args)
        .stdin(std::process::Stdio::null())
        .output()
    {
        Ok(out) => out,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            skip(format!("{name} is not installed (tests/setup-env.sh installs it)"))
        }
        Err(e) => panic!("cannot run {name}: {e}"),
    }
}

fn tool(name: &str, args: &[&str]) -> String {
    let args: Vec<String> = args.iter().map(|a| a.to_string()).collect();
    let out = run_tool(name, &args);
    assert!(
        out.status.success(),
        "{name} {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The C host, compiled (into a scratch folder) once per process. It saves, serializes and
/// restores an FMU state: an FMU that cannot skips the check.
fn host(fmu: &Fmu) -> PathBuf {
    static HOST: Mutex<Option<PathBuf>> = Mutex::new(None);
    if !fmu.can_snapshot() {
        skip(
            "the C host saves and restores a serialized FMU state: the FMU does not declare canGetAndSetFMUstate and canSerializeFMUstate",
        );
    }
    let mut host = HOST.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(exe) = host.as_ref().filter(|exe| exe.exists()) {
        return exe.clone();
    }
    {
        let src = fmu.scratch.join("host.c");
        std::fs::write(&src, include_str!("../../c/host.c")).unwrap_or_else(|e| panic!("{}: {e}", src.display()));
        let header = fmu.scratch.join("dl.h");
        std::fs::write(&header, include_str!("../../c/dl.h")).unwrap_or_else(|e| panic!("{}: {e}", header.display()));
        let src = src.to_str().unwrap();
        let exe = fmu.scratch.join("c-host");
        tool(
            "cc",
            &[
                "-std=gnu11",
                "-O1",
                "-g",
                "-Wall",
                "-Wextra",
                "-Werror",
                "-o",
                exe.to_str().unwrap(),
                src,
                "-ldl",
            ],
        );
        *host = Some(exe.clone());
        exe
    }
}

/// The C host's command for this FMU: on another exporter's FMU without the checks of this
/// exporter's conventions (an unknown category refused, with the category in the message).
fn host_command(program: &str, fmu: &Fmu) -> Command {
    let mut c = Command::new(program);
    c.stdin(std::process::Stdio::null());
    if let Some((steps, h)) = me_run(fmu) {
        c.env(
            "HOST_ME",
            format!(
                "{},{},{steps},{h:?}",
                fmu.md.number_of_continuous_states(),
                fmu.md.number_of_event_indicators
            ),
        );
    }
    if !convention(
        fmu,
        "the C host's check that an unknown log category is refused with a message naming it",
    ) {
        c.env("HOST_FOREIGN", "1");
    }
    c
}

fn host_args(fmu: &Fmu, steps: usize, h: f64) -> Vec<String> {
    let vrs: Vec<String> = fmu.md.vrs_of_type(Type::Real).iter().map(u32::to_string).collect();
    let mut args = vec![
        fmu.so.to_string_lossy().into_owned(),
        fmu.md.guid.clone(),
        fmu.resource_uri(),
        steps.to_string(),
        format!("{h:?}"),
        vrs.join(","),
    ];
    args.extend(excitation(fmu).iter().map(|(vr, v)| format!("{vr}={v:?}")));
    args
}

/// The Real values after `steps` steps at t = n·h, as the C host computes them, from the Rust
/// side through the same C API.
fn expected(fmu: &Fmu, steps: usize, h: f64) -> Vec<u64> {
    let mut inst = Instance::new(fmu);
    let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
    assert_eq!(inst.set_real(&vrs, &vals), fmi2OK);
    inst.initialize();
    for n in 0..steps {
        assert_eq!(inst.do_step(n as f64 * h, h), fmi2OK);
    }
    bits(&inst.get_real(&fmu.md.vrs_of_type(Type::Real)).1)
}

/// The model-exchange run of the C host, where the FMU declares Model Exchange (in this
/// binary): steps and step size (1e-4 s, or the default experiment's step where it is finer).
fn me_run(fmu: &Fmu) -> Option<(usize, f64)> {
    let me = fmu.md.me.as_ref()?;
    if me.model_identifier != fmu.md.model_identifier() || fmu.api.me.is_err() {
        return None;
    }
    Some((2000, crate::instance::step_size(fmu).min(1e-4)))
}

/// The Real values after the model-exchange run of the C host, from the Rust side, with the
/// same explicit-Euler loop ([`crate::me::Euler`]).
fn expected_me(fmu: &Fmu, steps: usize, h: f64) -> Vec<u64> {
    let mut inst = Instance::new_me(fmu);
    let info = inst.me_initialize();
    let mut euler = crate::me::Euler::new(&inst, h, &info);
    for _ in 0..steps {
        euler.step(&mut inst);
    }
    bits(&inst.get_real(&fmu.md.vrs_of_type(Type::Real)).1)
}

/// Compares the host's model-exchange result with the Rust importer's, where there is one.
fn compare_me(fmu: &Fmu, stdout: &str) {
    match me_run(fmu) {
        Some((steps, h)) => {
            let line = stdout
                .lines()
                .find(|l| l.starts_with("me-final"))
                .unwrap_or_else(|| panic!("{}: the C host printed no 'me-final' line: {stdout}", fmu.id));
            let got: Vec<u64> = line
                .split_whitespace()
                .skip(1)
                .map(|x| u64::from_str_radix(x, 16).unwrap())
                .collect();
            assert_eq!(
                got,
                expected_me(fmu, steps, h),
                "{}: model exchange ({steps} explicit-Euler steps of {h} s): C host and Rust importer differ",
                fmu.id
            );
            crate::outcome::info(format!("model exchange too: {steps} explicit-Euler steps of {h} s"));
        }
        None => {
            if fmu.md.me.is_some() {
                limitation("the C host's model-exchange run: the Model Exchange binary is another one");
            }
        }
    }
}

fn parse_final(stdout: &str) -> Vec<u64> {
    let line = stdout.lines().find(|l| l.starts_with("final")).expect("a 'final' line");
    line.split_whitespace()
        .skip(1)
        .map(|x| u64::from_str_radix(x, 16).unwrap())
        .collect()
}

pub fn a_c_host_runs_every_fmu_with_the_same_results_as_the_rust_importer(fmu: &Fmu) {
    let (steps, h) = (200, 0.01);
    let host = host(fmu);
    let out = host_command(host.to_str().unwrap(), fmu)
        .args(host_args(fmu, steps, h))
        .output()
        .unwrap_or_else(|e| panic!("{}: {e}", host.display()));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}: the C host failed: {}{stdout}",
        fmu.id,
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        parse_final(&stdout),
        expected(fmu, steps, h),
        "{}: C host and Rust importer differ",
        fmu.id
    );
    compare_me(fmu, &stdout);
}

/// Verdict: memory errors (invalid reads and writes, uses of uninitialized values, bad frees) fail:
/// they are undefined behaviour inside the importer's process, whatever the call. Leaks are
/// warnings ([`warn_of_leaks`]).
pub fn a_whole_run_of_every_fmu_is_clean_under_valgrind_memcheck(fmu: &Fmu) {
    let mut args = vec![
        "--error-exitcode=1".to_string(),
        "--leak-check=full".into(),
        "--show-leak-kinds=definite,indirect,possible".into(),
        // Leaks do not set the exit code: they are warnings (warn_of_leaks).
        "--errors-for-leak-kinds=none".into(),
        "--quiet".into(),
        host(fmu).to_string_lossy().into_owned(),
    ];
    args.extend(host_args(fmu, 200, 0.01));
    if Command::new("valgrind").arg("--version").output().is_err() {
        skip("valgrind is not installed (tests/setup-env.sh installs it)");
    }
    let out = host_command("valgrind", fmu)
        .args(&args)
        .output()
        .unwrap_or_else(|e| panic!("cannot run valgrind: {e}"));
    assert!(
        out.status.success(),
        "{}: valgrind memcheck found errors:\n{}",
        fmu.id,
        String::from_utf8_lossy(&out.stderr)
    );
    warn_of_leaks(&fmu.id, &String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        parse_final(&stdout),
        expected(fmu, 200, 0.01),
        "{}: results under valgrind",
        fmu.id
    );
    compare_me(fmu, &stdout);
}

/// Every fmi2 function of the interfaces the FMU offers; besides them, the binary may implement
/// FMI 3.0 too (rustfmu's `export_fmu!` binaries serve both versions), then with all 75 fmi3
/// functions and no other name; nothing else.
///
/// Verdict: the fmi2 functions of the declared interfaces must be there (a failure otherwise:
/// FMI 2.0.5 §2.1 has the FMU implement every function of its interface); other exported symbols
/// and a partial set of fmi3 names are portability and hygiene advice, warnings (they can clash
/// with the importer's or another FMU's symbols).
pub fn the_binary_exports_the_fmi2_functions_and_no_others(fmu: &Fmu) {
    let so = fmu.so.to_str().unwrap();
    let defined = tool("nm", &["-D", "--defined-only", so]);
    let names: Vec<&str> = defined
        .lines()
        .filter_map(|l| l.split_whitespace().nth(2))
        // What the linker defines in every shared object, not an export of the FMU's code.
        .filter(|name| !["_init", "_fini", "_edata", "_end", "__bss_start"].contains(name))
        .collect();
    let foreign: Vec<&str> = names
        .iter()
        .copied()
        .filter(|name| !name.starts_with("fmi2") && !name.starts_with("fmi3"))
        .collect();
    crate::outcome::warn_unless(foreign.is_empty(), || {
        format!(
            "{}: exports symbols that are not FMI functions: {foreign:?} (they can clash with the importer's or another FMU's symbols)",
            fmu.id
        )
    });
    let fmi3: Vec<&str> = names.iter().copied().filter(|n| n.starts_with("fmi3")).collect();
    let all3 = crate::fmi3::api::FUNCTIONS;
    crate::outcome::warn_unless(
        fmi3.is_empty() || (fmi3.len() == all3.len() && all3.iter().all(|f| fmi3.contains(f))),
        || {
            format!(
                "{}: exports some fmi3 names but not FMI 3.0 whole (a binary of both versions exports all {} \
                 fmi3 functions and no other fmi3 name): {fmi3:?}",
                fmu.id,
                all3.len()
            )
        },
    );
    let n = defined.lines().filter(|l| l.contains(" fmi2")).count();
    // The co-simulation interface has 34 functions; with <ModelExchange>, its 10 more.
    let (want, what) = if fmu.md.me.is_some() {
        (
            44,
            "the 34 functions of the co-simulation interface and the 10 of model exchange",
        )
    } else {
        (34, "the 34 functions of the co-simulation interface")
    };
    if n != want && !convention(fmu, &format!("exactly {what}")) {
        limitation(format!("the binary exports {n} fmi2 functions, not exactly {what}"));
    } else {
        assert_eq!(n, want, "{}: {what}", fmu.id);
    }
}

/// Verdict: warned, never failed: FMI 2.0.5 does not restrict what a binary links (§2.3: the FMU
/// may need other libraries, placed beside it); a dependency beyond the C runtime (libstdc++, a
/// Python) is portability advice, as the importer's machine may lack it.
pub fn the_binary_needs_only_the_c_runtime(fmu: &Fmu) {
    const LIBS: [&str; 6] = [
        "libc.so.6",
        "libm.so.6",
        "libdl.so.2",
        "libpthread.so.0",
        "libgcc_s.so.1",
        "ld-linux-x86-64.so.2",
    ];
    let so = fmu.so.to_str().unwrap();
    let dynamic = tool("readelf", &["-d", so]);
    for line in dynamic.lines().filter(|l| l.contains("(NEEDED)")) {
        let lib = line.split('[').nth(1).and_then(|s| s.split(']').next()).unwrap_or(line);
        crate::outcome::warn_unless(LIBS.contains(&lib), || {
            format!(
                "{}: needs {lib}, beyond the C runtime {LIBS:?} (an importer's machine may lack it)",
                fmu.id
            )
        });
    }
    let undefined = tool("nm", &["-D", "--undefined-only", so]);
    for line in undefined.lines() {
        let mut f = line.split_whitespace();
        let (kind, name) = (f.next().unwrap_or(""), f.next().unwrap_or(""));
        let versioned = ["@GLIBC_", "@GCC_"].iter().any(|v| name.contains(v));
        crate::outcome::warn_unless(versioned || kind == "w", || {
            format!(
                "{}: undefined symbol '{name}' ({kind}) comes from no C runtime library (portability)",
                fmu.id
            )
        });
    }
}

/// Warns of the leaks valgrind's memcheck reported in `stderr` (a run with `--leak-check=full`
/// and `--errors-for-leak-kinds=none`). A warning, not a failure: FMI 2.0.5 §2.1.5 and FMI 3.0.2
/// §2.3.1 have fmi2FreeInstance / fmi3FreeInstance free the instance's resources, but a leak
/// breaks no call; it matters to an importer that instantiates many times.
pub fn warn_of_leaks(id: &str, stderr: &str) {
    let lost: Vec<&str> = stderr
        .lines()
        .filter(|l| {
            l.contains("are definitely lost") || l.contains("are indirectly lost") || l.contains("are possibly lost")
        })
        .collect();
    if !lost.is_empty() {
        crate::outcome::warn(format!(
            "{id}: valgrind memcheck found leaks ({} records):\n{}",
            lost.len(),
            stderr.trim_end()
        ));
    }
}
