//! One FMU stepped alone, two ways: the Pendulum model's `do_step` called directly in Rust, and
//! any packaged FMU through its C API as an importer calls it (the `.so` unzipped from
//! `target/fmu/<id>.fmu` and loaded by the `fmi` crate). Both run the same swing
//! ([`crate::SWING_START`]) and restart it after a simulated second, so both do the same work.

use crate::{Fmu, SWING_START};
use fmi::fmi2::instance::{CoSimulation, Common, InstanceCS};
use fmi::fmi2::schema::Causality;
use pendulum_fmu::Pendulum;
use rustfmu::Value;
use rustfmu::{Standalone, Variables};
use std::hint::black_box;
use std::time::{Duration, Instant};

/// The plant's step without the FMI layer.
pub struct Direct {
    fresh: Standalone<Pendulum>,
    pub sim: Standalone<Pendulum>,
}

impl Default for Direct {
    fn default() -> Self {
        Self::new()
    }
}

impl Direct {
    pub fn new() -> Direct {
        let mut model = Pendulum::start();
        (model.alpha1_0, model.alpha2_0) = (SWING_START[0].1, SWING_START[1].1);
        let mut sim = Standalone::new(model, 0.0, None);
        sim.initialize().expect("the paper's parameters are valid");
        Direct {
            fresh: sim.clone(),
            sim,
        }
    }

    pub fn restart(&mut self) {
        self.sim.clone_from(&self.fresh);
    }

    #[inline]
    pub fn step(&mut self, t: f64, h: f64) {
        self.sim.time = t;
        self.sim.do_step(h).expect("the swing integrates");
    }

    /// What a master does around a step, without the FMI layer: set the two torques, step, read
    /// the four states.
    #[inline]
    pub fn round_trip(&mut self, t: f64, h: f64, u: [f64; 2]) -> [f64; 4] {
        (self.sim.model.M1, self.sim.model.M2) = (u[0], u[1]);
        self.step(t, h);
        let v = &self.sim.model;
        [v.alpha1, v.omega1, v.alpha2, v.omega2]
    }
}

/// A packaged FMU stepped through its C API.
pub struct ViaFmi {
    pub instance: InstanceCS,
    pub fmu: Fmu,
    starts: Vec<(u32, Value)>,
    pub in_vrs: Vec<u32>,
    pub out_vrs: Vec<u32>,
    out_values: Vec<f64>,
}

impl ViaFmi {
    /// `id`'s FMU, with the swing's start values if it is the Pendulum. A master sets the Real
    /// inputs and reads `outputs` (all Real outputs when `None`).
    pub fn new(id: &str, outputs: Option<&[&str]>) -> Result<ViaFmi, String> {
        let starts: Vec<(&str, Value)> = if id == "Pendulum" {
            SWING_START.iter().map(|(n, v)| (*n, Value::Real(*v))).collect()
        } else {
            vec![]
        };
        ViaFmi::with_starts(id, outputs, &starts)
    }

    /// `id`'s FMU with the given parameter and start values (set in initialization mode).
    pub fn with_starts(id: &str, outputs: Option<&[&str]>, starts: &[(&str, Value)]) -> Result<ViaFmi, String> {
        let fmu = Fmu::load(id)?;
        let instance = fmu.instantiate("bench")?;
        let starts = starts
            .iter()
            .map(|(n, v)| Ok((fmu.typed_vr(n, v.api_type())?, *v)))
            .collect::<Result<_, String>>()?;
        let in_vrs = fmu.reals_of(Causality::Input).map(|v| v.vr).collect();
        let out_vrs: Vec<u32> = match outputs {
            Some(names) => fmu.vrs(names)?,
            None => fmu.reals_of(Causality::Output).map(|v| v.vr).collect(),
        };
        let mut s = ViaFmi {
            instance,
            fmu,
            starts,
            in_vrs,
            out_values: vec![0.0; out_vrs.len()],
            out_vrs,
        };
        s.restart()?;
        Ok(s)
    }

    /// Back to t = 0 and the start values, initialized, with default tolerances.
    pub fn restart(&mut self) -> Result<(), String> {
        let id = &self.fmu.id;
        let e = |what: &str, err: fmi::fmi2::Fmi2Error| format!("{id}: {what} failed: {err:?}");
        self.instance.reset().map_err(|err| e("fmi2Reset", err))?;
        self.instance
            .setup_experiment(None, 0.0, None)
            .map_err(|err| e("fmi2SetupExperiment", err))?;
        self.instance
            .enter_initialization_mode()
            .map_err(|err| e("fmi2EnterInitializationMode", err))?;
        for (vr, v) in &self.starts {
            let vr = [*vr];
            match *v {
                Value::Real(x) => self.instance.set_real(&vr, &[x]),
                Value::Integer(x) => self.instance.set_integer(&vr, &[x]),
                Value::Boolean(x) => self.instance.set_boolean(&vr, &[i32::from(x)]),
                other => unreachable!("the benchmark topologies hold FMI 2.0 values only, not {other:?}"),
            }
            .map_err(|err| e(&format!("setting start value {v:?} (vr {})", vr[0]), err))?;
        }
        self.instance
            .exit_initialization_mode()
            .map_err(|err| e("fmi2ExitInitializationMode", err))?;
        Ok(())
    }

    #[inline]
    pub fn step(&mut self, t: f64, h: f64) {
        self.instance
            .do_step(t, h, true)
            .expect("fmi2DoStep returns fmi2OK on the swing");
    }

    /// fmi2SetReal of every Real input, fmi2DoStep, fmi2GetReal of the outputs.
    #[inline]
    pub fn round_trip(&mut self, t: f64, h: f64, u: &[f64]) -> &[f64] {
        self.instance
            .set_real(&self.in_vrs, u)
            .expect("fmi2SetReal returns fmi2OK");
        self.step(t, h);
        self.instance
            .get_real(&self.out_vrs, &mut self.out_values)
            .expect("fmi2GetReal returns fmi2OK");
        &self.out_values
    }
}

/// Times `iters` calls of `step(t, h)` on consecutive communication points, restarting (untimed)
/// after every simulated second: what criterion's `iter_custom` wants.
pub fn time_steps<S>(
    s: &mut S,
    iters: u64,
    h: f64,
    restart: impl Fn(&mut S),
    mut step: impl FnMut(&mut S, f64, f64),
) -> Duration {
    let per_swing = ((1.0 / h).round() as u64).max(1);
    let mut total = Duration::ZERO;
    let mut done = 0;
    while done < iters {
        restart(s);
        let n = per_swing.min(iters - done);
        let start = Instant::now();
        for k in 0..n {
            step(black_box(&mut *s), k as f64 * h, h);
        }
        total += start.elapsed();
        done += n;
    }
    total
}
