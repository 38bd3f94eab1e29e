//! `rustfmu-runner`: runs an SSP system of FMI 2.0 co-simulation FMUs from the command line.
//!
//! ```sh
//! rustfmu-runner run SYSTEM.ssp --stop-time 10 --step 1e-3 --set pendulum.alpha1_0=0.2 --output out.csv
//! rustfmu-runner info SYSTEM.ssp
//! ```

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rustfmu_runner::{Override, RunOptions, Scheme, Simulation};
use std::io::Write;
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "rustfmu-runner",
    version,
    about = "Fixed-step co-simulation of SSP 1.0 systems of FMI 2.0 co-simulation FMUs"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// A shared library to load (RTLD_GLOBAL) before the FMUs, in this process and in isolated
    /// components' ones (repeatable; also RUSTFMU_RUNNER_PRELOAD, paths separated by ':'). A
    /// PythonFMU binary needs libpython and names none: the runner finds the one of python3 on
    /// PATH (or RUSTFMU_RUNNER_PYTHON) by itself; this chooses another.
    #[arg(long = "preload-lib", value_name = "PATH", global = true)]
    preload_lib: Vec<PathBuf>,
}

// The command line is parsed once: the size of its largest variant costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand)]
enum Command {
    /// Runs the system from t = 0 and writes the recorded variables as CSV.
    Run {
        /// The SSP file.
        ssp: PathBuf,
        /// End of the run, s (default: the SSD's DefaultExperiment stopTime).
        #[arg(long)]
        stop_time: Option<f64>,
        /// Communication step, s (with --tolerance: the first step).
        #[arg(long)]
        step: f64,
        /// Error-controlled communication steps to this tolerance (step doubling with rollback
        /// through the FMUs' states; a system that cannot runs fixed steps and says why).
        #[arg(long)]
        tolerance: Option<f64>,
        /// With --tolerance: the smallest step, s (default: step / 1000).
        #[arg(long, requires = "tolerance")]
        min_step: Option<f64>,
        /// With --tolerance: the largest step, s (default: the stop time / 10).
        #[arg(long, requires = "tolerance")]
        max_step: Option<f64>,
        /// A first-order hold on the connections: the connected outputs' time derivatives
        /// (each component's own, and through its feedthrough by its directional derivative) set
        /// as input derivatives where a component interpolates its inputs.
        #[arg(long)]
        input_derivatives: bool,
        /// With --tolerance: a Real component.variable the error is estimated on (repeatable;
        /// default: every connected output).
        #[arg(long = "error-on", value_name = "COMPONENT.VARIABLE", requires = "tolerance")]
        error_on: Vec<String>,
        /// Algebraic loops: relative tolerance of Newton's method, |u - g(u)| <= atol + rtol |u|
        /// for every unknown (a connected input in the loop).
        #[arg(long, default_value_t = rustfmu_runner::LoopOptions::default().rtol)]
        loop_rtol: f64,
        /// Algebraic loops: absolute tolerance (the unknowns' units).
        #[arg(long, default_value_t = rustfmu_runner::LoopOptions::default().atol)]
        loop_atol: f64,
        /// Algebraic loops: Newton iterations allowed at one communication point.
        #[arg(long, default_value_t = rustfmu_runner::LoopOptions::default().max_iterations)]
        loop_max_iterations: usize,
        /// Algebraic loops: a finite-difference Jacobian even where every component of the loop
        /// gives directional derivatives.
        #[arg(long)]
        loop_finite_differences: bool,
        /// component.variable=value on top of the SSP's parameter bindings (repeatable).
        #[arg(long = "set", value_name = "COMPONENT.VARIABLE=VALUE")]
        set: Vec<String>,
        /// component.variable to record (repeatable; default: every output of every component).
        #[arg(long = "record", value_name = "COMPONENT.VARIABLE")]
        record: Vec<String>,
        /// CSV file to write (default: standard output).
        #[arg(long, short)]
        output: Option<PathBuf>,
        /// How a communication point is evaluated.
        #[arg(long, default_value = "gauss-seidel", value_parser = ["gauss-seidel", "jacobi"])]
        order: String,
        /// No progress bar (it is drawn on standard error when that is a terminal).
        #[arg(long)]
        no_progress: bool,
        /// Child processes (Linux): `component` (the default of a bare --isolate) each FMU in a
        /// process of its own, `system` every FMU and the master in one. An FMU that crashes,
        /// exits or hangs fails the run with the component, function and time, not the runner.
        #[arg(long, num_args = 0..=1, default_missing_value = "component", value_parser = ["component", "system"])]
        isolate: Option<String>,
        /// With --isolate: the longest one FMU call may take, s, before its process is killed.
        #[arg(long, requires = "isolate")]
        call_timeout: Option<f64>,
        /// An FMI 3.0 co-simulation component run with eventModeUsed and earlyReturnAllowed
        /// (repeatable): the events it reports are handled in Event Mode at their time, and a
        /// step it ends early ends every component's step there, under --isolate too.
        #[arg(long = "event-mode", value_name = "COMPONENT")]
        event_mode: Vec<String>,
        /// Also the values the FMI 3.0 co-simulation components give inside their steps: the
        /// recorded Float64 variables with intermediateUpdate="true" of those that provide
        /// intermediate update, read in their intermediateUpdate callbacks, as rows of their own
        /// (the other columns NaN), as fmusim's option of the same name (not with --isolate or
        /// --tolerance).
        #[arg(long)]
        record_intermediate_values: bool,
    },
    /// Runs a whole system for the runner that started this process (--isolate system).
    #[command(hide = true)]
    ServeSystem {
        #[arg(long)]
        ssp: PathBuf,
        #[arg(long)]
        shm: PathBuf,
        #[arg(long)]
        jacobi: bool,
        #[arg(long)]
        event_mode: Vec<String>,
    },
    /// Serves one component to the runner that started this process (--isolate).
    #[command(hide = true)]
    ServeComponent {
        #[arg(long)]
        dir: PathBuf,
        #[arg(long)]
        name: String,
        #[arg(long)]
        label: String,
        #[arg(long)]
        shm: PathBuf,
        #[arg(long)]
        model_exchange: bool,
        #[arg(long)]
        event_mode: bool,
        #[arg(long)]
        scheduled_execution: bool,
    },
    /// Prints the system: components, evaluation order, parameters, outputs.
    Info { ssp: PathBuf },
}

