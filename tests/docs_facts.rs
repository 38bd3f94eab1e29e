//! ARCHITECTURE.md and README.md state facts of the workspace that nobody should have to keep by
//! hand: which crates there are and in which folder, what each depends on inside the workspace,
//! which folders hold them, which crates are FMUs and how many. These tests read the same facts
//! from the Cargo.toml files (the workspace's `members`, each package's name, `[lib]
//! crate-type`, `[dependencies]`) and fail naming each crate the documents leave out or place
//! wrongly, and each count that disagrees. A new crate, a moved folder or a new dependency between
//! crates is one failing test until the documents say it.
//!
//! Only the standard library: the manifests are read line by line (the workspace writes them
//! that way: one dependency a line, `members` as one array of strings).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &str) -> String {
    let p = root().join(path);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// One package of the workspace, as its Cargo.toml declares it.
#[derive(Debug)]
struct Crate {
    /// The package name.
    name: String,
    /// Its folder relative to the workspace root, `.` for the root package.
    dir: String,
    /// Every package it depends on in `[dependencies]` and `[target.*.dependencies]` (renamed
    /// keys resolved to the package they name), inside the workspace or not.
    deps: BTreeSet<String>,
    /// `crate-type` includes `cdylib`.
    cdylib: bool,
    /// `[package.metadata.fmu] model = false`: a cdylib on rustfmu that is not an FMU.
    not_a_model: bool,
}

impl Crate {
    /// An FMU crate, by `cargo fmu`'s rule: a cdylib that depends on rustfmu and does not say
    /// `model = false`.
    fn is_fmu(&self) -> bool {
        self.cdylib && self.deps.contains("rustfmu") && !self.not_a_model
    }

    /// The top-level folder it sits in (`src` for the root package, whose code is there).
    fn top_folder(&self) -> &str {
        if self.dir == "." {
            "src"
        } else {
            self.dir.split('/').next().unwrap()
        }
    }
}

/// The texts between double quotes on a line.
fn quoted(line: &str) -> Vec<String> {
    line.split('"').skip(1).step_by(2).map(str::to_string).collect()
}

fn parse_manifest(dir: &str, text: &str) -> Crate {
    let (mut name, mut deps, mut cdylib, mut not_a_model) = (None, BTreeSet::new(), false, false);
    let mut section = String::new();
    for line in text.lines().map(str::trim) {
        if line.starts_with('[') {
            section = line.to_string();
            continue;
        }
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            continue;
        };
        let (key, value) = (key.trim(), value.trim());
        match section.as_str() {
            "[package]" if key == "name" => name = quoted(value).into_iter().next(),
            "[lib]" if key == "crate-type" => cdylib = quoted(value).iter().any(|t| t == "cdylib"),
            "[package.metadata.fmu]" if key == "model" => not_a_model = value == "false",
            s if s == "[dependencies]" || (s.starts_with("[target.") && s.ends_with(".dependencies]")) => {
                let renamed = value.split_once("package =").map(|(_, p)| quoted(p)[0].clone());
                deps.insert(renamed.unwrap_or_else(|| key.trim_end_matches(".workspace").to_string()));
            }
            _ => {}
        }
    }
    let name = name.unwrap_or_else(|| panic!("{dir}/Cargo.toml: no [package] name"));
    Crate {
        name,
        dir: dir.to_string(),
        deps,
        cdylib,
        not_a_model,
    }
}

/// The root Cargo.toml's `members`, as written (globs included).
fn member_patterns() -> Vec<String> {
    let manifest = read("Cargo.toml");
    let start = manifest.find("members = [").expect("Cargo.toml: no `members = [`");
    let end = start + manifest[start..].find(']').expect("Cargo.toml: `members` not closed");
    quoted(&manifest[start..end])
}

/// Every package of the workspace, by name.
fn workspace() -> BTreeMap<String, Crate> {
    let mut dirs = Vec::new();
    for pattern in member_patterns() {
        match pattern.strip_suffix("/*") {
            Some(parent) => {
                let entries = std::fs::read_dir(root().join(parent)).unwrap_or_else(|e| panic!("{parent}: {e}"));
                let mut found: Vec<String> = entries
                    .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                    .filter(|child| root().join(parent).join(child).join("Cargo.toml").is_file())
                    .map(|child| format!("{parent}/{child}"))
                    .collect();
                found.sort();
                dirs.extend(found);
            }
            None => dirs.push(pattern),
        }
    }
    dirs.iter()
        .map(|dir| parse_manifest(dir, &read(&format!("{dir}/Cargo.toml"))))
        .map(|c| (c.name.clone(), c))
        .collect()
}

