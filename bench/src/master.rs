//! A native co-simulation master on the `fmi` crate's importer: fixed communication step,
//! Jacobi scheme (all outputs at t are read, all inputs set, then every FMU steps from t to t+h,
//! as fmpy.ssp and libcosim's fixed-step algorithm do). All buffers are made when the master is
//! built, so a step allocates nothing and the time measured is the FMUs' and the wrapper's.

use crate::Fmu;
use crate::topology::Topology;
use fmi::fmi2::instance::{CoSimulation, Common, InstanceCS};

struct Slave {
    name: &'static str,
    instance: InstanceCS,
    /// Outputs read after each step (connected outputs, and the fed-back states).
    out_vrs: Vec<u32>,
    out_values: Vec<f64>,
    /// Inputs set before each step.
    in_vrs: Vec<u32>,
    in_values: Vec<f64>,
    starts: Vec<(u32, f64)>,
}

/// (from slave, index into its out_values) -> (to slave, index into its in_values)
#[derive(Clone, Copy)]
struct Link {
    from: (usize, usize),
    to: (usize, usize),
}

struct Feedback {
    plant: usize,
    /// Indices of x in the plant's out_values, and of u in its in_values.
    states: [usize; 4],
    inputs: [usize; 2],
    k: [[f64; 4]; 2],
}

pub struct Master {
    pub topology: Topology,
    slaves: Vec<Slave>,
    links: Vec<Link>,
    feedback: Option<Feedback>,
    /// Kept alive for the instances (they hold the libraries these unzipped).
    _fmus: Vec<Fmu>,
    pub time: f64,
}

fn index_of(list: &mut Vec<u32>, vr: u32) -> usize {
    match list.iter().position(|v| *v == vr) {
        Some(i) => i,
        None => {
            list.push(vr);
            list.len() - 1
        }
    }
}

impl Master {
    /// Loads every FMU of the topology and resolves every name; the error names what is missing.
    pub fn new(topology: Topology) -> Result<Master, String> {
        let mut fmus: Vec<Fmu> = Vec::new();
        for s in &topology.slaves {
            if !fmus.iter().any(|f| f.id == s.fmu) {
                fmus.push(Fmu::load(s.fmu)?);
            }
        }
        let fmu_of = |instance: &str| -> Result<(usize, &Fmu), String> {
            let i = topology
                .slaves
                .iter()
                .position(|s| s.instance == instance)
                .ok_or_else(|| format!("topology '{}': no instance named '{instance}'", topology.name))?;
            let fmu = fmus
                .iter()
                .find(|f| f.id == topology.slaves[i].fmu)
                .expect("loaded above");
            Ok((i, fmu))
        };
        let mut slaves: Vec<Slave> = Vec::new();
        for s in &topology.slaves {
            let fmu = fmus.iter().find(|f| f.id == s.fmu).expect("loaded above");
            slaves.push(Slave {
                name: s.instance,
                instance: fmu.instantiate(s.instance)?,
                out_vrs: vec![],
                out_values: vec![],
                in_vrs: vec![],
                in_values: vec![],
                starts: vec![],
            });
        }
        let mut links = Vec::new();
        for ((from_i, from_v), (to_i, to_v)) in &topology.connections {
            let (fi, ffmu) = fmu_of(from_i)?;
            let (ti, tfmu) = fmu_of(to_i)?;
            let (fvr, tvr) = (ffmu.vr(from_v)?, tfmu.vr(to_v)?);
            let from = (fi, index_of(&mut slaves[fi].out_vrs, fvr));
            let to = (ti, index_of(&mut slaves[ti].in_vrs, tvr));
            links.push(Link { from, to });
        }
        for ((inst, var), value) in &topology.start_values {
            let (i, fmu) = fmu_of(inst)?;
            let vr = fmu.vr(var)?;
            slaves[i].starts.push((vr, *value));
        }
        let feedback = match &topology.feedback {
            None => None,
            Some(f) => {
                let (p, fmu) = fmu_of(f.plant)?;
                let mut states = [0; 4];
                for (slot, name) in states.iter_mut().zip(f.states) {
                    *slot = index_of(&mut slaves[p].out_vrs, fmu.vr(name)?);
                }
                let mut inputs = [0; 2];
                for (slot, name) in inputs.iter_mut().zip(f.inputs) {
                    *slot = index_of(&mut slaves[p].in_vrs, fmu.vr(name)?);
                }
                Some(Feedback {
                    plant: p,
                    states,
                    inputs,
                    k: f.k,
                })
            }
        };
        for s in &mut slaves {
            s.out_values = vec![0.0; s.out_vrs.len()];
            s.in_values = vec![0.0; s.in_vrs.len()];
        }
        Ok(Master {
            topology,
            slaves,
            links,
            feedback,
            _fmus: fmus,
            time: 0.0,
        })
    }

