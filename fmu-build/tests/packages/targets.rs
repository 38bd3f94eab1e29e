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
    assert!(!err.contains(" build --release"), "{err}");
}

#[test]
fn macos_is_refused_before_anything_is_built() {
    fails_with(
        cargo_fmu().args(["build", "-p", "pendulum-fmu", "--target", "x86_64-apple-darwin"]),
        &["no macOS SDK", "nothing was built"],
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
