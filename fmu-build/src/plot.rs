//! The default experiment as a picture for the FMU's `documentation/index.html`: `cargo fmu
//! build` runs the freshly built library through FMI 2.0 co-simulation from the default
//! experiment's start to its stop time (in a child process, like the smoke run: a model that
//! crashes takes no build down with it) and draws its Real outputs as an SVG line chart.
//!
//! The chart is written here rather than with `plotters`: it is a few polylines, two axes and a
//! legend (about 100 lines), where `plotters` would add its font and rendering crates to every
//! `cargo fmu` build for it.

use crate::depends_fmi2::Api;
use fmi_conformance::fmi2::fmi2True;
use rustfmu::description::{Causality, ModelDescription, VarType, Variable};
use std::path::Path;

/// Points per curve at most.
const POINTS: usize = 500;

/// One simulated output: its name, unit and values at `times`.
pub struct Curve {
    pub name: String,
    pub unit: String,
    pub values: Vec<f64>,
}

/// What the default experiment gave.
pub struct Run {
    pub times: Vec<f64>,
    pub curves: Vec<Curve>,
    /// Why it stopped before the stop time, if it did.
    pub stopped: Option<String>,
}

/// Simulates the default experiment of the rustfmu library at `so` (description `d`) through
/// FMI 2.0 co-simulation and records its Real outputs (at most [`POINTS`] times).
pub fn simulate(
    so: &Path,
    d: &ModelDescription,
    guid: &str,
    resource_uri: &str,
    starts: &[(String, f64)],
) -> Result<Run, String> {
    // The crate's documentation-start values: each names a variable the run may set before
    // initialization (an input, or a parameter or state with initial = exact).
    let mut set: Vec<(&Variable, f64)> = Vec::new();
    for (name, x) in starts {
        let v = d
            .variables
            .iter()
            .find(|v| v.name == *name)
            .ok_or_else(|| format!("documentation-start: the model has no variable '{name}'"))?;
        let settable = v.causality == Causality::Input
            || (v.effective_initial() == Some(rustfmu::description::Initial::Exact)
                && v.variability != rustfmu::description::Variability::Constant);
        if !settable
            || !matches!(
                v.var_type,
                VarType::Real | VarType::Integer | VarType::Boolean | VarType::Enumeration
            )
        {
            return Err(format!(
                "documentation-start: '{name}' cannot be set before initialization (an input, or a Real, Integer, \
                 Boolean or enumeration variable with initial = exact that is not a constant, can)"
            ));
        }
        set.push((v, *x));
    }
    let outputs: Vec<&Variable> = d
        .variables
        .iter()
        .filter(|v| v.causality == Causality::Output && matches!(v.var_type, VarType::Real | VarType::Integer))
        .collect();
    if outputs.is_empty() {
        return Err("the model has no Real or Integer output to plot".into());
    }
    let e = d.default_experiment.unwrap_or_default();
    let start = e.start_time.unwrap_or(0.0);
    let stop = e.stop_time.unwrap_or(start + 1.0);
    if !(start.is_finite() && stop.is_finite() && stop > start) {
        return Err(format!("the default experiment runs from {start} to {stop}"));
    }
    // The default step where given (a sampled model's behaviour depends on it), recorded every
    // `stride` steps; else the span in POINTS steps.
    let (h, stride) = match e.step_size {
        Some(h) if h > 0.0 && h.is_finite() => {
            let steps = ((stop - start) / h).ceil().max(1.0);
            (h, (steps / POINTS as f64).ceil().max(1.0) as usize)
        }
        _ => ((stop - start) / POINTS as f64, 1),
    };
    let api = Api::load(so, false, guid, resource_uri)?;
    let do_step = api.fmi.do_step;
    let of = |ty: VarType| -> Vec<u32> {
        outputs
            .iter()
            .filter(|v| v.var_type == ty)
            .map(|v| v.value_reference)
            .collect()
    };
    let (vrs, int_vrs) = (of(VarType::Real), of(VarType::Integer));
    // The curves in that order: the Real outputs, then the Integer ones (a counter, Stair's).
    let outputs: Vec<&Variable> = outputs
        .iter()
        .filter(|v| v.var_type == VarType::Real)
        .chain(outputs.iter().filter(|v| v.var_type == VarType::Integer))
        .copied()
        .collect();
    api.with_instance_at(start, Some(stop), |c, ok| {
        // SAFETY: `c` is live; every array passed has the length passed with it.
        unsafe {
            let setting = |v: &Variable, x: f64| format!("setting '{}' to {x} (documentation-start)", v.name);
            api.initialize(c, ok, set.iter().copied(), setting)?;
            let mut run = Run {
                times: vec![],
                curves: outputs
                    .iter()
                    .map(|v| Curve {
                        name: v.name.to_string(),
                        unit: v.unit.to_string(),
                        values: vec![],
                    })
                    .collect(),
                stopped: None,
            };
            let mut y = vec![0.0; vrs.len()];
            let mut k = vec![0i32; int_vrs.len()];
            let record = |run: &mut Run, t: f64, y: &[f64], k: &[i32]| {
                run.times.push(t);
                let values = y.iter().copied().chain(k.iter().map(|&n| f64::from(n)));
                for (curve, value) in run.curves.iter_mut().zip(values) {
                    curve.values.push(value);
                }
            };
            let get = |y: &mut [f64], k: &mut [i32]| -> Result<(), String> {
                ok(
                    (api.fmi.get_real)(c, vrs.as_ptr(), vrs.len(), y.as_mut_ptr()),
                    "fmi2GetReal",
                )?;
                ok(
                    (api.fmi.get_integer)(c, int_vrs.as_ptr(), int_vrs.len(), k.as_mut_ptr()),
                    "fmi2GetInteger",
                )
            };
            get(&mut y, &mut k)?;
            record(&mut run, start, &y, &k);
            let mut t = start;
            let mut n = 0usize;
            while t < stop - 1e-12 * (stop - start) {
                let step = h.min(stop - t);
                let status = do_step(c, t, step, fmi2True);
                if let Err(e) = ok(status, &format!("fmi2DoStep at t = {t} s")) {
                    run.stopped = Some(e);
                    break;
                }
                t += step;
                n += 1;
                if n.is_multiple_of(stride) || t >= stop - 1e-12 * (stop - start) {
                    get(&mut y, &mut k)?;
                    record(&mut run, t, &y, &k);
                }
            }
            Ok(run)
        }
    })
}

