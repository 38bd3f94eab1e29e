//! Values of every FMI 3.0 type, scalars and arrays ([`crate::values::Values`]), got and set
//! with the type's own fmi3Get{Type} / fmi3Set{Type}, `nValues` the buffer's length.

use super::{Fmi2Error, Instance3, check};
use crate::values::Values;
use rustfmu::fmi3::abi::*;
use std::ffi::CStr;

impl Instance3 {
    /// The values of `vrs` (variables of `out`'s type; arrays whole) into `out`, as long as all
    /// their elements together. A clocked variable is read while one of its clocks ticks; between
    /// the ticks it gives the value of its last tick (see `clocks.rs`).
    pub fn get_typed(&mut self, vrs: &[u32], out: &mut Values) -> Result<(), Fmi2Error> {
        match self.clocked_call(vrs)? {
            None => self.get_typed_raw(vrs, out),
            Some(true) => {
                self.get_typed_raw(vrs, out)?;
                let held = self.clocks.as_mut().expect("clocks");
                held.evaluated = true;
                held.fresh.insert(vrs[0]);
                held.held_typed.insert(vrs[0], out.clone());
                Ok(())
            }
            Some(false) => {
                let held = self.clocks.as_ref().expect("clocks");
                if let Some(v) = held.held_typed.get(&vrs[0])
                    && std::mem::discriminant(v) == std::mem::discriminant(out)
                {
                    out.clone_from(v);
                }
                Ok(())
            }
        }
    }

    /// Sets `vrs` (variables of `values`' type; arrays whole) to `values`; a clocked variable
    /// only while one of its clocks ticks (the master sets it again at the next tick).
    pub fn set_typed(&mut self, vrs: &[u32], values: &Values) -> Result<(), Fmi2Error> {
        match self.clocked_call(vrs)? {
            None | Some(true) => self.set_typed_raw(vrs, values),
            Some(false) => Ok(()),
        }
    }

    /// None: no clocked variable among `vrs`; Some(whether its clocks tick) for one clocked
    /// variable (a typed call of the runner names one variable at a time).
    fn clocked_call(&self, vrs: &[u32]) -> Result<Option<bool>, Fmi2Error> {
        let Some(state) = self.clocks.as_ref() else {
            return Ok(None);
        };
        if !vrs.iter().any(|v| state.plan.clocked.contains_key(v)) {
            return Ok(None);
        }
        if vrs.len() != 1 {
            return Err(Fmi2Error::Importer(format!(
                "value references {vrs:?}: a clocked variable is got and set alone"
            )));
        }
        Ok(Some(state.free(vrs[0])))
    }

