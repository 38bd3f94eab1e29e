"""Runs a cargo command and shows its progress instead of its messages: on a terminal one line
redrawn in place (units done of all, what is compiling), in a log (CI, a pipe) a line at each
quarter; cargo's messages all go to LOG, and all of them are shown if cargo fails (then its exit
status is this script's). Warnings are counted and pointed to.

    python3 tests/cargo-progress.py LOG cargo build --release -p ...

(The main job's and the tests' host builds; `cargo fmu build` shows its own progress.)
"""

import os
import re
import subprocess
import sys
import time

PROGRESS = re.compile(r"^\s*Building \[[^\]]*\]\s*(\d+)/(\d+)(?::\s*(.*))?$")
ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")


def main() -> int:
    if len(sys.argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    log_path, command = sys.argv[1], sys.argv[2:]
    terminal = sys.stderr.isatty()
    env = dict(os.environ, CARGO_TERM_PROGRESS_WHEN="always", CARGO_TERM_PROGRESS_WIDTH="100", CARGO_TERM_COLOR="never")
    os.makedirs(os.path.dirname(os.path.abspath(log_path)), exist_ok=True)
    started = time.monotonic()
    shown_quarter = 0
    warnings = 0
    with open(log_path, "w") as log:
        log.write("$ " + " ".join(command) + "\n")
        child = subprocess.Popen(command, stderr=subprocess.PIPE, env=env)
        segment = b""
        assert child.stderr is not None
        while True:
            chunk = child.stderr.read1(8192)
            if not chunk:
                break
            data = segment + chunk
            parts = re.split(rb"[\r\n]", data)
            segment = parts.pop()
            for raw in parts:
                text = ANSI.sub("", raw.decode("utf-8", "replace"))
                m = PROGRESS.match(text)
                if m:
                    done, of, names = int(m.group(1)), int(m.group(2)), (m.group(3) or "")
                    if terminal:
                        line = f"cargo: {done}/{of} units  {names[:50]}  ({time.monotonic() - started:.0f} s)"
                        sys.stderr.write("\r" + line.ljust(90)[:90])
                        sys.stderr.flush()
                    elif of and done * 4 // of > shown_quarter:
                        shown_quarter = done * 4 // of
                        print(f"cargo: {done}/{of} units ({time.monotonic() - started:.0f} s)", file=sys.stderr, flush=True)
                    continue
                if not text.strip():
                    continue
                if text.startswith("warning") and " generated " not in text:
                    warnings += 1
                log.write(text + "\n")
        if segment.strip():
            log.write(ANSI.sub("", segment.decode("utf-8", "replace")) + "\n")
        status = child.wait()
    if terminal:
        sys.stderr.write("\r" + " " * 90 + "\r")
    seconds = time.monotonic() - started
    if status != 0:
        with open(log_path) as log:
            sys.stderr.write(log.read())
        print(f"cargo: failed ({status}) after {seconds:.0f} s; its messages above and in {log_path}", file=sys.stderr)
        return status
    note = f"; {warnings} warnings in {log_path}" if warnings else ""
    print(f"cargo: done in {seconds:.0f} s (its messages: {log_path}{note})", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
