//! The version-neutral calls of a [`Container`]: logging, the experiment, the modes, the values
//! (all or nothing) and the step.

use crate::*;

/// A value set before initialization (FMI 3.0 reads it back in Instantiated, where the FMI 2.0
/// components cannot be read).
#[derive(Clone, Debug)]
pub(crate) enum Held {
    Number(f64),
    Integer(i64),
    Boolean(bool),
}

/// A value of a getter's or setter's type: read from a start value of the spec, or from a value
/// set before initialization.
pub(crate) trait Scalar: Sized + Copy {
    fn from_start(text: &str) -> Option<Self>;
    fn held(self) -> Held;
    fn from_held(h: &Held) -> Option<Self>;
}

/// `Scalar` for a type: the `Held` variant it is kept as, the conversions to and from it
/// (`|x| ...`), and how its start text reads (the number types: `str::parse`).
macro_rules! scalar {
    ($ty:ty, $variant:ident, |$x:ident| $to:expr, |$y:ident| $from:expr, $parse:expr) => {
        impl Scalar for $ty {
            fn from_start(text: &str) -> Option<$ty> {
                $parse(text.trim())
            }
            fn held(self) -> Held {
                let $x = self;
                Held::$variant($to)
            }
            fn from_held(h: &Held) -> Option<$ty> {
                match h {
                    Held::$variant($y) => $from,
                    _ => None,
                }
            }
        }
    };
}

scalar!(f64, Number, |x| x, |x| Some(*x), |t: &str| t.parse().ok());
scalar!(i32, Integer, |x| i64::from(x), |x| i32::try_from(*x).ok(), |t: &str| t
    .parse()
    .ok());
scalar!(i64, Integer, |x| x, |x| Some(*x), |t: &str| t.parse().ok());
scalar!(bool, Boolean, |x| x, |x| Some(*x), |t: &str| match t {
    "true" | "1" => Some(true),
    "false" | "0" => Some(false),
    _ => None,
});

impl Container {
    pub(crate) fn set_debug_logging(&mut self, function: &str, on: bool, categories: &[*const c_char]) -> Outcome {
        self.check(Call::SetDebugLogging, function)?;
        for &p in categories {
            match text(p) {
                Some(n) if LOG_CATEGORIES.iter().any(|(c, _)| *c == n) => {}
                Some(n) => {
                    let known: Vec<&str> = LOG_CATEGORIES.iter().map(|(c, _)| *c).collect();
                    return Err(self.error(&format!(
                        "{function}: unknown log category '{n}' (this FMU's: {})",
                        known.join(", ")
                    )));
                }
                None => return Err(self.error(&format!("{function}: a category is NULL"))),
            }
        }
        self.sink.logging_on.set(on);
        for i in 0..self.sim.len() {
            let _ = self.sim.instance_mut(i).set_debug_logging(on, &[]);
        }
        Ok(fmi2OK)
    }

    /// The experiment's tolerance, start and stop time, checked and handed to every component
    /// (fmi2SetupExperiment; the first half of fmi3EnterInitializationMode).
    pub(crate) fn setup(
        &mut self,
        function: &str,
        tol: Option<f64>,
        start: f64,
        stop: Option<f64>,
    ) -> Result<(), Status> {
        if !start.is_finite() {
            return Err(self.error(&format!("{function}: startTime = {start}")));
        }
        if let Some(tol) = tol
            && !(tol.is_finite() && tol > 0.0)
        {
            return Err(self.error(&format!("{function}: tolerance = {tol} must be finite and > 0")));
        }
        if let Some(s) = stop
            && !(s.is_finite() && s >= start)
        {
            return Err(self.error(&format!(
                "{function}: stopTime = {s} must be finite and not before startTime = {start}"
            )));
        }
        for i in 0..self.sim.len() {
            let r = self.sim.instance_mut(i).setup_experiment(tol, start, stop);
            if let Err(e) = r {
                let name = self.sim.component_descriptions()[i].0.to_owned();
                let e = Error::fmi(&name, "fmi2SetupExperiment", &e, None, "");
                return Err(self.refused(function, e));
            }
        }
        self.time = start;
        self.last_successful = start;
        self.stop_time = stop;
        Ok(())
    }

