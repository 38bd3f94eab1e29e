//! The FMU's own reference results (FMI-LS-REF), reproduced by a co-simulation run of the
//! default experiment: the FMI 3.0 twin of
//! [`crate::checks::reference_results::reference_results_are_reproduced_by_the_default_experiment`],
//! whose doc comment gives the verdict (warned: the layered standard requires nothing of the
//! FMU about its result files) and its reasons.

use super::*;
use crate::checks::reference_results::NO_RESULTS;
use crate::outcome::{skip, warn, warned};
use crate::reference_results::{Value, compare, hex, read, steps};

/// A variable's value as the run gives it (None: a String or Clock, not compared).
fn value(inst: &Inst, v: &Variable) -> Option<Value> {
    if matches!(v.ty, Type::String | Type::Clock) {
        return None;
    }
    let (_, bytes) = inst.get_raw(v);
    if v.ty == Type::Binary {
        return Some(Value::Text(hex(&bytes)));
    }
    let size = super::super::c_size(v.ty);
    let numbers = bytes
        .chunks_exact(size)
        .map(|b| {
            let mut w = [0u8; 8];
            w[..size].copy_from_slice(b);
            match v.ty {
                Type::Float32 => f32::from_ne_bytes([b[0], b[1], b[2], b[3]]) as f64,
                Type::Float64 => f64::from_ne_bytes(w),
                Type::Int8 => b[0] as i8 as f64,
                Type::UInt8 => b[0] as f64,
                Type::Boolean => (b[0] != 0) as u8 as f64,
                Type::Int16 => i16::from_ne_bytes([b[0], b[1]]) as f64,
                Type::UInt16 => u16::from_ne_bytes([b[0], b[1]]) as f64,
                Type::Int32 => i32::from_ne_bytes([b[0], b[1], b[2], b[3]]) as f64,
                Type::UInt32 => u32::from_ne_bytes([b[0], b[1], b[2], b[3]]) as f64,
                Type::UInt64 => u64::from_ne_bytes(w) as f64,
                _ => i64::from_ne_bytes(w) as f64,
            }
        })
        .collect();
    Some(Value::Numbers(numbers))
}

pub fn fmi3_reference_results_are_reproduced_by_the_default_experiment(fmu: &Fmu3) {
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
        let vars: Vec<Option<&Variable>> = table
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
        let Some(&t0) = table.times.first() else {
            warned(format!("{}: {} has no row", fmu.id, table.file));
        };
        let mut inst = if fmu.has_clocks() {
            Inst::cs_event_mode(fmu)
        } else {
            Inst::cs(fmu)
        };
        let run = |s: fmi3Status, what: &str, inst: &Inst| {
            if s != fmi3OK && s != fmi3Warning {
                warned(format!(
                    "{}: the default experiment for {} stopped: {what} answered {}: {}",
                    fmu.id,
                    table.file,
                    status_name(s),
                    inst.log_text()
                ));
            }
        };
        let s = inst.enter_init(t0);
        run(s, "fmi3EnterInitializationMode", &inst);
        let s = inst.exit_init();
        run(s, "fmi3ExitInitializationMode", &inst);
        let mut observed: Vec<Option<Vec<Value>>> = vars.iter().map(|v| v.map(|_| vec![])).collect();
        for (i, &time) in table.times.iter().enumerate() {
            if i > 0 && time > inst.time {
                let from = inst.time;
                let (n, h) = steps(from, time, fmu.md.default_experiment.step_size());
                for k in 0..n {
                    let h = if k + 1 == n { time - inst.time } else { h };
                    let (s, _, _) = inst.do_step(h);
                    run(s, &format!("fmi3DoStep to t = {time}"), &inst);
                }
                inst.time = time;
            }
            for (c, v) in vars.iter().enumerate() {
                let Some(v) = v else { continue };
                match value(&inst, v) {
                    Some(x) => observed[c].as_mut().expect("a column of a known variable").push(x),
                    None => {
                        limitation(format!("String columns are not compared ({})", v.name));
                        observed[c] = None;
                    }
                }
            }
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
