//! Our bytes against the standard's own: the FMI-LS-BUS 1.0.0 C headers (the Modelica
//! Association's, BSD-2, in `../shared/independent/fmi-ls-bus-1.0.0/headers/`, used from there)
//! compiled with the system's C compiler.
//!
//! - Writing: a C program builds every CAN operation with the headers' `FMI3_LS_BUS_CAN_CREATE_OP_*`
//!   macros (and `FMI3_LS_BUS_CREATE_OP_FORMAT_ERROR`) into one buffer and prints it in hex; the
//!   same operations written by [`TxBuffer::push`] must give the same bytes.
//! - Reading: our bytes are handed to a C program that walks them with the headers'
//!   `FMI3_LS_BUS_READ_NEXT_OPERATION` and prints each operation's fields from the headers'
//!   packed structs; our [`decode_all`] of the same bytes must print the same lines.

use rustfmu_ls_bus::*;
use std::path::{Path, PathBuf};
use std::process::Command;

fn independent() -> PathBuf {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/independent");
    assert!(
        p.join("fmi-ls-bus-1.0.0/headers/fmi3LsBusUtilCan.h").is_file(),
        "{} has no FMI-LS-BUS headers",
        p.display()
    );
    p
}

/// Compiles `source` against the FMI-LS-BUS and FMI 3.0 headers, runs it with `args`, returns stdout.
fn run_c(name: &str, source: &str, args: &[&str]) -> String {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("ls-bus-c");
    std::fs::create_dir_all(&dir).unwrap();
    let c = dir.join(format!("{name}.c"));
    let exe = dir.join(name);
    std::fs::write(&c, source).unwrap();
    let inc = independent();
    let out = Command::new("cc")
        .args(["-std=c11", "-Wall", "-Werror", "-o"])
        .arg(&exe)
        .arg(&c)
        .arg("-I")
        .arg(inc.join("fmi-ls-bus-1.0.0/headers"))
        .arg("-I")
        .arg(inc.join("fmi-standard/3.0.2/headers"))
        .output()
        .expect("the C compiler `cc`");
    assert!(
        out.status.success(),
        "cc {}: {}",
        c.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let run = Command::new(&exe).args(args).output().unwrap();
    assert!(
        run.status.success(),
        "{}: {}",
        exe.display(),
        String::from_utf8_lossy(&run.stderr)
    );
    String::from_utf8(run.stdout).unwrap()
}

fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

// Every CAN operation, shared with the unit tests of src/lib.rs.
#[path = "common/every_operation.rs"]
mod every_operation;
use every_operation::every_operation;

const WRITE_C: &str = r#"
#include <stdio.h>
#include "fmi3LsBusUtilCan.h"

int main(void) {
    static fmi3UInt8 buffer[4096];
    fmi3LsBusUtilBufferInfo info;
    FMI3_LS_BUS_BUFFER_INFO_INIT(&info, buffer, sizeof(buffer));
    fmi3UInt8 can[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    fmi3UInt8 fd[12];
    for (int i = 0; i < 12; i++) fd[i] = (fmi3UInt8)(0xA0 + i);
    fmi3UInt8 xl[100];
    for (int i = 0; i < 100; i++) xl[i] = (fmi3UInt8)(i * 7 + 3);
    fmi3UInt8 bad[9] = {0x41, 0, 0, 0, 9, 0, 0, 0, 9};
    int ok = 1;
#define CHECK ok &= info.status == fmi3True
    FMI3_LS_BUS_CAN_CREATE_OP_CAN_TRANSMIT(&info, 0x123, FMI3_LS_BUS_FALSE, FMI3_LS_BUS_FALSE, 8, can); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_CAN_TRANSMIT(&info, 0x1ABCDEF0, FMI3_LS_BUS_TRUE, FMI3_LS_BUS_TRUE, 0, can); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_CAN_FD_TRANSMIT(&info, 0x7FF, FMI3_LS_BUS_FALSE, FMI3_LS_BUS_TRUE, FMI3_LS_BUS_TRUE, 12, fd); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_CAN_XL_TRANSMIT(&info, 0x42, FMI3_LS_BUS_FALSE, FMI3_LS_BUS_TRUE, 0x03, 0x7E, 0xDEADBEEF, 100, xl); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_CONFIRM(&info, 0x123); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_ARBITRATION_LOST(&info, 0x1ABCDEF0); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_BUS_ERROR(&info, 0x10, FMI3_LS_BUS_CAN_BUSERROR_PARAM_ERROR_CODE_CRC_ERROR,
        FMI3_LS_BUS_CAN_BUSERROR_PARAM_ERROR_FLAG_PRIMARY_ERROR_FLAG, FMI3_LS_BUS_TRUE); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_BUS_ERROR(&info, 0x11, FMI3_LS_BUS_CAN_BUSERROR_PARAM_ERROR_CODE_BROKEN_ERROR_FRAME,
        FMI3_LS_BUS_CAN_BUSERROR_PARAM_ERROR_FLAG_SECONDARY_ERROR_FLAG, FMI3_LS_BUS_FALSE); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_CONFIGURATION_CAN_BAUDRATE(&info, 500000); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_CONFIGURATION_CAN_FD_BAUDRATE(&info, 2000000); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_CONFIGURATION_CAN_XL_BAUDRATE(&info, 10000000); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_CONFIGURATION_ARBITRATION_LOST_BEHAVIOR(&info,
        FMI3_LS_BUS_CAN_CONFIG_PARAM_ARBITRATION_LOST_BEHAVIOR_BUFFER_AND_RETRANSMIT); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_CONFIGURATION_ARBITRATION_LOST_BEHAVIOR(&info,
        FMI3_LS_BUS_CAN_CONFIG_PARAM_ARBITRATION_LOST_BEHAVIOR_DISCARD_AND_NOTIFY); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_STATUS(&info, FMI3_LS_BUS_CAN_STATUS_PARAM_STATUS_KIND_ERROR_ACTIVE); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_STATUS(&info, FMI3_LS_BUS_CAN_STATUS_PARAM_STATUS_KIND_ERROR_PASSIVE); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_STATUS(&info, FMI3_LS_BUS_CAN_STATUS_PARAM_STATUS_KIND_BUS_OFF); CHECK;
    FMI3_LS_BUS_CAN_CREATE_OP_WAKEUP(&info); CHECK;
    FMI3_LS_BUS_CREATE_OP_FORMAT_ERROR(&info, 9, bad); CHECK;
    if (!ok) { fprintf(stderr, "a macro reported a full buffer\n"); return 1; }
    for (fmi3UInt8* p = FMI3_LS_BUS_BUFFER_START(&info); p < info.writePos; p++) printf("%02x", *p);
    printf("\n");
    return 0;
}
"#;

const READ_C: &str = r#"
#include <stdio.h>
#include <stdlib.h>
#include "fmi3LsBusUtilCan.h"

static void data(const fmi3UInt8* d, unsigned n) {
    printf(" data=");
    for (unsigned i = 0; i < n; i++) printf("%02x", d[i]);
}

int main(int argc, char** argv) {
    static fmi3UInt8 buffer[4096];
    const char* hex = argv[1];
    size_t n = 0;
    for (; hex[2 * n] && hex[2 * n + 1]; n++) {
        char two[3] = {hex[2 * n], hex[2 * n + 1], 0};
        buffer[n] = (fmi3UInt8)strtoul(two, NULL, 16);
    }
    fmi3LsBusUtilBufferInfo info;
    FMI3_LS_BUS_BUFFER_INFO_INIT(&info, buffer, sizeof(buffer));
    FMI3_LS_BUS_BUFFER_WRITE(&info, buffer, n);
    fmi3LsBusOperationHeader* op = NULL;
    while (FMI3_LS_BUS_READ_NEXT_OPERATION(&info, op)) {
        printf("op=%#x len=%u", (unsigned)op->opCode, (unsigned)op->length);
        switch (op->opCode) {
        case FMI3_LS_BUS_CAN_OP_CAN_TRANSMIT: {
            fmi3LsBusCanOperationCanTransmit* o = (fmi3LsBusCanOperationCanTransmit*)op;
            printf(" id=%#x ide=%u rtr=%u dl=%u", (unsigned)o->id, o->ide, o->rtr, (unsigned)o->dataLength);
            data(o->data, o->dataLength);
            break;
        }
        case FMI3_LS_BUS_CAN_OP_CANFD_TRANSMIT: {
            fmi3LsBusCanOperationCanFdTransmit* o = (fmi3LsBusCanOperationCanFdTransmit*)op;
            printf(" id=%#x ide=%u brs=%u esi=%u dl=%u", (unsigned)o->id, o->ide, o->brs, o->esi, (unsigned)o->dataLength);
            data(o->data, o->dataLength);
            break;
        }
        case FMI3_LS_BUS_CAN_OP_CANXL_TRANSMIT: {
            fmi3LsBusCanOperationCanXlTransmit* o = (fmi3LsBusCanOperationCanXlTransmit*)op;
            printf(" id=%#x ide=%u sec=%u sdt=%u vcid=%u af=%#x dl=%u", (unsigned)o->id, o->ide, o->sec, o->sdt, o->vcid,
                   (unsigned)o->af, (unsigned)o->dataLength);
            data(o->data, o->dataLength);
            break;
        }
        case FMI3_LS_BUS_CAN_OP_CONFIRM:
            printf(" id=%#x", (unsigned)((fmi3LsBusCanOperationConfirm*)op)->id);
            break;
        case FMI3_LS_BUS_CAN_OP_ARBITRATION_LOST:
            printf(" id=%#x", (unsigned)((fmi3LsBusCanOperationArbitrationLost*)op)->id);
            break;
        case FMI3_LS_BUS_CAN_OP_BUS_ERROR: {
            fmi3LsBusCanOperationBusError* o = (fmi3LsBusCanOperationBusError*)op;
            printf(" id=%#x code=%u flag=%u sender=%u", (unsigned)o->id, o->errorCode, o->errorFlag, o->isSender);
            break;
        }
        case FMI3_LS_BUS_CAN_OP_CONFIGURATION: {
            fmi3LsBusCanOperationConfiguration* o = (fmi3LsBusCanOperationConfiguration*)op;
            if (o->parameterType == FMI3_LS_BUS_CAN_CONFIG_PARAM_TYPE_ARBITRATION_LOST_BEHAVIOR)
                printf(" param=%u behavior=%u", o->parameterType, o->arbitrationLostBehavior);
            else
                printf(" param=%u baudrate=%u", o->parameterType, (unsigned)o->baudrate);
            break;
        }
        case FMI3_LS_BUS_CAN_OP_STATUS:
            printf(" status=%u", ((fmi3LsBusCanOperationStatus*)op)->status);
            break;
        case FMI3_LS_BUS_CAN_OP_WAKEUP:
            break;
        case FMI3_LS_BUS_OP_FORMAT_ERROR: {
            fmi3LsBusOperationFormatError* o = (fmi3LsBusOperationFormatError*)op;
            printf(" dl=%u", (unsigned)o->dataLength);
            data(o->data, o->dataLength);
            break;
        }
        default:
            printf(" unknown");
        }
        printf("\n");
    }
    return 0;
}
"#;

/// The line READ_C prints for `op`, from our decoded value.
fn line(op: &Operation<'_>) -> String {
    let data = |d: &[u8]| format!(" dl={} data={}", d.len(), hex(d));
    let c_hex = |v: u32| if v == 0 { "0".to_string() } else { format!("{v:#x}") };
    let head = format!("op={} len={}", c_hex(op.op_code()), op.encoded_len());
    let b = |v: bool| v as u8;
    let tail = match op {
        Operation::CanTransmit(f) => format!(" id={} ide={} rtr={}{}", c_hex(f.id), b(f.ide), b(f.rtr), data(f.data)),
        Operation::CanFdTransmit(f) => {
            format!(
                " id={} ide={} brs={} esi={}{}",
                c_hex(f.id),
                b(f.ide),
                b(f.brs),
                b(f.esi),
                data(f.data)
            )
        }
        Operation::CanXlTransmit(f) => format!(
            " id={} ide={} sec={} sdt={} vcid={} af={}{}",
            c_hex(f.id),
            b(f.ide),
            b(f.sec),
            f.sdt,
            f.vcid,
            c_hex(f.af),
            data(f.data)
        ),
        Operation::Confirm { id } | Operation::ArbitrationLost { id } => format!(" id={}", c_hex(*id)),
        Operation::BusError {
            id,
            error_code,
            error_flag,
            is_sender,
        } => format!(
            " id={} code={} flag={} sender={}",
            c_hex(*id),
            *error_code as u8,
            *error_flag as u8,
            b(*is_sender)
        ),
        Operation::Configuration(c) => match c {
            Configuration::CanBaudrate(r) => format!(" param=1 baudrate={r}"),
            Configuration::CanFdBaudrate(r) => format!(" param=2 baudrate={r}"),
            Configuration::CanXlBaudrate(r) => format!(" param=3 baudrate={r}"),
            Configuration::ArbitrationLostBehavior(x) => format!(" param=4 behavior={}", *x as u8),
        },
        Operation::Status(s) => format!(" status={}", *s as u8),
        Operation::Wakeup => String::new(),
        Operation::FormatError { data: d } => data(d),
    };
    head + &tail
}

#[test]
fn our_bytes_are_the_c_header_macros_bytes_for_every_can_operation() {
    let theirs = run_c("write", WRITE_C, &[]);
    let mut tx = TxBuffer::with_capacity(4096);
    for op in every_operation() {
        tx.push(&op).unwrap_or_else(|e| panic!("{op:?}: {e}"));
    }
    assert_eq!(hex(tx.as_bytes()), theirs.trim());
    // ... and what the macros wrote reads back as the same operations.
    let bytes: Vec<u8> = (0..theirs.trim().len() / 2)
        .map(|i| u8::from_str_radix(&theirs.trim()[2 * i..2 * i + 2], 16).unwrap())
        .collect();
    assert_eq!(decode_all(&bytes).unwrap(), every_operation());
}

#[test]
fn the_c_headers_read_our_bytes_as_the_operations_we_wrote() {
    let mut tx = TxBuffer::with_capacity(4096);
    let ops = every_operation();
    for op in &ops {
        tx.push(op).unwrap();
    }
    let theirs = run_c("read", READ_C, &[&hex(tx.as_bytes())]);
    let ours: Vec<String> = decode_all(tx.as_bytes()).unwrap().iter().map(line).collect();
    assert_eq!(theirs.lines().collect::<Vec<_>>(), ours);
    assert_eq!(ours.len(), ops.len());
}
