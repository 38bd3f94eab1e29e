//! A run's [`Report`] for CI systems: JUnit XML ([`junit`]) and JSON ([`json`]), written beside
//! the human summary (`--junit FILE`, `--json FILE`).
//!
//! JUnit: one `<testsuite>` per group of checks, one `<testcase>` per check; a failed check has
//! a `<failure>`, a skipped one `<skipped>`, a warned one passes with its warnings in
//! `<system-out>` (what JUnit readers such as Jenkins and GitLab show beside a test) and a
//! property `verdict` = `warned` (every test case has one: passed, failed, warned, skipped). An
//! FMU that could not be checked at all is one failed test case in a suite `preflight`.

use crate::outcome::Outcome;
use crate::runner::{CheckReport, Report};
use std::fmt::Write as _;

/// The verdict's word in the files: `passed`, `failed`, `warned`, `skipped`.
pub fn verdict(outcome: &Outcome) -> &'static str {
    match outcome {
        Outcome::Pass => "passed",
        Outcome::Fail(_) => "failed",
        Outcome::Warn(_) => "warned",
        Outcome::Skip(_) => "skipped",
    }
}

fn xml(text: &str) -> String {
    // XML 1.0 allows no control characters but tab, newline and carriage return.
    let clean: String = text
        .chars()
        .map(|c| {
            if c.is_control() && !matches!(c, '\t' | '\n' | '\r') {
                '?'
            } else {
                c
            }
        })
        .collect();
    quick_xml::escape::escape(clean.as_str()).into_owned()
}

fn first_line(text: &str) -> &str {
    text.lines().find(|l| !l.trim().is_empty()).unwrap_or("").trim()
}

/// The FMU's file name without `.fmu`, for the test cases' class names.
fn fmu_name(report: &Report) -> String {
    report
        .fmu
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "fmu".into())
}

fn testcase(out: &mut String, class: &str, c: &CheckReport) {
    let _ = write!(
        out,
        "    <testcase name=\"{}\" classname=\"{}\" time=\"{:.3}\">\n      <properties><property name=\"verdict\" value=\"{}\"/></properties>\n",
        xml(&c.name),
        xml(class),
        c.duration.as_secs_f64(),
        verdict(&c.outcome)
    );
    match &c.outcome {
        Outcome::Fail(m) => {
            let _ = writeln!(
                out,
                "      <failure message=\"{}\" type=\"failed\">{}</failure>",
                xml(first_line(m)),
                xml(m)
            );
        }
        Outcome::Skip(why) => {
            let _ = writeln!(out, "      <skipped message=\"{}\"/>", xml(why));
        }
        Outcome::Pass | Outcome::Warn(_) => {}
    }
    let mut text = String::new();
    for w in &c.warnings {
        let _ = writeln!(text, "WARNING: {w}");
    }
    for l in &c.limitations {
        let _ = writeln!(text, "not tested: {l}");
    }
    for l in &c.info {
        let _ = writeln!(text, "{l}");
    }
    if !text.is_empty() {
        let _ = writeln!(out, "      <system-out>{}</system-out>", xml(&text));
    }
    out.push_str("    </testcase>\n");
}

/// The report as JUnit XML.
pub fn junit(report: &Report) -> String {
    let name = fmu_name(report);
    let mut groups: Vec<(String, Vec<&CheckReport>)> = vec![];
    for c in &report.checks {
        let g = c.group.name().to_string();
        match groups.iter_mut().find(|(n, _)| *n == g) {
            Some((_, v)) => v.push(c),
            None => groups.push((g, vec![c])),
        }
    }
    let total_time: f64 = report.checks.iter().map(|c| c.duration.as_secs_f64()).sum();
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        out,
        "<testsuites name=\"cargo fmu check {}\" tests=\"{}\" failures=\"{}\" errors=\"0\" skipped=\"{}\" time=\"{total_time:.3}\">",
        xml(&report.fmu.display().to_string()),
        report.checks.len() + report.load_error.is_some() as usize,
        report.failed(),
        report.skipped()
    );
    if let Some(e) = &report.load_error {
        let _ = writeln!(
            out,
            "  <testsuite name=\"preflight\" tests=\"1\" failures=\"1\" errors=\"0\" skipped=\"0\" time=\"0\">\n    <testcase name=\"the_fmu_can_be_checked\" classname=\"{}.preflight\" time=\"0\">\n      <failure message=\"{}\" type=\"failed\">{}</failure>\n    </testcase>\n  </testsuite>",
            xml(&name),
            xml(first_line(e)),
            xml(e)
        );
    }
    for (group, checks) in &groups {
        let count = |word: &str| checks.iter().filter(|c| verdict(&c.outcome) == word).count();
        let time: f64 = checks.iter().map(|c| c.duration.as_secs_f64()).sum();
        let _ = writeln!(
            out,
            "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"0\" skipped=\"{}\" time=\"{time:.3}\">",
            xml(group),
            checks.len(),
            count("failed"),
            count("skipped")
        );
        let _ = writeln!(
            out,
            "    <properties><property name=\"fmu\" value=\"{}\"/><property name=\"strict\" value=\"{}\"/><property name=\"warned\" value=\"{}\"/></properties>",
            xml(&report.fmu.display().to_string()),
            report.strict,
            count("warned")
        );
        let class = format!("{name}.{}", group.replace([' ', '/'], "_"));
        for c in checks {
            testcase(&mut out, &class, c);
        }
        out.push_str("  </testsuite>\n");
    }
    out.push_str("</testsuites>\n");
    out
}

