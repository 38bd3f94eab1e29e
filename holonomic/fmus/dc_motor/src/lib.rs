//! The `DCMotor` FMU: the paper's DC motor (equation (17)) with a gearbox and a supply-voltage
//! limit; joint speed in, joint torque out. Model exchange integrates its equations; the
//! co-simulation step is their exact zero-order-hold discretization.

#![allow(non_snake_case)] // the paper's symbols: U, L, R, J, B

use holonomic::models::dc_motor::{DcMotorParams, DcMotorState};
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// Permanent-magnet DC motor with gearbox and supply-voltage limit (Liptak et al., 'The control
/// of holonomic system', eq. (17)); joint speed in, joint torque out
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(identifier = "DCMotor")]
// The output shaft (after the gearbox) as an FMI 3.0 terminal, a rotational flange as Modelica's:
// the joint speed comes in as a signal, the torque the motor delivers flows out of the FMU.
#[fmu(terminal(
    name = "shaft",
    kind = "org.modelica.Modelica.Mechanics.Rotational.Interfaces.Flange_b",
    description = "The gearbox's output shaft: the joint speed it turns at, the torque it delivers",
    member(variable = omega, name = "w", kind = "signal"),
    member(variable = tau, name = "tau", kind = "outflow"),
))]
pub struct DcMotor {
    /// Terminal voltage command U; the supply limits it to +-U_max (connect to Controller.U1 or U2)
    #[variable(vr = 0, input, continuous, start = 0.0, unit = "V")]
    pub U: f64,
    /// Speed of the driven joint, the generalized velocity conjugate to the torque output (connect to Pendulum.omega1 or omega2); ignored when coupled = false
    #[variable(vr = 1, input, continuous, start = 0.0, unit = "rad/s")]
    pub omega: f64,
    /// Torque on the joint, tau = n (km i - B omega_m) (connect to Pendulum.M1 or M2); 0 when coupled = false (unloaded)
    #[variable(vr = 10, output, continuous, unit = "N.m", depends = [omega, i], initial_depends = [omega, i, km, B, gear_ratio, coupled])]
    pub tau: f64,
    /// Armature current i, L di/dt = U_applied - R i - kb omega_m; the start value is the initial state
    #[variable(vr = 11, output, continuous, initial = exact, start = 0.0, unit = "A", depends = [i])]
    pub i: f64,
    /// Rotor speed omega_m: n omega when coupled, else the state omega_r of eq. (17)
    #[variable(vr = 12, output, continuous, unit = "rad/s", depends = [omega, omega_r], initial_depends = [omega, omega_r, gear_ratio, coupled])]
    pub omega_m: f64,
    /// Voltage actually applied: U limited to +-U_max
    #[variable(vr = 13, output, continuous, unit = "V", depends = [U], initial_depends = [U])]
    pub U_applied: f64,
    /// Rotor speed of the unloaded motor (coupled = false), J d(omega_r)/dt = km i - B omega_r; the start value is the initial speed. Coupled, the rotor follows the joint (omega_m = n omega) and omega_r keeps its start value
    #[variable(vr = 14, local, continuous, initial = exact, start = 0.0, unit = "rad/s")]
    pub omega_r: f64,
    /// d(i)/dt
    #[variable(vr = 15, name = "der(i)", local, continuous, unit = "A/s", derivative_of = i, depends = [U, omega, i, omega_r], initial_depends = [U, omega, i, omega_r, L, R, kb, gear_ratio, coupled])]
    pub der_i: f64,
    /// d(omega_r)/dt (0 when coupled)
    #[variable(vr = 16, name = "der(omega_r)", local, continuous, unit = "rad/s2", derivative_of = omega_r, depends = [i, omega_r], initial_depends = [i, omega_r, km, J, B, coupled])]
    pub der_omega_r: f64,
    /// Armature inductance L
    #[variable(vr = 20, parameter, fixed, start = 0.000121, unit = "H", min > 0.0)]
    pub L: f64,
    /// Armature resistance R
    #[variable(vr = 21, parameter, fixed, start = 2.22, unit = "Ohm", min > 0.0)]
    pub R: f64,
    /// Torque constant km (> 0: a motor without one gives no torque, and the Controller's voltage R/(n km) is undefined)
    #[variable(vr = 22, parameter, fixed, start = 0.00449, unit = "N.m/A", min > 0.0)]
    pub km: f64,
    /// Back-EMF constant kb
    #[variable(vr = 23, parameter, fixed, start = 0.00448, unit = "V.s/rad", min = 0.0)]
    pub kb: f64,
    /// Rotor inertia J (used when coupled = false; coupled, the rotor follows the joint rigidly and its n^2 J belongs to the plant: Pendulum.J1 or J2)
    #[variable(vr = 24, parameter, fixed, start = 2.18e-5, unit = "kg.m2", min > 0.0)]
    pub J: f64,
    /// Viscous friction B at the rotor (the paper's 9.0946 is about six orders of magnitude above small DC motors)
    #[variable(vr = 25, parameter, fixed, start = 9.0946, unit = "N.m.s/rad", min = 0.0)]
    pub B: f64,
    /// Gear ratio n = rotor speed / joint speed
    #[variable(vr = 26, parameter, fixed, start = 1.0, min > 0.0)]
    pub gear_ratio: f64,
    /// Supply voltage: |U| is limited to U_max
    #[variable(vr = 27, parameter, fixed, start = 6.0, unit = "V", min > 0.0)]
    pub U_max: f64,
    /// False (default): the motor runs unloaded and omega_m answers U as eq. (17) says; true: the rotor drives a joint through the gear (omega in, tau out), as the composed systems select
    #[variable(vr = 28, parameter, fixed, start = false)]
    pub coupled: bool,
}