    pub(crate) fn enter_initialization_mode(&mut self, function: &str) -> Outcome {
        let saved = self.snapshot();
        self.every_component_moves(
            function,
            saved,
            State::InitializationMode,
            "fmi2EnterInitializationMode",
            |i| i.enter_initialization_mode(),
        )
    }

    /// `call` (the FMI 2.0 function `component_function`) of every component, which moves the
    /// container to `to`; a failure undone to the snapshot `saved` where there is one.
    fn every_component_moves(
        &mut self,
        function: &str,
        saved: bool,
        to: State,
        component_function: &str,
        call: impl Fn(&mut InstanceCS) -> Result<(), Fmi2Error>,
    ) -> Outcome {
        if let Err(e) = each_raw(self, component_function, call) {
            return Err(self.undo(function, e, saved));
        }
        self.state = to;
        self.dirty = true;
        Ok(fmi2OK)
    }

    /// A step from `t` refused before anything moved: the container is in StepFailed at `t`
    /// (fmi2Discard, with the reason `message`).
    fn step_discarded(&mut self, t: f64, message: &str) -> Status {
        self.state = State::StepFailed;
        self.last_successful = t;
        self.sink.log(fmi2Discard, "logStatusDiscard", message);
        fmi2Discard
    }

    pub(crate) fn exit_initialization_mode(&mut self, function: &str) -> Outcome {
        self.check(Call::ExitInitializationMode, function)?;
        let saved = self.snapshot();
        // As the runner: the connections once per component, then every component leaves.
        for _ in 0..self.sim.len() {
            let t = self.time;
            if let Err(e) = self.sim.propagate(t) {
                return Err(self.undo(function, e, saved));
            }
        }
        self.every_component_moves(
            function,
            saved,
            State::StepComplete,
            "fmi2ExitInitializationMode",
            |i| i.exit_initialization_mode(),
        )?;
        if self.sim.steps_to_clock_ticks() {
            // The run's first point (its clocks tick at the start time, every Event Mode ends),
            // which the first step starts from.
            let t = self.time;
            if let Err(e) = self.sim.communication_point(t) {
                return Err(self.failed(function, e));
            }
            self.dirty = false;
        }
        Ok(fmi2OK)
    }

    pub(crate) fn terminate(&mut self, function: &str) -> Outcome {
        self.check(Call::Terminate, function)?;
        each(self, "fmi2Terminate", |i| i.terminate())?;
        self.state = State::Terminated;
        Ok(fmi2OK)
    }

    pub(crate) fn reset(&mut self, function: &str) -> Outcome {
        self.check(Call::Reset, function)?;
        each(self, "fmi2Reset", |i| i.reset())?;
        if let Err(e) = self.sim.apply_starts() {
            return Err(self.failed(function, e));
        }
        self.state = State::Instantiated;
        self.time = 0.0;
        self.last_successful = 0.0;
        self.stop_time = None;
        self.dirty = true;
        self.held.clear();
        self.held_strings.clear();
        Ok(fmi2OK)
    }

    /// Keeps a value set in Instantiated, to be read back there.
    pub(crate) fn hold(&mut self, vr: u32, h: Held) {
        let n = self.ports.len();
        self.held.resize(n, None);
        self.held[vr as usize] = Some(h);
    }

    /// The ports of `vrs`, each checked to be of type `ty`.
    pub(crate) fn ports_of(&self, vrs: &[u32], ty: Type, asked: &str, function: &str) -> Result<Vec<Port>, Status> {
        vrs.iter().map(|&v| self.port(v, ty, asked, function)).collect()
    }

    /// A value before initialization (FMI 3.0 getters in Instantiated): the one set since
    /// instantiation (or reset), else the spec's start value.
    pub(crate) fn start_of<T: Scalar>(&self, vr: u32, p: &Port, function: &str) -> Result<T, Status> {
        if let Some(Some(h)) = self.held.get(vr as usize)
            && let Some(x) = T::from_held(h)
        {
            return Ok(x);
        }
        let e = (p.component != TIME).then(|| &self.spec.variables[vr as usize]);
        match e.and_then(|e| e.start.as_deref()).and_then(T::from_start) {
            Some(x) => Ok(x),
            None => Err(self.error(&format!(
                "{function}: '{}' (vr {vr}) has no start value: it is known after initialization begins",
                self.name(vr)
            ))),
        }
    }

