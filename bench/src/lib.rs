//! Shared pieces of the benchmarks (`cargo bench -p rustfmu-bench`, the `perf-report`,
//! `composed-loop` and `work-precision` binaries, and the Python scripts in `bench/python/`):
//!
//! - where the packaged FMUs are ([`fmu_path`]),
//! - an FMU loaded through the `fmi` crate's importer, its variables looked up by name in its
//!   modelDescription.xml ([`Fmu`]),
//! - the composed loops, derived from the systems of `holonomic/systems.toml` ([`topology`]),
//! - a native co-simulation master that runs it without allocating per step ([`master`]),
//! - the fixed-step RK4 that the work-precision table sets against the plant's integrator
//!   ([`rk4`]).

pub mod master;
pub mod rk4;
pub mod topology;

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::InstanceCS;
use fmi::fmi2::schema::{Causality, ScalarVariableElement};
use fmi::traits::FmiImport;
use rustfmu::description::VarType;
use std::path::{Path, PathBuf};

/// What every run-timing program of the bench takes: how long a run is, its communication step,
/// and how many runs are timed (`#[command(flatten)]` in each program's arguments).
#[derive(clap::Args, Debug, Clone, Copy)]
// Its doc comment is not the programs' `--help` text.
#[command(about = None, long_about = None)]
pub struct RunArgs {
    /// Simulated time [s].
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f64,
    /// Communication step [s].
    #[arg(long, default_value_t = 1e-3)]
    pub step: f64,
    /// Runs; the fastest and the median are reported.
    #[arg(long, default_value_t = 5)]
    pub repeat: usize,
}

/// The median of `v` (of an even count, the upper of the middle two), as every report binary
/// gives its repeated timings.
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The end of a report binary's `main`: an error is printed as `<bin>: <error>` on stderr and
/// ends the process with status 1.
pub fn exit_on_error(bin: &str, result: Result<(), String>) {
    if let Err(e) = result {
        eprintln!("{bin}: {e}");
        std::process::exit(1);
    }
}

/// 1024 states of the Pendulum along a swing, for evaluating the right-hand side at a new state
/// each time (so that nothing is computed once for all iterations).
pub fn swing_states() -> Vec<[f64; 4]> {
    (0..1024)
        .map(|k| {
            let t = k as f64 * 1e-3;
            [
                0.1 * t.cos(),
                -0.1 * t.sin(),
                0.15 * (2.0 * t).cos(),
                -0.3 * (2.0 * t).sin(),
            ]
        })
        .collect()
}

/// The workspace root (the parent of this crate).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("bench/ lies inside the workspace")
        .to_path_buf()
}

/// `target/fmu/`, where `cargo run --release -p fmu-build` packages the FMUs (honours
/// `CARGO_TARGET_DIR`).
pub fn fmu_dir() -> PathBuf {
    let target = match std::env::var_os("CARGO_TARGET_DIR") {
        Some(dir) => {
            let dir = PathBuf::from(dir);
            if dir.is_absolute() {
                dir
            } else {
                workspace_root().join(dir)
            }
        }
        None => workspace_root().join("target"),
    };
    target.join("fmu")
}

/// `target/fmu/<id>.fmu`.
pub fn fmu_path(id: &str) -> PathBuf {
    fmu_dir().join(format!("{id}.fmu"))
}

/// Ids of every packaged FMU in `target/fmu/`, sorted.
pub fn packaged_fmus() -> Vec<String> {
    let mut ids: Vec<String> = std::fs::read_dir(fmu_dir())
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let p = e.path();
            (p.extension()? == "fmu").then(|| p.file_stem()?.to_str().map(str::to_owned))?
        })
        .collect();
    ids.sort();
    ids
}

/// One Real variable of an FMU, as its modelDescription.xml declares it.
#[derive(Debug, Clone)]
pub struct RealVar {
    pub name: String,
    pub vr: u32,
    pub causality: Causality,
    pub start: Option<f64>,
}

/// A packaged FMU, unzipped and parsed by the `fmi` crate's importer.
pub struct Fmu {
    pub id: String,
    pub import: Fmi2Import,
    pub reals: Vec<RealVar>,
    /// Every Real, Integer and Boolean variable: (name, value reference, type).
    pub scalars: Vec<(String, u32, VarType)>,
    /// Value references of the inputs some output depends on directly (ModelStructure/Outputs
    /// `dependencies`). The `fmi` crate reads an absent attribute as an empty list; the
    /// project's FMUs always write it.
    pub feedthrough: Vec<u32>,
}

