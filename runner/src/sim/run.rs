//! A run: initialization, the communication steps (fixed, or error-controlled with FMU states
//! kept to step again), the recorded rows.

use super::*;
use crate::ErrorKind;

/// What [`Simulation::through_ticks`] passed: a step taken (from, reached), or a point between
/// two steps where clocks ticked or a component returned early.
pub(super) enum Passed {
    Stepped(f64, f64),
    Point(f64),
}

impl Simulation {
    /// The recorded variables of each instance and type, and the names of the row's columns
    /// (an array's elements each a column: [`Simulation::typed_record`]); the FMI 3.0 variables
    /// FMI 2.0's view leaves out are kept in `self.typed`.
    pub(super) fn record_groups(&mut self, record: &[String]) -> Result<(Vec<RecordGroup>, Vec<String>), Error> {
        let mut groups: Vec<RecordGroup> = Vec::new();
        let mut names = Vec::new();
        self.typed.records.clear();
        for key in record {
            let col = names.len();
            if let Some(r) = self.typed_record(key, col, &mut names)? {
                self.typed.records.push(r);
                continue;
            }
            let t = self.resolve_qualified(key)?;
            let kind = match t.ty {
                Type::Real => Kind::Real,
                Type::Integer | Type::Enumeration => Kind::Integer,
                Type::Boolean => Kind::Boolean,
                Type::String => {
                    let (c, v) = key.split_once('.').unwrap_or((key, ""));
                    return Err(Error::variable(
                        c,
                        v,
                        format!("{key} is a String: it cannot be recorded"),
                    ));
                }
            };
            let i = match groups.iter().position(|g| g.slave == t.slave && g.kind == kind) {
                Some(i) => i,
                None => {
                    groups.push(RecordGroup {
                        slave: t.slave,
                        kind,
                        vrs: Vec::new(),
                        reals: Vec::new(),
                        ints: Vec::new(),
                        columns: Vec::new(),
                    });
                    groups.len() - 1
                }
            };
            groups[i].vrs.push(t.vr);
            groups[i].columns.push(col);
            names.push(key.clone());
        }
        for g in &mut groups {
            g.reals = vec![0.0; g.vrs.len()];
            g.ints = vec![0; g.vrs.len()];
        }
        Ok((groups, names))
    }

    /// One run (see the module): returns the recorded variables at every communication point,
    /// or the failure with what was recorded up to it. `progress(k, n)` is called at every
    /// communication point k = 0..n.
    pub fn run(&mut self, opts: &RunOptions, progress: &mut dyn FnMut(usize, usize)) -> Result<RunResult, Failure> {
        if !(opts.step > 0.0 && opts.step.is_finite()) {
            return Err(Error::usage(format!("step = {} s: must be a positive number", opts.step)).into());
        }
        if !(opts.stop_time >= 0.0 && opts.stop_time.is_finite()) {
            return Err(Error::usage(format!("stop time = {} s: must be a number >= 0", opts.stop_time)).into());
        }
        let l = &opts.loops;
        if !(l.rtol >= 0.0 && l.atol >= 0.0 && l.rtol + l.atol > 0.0 && (l.rtol + l.atol).is_finite()) {
            return Err(Error::usage(format!(
                "algebraic loops: rtol = {}, atol = {}: both numbers >= 0, not both 0",
                l.rtol, l.atol
            ))
            .into());
        }
        self.loop_options = *l;
        let n = (opts.stop_time / opts.step).round() as usize;
        crate::fmu_log::install();
        crate::fmu_log::clear();
        let outcome = self.run_inner(opts, n, progress);
        self.free_early_states();
        match outcome {
            Ok(mut result) => {
                result.loops = self.loop_reports();
                Ok(result)
            }
            Err(mut f) => {
                f.partial.loops = self.loop_reports();
                let log = crate::fmu_log::take();
                if !log.is_empty() {
                    f.error.message = format!("{} | FMU log: {}", f.error.message, log.join(" / "));
                }
                Err(f)
            }
        }
    }

