//! Every CAN operation of FMI-LS-BUS 1.0.0 (each Configuration parameter, each Status and a
//! Format Error included), once: the fixture of the unit tests of src/lib.rs (each one's Length)
//! and of tests/c_headers.rs (the bytes of the standard's C header macros). Both include this file
//! with `#[path]`; the parent module brings the crate's types into scope.

use super::*;

const XL_DATA: [u8; 100] = {
    let mut d = [0u8; 100];
    let mut i = 0;
    while i < 100 {
        d[i] = (i * 7 + 3) as u8;
        i += 1;
    }
    d
};
const FORMAT_ERROR_DATA: [u8; 9] = [0x41, 0, 0, 0, 9, 0, 0, 0, 9];

/// Every CAN operation (each Configuration parameter and a Format Error included), in the order
/// the C program of tests/c_headers.rs writes them.
pub fn every_operation() -> Vec<Operation<'static>> {
    vec![
        Operation::CanTransmit(CanFrame {
            id: 0x123,
            ide: false,
            rtr: false,
            data: &[1, 2, 3, 4, 5, 6, 7, 8],
        }),
        Operation::CanTransmit(CanFrame {
            id: 0x1ABC_DEF0,
            ide: true,
            rtr: true,
            data: &[],
        }),
        Operation::CanFdTransmit(CanFdFrame {
            id: 0x7FF,
            ide: false,
            brs: true,
            esi: true,
            data: &[0xA0, 0xA1, 0xA2, 0xA3, 0xA4, 0xA5, 0xA6, 0xA7, 0xA8, 0xA9, 0xAA, 0xAB],
        }),
        Operation::CanXlTransmit(CanXlFrame {
            id: 0x42,
            ide: false,
            sec: true,
            sdt: 0x03,
            vcid: 0x7E,
            af: 0xDEAD_BEEF,
            data: &XL_DATA,
        }),
        Operation::Confirm { id: 0x123 },
        Operation::ArbitrationLost { id: 0x1ABC_DEF0 },
        Operation::BusError {
            id: 0x10,
            error_code: ErrorCode::CrcError,
            error_flag: ErrorFlag::Primary,
            is_sender: true,
        },
        Operation::BusError {
            id: 0x11,
            error_code: ErrorCode::BrokenErrorFrame,
            error_flag: ErrorFlag::Secondary,
            is_sender: false,
        },
        Operation::Configuration(Configuration::CanBaudrate(500_000)),
        Operation::Configuration(Configuration::CanFdBaudrate(2_000_000)),
        Operation::Configuration(Configuration::CanXlBaudrate(10_000_000)),
        Operation::Configuration(Configuration::ArbitrationLostBehavior(
            ArbitrationLostBehavior::BufferAndRetransmit,
        )),
        Operation::Configuration(Configuration::ArbitrationLostBehavior(
            ArbitrationLostBehavior::DiscardAndNotify,
        )),
        Operation::Status(Status::ErrorActive),
        Operation::Status(Status::ErrorPassive),
        Operation::Status(Status::BusOff),
        Operation::Wakeup,
        Operation::FormatError {
            data: &FORMAT_ERROR_DATA,
        },
    ]
}
