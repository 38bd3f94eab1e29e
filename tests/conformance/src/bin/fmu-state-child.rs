//! The second process of the cross-process FMU state test: loads an FMU afresh, restores a
//! serialized state written by another process, and prints what it observes, so the parent can
//! compare bit for bit.
//!
//! Usage: `fmu-state-child <modelIdentifier> <state file> <steps> <step size>`. Prints the
//! re-serialized state as hex on the first line, then one line of observations (hex bit
//! patterns) after each step.

use fmi2_conformance::{Instance, by_id};
use rustfmu::fmi2::abi::fmi2OK;
use std::fmt::Write;

fn hex(bytes: impl IntoIterator<Item = u64>) -> String {
    bytes.into_iter().fold(String::new(), |mut s, b| {
        let _ = write!(s, "{b:x} ");
        s
    })
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let [_, id, file, steps, h] = args.as_slice() else {
        return Err("usage: fmu-state-child <modelIdentifier> <state file> <steps> <step size>".into());
    };
    let steps: usize = steps.parse().map_err(|e| format!("steps: {e}"))?;
    let h: f64 = h.parse().map_err(|e| format!("step size: {e}"))?;
    let bytes = std::fs::read(file).map_err(|e| format!("{file}: {e}"))?;
    let mut inst = Instance::new(by_id(id));
    inst.restore(&bytes);
    let (_, t) = inst.last_successful_time();
    inst.time = t;
    println!("{}", hex(inst.snapshot().into_iter().map(u64::from)));
    for _ in 0..steps {
        let s = inst.step(h);
        if s != fmi2OK {
            return Err(format!("step at t = {}: status {s}: {}", inst.time, inst.log_text()));
        }
        println!("{}", hex(inst.observe()));
    }
    Ok(())
}