impl Fmu {
    /// Loads `target/fmu/<id>.fmu`; the error says how to build it.
    pub fn load(id: &str) -> Result<Fmu, String> {
        let path = fmu_path(id);
        if !path.exists() {
            return Err(format!(
                "{} is missing: run `cargo run --release -p fmu-build` first",
                path.display()
            ));
        }
        let import: Fmi2Import =
            fmi::import::from_path(&path).map_err(|e| format!("{}: cannot import: {e}", path.display()))?;
        let reals = import
            .model_description()
            .model_variables
            .variables
            .iter()
            .filter_map(|v| match &v.elem {
                ScalarVariableElement::Real(r) => Some(RealVar {
                    name: v.name.clone(),
                    vr: v.value_reference,
                    causality: v.causality.clone(),
                    start: r.start,
                }),
                _ => None,
            })
            .collect();
        let scalars = import
            .model_description()
            .model_variables
            .variables
            .iter()
            .filter_map(|v| {
                let t = match &v.elem {
                    ScalarVariableElement::Real(_) => VarType::Real,
                    // An Enumeration is set and read through fmi2SetInteger / fmi2GetInteger.
                    ScalarVariableElement::Integer(_) | ScalarVariableElement::Enumeration => VarType::Integer,
                    ScalarVariableElement::Boolean(_) => VarType::Boolean,
                    _ => return None,
                };
                Some((v.name.clone(), v.value_reference, t))
            })
            .collect();
        let md = import.model_description();
        let variables = &md.model_variables.variables;
        let mut feedthrough: Vec<u32> = Vec::new();
        for output in &md.model_structure.outputs.unknowns {
            for dep in &output.dependencies {
                let v = variables
                    .get((*dep as usize).wrapping_sub(1))
                    .ok_or_else(|| format!("{id}: ModelStructure names variable index {dep}, which does not exist"))?;
                if v.causality == Causality::Input && !feedthrough.contains(&v.value_reference) {
                    feedthrough.push(v.value_reference);
                }
            }
        }
        Ok(Fmu {
            id: id.to_owned(),
            import,
            reals,
            scalars,
            feedthrough,
        })
    }

    /// The value reference of the Real variable `name`; the error lists the ones there are.
    pub fn vr(&self, name: &str) -> Result<u32, String> {
        self.reals.iter().find(|v| v.name == name).map(|v| v.vr).ok_or_else(|| {
            format!(
                "{} has no Real variable '{name}' in its modelDescription.xml; it has: {}",
                self.id,
                self.reals
                    .iter()
                    .map(|v| v.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
    }

    /// The value reference of the variable `name`, which must have type `t`; the error says
    /// what the FMU has instead.
    pub fn typed_vr(&self, name: &str, t: VarType) -> Result<u32, String> {
        match self.scalars.iter().find(|(n, _, _)| n == name) {
            Some((_, vr, have)) if *have == t => Ok(*vr),
            Some((_, _, have)) => Err(format!(
                "{}: variable '{name}' is {have:?} in its modelDescription.xml, not {t:?}",
                self.id
            )),
            None => Err(format!(
                "{} has no variable '{name}' in its modelDescription.xml; it has: {}",
                self.id,
                self.scalars
                    .iter()
                    .map(|(n, _, _)| n.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        }
    }

    /// Value references of the given variables, in order.
    pub fn vrs(&self, names: &[&str]) -> Result<Vec<u32>, String> {
        names.iter().map(|n| self.vr(n)).collect()
    }

    /// The Real variables of a causality (inputs, outputs, ...), in declaration order.
    pub fn reals_of(&self, causality: Causality) -> impl Iterator<Item = &RealVar> {
        self.reals.iter().filter(move |v| v.causality == causality)
    }

    /// A co-simulation instance of the FMU's binary, loaded as an importer loads it.
    pub fn instantiate(&self, instance_name: &str) -> Result<InstanceCS, String> {
        self.import
            .instantiate_cs(instance_name, false, false)
            .map_err(|e| format!("{}: fmi2Instantiate of '{instance_name}' failed: {e}", self.id))
    }
}

/// The swing every single-FMU benchmark runs: the plant released from rest at α1 = 0.1 rad,
/// α2 = 0.15 rad with no torque, so it falls and swings; the integrator's work per step is that
/// of a moving pendulum, not of one resting at its equilibrium.
pub const SWING_START: [(&str, f64); 2] = [("alpha1_0", 0.1), ("alpha2_0", 0.15)];

pub mod single;

/// The plant's state variables, in the order of eq. (12).
pub const STATE: [&str; 4] = ["alpha1", "omega1", "alpha2", "omega2"];
