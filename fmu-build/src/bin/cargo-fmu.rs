//! `cargo fmu`: installed by `cargo install --path fmu-build`; cargo runs it as
//! `cargo-fmu fmu <command> ...`.

fn main() -> std::process::ExitCode {
    let mut args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    if args.get(1).is_some_and(|a| a == "fmu") {
        args.remove(1);
    }
    fmu_build::cli::main(args, "cargo fmu")
}
