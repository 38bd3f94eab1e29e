//! Clocks across components: clock connections, and steps that end at the clocks' ticks.
//!
//! A data connection of two clocked variables whose input is clocked by triggered clocks comes
//! with the clock connection of their clocks, or the system is refused
//! ([`Simulation::check_clocked_connections`]).
//!
//! A clock connection (SSP 2.0: a connection of two `ssc:Clock` connectors) ticks the
//! receiver's triggered input clock whenever the sender's clock ticks: an output clock the
//! sender reports (fmi3GetClock in its Event Mode, after fmi3DoStep said eventHandlingNeeded), a
//! time-based input clock the runner ticks (FMI-LS-BUS 1.0.0, Time-based Tx Clocks: "it is
//! allowed to connect both, since a time-based Clock of an FMU is considered only to be a
//! request to the importer to provide a corresponding Clock source"), or a triggered clock a
//! connection ticked (chains). Every clock is ticked before any value is exchanged, and the
//! clocked values then travel in the connections' order (Gauss-Seidel): a sender's Tx_Data is
//! read before the receiver's Rx_Data is set ("an importer has to activate the Rx_Clock
//! respecting the Tx_Data and Rx_Data dependency").
//!
//! A system with a clock connection or a clock whose ticks no fixed step can meet (countdown,
//! changing, triggered, output) steps *to the ticks*: before each step every instance ends its
//! Event Mode (so the countdown intervals are known) and the step ends at the earliest tick if
//! it comes before the next communication point of the grid (FMI-LS-BUS 1.0.0: "the importer can
//! adapt the next communicationStepSize for all networked FMUs accordingly"); that time is a
//! communication point of its own, with a recorded row. Periodic clocks alone keep today's
//! rule (their ticks on the grid).

use super::*;

/// A clock connection: (component, clock value reference) at both ends, and how it is written.
#[derive(Debug, Clone)]
pub(super) struct ClockLink {
    pub from: (usize, u32),
    pub to: (usize, u32),
    /// The sender's clock is an output clock (its tick known once the sender's is evaluated).
    pub output: bool,
    pub text: String,
}

impl Simulation {
    /// The clock connections `conns` resolved and checked: both ends clocks of FMI 3.0
    /// co-simulation components, the receiver a triggered input clock.
    pub(super) fn build_clock_links(&mut self, conns: &[Connection]) -> Result<(), Error> {
        for k in conns {
            let text = format!("{}.{} -> {}.{}", k.start.0, k.start.1, k.end.0, k.end.1);
            let from = self.clock_end(&k.start, &text)?;
            let to = self.clock_end(&k.end, &text)?;
            let decl = self.clock_decl(to.0, to.1).expect("resolved");
            if decl.interval != crate::fmi3::Interval::Triggered {
                return Err(Error::variable(
                    &k.end.0,
                    &k.end.1,
                    format!(
                        "clock connection {text}: '{}.{}' is {}: a clock connection ticks a triggered input clock (intervalVariability=\"triggered\"); a time-based one ticks by its own intervals",
                        k.end.0,
                        k.end.1,
                        match decl.interval {
                            crate::fmi3::Interval::Output => "an output clock".to_owned(),
                            _ => "a time-based input clock".to_owned(),
                        }
                    ),
                ));
            }
            let output = self.clock_decl(from.0, from.1).expect("resolved").interval == crate::fmi3::Interval::Output;
            self.clock_links.push(ClockLink { from, to, output, text });
        }
        // The links out of a component after those into it (its output clocks are read once its
        // input clocks are set): the components in a topological order of the links (a cycle
        // keeps the system's order).
        let n = self.slaves.len();
        let mut rank = vec![usize::MAX; n];
        let mut next = 0;
        while next < n {
            let ready = (0..n).find(|&c| {
                rank[c] == usize::MAX
                    && !self
                        .clock_links
                        .iter()
                        .any(|k| k.to.0 == c && k.from.0 != c && rank[k.from.0] == usize::MAX)
            });
            let c = ready.unwrap_or_else(|| (0..n).find(|&c| rank[c] == usize::MAX).expect("one left"));
            rank[c] = next;
            next += 1;
        }
        self.clock_links.sort_by_key(|k| rank[k.from.0]);
        Ok(())
    }

