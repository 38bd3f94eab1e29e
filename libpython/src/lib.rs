//! The Python library an FMU binary expects its importer to have loaded (PythonFMU's and
//! PythonFMU3's: their binaries call the Python C API but name no `libpython` they need, so that
//! one binary serves every Python 3; loaded alone they fail with `undefined symbol:
//! _Py_NoneStruct`). Both importers of the workspace load FMU binaries through it: the runner
//! (`rustfmu-runner`, whose `--preload-lib` is [`preload`]) and the conformance checker
//! (`cargo fmu check`, whose report names what was loaded).
//!
//! Before an FMU binary is loaded ([`before`]), the libraries given with [`preload`] (or [`ENV`])
//! are loaded, each once, with `RTLD_GLOBAL`. Where none is given and the binary (ELF) needs
//! symbols of the Python C API that nothing loaded provides, or its loading fails on an
//! undefined `Py`/`_Py` symbol ([`after_failure`]), the shared `libpython` of the Python the
//! importer runs beside is found ([`PYTHON_ENV`], else `python3` on `PATH`: its sysconfig `LIBDIR`
//! with `INSTSONAME` or `LDLIBRARY`; else a `libpython3.N.so.1.0` the dynamic linker finds),
//! loaded with `RTLD_GLOBAL`, and the importer is handed a sentence saying which and why (it
//! prints it; [`loaded`] keeps them all). If there is none, the error names the missing symbol,
//! the library it comes from and how to give one. Child processes inherit the libraries given
//! through [`ENV`] ([`for_child`]).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The environment variable of the libraries to load before any FMU binary (paths separated
/// by `:`); [`preload`] adds to it, and child processes inherit it ([`for_child`]).
pub const ENV: &str = "RUSTFMU_RUNNER_PRELOAD";

/// The environment variable naming the Python interpreter whose `libpython` is loaded where an
/// FMU binary needs one (default: `python3` on `PATH`, then a `libpython3.N.so.1.0` on the
/// dynamic linker's search path; set, its library only).
pub const PYTHON_ENV: &str = "RUSTFMU_RUNNER_PYTHON";

/// The libraries loaded so far (kept loaded for the life of the process: the FMUs' symbols
/// point into them).
#[cfg(unix)]
static LOADED: Mutex<Vec<(PathBuf, libloading::os::unix::Library)>> = Mutex::new(Vec::new());

/// The libraries given to [`preload`], passed on to child processes.
static GIVEN: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// What [`before`] and [`after_failure`] loaded in this process, each as the sentence they
/// returned.
static NOTES: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// Every sentence [`before`] and [`after_failure`] returned in this process: which libpython was
/// loaded, before which FMU binary, why, and how it was found.
pub fn loaded() -> Vec<String> {
    lock(&NOTES).clone()
}

/// Loads the libraries `paths` now, with `RTLD_GLOBAL`, and before every FMU binary of this
/// process and its child processes ([`for_child`]); `option` names how the user gave them (the
/// runner's `--preload-lib`), for the error.
pub fn preload(paths: &[PathBuf], option: &str) -> Result<(), String> {
    for path in paths {
        load_global(path).map_err(|e| format!("{option} {}: {e}", path.display()))?;
        lock(&GIVEN).push(path.clone());
    }
    Ok(())
}

