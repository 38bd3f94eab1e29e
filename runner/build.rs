//! Compiles the importer's logger (c/logger.c): FMI's logger is a variadic C function, which
//! stable Rust cannot define.
fn main() {
    println!("cargo:rerun-if-changed=c/logger.c");
    cc::Build::new()
        .file("c/logger.c")
        .warnings(true)
        .compile("rustfmu_runner_logger");
}
