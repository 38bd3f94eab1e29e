//! The cost of a container FMU against the native runner on the SSP file it was made from: one
//! run of `--seconds` (default 10) at the container's internal step (default 1 ms), every Real
//! output read at every communication point in both, median of `--repeat` runs.
//!
//!     cargo run --release -p rustfmu-bench --bin container-cost -- [--system PendulumLQR] [--seconds 10] [--repeat 5]
//!
//! Needs target/fmu/<system>.ssp and target/fmu/containers/<system>.fmu (the main job makes
//! both). The container is loaded through the runner's own importer (rustfmu_runner::fmi2, the
//! one the container itself uses for its components), so both sides pay the same FFI costs; the
//! container's own share is its checks, its outputs read through it, and its rollback copy of the
//! components' FMU states at every fmi2DoStep. Prints one JSON line.

use clap::Parser;
use rustfmu_runner::fmi2::Fmi2Import;
use rustfmu_runner::{RunOptions, Simulation};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Parser)]
struct Args {
    #[arg(long, default_value = "PendulumLQR")]
    system: String,
    #[arg(long, default_value_t = 10.0)]
    seconds: f64,
    #[arg(long, default_value_t = 5)]
    repeat: usize,
    #[arg(long, default_value = "target/fmu")]
    fmu_dir: PathBuf,
}

fn main() {
    rustfmu_bench::exit_on_error("container-cost", run());
}

fn run() -> Result<(), String> {
    let args = Args::parse();
    let ssp = args.fmu_dir.join(format!("{}.ssp", args.system));
    let fmu = args.fmu_dir.join("containers").join(format!("{}.fmu", args.system));
    let bytes = std::fs::read(&fmu).map_err(|e| format!("{}: {e} (run the main job first)", fmu.display()))?;
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(&bytes)).map_err(|e| e.to_string())?;
    let mut xml = String::new();
    std::io::Read::read_to_string(
        &mut zip.by_name("modelDescription.xml").map_err(|e| e.to_string())?,
        &mut xml,
    )
    .map_err(|e| e.to_string())?;
    let md = md_reader::fmi2::ModelDescription::parse(&xml)?;
    let h: f64 = md
        .default_experiment
        .step_size
        .as_deref()
        .and_then(|s| s.parse().ok())
        .ok_or("the container names no step size")?;
    let outputs: Vec<(String, u32)> = md
        .variables
        .iter()
        .filter(|v| v.causality == md_reader::Causality::Output && v.ty == md_reader::fmi2::Type::Real)
        .map(|v| (v.name.clone(), v.vr))
        .collect();
    let vrs: Vec<u32> = outputs.iter().map(|(_, vr)| *vr).collect();
    let n = (args.seconds / h).round() as usize;

    // The container: unpacked once, one instance, n steps with the outputs read at every point.
    let import = Fmi2Import::from_bytes(&bytes, md.model_identifier(), &md.guid)?;
    let mut container = Vec::new();
    let mut last_container = 0.0;
    let mut instantiate = Vec::new();
    for _ in 0..args.repeat.max(1) {
        let started = Instant::now();
        let mut inst = import.instantiate_cs("container", false, false)?;
        instantiate.push(started.elapsed().as_secs_f64());
        let started = Instant::now();
        let e = |what: &'static str| move |err: rustfmu_runner::fmi2::Fmi2Error| format!("container: {what}: {err}");
        inst.setup_experiment(None, 0.0, Some(n as f64 * h))
            .map_err(e("setup"))?;
        inst.enter_initialization_mode().map_err(e("enter init"))?;
        inst.exit_initialization_mode().map_err(e("exit init"))?;
        let mut out = vec![0.0; vrs.len()];
        for k in 0..=n {
            inst.get_real(&vrs, &mut out).map_err(e("get"))?;
            if k < n {
                inst.do_step(k as f64 * h, h, true).map_err(e("step"))?;
            }
        }
        last_container = out[0];
        inst.terminate().map_err(e("terminate"))?;
        container.push(started.elapsed().as_secs_f64());
    }

    // The runner on the SSP file, the same outputs recorded.
    let mut sim = Simulation::from_ssp(&ssp).map_err(|e| e.message)?;
    let mut opts = RunOptions::new(args.seconds, h);
    opts.record = outputs.iter().map(|(name, _)| name.clone()).collect();
    let mut runner = Vec::new();
    let mut last_runner = 0.0;
    for _ in 0..args.repeat.max(1) {
        let started = Instant::now();
        let r = sim.run(&opts, &mut |_, _| {}).map_err(|f| f.to_string())?;
        runner.push(started.elapsed().as_secs_f64());
        last_runner = *r.values.get(r.values.len() - opts.record.len()).unwrap_or(&f64::NAN);
    }
    if last_container != last_runner {
        return Err(format!(
            "the container ({last_container}) and the runner ({last_runner}) end apart: not the same run"
        ));
    }
    let (c, r) = (rustfmu_bench::median(container), rustfmu_bench::median(runner));
    println!(
        "{{\"system\": \"{}\", \"seconds\": {}, \"step\": {h}, \"outputs\": {}, \"container_ms\": {:.2}, \"runner_ms\": {:.2}, \"ratio\": {:.3}, \"container_instantiate_ms\": {:.2}}}",
        args.system,
        args.seconds,
        vrs.len(),
        c * 1e3,
        r * 1e3,
        c / r,
        rustfmu_bench::median(instantiate) * 1e3
    );
    Ok(())
}
