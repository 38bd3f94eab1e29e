//! FMI 3.0 arrays: their lengths at the start, and the start values of the elements within them.

use super::real_text;
use rustfmu::description::{Causality, ModelDescription, NOT_SIZED, Start, VarType, Variable};

/// An FMI 3.0 array's lengths at the start: per dimension, the capacity (its `<Dimension
/// start>`), or for one set by a structural parameter that parameter's start value. Checks what
/// the sizes rest on: one entry of `sized_by` per dimension, each naming a UInt64 structural
/// parameter (FMI 3.0, 2.4.7.6) whose start and `max` are within the capacity, and a start of
/// the whole capacity where the array has one.
pub fn array_sizes(d: &ModelDescription, v: &Variable) -> Result<Vec<usize>, String> {
    let capacities = v.fmi3.dimensions;
    if !v.is_sized() {
        return Ok(capacities.iter().map(|&n| n as usize).collect());
    }
    if v.fmi3.sized_by.len() != capacities.len() {
        return Err(format!(
            "{} dimension(s), {} structural parameter entries (one per dimension)",
            capacities.len(),
            v.fmi3.sized_by.len()
        ));
    }
    let mut sizes = Vec::with_capacity(capacities.len());
    for (&capacity, &vr) in capacities.iter().zip(v.fmi3.sized_by) {
        if vr == NOT_SIZED {
            sizes.push(capacity as usize);
            continue;
        }
        let p = d
            .variables
            .iter()
            .find(|p| p.value_reference == vr)
            .ok_or_else(|| format!("a length is set by value reference {vr}, which is no variable"))?;
        if p.var_type != VarType::UInt64 || p.causality != Causality::StructuralParameter {
            return Err(format!(
                "a length is set by '{}' (vr {vr}), which is not a UInt64 structural parameter (FMI 3.0, 2.4.7.6)",
                p.name
            ));
        }
        let Start::UInt64(start) = p.start else {
            return Err(format!("'{}', which sets a length, has no UInt64 start value", p.name));
        };
        match p.max {
            Some(max) if max.value <= capacity as f64 => {}
            Some(max) => {
                return Err(format!(
                    "'{}' sets a length of capacity {capacity} with max {}",
                    p.name,
                    real_text(max.value)
                ));
            }
            None => {
                return Err(format!("'{}' sets a length of capacity {capacity} without max", p.name));
            }
        }
        if start > u64::from(capacity) {
            return Err(format!(
                "'{}' starts at {start}, beyond the capacity {capacity} of the length it sets",
                p.name
            ));
        }
        sizes.push(start as usize);
    }
    if let Start::Array(items) = v.start
        && items.len() != v.element_count()
    {
        return Err(format!(
            "{} start values for a capacity of {} elements",
            items.len(),
            v.element_count()
        ));
    }
    Ok(sizes)
}

/// The start values an FMI 3.0 array lists: those of the elements within `sizes` (the lengths
/// at the start, [`array_sizes`]), in row-major order, taken from `items`, the start values of
/// the whole capacity (`capacities`) in row-major order. With every length at its capacity:
/// all of them.
pub(super) fn active_items<'a>(items: &'a [Start], capacities: &[u32], sizes: &[usize]) -> Vec<&'a Start> {
    let count: usize = sizes.iter().product();
    let mut out = Vec::with_capacity(count);
    let mut index = vec![0usize; sizes.len()];
    for _ in 0..count {
        // The element's place in the capacity's row-major storage.
        let at = index
            .iter()
            .zip(capacities)
            .fold(0usize, |at, (&i, &c)| at * c as usize + i);
        out.extend(items.get(at));
        // The next index, the last dimension fastest.
        for k in (0..sizes.len()).rev() {
            index[k] += 1;
            if index[k] < sizes[k] {
                break;
            }
            index[k] = 0;
        }
    }
    out
}
