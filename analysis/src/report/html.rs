//! A self-contained HTML page: sections of prose, tables and inline SVG figures.

use std::fmt::Write;

/// Escape text for HTML.
pub fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A figure: its file name beside the page, its SVG and its size in pixels.
pub struct Figure {
    pub file: String,
    pub svg: String,
    pub caption: String,
}

impl Figure {
    /// The (width, height) the SVG declares on its root element.
    pub fn size(&self) -> Option<(u32, u32)> {
        svg_size(&self.svg)
    }
}

/// Width and height attributes of the root `<svg>` element.
pub fn svg_size(svg: &str) -> Option<(u32, u32)> {
    let start = svg.find("<svg")?;
    let end = start + svg[start..].find('>')?;
    let tag = &svg[start..end];
    let attr = |name: &str| -> Option<u32> {
        let key = format!(" {name}=\"");
        let i = tag.find(&key)? + key.len();
        let j = i + tag[i..].find('"')?;
        tag[i..j].trim_end_matches("px").parse().ok()
    };
    Some((attr("width")?, attr("height")?))
}

/// The page being built.
#[derive(Default)]
pub struct Page {
    body: String,
}

impl Page {
    pub fn heading(&mut self, level: u8, text: &str) {
        let _ = writeln!(self.body, "<h{level}>{}</h{level}>", escape(text));
    }

    pub fn paragraph(&mut self, text: &str) {
        let _ = writeln!(self.body, "<p>{}</p>", escape(text));
    }

    /// A paragraph of trusted inline HTML (built by this module's callers from escaped parts).
    pub fn raw(&mut self, html: &str) {
        self.body.push_str(html);
        self.body.push('\n');
    }

    pub fn preformatted(&mut self, text: &str) {
        let _ = writeln!(self.body, "<pre>{}</pre>", escape(text));
    }

    pub fn table(&mut self, header: &[&str], rows: &[Vec<String>]) {
        let _ = write!(self.body, "<table><thead><tr>");
        for h in header {
            let _ = write!(self.body, "<th>{}</th>", escape(h));
        }
        let _ = write!(self.body, "</tr></thead><tbody>");
        for r in rows {
            let _ = write!(self.body, "<tr>");
            for c in r {
                let _ = write!(self.body, "<td>{}</td>", escape(c));
            }
            let _ = write!(self.body, "</tr>");
        }
        let _ = writeln!(self.body, "</tbody></table>");
    }

    /// The figure inline, with a link to its file.
    pub fn figure(&mut self, fig: &Figure) {
        let (w, h) = fig.size().unwrap_or((0, 0));
        let _ = writeln!(
            self.body,
            "<figure data-file=\"{}\" data-width=\"{w}\" data-height=\"{h}\">{}<figcaption>{} \
             (<a href=\"{}\">{}</a>)</figcaption></figure>",
            escape(&fig.file),
            fig.svg,
            escape(&fig.caption),
            escape(&fig.file),
            escape(&fig.file)
        );
    }

    /// The whole document.
    pub fn finish(self, title: &str) -> String {
        format!(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\
             <style>body{{font-family:sans-serif;max-width:1250px;margin:auto;padding:1em;line-height:1.45}}\
             table{{border-collapse:collapse;margin:0.5em 0}}td,th{{border:1px solid #bbb;padding:2px 8px;\
             font-size:0.9em;text-align:right}}th{{background:#eee}}pre{{background:#f6f6f6;padding:0.5em;\
             overflow-x:auto;font-size:0.85em}}figure{{margin:1em 0}}figcaption{{font-size:0.9em;color:#444}}\
             svg{{max-width:100%;height:auto}}</style></head><body>\n{}</body></html>\n",
            escape(title),
            self.body
        )
    }
}
