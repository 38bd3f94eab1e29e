//! The documentation's lists of declarations against the derive's own: docs/declarations.md's
//! key tables, compile-error messages and runtime units, and docs/fmi3.md's feature table, each
//! compared with the list the derive parses with (`model::VARIABLE_KEYS`, `FMU_KEYS`,
//! `CLOCK_KEYS`, `TYPES`, `units::DEFAULT_UNITS`). A failure names what one side has and the
//! other lacks.

use crate::model::{self, CLOCK_KEYS, FMU_KEYS, TYPES, VARIABLE_KEYS};
use crate::units::{self, Base};
use std::collections::BTreeSet;

const DECLARATIONS: &str = include_str!("../../../docs/declarations.md");
const FMI3: &str = include_str!("../../../docs/fmi3.md");

/// The text under `heading` (a whole line), up to the next heading of its level or above.
fn section<'a>(doc: &'a str, heading: &str) -> &'a str {
    let level = heading.chars().take_while(|c| *c == '#').count();
    let start = doc
        .lines()
        .scan(0, |at, line| {
            let here = *at;
            *at += line.len() + 1;
            Some((here, line))
        })
        .find(|(_, line)| *line == heading)
        .unwrap_or_else(|| panic!("the heading `{heading}` is not in the document"))
        .0;
    let body = &doc[start + heading.len()..];
    let mut at = 0;
    let mut in_code_block = false;
    for line in body.split_inclusive('\n') {
        if line.starts_with("```") {
            in_code_block = !in_code_block;
        }
        let hashes = line.chars().take_while(|c| *c == '#').count();
        if !in_code_block && hashes > 0 && hashes <= level && line[hashes..].starts_with(' ') {
            return &body[..at];
        }
        at += line.len();
    }
    body
}

/// A Markdown table row's cells, split at `|` outside code spans (`` `a | b` `` is one cell).
fn cells(row: &str) -> Vec<String> {
    let mut cells = vec![String::new()];
    let mut chars = row.trim().trim_start_matches('|').chars().peekable();
    let mut fence = 0; // the length of the backtick run that opened the code span we are in
    while let Some(c) = chars.next() {
        if c == '`' {
            let mut run = 1;
            while chars.peek() == Some(&'`') {
                chars.next();
                run += 1;
            }
            if fence == 0 {
                fence = run;
            } else if fence == run {
                fence = 0;
            }
            cells.last_mut().unwrap().push_str(&"`".repeat(run));
        } else if c == '|' && fence == 0 {
            cells.push(String::new());
        } else {
            cells.last_mut().unwrap().push(c);
        }
    }
    if cells.last().is_some_and(|c| c.trim().is_empty()) {
        cells.pop();
    }
    cells.into_iter().map(|c| c.trim().to_string()).collect()
}

/// The rows of the first table in `text`, without its header and separator.
fn table(text: &str) -> Vec<Vec<String>> {
    let rows: Vec<_> = text
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .collect();
    assert!(rows.len() > 2, "no table in:\n{text}");
    rows[2..].iter().map(|r| cells(r)).collect()
}

/// The contents of the code spans in `text`, trimmed.
fn code_spans(text: &str) -> Vec<String> {
    let mut spans = Vec::new();
    let mut rest = text;
    while let Some(open) = rest.find('`') {
        let run = rest[open..].chars().take_while(|c| *c == '`').count();
        let fence = "`".repeat(run);
        let inner = &rest[open + run..];
        let Some(close) = inner.find(&fence) else { break };
        spans.push(inner[..close].trim().to_string());
        rest = &inner[close + run..];
    }
    spans
}

/// A key as the docs write it (`clock(..)`, `clock(...)`) or as the derive lists it: its name.
fn key_name(key: &str) -> &str {
    key.split('(').next().unwrap_or(key).trim()
}

fn names(keys: &[&str]) -> BTreeSet<String> {
    keys.iter().map(|k| key_name(k).to_string()).collect()
}

/// `documented` against `accepted`: panics listing what each lacks.
#[track_caller]
fn assert_same(what: &str, documented: &BTreeSet<String>, accepted: &BTreeSet<String>) {
    let undocumented: Vec<_> = accepted.difference(documented).collect();
    let unknown: Vec<_> = documented.difference(accepted).collect();
    assert!(
        undocumented.is_empty() && unknown.is_empty(),
        "{what}: the derive accepts, the docs do not list: {undocumented:?}; the docs list, the derive does not \
         accept: {unknown:?}"
    );
}

/// The keys in the first column of a "at a glance" table, and those of its rows marked
/// "FMI 3.0 only".
fn key_table(heading: &str) -> (BTreeSet<String>, BTreeSet<String>) {
    let (mut all, mut fmi3) = (BTreeSet::new(), BTreeSet::new());
    for row in table(section(DECLARATIONS, heading)) {
        let keys: Vec<_> = code_spans(&row[0]).iter().map(|k| key_name(k).to_string()).collect();
        assert!(!keys.is_empty(), "a row of `{heading}` names no key: {row:?}");
        if row.iter().any(|c| c.contains("FMI 3.0 only")) {
            fmi3.extend(keys.iter().cloned());
        }
        all.extend(keys);
    }
    (all, fmi3)
}

