"""The platforms of every FMU: Linux (x86_64, and aarch64 in FMI 3.0) that loads on glibc 2.17,
Windows, and macOS on Intel and on Apple silicon (FMI 2.0: one universal `darwin64` binary, as the
Reference-FMUs ship it). Nothing here can run a macOS binary, so they are read: with a Mach-O reader
of this file's own (independent of fmu-build's, which uses the object crate), for their
architecture, the libraries they load, the oldest macOS they load on and the FMI functions they
export; the Linux ones with binutils' objdump for the glibc symbol versions they need.
"""

import hashlib
import pathlib
import re
import shutil
import struct
import subprocess
import zipfile

import pytest

from conftest import FMU_DIR, ROOT, outside_crate

FMUS = ["Pendulum", "DCMotor", "Controller", "BouncingBall", "Dahlquist", "Feedthrough", "Stair", "VanDerPol"]
CARGO_FMU = FMU_DIR.parent / "release" / "cargo-fmu"
PYTHON = ROOT / ".venv" / "bin" / "python"

FOLDERS = {
    2: {"linux64": ".so", "win64": ".dll", "darwin64": ".dylib"},
    3: {"x86_64-linux": ".so", "aarch64-linux": ".so", "x86_64-windows": ".dll", "x86_64-darwin": ".dylib",
        "aarch64-darwin": ".dylib"},
}

# Functions each version's binary must export (a sample of the required ones; fmu-build's
# validator checks the whole list).
FMI2 = ["fmi2GetTypesPlatform", "fmi2GetVersion", "fmi2Instantiate", "fmi2FreeInstance", "fmi2DoStep",
        "fmi2GetReal", "fmi2SetReal", "fmi2GetDerivatives", "fmi2GetFMUstate"]
FMI3 = ["fmi3GetVersion", "fmi3InstantiateCoSimulation", "fmi3InstantiateModelExchange", "fmi3DoStep",
        "fmi3GetFloat64", "fmi3SetFloat64", "fmi3FreeInstance", "fmi3GetFMUState"]

CPU_X86_64, CPU_ARM64 = 0x01000007, 0x0100000C
LC_LOAD_DYLIB, LC_LOAD_WEAK_DYLIB, LC_REEXPORT_DYLIB = 0xC, 0x80000018, 0x8000001F
LC_SYMTAB, LC_VERSION_MIN_MACOSX, LC_BUILD_VERSION, LC_CODE_SIGNATURE = 0x2, 0x24, 0x32, 0x1D


def fmu_path(name, version):
    return FMU_DIR / f"{name}.fmu" if version == 2 else FMU_DIR / "fmi3" / f"{name}.fmu"


def binaries(fmu):
    with zipfile.ZipFile(fmu) as z:
        return {n: z.read(n) for n in z.namelist() if n.startswith("binaries/") and not n.endswith("/")}


def slices(data):
    """(cputype, bytes) of each architecture of a thin or universal Mach-O file."""
    magic = struct.unpack(">I", data[:4])[0]
    if magic == 0xCAFEBABE:  # universal: big-endian header, 32-bit offsets
        count = struct.unpack(">I", data[4:8])[0]
        out = []
        for i in range(count):
            cpu, _, offset, size, _ = struct.unpack(">iiIII", data[8 + 20 * i: 28 + 20 * i])
            out.append((cpu & 0xFFFFFFFF, data[offset:offset + size]))
        return out
    assert struct.unpack("<I", data[:4])[0] == 0xFEEDFACF, "not a 64-bit little-endian Mach-O file"
    return [(struct.unpack("<I", data[4:8])[0], data)]


