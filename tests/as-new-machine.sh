#!/usr/bin/env bash
# Runs a command in a checkout as on a new user's machine, without touching this machine: in a
# private mount namespace, an overlay over / hides (as whiteouts) every file of the Debian packages
# only the tests need and of what apt would remove with them (`apt-get -s remove --auto-remove` of
# `setup-env.sh --list` minus `setup-env.sh --main-job --list`: wine, qemu, valgrind, libclang,
# the aarch64 gcc, libtbb and their dependencies), the foreign Rust targets (and rustup's record
# of them, so that `rustup target add` installs them again), the crates cargo downloaded, and the
# zig, cargo-zigbuild, uv and pip caches; the command runs chrooted there, the checkout and
# ../shared bound in, so what it writes in the checkout stays; anything else it writes (rustup
# targets, crates, caches) goes to a tmpfs and is gone when it ends.
#
#   sudo bash tests/as-new-machine.sh CHECKOUT COMMAND...
#   e.g. git clone -q . /tmp/fresh/main && ln -s "$PWD/../shared" /tmp/fresh/shared &&
#        bash tests/as-new-machine.sh /tmp/fresh/main bash examples/run.sh
#
# Needs root (unshare -m, overlay and tmpfs mounts) and an apt-based system. Used for the README's
# "main job on a fresh machine without the tests' packages" (issue 53); CI does not run it.
set -euo pipefail
if [ "${1:-}" != --inside ]; then
  [ $# -ge 2 ] || { echo "usage: bash tests/as-new-machine.sh CHECKOUT COMMAND..." >&2; exit 2; }
  checkout=$(cd "$1" && pwd)
  shift
  here=$(cd "$(dirname "$0")" && pwd)
  # The packages only the tests need, and what apt would remove with them.
  mapfile -t main < <(bash "$here/setup-env.sh" --main-job --list)
  mapfile -t all < <(bash "$here/setup-env.sh" --list)
  only_tests=()
  for p in "${all[@]}"; do [[ " ${main[*]} " == *" $p "* ]] || only_tests+=("$p"); done
  # binutils stays: gcc needs it (apt would remove gcc with it).
  only_tests=("${only_tests[@]/binutils/}")
  list=$(mktemp)
  # shellcheck disable=SC2068
  apt-get -s remove --auto-remove ${only_tests[@]} 2>/dev/null | awk '/^Remv/ {print $2}' |
    while read -r p; do dpkg -L "$p" 2>/dev/null || true; done | sort -u |
    while read -r f; do
      if { [ -f "$f" ] || [ -L "$f" ]; } && [ ! -d "$f" ]; then
        echo "$(readlink -f "$(dirname "$f")")/$(basename "$f")"
      fi
    done >"$list"
  echo "as-new-machine: hiding $(wc -l <"$list") files of the tests' packages, the foreign Rust targets and the download caches" >&2
  shared=$(cd "$checkout/.." && pwd)/shared
  exec unshare -m --propagation private bash "$0" --inside "$list" "$checkout" "$(readlink -f "$shared")" "$@"
fi
shift
list=$1 checkout=$2 shared=$3
shift 3
top=$(mktemp -d /tmp/as-new-machine.XXXX)
mount -t tmpfs tmpfs "$top"
mkdir -p "$top/up" "$top/work" "$top/root"
python3 - "$list" "$top/up" <<'PY'
import os, subprocess, sys
listing, up = sys.argv[1], sys.argv[2]


def whiteout(path):
    p = up + path
    os.makedirs(os.path.dirname(p), exist_ok=True)
    if not os.path.lexists(p):
        os.mknod(p, 0o600 | 0o020000, os.makedev(0, 0))  # an overlay whiteout: 0/0 char device


for f in open(listing).read().split("\n"):
    if f:
        whiteout(f)
home = os.path.expanduser("~")
sysroot = subprocess.run(["rustc", "--print", "sysroot"], capture_output=True, text=True).stdout.strip()
rl = os.path.realpath(sysroot) + "/lib/rustlib"
foreign = ["x86_64-pc-windows-gnu", "aarch64-unknown-linux-gnu", "x86_64-apple-darwin", "aarch64-apple-darwin"]
for t in foreign:
    whiteout(f"{rl}/{t}")
    whiteout(f"{rl}/manifest-rust-std-{t}")
for d in ["/.cargo/registry", "/.cache/zig", "/.cache/cargo-zigbuild", "/.cache/uv", "/.cache/pip"]:
    whiteout(home + d)
# rustup's record of the installed components, without the foreign targets' rust-std.
comps = [c for c in open(rl + "/components").read().split("\n") if c and c not in {"rust-std-" + t for t in foreign}]
open(up + rl + "/components", "w").write("\n".join(comps) + "\n")
blocks = open(rl + "/multirust-config.toml").read().split("[[components]]")
keep = [b for b in blocks[1:] if not ('pkg = "rust-std"' in b and any(f'target = "{t}"' in b for t in foreign))]
open(up + rl + "/multirust-config.toml", "w").write(blocks[0] + "".join("[[components]]" + b for b in keep))
PY
mount -t overlay overlay -o "lowerdir=/,upperdir=$top/up,workdir=$top/work" "$top/root"
for d in proc sys dev dev/pts; do mount --rbind "/$d" "$top/root/$d"; done
mkdir -p "$top/root$checkout" "$top/root$shared"
mount --bind "$checkout" "$top/root$checkout"
mount --bind "$shared" "$top/root$shared"
exec chroot "$top/root" /usr/bin/env -C "$checkout" "$@"
