//! The Controller FMU through its C API, linked into the test binary: one instance with a
//! logger that collects the messages.
#![allow(dead_code)] // each test binary uses part of it

use controller_fmu::Controller;
use controller_fmu::*;
use rustfmu::__private::abi::*;
use rustfmu::Variables;
use rustfmu::testing::Log;

pub fn vr(name: &str) -> u32 {
    Controller::DESCRIPTION
        .by_name(name)
        .unwrap_or_else(|| panic!("the Controller has no variable '{name}'"))
        .value_reference
}

pub struct Fmu {
    pub c: fmi2Component,
    pub log: &'static Log,
    pub time: f64,
}

impl Fmu {
    /// Instantiated and in initialization mode.
    pub fn new() -> Fmu {
        Fmu::instantiate(fmi2CoSimulation)
    }

    /// Instantiated for `interface` (fmi2CoSimulation or fmi2ModelExchange), in initialization mode.
    pub fn instantiate(interface: fmi2Type) -> Fmu {
        let log = Log::leak();
        let c = rustfmu::testing::fmi2::instance(
            fmi2Instantiate,
            controller_fmu::__rustfmu_fmi2_exports::GUID,
            interface,
            c"robustness",
            log,
        );
        // SAFETY: a live instance.
        unsafe {
            assert_eq!(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
            assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        }
        Fmu { c, log, time: 0.0 }
    }

    pub fn set(&self, values: &[(&str, f64)]) -> fmi2Status {
        let (vrs, xs): (Vec<u32>, Vec<f64>) = values.iter().map(|(n, x)| (vr(n), *x)).unzip();
        // SAFETY: as many references as values.
        unsafe { fmi2SetReal(self.c, vrs.as_ptr(), vrs.len(), xs.as_ptr()) }
    }

    pub fn set_integer(&self, name: &str, x: i32) -> fmi2Status {
        // SAFETY: one reference, one value.
        unsafe { fmi2SetInteger(self.c, &vr(name), 1, &x) }
    }

    pub fn set_boolean(&self, name: &str, x: bool) -> fmi2Status {
        // SAFETY: one reference, one value.
        unsafe { fmi2SetBoolean(self.c, &vr(name), 1, &(x as fmi2Boolean)) }
    }

    pub fn get(&self, names: &[&str]) -> Vec<f64> {
        let vrs: Vec<u32> = names.iter().map(|n| vr(n)).collect();
        let mut out = vec![0.0; vrs.len()];
        // SAFETY: as many references as slots.
        let s = unsafe { fmi2GetReal(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) };
        assert_eq!(s, fmi2OK, "fmi2GetReal: {:?}", self.messages());
        out
    }

    pub fn exit_init(&self) -> fmi2Status {
        // SAFETY: a live instance.
        unsafe { fmi2ExitInitializationMode(self.c) }
    }

    pub fn step(&mut self, h: f64) -> fmi2Status {
        // SAFETY: a live instance.
        let s = unsafe { fmi2DoStep(self.c, self.time, h, fmi2True) };
        if s == fmi2OK {
            self.time += h;
        }
        s
    }

    pub fn messages(&self) -> Vec<(fmi2Status, String)> {
        self.log.take_texts()
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        // SAFETY: from fmi2Instantiate, freed once.
        unsafe { fmi2FreeInstance(self.c) };
    }
}
