"""The main job's setup installs what the main job's builds need, read from the dependency trees of
what it builds, not from what this machine happens to have: the tests install more (libclang-dev
for the benchmarks' fmi crate, valgrind, wine, ...), CI keeps the packages of earlier runs, so a main job that works here can
still fail on a new user's fresh machine (it did: the runner's fmi-sys runs bindgen, which needs
libclang, and only the tests' setup installed it).

What the main job builds is read from examples/run.sh (every `cargo ... -p NAME`, and `build
--workspace`: every FMU crate, for the targets its Cargo.toml names) and from tests/setup-env.sh
(the module it builds). What a crate needs from Debian is a table below, keyed by the native
library a crate declares (`links` in its Cargo.toml): a crate of the tree with a `links` key the
table does not know fails the test, so a new native dependency cannot slip in unseen."""

import json
import pathlib
import re
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]

# `links` value -> the Debian packages a build of that crate needs on the machine.
NEEDS_OF_LINKS = {
    # clang-sys (bindgen, in fmi-sys's build script) loads libclang.so at build time.
    "clang": ["libclang-dev"],
    # pyo3-ffi / pyo3: an extension module, built against the venv's CPython; links no libpython.
    "python": [],
    "pyo3-python": [],
    # zstd-sys compiles its bundled C sources (gcc, via the cc crate below).
    "zstd": [],
    # A `links` key that only keeps one version of the crate in a build; no native code.
    "prettyplease02": [],
}
# Crates whose presence in a build means a C compiler runs.
NEEDS_OF_CRATE = {"cc": ["gcc"]}
# Targets other than the host: the linker fmu-build's up-front check asks for. macOS and Linux with a
# glibc version (`x86_64-unknown-linux-gnu.2.17`) are linked by zig, from the venv (ziglang and
# cargo-zigbuild in examples/requirements.txt): no Debian package.
NEEDS_OF_TARGET = {
    "x86_64-pc-windows-gnu": ["gcc-mingw-w64-x86-64"],
    "aarch64-unknown-linux-gnu": ["gcc-aarch64-linux-gnu"],
    "x86_64-unknown-linux-gnu.2.17": [],
    "aarch64-unknown-linux-gnu.2.17": [],
    "x86_64-apple-darwin": [],
    "aarch64-apple-darwin": [],
}


def host_triple() -> str:
    out = subprocess.run(["rustc", "-vV"], capture_output=True, text=True, check=True).stdout
    return re.search(r"^host: (\S+)", out, re.M).group(1)


@pytest.fixture(scope="module")
def metadata():
    out = subprocess.run(["cargo", "metadata", "--format-version", "1", "--locked"], cwd=ROOT,
                         capture_output=True, text=True, check=True, timeout=300)
    return json.loads(out.stdout)


def fmu_crates(metadata):
    """The workspace's FMU crates (a cdylib depending on rustfmu), as `cargo fmu build --workspace`
    finds them, with the targets each names (or the workspace names for it)."""
    members = set(metadata["workspace_members"])
    # A crate without targets of its own takes [workspace.metadata.fmu] targets.
    default = ((metadata.get("metadata") or {}).get("fmu") or {}).get("targets") or []
    out = {}
    for p in metadata["packages"]:
        if p["id"] not in members:
            continue
        cdylib = any("cdylib" in t["crate_types"] for t in p["targets"])
        model = ((p.get("metadata") or {}).get("fmu") or {}).get("model", True)
        if cdylib and model is not False and any(d["name"] == "rustfmu" for d in p["dependencies"]):
            out[p["name"]] = ((p.get("metadata") or {}).get("fmu") or {}).get("targets") or default
    return out


def main_job_builds(metadata):
    """{package: [targets]} of what examples/run.sh and its setup build ([] = the host only)."""
    script = (ROOT / "examples" / "run.sh").read_text()
    setup = (ROOT / "tests" / "setup-env.sh").read_text()
    assert "tests/setup-env.sh --main-job" in script, "the main job no longer calls its setup"
    # Each `cargo run/build` command with its continuation lines (not in comments or in the
    # summary's labels); every `-p NAME` in it.
    code = "\n".join(l for l in script.splitlines() if not l.strip().startswith(("#", "lap ")))
    commands = re.findall(r"\bcargo (?:run|build)\b(?:[^\n]*\\\n)*[^\n]*", code)
    builds = {name: [] for c in commands for name in re.findall(r"-p (\S+)", c)}
    assert builds, "found no `cargo run/build -p NAME` in examples/run.sh"
    if re.search(r"(-p fmu-build --|cargo-fmu) build --workspace", script):
        builds.update(fmu_crates(metadata))
    if re.search(r"cargo-fmu (fmu )?container", script):
        # The container FMUs' binary, for the workspace's FMU targets (those the components carry).
        default = ((metadata.get("metadata") or {}).get("fmu") or {}).get("targets") or []
        builds["rustfmu-container"] = list(default)
    by_dir = {str(pathlib.Path(p["manifest_path"]).parent.relative_to(ROOT)): p["name"]
              for p in metadata["packages"] if p["id"] in set(metadata["workspace_members"])}
    for folder in re.findall(r"cd (\S+) && [^\n]*maturin", setup):
        assert folder in by_dir, f"setup-env.sh runs maturin in {folder}, which is no workspace package"
        builds[by_dir[folder]] = []
    return builds


