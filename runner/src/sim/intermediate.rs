//! Values between the communication points (`rustfmu-runner run --record-intermediate-values`):
//! the recorded Float64 variables of FMI 3.0 co-simulation components that provide intermediate
//! update, read in their intermediateUpdate callbacks (`fmi3/intermediate.rs`) and written as
//! rows of their own, in time order, between the rows of the communication points; the other
//! columns of such a row are NaN (no other component was sampled then). fmusim's option of the
//! same name does this for one FMU; here each component of a system gives its own rows.

use super::*;

impl Simulation {
    /// Instantiates the FMI 3.0 co-simulation components with recorded variables (`record`,
    /// "component.variable") again, with the intermediateUpdate callback reading those of them
    /// that are Float64 scalars with `intermediateUpdate="true"` (FMI 3.0.2: only those may be
    /// got in Intermediate Update Mode). Call it after [`Simulation::use_event_mode`]. Returns
    /// what is recorded at the communication points only, and why, a line each.
    pub fn record_intermediate_values(&mut self, record: &[String]) -> Result<Vec<String>, Error> {
        if self.isolation.is_some() {
            return Err(Error::usage(
                "--record-intermediate-values: not with --isolate (the intermediateUpdate callback reads the FMU in the runner's own process)",
            ));
        }
        let mut notes = Vec::new();
        for i in 0..self.slaves.len() {
            let name = self.slaves[i].name.clone();
            let keys: Vec<&String> = record
                .iter()
                .filter(|k| k.split_once('.').is_some_and(|(c, _)| c == name))
                .collect();
            if keys.is_empty() {
                continue;
            }
            let fmu = self.fmu_of(i);
            let label = format!("component '{name}' ({})", fmu.model_identifier());
            let Some(allowed) = fmu.intermediate.clone() else {
                notes.push(format!(
                    "{label}: no <CoSimulation providesIntermediateUpdate=\"true\"> (or an FMI 2.0 FMU): recorded at the communication points only"
                ));
                continue;
            };
            if self.slaves[i].me || self.slaves[i].scheduled {
                notes.push(format!(
                    "{label}: runs as model exchange or in Scheduled Execution (no fmi3DoStep, no intermediate update): recorded at the communication points only"
                ));
                continue;
            }
            let mut picked = Vec::new();
            for key in keys {
                let t = self.resolve_qualified(key)?;
                if allowed.contains(&t.vr) {
                    picked.push((key.clone(), t.vr));
                } else {
                    notes.push(format!(
                        "{key}: not a Float64 scalar with intermediateUpdate=\"true\": recorded at the communication points only"
                    ));
                }
            }
            if picked.is_empty() {
                continue;
            }
            let vrs: Vec<u32> = picked.iter().map(|(_, vr)| *vr).collect();
            let events = self.slaves[i].events;
            self.slaves[i].instance = None; // fmi3FreeInstance before the new one
            match self.fmu_of(i).instantiate_intermediate(&name, &vrs, events) {
                Ok(inst) => self.slaves[i].instance = Some(inst),
                Err(e) => {
                    let again = make_instance(self.fmu_of(i), &name, self.slaves[i].interface(), None);
                    self.slaves[i].instance = Some(again?);
                    return Err(e);
                }
            }
            self.slaves[i].intermediate = picked;
        }
        Ok(notes)
    }

    /// Whether any component records values between the communication points.
    pub(super) fn records_intermediate(&self) -> bool {
        self.slaves.iter().any(|s| !s.intermediate.is_empty())
    }

    /// After the step from `t` every component ended at `end`: the samples its components'
    /// callbacks took strictly between the two (those at `t` and `end` are the communication
    /// points' own rows) appended to `result` as rows, in time order (equal times in the
    /// components' order).
    pub(super) fn intermediate_rows(&mut self, t: f64, end: f64, result: &mut RunResult) -> Result<(), Error> {
        if !self.records_intermediate() {
            return Ok(());
        }
        let close = |x: f64| 1e-9 * x.abs().max(1.0);
        let m = result.names.len();
        let mut rows: Vec<(f64, Vec<f64>)> = Vec::new();
        for s in self.slaves.iter_mut().filter(|s| !s.intermediate.is_empty()) {
            let samples = s
                .instance
                .as_mut()
                .expect("instantiated")
                .take_intermediate()
                .map_err(|e| Error::fmi(&s.name, "fmi3GetFloat64", &e, Some(t), "intermediateUpdate callback"))?;
            let columns: Vec<Option<usize>> = s
                .intermediate
                .iter()
                .map(|(key, _)| result.names.iter().position(|n| n == key))
                .collect();
            for (at, x) in samples {
                if at <= t + close(t) || at >= end - close(end) {
                    continue;
                }
                let mut row = vec![f64::NAN; m];
                for (c, v) in columns.iter().zip(x) {
                    if let Some(c) = c {
                        row[*c] = v;
                    }
                }
                rows.push((at, row));
            }
        }
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (at, row) in rows {
            result.time.push(at);
            result.values.extend_from_slice(&row);
        }
        Ok(())
    }
}