    /// Reads `vrs` of type `ty` into `out` (one value per value reference) with `get`; `time`
    /// gives the independent variable's value in the getter's type (FMI 3.0 Float64 only).
    pub(crate) fn get_values<T: Scalar>(
        &mut self,
        function: &str,
        ty: Type,
        asked: &str,
        vrs: &[u32],
        out: &mut [T],
        get: impl Fn(&mut InstanceCS, &[u32], &mut [T]) -> Result<(), Fmi2Error>,
        finite: impl Fn(&T) -> bool,
        time: impl Fn(f64) -> Option<T>,
    ) -> Outcome {
        self.check(Call::GetValues, function)?;
        let ports = self.ports_of(vrs, ty, asked, function)?;
        let nvr = vrs.len();
        if self.state == State::Instantiated {
            // FMI 3.0 only (2.0's table refuses it): the start values.
            for k in 0..nvr {
                out[k] = match (ports[k].component, time(self.time)) {
                    (TIME, Some(t)) => t,
                    _ => self.start_of(vrs[k], &ports[k], function)?,
                };
            }
            return Ok(fmi2OK);
        }
        if nvr > 0 {
            self.settle(function)?;
        }
        // One call per run of variables of the same component.
        let mut i = 0;
        let mut component_vrs = Vec::with_capacity(nvr);
        while i < nvr {
            let c = ports[i].component;
            let j = i + ports[i..].iter().take_while(|p| p.component == c).count();
            if c == TIME {
                let t = time(self.time).expect("time is Float64");
                out[i..j].fill(t);
                i = j;
                continue;
            }
            component_vrs.clear();
            component_vrs.extend(ports[i..j].iter().map(|p| p.vr));
            let r = get(self.sim.instance_mut(c), &component_vrs, &mut out[i..j]);
            self.component_call(function, vrs[i], r)?;
            i = j;
        }
        for k in 0..nvr {
            if !finite(&out[k]) {
                return Err(self.error(&format!(
                    "{function}: '{}' (vr {}) is not a finite number",
                    self.name(vrs[k]),
                    vrs[k]
                )));
            }
        }
        Ok(fmi2OK)
    }

    /// Reads the String variables `vrs` into `self.strings`.
    pub(crate) fn get_strings(&mut self, function: &str, vrs: &[u32]) -> Outcome {
        self.check(Call::GetValues, function)?;
        let ports = self.ports_of(vrs, Type::String, "String", function)?;
        let mut strings = Vec::with_capacity(vrs.len());
        if self.state == State::Instantiated {
            for &vr in vrs {
                if let Some(Some(s)) = self.held_strings.get(vr as usize) {
                    strings.push(s.clone());
                    continue;
                }
                match self.spec.variables[vr as usize].start.as_deref() {
                    Some(s) => strings.push(CString::new(s).unwrap_or_default()),
                    None => {
                        return Err(self.error(&format!(
                            "{function}: '{}' (vr {vr}) has no start value: it is known after initialization begins",
                            self.name(vr)
                        )));
                    }
                }
            }
            self.strings = strings;
            return Ok(fmi2OK);
        }
        if !vrs.is_empty() {
            self.settle(function)?;
        }
        for (k, p) in ports.iter().enumerate() {
            let mut s = vec![CString::default()];
            let r = self.sim.instance_mut(p.component).get_string(&[p.vr], &mut s);
            self.component_call(function, vrs[k], r)?;
            strings.push(s.pop().unwrap_or_default());
        }
        self.strings = strings;
        Ok(fmi2OK)
    }