/// A number for an axis label: few digits, no trailing noise.
fn label(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let a = x.abs();
    if (1e-3..1e4).contains(&a) {
        let s = format!("{x:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{x:.3e}")
    }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The run as an SVG line chart: one polyline per output, shared axes, a legend with units.
/// Non-finite values break their line.
pub fn svg(run: &Run, title: &str) -> String {
    const W: f64 = 720.0;
    const H: f64 = 360.0;
    let (left, right, top, bottom) = (70.0, 180.0, 30.0, 40.0);
    let (pw, ph) = (W - left - right, H - top - bottom);
    let t0 = run.times.first().copied().unwrap_or(0.0);
    let t1 = run.times.last().copied().unwrap_or(1.0).max(t0 + f64::MIN_POSITIVE);
    let finite = run
        .curves
        .iter()
        .flat_map(|c| c.values.iter().copied())
        .filter(|v| v.is_finite());
    let (mut lo, mut hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        (lo, hi) = (-1.0, 1.0);
    }
    if hi - lo <= 1e-12 * hi.abs().max(lo.abs()).max(1e-300) {
        (lo, hi) = (lo - 0.5 * lo.abs().max(1.0), hi + 0.5 * hi.abs().max(1.0));
    }
    let x = |t: f64| left + (t - t0) / (t1 - t0) * pw;
    let y = |v: f64| top + (hi - v) / (hi - lo) * ph;
    const COLORS: [&str; 8] = [
        "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
    ];
    let mut out = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{W}\" height=\"{H}\" viewBox=\"0 0 {W} {H}\" \
         font-family=\"sans-serif\" font-size=\"12\">\n<title>{}</title>\n\
         <rect x=\"{left}\" y=\"{top}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"#888\"/>\n",
        escape(title)
    );
    // Axis labels: the ends and the middle of each axis.
    for (i, frac) in [0.0, 0.5, 1.0].iter().enumerate() {
        let t = t0 + frac * (t1 - t0);
        let v = lo + frac * (hi - lo);
        let anchor = ["start", "middle", "end"][i];
        out.push_str(&format!(
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"{anchor}\">{}</text>\n",
            x(t),
            top + ph + 16.0,
            label(t)
        ));
        out.push_str(&format!(
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>\n",
            left - 6.0,
            y(v) + 4.0,
            label(v)
        ));
    }
    out.push_str(&format!(
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">time (s)</text>\n",
        left + pw / 2.0,
        H - 6.0
    ));
    out.push_str(&format!("<text x=\"{left}\" y=\"18\">{}</text>\n", escape(title)));
    for (k, curve) in run.curves.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        // A polyline per finite stretch.
        let mut points = Vec::new();
        let flush = |points: &mut Vec<String>, out: &mut String| {
            if !points.is_empty() {
                out.push_str(&format!(
                    "<polyline fill=\"none\" stroke=\"{color}\" stroke-width=\"1.5\" points=\"{}\"/>\n",
                    points.join(" ")
                ));
                points.clear();
            }
        };
        for (&t, &v) in run.times.iter().zip(&curve.values) {
            if v.is_finite() {
                points.push(format!("{:.1},{:.1}", x(t), y(v)));
            } else {
                flush(&mut points, &mut out);
            }
        }
        flush(&mut points, &mut out);
        let ly = top + 14.0 + 16.0 * k as f64;
        let unit = if curve.unit.is_empty() {
            String::new()
        } else {
            format!(" ({})", curve.unit)
        };
        out.push_str(&format!(
            "<line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"{color}\" stroke-width=\"2\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\">{}</text>\n",
            W - right + 12.0,
            ly - 4.0,
            W - right + 30.0,
            ly - 4.0,
            W - right + 36.0,
            ly,
            escape(&format!("{}{unit}", curve.name))
        ));
    }
    if let Some(why) = &run.stopped {
        out.push_str(&format!(
            "<text x=\"{left}\" y=\"{:.1}\" fill=\"#d62728\">stopped: {}</text>\n",
            top + 14.0,
            escape(why)
        ));
    }
    out.push_str("</svg>\n");
    out
}