/// Where a run is made: here, or (--isolate system) in a child process.
enum Backend {
    Here(Simulation),
    Process(rustfmu_runner::isolate::SystemProcess),
}

fn main() {
    if let Err(e) = run(Cli::parse()) {
        eprintln!("rustfmu-runner: error: {e}");
        std::process::exit(1);
    }
}

fn parse_set(text: &str) -> Result<(String, Override), String> {
    let (key, value) = text
        .split_once('=')
        .ok_or_else(|| format!("--set '{text}': expected COMPONENT.VARIABLE=VALUE"))?;
    if !key.contains('.') {
        return Err(format!("--set '{text}': expected COMPONENT.VARIABLE=VALUE"));
    }
    Ok((key.trim().to_owned(), Override::Text(value.trim().to_owned())))
}

// ~170 lines: one match over the subcommands, each arm the plain sequence of its steps (read,
// run, write); nothing in it is shared between arms.
fn run(cli: Cli) -> Result<(), String> {
    rustfmu_runner::libpython::preload(&cli.preload_lib, "--preload-lib")?;
    match cli.command {
        #[cfg(target_os = "linux")]
        Command::ServeComponent {
            dir,
            name,
            label,
            shm,
            model_exchange,
            event_mode,
            scheduled_execution,
        } => {
            use rustfmu_runner::isolate::Interface;
            let interface = match (model_exchange, event_mode, scheduled_execution) {
                (true, _, _) => Interface::ModelExchange,
                (_, true, _) => Interface::EventMode,
                (_, _, true) => Interface::ScheduledExecution,
                _ => Interface::CoSimulation,
            };
            std::process::exit(rustfmu_runner::isolate::serve(&dir, &name, &label, interface, &shm))
        }
        #[cfg(not(target_os = "linux"))]
        Command::ServeComponent { .. } => Err("serve-component: isolation runs on Linux only".into()),
        #[cfg(target_os = "linux")]
        Command::ServeSystem {
            ssp,
            shm,
            jacobi,
            event_mode,
        } => std::process::exit(rustfmu_runner::isolate::serve_system(&ssp, &shm, jacobi, &event_mode)),
        #[cfg(not(target_os = "linux"))]
        Command::ServeSystem { .. } => Err("serve-system: isolation runs on Linux only".into()),
        Command::Info { ssp } => {
            let sim = Simulation::from_ssp(&ssp)?;
            println!("system {}", sim.name);
            for (c, id) in sim.components() {
                println!("  component {c}: {id}");
            }
            println!("evaluation order: {}", sim.evaluation_order().join(" -> "));
            for (components, unknowns) in sim.algebraic_loops() {
                println!(
                    "algebraic loop among {} (solved by Newton's method; unknowns: {})",
                    components.join(", "),
                    unknowns.join(", ")
                );
            }
            println!("parameters: {}", sim.parameters().join(", "));
            println!("outputs: {}", sim.outputs().join(", "));
            Ok(())
        }
        Command::Run {
            ssp,
            stop_time,
            step,
            tolerance,
            min_step,
            max_step,
            input_derivatives,
            error_on,
            loop_rtol,
            loop_atol,
            loop_max_iterations,
            loop_finite_differences,
            set,
            record,
            output,
            order,
            no_progress,
            isolate,
            call_timeout,
            event_mode,
            record_intermediate_values,
        } => {
            let stop_time = match stop_time {
                Some(t) => t,
                None => rustfmu_runner::ssp::Archive::open(&ssp)?
                    .ssd
                    .stop_time
                    .ok_or("no --stop-time given and the SSD has no DefaultExperiment stopTime")?,
            };
            let timeout = match call_timeout {
                Some(t) if !(t.is_finite() && t > 0.0) => {
                    return Err(format!("--call-timeout {t}: a time > 0 in seconds"));
                }
                t => t.map(std::time::Duration::from_secs_f64),
            };
            let isolation = match &isolate {
                Some(_) => Some(rustfmu_runner::isolate::Isolation {
                    worker: rustfmu_runner::isolate::find_worker(None, &[])?,
                    timeout,
                }),
                None => None,
            };
            let mut system = match (isolate.as_deref(), isolation) {
                (Some("system"), Some(iso)) => Backend::Process(rustfmu_runner::isolate::SystemProcess::spawn(
                    iso,
                    &ssp,
                    order == "jacobi",
                    &event_mode,
                )?),
                (_, Some(iso)) => Backend::Here(Simulation::from_ssp_isolated(&ssp, iso)?),
                _ => Backend::Here(Simulation::from_ssp(&ssp)?),
            };
            if let Backend::Here(sim) = &mut system
                && order == "jacobi"
            {
                sim.scheme = Scheme::Jacobi;
            }
            if let Backend::Here(sim) = &mut system {
                for c in &event_mode {
                    sim.use_event_mode(c)?;
                }
            }
            let (name, outputs) = match &system {
                Backend::Here(sim) => (sim.name.clone(), sim.outputs()),
                Backend::Process(p) => (p.info().name.clone(), p.info().outputs.clone()),
            };
            let mut opts = RunOptions::new(stop_time, step);
            opts.input_derivatives = input_derivatives;
            opts.loops = rustfmu_runner::LoopOptions {
                rtol: loop_rtol,
                atol: loop_atol,
                max_iterations: loop_max_iterations,
                finite_differences: loop_finite_differences,
            };
            opts.adaptive = tolerance.map(|tolerance| rustfmu_runner::Adaptive {
                tolerance,
                min_step,
                max_step,
                error_on: error_on.clone(),
            });
            opts.overrides = set.iter().map(|s| parse_set(s)).collect::<Result<_, _>>()?;
            opts.record = if record.is_empty() { outputs } else { record };
            if record_intermediate_values {
                match &mut system {
                    Backend::Here(sim) => {
                        for note in sim.record_intermediate_values(&opts.record)? {
                            eprintln!("rustfmu-runner: {note}");
                        }
                    }
                    Backend::Process(_) => {
                        return Err("--record-intermediate-values: not with --isolate system".into());
                    }
                }
            }
            let n = if opts.adaptive.is_some() {
                1000
            } else {
                (stop_time / step).round() as u64
            };
            let bar = if no_progress {
                ProgressBar::hidden()
            } else {
                ProgressBar::with_draw_target(Some(n + 1), ProgressDrawTarget::stderr())
            };
            bar.set_style(
                ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} steps ({per_sec}, ETA {eta})")
                    .map_err(|e| e.to_string())?
                    .progress_chars("=> "),
            );
            let every = (n / 200).max(1) as usize;
            let result = match &mut system {
                Backend::Here(sim) => sim.run(&opts, &mut |k, _| {
                    if k % every == 0 {
                        bar.set_position(k as u64 + 1);
                    }
                }),
                Backend::Process(p) => p.run(&opts),
            };
            bar.finish_and_clear();
            let result = result.map_err(|f| f.error.message)?;
            if let Some(note) = &result.note {
                eprintln!("rustfmu-runner: {note}");
            }
            if let Some(end) = &result.terminated {
                // Not a failure (FMI 2.0.5 4.2.3, FMI 3.0.2 4.2.1): the rows are written, exit 0.
                eprintln!("rustfmu-runner: {}", end.message);
            }
            for report in &result.loops {
                eprintln!("rustfmu-runner: {report}");
            }
            if opts.adaptive.is_some() {
                eprintln!(
                    "rustfmu-runner: {} points, {} fmi2DoStep calls per component, {} steps rejected",
                    result.time.len(),
                    result.fmu_steps,
                    result.rejected
                );
            }
            let mut out: Box<dyn Write> = match &output {
                Some(p) => Box::new(std::io::BufWriter::new(
                    std::fs::File::create(p).map_err(|e| format!("{}: {e}", p.display()))?,
                )),
                None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
            };
            let w = |e: std::io::Error| e.to_string();
            write!(out, "time").map_err(w)?;
            for name in &result.names {
                write!(out, ",{name}").map_err(w)?;
            }
            writeln!(out).map_err(w)?;
            let m = result.names.len();
            for (k, t) in result.time.iter().enumerate() {
                write!(out, "{t:?}").map_err(w)?;
                for x in &result.values[k * m..(k + 1) * m] {
                    write!(out, ",{x:?}").map_err(w)?;
                }
                writeln!(out).map_err(w)?;
            }
            out.flush().map_err(w)?;
            if let Some(p) = output {
                eprintln!(
                    "rustfmu-runner: {} rows x {} variables of {} to {}",
                    result.time.len(),
                    m,
                    name,
                    p.display()
                );
            }
            Ok(())
        }
    }
}
