//! Isolation: each component in a child process of its own (Linux).
//!
//! An FMU that crashes (a segmentation fault, `abort()`), exits or hangs takes its own process
//! down, not the runner or the Dask worker it runs in: the call fails with an error naming the
//! component, the FMI function and the time (fmi2Fatal: the next run starts every component's
//! process anew).
//!
//! The child is `rustfmu-runner serve-component` (the runner's own binary): it loads the FMU the
//! parent unpacked, instantiates it (co-simulation, FMI 2.0 or 3.0, or model exchange integrated
//! by [`crate::me`]) and answers the calls of an [`InstanceCS`](crate::instance::InstanceCS) it gets through a shared memory
//! file in /dev/shm (removed as soon as the child has it open). The FMUs' log messages travel back
//! with each answer and reach the parent's `log` logger as an in-process FMU's would.
//!
//! An FMI 3.0 component with clocks or Event Mode keeps its importer's clocks in the child too:
//! the master's calls of its clocks (an Event Mode ended, a clock ticked or read, an early
//! return taken, ...) cross the wire as the other calls, and the child makes the same FMI calls
//! as the runner's own process would (runner/README.md, "Clocks and Event Mode in child
//! processes").
//!
//! What keeps a step cheap (`bench/src/bin/isolation-cost.rs` measures it):
//! - calls that answer nothing but a status (the setters, fmi2DoStep, input derivatives) are not
//!   waited for: the setters travel with the next call that answers values, fmi2DoStep is sent at
//!   once so the components step in parallel in their processes while the master goes on. A
//!   failure of such a call comes back with the next call, reported as the call that failed (its
//!   function and time: [`Fmi2Error::Deferred`](crate::common::Fmi2Error::Deferred)); the calls sent after it are not made.
//! - both sides spin briefly on the shared memory before they sleep on a futex.
//!
//! The wire format is a few flat arrays of u32/f64 per call, written in place; a hand-written
//! codec (no serde): nothing is allocated per call on either side but the answer's values.

#[cfg(target_os = "linux")]
mod client;
#[cfg(not(target_os = "linux"))]
mod elsewhere;
mod options;
#[cfg(target_os = "linux")]
mod serve;
#[cfg(target_os = "linux")]
mod system;
#[cfg(target_os = "linux")]
mod wire;

#[cfg(target_os = "linux")]
pub use client::Isolated;
#[cfg(not(target_os = "linux"))]
pub use elsewhere::SystemProcess;
pub use options::{Granularity, Interface, Isolation, SystemInfo, find_worker};
#[cfg(not(target_os = "linux"))]
pub use options::{crumb, crumb_time};
#[cfg(target_os = "linux")]
pub use serve::serve;
#[cfg(target_os = "linux")]
pub use system::{SystemProcess, serve_system};
#[cfg(target_os = "linux")]
pub use wire::{crumb, crumb_time};