    /// The data connections `conns` of two clocked variables whose input's clocks all are
    /// triggered: each needs a clock connection from one of the output's clocks to one of the
    /// input's, else the input is never set (a clocked variable is set only while its clock
    /// ticks, a triggered clock ticks only through a clock connection; the FMI-LS-BUS Bus
    /// Terminal: Tx_Data and Tx_Clock connect to Rx_Data and Rx_Clock). Refused, as
    /// `cargo fmu build` refuses to write it, naming both variables and the clock connection.
    pub(super) fn check_clocked_connections(&self, conns: &[Connection]) -> Result<(), Error> {
        for k in conns {
            let (Some(from), Some(to)) = (self.clocks_of(&k.start), self.clocks_of(&k.end)) else {
                continue;
            };
            if from.1.is_empty()
                || to.1.is_empty()
                || !to.1.iter().all(|c| c.interval == crate::fmi3::Interval::Triggered)
            {
                continue;
            }
            let joined = self.clock_links.iter().any(|l| {
                l.from.0 == from.0
                    && l.to.0 == to.0
                    && from.1.iter().any(|c| c.vr == l.from.1)
                    && to.1.iter().any(|c| c.vr == l.to.1)
            });
            if joined {
                continue;
            }
            let names = |component: &str, list: &[&crate::fmi3::ClockDecl]| {
                list.iter()
                    .map(|c| format!("{component}.{}", c.name))
                    .collect::<Vec<_>>()
                    .join(" or ")
            };
            let (a, b) = (names(&k.start.0, &from.1), names(&k.end.0, &to.1));
            return Err(Error::variable(
                &k.end.0,
                &k.end.1,
                format!(
                    "connection {}.{} -> {}.{}: {}.{} is clocked by {a}, {}.{} by the triggered {b}, which ticks only through a clock connection: without the clock connection {a} -> {b} the input is never set (FMI 3.0: a clocked variable is set only while its clock ticks)",
                    k.start.0, k.start.1, k.end.0, k.end.1, k.start.0, k.start.1, k.end.0, k.end.1
                ),
            ));
        }
        Ok(())
    }

    /// The component of `end` and the clocks of its variable (empty: not clocked); None: not a
    /// variable of an FMI 3.0 co-simulation component with clocks.
    fn clocks_of(&self, end: &(String, String)) -> Option<(usize, Vec<&crate::fmi3::ClockDecl>)> {
        let slave = self.slave_index(&end.0).ok()?;
        let s = &self.slaves[slave];
        let fmu = &self.fmus[s.fmu];
        let plan = match &fmu.import {
            crate::fmu::Import::V3(i) if !s.me => i.clock_plan()?,
            _ => return None,
        };
        let vr = fmu
            .var3(&end.1)
            .map(|v| v.vr)
            .or_else(|| fmu.description.variables.iter().find(|v| v.name == end.1).map(|v| v.vr))?;
        let clocks = plan
            .clocked
            .get(&vr)
            .map(|ix| ix.iter().map(|&i| &plan.inputs[i]).collect())
            .unwrap_or_default();
        Some((slave, clocks))
    }

    fn clock_decl(&self, slave: usize, vr: u32) -> Option<&crate::fmi3::ClockDecl> {
        match &self.fmus[self.slaves[slave].fmu].import {
            crate::fmu::Import::V3(i) => i.clock_plan()?.inputs.iter().find(|c| c.vr == vr),
            _ => None,
        }
    }

    /// (component, clock) of the connector `end`, which must be a clock of an FMI 3.0
    /// co-simulation component.
    fn clock_end(&self, end: &(String, String), text: &str) -> Result<(usize, u32), Error> {
        let slave = self.slave_index(&end.0)?;
        let s = &self.slaves[slave];
        let plan = match &self.fmus[s.fmu].import {
            crate::fmu::Import::V3(i) if !s.me => i.clock_plan(),
            _ => None,
        };
        let clock = plan.and_then(|p| p.clock(&end.1).map(|i| p.inputs[i].vr));
        clock.map(|vr| (slave, vr)).ok_or_else(|| {
            Error::variable(
                &end.0,
                &end.1,
                format!(
                    "clock connection {text}: '{}.{}' is no clock of an FMI 3.0 co-simulation component",
                    end.0, end.1
                ),
            )
        })
    }

