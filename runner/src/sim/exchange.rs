//! A communication point's exchange and the calls around it: the connections propagated (values
//! and, where the FMUs take them, input derivatives), initialization, a step of every component,
//! termination.

use super::*;

impl Simulation {
    /// Sets every connected input from its output, as [`Simulation::scheme`] says (and, with
    /// [`Simulation::input_derivatives`], their first derivatives).
    pub fn propagate(&mut self, t: f64) -> Result<(), Error> {
        crate::isolate::crumb_time(t);
        self.propagate_values(t)?;
        if self.input_derivatives {
            self.propagate_derivatives(t)?;
        }
        Ok(())
    }

    /// The first-order hold of [`Simulation::input_derivatives`].
    pub(super) fn propagate_derivatives(&mut self, t: f64) -> Result<(), Error> {
        if self.dbufs.len() != self.reads.len() {
            self.dbufs = self.reads.iter().map(|r| vec![0.0; r.vrs.len()]).collect();
        }
        for _sweep in 0..2 {
            for i in 0..self.steps.len() {
                let c = self.steps[i].0;
                let Some(r) = self.read_of[c] else { continue };
                let fmu = &self.fmus[self.slaves[c].fmu].description;
                let own = fmu.cs.as_ref().is_some_and(|cs| cs.max_output_derivative_order >= 1) && !self.slaves[c].me;
                let directional = fmu.cs.as_ref().is_some_and(|cs| cs.provides_directional_derivative);
                let vrs = self.reads[r].vrs.clone();
                let mut dy = vec![0.0; vrs.len()];
                let s = &mut self.slaves[c];
                let inst = s.instance.as_mut().expect("instantiated");
                if own {
                    inst.get_output_derivatives(&vrs, &mut dy).map_err(|e| {
                        Error::fmi(
                            &s.name,
                            fname(s.v3, "fmi2GetRealOutputDerivatives"),
                            &e,
                            Some(t),
                            "first-order hold",
                        )
                    })?;
                }
                // The chain rule through the component's feedthrough: J du of its connected inputs.
                let (knowns, du) = self.input_derivative_values(c);
                if directional && du.iter().any(|x| *x != 0.0) {
                    let ft = &self.fmus[self.slaves[c].fmu].feedthrough;
                    if knowns.iter().any(|k| ft.contains(k)) {
                        let mut jdu = vec![0.0; vrs.len()];
                        let s = &mut self.slaves[c];
                        s.instance
                            .as_mut()
                            .expect("instantiated")
                            .get_directional_derivative(Directional {
                                unknowns: &vrs,
                                knowns: &knowns,
                                seed: &du,
                                out: &mut jdu,
                            })
                            .map_err(|e| {
                                Error::fmi(
                                    &s.name,
                                    fname(s.v3, "fmi2GetDirectionalDerivative"),
                                    &e,
                                    Some(t),
                                    "first-order hold",
                                )
                            })?;
                        for (a, b) in dy.iter_mut().zip(jdu) {
                            *a += b;
                        }
                    }
                }
                if let Some((k, x)) = dy.iter().enumerate().find(|(_, x)| !x.is_finite()) {
                    return Err(Error::fmi(
                        &self.slaves[c].name,
                        "fmi2GetRealOutputDerivatives",
                        &crate::fmi2::Fmi2Error::Importer(format!(
                            "the derivative of value reference {} is {x}",
                            vrs[k]
                        )),
                        Some(t),
                        "first-order hold",
                    ));
                }
                self.dbufs[r] = dy;
            }
        }
        for c in 0..self.slaves.len() {
            let interpolates = !self.slaves[c].v3
                && !self.slaves[c].me
                && self.fmus[self.slaves[c].fmu]
                    .description
                    .cs
                    .as_ref()
                    .is_some_and(|cs| cs.can_interpolate_inputs);
            if !interpolates {
                continue;
            }
            let (vrs, du) = self.input_derivative_values(c);
            if vrs.is_empty() {
                continue;
            }
            let s = &mut self.slaves[c];
            s.instance
                .as_mut()
                .expect("instantiated")
                .set_input_derivatives(&vrs, &du)
                .map_err(|e| Error::fmi(&s.name, "fmi2SetRealInputDerivatives", &e, Some(t), "first-order hold"))?;
        }
        Ok(())
    }

