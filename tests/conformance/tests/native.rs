//! Every packaged FMU in a host that is neither Python nor Rust (`c/host.c`, compiled here with
//! the system's `cc`), the same host under valgrind memcheck, and the binary's dynamic symbols.

use fmi2_conformance::instance::{Instance, excitation};
use fmi2_conformance::{Fmu, Type, all, bits};
use rustfmu::fmi2::abi::*;
use std::path::PathBuf;
use std::process::Command;
use std::sync::OnceLock;

fn tool(name: &str, args: &[&str]) -> String {
    let out = Command::new(name)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {name} (tests/setup-env.sh installs it): {e}"));
    assert!(
        out.status.success(),
        "{name} {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The C host, compiled once per test process.
fn host() -> &'static PathBuf {
    static HOST: OnceLock<PathBuf> = OnceLock::new();
    HOST.get_or_init(|| {
        let src = concat!(env!("CARGO_MANIFEST_DIR"), "/c/host.c");
        let dir = all()[0].dir.parent().unwrap().to_path_buf();
        let exe = dir.join("c-host");
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
        exe
    })
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
fn expected(fmu: &'static Fmu, steps: usize, h: f64) -> Vec<u64> {
    let mut inst = Instance::new(fmu);
    let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
    assert_eq!(inst.set_real(&vrs, &vals), fmi2OK);
    inst.initialize();
    for n in 0..steps {
        assert_eq!(inst.do_step(n as f64 * h, h), fmi2OK);
    }
    bits(&inst.get_real(&fmu.md.vrs_of_type(Type::Real)).1)
}

fn parse_final(stdout: &str) -> Vec<u64> {
    let line = stdout.lines().find(|l| l.starts_with("final")).expect("a 'final' line");
    line.split_whitespace()
        .skip(1)
        .map(|x| u64::from_str_radix(x, 16).unwrap())
        .collect()
}

#[test]
fn a_c_host_runs_every_fmu_with_the_same_results_as_the_rust_importer() {
    for fmu in all() {
        let (steps, h) = (200, 0.01);
        let out = Command::new(host()).args(host_args(fmu, steps, h)).output().unwrap();
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
    }
}

#[test]
fn a_whole_run_of_every_fmu_is_clean_under_valgrind_memcheck() {
    for fmu in all() {
        let mut args = vec![
            "--error-exitcode=1".to_string(),
            "--leak-check=full".into(),
            "--show-leak-kinds=definite,indirect,possible".into(),
            "--errors-for-leak-kinds=definite,indirect,possible".into(),
            "--quiet".into(),
            host().to_string_lossy().into_owned(),
        ];
        args.extend(host_args(fmu, 200, 0.01));
        let out = Command::new("valgrind")
            .args(&args)
            .output()
            .expect("valgrind (tests/setup-env.sh installs it)");
        assert!(
            out.status.success(),
            "{}: valgrind memcheck found errors:\n{}",
            fmu.id,
            String::from_utf8_lossy(&out.stderr)
        );
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(
            parse_final(&stdout),
            expected(fmu, 200, 0.01),
            "{}: results under valgrind",
            fmu.id
        );
    }
}

#[test]
fn the_binary_exports_only_fmi2_functions() {
    for fmu in all() {
        let so = fmu.so.to_str().unwrap();
        let defined = tool("nm", &["-D", "--defined-only", so]);
        let foreign: Vec<&str> = defined
            .lines()
            .filter_map(|l| l.split_whitespace().nth(2))
            .filter(|name| !name.starts_with("fmi2"))
            .collect();
        assert!(
            foreign.is_empty(),
            "{}: exports symbols that are not fmi2*: {foreign:?}",
            fmu.id
        );
        let n = defined.lines().filter(|l| l.contains(" fmi2")).count();
        assert_eq!(n, 34, "{}: the co-simulation interface has 34 functions", fmu.id);
    }
}

#[test]
fn the_binary_needs_only_the_c_runtime() {
    const LIBS: [&str; 6] = [
        "libc.so.6",
        "libm.so.6",
        "libdl.so.2",
        "libpthread.so.0",
        "libgcc_s.so.1",
        "ld-linux-x86-64.so.2",
    ];
    for fmu in all() {
        let so = fmu.so.to_str().unwrap();
        let dynamic = tool("readelf", &["-d", so]);
        for line in dynamic.lines().filter(|l| l.contains("(NEEDED)")) {
            let lib = line.split('[').nth(1).and_then(|s| s.split(']').next()).unwrap_or(line);
            assert!(
                LIBS.contains(&lib),
                "{}: needs {lib}, beyond the C runtime {LIBS:?}",
                fmu.id
            );
        }
        let undefined = tool("nm", &["-D", "--undefined-only", so]);
        for line in undefined.lines() {
            let mut f = line.split_whitespace();
            let (kind, name) = (f.next().unwrap_or(""), f.next().unwrap_or(""));
            let versioned = ["@GLIBC_", "@GCC_"].iter().any(|v| name.contains(v));
            assert!(
                versioned || kind == "w",
                "{}: undefined symbol '{name}' ({kind}) comes from no C runtime library",
                fmu.id
            );
        }
    }
}
