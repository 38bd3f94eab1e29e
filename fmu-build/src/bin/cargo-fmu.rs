//! `cargo fmu`: installed by `cargo install --path fmu-build`; cargo runs it as
//! `cargo-fmu fmu <command> ...`. In this workspace, `cargo run --release -p fmu-build` runs it
//! without the `fmu` argument: that is the workspace's build tool, `fmu-build`, which with no
//! arguments builds and packages every FMU of the workspace, refreshes the committed descriptions
//! and writes the SSP files (`fmu-build build --workspace`). One binary for both names: each
//! binary of this crate costs about 80 s of release build with thin LTO on 2 cores (cargo --timings).

fn main() -> std::process::ExitCode {
    let mut args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    if args.get(1).is_some_and(|a| a == "fmu") {
        args.remove(1);
        fmu_build::cli::main(args, "cargo fmu")
    } else {
        fmu_build::cli::main(args, "fmu-build")
    }
}