const VARIABLE_TABLE: &str = "### `#[variable(...)]` at a glance";
const FMU_TABLE: &str = "### `#[fmu(...)]` at a glance";

#[test]
fn the_variable_table_of_declarations_md_lists_every_key_the_derive_accepts() {
    assert_same(
        &format!("docs/declarations.md, {VARIABLE_TABLE}"),
        &key_table(VARIABLE_TABLE).0,
        &names(VARIABLE_KEYS),
    );
}

#[test]
fn the_fmu_table_of_declarations_md_lists_every_key_the_derive_accepts() {
    assert_same(
        &format!("docs/declarations.md, {FMU_TABLE}"),
        &key_table(FMU_TABLE).0,
        &names(FMU_KEYS),
    );
}

#[test]
fn the_clock_section_of_declarations_md_names_every_clock_key() {
    let text = section(DECLARATIONS, "### `clock(...)` and `clocks`: FMI 3.0 clocks");
    let words: BTreeSet<String> = code_spans(text)
        .iter()
        .flat_map(|s| {
            s.split(|c: char| !(c.is_alphanumeric() || c == '_'))
                .map(str::to_string)
                .collect::<Vec<_>>()
        })
        .collect();
    let missing: Vec<_> = CLOCK_KEYS.iter().filter(|k| !words.contains(**k)).collect();
    assert!(
        missing.is_empty(),
        "clock(..) accepts {missing:?}, which the clock section never shows"
    );
}

/// The one error the derive gives for `src`.
fn derive_error(src: &str) -> String {
    let e = model::expand_parts(syn::parse_str(src).expect("the test's source parses"));
    e.error.expect("the declaration is wrong").to_string()
}

#[test]
fn the_compile_error_table_quotes_the_unknown_key_messages_as_the_derive_gives_them() {
    let table = table(section(DECLARATIONS, "## Compile errors"));
    let quoted: Vec<String> = table
        .iter()
        .filter_map(|r| r.get(1))
        .flat_map(|c| code_spans(c))
        .collect();
    let cases = [
        ("#[variable]", "struct M {\n#[variable(vr = 0, causal)]\nx: f64,\n}"),
        (
            "#[fmu]",
            "#[fmu(colour = \"red\")]\nstruct M {\n#[variable(vr = 0, input)]\nx: f64,\n}",
        ),
        (
            "unit(..)",
            "#[fmu(unit(name = \"ft\", feet = 1))]\nstruct M {\n#[variable(vr = 0, input)]\nx: f64,\n}",
        ),
        (
            "clock(..)",
            "#[fmu(fmi3_only)]\nstruct M {\n#[variable(vr = 0, input, clock(every = 0.1))]\nc: rustfmu::Clock,\n}",
        ),
    ];
    let mut wrong = Vec::new();
    for (what, src) in cases {
        let message = derive_error(src);
        assert!(message.starts_with("unknown "), "{what}: {message}");
        if !quoted.contains(&message) {
            let head = message.split(';').next().unwrap_or_default();
            let head = &head[..head.find('`').unwrap_or(head.len())];
            let documented: Vec<_> = quoted.iter().filter(|q| q.starts_with(head)).collect();
            wrong.push(format!(
                "{what}: the derive says\n  {message}\nthe table says\n  {documented:?}"
            ));
        }
    }
    assert!(
        wrong.is_empty(),
        "docs/declarations.md, Compile errors:\n{}",
        wrong.join("\n")
    );
}

/// `kg m2 s-3 A-1`, `K, offset 273.15`: a unit's base units as the docs' table writes them.
fn base_text(b: &Base) -> String {
    let mut parts: Vec<String> = units::EXPONENT_NAMES
        .iter()
        .zip(b.exps)
        .filter(|(_, e)| *e != 0)
        .map(|(n, e)| if e == 1 { n.to_string() } else { format!("{n}{e}") })
        .collect();
    if parts.is_empty() {
        parts.push("(none)".into());
    }
    let mut text = parts.join(" ");
    if b.factor != 1.0 {
        text += &format!(", factor {}", b.factor);
    }
    if b.offset != 0.0 {
        text += &format!(", offset {}", b.offset);
    }
    text
}

