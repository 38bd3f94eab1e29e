//! The `CanSensor` FMU (FMI 3.0, FMI-LS-BUS 1.0.0): the sensor node of the networked pendulum.
//! At every tick of its Tx clock (a countdown it sets to `period` again at each tick) it samples
//! its four inputs, the Pendulum's measured state x = (α1, ω1, α2, ω2), and sends them in one
//! CAN frame of identifier `tx_id`: four signed 16-bit signals, angles in units of
//! `angle_resolution`, angular velocities in units of `rate_resolution` (the layout:
//! holonomic::models::can_messages). The bus's Confirm, Arbitration Lost and Bus Error about its
//! frames are counted; a malformed received buffer is answered with a Format Error
//! (../can_node.rs).

// Not every node uses every helper of the shared file.
#[allow(dead_code)]
#[macro_use]
#[path = "../../can_node.rs"]
mod can_node;

use can_node::{Notified, RX_MAX_SIZE, TX_MAX_SIZE, received, send};
use holonomic::models::can_messages::{Measurement, MeasurementFrame, Signal};
use rustfmu::prelude::*;

can_node! {
    network: "The CAN bus the measurement travels on";
    log_bus: "Bus operations refused";
    /// The networked pendulum's sensor node: samples alpha1, omega1, alpha2, omega2 every period and sends them in a CAN frame
    pub struct CanSensor {
        /// Measured angle alpha1 of link 1 from the upward vertical, sampled at each Tx tick (connect Pendulum.alpha1)
        #[variable(vr = 1, input, start = 0.0, unit = "rad")]
        pub alpha1: f64,
        /// Measured angular velocity omega1 (connect Pendulum.omega1)
        #[variable(vr = 2, input, start = 0.0, unit = "rad/s")]
        pub omega1: f64,
        /// Measured absolute angle alpha2 of link 2 (connect Pendulum.alpha2)
        #[variable(vr = 3, input, start = 0.0, unit = "rad")]
        pub alpha2: f64,
        /// Measured angular velocity omega2 (connect Pendulum.omega2)
        #[variable(vr = 4, input, start = 0.0, unit = "rad/s")]
        pub omega2: f64,
        /// Identifier of the measurement frame (standard, 11 bits)
        #[variable(vr = 10, parameter, fixed, start = 0x020, min = 0, max = 0x7FF)]
        pub tx_id: i32,
        /// Sample period: the interval of CAN.Tx_Clock, the first tick one period after the start
        #[variable(vr = 12, parameter, fixed, start = 0.01, unit = "s", min > 0.0)]
        pub period: f64,
        bus_notifications(vr = 13),
        /// Angle resolution: the value of one bit of the 16-bit signals alpha1, alpha2
        #[variable(vr = 14, parameter, fixed, start = 1e-4, unit = "rad", min > 0.0)]
        pub angle_resolution: f64,
        /// Angular velocity resolution: the value of one bit of the 16-bit signals omega1, omega2
        #[variable(vr = 15, parameter, fixed, start = 1e-3, unit = "rad/s", min > 0.0)]
        pub rate_resolution: f64,
        terminal {
            /// Ticks every period (a countdown the node sets to period at each tick): the samples
            tx_clock: input, clock(countdown);
            tx_data: depends = [alpha1, omega1, alpha2, omega2];
        },
        /// Measurement frames sent
        count frames_sent(vr = 20),
        /// Signals sent limited to their range (+-32767 resolutions), or as 0 (not a number)
        count signals_limited(vr = 21),
        notifications(confirmed = 22, arbitration_lost = 23, ours = "tx_id"),
        bus_errors_and_format_errors(vr = 24, 25),
    }
}

impl CanSensor {
    fn layout(&self) -> MeasurementFrame {
        MeasurementFrame {
            angle: Signal {
                resolution: self.angle_resolution,
            },
            rate: Signal {
                resolution: self.rate_resolution,
            },
        }
    }
}

impl Model for CanSensor {
    fn initialize(&mut self, _ctx: &Context) -> Result<(), String> {
        // The first sample one period after the start (a countdown clock: what importers with a
        // bus simulation schedule, as for CanSignal).
        self.tx_clock.set_interval(self.period);
        Ok(())
    }

    fn update(&mut self, event: &mut Event) -> Result<(), String> {
        self.forget_sent();
        if self.rx_clock.is_active() {
            let mut notified = Notified {
                confirmed: self.confirmed,
                arbitration_lost: self.arbitration_lost,
                bus_errors: self.bus_errors,
            };
            for op in received(&self.rx_data, &mut self.tx_data, event, &mut self.format_errors) {
                notified.count(&op, &[self.tx_id]);
            }
            (self.confirmed, self.arbitration_lost, self.bus_errors) =
                (notified.confirmed, notified.arbitration_lost, notified.bus_errors);
        }
        if self.tx_clock.is_active() {
            let x = Measurement {
                alpha1: self.alpha1,
                omega1: self.omega1,
                alpha2: self.alpha2,
                omega2: self.omega2,
            };
            let (data, limited) = self.layout().encode(&x);
            send(&mut self.tx_data, self.tx_id, &data)?;
            self.frames_sent += 1;
            self.signals_limited += limited as i32;
            self.sent = true;
            self.tx_clock.set_interval(self.period);
        }
        Ok(())
    }
}

impl CoSimulation for CanSensor {}

rustfmu::export_fmi3!(CanSensor);
