//! Reference results as the layered standard FMI-LS-REF (1.0.0-alpha.1) has an FMU ship them:
//! the manifest `extra/org.fmi-standard.fmi-ls-ref/fmi-ls-manifest.xml`, whose root
//! `<fmiReferences>` holds one `<Related type=".." source=".." role=".."/>` per related file
//! (FMI-LS-REF section "Related Files"; `source` a URI relative to the manifest), and among them
//! the files of role `result` ("a result file that contains the results of an experiment or
//! simulation run"). The Reference-FMUs v0.0.41 ship one each: `<model>_out.csv`, type
//! `text/csv`, "Output of the default experiment": a header `time,<variable>,...` and one row per
//! output time; an array's elements separated by spaces, a Boolean `true`/`false`, a Binary in
//! hex.
//!
//! [`write`] writes them in that form (`cargo fmu build` does, from the default experiment it
//! runs for the documentation page); [`read`], [`steps`] and [`compare`] serve the checks that
//! run the default experiment again (at its step size where it declares one) and compare (`reference_results_are_reproduced_by_the_default_experiment`
//! and its FMI 3.0 twin).

use std::fmt::Write as _;
use std::path::{Component, Path, PathBuf};

/// The layered standard's folder in the FMU archive.
pub const FOLDER: &str = "extra/org.fmi-standard.fmi-ls-ref";
/// Its manifest, as FMI-LS-REF names it.
pub const MANIFEST: &str = "extra/org.fmi-standard.fmi-ls-ref/fmi-ls-manifest.xml";

/// The manifest of an FMU whose only related file is the result of its default experiment,
/// `source` (relative to the manifest's folder), as the Reference-FMUs write it.
pub fn manifest(source: &str) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiReferences
    xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
    xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"
    fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-ref"
    fmi-ls:fmi-ls-version="1.0.0-alpha.1">
    <Related type="text/csv" source="{source}" role="result" description="Output of the default experiment"/>
</fmiReferences>
"#
    )
}

/// The CSV of a run: `time,<names>` and a row per time (values as Rust prints them: they read
/// back bit for bit).
pub fn csv(names: &[String], times: &[f64], columns: &[Vec<f64>]) -> String {
    let mut t = String::from("time");
    for n in names {
        let _ = write!(t, ",{}", quoted(n));
    }
    t.push('\n');
    for (i, time) in times.iter().enumerate() {
        let _ = write!(t, "{time:?}");
        for c in columns {
            let _ = write!(t, ",{:?}", c[i]);
        }
        t.push('\n');
    }
    t
}

/// A CSV field, quoted when it holds a comma or a quote.
fn quoted(name: &str) -> String {
    if name.contains([',', '"', '\n']) {
        format!("\"{}\"", name.replace('"', "\"\""))
    } else {
        name.to_string()
    }
}

/// One result file: its path in the archive, its columns' names (after `time`), the times, and
/// each row's cells.
#[derive(Debug, Clone)]
pub struct Table {
    pub file: String,
    pub names: Vec<String>,
    pub times: Vec<f64>,
    pub rows: Vec<Vec<String>>,
}

/// What an FMU's manifest names of role `result`: the tables read, and the files it names that
/// the archive does not hold (FMI-LS-REF, "Related Files": "an importer should be prepared to
/// handle related files that are described in the layered standard manifest file, but are not
/// present in the FMU archive").
#[derive(Debug, Clone, Default)]
pub struct Results {
    pub tables: Vec<Table>,
    pub missing: Vec<String>,
}

/// The result files the unpacked FMU at `dir` declares in its FMI-LS-REF manifest: None when it
/// has no manifest or the manifest names no file of role `result` in CSV; Err when the manifest
/// or a file cannot be read as such (the message names the file and the line).
pub fn read(dir: &Path) -> Result<Option<Results>, String> {
    let path = dir.join(MANIFEST);
    let Ok(xml) = std::fs::read_to_string(&path) else {
        return Ok(None);
    };
    let mut results = Results::default();
    let mut named = false;
    for (role, ty, source) in related(&xml).map_err(|e| format!("{MANIFEST}: {e}"))? {
        // "A role can consist of a main role and optionally one or more sub-roles".
        if role.split('/').next() != Some("result") || !(ty == "text/csv" || source.ends_with(".csv")) {
            continue;
        }
        let inside = resolve(&source).ok_or_else(|| {
            format!("{MANIFEST}: source=\"{source}\": not a relative URI of a file inside the FMU archive")
        })?;
        named = true;
        let file = dir.join(&inside);
        if !file.is_file() {
            results.missing.push(inside.display().to_string());
            continue;
        }
        let text = std::fs::read_to_string(&file)
            .map_err(|e| format!("{MANIFEST} names {}, which cannot be read: {e}", inside.display()))?;
        results.tables.push(parse_csv(&inside.display().to_string(), &text)?);
    }
    Ok(named.then_some(results))
}

