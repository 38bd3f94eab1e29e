//! A model-exchange FMU (FMI 2.0 or 3.0) as a co-simulation component: the runner integrates it over
//! each communication step with its own integrator, so a system can hold an FMU exported
//! without co-simulation (or one the SSD asks to run as `implementation="ModelExchange"`).
//!
//! The integrator: Dormand–Prince 5(4) with the standard error estimate and step-size control
//! (Hairer, Nørsett & Wanner, "Solving ODEs I", II.4; err = RMS of e_i / (atol_i + rtol
//! max(|x0_i|, |x1_i|)), h' = h min(5, max(0.2, 0.9 err^(-1/5)))), relative tolerance the
//! experiment's (default 1e-6), absolute 1e-3 rtol times each state's nominal. Written here, not
//! taken from the runtime's `rustfmu::solver` (sized at compile time, `SVector<f64, N>`) or from
//! ode_solvers (it keeps every step in growing Vecs, and its `System::system(&self, ..)` cannot
//! call the FMU, which needs `&mut`); events need the step's start kept to locate a crossing.
//!
//! Events (FMI 2.0, 3.2.2): time events (nextEventTime) end an integration step exactly there;
//! a state event is a sign change of an event indicator over an accepted step, located by
//! bisection on θ of the step made again from its start with θ h (to 1e-12 relative in time), the
//! state set just after the crossing; step events from fmi2CompletedIntegratorStep. At each,
//! fmi2EnterEventMode, fmi2NewDiscreteStates until no new discrete states are needed,
//! fmi2EnterContinuousTimeMode, and the states read back.

use crate::common::{Fmi2Error, FmuState, dispatch_with};
use crate::fmi2::Instance2;
use crate::fmi3::Instance3;
use rustfmu::fmi2::abi::{fmi2EventInfo, fmi2False};

/// The model-exchange instance integrated: FMI 2.0's, or FMI 3.0's (fmi3UpdateDiscreteStates
/// answered as fmi2NewDiscreteStates' event info; its Event Mode after initialization as FMI
/// 2.0's).
pub enum MeInner {
    V2(Instance2),
    V3(Instance3),
}

dispatch_with! {
    values_and_states;
    MeInner { V2, V3 }
    fn setup_experiment(&mut self, tolerance: Option<f64>, start: f64, stop: Option<f64>) -> Result<(), Fmi2Error>;
    fn exit_initialization_mode(&mut self) -> Result<(), Fmi2Error>;
    fn reset(&mut self) -> Result<(), Fmi2Error>;
    fn set_time(&mut self, t: f64) -> Result<(), Fmi2Error>;
    fn set_continuous_states(&mut self, x: &[f64]) -> Result<(), Fmi2Error>;
    fn get_derivatives(&mut self, dx: &mut [f64]) -> Result<(), Fmi2Error>;
    fn get_event_indicators(&mut self, z: &mut [f64]) -> Result<(), Fmi2Error>;
    fn get_continuous_states(&mut self, x: &mut [f64]) -> Result<(), Fmi2Error>;
    fn get_nominals(&mut self, x: &mut [f64]) -> Result<(), Fmi2Error>;
    fn completed_integrator_step(&mut self, no_set_prior: bool) -> Result<(bool, bool), Fmi2Error>;
    fn enter_event_mode(&mut self) -> Result<(), Fmi2Error>;
    fn new_discrete_states(&mut self) -> Result<fmi2EventInfo, Fmi2Error>;
    fn enter_continuous_time_mode(&mut self) -> Result<(), Fmi2Error>;
}

// Dormand–Prince 5(4) tableau.
const C: [f64; 7] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
        0.0,
    ],
    [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];
/// The 5th-order solution's weights (the last row of A: first same as last).
const B: [f64; 7] = [A[6][0], A[6][1], A[6][2], A[6][3], A[6][4], A[6][5], 0.0];
/// 5th minus 4th order weights: the local error estimate.
const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

/// Most integration steps in one communication step before it fails.
const MAX_STEPS: usize = 1_000_000;

/// The integrator's and the event logic's own state, kept beside each FMU state.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Clock {
    t: f64,
    next_event: Option<f64>,
    h: f64,
}

impl Clock {
    /// At `t`, no event ahead known, the first step size still to be chosen.
    fn at(t: f64) -> Clock {
        Clock {
            t,
            next_event: None,
            h: 0.0,
        }
    }
}