    /// Whether the system steps to its clocks' ticks (see the module).
    pub(super) fn steps_to_ticks(&self) -> bool {
        !self.clock_links.is_empty()
            || self.slaves.iter().any(|s| s.events)
            || self.slaves.iter().any(|s| {
                !s.me
                    && matches!(&self.fmus[s.fmu].import,
                        crate::fmu::Import::V3(i) if i.clock_plan().is_some_and(|p| p.has_events()))
            })
    }

    /// At `t`, after every instance reached it: each clock connection whose sender ticks ticks
    /// its receiver, until none is left (a chain of connections). `outputs` false: only the
    /// connections from input clocks (known without evaluating the sender's tick); true: also
    /// those from output clocks, as [`Simulation::poll_senders`] read them (a sender that enters
    /// Event Mode only by a connection here is read when its Event Mode ends, too late for its
    /// own connections at this time). Returns whether a receiver ticked.
    pub(super) fn link_clocks(&mut self, t: f64, outputs: bool) -> Result<bool, Error> {
        let ticking = self.ticking_senders(t, outputs)?;
        Ok(!self.tick_links(t, ticking, false)?.is_empty())
    }

    /// The senders' clocks that tick now (those of output clocks too where `outputs`), as they
    /// are before any receiver takes its tick: a receiver whose round ends for a tick stops
    /// ticking its own clocks, which tick at this time all the same.
    fn ticking_senders(&mut self, t: f64, outputs: bool) -> Result<Vec<(usize, u32)>, Error> {
        let mut ticking: Vec<(usize, u32)> = Vec::new();
        for k in 0..self.clock_links.len() {
            let ClockLink { from, output, .. } = self.clock_links[k];
            if (outputs || !output) && !ticking.contains(&from) && self.ticks(from, t, k)? {
                ticking.push(from);
            }
        }
        Ok(ticking)
    }

    /// Whether each clock connection is *late*: its receiver's outputs are read before its
    /// sender's at a communication point (the receiver comes before the sender in the evaluation
    /// order, or is the sender; every connection under Jacobi, where all outputs are read first).
    fn late_links(&self) -> Vec<bool> {
        let mut position = vec![usize::MAX; self.slaves.len()];
        for (k, (c, _)) in self.steps.iter().enumerate() {
            position[*c] = k;
        }
        let jacobi = matches!(self.scheme, Scheme::Jacobi);
        self.clock_links
            .iter()
            .map(|k| jacobi || position[k.to.0] <= position[k.from.0])
            .collect()
    }

    /// The clock connections of [`Simulation::link_clocks`] from the senders `ticking`, those
    /// that are late (`late`) or the others; returns the receivers that ticked.
    fn tick_links(&mut self, t: f64, mut ticking: Vec<(usize, u32)>, late: bool) -> Result<Vec<usize>, Error> {
        let is_late = self.late_links();
        let mut done: Vec<bool> = is_late.iter().map(|&l| l != late).collect();
        let mut receivers: Vec<usize> = Vec::new();
        for _ in 0..=self.clock_links.len() {
            let mut changed = false;
            for (k, finished) in done.iter_mut().enumerate() {
                let ClockLink { from, to, .. } = self.clock_links[k];
                if *finished || !ticking.contains(&from) {
                    continue;
                }
                *finished = true;
                if !self.ticks(to, t, k)? {
                    let s = &mut self.slaves[to.0];
                    s.instance
                        .as_mut()
                        .expect("instantiated")
                        .trigger(to.1, t)
                        .map_err(|e| {
                            Error::fmi(
                                &s.name,
                                "fmi3SetClock",
                                &e,
                                Some(t),
                                &format!("clock connection {}", self.clock_links[k].text),
                            )
                        })?;
                    if !receivers.contains(&to.0) {
                        receivers.push(to.0);
                    }
                }
                if !ticking.contains(&to) {
                    ticking.push(to);
                }
                changed = true;
            }
            if !changed {
                break;
            }
        }
        Ok(receivers)
    }

