//! The parameters the Controller and the SampledController share, declared once: the control
//! law and its PID gains (`mode` .. `drives_motors`), the plant the LQR gain is designed for
//! (`m1` .. `J2`), the LQR weights (`Q11` .. `R22`) and the motors the voltages are computed for
//! (`motor_R` .. `U_max`); and the type of `mode`. Both crates include this file with `#[path]`
//! (an FMU crate is a `cdylib` of exported C functions: one cannot depend on the other).
//!
//! The two FMUs describe them in words of their own (the Controller a sentence a parameter, the
//! SampledController a group heading and short names) and the Controller's law and gains are
//! tunable where the SampledController's are fixed; each row carries both, so that both
//! modelDescription.xml files stay what they were (their GUIDs follow their content).

/// `control_mode!(<doc comment>)`: the type of `mode`, the control law, with the description each
/// FMU gives it.
macro_rules! control_mode {
    ($(# $doc:tt)*) => {
        $(# $doc)*
        #[derive(FmuEnum, Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
        pub enum ControlMode {
            /// Full-state feedback M = -K (x - x_ref), eq. (14)
            #[fmu(name = "LQR")]
            Lqr = 1,
            /// A PID per joint, eq. (16)
            #[fmu(name = "PID")]
            Pid = 2,
            /// LQR and PID added
            #[fmu(name = "LQR_PID")]
            LqrPid = 3,
        }
    };
}

/// `with_design_parameters! { controller | sampled; <attributes> pub struct Name { <fields
/// before> } { <fields after> } }`: the struct with the design parameters between the two
/// groups of fields, each with the description and variability of the FMU named first; and what
/// is computed from them alone: `plant()`, `lqr_gain_rows()`, `law_with_gain(k)`.
macro_rules! with_design_parameters {
    ($which:ident; $(# $attr:tt)* pub struct $name:ident { $($head:tt)* } { $($tail:tt)* }) => {
        with_design_parameters!(@row $which [$($head)*] [$(# $attr)* pub struct $name] [$($tail)*] $name
            // A row: vr, field, the rest of its #[variable(vr, parameter, <variability>, ...)], then
            // each FMU's variability and description.
            20 mode: ControlMode [start = ControlMode::Lqr] controller tunable "Control law: LQR (M = -K (x - x_ref)), PID per joint, or LQR + PID" sampled fixed "Control law";
            21 Kp1: f64 [start = DEFAULT_PID[0].kp, unit = "N.m/rad", min = 0.0] controller tunable "PID proportional gain of joint 1" sampled fixed "PID gains of joint 1: proportional";
            22 Ki1: f64 [start = DEFAULT_PID[0].ki, unit = "N.m/(rad.s)", min = 0.0] controller tunable "PID integral gain of joint 1" sampled fixed "integral";
            23 Kd1: f64 [start = DEFAULT_PID[0].kd, unit = "N.m.s/rad", min = 0.0] controller tunable "PID derivative gain of joint 1 (acts on the filtered measured speed)" sampled fixed "derivative (on the filtered measured speed)";
            24 Kp2: f64 [start = DEFAULT_PID[1].kp, unit = "N.m/rad", min = 0.0] controller tunable "PID proportional gain of joint 2" sampled fixed "PID gains of joint 2: proportional";
            25 Ki2: f64 [start = DEFAULT_PID[1].ki, unit = "N.m/(rad.s)", min = 0.0] controller tunable "PID integral gain of joint 2" sampled fixed "integral";
            26 Kd2: f64 [start = DEFAULT_PID[1].kd, unit = "N.m.s/rad", min = 0.0] controller tunable "PID derivative gain of joint 2 (acts on the filtered measured speed)" sampled fixed "derivative";
            27 Tf: f64 [start = 0.01, unit = "s", min = 0.0] controller tunable "Time constant Tf of the derivative filter Kd s/(Tf s + 1); 0 = no filter" sampled fixed "Time constant Tf of the derivative filter; 0 = no filter";
            28 M_max: f64 [start = 20.0, unit = "N.m", min > 0.0] controller tunable "Torque limit M_max of M1, M2 (anti-windup: the integrators stop growing into it)" sampled fixed "Torque limit M_max";
            29 drives_motors: bool [start = false] controller fixed "True when U1, U2 drive the plant through motors: the voltage limit then also stops the integrators" sampled fixed "True when U1, U2 drive the plant through motors (the voltage limit stops the integrators)";
            40 m1: f64 [start = 0.5, unit = "kg", min > 0.0] controller fixed "Mass m1 of link 1 of the plant the LQR gain is designed for" sampled fixed "The plant the LQR gain is designed for: mass m1 of link 1";
            41 m2: f64 [start = 0.5, unit = "kg", min > 0.0] controller fixed "Mass m2 of link 2 of the plant the LQR gain is designed for" sampled fixed "mass m2 of link 2";
            42 l1: f64 [start = 1.0, unit = "m", min > 0.0] controller fixed "Length l1 of link 1 of the plant the LQR gain is designed for" sampled fixed "length l1 of link 1";
            43 l2: f64 [start = 1.0, unit = "m", min > 0.0] controller fixed "Length l2 of link 2 of the plant the LQR gain is designed for" sampled fixed "length l2 of link 2";
            44 g: f64 [start = 9.81, unit = "m/s2"] controller fixed "Gravitational acceleration g of the plant the LQR gain is designed for (any finite value)" sampled fixed "gravitational acceleration g";
            45 J1: f64 [start = 0.0, unit = "kg.m2", min = 0.0] controller fixed "Extra inertia J1 at joint 1 of the plant the LQR gain is designed for (the Pendulum's J1: n^2 J of the motor geared to joint 1)" sampled fixed "extra inertia J1 at joint 1";
            46 J2: f64 [start = 0.0, unit = "kg.m2", min = 0.0] controller fixed "Extra inertia J2 at joint 2 of the plant the LQR gain is designed for (the Pendulum's J2)" sampled fixed "extra inertia J2 at joint 2";
            50 Q11: f64 [start = 1.0, min = 0.0] controller fixed "LQR state weight Q(1,1) on alpha1 (Q is diagonal; the paper's Q = C'C gives 1, 0, 1, 0)" sampled fixed "LQR weights (diagonal Q, R; the paper's Q = C'C, R = I): Q(1,1)";
            51 Q22: f64 [start = 0.0, min = 0.0] controller fixed "LQR state weight Q(2,2) on omega1" sampled fixed "Q(2,2)";
            52 Q33: f64 [start = 1.0, min = 0.0] controller fixed "LQR state weight Q(3,3) on alpha2" sampled fixed "Q(3,3)";
            53 Q44: f64 [start = 0.0, min = 0.0] controller fixed "LQR state weight Q(4,4) on omega2" sampled fixed "Q(4,4)";
            54 R11: f64 [start = 1.0, min > 0.0] controller fixed "LQR input weight R(1,1) on M1 (R is diagonal; the paper's R = I)" sampled fixed "R(1,1)";
            55 R22: f64 [start = 1.0, min > 0.0] controller fixed "LQR input weight R(2,2) on M2" sampled fixed "R(2,2)";
            60 motor_R: f64 [start = 2.22, unit = "Ohm", min > 0.0] controller fixed "Armature resistance R of the motors the voltages are computed for" sampled fixed "The motors the voltages are computed for: armature resistance R";
            61 motor_km: f64 [start = 0.00449, unit = "N.m/A", min > 0.0] controller fixed "Torque constant km of the motors (> 0: U divides by it)" sampled fixed "torque constant km";
            62 motor_kb: f64 [start = 0.00448, unit = "V.s/rad", min = 0.0] controller fixed "Back-EMF constant kb of the motors" sampled fixed "back-EMF constant kb";
            63 motor_B: f64 [start = 9.0946, unit = "N.m.s/rad", min = 0.0] controller fixed "Viscous friction B of the motors, at the rotor (compensated in U)" sampled fixed "viscous friction B at the rotor";
            64 gear_ratio: f64 [start = 1.0, min > 0.0] controller fixed "Gear ratio n of the motors (rotor speed / joint speed)" sampled fixed "gear ratio n (rotor speed / joint speed)";
            65 U_max: f64 [start = 6.0, unit = "V", min > 0.0] controller fixed "Supply voltage: U1, U2 are limited to +-U_max" sampled fixed "supply voltage limit U_max";
        );
    };
    (@row controller [$($done:tt)*] $item:tt $tail:tt $name:ident
        $vr:tt $field:ident : $ty:tt [$($rest:tt)*] controller $var:ident $doc:tt sampled $_var:ident $_doc:tt; $($more:tt)*) => {
        with_design_parameters!(@row controller [$($done)* #[doc = $doc] #[variable(vr = $vr, parameter, $var, $($rest)*)] pub $field: $ty,] $item $tail $name $($more)*);
    };
    (@row sampled [$($done:tt)*] $item:tt $tail:tt $name:ident
        $vr:tt $field:ident : $ty:tt [$($rest:tt)*] controller $_var:ident $_doc:tt sampled $var:ident $doc:tt; $($more:tt)*) => {
        with_design_parameters!(@row sampled [$($done)* #[doc = $doc] #[variable(vr = $vr, parameter, $var, $($rest)*)] pub $field: $ty,] $item $tail $name $($more)*);
    };
    (@row $which:ident [$($done:tt)*] [$($item:tt)*] [$($tail:tt)*] $name:ident) => {
        $($item)* { $($done)* $($tail)* }

        impl $name {
            /// The plant the LQR gain is designed for.
            fn plant(&self) -> PendulumParams {
                PendulumParams {
                    m1: self.m1,
                    m2: self.m2,
                    l1: self.l1,
                    l2: self.l2,
                    g: self.g,
                    j1: self.J1,
                    j2: self.J2,
                }
            }

            /// The LQR gain K of eq. (14) for this plant and these weights, row i the torque M_i
            /// (the 2 x 4 array `K` every one of these FMUs declares).
            fn lqr_gain_rows(&self) -> Result<[[f64; 4]; 2], String> {
                let q = Matrix4::from_diagonal(&Vector4::new(self.Q11, self.Q22, self.Q33, self.Q44));
                let r = Matrix2::from_diagonal(&Vector2::new(self.R11, self.R22));
                let k = lqr_gain(&self.plant(), &q, &r)?;
                Ok([
                    [k[(0, 0)], k[(0, 1)], k[(0, 2)], k[(0, 3)]],
                    [k[(1, 0)], k[(1, 1)], k[(1, 2)], k[(1, 3)]],
                ])
            }

            /// The control law of the parameters, with the LQR gain `k`. Their domains are
            /// declared and enforced by the runtime, so every parameter set that reaches here is
            /// one the law can use.
            fn law_with_gain(&self, k: SMatrix<f64, 2, 4>) -> ControlLaw {
                ControlLaw {
                    mode: match self.mode {
                        ControlMode::Lqr => Mode::Lqr,
                        ControlMode::Pid => Mode::Pid,
                        ControlMode::LqrPid => Mode::LqrPid,
                    },
                    k,
                    pid: [
                        PidGains {
                            kp: self.Kp1,
                            ki: self.Ki1,
                            kd: self.Kd1,
                        },
                        PidGains {
                            kp: self.Kp2,
                            ki: self.Ki2,
                            kd: self.Kd2,
                        },
                    ],
                    tf: self.Tf,
                    m_max: self.M_max,
                    motor: DcMotorParams {
                        r: self.motor_R,
                        km: self.motor_km,
                        kb: self.motor_kb,
                        b: self.motor_B,
                        gear_ratio: self.gear_ratio,
                        u_max: self.U_max,
                        ..DcMotorParams::default()
                    },
                    drives_motors: self.drives_motors,
                }
            }
        }
    };
}
