//! [`InstanceCS`]: a co-simulation component as the master sees it, whichever importer (FMI 2.0,
//! FMI 3.0), whether the runner integrates it (model exchange) and whether it runs in a child
//! process; above all of them, so that none imports it.

use crate::common::{Fmi2Error, dispatch_with};

/// A co-simulation instance of an FMI 2.0 or an FMI 3.0 FMU ([`crate::fmi3`]), with FMI 2.0's
/// view of its values and statuses; freed when dropped (its FMU states first).
pub enum InstanceCS {
    V2(crate::fmi2::Instance2),
    V3(crate::fmi3::Instance3),
    /// A model-exchange instance (FMI 2.0 or 3.0) the runner integrates ([`crate::me`]).
    Me(crate::me::MeInstance),
    /// Any of the above in a child process ([`crate::isolate`]).
    #[cfg(target_os = "linux")]
    Isolated(Box<crate::isolate::Isolated>),
}

// Each method forwarded to the instance's own, after the crumb an isolated system's child
// leaves before every call (what a crash or hang is reported at).
dispatch_with! {
    values_and_states;
    InstanceCS {
        V2,
        V3,
        Me,
        #[cfg(target_os = "linux")]
        Isolated,
    }
    hook crate::isolate::crumb;
    /// FMI 3.0: kept for fmi3EnterInitializationMode.
    fn setup_experiment(&mut self, tolerance: Option<f64>, start: f64, stop: Option<f64>) -> Result<(), Fmi2Error>;
    fn exit_initialization_mode(&mut self) -> Result<(), Fmi2Error>;
    fn reset(&mut self) -> Result<(), Fmi2Error>;
    fn do_step(&mut self, t: f64, h: f64, no_set_prior: bool) -> Result<(), Fmi2Error>;
    /// First time derivatives of outputs (FMI 2.0 fmi2GetRealOutputDerivatives, FMI 3.0
    /// fmi3GetOutputDerivatives; order 1).
    fn get_output_derivatives(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), Fmi2Error>;
    /// First time derivatives of inputs (FMI 2.0 only: canInterpolateInputs).
    fn set_input_derivatives(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), Fmi2Error>;
}

/// The clocks of a system's components: what the system asks of an instance to tick the clocks
/// connected to others and to step to the ticks (`fmi3/clocks.rs`; `sim/clocks.rs`). Only an
/// FMI 3.0 co-simulation instance in this process has clocks (the system refuses the others).
impl InstanceCS {
    fn v3(&mut self) -> Option<&mut crate::fmi3::Instance3> {
        match self {
            InstanceCS::V3(i) => Some(i),
            _ => None,
        }
    }

    /// An Event Mode ends at `t` (updates, intervals read, Step Mode).
    pub fn settle(&mut self, t: f64) -> Result<(), Fmi2Error> {
        self.v3().map_or(Ok(()), |i| i.settle(t))
    }

    /// The next tick of its time-based clocks.
    pub fn next_tick(&mut self) -> Option<f64> {
        self.v3().and_then(|i| i.next_tick())
    }

    /// The clocks due at `t` tick (Event Mode entered for them).
    pub fn tick_now(&mut self, t: f64) -> Result<(), Fmi2Error> {
        self.v3().map_or(Ok(()), |i| i.tick_now(t))
    }

    /// The samples its intermediateUpdate callback took since the last call (an FMI 3.0
    /// instance made with one; none for the others).
    pub fn take_intermediate(&mut self) -> Result<Vec<(f64, Vec<f64>)>, Fmi2Error> {
        self.v3().map_or(Ok(Vec::new()), |i| i.take_intermediate())
    }

    /// Where its last step returned early (an instance with earlyReturnAllowed).
    pub fn take_early_return(&mut self) -> Option<f64> {
        self.v3().and_then(|i| i.take_early_return())
    }

    /// The importer's side of its clocks, kept with an FMU state (an FMI 3.0 instance with
    /// clocks or Event Mode; None for the others).
    pub fn clock_snapshot(&mut self) -> Option<crate::fmi3::ClockState> {
        self.v3().and_then(|i| i.clock_snapshot())
    }

    /// Its clocks as `snapshot` kept them (with the FMU state set back to the one taken then).
    pub fn restore_clocks(&mut self, snapshot: &crate::fmi3::ClockState) {
        if let Some(i) = self.v3() {
            i.restore_clocks(snapshot);
        }
    }

    /// Scheduled Execution: the partitions of the clocks that tick at `t` activated, once the
    /// inputs are set (nothing for the other instances); whether one was.
    pub fn activate_scheduled(&mut self, t: f64) -> Result<bool, Fmi2Error> {
        self.v3().map_or(Ok(false), |i| i.activate_pending(t))
    }

    /// Its output clocks read, once its input clocks are set.
    pub fn poll_output_clocks(&mut self, t: f64) -> Result<(), Fmi2Error> {
        self.v3().map_or(Ok(()), |i| i.poll_output_clocks(t))
    }

    /// Whether its clock `vr` ticks now.
    pub fn clock_active(&mut self, vr: u32) -> bool {
        self.v3().is_some_and(|i| i.clock_active(vr))
    }

    /// Its input clock `vr` ticks at `t` (a clock connected to it ticked).
    pub fn trigger(&mut self, vr: u32, t: f64) -> Result<(), Fmi2Error> {
        match self.v3() {
            Some(i) => i.trigger(vr, t),
            None => Err(Fmi2Error::Importer(
                "only an FMI 3.0 co-simulation instance has clocks".into(),
            )),
        }
    }
}

impl InstanceCS {
    /// Waits for every call made so far (an isolated instance sends the calls that answer only
    /// a status with the next one that answers values): their failure, if any, now.
    pub fn sync(&mut self) -> Result<(), Fmi2Error> {
        match self {
            #[cfg(target_os = "linux")]
            InstanceCS::Isolated(i) => i.sync(),
            _ => Ok(()),
        }
    }
}