    fn get_typed_raw(&mut self, vrs: &[u32], out: &mut Values) -> Result<(), Fmi2Error> {
        let api = &self.library.api;
        let c = self.c;
        macro_rules! get {
            ($f:ident, $x:expr) => {
                // SAFETY: a live instance; `vrs` holds vrs.len() references and the buffer
                // $x.len() values of the function's type, passed as nValues.
                check(unsafe { (api.$f)(c, vrs.as_ptr(), vrs.len(), $x.as_mut_ptr(), $x.len()) })
            };
        }
        match out {
            Values::Float32(x) => get!(get_float32, x),
            Values::Float64(x) => get!(get_float64, x),
            Values::Int8(x) => get!(get_int8, x),
            Values::UInt8(x) => get!(get_uint8, x),
            Values::Int16(x) => get!(get_int16, x),
            Values::UInt16(x) => get!(get_uint16, x),
            Values::Int32(x) => get!(get_int32, x),
            Values::UInt32(x) => get!(get_uint32, x),
            Values::Int64(x) => get!(get_int64, x),
            Values::UInt64(x) => get!(get_uint64, x),
            Values::Boolean(x) => get!(get_boolean, x),
            Values::String(x) => {
                self.ptrs.clear();
                self.ptrs.resize(x.len(), std::ptr::null());
                // SAFETY: a live instance; `ptrs` holds x.len() pointers for the FMU to fill.
                check(unsafe {
                    (api.get_string)(
                        c,
                        vrs.as_ptr(),
                        vrs.len(),
                        self.ptrs.as_mut_ptr() as *mut fmi3String,
                        x.len(),
                    )
                })?;
                for (o, p) in x.iter_mut().zip(&self.ptrs) {
                    if p.is_null() {
                        return Err(Fmi2Error::Importer("fmi3GetString gave a NULL string".into()));
                    }
                    // SAFETY: a NUL-terminated string of the FMU, valid until its next call.
                    let s = unsafe { CStr::from_ptr(p.cast()) };
                    o.clear();
                    o.extend_from_slice(s.to_bytes_with_nul());
                }
                Ok(())
            }
            Values::Binary(x) => {
                self.ptrs.clear();
                self.ptrs.resize(x.len(), std::ptr::null());
                self.sizes.clear();
                self.sizes.resize(x.len(), 0);
                // SAFETY: a live instance; `sizes` and `ptrs` hold x.len() slots for the FMU.
                check(unsafe {
                    (api.get_binary)(
                        c,
                        vrs.as_ptr(),
                        vrs.len(),
                        self.sizes.as_mut_ptr(),
                        self.ptrs.as_mut_ptr(),
                        x.len(),
                    )
                })?;
                for ((o, p), n) in x.iter_mut().zip(&self.ptrs).zip(&self.sizes) {
                    o.clear();
                    if *n == 0 {
                        continue;
                    }
                    if p.is_null() {
                        return Err(Fmi2Error::Importer(format!("fmi3GetBinary gave NULL for {n} bytes")));
                    }
                    // SAFETY: the FMU's `n` bytes at `p`, valid until its next call.
                    o.extend_from_slice(unsafe { std::slice::from_raw_parts(*p, *n) });
                }
                Ok(())
            }
        }
    }

    fn set_typed_raw(&mut self, vrs: &[u32], values: &Values) -> Result<(), Fmi2Error> {
        let api = &self.library.api;
        let c = self.c;
        macro_rules! set {
            ($f:ident, $x:expr) => {
                // SAFETY: a live instance; `vrs` holds vrs.len() references and the values
                // $x.len() of the function's type, passed as nValues.
                check(unsafe { (api.$f)(c, vrs.as_ptr(), vrs.len(), $x.as_ptr(), $x.len()) })
            };
        }
        match values {
            Values::Float32(x) => set!(set_float32, x),
            Values::Float64(x) => set!(set_float64, x),
            Values::Int8(x) => set!(set_int8, x),
            Values::UInt8(x) => set!(set_uint8, x),
            Values::Int16(x) => set!(set_int16, x),
            Values::UInt16(x) => set!(set_uint16, x),
            Values::Int32(x) => set!(set_int32, x),
            Values::UInt32(x) => set!(set_uint32, x),
            Values::Int64(x) => set!(set_int64, x),
            Values::UInt64(x) => set!(set_uint64, x),
            Values::Boolean(x) => set!(set_boolean, x),
            Values::String(x) => {
                self.ptrs.clear();
                for s in x {
                    if s.last() != Some(&0) {
                        return Err(Fmi2Error::Importer("a String without its NUL".into()));
                    }
                    self.ptrs.push(s.as_ptr());
                }
                // SAFETY: a live instance; `ptrs` holds x.len() NUL-terminated strings.
                check(unsafe {
                    (api.set_string)(
                        c,
                        vrs.as_ptr(),
                        vrs.len(),
                        self.ptrs.as_ptr() as *const fmi3String,
                        x.len(),
                    )
                })
            }
            Values::Binary(x) => {
                self.ptrs.clear();
                self.sizes.clear();
                for b in x {
                    self.ptrs.push(b.as_ptr());
                    self.sizes.push(b.len());
                }
                // SAFETY: a live instance; `ptrs` and `sizes` hold x.len() byte arrays and lengths.
                check(unsafe {
                    (api.set_binary)(
                        c,
                        vrs.as_ptr(),
                        vrs.len(),
                        self.sizes.as_ptr(),
                        self.ptrs.as_ptr(),
                        x.len(),
                    )
                })
            }
        }
    }
}
