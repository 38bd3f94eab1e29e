//! How FMI 2.0 says what the core speaks of: its function names (the first column of the
//! core's table of both versions' names), its state names (the standard's, section 4.2.4 and
//! 3.2.3), and `GUID`.

use crate::core::{Terms, Version};

/// The functions' names of `crate::core::c_names`; the state names are the core's (FMI 2.0's).
pub static TERMS: Terms = Terms::of(Version::Fmi2, "GUID", "FMUstate", &[]);

// The core answers in its own status values; they are FMI 2.0's.
const _: () = {
    use super::abi::*;
    use crate::core::*;
    assert!(fmi2OK == OK && fmi2Warning == WARNING && fmi2Discard == DISCARD);
    assert!(fmi2Error == ERROR && fmi2Fatal == FATAL);
};
