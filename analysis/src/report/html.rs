//! A self-contained HTML page: sections of prose, tables and inline SVG figures.

use std::fmt::Write;

/// Escape text for HTML.
pub fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A figure: its file name beside the page, its SVG (inlined) and PNG, and its caption.
pub struct Figure {
    pub file: String,
    pub svg: String,
    pub png: Vec<u8>,
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

/// The technical detail behind a summary line, one click away.
fn more(text: &str) -> String {
    if text.is_empty() {
        String::new()
    } else {
        format!(
            " <details><summary>details</summary>{}</details>",
            escape(text)
        )
    }
}

/// A cell that reads as a number (with at most a unit after it), right-aligned in tables.
fn is_number(cell: &str) -> bool {
    let first = cell.split_whitespace().next().unwrap_or("");
    let digits = first.trim_start_matches(['+', '-', '−', '[', '(']);
    cell.split_whitespace().count() <= 2
        && digits
            .chars()
            .next()
            .is_some_and(|c| c.is_ascii_digit() || c == '.')
}

/// The widest the page's text column gets [px] (a comfortable line length for prose); figures
/// are shown at their own width up to this, and scaled down to it beyond.
pub const PAGE_WIDTH: u32 = 1000;

/// The page's padding on each side [px].
pub const PAGE_PADDING: u32 = 16;

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

    /// A table: numbers right-aligned (their digits line up), words left-aligned.
    pub fn table(&mut self, header: &[&str], rows: &[Vec<String>]) {
        let _ = write!(self.body, "<table><thead><tr>");
        for h in header {
            let _ = write!(self.body, "<th>{}</th>", escape(h));
        }
        let _ = write!(self.body, "</tr></thead><tbody>");
        for r in rows {
            let _ = write!(self.body, "<tr>");
            for c in r {
                let class = if is_number(c) { " class=\"n\"" } else { "" };
                let _ = write!(self.body, "<td{class}>{}</td>", escape(c));
            }
            let _ = write!(self.body, "</tr>");
        }
        let _ = writeln!(self.body, "</tbody></table>");
    }

    /// The summary at the top: failed checks first (in a red box), then every check and finding
    /// with its verdict.
    pub fn summary(&mut self, checks: &[super::Check], findings: &[super::Finding]) {
        let failed: Vec<&super::Check> = checks.iter().filter(|c| !c.passed).collect();
        if !failed.is_empty() {
            let _ = write!(
                self.body,
                "<div class=\"failed\"><strong>{} check(s) FAILED</strong> — the results below \
                 rest on them:<ul>",
                failed.len()
            );
            for c in &failed {
                let _ = write!(
                    self.body,
                    "<li><strong>{}</strong>: {}</li>",
                    escape(&c.name),
                    escape(&c.detail)
                );
            }
            let _ = writeln!(self.body, "</ul></div>");
        }
        let _ = write!(
            self.body,
            "<div class=\"summary\"><h2>Summary of findings</h2><ul>"
        );
        for c in checks {
            let _ = write!(
                self.body,
                "<li class=\"{}\"><strong>check — {}: {}</strong>. {}{}</li>",
                if c.passed { "pass" } else { "fail" },
                escape(&c.name),
                if c.passed { "passed" } else { "FAILED" },
                escape(&c.detail),
                more(&c.more)
            );
        }
        for f in findings {
            let _ = write!(
                self.body,
                "<li><strong>{}: {}</strong>. {}{}</li>",
                escape(&f.topic),
                escape(&f.verdict),
                escape(&f.text),
                more(&f.more)
            );
        }
        let _ = writeln!(self.body, "</ul></div>");
    }

    /// The figure inline at its own size (never wider than the page), with links to its SVG
    /// and PNG files.
    pub fn figure(&mut self, fig: &Figure) {
        let (w, h) = fig.size().unwrap_or((0, 0));
        let png = format!("{}.png", fig.file.trim_end_matches(".svg"));
        let _ = writeln!(
            self.body,
            "<figure data-file=\"{}\" data-width=\"{w}\" data-height=\"{h}\" \
             style=\"max-width:{w}px\">{}<figcaption>{} (<a href=\"{}\">SVG</a>, \
             <a href=\"{}\">PNG</a>)</figcaption></figure>",
            escape(&fig.file),
            fig.svg,
            escape(&fig.caption),
            escape(&fig.file),
            escape(&png)
        );
    }

    /// The whole document.
    pub fn finish(self, title: &str) -> String {
        format!(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\
             <style>body{{font-family:sans-serif;max-width:{PAGE_WIDTH}px;margin:auto;padding:{PAGE_PADDING}px;line-height:1.45}}\
             table{{border-collapse:collapse;margin:0.5em 0}}td,th{{border:1px solid #bbb;padding:2px 8px;\
             font-size:0.9em;text-align:left}}td.n{{text-align:right}}th{{background:#eee}}\
             details{{display:inline}}summary{{cursor:pointer;color:#446}}pre{{background:#f6f6f6;padding:0.5em;\
             overflow-x:auto;font-size:0.85em}}figure{{margin:1em 0}}figcaption{{font-size:0.9em;color:#444}}\
             figure svg{{width:100%;height:auto}}.failed{{border:2px solid #c00;background:#fee;\
             padding:0.5em 1em;margin:1em 0}}.summary{{background:#f4f8ff;padding:0.3em 1em;\
             margin:1em 0}}li.fail{{color:#a00}}</style></head><body>\n{}</body></html>\n",
            escape(title),
            self.body
        )
    }
}
