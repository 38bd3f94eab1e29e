//! `documentation/index.html`: what the FMU is (FMI version, interfaces, the platforms its
//! binaries are for), the variables with units, and the crate's own documentation fragment
//! (`[package.metadata.fmu] documentation`).

use rustfmu::description::{FmiVersion, Interfaces, ModelDescription, Start, VarType};

fn escape(s: &str) -> String {
    quick_xml::escape::escape(s).into_owned()
}

/// What the FMU is, in one phrase: "FMI 2.0 FMU for model exchange and co-simulation".
fn kind(interfaces: Interfaces) -> String {
    let version = match interfaces.version {
        FmiVersion::V2 => "FMI 2.0",
        FmiVersion::V3 => "FMI 3.0",
    };
    let what = match (interfaces.model_exchange, interfaces.co_simulation) {
        (true, true) => "model exchange and co-simulation",
        (true, false) => "model exchange",
        (false, true) => "co-simulation",
        (false, false) => "no interface",
    };
    format!("{version} FMU for {what}")
}

/// `platforms`: the folders of `binaries/` the FMU has (`linux64`, `x86_64-windows`, ...).
/// `picture`: the default experiment as SVG ([`crate::plot`]), shown above the variables.
pub fn index_html(
    d: &ModelDescription,
    fragment: &str,
    interfaces: Interfaces,
    platforms: &[String],
    picture: Option<&str>,
) -> String {
    let mut rows = String::new();
    for v in d.variables {
        let start = if v.has_start() {
            match v.start {
                Start::Real(x) if v.var_type == VarType::Float32 => format!("{:?}", x as f32),
                Start::Real(x) => format!("{x:?}"),
                Start::Int64(x) => x.to_string(),
                Start::UInt64(x) => x.to_string(),
                Start::Binary(b) => format!("0x{}", b.iter().map(|x| format!("{x:02x}")).collect::<String>()),
                Start::Array(items) => format!("{} values", items.len()),
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
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{:?}</td><td>{:?}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            escape(v.name),
            v.value_reference,
            v.var_type.fmi3_name(),
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
         <h1>{id}</h1>\n<p>{description}</p>\n<p>{kind}, version {version}, built by {tool}.</p>\n<p>Binaries for: {platforms}.</p>\n{picture}\
         <h2>Variables</h2>\n<table><tr><th>name</th><th>value reference</th><th>type</th><th>causality</th><th>variability</th>\
         <th>unit</th><th>start</th><th>description</th></tr>\n{rows}</table>\n{fragment}\n</body></html>\n",
        id = escape(d.model_identifier),
        description = escape(d.description),
        version = escape(d.version),
        tool = escape(d.generation_tool),
        kind = kind(interfaces),
        platforms = escape(&platforms.join(", ")),
        picture = match picture {
            Some(svg) => format!("<h2>Default experiment</h2>\n<figure>\n{svg}</figure>\n"),
            None => String::new(),
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 23: the page said "FMI 2.0 co-simulation FMU" of an FMU that is model exchange and
    /// co-simulation, and named no platform.
    #[test]
    fn the_page_says_what_the_fmu_is_and_its_platforms() {
        let d = ModelDescription {
            model_identifier: "Lag",
            description: "A lag",
            author: "",
            version: "0.1.0",
            copyright: "",
            license: "",
            generation_tool: "rustfmu",
            default_experiment: None,
            units: &[],
            log_categories: &[],
            variables: &[],
            internal_state: "",
            event_indicators: &[],
            terminals: &[],
            bus_simulation: false,
        };
        let both = Interfaces {
            co_simulation: true,
            model_exchange: true,
            version: FmiVersion::V2,
            can_interpolate_inputs: false,
            scheduled_execution: false,
        };
        let html = index_html(&d, "", both, &["linux64".into(), "win64".into()], None);
        assert!(
            html.contains("FMI 2.0 FMU for model exchange and co-simulation"),
            "{html}"
        );
        assert!(html.contains("Binaries for: linux64, win64."), "{html}");
        let cs3 = Interfaces {
            co_simulation: true,
            model_exchange: false,
            version: FmiVersion::V3,
            can_interpolate_inputs: false,
            scheduled_execution: false,
        };
        let html = index_html(&d, "", cs3, &["x86_64-linux".into()], Some("<svg></svg>"));
        assert!(html.contains("FMI 3.0 FMU for co-simulation"), "{html}");
    }
}