/// What separates the SVG from the reference results in [`default_experiment_svg`]'s text.
const RESULTS_MARKER: &str = "\n<!-- cargo-fmu: the run as FMI-LS-REF reference results -->\n";

/// The default experiment of the library at `so` as an SVG (the smoke run's child does this;
/// `Err` says why there is no picture), followed, when the run is the default experiment as an
/// importer runs it (no documentation-start values) and reached its stop time, by a marker line
/// and the run as FMI-LS-REF reference results (the CSV of
/// [`fmi_conformance::reference_results::csv`]: every step recorded, or every `stride`-th).
pub fn default_experiment_svg(so: &Path, resource_uri: &str, starts: &[(String, f64)]) -> Result<String, String> {
    let binary = std::fs::read(so).map_err(|e| format!("{}: {e}", so.display()))?;
    let me = crate::library::read_library(&binary, rustfmu::description::FmiVersion::V2).map_err(|_| {
        "the page's run goes through FMI 2.0 co-simulation, and the library implements FMI 3.0 only".to_string()
    })?;
    if !me.interfaces.co_simulation {
        return Err("the library has no co-simulation interface to run it through".into());
    }
    let run = simulate(so, &me.description, &me.guid, resource_uri, starts)?;
    let e = me.description.default_experiment.unwrap_or_default();
    let from = if starts.is_empty() {
        String::new()
    } else {
        let list: Vec<String> = starts.iter().map(|(n, x)| format!("{n} = {}", label(*x))).collect();
        format!(", from {}", list.join(", "))
    };
    let title = format!(
        "{}: the default experiment, {} s to {} s{from}",
        me.description.model_identifier,
        label(e.start_time.unwrap_or(0.0)),
        label(run.times.last().copied().unwrap_or(0.0))
    );
    let mut text = svg(&run, &title);
    if starts.is_empty() && run.stopped.is_none() {
        let names: Vec<String> = run.curves.iter().map(|c| c.name.clone()).collect();
        let values: Vec<Vec<f64>> = run.curves.iter().map(|c| c.values.clone()).collect();
        text.push_str(RESULTS_MARKER);
        text.push_str(&fmi_conformance::reference_results::csv(&names, &run.times, &values));
    }
    Ok(text)
}

