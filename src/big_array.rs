//! Arrays of any length in a model's FMU state. The FMU state serializes the whole model struct
//! with serde, and serde's derive handles arrays of at most 32 elements. A longer array field (a
//! heat rod of 50 cells; a variable or internal state) gets one attribute:
//! `#[serde(with = "rustfmu::BigArray")]` for `[T; N]`, `#[serde(with = "rustfmu::BigMatrix")]`
//! for `[[T; M]; N]` (`#[derive(Model)]` says which at the field when it is missing).
//!
//! ```
//! use rustfmu::prelude::*;
//! use serde::{Deserialize, Serialize};
//!
//! /// Fifty cells
//! #[derive(Model, Debug, Clone, Serialize, Deserialize)]
//! #[fmu(fmi3_only)]
//! pub struct Cells {
//!     /// cell temperatures
//!     #[variable(vr = 1, parameter, fixed, start = [1.0; 50])]
//!     #[serde(with = "rustfmu::BigArray")]
//!     pub temperature: [f64; 50],
//!     /// a 40 x 40 grid
//!     #[variable(vr = 2, parameter, fixed)]
//!     #[serde(with = "rustfmu::BigMatrix")]
//!     pub grid: [[f32; 40]; 40],
//! }
//! # impl Model for Cells {}
//! # impl CoSimulation for Cells {}
//! let cells = <Cells as rustfmu::Variables>::start();
//! let bytes = postcard::to_allocvec(&cells).unwrap();
//! let back: Cells = postcard::from_bytes(&bytes).unwrap();
//! assert_eq!(back.temperature, [1.0; 50]);
//! ```

use serde::ser::SerializeTuple;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// `#[serde(with = "rustfmu::BigArray")]`: a one-dimensional array `[T; N]` of any length
/// (`serde_big_array`'s), serialized as serde's derive serializes one of at most 32 elements.
pub use serde_big_array::BigArray;

/// `#[serde(with = "rustfmu::BigMatrix")]`: a two-dimensional array `[[T; M]; N]` of any
/// lengths, serialized as serde's derive serializes one of at most 32 × 32 (a tuple of rows,
/// each a tuple of elements).
pub trait BigMatrix<'de>: Sized {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error>;
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error>;
}

impl<'de, T, const M: usize, const N: usize> BigMatrix<'de> for [[T; M]; N]
where
    T: Serialize + Deserialize<'de>,
{
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        /// A row, serialized as `serde_big_array` serializes a one-dimensional array.
        struct Row<'a, T, const M: usize>(&'a [T; M]);
        impl<T: Serialize, const M: usize> Serialize for Row<'_, T, M> {
            fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                BigArray::serialize(self.0, serializer)
            }
        }
        let mut rows = serializer.serialize_tuple(N)?;
        for row in self {
            rows.serialize_element(&Row(row))?;
        }
        rows.end()
    }
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let rows: [serde_big_array::Array<T, M>; N] = BigArray::deserialize(deserializer)?;
        Ok(rows.map(|row| row.0))
    }
}

#[cfg(test)]
mod tests {
    use super::{BigArray, BigMatrix};
    use serde::{Deserialize, Serialize};

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct Long {
        #[serde(with = "BigArray")]
        cells: [f64; 100],
        #[serde(with = "BigMatrix")]
        grid: [[i32; 33]; 3],
        #[serde(with = "BigMatrix")]
        tall: [[bool; 2]; 40],
        #[serde(with = "BigArray")]
        pairs: [(u8, char); 40],
        short: [[u8; 3]; 2],
    }

    #[test]
    fn arrays_longer_than_32_round_trip_as_serde_writes_short_ones() {
        let mut long = Long {
            cells: [0.0; 100],
            grid: [[0; 33]; 3],
            tall: [[false; 2]; 40],
            short: [[1, 2, 3], [4, 5, 6]],
            pairs: [(7, 'x'); 40],
        };
        for (i, c) in long.cells.iter_mut().enumerate() {
            *c = i as f64 * 0.5;
        }
        long.grid[2][32] = -7;
        long.tall[39][1] = true;
        let bytes = postcard::to_allocvec(&long).unwrap();
        let back: Long = postcard::from_bytes(&bytes).unwrap();
        assert_eq!(back, long);
        // The same bytes serde's derive writes for an array: its elements, then the next field
        // (no lengths in postcard's tuples).
        let cells: Vec<u8> = long
            .cells
            .iter()
            .flat_map(|c| postcard::to_allocvec(c).unwrap())
            .collect();
        assert_eq!(&bytes[..cells.len()], &cells[..]);
        // Too few elements is an error, not a panic.
        assert!(postcard::from_bytes::<Long>(&bytes[..bytes.len() - 1]).is_err());
    }
}