/// (role, type, source) of every `<Related>` of the manifest.
fn related(xml: &str) -> Result<Vec<(String, String, String)>, String> {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(xml);
    let mut out = vec![];
    loop {
        match reader.read_event() {
            Ok(Event::Start(e) | Event::Empty(e)) if e.local_name().as_ref() == b"Related" => {
                let get = |name: &[u8]| -> String {
                    e.attributes()
                        .flatten()
                        .find(|a| a.key.local_name().as_ref() == name)
                        .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
                        .unwrap_or_default()
                };
                out.push((get(b"role"), get(b"type"), get(b"source")));
            }
            Ok(Event::Eof) => return Ok(out),
            Ok(_) => {}
            Err(e) => return Err(format!("at byte {}: {e}", reader.buffer_position())),
        }
    }
}

/// The archive path of a relative URI `source` (relative to the manifest's folder); None for an
/// absolute URI or one that leaves the archive.
fn resolve(source: &str) -> Option<PathBuf> {
    if source.contains(':') || source.starts_with('/') || source.is_empty() {
        return None;
    }
    let mut parts: Vec<String> = FOLDER.split('/').map(String::from).collect();
    for c in Path::new(source).components() {
        match c {
            Component::Normal(p) => parts.push(p.to_str()?.to_string()),
            Component::ParentDir => {
                parts.pop()?;
            }
            Component::CurDir => {}
            _ => return None,
        }
    }
    Some(parts.iter().collect())
}

/// A result CSV: the header's first column is the time.
fn parse_csv(file: &str, text: &str) -> Result<Table, String> {
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines.next().ok_or_else(|| format!("{file}: empty"))?;
    let mut names = fields(header);
    if names.first().map(|n| n.trim()) != Some("time") {
        return Err(format!("{file}: line 1: the first column is not \"time\""));
    }
    names.remove(0);
    let (mut times, mut rows) = (vec![], vec![]);
    for (i, line) in lines {
        let mut cells = fields(line);
        if cells.len() != names.len() + 1 {
            return Err(format!(
                "{file}: line {}: {} fields, the header has {}",
                i + 1,
                cells.len(),
                names.len() + 1
            ));
        }
        let t: f64 = cells[0]
            .trim()
            .parse()
            .map_err(|_| format!("{file}: line {}: time {:?} is no number", i + 1, cells[0]))?;
        if times.last().is_some_and(|last| t < *last) || !t.is_finite() {
            return Err(format!("{file}: line {}: time {t} goes back or is not finite", i + 1));
        }
        times.push(t);
        cells.remove(0);
        rows.push(cells);
    }
    Ok(Table {
        file: file.to_string(),
        names,
        times,
        rows,
    })
}

/// The fields of a CSV line (RFC 4180 quotes).
fn fields(line: &str) -> Vec<String> {
    let (mut out, mut cur, mut quoted, mut chars) = (vec![], String::new(), false, line.chars().peekable());
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut cur)),
            (c, _) => cur.push(c),
        }
    }
    out.push(cur);
    out
}

/// A value as the run gave it: numbers (a scalar is one; Booleans 0 and 1), or a text (a String,
/// a Binary in hex).
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Numbers(Vec<f64>),
    Text(String),
}

/// A cell as a value: its space-separated numbers (`true`/`false` as 1 and 0), else its text.
fn cell_value(cell: &str) -> Value {
    let numbers: Option<Vec<f64>> = cell
        .split_whitespace()
        .map(|x| match x {
            "true" => Some(1.0),
            "false" => Some(0.0),
            x => x.parse().ok(),
        })
        .collect();
    match numbers {
        Some(n) if !n.is_empty() => Value::Numbers(n),
        _ => Value::Text(cell.to_string()),
    }
}

/// The relative tolerance of the comparison (the layered standard gives none; see [`compare`]).
pub const RELATIVE_TOLERANCE: f64 = 1e-3;