    /// The connected inputs of component `c` and their derivatives (its sources' current ones).
    pub(super) fn input_derivative_values(&self, c: usize) -> (Vec<u32>, Vec<f64>) {
        let mut vrs = Vec::new();
        let mut du = Vec::new();
        for w in self.writes.iter().filter(|w| w.port.slave == c) {
            let src = self.dbufs.get(w.source);
            for (j, vr) in w.port.vrs.iter().enumerate() {
                vrs.push(*vr);
                du.push(src.map_or(0.0, |d| d[w.idx[j]]));
            }
        }
        (vrs, du)
    }

    /// Gauss-Seidel's exchange at entry `i` of [`Simulation::steps`]: the component's inputs
    /// set from the outputs read before, then its outputs read.
    pub(super) fn exchange_at_step(&mut self, i: usize, t: f64) -> Result<(), Error> {
        self.typed_inputs(self.steps[i].0, t)?;
        for j in 0..self.steps[i].1.len() {
            let w = self.steps[i].1[j];
            self.write(w, t)?;
        }
        if let Some(r) = self.read_of[self.steps[i].0] {
            self.read(r, t)?;
        }
        self.typed_outputs(self.steps[i].0, t)
    }

    /// Gauss-Seidel's last exchange: the inputs set after every output was read.
    pub(super) fn exchange_late(&mut self, t: f64) -> Result<(), Error> {
        for j in 0..self.late.len() {
            let w = self.late[j];
            self.write(w, t)?;
        }
        self.typed_late(t)
    }

    /// Sets every connected input from its output, as [`Simulation::scheme`] says.
    pub(super) fn propagate_values(&mut self, t: f64) -> Result<(), Error> {
        match self.scheme {
            Scheme::GaussSeidel if !self.loops.is_empty() => self.propagate_with_loops(t)?,
            Scheme::GaussSeidel => {
                for i in 0..self.steps.len() {
                    self.exchange_at_step(i, t)?;
                }
                self.exchange_late(t)?;
            }
            Scheme::Jacobi => {
                for r in 0..self.reads.len() {
                    self.read(r, t)?;
                }
                self.typed_all(true, t)?;
                for w in 0..self.writes.len() {
                    self.write(w, t)?;
                }
                self.typed_all(false, t)?;
            }
        }
        Ok(())
    }

    /// Instantiates every FMU again (after fmi2Fatal).
    pub(super) fn reinstantiate(&mut self) -> Result<(), Error> {
        for i in 0..self.slaves.len() {
            self.slaves[i].instance = None; // fmi2FreeInstance
            let name = self.slaves[i].name.clone();
            let inst = if !self.slaves[i].intermediate.is_empty() {
                let vrs: Vec<u32> = self.slaves[i].intermediate.iter().map(|(_, vr)| *vr).collect();
                self.fmu_of(i)
                    .instantiate_intermediate(&name, &vrs, self.slaves[i].events)?
            } else {
                // As it ran: co-simulation, model exchange, Event Mode or Scheduled Execution.
                make_instance(
                    self.fmu_of(i),
                    &name,
                    self.slaves[i].interface(),
                    self.isolation.as_ref(),
                )?
            };
            self.slaves[i].instance = Some(inst);
        }
        self.runs = 0;
        self.broken = false;
        Ok(())
    }

    /// Steps 1-3 of a run (see the module): (re)starts every instance at t = 0 for a run to
    /// `stop_time`, with `overrides` on top of the system's values.
    pub fn initialize(&mut self, stop_time: f64, overrides: &[(String, Override)]) -> Result<(), Error> {
        let values = self.start_values(overrides)?;
        self.initialize_with(stop_time, &values)
    }

    /// The system's values with `overrides` on top, resolved.
    pub(super) fn start_values(
        &self,
        overrides: &[(String, Override)],
    ) -> Result<Vec<(String, Target, Setter)>, Error> {
        let mut values = self.starts.clone();
        for (key, value) in overrides {
            let (target, setter) = match self.typed_override(key, value)? {
                Some(typed) => typed,
                None => {
                    let target = self.resolve_qualified(key)?;
                    (target, self.override_setter(key, target.ty, value)?)
                }
            };
            match values.iter_mut().find(|(k, _, _)| k == key) {
                Some(slot) => slot.2 = setter,
                None => values.push((key.clone(), target, setter)),
            }
        }
        Ok(values)
    }