/// The value of [`ENV`] for a child process: the libraries of [`ENV`] and `--preload-lib`
/// (None: there are none).
pub fn for_child() -> Option<std::ffi::OsString> {
    let mut all: Vec<PathBuf> = from_env();
    all.extend(lock(&GIVEN).iter().cloned());
    if all.is_empty() {
        return None;
    }
    std::env::join_paths(all).ok()
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

fn from_env() -> Vec<PathBuf> {
    std::env::var_os(ENV)
        .map(|v| {
            std::env::split_paths(&v)
                .filter(|p| !p.as_os_str().is_empty())
                .collect()
        })
        .unwrap_or_default()
}

/// Loads `path` with `RTLD_NOW | RTLD_GLOBAL` (once per process); true: loaded by this call.
#[cfg(unix)]
fn load_global(path: &Path) -> Result<bool, String> {
    use libloading::os::unix::{Library, RTLD_GLOBAL, RTLD_NOW};
    let mut loaded = lock(&LOADED);
    if loaded.iter().any(|(p, _)| p == path) {
        return Ok(false);
    }
    // SAFETY: loading runs the library's initializers: a library the user named, or the
    // shared libpython of a Python installed on this machine.
    let lib = unsafe { Library::open(Some(path), RTLD_NOW | RTLD_GLOBAL) }.map_err(|e| e.to_string())?;
    loaded.push((path.to_path_buf(), lib));
    Ok(true)
}

#[cfg(not(unix))]
fn load_global(path: &Path) -> Result<bool, String> {
    Err(format!(
        "{}: preloading a library runs on Linux and macOS only",
        path.display()
    ))
}

/// Before the FMU binary `path` is loaded: the libraries of [`ENV`], and libpython if its ELF
/// needs the Python C API and nothing loaded provides it. `option`: the importer's own way to
/// give a library (the runner's `--preload-lib`; None: [`ENV`] only), named in what it says.
/// Ok(Some(sentence)): libpython loaded now, the sentence saying which, why, how it was found
/// and how to choose another, for the importer to print.
pub fn before(path: &Path, option: Option<&str>) -> Result<Option<String>, String> {
    for p in from_env() {
        load_global(&p).map_err(|e| format!("{ENV}={}: {e}", p.display()))?;
    }
    if let Some(symbols) = python_symbols_needed(path)
        && !provided(&symbols)
    {
        let why = format!(
            "it calls the Python C API ({}{}) and names no libpython it needs",
            symbols.iter().take(3).cloned().collect::<Vec<_>>().join(", "),
            if symbols.len() > 3 {
                format!(" and {} more", symbols.len() - 3)
            } else {
                String::new()
            }
        );
        return load_libpython(path, &symbols[0], &why, option);
    }
    Ok(None)
}

/// After the FMU binary `path` failed to load with `error`: Ok(None), not an undefined Python
/// symbol (the error stands); Ok(Some(sentence)), libpython loaded (try again; the sentence is
/// empty when an earlier call had loaded it); Err, the error saying what is missing.
pub fn after_failure(path: &Path, error: &str, option: Option<&str>) -> Result<Option<String>, String> {
    let Some(symbol) = undefined_python_symbol(error) else {
        return Ok(None);
    };
    let why = format!("loading it failed: undefined symbol {symbol}");
    load_libpython(path, symbol, &why, option).map(|s| Some(s.unwrap_or_default()))
}

/// The symbol of `undefined symbol: NAME` in a dynamic linker's message, if of the Python C API.
fn undefined_python_symbol(error: &str) -> Option<&str> {
    let (_, rest) = error.split_once("undefined symbol: ")?;
    let name = rest.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).next()?;
    is_python_symbol(name).then_some(name)
}

fn is_python_symbol(name: &str) -> bool {
    name.starts_with("Py") || name.starts_with("_Py")
}

/// The undefined dynamic symbols of the Python C API of the ELF file `path`, if it has some and
/// names no libpython in its `DT_NEEDED` (None: not ELF, none, or it names its libpython).
fn python_symbols_needed(path: &Path) -> Option<Vec<String>> {
    use object::{Object, ObjectSymbol};
    let data = std::fs::read(path).ok()?;
    let file = object::File::parse(&*data).ok()?;
    if file.format() != object::BinaryFormat::Elf {
        return None;
    }
    if needed(&data)?.iter().any(|n| n.starts_with("libpython")) {
        return None;
    }
    let mut symbols: Vec<String> = file
        .dynamic_symbols()
        .filter(|s| s.is_undefined())
        .filter_map(|s| s.name().ok().map(str::to_owned))
        .filter(|n| is_python_symbol(n))
        .collect();
    // The data symbol the dynamic linker stops at first, as it names it.
    symbols.sort_by_key(|n| (n != "_Py_NoneStruct", n.clone()));
    (!symbols.is_empty()).then_some(symbols)
}

/// The `DT_NEEDED` names of the 64-bit little-endian ELF `data` (None: another kind of ELF).
fn needed(data: &[u8]) -> Option<Vec<String>> {
    use object::Endianness;
    use object::read::elf::{Dyn, ElfFile64, FileHeader};
    let elf = ElfFile64::<Endianness>::parse(data).ok()?;
    let endian = elf.endian();
    let sections = elf.elf_header().sections(endian, data).ok()?;
    let (dynamic, index) = sections.dynamic(endian, data).ok()??;
    let strings = sections.strings(endian, data, index).ok()?;
    Some(
        dynamic
            .iter()
            .filter(|d| d.tag32(endian) == Some(object::elf::DT_NEEDED))
            .filter_map(|d| d.string(endian, strings).ok())
            .map(|s| String::from_utf8_lossy(s).into_owned())
            .collect(),
    )
}

