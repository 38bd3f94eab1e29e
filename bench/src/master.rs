//! A native co-simulation master on the `fmi` crate's importer, with a fixed communication step.
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

use crate::Fmu;
use crate::topology::Topology;
use fmi::fmi2::instance::{CoSimulation, Common, InstanceCS};
use rustfmu::Value;

struct Slave {
    name: &'static str,
    instance: InstanceCS,
    /// Outputs read after each step (connected outputs, and the fed-back states).
    out_vrs: Vec<u32>,
    out_values: Vec<f64>,
    /// Inputs set before each step.
    in_vrs: Vec<u32>,
    in_values: Vec<f64>,
    starts: Vec<(u32, Value)>,
}

/// (from slave, index into its out_values) -> (to slave, index into its in_values)
#[derive(Clone, Copy)]
struct Link {
    from: (usize, usize),
    to: (usize, usize),
}

/// How a communication point is evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheme {
    /// In dependency order: each instance's inputs from the outputs read just before (the default).
    GaussSeidel,
    /// Every output read, then every input set: a one-step delay at each feedthrough in a loop.
    Jacobi,
}

pub struct Master {
    pub topology: Topology,
    /// How [`Master::step`] evaluates a communication point (default [`Scheme::GaussSeidel`]).
    pub scheme: Scheme,
    slaves: Vec<Slave>,
    links: Vec<Link>,
    /// The instances in dependency order, each with the links set before its outputs are read.
    order: Vec<(usize, Vec<Link>)>,
    /// Links from an instance later in the order (set after every output was read), and the
    /// instances they set.
    late: (Vec<Link>, Vec<usize>),
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
            let vr = fmu.typed_vr(var, value.api_type())?;
            slaves[i].starts.push((vr, *value));
        }
        for s in &mut slaves {
            s.out_values = vec![0.0; s.out_vrs.len()];
            s.in_values = vec![0.0; s.in_vrs.len()];
        }
        // i must follow j when a link from j reaches an input of i that feeds through.
        let fmu_at = |i: usize| {
            fmus.iter()
                .find(|f| f.id == topology.slaves[i].fmu)
                .expect("loaded above")
        };
        let follows = |i: usize, j: usize| {
            links
                .iter()
                .any(|l| l.from.0 == j && l.to.0 == i && fmu_at(i).feedthrough.contains(&slaves[i].in_vrs[l.to.1]))
        };
        let mut sorted: Vec<usize> = Vec::new();
        while sorted.len() < slaves.len() {
            let ready = (0..slaves.len())
                .find(|&i| {
                    !sorted.contains(&i) && (0..slaves.len()).all(|j| j == i || sorted.contains(&j) || !follows(i, j))
                })
                .ok_or_else(|| {
                    let left: Vec<&str> = (0..slaves.len())
                        .filter(|i| !sorted.contains(i))
                        .map(|i| slaves[i].name)
                        .collect();
                    format!(
                        "topology '{}': algebraic loop (direct feedthrough in a cycle) among {left:?}",
                        topology.name
                    )
                })?;
            sorted.push(ready);
        }
        let position = |i: usize| sorted.iter().position(|&s| s == i).expect("sorted");
        let order = sorted
            .iter()
            .map(|&i| {
                (
                    i,
                    links
                        .iter()
                        .copied()
                        .filter(|l| l.to.0 == i && position(l.from.0) < position(i))
                        .collect(),
                )
            })
            .collect();
        let late_links: Vec<Link> = links
            .iter()
            .copied()
            .filter(|l| position(l.from.0) >= position(l.to.0))
            .collect();
        let mut late_targets: Vec<usize> = late_links.iter().map(|l| l.to.0).collect();
        late_targets.sort_unstable();
        late_targets.dedup();
        Ok(Master {
            topology,
            scheme: Scheme::GaussSeidel,
            order,
            late: (late_links, late_targets),
            slaves,
            links,
            _fmus: fmus,
            time: 0.0,
        })
    }

    /// (Re)starts every instance at t = 0 for a run to `stop_time`: fmi2Reset if it ran before,
    /// parameter and start values, setup, initialization with the connections propagated once
    /// per instance.
    pub fn initialize(&mut self, stop_time: f64) -> Result<(), String> {
        for s in &mut self.slaves {
            let name = s.name;
            let e = |what: &str, err: fmi::fmi2::Fmi2Error| format!("{name}: {what} failed: {err:?}");
            s.instance.reset().map_err(|err| e("fmi2Reset", err))?;
            for (vr, v) in &s.starts {
                let vr = [*vr];
                match *v {
                    Value::Real(x) => s.instance.set_real(&vr, &[x]),
                    Value::Integer(x) => s.instance.set_integer(&vr, &[x]),
                    Value::Boolean(x) => s.instance.set_boolean(&vr, &[i32::from(x)]),
                }
                .map_err(|err| e(&format!("setting the start value {v:?} (vr {})", vr[0]), err))?;
            }
            s.instance
                .setup_experiment(None, 0.0, Some(stop_time))
                .map_err(|err| e("fmi2SetupExperiment", err))?;
        }
        for s in &mut self.slaves {
            s.instance
                .enter_initialization_mode()
                .map_err(|err| format!("{}: fmi2EnterInitializationMode failed: {err:?}", s.name))?;
        }
        for _ in 0..self.slaves.len() {
            self.exchange(0.0)?;
        }
        for s in &mut self.slaves {
            s.instance
                .exit_initialization_mode()
                .map_err(|err| format!("{}: fmi2ExitInitializationMode failed: {err:?}", s.name))?;
        }
        self.time = 0.0;
        Ok(())
    }

    /// Sets every connected input from its output, as [`Master::scheme`] says. Allocates nothing.
    fn exchange(&mut self, t: f64) -> Result<(), String> {
        if self.scheme == Scheme::Jacobi {
            return self.exchange_jacobi(t);
        }
        for (i, before) in &self.order {
            for l in before {
                let v = self.slaves[l.from.0].out_values[l.from.1];
                self.slaves[l.to.0].in_values[l.to.1] = v;
            }
            let s = &mut self.slaves[*i];
            if !before.is_empty() {
                s.instance
                    .set_real(&s.in_vrs, &s.in_values)
                    .map_err(|err| format!("{}: fmi2SetReal at t = {t} failed: {err:?}", s.name))?;
            }
            if !s.out_vrs.is_empty() {
                s.instance
                    .get_real(&s.out_vrs, &mut s.out_values)
                    .map_err(|err| format!("{}: fmi2GetReal at t = {t} failed: {err:?}", s.name))?;
            }
        }
        let (late, targets) = &self.late;
        for l in late {
            let v = self.slaves[l.from.0].out_values[l.from.1];
            self.slaves[l.to.0].in_values[l.to.1] = v;
        }
        for &i in targets {
            let s = &mut self.slaves[i];
            s.instance
                .set_real(&s.in_vrs, &s.in_values)
                .map_err(|err| format!("{}: fmi2SetReal at t = {t} failed: {err:?}", s.name))?;
        }
        Ok(())
    }

    /// Reads every connected output, then sets every connected input.
    fn exchange_jacobi(&mut self, t: f64) -> Result<(), String> {
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
        for s in &mut self.slaves {
            if !s.in_vrs.is_empty() {
                s.instance
                    .set_real(&s.in_vrs, &s.in_values)
                    .map_err(|err| format!("{}: fmi2SetReal at t = {t} failed: {err:?}", s.name))?;
            }
        }
        Ok(())
    }

    /// One communication step of size `h` from `self.time`. Allocates nothing.
    pub fn step(&mut self, h: f64) -> Result<(), String> {
        let t = self.time;
        self.exchange(t)?;
        for s in &mut self.slaves {
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

    /// The instances in the order [`Scheme::GaussSeidel`] evaluates them.
    pub fn evaluation_order(&self) -> Vec<&'static str> {
        self.order.iter().map(|(i, _)| self.slaves[*i].name).collect()
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