/// A model-exchange instance (FMI 2.0 or 3.0) stepped as a co-simulation one.
pub struct MeInstance {
    inner: MeInner,
    nx: usize,
    nz: usize,
    rtol: f64,
    clock: Clock,
    x: Vec<f64>,
    nominal: Vec<f64>,
    z: Vec<f64>,
    /// The clock of each FMU state taken, by its index.
    saved: Vec<Option<Clock>>,
    k: Vec<Vec<f64>>,
    scratch: Vec<f64>,
}

/// A trailer on a serialized FMU state: this magic, then t, next event (NaN: none), h.
const TRAILER: &[u8; 8] = b"RFMUME01";

fn importer(m: String) -> Fmi2Error {
    Fmi2Error::Importer(m)
}

// What the integration leaves as it is: the values, the partial derivatives, logging.
dispatch_with! {
    values;
    MeInstance.inner
}

impl MeInstance {
    /// `nx` continuous states, `nz` event indicators (the description's).
    pub fn new(inner: MeInner, nx: usize, nz: usize) -> MeInstance {
        MeInstance {
            inner,
            nx,
            nz,
            rtol: 1e-6,
            clock: Clock::at(0.0),
            x: vec![0.0; nx],
            nominal: vec![1.0; nx],
            z: vec![0.0; nz],
            saved: Vec::new(),
            k: vec![vec![0.0; nx]; 7],
            scratch: vec![0.0; nx],
        }
    }

    pub fn setup_experiment(&mut self, tolerance: Option<f64>, start: f64, stop: Option<f64>) -> Result<(), Fmi2Error> {
        self.rtol = tolerance.filter(|t| *t > 0.0 && t.is_finite()).unwrap_or(1e-6);
        self.clock = Clock::at(start);
        self.inner.setup_experiment(tolerance, start, stop)
    }

    /// Leaves initialization, settles the discrete states at the start (the event iteration),
    /// and enters continuous-time mode.
    pub fn exit_initialization_mode(&mut self) -> Result<(), Fmi2Error> {
        self.inner.exit_initialization_mode()?;
        self.resize()?;
        self.iterate_events()?;
        self.inner.enter_continuous_time_mode()?;
        self.read_back()
    }

    pub fn reset(&mut self) -> Result<(), Fmi2Error> {
        self.clock = Clock::at(0.0);
        self.inner.reset()
    }

    /// FMI 3.0: the numbers of continuous states and event indicators the FMU gives once
    /// initialized (its structural parameters, set in Configuration Mode, may change them from
    /// the description's), and the integrator's vectors sized by them.
    fn resize(&mut self) -> Result<(), Fmi2Error> {
        let MeInner::V3(i) = &mut self.inner else {
            return Ok(());
        };
        let Some((nx, nz)) = i.me_sizes()? else {
            return Ok(());
        };
        if (nx, nz) != (self.nx, self.nz) {
            (self.nx, self.nz) = (nx, nz);
            self.x = vec![0.0; nx];
            self.nominal = vec![1.0; nx];
            self.z = vec![0.0; nz];
            self.k = vec![vec![0.0; nx]; 7];
            self.scratch = vec![0.0; nx];
        }
        Ok(())
    }

    /// fmi2NewDiscreteStates until none are needed (the instance in Event Mode).
    fn iterate_events(&mut self) -> Result<(), Fmi2Error> {
        for _ in 0..10_000 {
            let info = self.inner.new_discrete_states()?;
            if info.terminateSimulation != fmi2False {
                return Err(Fmi2Error::Terminate(self.clock.t));
            }
            self.clock.next_event = (info.nextEventTimeDefined != fmi2False).then_some(info.nextEventTime);
            if info.newDiscreteStatesNeeded == fmi2False {
                return Ok(());
            }
        }
        Err(importer(format!(
            "the event iteration at t = {} did not settle in 10000 rounds",
            self.clock.t
        )))
    }

    /// The states, nominals and event indicators as the FMU has them now.
    fn read_back(&mut self) -> Result<(), Fmi2Error> {
        if self.nx > 0 {
            self.inner.get_continuous_states(&mut self.x)?;
            self.inner.get_nominals(&mut self.nominal)?;
            for n in &mut self.nominal {
                if !(n.is_finite() && *n > 0.0) {
                    *n = 1.0;
                }
            }
        }
        self.inner.get_event_indicators(&mut self.z)
    }

    /// dx/dt at (t, x) into `out`.
    fn rhs(inner: &mut MeInner, t: f64, x: &[f64], out: &mut [f64]) -> Result<(), Fmi2Error> {
        inner.set_time(t)?;
        if !x.is_empty() {
            inner.set_continuous_states(x)?;
            inner.get_derivatives(out)?;
        }
        if out.iter().any(|v| !v.is_finite()) {
            return Err(importer(format!("the derivatives at t = {t} are not finite")));
        }
        Ok(())
    }

