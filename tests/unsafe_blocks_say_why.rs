//! Every `unsafe` block of the repository says why it is sound, on the comment line(s) just above
//! it (`// SAFETY: ...`). Clippy's `undocumented_unsafe_blocks` (denied for every crate in the
//! root Cargo.toml's `[workspace.lints]`) checks the code it compiles; this test reads every
//! tracked `.rs` file as text, so it also reaches what clippy does not: `quote!` bodies of the
//! derive, code behind a `cfg` of another platform, test fixtures, files no crate builds.
//!
//! What counts as a block: the keyword followed by `{` in code (not after `//`, not inside a
//! one-line string literal); `unsafe fn`, `unsafe impl`, `unsafe extern` and `unsafe trait` are
//! no blocks. What counts as the comment: the contiguous `//` lines (attributes `#[...]` between
//! them and the block allowed) directly above the line the block opens on, one of them holding
//! `SAFETY:`.

use std::path::Path;
use std::process::Command;

/// The 1-based lines of `source` that open an `unsafe` block without a `SAFETY:` comment above.
fn undocumented_blocks(source: &str) -> Vec<usize> {
    let lines: Vec<&str> = source.lines().collect();
    let mut missing = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        if opens_unsafe_block(line) && !safety_comment_above(&lines[..i]) {
            missing.push(i + 1);
        }
    }
    missing
}

/// Whether `line` has the keyword followed by `{` in its code: outside a string literal (escaped
/// quotes and the character literal `'"'` taken into account) and before any `//`.
fn opens_unsafe_block(line: &str) -> bool {
    const KEYWORD: &str = "unsafe";
    let trimmed = line.trim_start();
    if trimmed.starts_with("//") || trimmed.starts_with("/*") {
        return false;
    }
    let (mut in_string, mut escaped) = (false, false);
    let mut i = 0;
    while i < line.len() {
        let rest = &line[i..];
        let c = rest.chars().next().expect("i is below the length");
        if in_string {
            match c {
                _ if escaped => escaped = false,
                '\\' => escaped = true,
                '"' => in_string = false,
                _ => {}
            }
        } else if rest.starts_with("'\"'") {
            i += 2;
        } else if c == '"' {
            in_string = true;
        } else if rest.starts_with("//") {
            return false;
        } else if rest.starts_with(KEYWORD)
            && line[..i]
                .chars()
                .next_back()
                .is_none_or(|p| !(p.is_alphanumeric() || p == '_'))
            && rest[KEYWORD.len()..].trim_start().starts_with('{')
        {
            return true;
        }
        i += c.len_utf8();
    }
    false
}

/// Whether the comment lines directly above (the end of `above`) hold `SAFETY:`.
fn safety_comment_above(above: &[&str]) -> bool {
    for line in above.iter().rev().map(|l| l.trim_start()) {
        if line.starts_with("//") {
            if line.contains("SAFETY:") {
                return true;
            }
        } else if !line.starts_with("#[") {
            return false;
        }
    }
    false
}

#[test]
fn every_unsafe_block_of_the_repository_has_a_safety_comment_just_above_it() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new("git")
        .args(["ls-files", "-z", "--", "*.rs"])
        .current_dir(root)
        .output()
        .expect("git runs (the test reads the tracked files)");
    assert!(
        out.status.success(),
        "git ls-files: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let files: Vec<&str> = std::str::from_utf8(&out.stdout)
        .expect("file names in UTF-8")
        .split('\0')
        .filter(|f| !f.is_empty())
        .collect();
    assert!(files.len() > 100, "git ls-files listed only {} .rs files", files.len());
    let mut missing = Vec::new();
    for file in files {
        // A file deleted in the working tree but still tracked is not there to read.
        let Ok(source) = std::fs::read_to_string(root.join(file)) else {
            continue;
        };
        missing.extend(
            undocumented_blocks(&source)
                .into_iter()
                .map(|line| format!("{file}:{line}")),
        );
    }
    assert!(
        missing.is_empty(),
        "{} unsafe blocks without a `// SAFETY:` comment on the line(s) just above them:\n{}",
        missing.len(),
        missing.join("\n")
    );
}

#[test]
fn the_check_finds_blocks_and_their_comments_as_clippy_does() {
    let source = concat!(
        "// SAFETY: a reason\n",
        "let a = unsafe { f() };\n",
        "// SAFETY: a reason over\n",
        "// two lines\n",
        "#[allow(unused)]\n",
        "let b = unsafe { f() };\n",
        "let c = unsafe { f() }; // a comment after it is not above it\n",
        "unsafe fn g() {}\n",
        "unsafe impl Send for X {}\n",
        "unsafe extern \"C\" fn h() {}\n",
        "let s = \"unsafe { in a string }\";\n",
        "let t = \"a \\\" quote, then unsafe { in the same string }\";\n",
        "let q = '\"'; let u = unsafe { f() };\n",
        "// unsafe { in a comment }\n",
        "// a comment that gives no reason\n",
        "unsafe {\n",
        "}\n",
        "let d = not_unsafe { x };\n",
    );
    assert_eq!(undocumented_blocks(source), vec![7, 13, 16]);
}