    pub(super) fn run_inner(
        &mut self,
        opts: &RunOptions,
        n: usize,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<RunResult, Failure> {
        if opts.input_derivatives && self.scheme == Scheme::Jacobi {
            return Err(Error::usage(
                "input derivatives (a first-order hold) follow the Gauss-Seidel order: not with the Jacobi scheme",
            )
            .into());
        }
        if opts.input_derivatives && self.scheme == Scheme::GaussSeidel && !self.loops.is_empty() {
            return Err(Error::usage(format!(
                "input derivatives (a first-order hold) through an algebraic loop are not computed: the loop among {} has no derivative sweep; run without them",
                self.loops_named()
            ))
            .into());
        }
        if opts.adaptive.is_some() && self.records_intermediate() {
            return Err(Error::usage(
                "--record-intermediate-values: not with --tolerance (a rejected step's callbacks would give rows of a step taken back)",
            )
            .into());
        }
        self.input_derivatives = opts.input_derivatives;
        self.dbufs.clear();
        let values = self.start_values(&opts.overrides)?;
        let (mut groups, names) = self.record_groups(&opts.record)?;
        let mut stops = Vec::new();
        for (key, limit) in &opts.stop_when_above {
            let col = names.iter().position(|r| r == key).ok_or_else(|| {
                let (c, v) = key.split_once('.').unwrap_or((key, ""));
                Error::variable(
                    c,
                    v,
                    format!("stop condition on {key}: it must be one of the recorded variables"),
                )
            })?;
            stops.push((col, *limit));
        }
        let m = names.len();
        let mut result = RunResult {
            names,
            time: Vec::with_capacity(n + 1),
            values: Vec::with_capacity((n + 1) * m),
            stopped: false,
            fmu_steps: 0,
            rejected: 0,
            note: None,
            loops: Vec::new(),
            terminated: None,
        };
        if let Some(a) = &opts.adaptive {
            match self.why_fixed_steps() {
                None => return self.run_adaptive(opts, a, &values, &mut groups, &stops, result, progress),
                Some(why) => result.note = Some(why),
            }
        }
        self.back.ending = None;
        if let Err(error) = self.initialize_with(n as f64 * opts.step, &values) {
            if error.kind == ErrorKind::Terminated {
                return self.end_on_request(error, None, &mut groups, &mut vec![0.0; m], result);
            }
            return Err(Failure { error, partial: result });
        }
        let ticks = self.steps_to_ticks();
        // Scheduled Execution components: their partitions activated between two propagations.
        let scheduled = self.slaves.iter().any(|s| s.scheduled);
        let mut row = vec![0.0; m];
        for k in 0..=n {
            let t = k as f64 * opts.step;
            let r = (if ticks {
                self.event_point(t)
            } else if scheduled {
                self.exchange(t)
            } else {
                self.propagate(t)
            })
            .and_then(|_| self.read_record(&mut groups, &mut row, t));
            if let Err(error) = r {
                if error.kind == ErrorKind::Terminated {
                    return self.end_on_request(error, Some(t), &mut groups, &mut row, result);
                }
                self.note(&error);
                return Err(Failure { error, partial: result });
            }
            result.time.push(t);
            result.values.extend_from_slice(&row);
            progress(k, n);
            if stops.iter().any(|&(c, limit)| row[c].abs() > limit) {
                result.stopped = k < n;
                break;
            }
            if k == n {
                break;
            }
            if ticks {
                let end = (k + 1) as f64 * opts.step;
                match self.step_to_ticks(t, end, &mut groups, &mut row, &mut result, &stops) {
                    Ok(true) => continue,
                    Ok(false) => break,
                    Err(error) if error.kind == ErrorKind::Terminated => {
                        // A request at a tick's point comes at the point's own time.
                        let point = error.time;
                        return self.end_on_request(error, point, &mut groups, &mut row, result);
                    }
                    Err(error) => {
                        self.note(&error);
                        return Err(Failure { error, partial: result });
                    }
                }
            }
            if let Err(error) = self
                .do_step(t, opts.step)
                .and_then(|_| self.intermediate_rows(t, (k + 1) as f64 * opts.step, &mut result))
            {
                if error.kind == ErrorKind::Terminated {
                    return self.end_on_request(error, None, &mut groups, &mut row, result);
                }
                self.note(&error);
                return Err(Failure { error, partial: result });
            }
            result.fmu_steps += 1;
        }
        if let Err(error) = self.terminate() {
            self.note(&error);
            return Err(Failure { error, partial: result });
        }
        Ok(result)
    }

    /// [`Simulation::through_ticks`] from the communication point `t` to `end`, each tick's
    /// point recorded as a row. Returns false where a stop condition ended the run.
    fn step_to_ticks(
        &mut self,
        t: f64,
        end: f64,
        groups: &mut [RecordGroup],
        row: &mut [f64],
        result: &mut RunResult,
        stops: &[(usize, f64)],
    ) -> Result<bool, Error> {
        self.through_ticks(t, end, &mut |sim, passed| match passed {
            Passed::Stepped(from, reached) => {
                sim.intermediate_rows(from, reached, result)?;
                result.fmu_steps += 1;
                Ok(true)
            }
            Passed::Point(t) => {
                sim.read_record(groups, row, t)?;
                result.time.push(t);
                result.values.extend_from_slice(row);
                if stops.iter().any(|&(c, limit)| row[c].abs() > limit) {
                    result.stopped = true;
                    return Ok(false);
                }
                Ok(true)
            }
        })
    }

    /// From the communication point `t` to `end` (`sim/clocks.rs`): every Event Mode ended,
    /// then a step to each tick before `end` and to each time a component returns early at, where
    /// the clocks and connections tick and the values are propagated
    /// ([`Simulation::event_point`]); then the step to `end` (whose point is the caller's).
    /// `passed` hears of every step taken and every point between; it returns false to stop
    /// there, and then so does this.
    pub(super) fn through_ticks(
        &mut self,
        mut t: f64,
        end: f64,
        passed: &mut dyn FnMut(&mut Simulation, Passed) -> Result<bool, Error>,
    ) -> Result<bool, Error> {
        let close = |x: f64| 1e-9 * x.abs().max(1.0);
        let mut same = 0;
        while same < 1000 {
            let at = match self.settle_clocks(t)? {
                Some(e) if e <= t + close(t) => {
                    self.tick_clocks_now(t)?;
                    same += 1;
                    t
                }
                next => {
                    let to = match next {
                        Some(e) if e < end - close(end) => e,
                        _ => end,
                    };
                    let reached = self.do_step_events(t, to - t)?;
                    passed(self, Passed::Stepped(t, reached))?;
                    same = 0;
                    if reached == end {
                        return Ok(true);
                    }
                    reached
                }
            };
            t = at;
            self.event_point(t)?;
            if !passed(self, Passed::Point(t))? {
                return Ok(false);
            }
        }
        Err(Error::usage(format!(
            "clocks ticked 1000 times at t = {t} s without time advancing (a countdown clock of interval 0 set again at every tick)"
        )))
    }

    /// A communication point `t` as a run takes it, for an importer that runs the whole system
    /// as one FMU (the container, `runner/container`): where the system steps to its clocks'
    /// ticks, the clocks and connections tick and every Event Mode ends
    /// ([`Simulation::event_point`]); where Scheduled Execution components are, their partitions
    /// run ([`Simulation::exchange`]); else the values are propagated.
    pub fn communication_point(&mut self, t: f64) -> Result<(), Error> {
        let r = if self.steps_to_ticks() {
            self.event_point(t)
        } else if self.slaves.iter().any(|s| s.scheduled) {
            self.exchange(t)
        } else {
            self.propagate(t)
        };
        if let Err(e) = &r {
            self.note(e);
        }
        r
    }

    /// The step from the communication point `t` to `end` as a run takes it, for the container:
    /// where the system steps to its clocks' ticks, a step to each tick between, with its point
    /// ([`Simulation::through_ticks`]); else fmi2DoStep of every instance. Not the point at
    /// `end`: [`Simulation::communication_point`] is.
    pub fn step_between_points(&mut self, t: f64, end: f64, no_set_prior: bool) -> Result<(), Error> {
        let r = if self.steps_to_ticks() {
            self.through_ticks(t, end, &mut |_, _| Ok(true)).map(|_| ())
        } else {
            self.do_step_with(t, end - t, no_set_prior)
        };
        if let Err(e) = &r {
            self.note(e);
        }
        r
    }

    /// Whether this system steps to its clocks' ticks (a clock connection, or a clock whose
    /// ticks no fixed step meets): its steps and points are then
    /// [`Simulation::step_between_points`] and [`Simulation::communication_point`].
    pub fn steps_to_clock_ticks(&self) -> bool {
        self.steps_to_ticks()
    }

    /// Why this system cannot take error-controlled steps (None: it can).
    pub fn why_fixed_steps(&self) -> Option<String> {
        for s in &self.slaves {
            let d = &self.fmus[s.fmu].description;
            if s.me {
                // The runner's own integration takes any step; the FMU's state must be settable.
                if !d.me.as_ref().is_some_and(|me| me.can_get_and_set_fmu_state) {
                    return Some(format!(
                        "fixed steps: component '{}' cannot get and set its FMU state (canGetAndSetFMUstate = false), so a step cannot be made again",
                        s.name
                    ));
                }
                continue;
            }
            let Some(cs) = d.cs.as_ref() else {
                return Some(format!("fixed steps: component '{}' is no co-simulation FMU", s.name));
            };
            if matches!(&self.fmus[s.fmu].import, crate::fmu::Import::V3(i) if i.has_clocks()) {
                // Its clocks tick at communication points, with an Event Mode the rollback does
                // not take back.
                return Some(format!(
                    "fixed steps: component '{}' has input clocks, which the runner ticks at fixed communication points",
                    s.name
                ));
            }
            if !cs.can_get_and_set_fmu_state {
                return Some(format!(
                    "fixed steps: component '{}' cannot get and set its FMU state (canGetAndSetFMUstate = false), so a step cannot be made again",
                    s.name
                ));
            }
            if !cs.can_handle_variable_step {
                return Some(format!(
                    "fixed steps: component '{}' cannot take steps of varying size (canHandleVariableCommunicationStepSize = false)",
                    s.name
                ));
            }
        }
        None
    }

    /// Every component's FMU state into `slots` (taken anew, or updated).
    pub(super) fn save_states(&mut self, slots: &mut Vec<FmuState>, t: f64) -> Result<(), Error> {
        if slots.is_empty() {
            self.each_instance("fmi2GetFMUstate", Some(t), "", |_, inst| {
                slots.push(inst.get_fmu_state()?);
                Ok(())
            })
        } else {
            self.each_instance("fmi2GetFMUstate", Some(t), "", |i, inst| {
                inst.update_fmu_state(&slots[i])
            })
        }
    }

    pub(super) fn load_states(&mut self, slots: &[FmuState], t: f64) -> Result<(), Error> {
        self.each_instance("fmi2SetFMUstate", Some(t), "rolling back a rejected step", |i, inst| {
            inst.set_fmu_state(&slots[i])
        })
    }

    /// What the error is estimated on: the `watched` variables, read now, or (none watched)
    /// every connected output as the last propagation read them.
    pub(super) fn estimated(&mut self, watched: &[Target], out: &mut Vec<f64>, t: f64) -> Result<(), Error> {
        out.clear();
        if watched.is_empty() {
            for r in &self.reads {
                out.extend_from_slice(&r.buf);
            }
            return Ok(());
        }
        let mut x = [0.0];
        for w in watched {
            let s = &mut self.slaves[w.slave];
            s.instance
                .as_mut()
                .expect("instantiated")
                .get_real(&[w.vr], &mut x)
                .map_err(|e| Error::fmi(&s.name, fname(s.v3, "fmi2GetReal"), &e, Some(t), "error estimate"))?;
            out.push(x[0]);
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn run_adaptive(
        &mut self,
        opts: &RunOptions,
        a: &Adaptive,
        values: &[(String, Target, Setter)],
        groups: &mut [RecordGroup],
        stops: &[(usize, f64)],
        mut result: RunResult,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<RunResult, Failure> {
        let stop = opts.stop_time;
        let min_step = a.min_step.unwrap_or(opts.step / 1000.0);
        let max_step = a.max_step.unwrap_or(stop / 10.0).max(min_step);
        if !(a.tolerance > 0.0 && a.tolerance.is_finite() && min_step > 0.0 && min_step.is_finite()) {
            return Err(Error::usage(format!(
                "error-controlled steps: tolerance = {}, min_step = {min_step}: both must be positive numbers",
                a.tolerance
            ))
            .into());
        }
        let mut watched = Vec::with_capacity(a.error_on.len());
        for key in &a.error_on {
            let target = self.resolve_qualified(key)?;
            if target.ty != Type::Real {
                let (c, v) = key.split_once('.').unwrap_or((key, ""));
                return Err(Error::variable(c, v, format!("error_on {key}: not a Real variable")).into());
            }
            watched.push(target);
        }
        if let Err(error) = self.initialize_with(stop, values) {
            return Err(Failure { error, partial: result });
        }
        let scale = 1000usize;
        let m = result.names.len();
        let mut row = vec![0.0; m];
        let (mut whole, mut halves) = (Vec::new(), Vec::new());
        let mut slots: Vec<FmuState> = Vec::new();
        let mut t = 0.0f64;
        let mut h = opts.step.clamp(min_step, max_step);
        let outcome: Result<(), Error> = (|| {
            loop {
                self.propagate(t)?;
                self.read_record(groups, &mut row, t)?;
                result.time.push(t);
                result.values.extend_from_slice(&row);
                progress(((t / stop.max(f64::MIN_POSITIVE)) * scale as f64) as usize, scale);
                if stops.iter().any(|&(c, limit)| row[c].abs() > limit) {
                    result.stopped = t < stop;
                    return Ok(());
                }
                if t >= stop {
                    return Ok(());
                }
                loop {
                    // The last step ends at the stop time (a remainder under a tenth of a step joins it).
                    let mut step = h.min(stop - t);
                    if stop - (t + step) < 0.1 * step {
                        step = stop - t;
                    }
                    self.save_states(&mut slots, t)?;
                    self.do_step_with(t, step, false)?;
                    self.propagate(t + step)?;
                    self.estimated(&watched, &mut whole, t + step)?;
                    self.load_states(&slots, t)?;
                    let mid = t + step / 2.0;
                    self.do_step_with(t, step / 2.0, false)?;
                    self.propagate(mid)?;
                    self.do_step_with(mid, t + step - mid, false)?;
                    self.propagate(t + step)?;
                    self.estimated(&watched, &mut halves, t + step)?;
                    result.fmu_steps += 3;
                    let err = whole
                        .iter()
                        .zip(&halves)
                        .map(|(w, b)| (w - b).abs() / (a.tolerance * (1.0 + b.abs())))
                        .fold(0.0f64, f64::max);
                    let grow = if err > 0.0 { 0.9 / err.sqrt() } else { 2.0 };
                    if err <= 1.0 || step <= min_step * (1.0 + 1e-9) {
                        t = if step == stop - t { stop } else { t + step };
                        h = (step * grow.clamp(0.2, 2.0)).clamp(min_step, max_step);
                        break;
                    }
                    result.rejected += 1;
                    self.load_states(&slots, t)?;
                    h = (step * grow.clamp(0.2, 0.9)).max(min_step);
                }
            }
        })();
        for (i, slot) in slots.into_iter().enumerate() {
            let _ = self.instance(i).free_fmu_state(slot);
        }
        if let Err(error) = outcome {
            if error.kind == ErrorKind::Terminated {
                // A step tried, not accepted: the rows end at the last accepted point.
                self.back.ending = Some(None);
                return self.end_on_request(error, None, groups, &mut row, result);
            }
            self.note(&error);
            return Err(Failure { error, partial: result });
        }
        if let Err(error) = self.terminate() {
            self.note(&error);
            return Err(Failure { error, partial: result });
        }
        Ok(result)
    }

    /// A component asked to end the simulation (`error`, [`ErrorKind::Terminated`]): the run
    /// ends there, with what it recorded and, where every component reached one time after the
    /// last row (`back.ending`, or `point`, the communication point the request came
    /// at), a last row there, read as the steps left the components (no input is set: an FMI
    /// 2.0 slave that asked accepts none, FMI 2.0.5 4.3.1 stepFailed); then every component
    /// terminated.
    #[cold]
    fn end_on_request(
        &mut self,
        error: Error,
        point: Option<f64>,
        groups: &mut [RecordGroup],
        row: &mut [f64],
        mut result: RunResult,
    ) -> Result<RunResult, Failure> {
        let close = |x: f64| 1e-9 * x.abs().max(1.0);
        let at = error.time.unwrap_or(f64::NAN);
        let row_at = match self.back.ending.take() {
            Some(decided) => decided,
            None => point.filter(|&p| (at - p).abs() <= close(p)),
        }
        .filter(|&r| result.time.last().is_none_or(|&l| r > l + close(l)));
        let mut rows = match row_at {
            Some(r) => match self.read_record(groups, row, r) {
                Ok(()) => {
                    result.time.push(r);
                    result.values.extend_from_slice(row);
                    String::new()
                }
                Err(e) => format!(" (the row at t = {r} s could not be read: {})", e.message),
            },
            None => String::new(),
        };
        if row_at.is_none() && result.time.last().is_some_and(|&l| at > l + close(l)) {
            rows = format!(
                " (no row at t = {at} s: a component stepped before it had passed that time and is not taken back, or one takes no shorter step){rows}"
            );
        }
        rows = match result.time.last() {
            Some(l) => format!("the rows end at t = {l} s{rows}"),
            None => format!("no row was recorded{rows}"),
        };
        let message = format!("{}: the run ends there; {rows}", error.message);
        if let Err(error) = self.terminate() {
            self.note(&error);
            return Err(Failure { error, partial: result });
        }
        result.terminated = Some(Terminated {
            component: error.component.clone().unwrap_or_default(),
            time: at,
            message,
        });
        Ok(result)
    }

    pub(super) fn read_record(&mut self, groups: &mut [RecordGroup], row: &mut [f64], t: f64) -> Result<(), Error> {
        for g in groups.iter_mut() {
            let s = &mut self.slaves[g.slave];
            let inst = s.instance.as_mut().expect("instantiated");
            let (f, r) = match g.kind {
                Kind::Real => ("fmi2GetReal", inst.get_real(&g.vrs, &mut g.reals)),
                Kind::Integer => ("fmi2GetInteger", inst.get_integer(&g.vrs, &mut g.ints)),
                Kind::Boolean => ("fmi2GetBoolean", inst.get_boolean(&g.vrs, &mut g.ints)),
            };
            r.map_err(|e| Error::fmi(&s.name, fname(s.v3, f), &e, Some(t), "recorded variables"))?;
            for (j, c) in g.columns.iter().enumerate() {
                row[*c] = match g.kind {
                    Kind::Real => g.reals[j],
                    Kind::Integer => f64::from(g.ints[j]),
                    Kind::Boolean => f64::from(u8::from(g.ints[j] != 0)),
                };
            }
        }
        let mut typed = std::mem::take(&mut self.typed.records);
        let r = self.read_typed_record(&mut typed, row, t);
        self.typed.records = typed;
        r
    }
}