    /// One Dormand–Prince step of `h` from (t, x): the 5th-order solution into `x1`, the scaled
    /// error (<= 1: accepted) returned. `k[0]` must hold f(t, x).
    fn dopri(&mut self, t: f64, x: &[f64], h: f64, x1: &mut [f64]) -> Result<f64, Fmi2Error> {
        let n = self.nx;
        for s in 1..7 {
            for (i, (out, x0)) in self.scratch.iter_mut().zip(x).enumerate() {
                *out = x0 + A[s][..s].iter().zip(&self.k).map(|(a, k)| h * a * k[i]).sum::<f64>();
            }
            let (_, after) = self.k.split_at_mut(s);
            Self::rhs(&mut self.inner, t + C[s] * h, &self.scratch, &mut after[0])?;
        }
        let mut sum = 0.0;
        for i in 0..n {
            let mut y = x[i];
            let mut e = 0.0;
            for s in 0..7 {
                y += h * B[s] * self.k[s][i];
                e += h * E[s] * self.k[s][i];
            }
            x1[i] = y;
            let sc = 1e-3 * self.rtol * self.nominal[i] + self.rtol * x[i].abs().max(y.abs());
            sum += (e / sc) * (e / sc);
        }
        Ok(if n == 0 { 0.0 } else { (sum / n as f64).sqrt() })
    }

    /// Integrates from the current time to `end`, handling the events on the way.
    pub fn do_step(&mut self, t: f64, h: f64, no_set_prior: bool) -> Result<(), Fmi2Error> {
        let tol = 1e-9 * self.clock.t.abs().max(1.0);
        if (t - self.clock.t).abs() > tol {
            return Err(importer(format!(
                "step from t = {t}, but the model-exchange component is at t = {}",
                self.clock.t
            )));
        }
        let end = t + h;
        let n = self.nx;
        let mut x1 = vec![0.0; n];
        let mut steps = 0usize;
        if self.clock.h <= 0.0 {
            self.clock.h = (h / 10.0).max(1e-12);
        }
        while self.clock.t < end {
            steps += 1;
            if steps > MAX_STEPS {
                return Err(importer(format!(
                    "more than {MAX_STEPS} integration steps from t = {t} to {end}"
                )));
            }
            let t0 = self.clock.t;
            let stop = match self.clock.next_event {
                Some(te) if te > t0 && te < end => te,
                _ => end,
            };
            let mut step = self.clock.h.min(stop - t0);
            if stop - (t0 + step) < 1e-12 * stop.abs().max(1.0) {
                step = stop - t0;
            }
            let x0 = self.x.clone();
            let mut k0 = std::mem::take(&mut self.k[0]);
            Self::rhs(&mut self.inner, t0, &x0, &mut k0)?;
            self.k[0] = k0;
            let err = self.dopri(t0, &x0, step, &mut x1)?;
            let grow = if err > 0.0 { 0.9 * err.powf(-0.2) } else { 5.0 };
            if err > 1.0 && step > 1e-14 * t0.abs().max(1.0) {
                self.clock.h = step * grow.clamp(0.2, 1.0);
                continue;
            }
            // Accepted: the end point, or the first crossing of an event indicator inside.
            let t1 = if step == stop - t0 { stop } else { t0 + step };
            self.inner.set_time(t1)?;
            if n > 0 {
                self.inner.set_continuous_states(&x1)?;
            }
            let mut z1 = vec![0.0; self.nz];
            self.inner.get_event_indicators(&mut z1)?;
            let crossed = |z0: &[f64], z1: &[f64]| z0.iter().zip(z1).any(|(a, b)| (*a > 0.0) != (*b > 0.0));
            let mut at = t1;
            let mut state_event = false;
            if crossed(&self.z, &z1) {
                // Bisection on θ: the step made again from (t0, x0) with θ step.
                let (mut lo, mut hi) = (0.0f64, 1.0f64);
                let z0 = self.z.clone();
                let mut x_hi = x1.clone();
                let mut xm = vec![0.0; n];
                while (hi - lo) * step > 1e-12 * t1.abs().max(1.0) {
                    let mid = 0.5 * (lo + hi);
                    // k[0] still holds f(t0, x0): dopri writes the other stages only.
                    self.dopri(t0, &x0, mid * step, &mut xm)?;
                    self.inner.set_time(t0 + mid * step)?;
                    if n > 0 {
                        self.inner.set_continuous_states(&xm)?;
                    }
                    let mut zm = vec![0.0; self.nz];
                    self.inner.get_event_indicators(&mut zm)?;
                    if crossed(&z0, &zm) {
                        hi = mid;
                        x_hi.copy_from_slice(&xm);
                    } else {
                        lo = mid;
                    }
                }
                at = t0 + hi * step;
                x1.copy_from_slice(&x_hi);
                self.inner.set_time(at)?;
                if n > 0 {
                    self.inner.set_continuous_states(&x1)?;
                }
                state_event = true;
            }
            self.clock.t = at;
            self.x.copy_from_slice(&x1);
            let (step_event, terminate) = self.inner.completed_integrator_step(no_set_prior)?;
            if terminate {
                return Err(Fmi2Error::Terminate(at));
            }
            let time_event = self.clock.next_event.is_some_and(|te| te <= at);
            if state_event || step_event || time_event {
                self.inner.enter_event_mode()?;
                self.iterate_events()?;
                self.inner.enter_continuous_time_mode()?;
                self.read_back()?;
            } else {
                self.inner.get_event_indicators(&mut self.z)?;
            }
            if !state_event {
                self.clock.h = step * grow.clamp(0.2, 5.0);
            }
            if (end - self.clock.t).abs() <= 1e-12 * end.abs().max(1.0) {
                self.clock.t = end;
            }
        }
        Ok(())
    }