    /// Sets `vrs` of type `ty`: every value reference and value checked first (all or nothing).
    pub(crate) fn set_values<T: Scalar>(
        &mut self,
        function: &str,
        ty: Type,
        asked: &str,
        vrs: &[u32],
        values: &[T],
        number: impl Fn(&T) -> Option<f64>,
        set: impl Fn(&mut InstanceCS, u32, T) -> Result<(), Fmi2Error>,
    ) -> Outcome {
        let call = if ty == Type::Real {
            Call::SetValues
        } else {
            Call::SetDiscreteValues
        };
        self.check(call, function)?;
        let mut ports = Vec::with_capacity(vrs.len());
        for (k, &v) in vrs.iter().enumerate() {
            let p = self.port(v, ty, asked, function)?;
            self.settable(v, &p, function)?;
            if let Some(x) = number(&values[k]) {
                let name = self.name(v);
                if !x.is_finite() {
                    return Err(self.error(&format!(
                        "{function}: '{name}' (vr {v}) = {x}: not a finite number; nothing set"
                    )));
                }
                if p.min.is_some_and(|m| x < m) || p.max.is_some_and(|m| x > m) {
                    return Err(self.error(&format!(
                        "{function}: '{name}' (vr {v}) = {x} is outside [{}, {}]; nothing set",
                        p.min.map_or("-inf".into(), |m| m.to_string()),
                        p.max.map_or("inf".into(), |m| m.to_string())
                    )));
                }
            }
            ports.push(p);
        }
        for (k, p) in ports.iter().enumerate() {
            let r = set(self.sim.instance_mut(p.component), p.vr, values[k]);
            self.component_call(function, vrs[k], r)?;
            for i in 0..self.also[vrs[k] as usize].len() {
                let (c, vr) = self.also[vrs[k] as usize][i];
                let r = set(self.sim.instance_mut(c), vr, values[k]);
                self.component_call(function, vrs[k], r)?;
            }
            if self.state == State::Instantiated {
                self.hold(vrs[k], values[k].held());
            }
        }
        if !vrs.is_empty() {
            self.dirty = true;
        }
        Ok(fmi2OK)
    }

    /// Sets the String variables `vrs` (all or nothing).
    pub(crate) fn set_strings(&mut self, function: &str, vrs: &[u32], values: &[*const c_char]) -> Outcome {
        self.check(Call::SetDiscreteValues, function)?;
        let mut sets = Vec::with_capacity(vrs.len());
        for (k, &v) in vrs.iter().enumerate() {
            let p = self.port(v, Type::String, "String", function)?;
            self.settable(v, &p, function)?;
            if values[k].is_null() {
                return Err(self.error(&format!(
                    "{function}: '{}' (vr {v}): the value is NULL; nothing set",
                    self.name(v)
                )));
            }
            // SAFETY: non-NULL (checked above) and NUL-terminated (the importer's promise).
            sets.push((p, unsafe { CStr::from_ptr(values[k]) }.to_owned()));
        }
        for (k, (p, s)) in sets.iter().enumerate() {
            let r = self
                .sim
                .instance_mut(p.component)
                .set_string(&[p.vr], std::slice::from_ref(s));
            self.component_call(function, vrs[k], r)?;
            for i in 0..self.also[vrs[k] as usize].len() {
                let (c, vr) = self.also[vrs[k] as usize][i];
                let r = self.sim.instance_mut(c).set_string(&[vr], std::slice::from_ref(s));
                self.component_call(function, vrs[k], r)?;
            }
            if self.state == State::Instantiated {
                let n = self.ports.len();
                self.held_strings.resize(n, None);
                self.held_strings[vrs[k] as usize] = Some(s.clone());
            }
        }
        if !vrs.is_empty() {
            self.dirty = true;
        }
        Ok(fmi2OK)
    }

