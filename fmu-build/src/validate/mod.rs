//! Checks on a packaged FMU, each reported as a readable problem (an empty list: valid).
//! Archive layout, the description against the declarations it came from, the binary's
//! exported functions, and a short run through the C API as an importer makes it.
//!
//! One file per concern: [`archive`] (the whole check, entry point [`validate`]), [`description`]
//! (arrays, terminals), [`functions`] (the standards' function lists), [`binary`] (ELF exports,
//! architecture), [`pe`] (Windows), [`macho`] (macOS), [`glibc`], [`smoke`] ([`smoke2`],
//! [`smoke3`], [`run`]: the run through the C API), [`fmpy`], [`info`] (`cargo fmu info`).

mod archive;
mod binary;
mod description;
mod fmpy;
mod functions;
mod glibc;
mod info;
mod ls_bus;
mod macho;
mod pe;
mod run;
mod smoke;
mod smoke2;
mod smoke3;

pub use archive::validate;
pub use binary::{architecture_problems, check_exports, elf_exports, export_problems};
pub use description::{array_problems, terminal_problems};
pub use fmpy::{fmpy_ready, fmpy_validate};
pub use functions::{FMI2_CS_FUNCTIONS, FMI2_FUNCTIONS, FMI3_FUNCTIONS};
pub use glibc::{GlibcVersion, glibc_needed, glibc_requirements};
pub use info::info;
pub use ls_bus::ls_bus_problems;
pub use macho::{MachOSlice, macho_problems, macho_slices, macos_binaries};
pub use pe::{PeTables, not_windows_dlls, pe_problems, pe_tables};
pub use run::NOTE;
use smoke::smoke_run_in_child;
pub use smoke::smoke_run_version;
pub use smoke2::smoke_run;
pub use smoke3::smoke_run3;