    /// The late clock connections whose senders ticked at `t` tick their receivers, each in a
    /// round of its own after the one whose outputs were read ([`Instance3::trigger`]: the round
    /// ends with fmi3UpdateDiscreteStates, the clock starts the next one, FMI 3.0.2 super-dense
    /// time), and the receivers' inputs are set again from the outputs already read: the clocked
    /// inputs of the new round take the values of this time. FMI-LS-BUS 1.0.0, 4 (Time-based Tx
    /// Clocks): "an importer has to activate the Rx_Clock respecting the Tx_Data and Rx_Data
    /// dependency" — a network FMU whose Tx_Data the bus read at `t` gets the bus's Tx_Data of
    /// `t` after it, not in the round its own was computed in (where its Rx_Clock would tick
    /// with the Rx_Data of the last time, and setting the new one is refused).
    ///
    /// [`Instance3::trigger`]: crate::fmi3::Instance3::trigger
    pub(super) fn late_round(&mut self, t: f64, ticking: Vec<(usize, u32)>) -> Result<(), Error> {
        let receivers = self.tick_links(t, ticking, true)?;
        if receivers.is_empty() {
            return Ok(());
        }
        let jacobi = matches!(self.scheme, Scheme::Jacobi);
        let real: Vec<usize> = if jacobi {
            (0..self.writes.len()).collect()
        } else {
            self.late.clone()
        };
        for w in real {
            if receivers.contains(&self.writes[w].port.slave) {
                self.write(w, t)?;
            }
        }
        self.typed_into(&receivers, jacobi, t)
    }

    /// Whether the clock `end` (component, value reference) of the clock connection `k` ticks now.
    fn ticks(&mut self, end: (usize, u32), t: f64, k: usize) -> Result<bool, Error> {
        let text = &self.clock_links[k].text;
        clock_call(&mut self.slaves[end.0], t, text, |i| i.clock_active(end.1))
    }

    /// The senders of connections from output clocks read their output clocks (their ticks
    /// evaluated), before any value is exchanged.
    fn poll_senders(&mut self, t: f64) -> Result<(), Error> {
        for k in 0..self.clock_links.len() {
            let ClockLink { from, output, .. } = self.clock_links[k];
            if output {
                let text = &self.clock_links[k].text;
                clock_call(&mut self.slaves[from.0], t, text, |i| i.poll_output_clocks(t))?;
            }
        }
        Ok(())
    }

    /// A communication point `t` of a system that steps to its ticks: the clock connections
    /// tick, the values are propagated (the clocked ones of the clocks ticking), every Event Mode
    /// ends (fmi3UpdateDiscreteStates: what the components received is taken in), and the
    /// values are propagated again, so that what is recorded and what the next step starts
    /// from are the values after the event, as an importer's event iteration leaves them.
    pub(super) fn event_point(&mut self, t: f64) -> Result<(), Error> {
        self.link_clocks(t, false)?;
        self.poll_senders(t)?;
        self.exchange(t)?;
        let ticking = self.ticking_senders(t, true)?;
        if !self.tick_links(t, ticking.clone(), false)?.is_empty() {
            // A round the receivers of output clocks take their values in.
            self.propagate(t)?;
        }
        self.late_round(t, ticking)?;
        self.settle_clocks(t)?;
        self.propagate(t)
    }

    /// The values propagated at `t`; where a Scheduled Execution component's clocks tick, its
    /// partitions then run with the inputs just set, and the values are propagated again (its
    /// outputs, and output clocks, are read after the activations).
    pub(super) fn exchange(&mut self, t: f64) -> Result<(), Error> {
        self.propagate(t)?;
        if self.slaves.iter().any(|s| s.scheduled) {
            let mut any = false;
            for s in self.slaves.iter_mut().filter(|s| s.scheduled) {
                any |= s
                    .instance
                    .as_mut()
                    .expect("instantiated")
                    .activate_scheduled(t)
                    .map_err(|e| Error::fmi(&s.name, "fmi3ActivateModelPartition", &e, Some(t), "its clocks tick"))?;
            }
            if any {
                self.propagate(t)?;
            }
        }
        Ok(())
    }

    /// Before a step from `t`: every Event Mode ends (so the intervals of countdown clocks are
    /// known); then the earliest tick of any instance (None: none planned).
    pub(super) fn settle_clocks(&mut self, t: f64) -> Result<Option<f64>, Error> {
        let mut next: Option<f64> = None;
        for s in &mut self.slaves {
            let inst = s.instance.as_mut().expect("instantiated");
            let settled = inst.settle(t).and_then(|_| inst.next_tick());
            let tick = settled
                .map_err(|e| Error::fmi(&s.name, "fmi3UpdateDiscreteStates", &e, Some(t), "ending Event Mode"))?;
            if let Some(n) = tick {
                next = Some(next.map_or(n, |m: f64| m.min(n)));
            }
        }
        Ok(next)
    }

