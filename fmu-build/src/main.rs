//! `fmu-build`: this workspace's build tool, the same program as `cargo fmu`. With no
//! arguments it builds and packages every FMU of the workspace, refreshes the committed
//! descriptions and writes the SSP files (`fmu-build build --workspace`).

fn main() -> std::process::ExitCode {
    fmu_build::cli::main(std::env::args_os().collect(), "fmu-build")
}