    pub(super) fn initialize_with(&mut self, stop_time: f64, values: &[(String, Target, Setter)]) -> Result<(), Error> {
        if self.broken {
            self.reinstantiate()?;
        }
        // No derivatives in Initialization Mode (FMI 2.0, 4.2.4): the first-order hold begins
        // at the first communication point.
        let derivatives = std::mem::replace(&mut self.input_derivatives, false);
        let result = self.initialize_inner(stop_time, values);
        self.input_derivatives = derivatives;
        if let Err(e) = &result {
            self.note(e);
        }
        result
    }

    pub(super) fn note(&mut self, e: &Error) {
        if e.status.as_deref() == Some("Fatal") {
            self.broken = true;
        }
    }

    pub(super) fn initialize_inner(
        &mut self,
        stop_time: f64,
        values: &[(String, Target, Setter)],
    ) -> Result<(), Error> {
        if self.runs > 0 {
            self.each_instance("fmi2Reset", None, "", |_, i| i.reset())?;
        }
        self.runs += 1;
        // FMI 3.0.2: structural parameters are set in Configuration Mode, before the others.
        self.configure(values)?;
        for (key, target, value) in values {
            if !self.is_structural(*target) {
                self.set(key, *target, value)?;
            }
        }
        self.reset_loops(values);
        self.each_instance("fmi2SetupExperiment", None, "", |_, i| {
            i.setup_experiment(None, 0.0, Some(stop_time))
        })?;
        self.each_instance("fmi2EnterInitializationMode", None, "", |_, i| {
            i.enter_initialization_mode()
        })?;
        for _ in 0..self.slaves.len() {
            self.propagate(0.0)?;
        }
        self.each_instance("fmi2ExitInitializationMode", None, "", |_, i| {
            i.exit_initialization_mode()
        })
    }

    /// One communication step from `t` to `t + h`: propagate, then fmi2DoStep of every instance.
    pub fn step(&mut self, t: f64, h: f64) -> Result<(), Error> {
        let r = self.propagate(t).and_then(|_| self.do_step(t, h));
        if let Err(e) = &r {
            self.note(e);
        }
        r
    }

    /// fmi2DoStep(t, h) of every instance, in the system's order (noSetFMUStatePriorToCurrentPoint
    /// = true: nothing is set back before this point).
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<(), Error> {
        self.do_step_with(t, h, true)
    }

    /// fmi2DoStep(t, h, no_set_prior) of every instance, in the system's order; `no_set_prior =
    /// false` when an FMU state of before this point may be set afterwards (a rollback).
    ///
    /// A component that asks to end the simulation ([`crate::ErrorKind::Terminated`]): the
    /// components after it are stepped to where the others are, if they can be (runner/README.md,
    /// "A component that asks to end the simulation").
    pub fn do_step_with(&mut self, t: f64, h: f64, no_set_prior: bool) -> Result<(), Error> {
        crate::isolate::crumb_time(t);
        for i in 0..self.slaves.len() {
            let s = &mut self.slaves[i];
            if let Err(e) = s.instance.as_mut().expect("instantiated").do_step(t, h, no_set_prior) {
                return Err(self.step_failed(i, e, t, h, no_set_prior));
            }
        }
        self.steps_answered(t, h, no_set_prior)
    }

    /// Isolated components: the steps sent and not waited for (an unclocked component's; they
    /// ran in parallel in their processes) waited for, once every component's step is sent, so
    /// that a request to end the simulation made in this step ends the run at it
    /// ([`Simulation::complete_ended_step`]), not at the component's next call.
    pub(super) fn steps_answered(&mut self, t: f64, h: f64, no_set_prior: bool) -> Result<(), Error> {
        if self.isolation.is_none() {
            return Ok(());
        }
        for i in 0..self.slaves.len() {
            if let Err(e) = self.instance(i).sync() {
                return Err(self.step_failed(i, e, t, h, no_set_prior));
            }
        }
        Ok(())
    }