/// The texts between backticks.
fn backticked(text: &str) -> Vec<&str> {
    text.split('`').skip(1).step_by(2).collect()
}

/// The rows of the Markdown table whose header line starts with `header`, as trimmed cells.
fn table_rows(doc: &str, header: &str) -> Vec<Vec<String>> {
    let mut lines = doc.lines().skip_while(|l| !l.starts_with(header));
    assert!(lines.next().is_some(), "no table with the header {header:?}");
    lines
        .skip(1) // | --- | --- |
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            l.trim()
                .trim_matches('|')
                .split('|')
                .map(|c| c.trim().to_string())
                .collect()
        })
        .collect()
}

/// Whether a folder as the documents write it (`runner/`, `holonomic/fmus/*`, `src/` for the
/// root package) holds the crate in `dir`.
fn folder_holds(folder: &str, dir: &str) -> bool {
    let folder = folder.trim_end_matches('/');
    match folder.strip_suffix("/*") {
        Some(parent) => dir.rsplit_once('/').is_some_and(|(p, _)| p == parent),
        None => folder == dir || (dir == "." && folder == "src"),
    }
}

/// Whether a folder the documents name exists (a glob: its parent).
fn folder_exists(folder: &str) -> bool {
    root().join(folder.trim_end_matches('*')).is_dir()
}

fn assert_none(problems: Vec<String>) {
    assert!(
        problems.is_empty(),
        "the documents disagree with the Cargo.toml files:\n- {}",
        problems.join("\n- ")
    );
}

const CRATE_TABLE: &str = "| crate | folder |";

#[test]
fn architecture_lists_every_crate_of_the_workspace_once_in_its_folder() {
    let crates = workspace();
    let doc = read("ARCHITECTURE.md");
    let mut problems = Vec::new();
    let mut listed = BTreeMap::<String, usize>::new();
    for row in table_rows(&doc, CRATE_TABLE) {
        let folder = backticked(&row[1]).first().copied().unwrap_or("");
        for name in backticked(&row[0]) {
            *listed.entry(name.to_string()).or_default() += 1;
            match crates.get(name) {
                None => problems.push(format!(
                    "ARCHITECTURE.md lists `{name}`, which is no crate of the workspace"
                )),
                Some(c) if !folder_holds(folder, &c.dir) => problems.push(format!(
                    "ARCHITECTURE.md puts `{name}` in `{folder}`; it is in `{}/`",
                    c.dir
                )),
                Some(_) => {}
            }
        }
    }
    for c in crates.values() {
        match listed.get(&c.name) {
            None => problems.push(format!(
                "ARCHITECTURE.md's crate table does not list `{}` (`{}/`)",
                c.name, c.dir
            )),
            Some(&n) if n > 1 => problems.push(format!("ARCHITECTURE.md's crate table lists `{}` {n} times", c.name)),
            Some(_) => {}
        }
    }
    assert_none(problems);
}

/// `rustfmu-workspace-hack` has no code: ARCHITECTURE.md says once, below the table, why the
/// crates that name it do.
const NOT_A_DEPENDENCY_TO_NAME: &str = "rustfmu-workspace-hack";

#[test]
fn architecture_names_exactly_the_workspace_crates_each_crate_depends_on() {
    let crates = workspace();
    let doc = read("ARCHITECTURE.md");
    let mut problems = Vec::new();
    for row in table_rows(&doc, CRATE_TABLE) {
        let named: BTreeSet<&str> = backticked(&row[3])
            .into_iter()
            .filter(|n| crates.contains_key(*n))
            .collect();
        for c in backticked(&row[0]).iter().filter_map(|n| crates.get(*n)) {
            let actual: BTreeSet<&str> = c
                .deps
                .iter()
                .map(String::as_str)
                .filter(|d| crates.contains_key(*d) && *d != NOT_A_DEPENDENCY_TO_NAME)
                .collect();
            for missing in actual.difference(&named) {
                problems.push(format!(
                    "`{}` depends on `{missing}`; ARCHITECTURE.md's row does not say so",
                    c.name
                ));
            }
            for extra in named.difference(&actual) {
                problems.push(format!(
                    "ARCHITECTURE.md says `{}` depends on `{extra}`; its Cargo.toml does not",
                    c.name
                ));
            }
        }
    }
    assert_none(problems);
}

