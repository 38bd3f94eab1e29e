//! The cost of a clock tick: the SampledController (FMI 3.0; its sample rate a periodic clock)
//! through its C API as a clock-aware co-simulation importer drives it at each tick
//! (fmi3EnterEventMode, fmi3SetClock, the six clocked inputs, the four clocked outputs,
//! fmi3UpdateDiscreteStates, fmi3EnterStepMode, fmi3DoStep over Ts), against the 2.0 Controller
//! with `sampled = true` at a communication point (fmi2SetReal of the six inputs, fmi2GetReal of
//! the four outputs, fmi2DoStep over Ts): the same law, the same work. Count instructions with
//! callgrind (bench/callgrind.sh does, 1000 and 2000 ticks):
//!
//!     valgrind --tool=callgrind target/release/clock-tick --variant clocked --ticks 2000

use clap::Parser;
use fmi::fmi2::instance::{CoSimulation, Common};
use std::ffi::{CString, c_char, c_void};
use std::hint::black_box;
use std::io::Read;

#[derive(Parser)]
struct Args {
    /// `clocked` (the 3.0 SampledController) or `sampled-2.0` (the 2.0 Controller, sampled = true).
    #[arg(long, default_value = "clocked")]
    variant: String,
    #[arg(long, default_value_t = 1000)]
    ticks: usize,
}

const TS: f64 = 0.01;
const INPUTS: [&str; 6] = ["alpha1", "omega1", "alpha2", "omega2", "alpha1_ref", "alpha2_ref"];
const OUTPUTS: [&str; 4] = ["M1", "M2", "U1", "U2"];

fn measurement(t: f64) -> [f64; 6] {
    [
        0.05 * (3.0 * t).cos(),
        -0.15 * (3.0 * t).sin(),
        -0.02 * (5.0 * t).sin(),
        -0.1 * (5.0 * t).cos(),
        0.0,
        0.0,
    ]
}

fn main() {
    let args = Args::parse();
    let result = match args.variant.as_str() {
        "clocked" => clocked(args.ticks),
        "sampled-2.0" => sampled(args.ticks),
        other => Err(format!("unknown variant '{other}' (clocked, sampled-2.0)")),
    };
    // The two variants give the same torques (tests/python/test_sampled_controller.py): the same
    // sum.
    let printed = result.map(|sum| println!("{} ticks, sum of M1: {sum:.17e}", args.ticks));
    rustfmu_bench::exit_on_error("clock-tick", printed);
}

fn sampled(ticks: usize) -> Result<f64, String> {
    let fmu = rustfmu_bench::Fmu::load("Controller")?;
    let mut c = fmu.instantiate("sampled")?;
    let e = |what: &'static str| move |err| format!("{what}: {err:?}");
    let (sampled, ts) = (
        fmu.typed_vr("sampled", rustfmu::description::VarType::Boolean)?,
        fmu.vr("Ts")?,
    );
    c.set_boolean(&[sampled], &[1]).map_err(e("fmi2SetBoolean"))?;
    c.set_real(&[ts], &[TS]).map_err(e("fmi2SetReal"))?;
    let (inputs, outputs) = (fmu.vrs(&INPUTS)?, fmu.vrs(&OUTPUTS)?);
    c.set_real(&inputs, &measurement(0.0)).map_err(e("fmi2SetReal"))?;
    c.setup_experiment(None, 0.0, None).map_err(e("fmi2SetupExperiment"))?;
    c.enter_initialization_mode()
        .map_err(e("fmi2EnterInitializationMode"))?;
    c.exit_initialization_mode().map_err(e("fmi2ExitInitializationMode"))?;
    let (mut out, mut sum) = ([0.0; 4], 0.0);
    for k in 0..ticks {
        let t = k as f64 * TS;
        c.set_real(&inputs, black_box(&measurement(t)))
            .map_err(e("fmi2SetReal"))?;
        c.get_real(&outputs, &mut out).map_err(e("fmi2GetReal"))?;
        sum += black_box(out)[0];
        c.do_step(t, TS, true).map_err(e("fmi2DoStep"))?;
    }
    Ok(sum)
}

type Instance = *mut c_void;