    /// Not offered: the runner's integration has no output derivatives of its own.
    pub fn get_output_derivatives(&mut self, _vrs: &[u32], _out: &mut [f64]) -> Result<(), Fmi2Error> {
        Err(importer(
            "a model-exchange component gives no output derivatives".into(),
        ))
    }

    pub fn set_input_derivatives(&mut self, _vrs: &[u32], _values: &[f64]) -> Result<(), Fmi2Error> {
        Err(importer(
            "a model-exchange component does not interpolate inputs".into(),
        ))
    }

    /// The integrator's clock kept with the FMU state `s`.
    fn clock_of(&self, s: &FmuState) -> Result<Clock, Fmi2Error> {
        self.saved
            .get(s.0)
            .copied()
            .flatten()
            .ok_or_else(|| importer(format!("FMU state {} is not one of this instance's", s.0)))
    }

    fn remember(&mut self, s: &FmuState) {
        if self.saved.len() <= s.0 {
            self.saved.resize(s.0 + 1, None);
        }
        self.saved[s.0] = Some(self.clock);
    }

    pub fn get_fmu_state(&mut self) -> Result<FmuState, Fmi2Error> {
        let s = self.inner.get_fmu_state()?;
        self.remember(&s);
        Ok(s)
    }

    pub fn update_fmu_state(&mut self, s: &FmuState) -> Result<(), Fmi2Error> {
        self.inner.update_fmu_state(s)?;
        self.remember(s);
        Ok(())
    }

    pub fn set_fmu_state(&mut self, s: &FmuState) -> Result<(), Fmi2Error> {
        let clock = self.clock_of(s)?;
        self.inner.set_fmu_state(s)?;
        self.clock = clock;
        self.read_back()
    }

    pub fn free_fmu_state(&mut self, s: FmuState) -> Result<(), Fmi2Error> {
        if let Some(slot) = self.saved.get_mut(s.0) {
            *slot = None;
        }
        self.inner.free_fmu_state(s)
    }

    pub fn serialize_fmu_state(&mut self, s: &FmuState) -> Result<Vec<u8>, Fmi2Error> {
        let clock = self.clock_of(s)?;
        let mut bytes = self.inner.serialize_fmu_state(s)?;
        bytes.extend_from_slice(TRAILER);
        bytes.extend_from_slice(&clock.t.to_le_bytes());
        bytes.extend_from_slice(&clock.next_event.unwrap_or(f64::NAN).to_le_bytes());
        bytes.extend_from_slice(&clock.h.to_le_bytes());
        Ok(bytes)
    }

    pub fn deserialize_fmu_state(&mut self, bytes: &[u8]) -> Result<FmuState, Fmi2Error> {
        let n = bytes.len();
        if n < 32 || &bytes[n - 32..n - 24] != TRAILER {
            return Err(importer("not a serialized state of a model-exchange component".into()));
        }
        let f = |at: usize| f64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"));
        let clock = Clock {
            t: f(n - 24),
            next_event: Some(f(n - 16)).filter(|x| !x.is_nan()),
            h: f(n - 8),
        };
        let s = self.inner.deserialize_fmu_state(&bytes[..n - 32])?;
        if self.saved.len() <= s.0 {
            self.saved.resize(s.0 + 1, None);
        }
        self.saved[s.0] = Some(clock);
        Ok(s)
    }
}