/// The first whitespace-separated word of each line of README's layout block (the fenced block
/// that starts with `src/`), continuation lines (starting with spaces) left out.
fn readme_layout(readme: &str) -> Vec<(String, String)> {
    let mut lines = readme
        .lines()
        .skip_while(|l| !l.starts_with("src/ "))
        .take_while(|l| !l.starts_with("```"));
    let mut entries = Vec::new();
    for line in lines.by_ref().filter(|l| !l.starts_with(' ')) {
        let (folder, text) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        entries.push((folder.to_string(), text.trim().to_string()));
    }
    assert!(!entries.is_empty(), "README.md: no layout block starting with `src/`");
    entries
}

#[test]
fn both_layouts_name_every_top_level_folder_that_holds_a_crate_and_only_folders_that_exist() {
    let crates = workspace();
    let architecture = read("ARCHITECTURE.md");
    let readme = read("README.md");
    let in_architecture: Vec<String> = table_rows(&architecture, "| folder | why it is there |")
        .iter()
        .filter_map(|row| backticked(&row[0]).first().map(|f| f.to_string()))
        .collect();
    let in_readme: Vec<String> = readme_layout(&readme).into_iter().map(|(f, _)| f).collect();
    let mut problems = Vec::new();
    let tops: BTreeSet<&str> = crates.values().map(Crate::top_folder).collect();
    for (doc, folders) in [
        ("ARCHITECTURE.md's folder table", &in_architecture),
        ("README.md's layout", &in_readme),
    ] {
        for top in &tops {
            if !folders
                .iter()
                .any(|f| f.trim_end_matches('*').trim_end_matches('/') == *top)
            {
                problems.push(format!("{doc} does not name `{top}/`, which holds crates"));
            }
        }
        for f in folders.iter().filter(|f| f.ends_with('/') || f.ends_with("/*")) {
            if !folder_exists(f) {
                problems.push(format!("{doc} names `{f}`, which does not exist"));
            }
        }
    }
    assert_none(problems);
}

const NUMBER_WORDS: [&str; 13] = [
    "no", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten", "eleven", "twelve",
];

/// The count a line states: the first number word, or the first number.
fn stated_count(text: &str) -> Option<usize> {
    text.split(|c: char| !c.is_alphanumeric()).find_map(|w| {
        NUMBER_WORDS
            .iter()
            .position(|n| n.eq_ignore_ascii_case(w))
            .or_else(|| w.parse().ok())
    })
}

#[test]
fn readme_counts_and_names_the_crates_of_each_folder_of_fmu_crates() {
    let crates = workspace();
    let readme = read("README.md");
    let layout = readme_layout(&readme);
    let mut problems = Vec::new();
    for pattern in member_patterns().iter().filter(|p| p.ends_with("/*")) {
        let inside: Vec<&Crate> = crates.values().filter(|c| folder_holds(pattern, &c.dir)).collect();
        let Some((_, text)) = layout.iter().find(|(f, _)| f == pattern) else {
            problems.push(format!(
                "README.md's layout has no line for `{pattern}` ({} crates)",
                inside.len()
            ));
            continue;
        };
        if stated_count(text) != Some(inside.len()) {
            problems.push(format!(
                "README.md says of `{pattern}` \"{text}\"; it holds {} crates",
                inside.len()
            ));
        }
        // The models in parentheses, one per crate.
        let listed = text
            .split_once('(')
            .and_then(|(_, r)| r.split_once(')'))
            .map(|(l, _)| l.split(',').count());
        if listed != Some(inside.len()) {
            problems.push(format!(
                "README.md's line for `{pattern}` names {} models in parentheses; it holds {} crates",
                listed.unwrap_or(0),
                inside.len()
            ));
        }
        for c in inside.iter().filter(|c| !c.is_fmu()) {
            problems.push(format!(
                "`{}` in `{pattern}` is not an FMU crate (a cdylib on rustfmu)",
                c.name
            ));
        }
    }
    assert_none(problems);
}