    /// The step from `t` of `h` of every instance, those that may return early first
    /// ([`Simulation::use_event_mode`]): where one returns early, the others step to that time.
    /// Returns the time every instance reached.
    ///
    /// With two or more such components, each one's FMU state is taken before the step
    /// (fmi3GetFMUState, with the importer's side of its clocks): where one returns early at
    /// t_e after another had stepped past t_e, that one is set back (fmi3SetFMUState) and steps
    /// again to t_e, and so on until every one of them stops at the earliest time (FMI 3.0.2,
    /// Co-Simulation, Early Return: the importer "may ... roll back" the FMUs that went further).
    /// A component that cannot (canGetAndSetFMUState = false) fails the run then, saying so.
    pub(super) fn do_step_events(&mut self, t: f64, h: f64) -> Result<f64, Error> {
        crate::isolate::crumb_time(t);
        let close = |x: f64| 1e-9 * x.abs().max(1.0);
        let mut end = t + h;
        let n = self.slaves.len();
        let early: Vec<usize> = (0..n).filter(|&i| self.slaves[i].events).collect();
        let order: Vec<usize> = early
            .iter()
            .copied()
            .chain((0..n).filter(|&i| !self.slaves[i].events))
            .collect();
        let rollback = early.len() > 1 && early.iter().all(|&i| self.can_roll_back(i));
        if rollback {
            self.save_early_states(&early, t)?;
        }
        // Where each early-returning component is (None: not stepped yet).
        let mut reached: Vec<Option<f64>> = vec![None; n];
        let mut rounds = 0;
        loop {
            let mut moved = false;
            for (k, &i) in order.iter().enumerate() {
                if !self.slaves[i].events {
                    break;
                }
                match reached[i] {
                    Some(r) if r == end => continue,
                    Some(r) => self.roll_back(i, t, r, end, rollback)?,
                    None => {}
                }
                self.step_one(i, t, end - t, !rollback, k, &order)?;
                let s = &mut self.slaves[i];
                let at = s
                    .instance
                    .as_mut()
                    .expect("instantiated")
                    .take_early_return()
                    .map_err(|e| Error::fmi(&s.name, "fmi3DoStep", &e, Some(t), &format!("step {} s", end - t)))?;
                match at {
                    Some(at) if at < end - close(end) => {
                        end = at;
                        moved = true;
                        reached[i] = Some(at);
                    }
                    _ => reached[i] = Some(end),
                }
            }
            rounds += 1;
            if !moved || early.len() < 2 {
                break;
            }
            if rounds > 100 {
                return Err(Error::usage(format!(
                    "the components of --event-mode returned early 100 times in the step from t = {t} s without agreeing on a time (the last {end} s)"
                )));
            }
        }
        for (k, &i) in order.iter().enumerate().skip(early.len()) {
            self.step_one(i, t, end - t, true, k, &order)?;
        }
        self.steps_answered(t, end - t, true)?;
        Ok(end)
    }

    /// fmi3DoStep / fmi2DoStep(t, h) of component `i`, the `k`th of `order` this step; a request
    /// to end the simulation completes the step of those after it ([`Simulation::complete_ended_step`]).
    fn step_one(
        &mut self,
        i: usize,
        t: f64,
        h: f64,
        no_set_prior: bool,
        k: usize,
        order: &[usize],
    ) -> Result<(), Error> {
        let s = &mut self.slaves[i];
        let inst = s.instance.as_mut().expect("instantiated");
        if let Err(e) = inst.do_step(t, h, no_set_prior) {
            let error = Error::fmi(&s.name, fname(s.v3, "fmi2DoStep"), &e, Some(t), &format!("step {h} s"));
            if let Fmi2Error::Terminate(at) = e {
                self.complete_ended_step(t, at, t + h, k > 0, &order[k + 1..], no_set_prior)?;
            }
            return Err(error);
        }
        Ok(())
    }

    /// Whether component `i` can be set back to a state it had (canGetAndSetFMUState).
    fn can_roll_back(&self, i: usize) -> bool {
        let d = &self.fmus[self.slaves[i].fmu].description;
        d.cs.as_ref().is_some_and(|cs| cs.can_get_and_set_fmu_state)
    }