    /// A communication step from `t` by `big_h`: n internal steps of the components.
    pub(crate) fn do_step(&mut self, function: &str, t: f64, big_h: f64) -> Outcome {
        self.check(Call::DoStep, function)?;
        if !(big_h > 0.0 && big_h.is_finite()) {
            return Err(self.error(&format!(
                "{function}: communicationStepSize = {big_h} must be finite and > 0; time stays {}",
                self.time
            )));
        }
        // As the FMU runtime: a tolerance for importers that sum their steps.
        let tol = 1e-8 * self.time.abs().max(1.0) + 4.0 * f64::EPSILON * big_h;
        if !t.is_finite() || (t - self.time).abs() > tol {
            return Err(self.error(&format!(
                "{function}: currentCommunicationPoint = {t} does not match the container's time {}",
                self.time
            )));
        }
        let end = t + big_h;
        if end <= t {
            return Err(self.error(&format!(
                "{function}: communicationStepSize = {big_h} is too small to advance time from {t}"
            )));
        }
        if let Some(stop) = self.stop_time
            && end > stop + 1e-8 * stop.abs().max(big_h)
        {
            let given = match self.version {
                Version::Fmi2 => "fmi2SetupExperiment",
                Version::Fmi3 => "fmi3EnterInitializationMode",
            };
            return Err(self.error(&format!(
                "{function}: the step from {t} by {big_h} ends after stopTime = {stop} set in {given}"
            )));
        }
        let ratio = big_h / self.spec.step;
        let n = if (ratio - ratio.round()).abs() <= 1e-9 * ratio.max(1.0) {
            ratio.round().max(1.0)
        } else {
            ratio.ceil().max(1.0)
        };
        if n > MAX_INTERNAL_STEPS {
            return Err(self.step_discarded(
                t,
                &format!(
                    "{function}: a step of {big_h} s from t = {t} is {n} internal steps of {} s, more than {MAX_INTERNAL_STEPS}: discarded, nothing stepped",
                    self.spec.step
                ),
            ));
        }
        let n = n as usize;
        let h = big_h / n as f64;
        if !(t + h > t && end - h < end) {
            // Far from 0 the internal step is below the resolution of time: a component would
            // be asked to step without its time moving. Nothing has moved yet.
            return Err(self.step_discarded(
                t,
                &format!(
                    "{function}: a step of {big_h} s from t = {t} is {n} internal steps of {h} s, too small to advance time there: discarded, nothing stepped (a longer communication step, or a container of a longer internal step)"
                ),
            ));
        }
        let saved = self.snapshot();
        let (time0, dirty0) = (self.time, self.dirty);
        let ticks = self.sim.steps_to_clock_ticks();
        for k in 0..n {
            let tk = t + k as f64 * h;
            self.time = tk;
            if k > 0 && !ticks {
                self.dirty = true;
            }
            let r = if self.dirty {
                self.sim.propagate(tk).map(|_| self.dirty = false)
            } else {
                Ok(())
            };
            let last = k + 1 == n;
            let r = if ticks {
                // A system that steps to its clocks' ticks (LS-BUS networks, clock connections):
                // the internal step as the runner's run takes it, through every tick between,
                // and the point at its end (the clocks tick, every Event Mode ends), so that the
                // next internal step starts from it as the run's does.
                let next = if last { end } else { t + (k + 1) as f64 * h };
                r.and_then(|_| self.sim.step_between_points(tk, next, false))
                    .and_then(|_| self.sim.communication_point(next))
                    .map(|_| self.dirty = false)
            } else {
                r.and_then(|_| self.sim.do_step_with(tk, h, false)).and_then(|_| {
                    // The connections at the step's end, inside the step (undone with it): what
                    // the runner does before it reads the outputs.
                    if last {
                        self.sim.propagate(end).map(|_| self.dirty = false)
                    } else {
                        Ok(())
                    }
                })
            };
            if let Err(e) = r {
                let discard = e.status.as_deref() == Some("Discard");
                let status = self.undo(function, e, saved);
                if saved && self.state != State::Error && self.state != State::Fatal {
                    // Back at the step's start: nothing of it happened.
                    (self.time, self.dirty) = (time0, dirty0);
                    self.last_successful = time0;
                    if discard {
                        self.state = State::StepFailed;
                    }
                } else {
                    self.last_successful = tk;
                    if discard && self.state != State::Fatal {
                        self.state = State::StepFailed;
                    }
                }
                return Err(status);
            }
        }
        self.last_successful = end;
        self.time = end;
        Ok(fmi2OK)
    }
}
