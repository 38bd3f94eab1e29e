//! FMI 3.0 clocks as a model sees them: a field of type [`Clock`] declared
//! `#[variable(.., clock(..))]` is a Clock variable, and [`Clock::is_active`] says in
//! [`Model::update`](crate::Model::update) whether it ticks now.
//!
//! The importer activates an input clock (`fmi3SetClock`) in Event Mode at the clock's ticks;
//! the runtime deactivates every clock when the event's `fmi3UpdateDiscreteStates` has run
//! (FMI 3.0, 2.2.9: "Any Clock active during fmi3UpdateDiscreteStates must be deactivated by
//! the FMU itself"). Between ticks the variables it clocks keep their values.

use serde::{Deserialize, Serialize};

/// A Clock variable's state: whether it ticks now, and, for a `changing` or `countdown` clock,
/// the interval to its next tick the model has given ([`Clock::set_interval`]).
///
/// ```
/// use rustfmu::prelude::*;
/// use rustfmu::{Clock, Variables};
/// use serde::{Deserialize, Serialize};
///
/// /// Counts the ticks of a periodic clock of 0.1 s.
/// #[derive(Model, Debug, Clone, Serialize, Deserialize)]
/// #[fmu(fmi3_only)]
/// pub struct Counter {
///     /// Ticks every 0.1 s
///     #[variable(vr = 0, input, clock(constant, interval = 0.1))]
///     pub tick: Clock,
///     /// Ticks so far
///     #[variable(vr = 1, output, discrete, clocks = [tick])]
///     pub count: i32,
/// }
///
/// impl Model for Counter {
///     fn update(&mut self, _event: &mut Event) -> Result<(), String> {
///         if self.tick.is_active() {
///             self.count += 1;
///         }
///         Ok(())
///     }
/// }
/// # impl CoSimulation for Counter {}
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Clock {
    active: bool,
    /// The interval the model gave (changing, countdown clocks), from the time it gave it.
    interval: Option<f64>,
    /// Given since the importer last read it (`fmi3GetIntervalDecimal` then says "changed").
    fresh: bool,
    /// The interval of a periodic clock the importer set (`fmi3SetIntervalDecimal`).
    set_interval: Option<f64>,
    /// The shift of a periodic clock the importer set (`fmi3SetShiftDecimal`).
    set_shift: Option<f64>,
    /// The interval last reported to the importer (periodic clocks: "changed" when it differs).
    reported: Option<f64>,
    /// An output clock the model ticked at this event.
    #[serde(default)]
    ticked: bool,
}

impl Clock {
    /// Whether the clock ticks now (in [`Model::update`](crate::Model::update): the importer
    /// activated it for this event).
    pub fn is_active(&self) -> bool {
        self.active || self.ticked
    }

    /// A `changing` or `countdown` clock: the next tick comes `interval` seconds from now (the
    /// importer reads it with `fmi3GetIntervalDecimal` after this event). Call it in
    /// [`Model::initialize`](crate::Model::initialize) for the first tick, and in
    /// [`Model::update`](crate::Model::update) for the next ones. `interval` must be finite and
    /// > 0 (the runtime refuses the event otherwise).
    pub fn set_interval(&mut self, interval: f64) {
        self.interval = Some(interval);
        self.fresh = true;
    }

    /// A triggered output clock: it ticks at this event (call it in
    /// [`Model::update`](crate::Model::update)). The importer learns it with `fmi3GetClock` in
    /// this Event Mode and reads the variables it clocks, which are then the values `update`
    /// left; `fmi3UpdateDiscreteStates` ends the tick. (On an input clock it does nothing: the
    /// importer activates those.)
    pub fn tick(&mut self) {
        self.ticked = true;
    }

    /// Whether [`tick`](Self::tick) was called at this event (an output clock).
    pub fn ticked(&self) -> bool {
        self.ticked
    }

    /// The interval given by [`set_interval`](Self::set_interval), if any.
    pub fn interval(&self) -> Option<f64> {
        self.interval
    }

    #[doc(hidden)]
    pub fn __set_active(&mut self, active: bool) {
        self.active = active;
        if !active {
            self.ticked = false;
        }
    }

    /// (interval, changed since the last report) of a clock the model times; the report is taken.
    #[doc(hidden)]
    pub fn __take_interval(&mut self) -> (Option<f64>, bool) {
        let fresh = std::mem::take(&mut self.fresh);
        (self.interval, fresh)
    }

    /// Whether an interval was given since the importer last read it.
    #[doc(hidden)]
    pub fn __fresh(&self) -> bool {
        self.fresh
    }

    /// Whether `interval` differs from the last one reported (periodic clocks); it is reported now.
    #[doc(hidden)]
    pub fn __report(&mut self, interval: f64) -> bool {
        let changed = self.reported.is_none_or(|r| r.to_bits() != interval.to_bits());
        self.reported = Some(interval);
        changed
    }

    #[doc(hidden)]
    pub fn __set_by_importer(&mut self) -> (&mut Option<f64>, &mut Option<f64>) {
        (&mut self.set_interval, &mut self.set_shift)
    }

    #[doc(hidden)]
    pub fn __importer_values(&self) -> (Option<f64>, Option<f64>) {
        (self.set_interval, self.set_shift)
    }
}