impl DcMotor {
    pub fn params(&self) -> DcMotorParams {
        DcMotorParams {
            l: self.L,
            r: self.R,
            km: self.km,
            kb: self.kb,
            j: self.J,
            b: self.B,
            gear_ratio: self.gear_ratio,
            u_max: self.U_max,
        }
    }

    /// The rotor speed: n omega coupled, the state omega_r unloaded.
    fn rotor_speed<D: Real>(&self, v: &DcMotorContinuous<D>) -> D {
        if self.coupled {
            v.omega * self.gear_ratio
        } else {
            v.omega_r
        }
    }

    /// U limited to +-U_max (on the value: a limited voltage does not depend on U).
    fn applied<D: Real>(&self, u: D) -> D {
        if u.re() > self.U_max {
            D::from(self.U_max)
        } else if u.re() < -self.U_max {
            D::from(-self.U_max)
        } else {
            u
        }
    }
}

impl Model for DcMotor {
    // Every parameter's domain is declared and enforced by the runtime: nothing to check here.

    /// Eq. (17)'s armature circuit and, unloaded, the rotor.
    fn derivatives<D: Real>(&self, _t: D, v: &mut DcMotorContinuous<D>) {
        let omega_m = self.rotor_speed(v);
        v.der_i = (self.applied(v.U) - v.i * self.R - omega_m * self.kb) / self.L;
        v.der_omega_r = if self.coupled {
            D::from(0.0)
        } else {
            (v.i * self.km - v.omega_r * self.B) / self.J
        };
    }

    /// The joint torque n (km i - B omega_m), the rotor speed and the applied voltage.
    fn outputs<D: Real>(&self, _t: D, v: &mut DcMotorContinuous<D>) {
        let omega_m = self.rotor_speed(v);
        v.omega_m = omega_m;
        v.tau = if self.coupled {
            (v.i * self.km - omega_m * self.B) * self.gear_ratio
        } else {
            D::from(0.0)
        };
        v.U_applied = self.applied(v.U);
    }
}

impl CoSimulation for DcMotor {
    /// The exact zero-order-hold step of the linear equations (U and omega held).
    fn do_step(&mut self, t: f64, h: f64, _ctx: &mut Context) -> Result<(), StepFailure> {
        let p = self.params();
        if self.coupled {
            let s = DcMotorState {
                i: self.i,
                omega_m: p.gear_ratio * self.omega,
            };
            self.i = p.step_coupled(&s, self.U, self.omega, h).i;
        } else {
            let s = DcMotorState {
                i: self.i,
                omega_m: self.omega_r,
            };
            let next = p.step_free(&s, self.U, h).map_err(|message| StepFailure {
                reached_time: t,
                message,
            })?;
            (self.i, self.omega_r) = (next.i, next.omega_m);
        }
        Ok(())
    }
}

rustfmu::export_fmu!(DcMotor);
