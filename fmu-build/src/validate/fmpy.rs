//! fmpy's validator, run with a Python the user names (`--python`).

use std::path::Path;

/// Whether `python` (`--python`) can run fmpy's validator: an interpreter without fmpy is the
/// environment's problem, said as such before anything is built or judged, not an invalid FMU.
pub fn fmpy_ready(python: &Path) -> Result<(), String> {
    let p = python.display();
    let out = std::process::Command::new(python)
        .arg("-c")
        .arg("import fmpy.validation")
        .output()
        .map_err(|e| format!("--python {p}: cannot run this interpreter: {e}"))?;
    if out.status.success() {
        return Ok(());
    }
    let stderr = String::from_utf8_lossy(&out.stderr);
    let why = stderr
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("no message")
        .trim();
    Err(format!(
        "--python {p}: this interpreter cannot import fmpy ({why}), which runs fmpy's validator on the FMUs; \
         install it there (`{p} -m pip install fmpy`), give an interpreter that has it, or leave out --python"
    ))
}

/// fmpy's validator, run with the given Python.
pub fn fmpy_validate(python: &Path, fmu: &Path) -> Vec<String> {
    let script = "import sys\nfrom fmpy.validation import validate_fmu\np = validate_fmu(sys.argv[1])\nprint('\\n'.join(p))\nsys.exit(1 if p else 0)";
    match std::process::Command::new(python)
        .arg("-c")
        .arg(script)
        .arg(fmu)
        .output()
    {
        Ok(out) if out.status.success() => vec![],
        Ok(out) => vec![format!(
            "fmpy's validate_fmu: {}{}",
            String::from_utf8_lossy(&out.stdout).trim(),
            String::from_utf8_lossy(&out.stderr).trim()
        )],
        Err(e) => vec![format!("cannot run {}: {e}", python.display())],
    }
}