fn json_str(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

fn json_list(items: &[String]) -> String {
    format!("[{}]", items.iter().map(|s| json_str(s)).collect::<Vec<_>>().join(", "))
}

/// The report as JSON: the FMU, the run's head, the totals, and every check with its verdict,
/// message, warnings, parts not tested and figures.
pub fn json(report: &Report) -> String {
    let mut out = String::from("{\n");
    let _ = writeln!(out, "  \"fmu\": {},", json_str(&report.fmu.display().to_string()));
    let _ = writeln!(out, "  \"strict\": {},", report.strict);
    let _ = writeln!(out, "  \"about\": {},", json_list(&report.about));
    let _ = writeln!(
        out,
        "  \"load_error\": {},",
        report.load_error.as_deref().map_or("null".to_string(), json_str)
    );
    let _ = writeln!(
        out,
        "  \"totals\": {{\"passed\": {}, \"failed\": {}, \"warned\": {}, \"skipped\": {}}},",
        report.passed(),
        report.failed(),
        report.warned(),
        report.skipped()
    );
    out.push_str("  \"checks\": [");
    for (k, c) in report.checks.iter().enumerate() {
        let message = match &c.outcome {
            Outcome::Pass => "null".to_string(),
            Outcome::Fail(m) | Outcome::Warn(m) | Outcome::Skip(m) => json_str(m),
        };
        let _ = write!(
            out,
            "{}\n    {{\"name\": {}, \"group\": {}, \"verdict\": {}, \"message\": {message}, \"warnings\": {}, \"not_tested\": {}, \"info\": {}, \"seconds\": {:.3}}}",
            if k == 0 { "" } else { "," },
            json_str(&c.name),
            json_str(c.group.name()),
            json_str(verdict(&c.outcome)),
            json_list(&c.warnings),
            json_list(&c.limitations),
            json_list(&c.info),
            c.duration.as_secs_f64()
        );
    }
    out.push_str("\n  ]\n}\n");
    out
}

/// Writes the files a run was asked for (`--junit`, `--json`).
pub fn write_files(
    report: &Report,
    junit_file: Option<&std::path::Path>,
    json_file: Option<&std::path::Path>,
) -> Result<(), String> {
    if let Some(f) = junit_file {
        std::fs::write(f, junit(report)).map_err(|e| format!("--junit {}: {e}", f.display()))?;
    }
    if let Some(f) = json_file {
        std::fs::write(f, json(report)).map_err(|e| format!("--json {}: {e}", f.display()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checks::Group;
    use std::time::Duration;

    fn check(name: &str, outcome: Outcome, warnings: &[&str]) -> CheckReport {
        CheckReport {
            name: name.into(),
            group: Group::Calls,
            outcome,
            limitations: vec![],
            info: vec![],
            warnings: warnings.iter().map(|s| s.to_string()).collect(),
            duration: Duration::from_millis(5),
        }
    }

    #[test]
    fn each_verdict_has_its_junit_element_and_json_word_and_text_is_escaped() {
        let report = Report {
            fmu: "x/A<B>.fmu".into(),
            about: vec!["made \"here\"".into()],
            load_error: None,
            checks: vec![
                check("p", Outcome::Pass, &[]),
                check("f", Outcome::Fail("FMI 2.0.5 §2.1.3: a < b & \"c\"\nmore".into()), &[]),
                check("w", Outcome::Warn("w1".into()), &["w1"]),
                check("s", Outcome::Skip("not declared by the FMU: x".into()), &[]),
            ],
            strict: false,
        };
        let x = junit(&report);
        assert!(
            x.contains("tests=\"4\" failures=\"1\" errors=\"0\" skipped=\"1\""),
            "{x}"
        );
        assert!(
            x.contains("<failure message=\"FMI 2.0.5 §2.1.3: a &lt; b &amp; &quot;c&quot;\""),
            "{x}"
        );
        assert!(x.contains("<skipped message=\"not declared by the FMU: x\"/>"), "{x}");
        assert!(x.contains("<system-out>WARNING: w1\n</system-out>"), "{x}");
        assert!(x.contains("<property name=\"verdict\" value=\"warned\"/>"), "{x}");
        let j = json(&report);
        assert!(
            j.contains("\"totals\": {\"passed\": 1, \"failed\": 1, \"warned\": 1, \"skipped\": 1}"),
            "{j}"
        );
        assert!(j.contains("\"about\": [\"made \\\"here\\\"\"]"), "{j}");
        assert!(j.contains("a < b & \\\"c\\\"\\nmore"), "{j}");
    }
}