def tree(packages, target):
    out = subprocess.run(["cargo", "tree", "--locked", "-e", "normal,build", "--target", target, "--prefix", "none",
                          "--format", "{p}"] + [a for p in packages for a in ("-p", p)],
                         cwd=ROOT, capture_output=True, text=True, check=True, timeout=300)
    return {line.split()[0] for line in out.stdout.splitlines() if line.strip()}


def setup_installs(*args):
    out = subprocess.run(["bash", "tests/setup-env.sh", *args, "--list"], cwd=ROOT, capture_output=True,
                         text=True, check=True, timeout=60)
    return set(out.stdout.split())


def test_the_main_jobs_setup_installs_what_its_builds_need(metadata):
    host = host_triple()
    builds = main_job_builds(metadata)
    assert "rustfmu-runner-python" in builds and "fmu-build" in builds, builds
    links = {p["name"]: p["links"] for p in metadata["packages"] if p.get("links")}
    needed = {}  # Debian package -> why
    for target in sorted({t for ts in builds.values() for t in ts} | {host}):
        crates = list(builds) if target == host else [p for p, ts in builds.items() if target in ts]
        names = tree(crates, re.sub(r"\.\d+\.\d+$", "", target))
        for name in sorted(names):
            if name in links:
                assert links[name] in NEEDS_OF_LINKS, (
                    f"{name} (built by the main job for {target}) links the native library '{links[name]}': say in "
                    f"NEEDS_OF_LINKS of {__file__} which Debian packages it needs, and install them in tests/setup-env.sh --main-job")
                for deb in NEEDS_OF_LINKS[links[name]]:
                    needed.setdefault(deb, f"{name} (links {links[name]})")
            for deb in NEEDS_OF_CRATE.get(name, []):
                needed.setdefault(deb, f"{name}: a build script compiles C")
        if target != host:
            for deb in NEEDS_OF_TARGET.get(target, [f"<a linker for {target}>"]):
                needed.setdefault(deb, f"the linker of target {target}")
    installs = setup_installs("--main-job")
    missing = {deb: why for deb, why in needed.items() if deb not in installs}
    assert not missing, (f"the main job builds {sorted(builds)}; its setup (tests/setup-env.sh --main-job) does not "
                         f"install {missing}; it installs {sorted(installs)}")


def test_the_main_job_installs_zig_for_the_targets_it_links_with_zig(metadata):
    builds = main_job_builds(metadata)
    zig_targets = {t for ts in builds.values() for t in ts if "apple-darwin" in t or re.search(r"\.\d+\.\d+$", t)}
    assert zig_targets, "no FMU crate names a macOS or glibc-versioned target any more"
    pins = (ROOT / "examples" / "requirements.txt").read_text()
    assert re.search(r"^ziglang==", pins, re.M) and re.search(r"^cargo-zigbuild==", pins, re.M), pins
    setup = (ROOT / "tests" / "setup-env.sh").read_text()
    for t in {re.sub(r"\.\d+\.\d+$", "", t) for t in zig_targets} - {host_triple()}:
        assert t in setup, f"tests/setup-env.sh does not `rustup target add {t}`"


def test_the_tests_setup_installs_everything_the_main_jobs_does():
    assert setup_installs("--main-job") <= setup_installs()


def test_the_main_job_needs_none_of_the_test_only_python_packages():
    """examples/ imports nothing that only tests/python/requirements.txt installs (libcosimpy is
    imported lazily, by the tests' SSP checks only)."""
    main = (ROOT / "examples" / "requirements.txt").read_text()
    tests = (ROOT / "tests" / "python" / "requirements.txt").read_text()
    assert "-r ../../examples/requirements.txt" in tests
    pins = lambda text: {re.split(r"[=<>\[]", l)[0].strip().lower() for l in text.splitlines()
                         if l.strip() and not l.startswith(("#", "-r"))}
    test_only = pins(tests) - pins(main)
    import_names = {"fmu_manipulation_toolbox": "fmu_manipulation_toolbox", "control": "control",
                    "pytest": "pytest", "ecospy": "ecospy", "libcosimpy": "libcosimpy"}
    for py in ROOT.glob("examples/**/*.py"):
        for line in py.read_text().splitlines():
            m = re.match(r"\s*(?:import|from) (\w+)", line)
            if m and not line.startswith((" ", "\t")):
                assert import_names.get(m.group(1)) not in test_only, f"{py}: {line.strip()} is a test-only package"