    /// The FMU states of `early` at `t` (taken anew, or updated in place).
    #[cold]
    fn save_early_states(&mut self, early: &[usize], t: f64) -> Result<(), Error> {
        if self.back.early_states.len() < self.slaves.len() {
            self.back.early_states.resize_with(self.slaves.len(), || None);
        }
        for &i in early {
            let s = &mut self.slaves[i];
            let inst = s.instance.as_mut().expect("instantiated");
            let r = match &self.back.early_states[i] {
                Some((state, _)) => inst.update_fmu_state(state),
                None => inst
                    .get_fmu_state()
                    .map(|state| self.back.early_states[i] = Some((state, None))),
            };
            let clocks = r.and_then(|_| inst.clock_snapshot()).map_err(|e| {
                Error::fmi(
                    &s.name,
                    "fmi3GetFMUState",
                    &e,
                    Some(t),
                    "kept to take an early return back",
                )
            })?;
            if let Some(slot) = &mut self.back.early_states[i] {
                slot.1 = clocks;
            }
        }
        Ok(())
    }

    /// Component `i`, which stepped to `past`, set back to its state at `t` (another component
    /// returned early at `end`, before it), or why it cannot be.
    #[cold]
    fn roll_back(&mut self, i: usize, t: f64, past: f64, end: f64, rollback: bool) -> Result<(), Error> {
        let name = self.slaves[i].name.clone();
        if !rollback {
            let cannot: Vec<String> = self
                .slaves
                .iter()
                .enumerate()
                .filter(|&(j, s)| s.events && !self.can_roll_back(j))
                .map(|(_, s)| format!("'{}'", s.name))
                .collect();
            return Err(Error {
                component: Some(name.clone()),
                time: Some(t),
                ..Error::usage(format!(
                    "component '{name}' stepped to t = {past} s, past another component's early return at t = {end} s: taking it back needs fmi3GetFMUState/fmi3SetFMUState, which {} cannot (canGetAndSetFMUState = false)",
                    cannot.join(", ")
                ))
            });
        }
        let (state, clocks) = self.back.early_states[i].as_ref().expect("saved before the step");
        let s = &mut self.slaves[i];
        let inst = s.instance.as_mut().expect("instantiated");
        let taken_back = |e: crate::fmi2::Fmi2Error| {
            Error::fmi(
                &s.name,
                "fmi3SetFMUState",
                &e,
                Some(t),
                &format!("taking back its step to {past} s: another component returned early at {end} s"),
            )
        };
        inst.set_fmu_state(state).map_err(taken_back)?;
        if let Some(c) = clocks {
            inst.restore_clocks(c).map_err(taken_back)?;
        }
        // The samples of the step taken back: the step again gives its own.
        let _ = inst.take_intermediate();
        Ok(())
    }

    /// Frees the states [`Simulation::do_step_events`] kept.
    pub(super) fn free_early_states(&mut self) {
        for (i, slot) in std::mem::take(&mut self.back.early_states).into_iter().enumerate() {
            if let (Some((state, _)), Some(s)) = (slot, self.slaves.get_mut(i))
                && let Some(inst) = s.instance.as_mut()
            {
                let _ = inst.free_fmu_state(state);
            }
        }
    }

    /// At `t` without a step ending there (a countdown of interval 0): the clocks due tick.
    pub(super) fn tick_clocks_now(&mut self, t: f64) -> Result<(), Error> {
        for s in &mut self.slaves {
            s.instance
                .as_mut()
                .expect("instantiated")
                .tick_now(t)
                .map_err(|e| Error::fmi(&s.name, "fmi3SetClock", &e, Some(t), "clocks due"))?;
        }
        Ok(())
    }
}

/// `call` on the instance of `s` at `t`, for the clock connection `text`: its failure as
/// fmi3GetClock's, which reads the clocks.
fn clock_call<R>(
    s: &mut Slave,
    t: f64,
    text: &str,
    call: impl FnOnce(&mut InstanceCS) -> Result<R, crate::fmi2::Fmi2Error>,
) -> Result<R, Error> {
    call(s.instance.as_mut().expect("instantiated")).map_err(|e| {
        Error::fmi(
            &s.name,
            "fmi3GetClock",
            &e,
            Some(t),
            &format!("clock connection {text}"),
        )
    })
}
