//! The XML reading both versions share: events with their attributes unescaped, errors with
//! line and column.

use quick_xml::Reader;
use quick_xml::events::{BytesStart, Event};
use std::str::FromStr;

/// An element's name and attributes.
pub(crate) struct Element {
    pub name: Vec<u8>,
    attributes: Vec<(Vec<u8>, String)>,
}

impl Element {
    /// The attribute's value, unescaped; `None` where it is not written.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attributes
            .iter()
            .find(|(k, _)| k == name.as_bytes())
            .map(|(_, v)| v.as_str())
    }

    pub fn string(&self, name: &str) -> Option<String> {
        self.attr(name).map(str::to_owned)
    }

    /// An xs:boolean attribute: `true` only where it says "true" (or "1").
    pub fn flag(&self, name: &str) -> bool {
        matches!(self.attr(name), Some("true" | "1"))
    }

    /// A number, surrounding white space allowed; `None` where it is missing or no number.
    pub fn number<T: FromStr>(&self, name: &str) -> Option<T> {
        self.attr(name).and_then(|v| v.trim().parse().ok())
    }

    /// A white-space separated list of numbers (`dependencies`): `None` where the attribute is
    /// missing, the first entry that is no number as the error.
    pub fn list<T: FromStr>(&self, name: &str) -> Option<Result<Vec<T>, T::Err>> {
        self.attr(name)
            .map(|v| v.split_whitespace().map(str::parse).collect::<Result<Vec<T>, _>>())
    }
}

pub(crate) enum Node {
    /// An opening tag, and whether it is empty (`<a/>`: no end follows).
    Start(Element, bool),
    End(Vec<u8>),
    Eof,
}

pub(crate) struct Events<'a> {
    xml: &'a str,
    reader: Reader<&'a [u8]>,
}

impl<'a> Events<'a> {
    pub fn new(xml: &'a str) -> Events<'a> {
        Events {
            xml,
            reader: Reader::from_str(xml),
        }
    }

    /// `modelDescription.xml:line:column` of where the reader stands (after the last element).
    pub fn here(&self) -> String {
        let (line, col) = crate::line_column(self.xml, self.reader.buffer_position() as usize);
        format!("modelDescription.xml:{line}:{col}")
    }

    /// The next element event (text, comments and the like are passed over).
    pub fn next(&mut self) -> Result<Node, String> {
        loop {
            let event = self.reader.read_event().map_err(|e| {
                let (line, col) = crate::line_column(self.xml, self.reader.error_position() as usize);
                format!("modelDescription.xml:{line}:{col}: {e}")
            })?;
            return Ok(match event {
                Event::Eof => Node::Eof,
                Event::Start(e) => Node::Start(self.element(&e)?, false),
                Event::Empty(e) => Node::Start(self.element(&e)?, true),
                Event::End(e) => Node::End(e.name().as_ref().to_vec()),
                _ => continue,
            });
        }
    }

    fn element(&self, e: &BytesStart) -> Result<Element, String> {
        let mut attributes = vec![];
        for a in e.attributes() {
            let a = a.map_err(|err| format!("{}: bad attribute: {err}", self.here()))?;
            let value = a
                .unescape_value()
                .map_err(|err| format!("{}: bad attribute value: {err}", self.here()))?;
            attributes.push((a.key.as_ref().to_vec(), value.into_owned()));
        }
        Ok(Element {
            name: e.name().as_ref().to_vec(),
            attributes,
        })
    }
}
