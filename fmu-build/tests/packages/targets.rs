//! `cargo fmu build --target`: a target this machine cannot build stops the build before
//! anything is built, with a message that says what to install, and leaves the FMUs as they were.

use std::process::Command;

fn cargo_fmu() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_cargo-fmu"));
    c.current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."));
    c.arg("fmu");
    c
}

fn fails_with(cmd: &mut Command, words: &[&str]) {
    let out = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    for w in words {
        assert!(err.contains(w), "'{w}' not in: {err}");
    }
    // Stopped before any build: cargo was never run.
    assert!(!err.contains("--crate-type cdylib"), "{err}");
}

/// A `PATH` with cargo and the system's programs but no venv: no cargo-zigbuild, no zig.
fn path_without_zig() -> String {
    let cargo = std::path::PathBuf::from(env!("CARGO"));
    let cargo_dir = cargo.parent().map(|d| d.display().to_string()).unwrap_or_default();
    format!("{cargo_dir}:/usr/bin:/bin")
}

#[test]
fn macos_without_zig_is_refused_before_anything_is_built() {
    fails_with(
        cargo_fmu()
            .args(["build", "-p", "pendulum-fmu", "--target", "x86_64-apple-darwin"])
            .env("PATH", path_without_zig()),
        &[
            "x86_64-apple-darwin",
            "linked by zig",
            "cargo-zigbuild is not installed",
            "pip install ziglang cargo-zigbuild",
            "nothing was built",
        ],
    );
    // A glibc version asks for zig too.
    fails_with(
        cargo_fmu()
            .args([
                "build",
                "-p",
                "pendulum-fmu",
                "--target",
                "x86_64-unknown-linux-gnu.2.17",
            ])
            .env("PATH", path_without_zig()),
        &["cargo-zigbuild is not installed", "nothing was built"],
    );
}

#[test]
fn a_missing_linker_is_named_with_what_to_install() {
    fails_with(
        cargo_fmu()
            .args(["build", "-p", "pendulum-fmu", "--target", "x86_64-pc-windows-gnu"])
            .env(
                "CARGO_TARGET_X86_64_PC_WINDOWS_GNU_LINKER",
                "/nonexistent/x86_64-w64-mingw32-gcc",
            ),
        &[
            "/nonexistent/x86_64-w64-mingw32-gcc",
            "not installed",
            "nothing was built",
        ],
    );
}

#[test]
fn a_target_fmi_does_not_name_is_refused() {
    fails_with(
        cargo_fmu().args(["build", "-p", "pendulum-fmu", "--target", "wasm32-unknown-unknown"]),
        &["wasm32", "FMI names no binaries folder"],
    );
    // FMI 2.0 has no folder for aarch64 Linux: only its 3.0 build may have it.
    fails_with(
        cargo_fmu().args([
            "build",
            "-p",
            "pendulum-fmu",
            "--fmi-version",
            "2",
            "--target",
            "aarch64-unknown-linux-gnu",
        ]),
        &["FMI 2.0 names no binaries folder", "build it as FMI 3.0"],
    );
}