    /// Component `i`'s fmi2DoStep(t, h) failed with `e`, or asked to end the simulation: the
    /// components after it then step to where the others are ([`Simulation::do_step_with`]).
    #[cold]
    #[inline(never)]
    fn step_failed(&mut self, i: usize, e: Fmi2Error, t: f64, h: f64, no_set_prior: bool) -> Error {
        let s = &self.slaves[i];
        let error = Error::fmi(&s.name, fname(s.v3, "fmi2DoStep"), &e, Some(t), &format!("step {h} s"));
        let (at, pending): (f64, Vec<usize>) = match e {
            Fmi2Error::Terminate(at) => (at, (i + 1..self.slaves.len()).collect()),
            // An isolated component's step, answered once every component's step was sent:
            // the others have stepped.
            Fmi2Error::Deferred(d) if d.function == "fmi2DoStep" && d.time == Some(t) => match d.error {
                Fmi2Error::Terminate(at) => (at, Vec::new()),
                _ => return error,
            },
            _ => return error,
        };
        let others_stepped = i > 0 || (pending.is_empty() && self.slaves.len() > 1);
        if let Err(other) = self.complete_ended_step(t, at, t + h, others_stepped, &pending, no_set_prior) {
            return other;
        }
        error
    }

    /// A component asked to end the simulation at `at` in the step from `t`; the components
    /// stepped before it (`others_stepped`) reached `reached`, those of `pending` have not
    /// stepped. Where every component can be at one time, the pending ones step to it and
    /// `back.ending` is that time: `reached` if `at` is it (within 1e-9 relative), else
    /// `at` when no other component stepped yet and each pending one takes a shorter step
    /// (model exchange, or canHandleVariableCommunicationStepSize). A pending component's failure
    /// is the run's; one that asks to end too, at the same time, is taken as it is.
    #[cold]
    pub(super) fn complete_ended_step(
        &mut self,
        t: f64,
        at: f64,
        reached: f64,
        others_stepped: bool,
        pending: &[usize],
        no_set_prior: bool,
    ) -> Result<(), Error> {
        self.back.ending = Some(None);
        let close = |x: f64| 1e-9 * x.abs().max(1.0);
        let target = if (at - reached).abs() <= close(reached) {
            reached
        } else if !others_stepped {
            at
        } else {
            return Ok(());
        };
        if target <= t + close(t) {
            // Nothing reached beyond the last communication point.
            return Ok(());
        }
        let shorter = target < reached;
        for &j in pending {
            let s = &self.slaves[j];
            if shorter
                && !s.me
                && !self.fmus[s.fmu]
                    .description
                    .cs
                    .as_ref()
                    .is_some_and(|cs| cs.can_handle_variable_step)
            {
                return Ok(());
            }
        }
        for &j in pending {
            let s = &mut self.slaves[j];
            let h = target - t;
            match s.instance.as_mut().expect("instantiated").do_step(t, h, no_set_prior) {
                Ok(()) => {}
                Err(Fmi2Error::Terminate(other)) if (other - target).abs() <= close(target) => {}
                Err(Fmi2Error::Terminate(_)) => return Ok(()),
                Err(e) => {
                    return Err(Error::fmi(
                        &s.name,
                        fname(s.v3, "fmi2DoStep"),
                        &e,
                        Some(t),
                        &format!("step {h} s"),
                    ));
                }
            }
        }
        self.back.ending = Some(Some(target));
        Ok(())
    }

    /// fmi2Terminate of every instance.
    pub fn terminate(&mut self) -> Result<(), Error> {
        self.each_instance("fmi2Terminate", None, "", |_, i| i.terminate())
    }

    /// `call(i, instance)` of every instance, in the system's order; the first that fails stops
    /// it, reported as `function` (its FMI 2.0 name) of its component at `time`, doing `what`.
    pub(super) fn each_instance(
        &mut self,
        function: &'static str,
        time: Option<f64>,
        what: &str,
        mut call: impl FnMut(usize, &mut InstanceCS) -> Result<(), Fmi2Error>,
    ) -> Result<(), Error> {
        for i in 0..self.slaves.len() {
            let name = self.slaves[i].name.clone();
            call(i, self.instance(i)).map_err(fmi_err(&name, fname(self.slaves[i].v3, function), time, what))?;
        }
        Ok(())
    }
}
