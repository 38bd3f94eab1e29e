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

/// The importer's side of an instance's clocks, kept with an FMU state to take a step back
/// ([`InstanceCS::clock_snapshot`]).
pub enum ClockSnapshot {
    Here(Box<crate::fmi3::ClockState>),
    /// Kept by an isolated instance's child: the number it gave the snapshot.
    #[cfg(target_os = "linux")]
    There(u32),
}

/// The clocks of a system's components: what the system asks of an instance to tick the clocks
/// connected to others and to step to the ticks (`fmi3/clocks.rs`; `sim/clocks.rs`). Only an
/// FMI 3.0 co-simulation instance has clocks, in this process or in a child's (the system
/// refuses the others); each call leaves its crumb as the other calls do.
impl InstanceCS {
    fn crumb(&self, method: &'static str) {
        crate::isolate::crumb(self as *const InstanceCS as usize, method);
    }

    /// An Event Mode ends at `t` (updates, intervals read, Step Mode).
    pub fn settle(&mut self, t: f64) -> Result<(), Fmi2Error> {
        self.crumb("settle");
        match self {
            InstanceCS::V3(i) => i.settle(t),
            #[cfg(target_os = "linux")]
            InstanceCS::Isolated(i) => i.settle(t),
            _ => Ok(()),
        }
    }

    /// The next tick of its time-based clocks.
    pub fn next_tick(&mut self) -> Result<Option<f64>, Fmi2Error> {
        match self {
            InstanceCS::V3(i) => Ok(i.next_tick()),
            #[cfg(target_os = "linux")]
            InstanceCS::Isolated(i) => i.next_tick(),
            _ => Ok(None),
        }
    }

    /// The clocks due at `t` tick (Event Mode entered for them).
    pub fn tick_now(&mut self, t: f64) -> Result<(), Fmi2Error> {
        self.crumb("tick_now");
        match self {
            InstanceCS::V3(i) => i.tick_now(t),
            #[cfg(target_os = "linux")]
            InstanceCS::Isolated(i) => i.tick_now(t),
            _ => Ok(()),
        }
    }

    /// The samples its intermediateUpdate callback took since the last call (an FMI 3.0
    /// instance made with one; none for the others).
    pub fn take_intermediate(&mut self) -> Result<Vec<(f64, Vec<f64>)>, Fmi2Error> {
        match self {
            InstanceCS::V3(i) => i.take_intermediate(),
            _ => Ok(Vec::new()),
        }
    }

    /// Where its last step returned early (an instance with earlyReturnAllowed).
    pub fn take_early_return(&mut self) -> Result<Option<f64>, Fmi2Error> {
        match self {
            InstanceCS::V3(i) => Ok(i.take_early_return()),
            #[cfg(target_os = "linux")]
            InstanceCS::Isolated(i) => i.take_early_return(),
            _ => Ok(None),
        }
    }

    /// The importer's side of its clocks, kept with an FMU state (an FMI 3.0 instance with
    /// clocks or Event Mode; None for the others).
    pub fn clock_snapshot(&mut self) -> Result<Option<ClockSnapshot>, Fmi2Error> {
        match self {
            InstanceCS::V3(i) => Ok(i.clock_snapshot().map(|c| ClockSnapshot::Here(Box::new(c)))),
            #[cfg(target_os = "linux")]
            InstanceCS::Isolated(i) => Ok(i.clock_snapshot()?.map(ClockSnapshot::There)),
            _ => Ok(None),
        }
    }

    /// Its clocks as `snapshot` kept them (with the FMU state set back to the one taken then).
    pub fn restore_clocks(&mut self, snapshot: &ClockSnapshot) -> Result<(), Fmi2Error> {
        match (self, snapshot) {
            (InstanceCS::V3(i), ClockSnapshot::Here(s)) => {
                i.restore_clocks(s);
                Ok(())
            }
            #[cfg(target_os = "linux")]
            (InstanceCS::Isolated(i), ClockSnapshot::There(n)) => i.restore_clocks(*n),
            _ => Err(Fmi2Error::Importer("a clock snapshot of another instance".into())),
        }
    }

    /// Scheduled Execution: the partitions of the clocks that tick at `t` activated, once the
    /// inputs are set (nothing for the other instances); whether one was.
    pub fn activate_scheduled(&mut self, t: f64) -> Result<bool, Fmi2Error> {
        self.crumb("activate_scheduled");
        match self {
            InstanceCS::V3(i) => i.activate_pending(t),
            #[cfg(target_os = "linux")]
            InstanceCS::Isolated(i) => i.activate_scheduled(t),
            _ => Ok(false),
        }
    }

    /// Its output clocks read, once its input clocks are set.
    pub fn poll_output_clocks(&mut self, t: f64) -> Result<(), Fmi2Error> {
        self.crumb("poll_output_clocks");
        match self {
            InstanceCS::V3(i) => i.poll_output_clocks(t),
            #[cfg(target_os = "linux")]
            InstanceCS::Isolated(i) => i.poll_output_clocks(t),
            _ => Ok(()),
        }
    }

    /// Whether its clock `vr` ticks now.
    pub fn clock_active(&mut self, vr: u32) -> Result<bool, Fmi2Error> {
        match self {
            InstanceCS::V3(i) => Ok(i.clock_active(vr)),
            #[cfg(target_os = "linux")]
            InstanceCS::Isolated(i) => i.clock_active(vr),
            _ => Ok(false),
        }
    }

    /// Its input clock `vr` ticks at `t` (a clock connected to it ticked).
    pub fn trigger(&mut self, vr: u32, t: f64) -> Result<(), Fmi2Error> {
        self.crumb("trigger");
        match self {
            InstanceCS::V3(i) => i.trigger(vr, t),
            #[cfg(target_os = "linux")]
            InstanceCS::Isolated(i) => i.trigger(vr, t),
            _ => Err(Fmi2Error::Importer(
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