    /// (Re)starts every instance at t = 0 for a run to `stop_time`: fmi2Reset if it ran before,
    /// setup, start values, initialization.
    pub fn initialize(&mut self, stop_time: f64) -> Result<(), String> {
        for s in &mut self.slaves {
            let name = s.name;
            let e = |what: &str, err: fmi::fmi2::Fmi2Error| format!("{name}: {what} failed: {err:?}");
            s.instance.reset().map_err(|err| e("fmi2Reset", err))?;
            s.instance
                .setup_experiment(None, 0.0, Some(stop_time))
                .map_err(|err| e("fmi2SetupExperiment", err))?;
            s.instance
                .enter_initialization_mode()
                .map_err(|err| e("fmi2EnterInitializationMode", err))?;
            for (vr, v) in &s.starts {
                s.instance
                    .set_real(&[*vr], &[*v])
                    .map_err(|err| e("fmi2SetReal (start value)", err))?;
            }
            s.instance
                .exit_initialization_mode()
                .map_err(|err| e("fmi2ExitInitializationMode", err))?;
        }
        self.time = 0.0;
        Ok(())
    }

    /// One communication step of size `h` from `self.time`. Allocates nothing.
    pub fn step(&mut self, h: f64) -> Result<(), String> {
        let t = self.time;
        for s in &mut self.slaves {
            if !s.out_vrs.is_empty() {
                s.instance
                    .get_real(&s.out_vrs, &mut s.out_values)
                    .map_err(|err| format!("{}: fmi2GetReal at t = {t} failed: {err:?}", s.name))?;
            }
        }
        for l in &self.links {
            let v = self.slaves[l.from.0].out_values[l.from.1];
            self.slaves[l.to.0].in_values[l.to.1] = v;
        }
        if let Some(f) = &self.feedback {
            let p = &mut self.slaves[f.plant];
            for (row, input) in f.k.iter().zip(f.inputs) {
                let u: f64 = -row.iter().zip(f.states).map(|(k, i)| k * p.out_values[i]).sum::<f64>();
                p.in_values[input] = u;
            }
        }
        for s in &mut self.slaves {
            if !s.in_vrs.is_empty() {
                s.instance
                    .set_real(&s.in_vrs, &s.in_values)
                    .map_err(|err| format!("{}: fmi2SetReal at t = {t} failed: {err:?}", s.name))?;
            }
            s.instance
                .do_step(t, h, true)
                .map_err(|err| format!("{}: fmi2DoStep({t}, {h}) failed: {err:?}", s.name))?;
        }
        self.time = t + h;
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

    /// Current Real values of an instance's variables (for checks after a run).
    pub fn get(&mut self, instance: &str, vrs: &[u32]) -> Result<Vec<f64>, String> {
        let s = self
            .slaves
            .iter_mut()
            .find(|s| s.name == instance)
            .ok_or_else(|| format!("no instance '{instance}'"))?;
        let mut out = vec![0.0; vrs.len()];
        s.instance
            .get_real(vrs, &mut out)
            .map_err(|err| format!("{instance}: fmi2GetReal failed: {err:?}"))?;
        Ok(out)
    }

    /// Value reference of `instance.name`.
    pub fn vr(&self, instance: &str, name: &str) -> Result<u32, String> {
        let slave = self
            .topology
            .slaves
            .iter()
            .find(|s| s.instance == instance)
            .ok_or_else(|| format!("no instance '{instance}'"))?;
        self._fmus.iter().find(|f| f.id == slave.fmu).expect("loaded").vr(name)
    }
}