fn clocked(ticks: usize) -> Result<f64, String> {
    // The binary, out of the packaged FMU, as an importer unpacks it.
    let path = rustfmu_bench::fmu_dir().join("fmi3").join("SampledController.fmu");
    let file = std::fs::File::open(&path)
        .map_err(|e| format!("{}: {e}; run `cargo run --release -p fmu-build` first", path.display()))?;
    let mut zip = zip::ZipArchive::new(file).map_err(|e| e.to_string())?;
    let mut bytes = vec![];
    zip.by_name("binaries/x86_64-linux/SampledController.so")
        .map_err(|e| e.to_string())?
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    let xml = {
        let mut s = String::new();
        zip.by_name("modelDescription.xml")
            .map_err(|e| e.to_string())?
            .read_to_string(&mut s)
            .map_err(|e| e.to_string())?;
        s
    };
    let d = md_reader::fmi3::ModelDescription::parse(&xml)?;
    let vr = |name: &str| {
        d.variables
            .iter()
            .find(|v| v.name == name)
            .map(|v| v.vr)
            .ok_or_else(|| format!("no variable '{name}'"))
    };
    let inputs: Vec<u32> = INPUTS.iter().map(|n| vr(n)).collect::<Result<_, _>>()?;
    let outputs: Vec<u32> = OUTPUTS.iter().map(|n| vr(n)).collect::<Result<_, _>>()?;
    let clock = vr("sample")?;
    let so = std::env::temp_dir().join(format!("clock-tick-{}.so", std::process::id()));
    std::fs::write(&so, &bytes).map_err(|e| e.to_string())?;
    // SAFETY: our own packaged FMU binary; the signatures are fmi3FunctionTypes.h's.
    let sum = unsafe {
        let lib = libloading::Library::new(&so).map_err(|e| e.to_string())?;
        type Inst = unsafe extern "C" fn(
            *const c_char,
            *const c_char,
            *const c_char,
            bool,
            bool,
            bool,
            bool,
            *const u32,
            usize,
            *mut c_void,
            *const c_void,
            *const c_void,
        ) -> Instance;
        type Unary = unsafe extern "C" fn(Instance) -> i32;
        let sym =
            |name: &[u8]| -> Result<Unary, String> { lib.get::<Unary>(name).map(|s| *s).map_err(|e| e.to_string()) };
        let instantiate = *lib
            .get::<Inst>(b"fmi3InstantiateCoSimulation")
            .map_err(|e| e.to_string())?;
        let enter_init = *lib
            .get::<unsafe extern "C" fn(Instance, bool, f64, f64, bool, f64) -> i32>(b"fmi3EnterInitializationMode")
            .map_err(|e| e.to_string())?;
        let set_f64 = *lib
            .get::<unsafe extern "C" fn(Instance, *const u32, usize, *const f64, usize) -> i32>(b"fmi3SetFloat64")
            .map_err(|e| e.to_string())?;
        let get_f64 = *lib
            .get::<unsafe extern "C" fn(Instance, *const u32, usize, *mut f64, usize) -> i32>(b"fmi3GetFloat64")
            .map_err(|e| e.to_string())?;
        let set_clock = *lib
            .get::<unsafe extern "C" fn(Instance, *const u32, usize, *const bool) -> i32>(b"fmi3SetClock")
            .map_err(|e| e.to_string())?;
        let update = *lib
            .get::<unsafe extern "C" fn(Instance, *mut bool, *mut bool, *mut bool, *mut bool, *mut bool, *mut f64) -> i32>(
                b"fmi3UpdateDiscreteStates",
            )
            .map_err(|e| e.to_string())?;
        let do_step = *lib
            .get::<unsafe extern "C" fn(Instance, f64, f64, bool, *mut bool, *mut bool, *mut bool, *mut f64) -> i32>(
                b"fmi3DoStep",
            )
            .map_err(|e| e.to_string())?;
        let (exit_init, enter_event, enter_step, free) = (
            sym(b"fmi3ExitInitializationMode")?,
            sym(b"fmi3EnterEventMode")?,
            sym(b"fmi3EnterStepMode")?,
            *lib.get::<unsafe extern "C" fn(Instance)>(b"fmi3FreeInstance")
                .map_err(|e| e.to_string())?,
        );
        let (name, token) = (CString::new("tick").unwrap(), CString::new(d.token.clone()).unwrap());
        let c = instantiate(
            name.as_ptr(),
            token.as_ptr(),
            std::ptr::null(),
            false,
            false,
            true,
            false,
            std::ptr::null(),
            0,
            std::ptr::null_mut(),
            std::ptr::null(),
            std::ptr::null(),
        );
        if c.is_null() {
            return Err("fmi3InstantiateCoSimulation returned NULL".into());
        }
        let ok = |s: i32, what: &str| {
            if s == 0 {
                Ok(())
            } else {
                Err(format!("{what}: status {s}"))
            }
        };
        ok(
            enter_init(c, false, 0.0, 0.0, false, 0.0),
            "fmi3EnterInitializationMode",
        )?;
        let m0 = measurement(0.0);
        ok(set_f64(c, inputs.as_ptr(), 6, m0.as_ptr(), 6), "fmi3SetFloat64")?;
        ok(exit_init(c), "fmi3ExitInitializationMode")?;
        let (mut out, mut sum) = ([0.0; 4], 0.0);
        let (mut a, mut b, mut cc, mut dd, mut ee, mut next) = (false, false, false, false, false, 0.0);
        let (mut ev, mut term, mut early, mut last) = (false, false, false, 0.0);
        for k in 0..ticks {
            let t = k as f64 * TS;
            if k > 0 {
                ok(enter_event(c), "fmi3EnterEventMode")?;
            }
            ok(set_clock(c, &clock, 1, &true), "fmi3SetClock")?;
            let m = black_box(measurement(t));
            ok(set_f64(c, inputs.as_ptr(), 6, m.as_ptr(), 6), "fmi3SetFloat64")?;
            ok(get_f64(c, outputs.as_ptr(), 4, out.as_mut_ptr(), 4), "fmi3GetFloat64")?;
            sum += black_box(out)[0];
            ok(
                update(c, &mut a, &mut b, &mut cc, &mut dd, &mut ee, &mut next),
                "fmi3UpdateDiscreteStates",
            )?;
            ok(enter_step(c), "fmi3EnterStepMode")?;
            ok(
                do_step(c, t, TS, true, &mut ev, &mut term, &mut early, &mut last),
                "fmi3DoStep",
            )?;
        }
        free(c);
        sum
    };
    let _ = std::fs::remove_file(&so);
    Ok(sum)
}