def code_signature_pages(data):
    """Checks the code signature of a thin Mach-O file (macOS on Apple silicon runs no unsigned
    code; zig signs ad hoc, as Apple's linker does): every page's SHA-256 in its CodeDirectory
    against the page. Returns (pages, ad-hoc flag), or None without a signature."""
    ncmds = struct.unpack("<I", data[16:20])[0]
    at, where = 32, None
    for _ in range(ncmds):
        cmd, size = struct.unpack("<II", data[at:at + 8])
        if cmd == LC_CODE_SIGNATURE:
            where = struct.unpack("<II", data[at + 8:at + 16])
        at += size
    if where is None:
        return None
    blob = data[where[0]:where[0] + where[1]]
    magic, _, count = struct.unpack(">III", blob[:12])
    assert magic == 0xFADE0CC0, hex(magic)  # embedded signature SuperBlob
    for i in range(count):
        _, offset = struct.unpack(">II", blob[12 + 8 * i:20 + 8 * i])
        cd = blob[offset:]
        if struct.unpack(">I", cd[:4])[0] != 0xFADE0C02:  # not the CodeDirectory
            continue
        _, _, _, flags, hash_offset, _, _, n_code, code_limit = struct.unpack(">9I", cd[:36])
        hash_size, hash_type, _, page_log2 = struct.unpack(">4B", cd[36:40])
        assert hash_type == 2 and hash_size == 32, (hash_type, hash_size)  # SHA-256
        page = 1 << page_log2
        assert n_code == -(-code_limit // page), (n_code, code_limit)
        for k in range(n_code):
            want = cd[hash_offset + 32 * k:hash_offset + 32 * (k + 1)]
            assert hashlib.sha256(data[k * page:min((k + 1) * page, code_limit)]).digest() == want, f"page {k}"
        return n_code, bool(flags & 0x2)
    raise AssertionError("a signature without a CodeDirectory")


def read_macho(data):
    """What one thin 64-bit Mach-O file is: cputype, file type, loaded libraries, oldest macOS
    (major, minor), and its external defined symbols (LC_SYMTAB)."""
    _, cpu, _, filetype, ncmds, _, _, _ = struct.unpack("<IiiIIIII", data[:32])
    libraries, minos, exports = [], None, []
    at = 32
    for _ in range(ncmds):
        cmd, size = struct.unpack("<II", data[at:at + 8])
        if cmd in (LC_LOAD_DYLIB, LC_LOAD_WEAK_DYLIB, LC_REEXPORT_DYLIB):
            name_at = struct.unpack("<I", data[at + 8:at + 12])[0]
            libraries.append(data[at + name_at:at + size].split(b"\0")[0].decode())
        elif cmd == LC_VERSION_MIN_MACOSX:
            v = struct.unpack("<I", data[at + 8:at + 12])[0]
            minos = (v >> 16, (v >> 8) & 0xFF)
        elif cmd == LC_BUILD_VERSION:
            platform, v = struct.unpack("<II", data[at + 8:at + 16])
            if platform == 1:  # macOS
                minos = (v >> 16, (v >> 8) & 0xFF)
        elif cmd == LC_SYMTAB:
            symoff, nsyms, stroff, _ = struct.unpack("<IIII", data[at + 8:at + 24])
            for i in range(nsyms):
                strx, ntype, sect, _, _ = struct.unpack("<IBBHQ", data[symoff + 16 * i: symoff + 16 * i + 16])
                # N_EXT, defined in a section (N_SECT), not a debugging entry (N_STAB).
                if ntype & 0x01 and ntype & 0x0E == 0x0E and not ntype & 0xE0 and sect:
                    exports.append(data[stroff + strx:].split(b"\0")[0].decode())
        at += size
    return cpu & 0xFFFFFFFF, filetype, libraries, minos, exports


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("name", FMUS)
def test_every_fmu_carries_every_platform(name, version):
    fmu = fmu_path(name, version)
    assert fmu.exists(), f"{fmu} is missing: run `cargo run --release -p fmu-build` first"
    have = sorted(binaries(fmu))
    want = sorted(f"binaries/{folder}/{name}{ext}" for folder, ext in FOLDERS[version].items())
    assert have == want


@pytest.mark.parametrize("name", FMUS)
def test_the_macos_binaries_are_what_their_folders_say(name):
    two, three = binaries(fmu_path(name, 2)), binaries(fmu_path(name, 3))
    intel, arm = three[f"binaries/x86_64-darwin/{name}.dylib"], three[f"binaries/aarch64-darwin/{name}.dylib"]
    # FMI 2.0's darwin64: one universal file of both, slice for slice the FMI 3.0 FMU's binaries
    # (one library serves both versions).
    universal = slices(two[f"binaries/darwin64/{name}.dylib"])
    assert sorted(cpu for cpu, _ in universal) == [CPU_X86_64, CPU_ARM64]
    assert dict(universal) == {CPU_X86_64: intel, CPU_ARM64: arm}
    for data, cpu, oldest in [(intel, CPU_X86_64, (10, 12)), (arm, CPU_ARM64, (11, 0))]:
        [(got_cpu, thin)] = slices(data)
        assert got_cpu == cpu
        got_cpu, filetype, libraries, minos, exports = read_macho(thin)
        assert filetype == 6, "not a dynamic library (MH_DYLIB)"
        assert libraries == ["/usr/lib/libSystem.B.dylib"], libraries
        assert minos == oldest, minos
        if cpu == CPU_ARM64:
            signed = code_signature_pages(thin)
            assert signed and signed[1], "an arm64 binary without a valid ad-hoc code signature does not load"
        names = {e[1:] for e in exports}  # Mach-O symbols carry a leading underscore
        missing = [f for f in FMI2 + FMI3 if f not in names]
        assert not missing, missing
        # Besides the FMI functions, only what zig's linker leaves exported (it ignores rustc's
        # export list): the linker's two and Rust's unwinder personality and one panic constant.
        other = sorted(n for n in names if not n.startswith(("fmi2", "fmi3")))
        assert len(other) <= 4 and all(re.search(r"dso_handle|mh_dylib_header|rust_eh_personality|EMPTY_PANIC", n)
                                       for n in other), other


def glibc_versions(so: pathlib.Path):
    out = subprocess.run(["objdump", "-T", so], capture_output=True, text=True, check=True).stdout
    return sorted({tuple(int(x) for x in v.split(".")[:2]) for v in re.findall(r"GLIBC_(\d+\.\d+(?:\.\d+)?)", out)})


def test_no_linux_binary_needs_a_glibc_newer_than_2_17(tmp_path):
    if not shutil.which("objdump"):
        pytest.fail("objdump is missing: run `bash tests/setup-env.sh` (binutils)")
    highest = {}
    for version in (2, 3):
        for name in FMUS:
            for entry, data in binaries(fmu_path(name, version)).items():
                if entry.endswith(".so"):
                    so = tmp_path / entry.replace("/", "_")
                    so.write_bytes(data)
                    highest[f"{fmu_path(name, version).relative_to(FMU_DIR)}:{entry}"] = glibc_versions(so)[-1]
    assert len(highest) == 2 * len(FMUS) + len(FMUS), highest  # linux64; x86_64-linux and aarch64-linux
    too_new = {k: v for k, v in highest.items() if v > (2, 17)}
    assert not too_new, too_new


def run(args, **kw):
    return subprocess.run([str(a) for a in args], capture_output=True, text=True, timeout=1800, **kw)


def rezip(src, dst, replace):
    with zipfile.ZipFile(src) as z, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as out:
        for n in z.namelist():
            out.writestr(n, replace.get(n, z.read(n)))


def test_validate_refuses_a_macos_binary_of_the_wrong_architecture_or_format(tmp_path):
    fmu = fmu_path("DCMotor", 3)
    b = binaries(fmu)
    swapped = tmp_path / "swapped.fmu"
    rezip(fmu, swapped, {"binaries/aarch64-darwin/DCMotor.dylib": b["binaries/x86_64-darwin/DCMotor.dylib"]})
    out = run([CARGO_FMU, "validate", swapped])
    assert out.returncode != 0
    assert "holds a x86_64 binary, which binaries/aarch64-darwin/ is not for" in out.stderr, out.stderr
    elf = tmp_path / "elf.fmu"
    rezip(fmu, elf, {"binaries/x86_64-darwin/DCMotor.dylib": b["binaries/x86_64-linux/DCMotor.so"]})
    out = run([CARGO_FMU, "validate", elf])
    assert out.returncode != 0
    assert "is no Mach-O binary" in out.stderr, out.stderr
    arm_linux = tmp_path / "arm.fmu"
    rezip(fmu, arm_linux, {"binaries/x86_64-linux/DCMotor.so": b["binaries/aarch64-linux/DCMotor.so"]})
    out = run([CARGO_FMU, "validate", arm_linux])
    assert out.returncode != 0
    assert "Aarch64 binary, which binaries/x86_64-linux/ is not for" in out.stderr, out.stderr


def test_a_new_crate_builds_for_linux_windows_and_both_macs_in_one_fmu():
    """`cargo fmu new` and `cargo fmu build --target ...` for the four platforms a user ships most:
    one FMU of each version with all of them, valid for fmu-build and fmpy (--python)."""
    crate, env = outside_crate("every-platform")
    targets = ["x86_64-unknown-linux-gnu.2.17", "x86_64-pc-windows-gnu", "x86_64-apple-darwin", "aarch64-apple-darwin"]
    args = ["cargo", "fmu", "build", "--python", PYTHON] + [a for t in targets for a in ("--target", t)]
    out = run(args, cwd=crate, env=env)
    assert out.returncode == 0, out.stderr[-4000:]
    fmus = FMU_DIR.parent / "user-crates" / "fmu"
    two, three = binaries(fmus / "EveryPlatform.fmu"), binaries(fmus / "fmi3" / "EveryPlatform.fmu")
    assert sorted(two) == [f"binaries/{f}/EveryPlatform{e}" for f, e in
                           [("darwin64", ".dylib"), ("linux64", ".so"), ("win64", ".dll")]]
    assert sorted(three) == [f"binaries/{f}/EveryPlatform{e}" for f, e in
                             [("aarch64-darwin", ".dylib"), ("x86_64-darwin", ".dylib"), ("x86_64-linux", ".so"),
                              ("x86_64-windows", ".dll")]]
    assert sorted(cpu for cpu, _ in slices(two["binaries/darwin64/EveryPlatform.dylib"])) == [CPU_X86_64, CPU_ARM64]
    for fmu in (fmus / "EveryPlatform.fmu", fmus / "fmi3" / "EveryPlatform.fmu"):
        out = run([CARGO_FMU, "validate", fmu, "--python", PYTHON])
        assert out.returncode == 0, out.stderr
        assert "not run on this machine" in out.stderr, out.stderr
