//! The CAN messages of the networked pendulum (issue 55): which signals each frame carries, in
//! which bytes, with which scaling and units. Plain bytes, no FMI and no bus: the network FMUs
//! (holonomic/fmus/can_sensor, can_controller, can_motor_drive) put these data fields into CAN
//! frames and take them out.
//!
//! Every signal is a little-endian signed 16-bit integer, `raw = round(value / resolution)`,
//! `value = raw · resolution` (a DBC signal with factor = resolution, offset 0). A value beyond
//! the range ±32767 · resolution is sent as the end of the range (and counted by the sender);
//! a value that is not a number is sent as 0 (counted too).
//!
//! | frame | identifier (parameter) | DLC | bytes 0-1 | bytes 2-3 | bytes 4-5 | bytes 6-7 |
//! |---|---|---|---|---|---|---|
//! | measurement | `sensor_id` (0x020) | 8 | α1 (rad) | ω1 (rad/s) | α2 (rad) | ω2 (rad/s) |
//! | command of motor i | `motor1_id` (0x010), `motor2_id` (0x011) | 2 | U_i (V) | | | |
//!
//! Resolutions (parameters of the sender and the receiver, which must agree): angles 1e-4 rad
//! (±3.2767 rad, more than ±π), angular velocities 1e-3 rad/s (±32.767 rad/s), voltages 1e-3 V
//! (±32.767 V; the supply limits U to ±6 V). The commands have the lower identifiers: they win
//! the arbitration against the measurement when both wait (on CAN the lowest identifier wins).

/// One signal's scaling: value = raw · resolution, raw an i16.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Signal {
    /// The value of one least significant bit, in the signal's unit.
    pub resolution: f64,
}

impl Signal {
    /// The raw value of `value`, and whether it had to be limited (beyond the range, or NaN).
    pub fn encode(&self, value: f64) -> (i16, bool) {
        let raw = (value / self.resolution).round();
        if raw.is_nan() {
            (0, true)
        } else if raw > f64::from(i16::MAX) {
            (i16::MAX, true)
        } else if raw < -f64::from(i16::MAX) {
            (-i16::MAX, true)
        } else {
            (raw as i16, false)
        }
    }

    /// The value of `raw`.
    pub fn decode(&self, raw: i16) -> f64 {
        f64::from(raw) * self.resolution
    }
}

/// The pendulum's measured state x = (α1, ω1, α2, ω2) (rad, rad/s, rad, rad/s).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Measurement {
    pub alpha1: f64,
    pub omega1: f64,
    pub alpha2: f64,
    pub omega2: f64,
}

/// The measurement frame's layout: its angle and angular velocity scaling.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasurementFrame {
    pub angle: Signal,
    pub rate: Signal,
}

/// Data length of the measurement frame (bytes).
pub const MEASUREMENT_DLC: usize = 8;
/// Data length of a command frame (bytes).
pub const COMMAND_DLC: usize = 2;

impl MeasurementFrame {
    /// The frame's data, and how many of its four signals had to be limited.
    pub fn encode(&self, m: &Measurement) -> ([u8; MEASUREMENT_DLC], u32) {
        let mut data = [0u8; MEASUREMENT_DLC];
        let mut limited = 0;
        let signals = [
            (self.angle, m.alpha1),
            (self.rate, m.omega1),
            (self.angle, m.alpha2),
            (self.rate, m.omega2),
        ];
        for (k, (signal, value)) in signals.into_iter().enumerate() {
            let (raw, clipped) = signal.encode(value);
            data[2 * k..2 * k + 2].copy_from_slice(&raw.to_le_bytes());
            limited += u32::from(clipped);
        }
        (data, limited)
    }

    /// The measurement of a frame's data; refused (with why) unless it is 8 bytes.
    pub fn decode(&self, data: &[u8]) -> Result<Measurement, String> {
        if data.len() != MEASUREMENT_DLC {
            return Err(format!(
                "a measurement frame has {MEASUREMENT_DLC} data bytes, this one {}",
                data.len()
            ));
        }
        let raw = |k: usize| i16::from_le_bytes([data[2 * k], data[2 * k + 1]]);
        Ok(Measurement {
            alpha1: self.angle.decode(raw(0)),
            omega1: self.rate.decode(raw(1)),
            alpha2: self.angle.decode(raw(2)),
            omega2: self.rate.decode(raw(3)),
        })
    }
}

/// A motor command frame's layout: the voltage's scaling.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommandFrame {
    pub voltage: Signal,
}

impl CommandFrame {
    /// The frame's data for voltage `u` (V), and whether it had to be limited.
    pub fn encode(&self, u: f64) -> ([u8; COMMAND_DLC], bool) {
        let (raw, clipped) = self.voltage.encode(u);
        (raw.to_le_bytes(), clipped)
    }

    /// The voltage of a frame's data (V); refused (with why) unless it is 2 bytes.
    pub fn decode(&self, data: &[u8]) -> Result<f64, String> {
        match <[u8; COMMAND_DLC]>::try_from(data) {
            Ok(bytes) => Ok(self.voltage.decode(i16::from_le_bytes(bytes))),
            Err(_) => Err(format!(
                "a command frame has {COMMAND_DLC} data bytes, this one {}",
                data.len()
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAYOUT: MeasurementFrame = MeasurementFrame {
        angle: Signal { resolution: 1e-4 },
        rate: Signal { resolution: 1e-3 },
    };

    #[test]
    fn a_measurement_arrives_rounded_to_its_resolution_in_the_documented_bytes() {
        let m = Measurement {
            alpha1: 0.1,
            omega1: -1.23456,
            alpha2: -0.05,
            omega2: 0.0004,
        };
        let (data, limited) = LAYOUT.encode(&m);
        assert_eq!(limited, 0);
        // α1 = 0.1 rad = 1000 · 1e-4: 0x03E8, little-endian; ω1 = -1.235 rad/s: -1235 = 0xFB2D.
        assert_eq!(&data[0..4], &[0xE8, 0x03, 0x2D, 0xFB]);
        let back = LAYOUT.decode(&data).unwrap();
        for (got, want, q) in [
            (back.alpha1, m.alpha1, 1e-4),
            (back.omega1, m.omega1, 1e-3),
            (back.alpha2, m.alpha2, 1e-4),
            (back.omega2, m.omega2, 1e-3),
        ] {
            assert!((got - want).abs() <= q / 2.0 + 1e-15, "{got} for {want}");
        }
    }

    #[test]
    fn values_beyond_the_range_are_sent_as_its_end_and_counted() {
        let m = Measurement {
            alpha1: 4.0,
            omega1: f64::NAN,
            alpha2: -1e300,
            omega2: 0.0,
        };
        let (data, limited) = LAYOUT.encode(&m);
        assert_eq!(limited, 3);
        let back = LAYOUT.decode(&data).unwrap();
        assert_eq!((back.alpha1, back.omega1, back.alpha2), (3.2767, 0.0, -3.2767));
    }

    #[test]
    fn data_of_another_length_is_refused_saying_what_was_expected() {
        let e = LAYOUT.decode(&[0; 7]).unwrap_err();
        assert!(e.contains("8 data bytes, this one 7"), "{e}");
        let command = CommandFrame {
            voltage: Signal { resolution: 1e-3 },
        };
        assert!(
            command
                .decode(&[1, 2, 3])
                .unwrap_err()
                .contains("2 data bytes, this one 3")
        );
        let (data, clipped) = command.encode(-5.9996);
        assert!(!clipped);
        assert_eq!(command.decode(&data).unwrap(), -6.0);
    }
}