/// Whether every symbol of `symbols` is already in the process's global scope (a Python process
/// running the runner's Python module, or a libpython loaded before).
#[cfg(unix)]
fn provided(symbols: &[String]) -> bool {
    let this = libloading::os::unix::Library::this();
    symbols.iter().all(|s| {
        // SAFETY: the symbol is only looked up (its address compared with NULL), never called.
        unsafe { this.get::<*const u8>(format!("{s}\0").as_bytes()) }.is_ok()
    })
}

#[cfg(not(unix))]
fn provided(_symbols: &[String]) -> bool {
    true
}

/// Finds and loads the shared libpython for the FMU binary `path`, which needs `symbol`
/// (`why`): the sentence saying which (None: loaded before), kept in [`NOTES`]; or the error
/// naming the symbol and how to give a library (`option`, [`ENV`], [`PYTHON_ENV`]).
fn load_libpython(path: &Path, symbol: &str, why: &str, option: Option<&str>) -> Result<Option<String>, String> {
    let mut tried = Vec::new();
    for (candidate, found_by) in candidates(&mut tried) {
        match load_global(&candidate) {
            Ok(true) => {
                let sentence = format!(
                    "loaded {} (RTLD_GLOBAL) before {}: {why}; found by {found_by} ({} chooses another)",
                    candidate.display(),
                    path.display(),
                    match option {
                        Some(o) => format!("{o} PATH or {ENV}"),
                        None => format!("{ENV}=PATH"),
                    }
                );
                lock(&NOTES).push(sentence.clone());
                return Ok(Some(sentence));
            }
            Ok(false) => return Ok(None),
            // A bare name not on the search path: said once, by `candidates`.
            Err(_) if candidate.parent() == Some(Path::new("")) => {}
            Err(e) => tried.push(format!("{}: {e}", candidate.display())),
        }
    }
    let give = match option {
        Some(o) => format!(
            "{o} /path/to/libpython3.X.so.1.0 (or {ENV}=PATH, or {PYTHON_ENV}=a python3 built with --enable-shared)"
        ),
        None => format!("{ENV}=/path/to/libpython3.X.so.1.0 (or {PYTHON_ENV}=a python3 built with --enable-shared)"),
    };
    Err(format!(
        "it needs the symbol {symbol} of the Python C library (libpython3.X.so, which PythonFMU and PythonFMU3 binaries expect the importer to load) and no libpython was found ({}); give it with {give}",
        tried.join("; ")
    ))
}

/// The libpython files to try, each with how it was found; `tried` gets what did not give one.
fn candidates(tried: &mut Vec<String>) -> Vec<(PathBuf, String)> {
    let chosen = std::env::var_os(PYTHON_ENV);
    let python = chosen.clone().unwrap_or_else(|| "python3".into());
    let shown = Path::new(&python).display().to_string();
    let mut out = Vec::new();
    let query = "import sys, sysconfig as s; print(sys.executable); \
                 print(*(s.get_config_var(k) or '' for k in ('Py_ENABLE_SHARED', 'LIBDIR', 'INSTSONAME', 'LDLIBRARY')), sep='\\n')";
    match std::process::Command::new(&python).args(["-c", query]).output() {
        Ok(o) if o.status.success() => {
            let text = String::from_utf8_lossy(&o.stdout);
            let lines: Vec<&str> = text.lines().collect();
            match lines.as_slice() {
                [exe, shared, libdir, names @ ..] if *shared == "1" => {
                    for name in names.iter().filter(|n| !n.is_empty() && !n.ends_with(".a")) {
                        let p = Path::new(libdir).join(name);
                        if p.exists() && !out.iter().any(|(q, _)| q == &p) {
                            out.push((p, format!("{shown} ({exe}): sysconfig LIBDIR/{name}")));
                        }
                    }
                    if out.is_empty() {
                        tried.push(format!("{shown} ({exe}): no {} in {libdir}", names.join(" or ")));
                    }
                }
                [exe, ..] => tried.push(format!(
                    "{shown} ({exe}) has no shared libpython (built without --enable-shared)"
                )),
                [] => tried.push(format!("{shown}: no answer")),
            }
        }
        Ok(o) => tried.push(match String::from_utf8_lossy(&o.stderr).trim() {
            "" => format!("{shown}: {}", o.status),
            e => format!("{shown}: {e}"),
        }),
        Err(e) => tried.push(format!("{shown}: {e}")),
    }
    // An interpreter the user chose: its library or none (another Python's would surprise).
    if chosen.is_some() {
        return out;
    }
    for minor in (8..=14).rev() {
        let name = format!("libpython3.{minor}.so.1.0");
        out.push((
            PathBuf::from(&name),
            format!("the dynamic linker's search path ({name})"),
        ));
    }
    tried.push("no libpython3.8 to 3.14 on the dynamic linker's search path".into());
    out
}