/// The picture and the reference results of one run (see [`default_experiment_svg`]).
type Made = Result<(String, Option<String>), String>;

static MADE: std::sync::Mutex<Option<std::collections::HashMap<std::path::PathBuf, Made>>> =
    std::sync::Mutex::new(None);

/// The reference results of the run [`picture`] made of the library at `so` (None: no run, or
/// one that is not the default experiment as an importer runs it).
pub fn reference_results(so: &Path) -> Option<String> {
    let made = MADE.lock().ok()?;
    made.as_ref()?.get(so)?.as_ref().ok()?.1.clone()
}

/// The picture of the library at `so`, made in a child process (this program run as `__plot`)
/// when this program is `cargo fmu`, else here; once per library and process (the FMI 2.0 and
/// 3.0 packages of one build share it). `resources`: the crate's `resources/` folder, if any.
pub fn picture(so: &Path, resources: Option<&Path>, starts: &[(String, f64)]) -> Result<String, String> {
    use std::collections::HashMap;
    let key = so.to_path_buf();
    if let Some(made) = MADE
        .lock()
        .ok()
        .and_then(|m| m.as_ref().and_then(|m| m.get(&key).cloned()))
    {
        return made.map(|(svg, _)| svg);
    }
    // A crate without resources/ gets an empty folder, as an importer gives one.
    let empty = std::env::temp_dir().join(format!("cargo-fmu-no-resources-{}", std::process::id()));
    let uri = match resources {
        Some(dir) => crate::library::file_uri(dir),
        None => {
            std::fs::create_dir_all(&empty).map_err(|e| format!("{}: {e}", empty.display()))?;
            crate::library::file_uri(&empty)
        }
    };
    let made = match std::env::current_exe() {
        Ok(exe) if exe.file_stem().is_some_and(|s| s == "cargo-fmu" || s == "fmu-build") => {
            match std::process::Command::new(&exe)
                .arg("__plot")
                .arg(so)
                .arg(&uri)
                .args(starts.iter().map(|(n, x)| format!("{n}={x:?}")))
                .output()
            {
                Ok(out) if out.status.success() => Ok(String::from_utf8_lossy(&out.stdout).into_owned()),
                // The child's last line, without its "cargo-fmu: error: " (a missing picture is a
                // note of the build, not an error).
                Ok(out) => Err(String::from_utf8_lossy(&out.stderr)
                    .lines()
                    .last()
                    .map(|l| l.split_once(": error: ").map_or(l, |(_, m)| m).to_string())
                    .unwrap_or_else(|| format!("the default experiment's run ended with {}", out.status))),
                Err(e) => Err(format!("cannot start {}: {e}", exe.display())),
            }
        }
        _ => default_experiment_svg(so, &uri, starts),
    };
    let _ = std::fs::remove_dir(&empty);
    let made: Made = made.map(|text| match text.split_once(RESULTS_MARKER) {
        Some((svg, csv)) => (svg.to_string(), Some(csv.to_string())),
        None => (text, None),
    });
    if let Ok(mut m) = MADE.lock() {
        m.get_or_insert_with(HashMap::new).insert(key, made.clone());
    }
    made.map(|(svg, _)| svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chart_has_a_line_per_output_and_breaks_at_non_finite_values() {
        let run = Run {
            times: vec![0.0, 0.5, 1.0, 1.5],
            curves: vec![
                Curve {
                    name: "y".into(),
                    unit: "m".into(),
                    values: vec![0.0, 1.0, 2.0, 3.0],
                },
                Curve {
                    name: "z<1>".into(),
                    unit: String::new(),
                    values: vec![1.0, f64::NAN, 1.0, 1.0],
                },
            ],
            stopped: None,
        };
        let s = svg(&run, "Lag");
        assert_eq!(s.matches("<polyline").count(), 3, "{s}");
        assert!(s.contains("y (m)") && s.contains("z&lt;1&gt;"), "{s}");
        assert!(s.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""), "{s}");
        assert!(!s.contains("NaN"), "{s}");
    }

    #[test]
    fn labels_are_short() {
        assert_eq!(label(0.0), "0");
        assert_eq!(label(1.5), "1.5");
        assert_eq!(label(10.0), "10");
        assert_eq!(label(1e-7), "1.000e-7");
    }
}
