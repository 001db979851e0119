//! Just enough XML for `modelDescription.xml`: elements with escaped attributes, indented.

use std::fmt::Write;

/// Text as an XML attribute value (`&`, `<`, `>`, `"`, `'` and control characters escaped).
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "&#x{:X};", c as u32);
            }
            c => out.push(c),
        }
    }
    out
}

/// An XML document being written.
#[derive(Default)]
pub struct Writer {
    text: String,
    depth: usize,
}

impl Writer {
    /// A document with the XML declaration.
    pub fn new() -> Self {
        Writer {
            text: "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n".into(),
            depth: 0,
        }
    }

    fn tag(&mut self, name: &str, attributes: &[(&str, String)], close: &str) {
        let _ = write!(self.text, "{:indent$}<{name}", "", indent = 2 * self.depth);
        for (key, value) in attributes {
            let _ = write!(self.text, " {key}=\"{}\"", escape(value));
        }
        self.text.push_str(close);
        self.text.push('\n');
    }

    /// `<name …/>`.
    pub fn empty(&mut self, name: &str, attributes: &[(&str, String)]) {
        self.tag(name, attributes, "/>");
    }

    /// `<name …>`: the children follow until [`close`](Self::close).
    pub fn open(&mut self, name: &str, attributes: &[(&str, String)]) {
        self.tag(name, attributes, ">");
        self.depth += 1;
    }

    /// `</name>`.
    pub fn close(&mut self, name: &str) {
        self.depth = self.depth.saturating_sub(1);
        let _ = writeln!(
            self.text,
            "{:indent$}</{name}>",
            "",
            indent = 2 * self.depth
        );
    }

    /// The document.
    pub fn finish(self) -> String {
        self.text
    }
}
