//! The FMU's own reference results (FMI-LS-REF, [`crate::reference_results`]), reproduced: the
//! default experiment run again through co-simulation, at its step size where it declares one,
//! output at the result file's times.
//!
//! Verdict: *warned* where the run does not reproduce them. FMI-LS-REF (1.0.0-alpha.1, "Related
//! Files", role `result`: "Result file, e.g., a result file that contains the results of an
//! experiment or simulation run") requires nothing of the FMU about them: no "shall" says that
//! the FMU reproduces its result file, nor within what tolerance (the layered standard gives
//! none; [`crate::reference_results::compare`] says which one this check uses). But an FMU that
//! ships results it does not reproduce misleads whoever validates it with them; under `--strict`
//! (this exporter's own FMUs, whose results `cargo fmu build` writes) a mismatch fails.
//! Skipped when the FMU ships no result file or does not declare co-simulation.

use crate::Fmu;
use crate::fmi2::*;
use crate::instance::{Args, Instance, status_name};
use crate::outcome::{info, limitation, skip, skip_not_declared, warn, warned};
use crate::reference_results::{Value, compare, read, steps};
use md_reader::fmi2::Type;

/// What the skip says when the FMU ships no reference results (FMI 2.0 and 3.0).
pub const NO_RESULTS: &str = "reference results (FMI-LS-REF: extra/org.fmi-standard.fmi-ls-ref/fmi-ls-manifest.xml naming a CSV of role \"result\")";

pub fn reference_results_are_reproduced_by_the_default_experiment(fmu: &Fmu) {
    let tables = match read(&fmu.dir) {
        Ok(Some(r)) => {
            for m in &r.missing {
                limitation(format!(
                    "the FMI-LS-REF manifest names {m}, which the archive does not hold (FMI-LS-REF allows that)"
                ));
            }
            if r.tables.is_empty() {
                skip(format!(
                    "the result files the FMI-LS-REF manifest names are not in the archive: {:?}",
                    r.missing
                ));
            }
            r.tables
        }
        Ok(None) => skip_not_declared(NO_RESULTS),
        Err(e) => warned(format!(
            "{}: the FMI-LS-REF reference results cannot be read: {e}",
            fmu.id
        )),
    };
    if fmu.md.cs.is_none() {
        skip_not_declared("<CoSimulation> (the reference results are compared with a co-simulation run)");
    }
    for table in &tables {
        let vars: Vec<Option<&md_reader::fmi2::Variable>> = table
            .names
            .iter()
            .map(|n| fmu.md.variables.iter().find(|v| v.name == *n))
            .collect();
        let missing: Vec<&String> = table
            .names
            .iter()
            .zip(&vars)
            .filter(|(_, v)| v.is_none())
            .map(|(n, _)| n)
            .collect();
        if !missing.is_empty() {
            warn(format!(
                "{}: {} names variables the FMU does not have (not compared): {missing:?}",
                fmu.id, table.file
            ));
        }
        let Some((&t0, &t_end)) = table.times.first().zip(table.times.last()) else {
            warned(format!("{}: {} has no row", fmu.id, table.file));
        };
        let mut inst = Instance::with(fmu, &Args::valid(fmu))
            .unwrap_or_else(|log| warned(format!("{}: fmi2Instantiate failed: {log:?}", fmu.id)));
        let run = |s: fmi2Status, what: &str, inst: &Instance| {
            if s != fmi2OK && s != fmi2Warning {
                warned(format!(
                    "{}: the default experiment for {} stopped: {what} answered {}: {}",
                    fmu.id,
                    table.file,
                    status_name(s),
                    inst.log_text()
                ));
            }
        };
        run(inst.setup(t0, Some(t_end)), "fmi2SetupExperiment", &inst);
        run(inst.enter_init(), "fmi2EnterInitializationMode", &inst);
        run(inst.exit_init(), "fmi2ExitInitializationMode", &inst);
        let mut observed: Vec<Option<Vec<Value>>> = vars.iter().map(|v| v.map(|_| vec![])).collect();
        let read_row = |inst: &Instance, observed: &mut Vec<Option<Vec<Value>>>| {
            for (c, v) in vars.iter().enumerate() {
                let Some(v) = v else { continue };
                let value = match v.ty {
                    Type::Real => inst.get_real(&[v.vr]).1.first().map(|x| Value::Numbers(vec![*x])),
                    Type::Integer | Type::Enumeration => inst
                        .get_integer(&[v.vr])
                        .1
                        .first()
                        .map(|x| Value::Numbers(vec![*x as f64])),
                    Type::Boolean => inst
                        .get_boolean(&[v.vr])
                        .1
                        .first()
                        .map(|x| Value::Numbers(vec![(*x != 0) as u8 as f64])),
                    Type::String => None,
                };
                match value {
                    Some(x) => observed[c].as_mut().expect("a column of a known variable").push(x),
                    None => {
                        limitation(format!("String columns are not compared ({})", v.name));
                        observed[c] = None;
                    }
                }
            }
        };
        let mut t = t0;
        for (i, &time) in table.times.iter().enumerate() {
            if i > 0 && time > t {
                let (n, h) = steps(t, time, fmu.md.default_experiment.step_size());
                let mut ended = false;
                for k in 0..n {
                    let from = if k == 0 { t } else { t + k as f64 * h };
                    let s = inst.do_step(from, if k + 1 == n { time - from } else { h });
                    // The FMU ended the simulation (fmi2Discard, fmi2Terminated true): the
                    // values of this row are those at its last successful time; the run ends.
                    ended = s == fmi2Discard && inst.terminated() == (fmi2OK, fmi2True);
                    if ended {
                        break;
                    }
                    run(s, &format!("fmi2DoStep to t = {time}"), &inst);
                }
                t = time;
                if ended {
                    info(format!("the FMU ended the simulation at t = {time} (fmi2Terminated)"));
                    read_row(&inst, &mut observed);
                    break;
                }
            }
            read_row(&inst, &mut observed);
        }
        let mismatches = compare(table, &observed, 10);
        if !mismatches.is_empty() {
            warn(format!(
                "{}: the default experiment does not reproduce the reference results of {} (FMI-LS-REF role \"result\"; \
                 relative tolerance {} of each column's largest magnitude, or within its neighbouring rows):\n  {}",
                fmu.id,
                table.file,
                crate::reference_results::RELATIVE_TOLERANCE,
                mismatches.join("\n  ")
            ));
        }
        info(format!(
            "{}: {} rows, {} columns compared",
            table.file,
            table.times.len(),
            observed.iter().flatten().count()
        ));
    }
}
