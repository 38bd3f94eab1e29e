//! The Reference-FMUs' Clocks (modelica/Reference-FMUs, `Clocks/`) written with rustfmu, for FMI
//! 3.0 Scheduled Execution: the same model identifier, variable names, value references, types,
//! causalities and clock priorities. Each input clock is a model partition that the importer
//! activates with fmi3ActivateModelPartition:
//!
//! - `inClock1` (constant, every 1 s, priority 0) counts its ticks; at t = 4 it gives the
//!   countdown clock `inClock3` its interval (0.5 s here: the runtime takes intervals > 0, the
//!   Reference-FMUs give 0);
//! - `inClock2` (triggered, priority 1: the importer activates it at 0, 1, 8 and 9) counts its
//!   ticks and adds `input2` to `result2` (then sets `input2` back to 0, as the original does);
//! - `inClock3` (countdown, priority 2) counts its ticks and sets `output3` to 1000;
//! - `outClock` (an output clock, triggered, priority 2) ticks when a partition brings
//!   `totalInClockTicks` (the ticks of every input clock) to a multiple of 5.
//!
//! The original burns CPU time in partition 3 to show preemption; this one does not (the
//! runtime serializes the calls into one instance). The `clocks` attributes of `inClock3` and
//! `outClock` (a Clock clocked by other Clocks) are left out.

use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// Model partitions activated by three input clocks, and an output clock
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(fmi3_only, scheduled_execution)]
pub struct Clocks {
    /// Simulation time
    #[variable(vr = 0, independent)]
    pub time: f64,
    /// Ticks every second
    #[variable(vr = 1001, name = "inClock1", input, clock(constant, interval = 1.0, priority = 0))]
    pub in_clock1: Clock,
    /// Ticks when the importer says
    #[variable(vr = 1002, name = "inClock2", input, clock(triggered, priority = 1))]
    pub in_clock2: Clock,
    /// Ticks when the interval inClock1's partition gives it has passed
    #[variable(vr = 1003, name = "inClock3", input, clock(countdown, priority = 2))]
    pub in_clock3: Clock,
    /// Ticks when totalInClockTicks reaches a multiple of 5
    #[variable(vr = 1005, name = "outClock", output, clock(triggered, priority = 2))]
    pub out_clock: Clock,
    /// Ticks of inClock1
    #[variable(vr = 2001, name = "inClock1Ticks", output, discrete, clocks = [in_clock1])]
    pub in_clock1_ticks: i32,
    /// Ticks of inClock2
    #[variable(vr = 2002, name = "inClock2Ticks", output, discrete, clocks = [in_clock2])]
    pub in_clock2_ticks: i32,
    /// Ticks of inClock3
    #[variable(vr = 2003, name = "inClock3Ticks", output, discrete)]
    pub in_clock3_ticks: i32,
    /// Ticks of every input clock
    #[variable(vr = 2004, name = "totalInClockTicks", output, discrete, clocks = [in_clock1, in_clock3])]
    pub total_in_clock_ticks: i32,
    /// The sum of input2 over the ticks of inClock2
    #[variable(vr = 2005, name = "result2", output, discrete, clocks = [in_clock2])]
    pub result2: i32,
    /// Added to result2 at the next tick of inClock2
    #[variable(vr = 2006, name = "input2", input, discrete, start = 0)]
    pub input2: i32,
    /// 1000 from the first tick of inClock3
    #[variable(vr = 2007, name = "output3", output, discrete, clocks = [in_clock3])]
    pub output3: i32,
}

impl Model for Clocks {
    fn update(&mut self, event: &mut Event) -> Result<(), String> {
        let before = self.total_in_clock_ticks;
        // Partition 1.
        if self.in_clock1.is_active() {
            self.in_clock1_ticks += 1;
            self.total_in_clock_ticks += 1;
            if event.time() == 4.0 {
                self.in_clock3.set_interval(0.5);
            }
        }
        // Partition 2.
        if self.in_clock2.is_active() {
            self.in_clock2_ticks += 1;
            self.total_in_clock_ticks += 1;
            self.result2 += self.input2;
            self.input2 = 0;
        }
        // Partition 3.
        if self.in_clock3.is_active() {
            self.in_clock3_ticks += 1;
            self.output3 = 1000;
            self.total_in_clock_ticks += 1;
        }
        if self.total_in_clock_ticks != before && self.total_in_clock_ticks % 5 == 0 {
            self.out_clock.tick();
        }
        Ok(())
    }
}

impl CoSimulation for Clocks {}

rustfmu::export_fmi3!(Clocks);