#[test]
fn the_units_table_of_declarations_md_is_the_runtimes_units() {
    let mut documented = BTreeSet::new();
    let mut wrong = Vec::new();
    for row in table(section(DECLARATIONS, "## The runtime's units")) {
        for pair in row.chunks(2) {
            let [unit, base] = pair else { continue };
            let Some(name) = code_spans(unit).into_iter().next() else {
                continue;
            };
            match units::default_unit(&name) {
                Some(b) if base_text(&b) != *base => wrong.push(format!(
                    "'{name}': the table says {base}, the derive has {}",
                    base_text(&b)
                )),
                _ => {}
            }
            documented.insert(name);
        }
    }
    let accepted: BTreeSet<String> = units::DEFAULT_UNITS.iter().map(|(n, _)| n.to_string()).collect();
    assert_same("docs/declarations.md, The runtime's units", &documented, &accepted);
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// The Rust types of FMI 3.0's own variable types, from the derive's list of types: the words
/// after "FMI 3.0 only:" that are types (`f32` .. `u64`, `Vec<u8>`).
fn fmi3_types() -> BTreeSet<String> {
    let (_, fmi3) = TYPES
        .split_once("FMI 3.0 only:")
        .expect("TYPES names the FMI 3.0 types");
    fmi3.split([',', ' '])
        .filter(|w| w.starts_with(|c: char| c.is_ascii_lowercase()) || w.starts_with("Vec<"))
        .map(str::to_string)
        .collect()
}

/// What a code span of the feature table's "Declared with" column declares: a key (`dims = [n]`
/// is `dims`, `clock(..)` is `clock`) or a field type (`[f64; N]` is `f64`).
fn declared(span: &str) -> String {
    let mut s = span.trim();
    while let Some(inner) = s.strip_prefix('[') {
        s = inner.split(';').next().unwrap_or(inner).trim();
    }
    if s.starts_with("Vec<") || s.starts_with("#[") {
        return s.to_string();
    }
    s.split(['(', ' ', '=']).next().unwrap_or(s).to_string()
}

#[test]
fn the_fmi3_feature_table_declares_with_what_the_derive_accepts_and_names_every_fmi3_declaration() {
    let text = section(FMI3, "## What FMI 3.0 offers here");
    let header = text.lines().find(|l| l.starts_with('|')).expect("the feature table");
    let columns = cells(header);
    let col = |name: &str| {
        columns
            .iter()
            .position(|c| c == name)
            .unwrap_or_else(|| panic!("docs/fmi3.md's feature table has no column '{name}': {columns:?}"))
    };
    let (here, with) = (col("Here"), col("Declared with"));
    let type_words: BTreeSet<String> = TYPES.split([',', ' ']).map(str::to_string).collect();
    let accepted: BTreeSet<String> = names(VARIABLE_KEYS)
        .into_iter()
        .chain(names(FMU_KEYS))
        .chain(names(CLOCK_KEYS))
        .chain(type_words)
        .collect();
    let mut offered = BTreeSet::new();
    let mut wrong = Vec::new();
    for row in table(text) {
        let feature = &row[0];
        let keys: Vec<String> = code_spans(&row[with]).iter().map(|s| declared(s)).collect();
        for k in keys.iter().filter(|k| !accepted.contains(*k)) {
            wrong.push(format!(
                "'{feature}' is declared with `{k}`, which the derive does not accept"
            ));
        }
        let yes = row[here].starts_with("yes");
        if !yes && !row[here].starts_with("no") {
            wrong.push(format!(
                "'{feature}': the Here column starts with yes or no, not: {}",
                row[here]
            ));
        }
        if yes {
            offered.extend(keys);
        } else if !keys.is_empty() {
            wrong.push(format!("'{feature}' is not offered but declared with {keys:?}"));
        }
    }
    let fmi3_only: BTreeSet<String> = key_table(VARIABLE_TABLE)
        .1
        .into_iter()
        .chain(key_table(FMU_TABLE).1)
        .chain(fmi3_types())
        .collect();
    assert!(
        fmi3_only.contains("structural_parameter") && fmi3_only.contains("f32"),
        "{fmi3_only:?}"
    );
    for k in fmi3_only.difference(&offered) {
        wrong.push(format!(
            "`{k}` declares an FMI 3.0 feature (declarations.md, the derive), which no row of the table offers"
        ));
    }
    assert!(
        wrong.is_empty(),
        "docs/fmi3.md, the feature table:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_tables_are_read_as_markdown_reads_them() {
    assert_eq!(cells("| `a | b` | c |"), ["`a | b`", "c"]);
    assert_eq!(cells("| ``x `y` z`` | `w` |"), ["``x `y` z``", "`w`"]);
    assert_eq!(code_spans("`a`, ``b `c` d``"), ["a", "b `c` d"]);
    assert_eq!(declared("dims = [n, m]"), "dims");
    assert_eq!(declared("clock(..)"), "clock");
    assert_eq!(declared("[[f64; M]; N]"), "f64");
    assert_eq!(declared("Vec<u8>"), "Vec<u8>");
    assert_eq!(declared("#[derive(FmuEnum)]"), "#[derive(FmuEnum)]");
    assert_eq!(section("# A\n## B\nb\n### C\nc\n## D\nd\n", "## B"), "\nb\n### C\nc\n");
}
