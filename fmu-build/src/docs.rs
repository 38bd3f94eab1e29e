//! `documentation/index.html`: the variables with units, and the crate's own documentation
//! fragment (`[package.metadata.fmu] documentation`).

use rustfmu::description::{FmiVersion, ModelDescription, Start};

fn escape(s: &str) -> String {
    quick_xml::escape::escape(s).into_owned()
}

pub fn index_html(d: &ModelDescription, fragment: &str, version: FmiVersion) -> String {
    let mut rows = String::new();
    for v in d.variables {
        let start = if v.has_start() {
            match v.start {
                Start::Real(x) => format!("{x:?}"),
                Start::Integer(x) => match v.enumeration.and_then(|e| e.item(x)) {
                    Some(item) => format!("{x} ({})", item.name),
                    None => x.to_string(),
                },
                Start::Boolean(x) => x.to_string(),
                Start::String(s) => format!("\"{s}\""),
                Start::None => String::new(),
            }
        } else {
            String::new()
        };
        rows.push_str(&format!(
            "<tr><td><code>{}</code></td><td>{}</td><td>{:?}</td><td>{:?}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            escape(v.name),
            v.value_reference,
            v.causality,
            v.variability,
            escape(v.unit),
            escape(&start),
            escape(v.description.trim())
        ));
    }
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{id}</title>\
         <style>body{{font-family:sans-serif;max-width:60em;margin:auto}}td,th{{padding:2px 8px;text-align:left}}\
         tr:nth-child(even){{background:#f3f3f3}}pre{{background:#f6f6f6;padding:8px}}</style></head><body>\n\
         <h1>{id}</h1>\n<p>{description}</p>\n<p>{kind}, version {version}, built by {tool}.</p>\n\
         <h2>Variables</h2>\n<table><tr><th>name</th><th>value reference</th><th>causality</th><th>variability</th>\
         <th>unit</th><th>start</th><th>description</th></tr>\n{rows}</table>\n{fragment}\n</body></html>\n",
        id = escape(d.model_identifier),
        description = escape(d.description),
        version = escape(d.version),
        tool = escape(d.generation_tool),
        kind = match version {
            FmiVersion::V2 => "FMI 2.0 co-simulation FMU",
            FmiVersion::V3 => "FMI 3.0 FMU (model exchange and co-simulation)",
        },
    )
}
