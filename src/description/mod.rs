//! The typed description of a model: what `#[derive(Model)]` declares, fixed at compile time.
//!
//! One description feeds every output: the runtime dispatches and checks values with it, the
//! export macro encodes it into the binary (so the built library describes itself), and
//! `cargo fmu` decodes it from the binary and writes `modelDescription.xml` (FMI 2.0, later 3.0)
//! and the SSP files from it. The GUID is a name-based (SHA-1) UUID of the encoded description,
//! computed at compile time: the binary carries no XML writer and no hashing code.
//!
//! Every item here is `const`-constructible: the derive macro writes a `ModelDescription`
//! literal, and [`encode`] runs in const evaluation.
//!
//! One file per concern: the declarations (`variable`, `model`), the const encoder
//! ([`encode`]), the GUID (`guid`), the decoder ([`decode`]), the compile-time
//! checks of values (`check`). Every item is re-exported here, at the paths
//! (`rustfmu::description::X`) the derive's generated code and the tools use.

mod check;
mod decode;
mod encode;
mod guid;
mod model;
mod variable;

pub use check::*;
pub use decode::*;
pub use encode::*;
pub use guid::*;
pub use model::*;
pub use variable::*;
