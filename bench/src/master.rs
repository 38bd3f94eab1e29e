//! The benchmarks' native co-simulation master: the SSP runner of `runner/`
//! ([`rustfmu_runner::Simulation`], the `fmi` crate's importer, a fixed communication step)
//! on a [`Topology`] of the packaged FMUs in `target/fmu/`.
//!
//! A communication point is evaluated in dependency order (Gauss-Seidel along the connections,
//! [`Scheme::GaussSeidel`], the default): every instance comes after those whose outputs reach an
//! input it feeds through to an output (ModelStructure `dependencies`), its inputs are set from
//! the outputs just read, then its outputs are read; inputs from instances later in that order
//! (which do not feed through) are set last. For the paper's loops: plant outputs -> controller ->
//! motors -> plant inputs. Then every FMU steps from t to t+h. [`Scheme::Jacobi`] reads all
//! outputs first, then sets all inputs (as fmpy.ssp and libcosim's fixed-step algorithm do), which
//! makes each feedthrough in a loop a one-step delay. All buffers are made when the master is
//! built, so a step allocates nothing and the time measured is the FMUs' and the wrapper's.
//!
//! Its call sequence is that of the project's fmpy master (`examples/cosim/master.py`): parameter
//! and start values after fmi2Instantiate, then in initialization mode the connections are
//! propagated once per instance, then the steps. The two therefore end in the same state up to
//! round-off.

use crate::topology::Topology;
use rustfmu::Value;
pub use rustfmu_runner::Scheme;
use rustfmu_runner::fmu::Fmu;
use rustfmu_runner::ssp::Connection;
use rustfmu_runner::{Simulation, Value as RunnerValue};

pub struct Master {
    pub topology: Topology,
    /// How [`Master::step`] evaluates a communication point (default [`Scheme::GaussSeidel`]).
    pub scheme: Scheme,
    sim: Simulation,
    pub time: f64,
}

impl Master {
    /// Loads every FMU of the topology and resolves every name; the error names what is missing.
    pub fn new(topology: Topology) -> Result<Master, String> {
        let mut fmus: Vec<Fmu> = Vec::new();
        let mut ids: Vec<&str> = Vec::new();
        let mut components = Vec::new();
        for s in &topology.slaves {
            let i = match ids.iter().position(|id| *id == s.fmu) {
                Some(i) => i,
                None => {
                    let path = crate::fmu_path(s.fmu);
                    if !path.exists() {
                        return Err(format!(
                            "{} is missing: run `cargo run --release -p fmu-build` first",
                            path.display()
                        ));
                    }
                    fmus.push(Fmu::from_path(s.instance, &path)?);
                    ids.push(s.fmu);
                    fmus.len() - 1
                }
            };
            components.push((s.instance.to_owned(), i));
        }
        let connections: Vec<Connection> = topology
            .connections
            .iter()
            .map(|((fi, fv), (ti, tv))| Connection {
                start: (fi.to_string(), fv.to_string()),
                end: (ti.to_string(), tv.to_string()),
            })
            .collect();
        let parameters = topology
            .start_values
            .iter()
            .map(|((inst, var), value)| {
                let v = match *value {
                    Value::Real(x) => RunnerValue::Real(x),
                    Value::Integer(x) => RunnerValue::Integer(i64::from(x)),
                    Value::Boolean(x) => RunnerValue::Boolean(x),
                    other => unreachable!("the benchmark topologies hold FMI 2.0 values only, not {other:?}"),
                };
                (inst.to_string(), var.to_string(), v)
            })
            .collect();
        let sim = Simulation::new(topology.name, fmus, components, &connections, parameters)
            .map_err(|e| format!("topology '{}': {e}", topology.name))?;
        Ok(Master {
            topology,
            scheme: Scheme::GaussSeidel,
            sim,
            time: 0.0,
        })
    }

    /// (Re)starts every instance at t = 0 for a run to `stop_time`: fmi2Reset if it ran before,
    /// parameter and start values, setup, initialization with the connections propagated once
    /// per instance.
    pub fn initialize(&mut self, stop_time: f64) -> Result<(), String> {
        self.sim.scheme = self.scheme;
        self.sim.initialize(stop_time, &[])?;
        self.time = 0.0;
        Ok(())
    }

    /// One communication step of size `h` from `self.time`. Allocates nothing.
    pub fn step(&mut self, h: f64) -> Result<(), String> {
        self.sim.scheme = self.scheme;
        self.sim.step(self.time, h)?;
        self.time += h;
        Ok(())
    }

    /// `n` steps of size `h` from t = 0 (the master was just initialized). The communication
    /// points are n·h, not a running sum, so they carry no rounding drift.
    pub fn run(&mut self, n: usize, h: f64) -> Result<(), String> {
        for i in 0..n {
            self.time = i as f64 * h;
            self.step(h)?;
        }
        Ok(())
    }

    /// The instances in the order [`Scheme::GaussSeidel`] evaluates them.
    pub fn evaluation_order(&self) -> Vec<&str> {
        self.sim.evaluation_order()
    }

    /// The plant's state (alpha1, omega1, alpha2, omega2) now.
    pub fn plant_state(&mut self) -> Result<Vec<f64>, String> {
        let plant = self.topology.plant;
        let vrs = crate::topology::STATE
            .iter()
            .map(|v| self.vr(plant, v))
            .collect::<Result<Vec<_>, _>>()?;
        self.get(plant, &vrs)
    }

    /// Current Real values of an instance's variables (for checks after a run).
    pub fn get(&mut self, instance: &str, vrs: &[u32]) -> Result<Vec<f64>, String> {
        Ok(self.sim.get_real(instance, vrs)?)
    }

    /// Value reference of `instance.name`.
    pub fn vr(&self, instance: &str, name: &str) -> Result<u32, String> {
        Ok(self.sim.vr(instance, name)?)
    }

    /// The runner underneath.
    pub fn simulation(&mut self) -> &mut Simulation {
        &mut self.sim
    }
}