/// Compares the run's values with the table: `observed[column][row]` (None: the run did not give
/// that column). A number matches within `RELATIVE_TOLERANCE` times the largest magnitude of
/// its column (and 1e-9 absolute), or lies within the reference's values at the row before and
/// after, as widened so (an event the run places a round-off earlier or later moves a jump by one
/// row). Texts match exactly. The mismatches, at most `limit`, each a line.
pub fn compare(table: &Table, observed: &[Option<Vec<Value>>], limit: usize) -> Vec<String> {
    let mut out = vec![];
    let mut count = 0;
    for (c, name) in table.names.iter().enumerate() {
        let Some(Some(values)) = observed.get(c) else { continue };
        let reference: Vec<Value> = table.rows.iter().map(|r| cell_value(&r[c])).collect();
        let scale = reference
            .iter()
            .flat_map(|v| match v {
                Value::Numbers(n) => n.clone(),
                Value::Text(_) => vec![],
            })
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let tol = RELATIVE_TOLERANCE * scale + 1e-9;
        for (i, (got, want)) in values.iter().zip(&reference).enumerate() {
            let ok = match (got, want) {
                (Value::Numbers(g), Value::Numbers(w)) if g.len() == w.len() => g.iter().enumerate().all(|(k, x)| {
                    let near = |r: &Value| match r {
                        Value::Numbers(n) => n.get(k).copied(),
                        Value::Text(_) => None,
                    };
                    let around: Vec<f64> = [i.checked_sub(1), Some(i), Some(i + 1)]
                        .iter()
                        .flatten()
                        .filter_map(|j| reference.get(*j).and_then(near))
                        .collect();
                    let (lo, hi) = around
                        .iter()
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| (a.min(*y), b.max(*y)));
                    (x - w[k]).abs() <= tol || (lo - tol <= *x && *x <= hi + tol)
                }),
                (Value::Text(g), Value::Text(w)) => g == w,
                _ => false,
            };
            if !ok {
                count += 1;
                if out.len() < limit {
                    out.push(format!(
                        "{name} at t = {}: {} (reference {})",
                        table.times[i],
                        show(got),
                        table.rows[i][c]
                    ));
                }
            }
        }
    }
    if count > out.len() {
        out.push(format!("... {} more", count - out.len()));
    }
    out
}

fn show(v: &Value) -> String {
    match v {
        Value::Numbers(n) => n.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(" "),
        Value::Text(t) => t.clone(),
    }
}

/// The steps from `from` to `to`: as many equal steps as the default experiment's step size `h`
/// makes (within 1e-6 of a whole number), the run's own grid, else one.
pub fn steps(from: f64, to: f64, h: Option<f64>) -> (usize, f64) {
    let span = to - from;
    let n = match h {
        Some(h) if h > 0.0 && h.is_finite() => {
            let k = (span / h).round();
            if k >= 1.0 && (span / h - k).abs() <= 1e-6 * k {
                k as usize
            } else {
                1
            }
        }
        _ => 1,
    };
    (n, span / n as f64)
}

/// Lower-case hex of bytes (a Binary as the Reference-FMUs' CSV writes it).
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_written_result_reads_back_and_compares_equal_to_its_run() {
        let names = vec!["h".to_string(), "a,b".to_string()];
        let times = [0.0, 0.1, 0.2];
        let columns = vec![vec![1.0, 0.5, 0.1], vec![0.0, -1.0, f64::MIN_POSITIVE]];
        let t = parse_csv("x.csv", &csv(&names, &times, &columns)).unwrap();
        assert_eq!(t.names, names);
        assert_eq!(t.times, times);
        let observed: Vec<Option<Vec<Value>>> = columns
            .iter()
            .map(|c| Some(c.iter().map(|x| Value::Numbers(vec![*x])).collect()))
            .collect();
        assert!(compare(&t, &observed, 5).is_empty());
        let mut off = observed.clone();
        off[0].as_mut().unwrap()[1] = Value::Numbers(vec![2.0]);
        let m = compare(&t, &off, 5);
        assert_eq!(m.len(), 1, "{m:?}");
        assert!(m[0].starts_with("h at t = 0.1: 2.0"), "{m:?}");
    }

    #[test]
    fn sources_resolve_inside_the_archive_only() {
        assert_eq!(resolve("a_out.csv").unwrap(), Path::new(FOLDER).join("a_out.csv"));
        assert_eq!(
            resolve("../../documentation/x.txt").unwrap(),
            Path::new("documentation/x.txt")
        );
        assert_eq!(resolve("../../../x"), None);
        assert_eq!(resolve("https://example.org/x.csv"), None);
        assert_eq!(related(&manifest("m_out.csv")).unwrap()[0].2, "m_out.csv");
    }
}