#[test]
fn the_layer_diagram_covers_every_fmu_crate_with_folders_that_exist() {
    let crates = workspace();
    let doc = read("ARCHITECTURE.md");
    let line = doc
        .lines()
        .find(|l| l.trim_start().starts_with("FMU crates"))
        .expect("ARCHITECTURE.md: no `FMU crates` layer");
    let folders: Vec<&str> = line
        .trim_start()
        .trim_start_matches("FMU crates")
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|w| w.contains('/'))
        .collect();
    let mut problems = Vec::new();
    for c in crates.values().filter(|c| c.is_fmu()) {
        if !folders.iter().any(|f| folder_holds(f, &c.dir)) {
            problems.push(format!(
                "the `FMU crates` layer of ARCHITECTURE.md does not cover `{}` (`{}/`)",
                c.name, c.dir
            ));
        }
    }
    for f in folders.iter().filter(|f| !folder_exists(f)) {
        problems.push(format!(
            "the `FMU crates` layer of ARCHITECTURE.md names `{f}`, which does not exist"
        ));
    }
    assert_none(problems);
}

/// The reading itself: the root package, a glob member and a renamed dependency come out as the
/// tests above assume.
#[test]
fn the_manifests_are_read_as_cargo_reads_them() {
    let crates = workspace();
    let rustfmu = &crates["rustfmu"];
    assert_eq!(
        (rustfmu.dir.as_str(), rustfmu.top_folder(), rustfmu.is_fmu()),
        (".", "src", false)
    );
    assert!(
        crates["fmi-conformance"].deps.contains("md-reader"),
        "{:?}",
        crates["fmi-conformance"].deps
    );
    assert!(crates["pendulum-fmu"].is_fmu() && crates["pendulum-fmu"].dir == "holonomic/fmus/pendulum");
    assert!(crates["rustfmu-container"].cdylib && !crates["rustfmu-container"].is_fmu());
    assert!(Path::new(&root()).join("md-reader/Cargo.toml").is_file());
}

/// The documents a newcomer reads, each a path from the workspace root.
fn documents() -> Vec<String> {
    let mut docs = vec!["README.md".to_string(), "ARCHITECTURE.md".to_string()];
    for dir in ["docs", "conformance", "tests/independent", "bench", "runner"] {
        let Ok(entries) = std::fs::read_dir(root().join(dir)) else {
            continue;
        };
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.ends_with(".md") {
                docs.push(format!("{dir}/{name}"));
            }
        }
    }
    docs.sort();
    docs
}

/// The words of `text` that name a source file of this repository: a path with a `/`, ending in
/// a source or script extension, whose first folder is a top-level folder of the workspace (or
/// `..`, `./`, `src/`: then read from the document's own folder too). Paths of other projects
/// (`include/model.h` of the Reference-FMUs) and of generated files (`target/...`) are not ours
/// and are passed over.
fn named_paths(text: &str) -> Vec<String> {
    const EXTENSIONS: [&str; 8] = [".rs", ".toml", ".sh", ".py", ".md", ".c", ".h", ".in"];
    text.split(|c: char| c.is_whitespace() || "`()[]<>\"',;|*".contains(c))
        .map(|w| w.trim_end_matches(['.', ':']))
        .filter(|w| w.contains('/') && EXTENSIONS.iter().any(|e| w.ends_with(e)))
        .filter(|w| !w.contains("://") && !w.contains('$') && !w.contains('{') && !w.starts_with('/'))
        .map(|w| w.split(':').next().unwrap_or(w).to_string())
        .collect()
}

#[test]
fn every_source_path_the_documents_name_exists() {
    let tops: BTreeSet<String> = std::fs::read_dir(root())
        .unwrap()
        .flatten()
        .filter(|e| e.path().is_dir())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != "target" && !n.starts_with('.'))
        .collect();
    let mut problems = Vec::new();
    for doc in documents() {
        let dir = Path::new(&doc).parent().unwrap_or(Path::new("")).to_path_buf();
        for (n, line) in read(&doc).lines().enumerate() {
            for path in named_paths(line) {
                let first = path.split('/').next().unwrap_or("");
                let ours = tops.contains(first) || first == ".." || first == ".";
                if !ours {
                    continue;
                }
                // A crate table's row names its files from the crate's folder (`src/fmi2.rs` on
                // the row of `runner/container/`): the folders the line names are bases too.
                let bases = backticked(line)
                    .into_iter()
                    .filter(|w| w.ends_with('/') && root().join(w).is_dir())
                    .map(PathBuf::from)
                    .chain([PathBuf::new(), dir.clone()]);
                let exists = bases.into_iter().any(|b| root().join(b).join(&path).exists());
                if !exists {
                    problems.push(format!(
                        "{doc}:{}: names `{path}`, which is not a file of the repository (moved or renamed?)",
                        n + 1
                    ));
                }
            }
        }
    }
    assert_none(problems);
}
