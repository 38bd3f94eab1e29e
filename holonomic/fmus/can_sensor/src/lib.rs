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
#[path = "../../can_node.rs"]
mod can_node;

use can_node::{Notified, RX_MAX_SIZE, TX_MAX_SIZE, received, send};
use holonomic::models::can_messages::{Measurement, MeasurementFrame, Signal};
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// The networked pendulum's sensor node: samples alpha1, omega1, alpha2, omega2 every period and sends them in a CAN frame
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(
    fmi3_only,
    co_simulation_only,
    log_category(name = "logBus", description = "Bus operations refused"),
    can_network(
        name = "CAN",
        description = "The CAN bus the measurement travels on",
        rx_clock = rx_clock,
        rx_data = rx_data,
        tx_clock = tx_clock,
        tx_data = tx_data,
        bus_notifications = bus_notifications,
    )
)]
pub struct CanSensor {
    /// Simulation time
    #[variable(vr = 0, independent, unit = "s")]
    pub time: f64,
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
    /// Whether the node waits for Confirm, Arbitration Lost and Bus Error (FMI-LS-BUS BusNotifications)
    #[variable(vr = 13, name = "BusNotifications", parameter, fixed, start = false)]
    pub bus_notifications: bool,
    /// Angle resolution: the value of one bit of the 16-bit signals alpha1, alpha2
    #[variable(vr = 14, parameter, fixed, start = 1e-4, unit = "rad", min > 0.0)]
    pub angle_resolution: f64,
    /// Angular velocity resolution: the value of one bit of the 16-bit signals omega1, omega2
    #[variable(vr = 15, parameter, fixed, start = 1e-3, unit = "rad/s", min > 0.0)]
    pub rate_resolution: f64,
    /// Ticks when the importer delivers bus operations to this node
    #[variable(vr = 1002, name = "CAN.Rx_Clock", input, clock(triggered))]
    pub rx_clock: Clock,
    /// The bus operations delivered (FMI-LS-BUS CAN)
    #[variable(vr = 1001, name = "CAN.Rx_Data", input, discrete, clocks = [rx_clock], max_size = RX_MAX_SIZE)]
    pub rx_data: Vec<u8>,
    /// Ticks every period (a countdown the node sets to period at each tick): the samples
    #[variable(vr = 1004, name = "CAN.Tx_Clock", input, clock(countdown))]
    pub tx_clock: Clock,
    /// The bus operations this node sends (FMI-LS-BUS CAN)
    #[variable(vr = 1003, name = "CAN.Tx_Data", output, discrete, clocks = [tx_clock], max_size = TX_MAX_SIZE, depends = [alpha1, omega1, alpha2, omega2])]
    pub tx_data: Vec<u8>,
    /// Measurement frames sent
    #[variable(vr = 20, output, discrete, initial = exact, start = 0, depends = [])]
    pub frames_sent: i32,
    /// Signals sent limited to their range (+-32767 resolutions), or as 0 (not a number)
    #[variable(vr = 21, output, discrete, initial = exact, start = 0, depends = [])]
    pub signals_limited: i32,
    /// Confirm operations for tx_id received
    #[variable(vr = 22, output, discrete, initial = exact, start = 0, depends = [])]
    pub confirmed: i32,
    /// Arbitration Lost operations for tx_id received
    #[variable(vr = 23, output, discrete, initial = exact, start = 0, depends = [])]
    pub arbitration_lost: i32,
    /// Bus Error operations received
    #[variable(vr = 24, output, discrete, initial = exact, start = 0, depends = [])]
    pub bus_errors: i32,
    /// Received buffers refused as malformed (each answered with a Format Error operation)
    #[variable(vr = 25, output, discrete, initial = exact, start = 0, depends = [])]
    pub format_errors: i32,
    /// Tx_Data was read at the last Tx tick: it is emptied at the next event
    sent: bool,
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
        // What the importer read at the last Tx tick is gone ("the size of the corresponding
        // binary Tx_Data variable shall be set to zero").
        if self.sent {
            self.tx_data.clear();
            self.sent = false;
        }
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
