//! The two backends: SVG (drawn at SUPERSAMPLE ×, declared at 1×) and PNG (drawn by plotters'
//! bitmap backend at PNG_SCALE ×, encoded by the png crate).

use std::sync::OnceLock;

use plotters::prelude::*;
use plotters::style::FontStyle;

use super::{Figure, PlotError, PNG_SCALE, SUPERSAMPLE};

fn error(fig: &Figure, message: impl std::fmt::Display) -> PlotError {
    PlotError {
        title: fig.title().to_string(),
        message: message.to_string(),
    }
}

/// The SVG of `fig`.
pub fn svg(fig: &Figure) -> Result<String, PlotError> {
    // Text is laid out with the same font as the PNG's.
    register_font().map_err(|e| error(fig, e))?;
    let (w, h) = fig.size();
    let k = SUPERSAMPLE;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w * k, h * k)).into_drawing_area();
        fig.draw(&root, k).map_err(|e| error(fig, e))?;
        root.present().map_err(|e| error(fig, e))?;
    }
    let (sw, sh) = (w * k, h * k);
    Ok(svg.replacen(
        &format!("width=\"{sw}\" height=\"{sh}\" viewBox=\"0 0 {sw} {sh}\""),
        &format!("width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {sw} {sh}\""),
        1,
    ))
}

/// Font files tried for the PNG's text, Debian's DejaVu Sans first (on every machine of this
/// kind); the SVG needs none (its text is text).
const FONT_FILES: [&str; 4] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
];

/// Registers a sans-serif font with plotters' ab_glyph text once; the error names the files
/// tried.
fn register_font() -> Result<(), String> {
    static FONT: OnceLock<Result<(), String>> = OnceLock::new();
    FONT.get_or_init(|| {
        let bytes = FONT_FILES
            .iter()
            .find_map(|f| std::fs::read(f).ok())
            .ok_or_else(|| {
                format!(
                    "no font for the PNG text: none of {}",
                    FONT_FILES.join(", ")
                )
            })?;
        // plotters keeps fonts for the life of the program; one leak, once.
        let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
        plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
            .map_err(|_| "the font file does not parse".to_string())
    })
    .clone()
}

/// The PNG of `fig`.
pub fn png(fig: &Figure) -> Result<Vec<u8>, PlotError> {
    register_font().map_err(|e| error(fig, e))?;
    let (w, h) = fig.size();
    let k = PNG_SCALE;
    let (pw, ph) = (w * k, h * k);
    let mut rgb = vec![0u8; (pw * ph * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (pw, ph)).into_drawing_area();
        fig.draw(&root, k).map_err(|e| error(fig, e))?;
        root.present().map_err(|e| error(fig, e))?;
    }
    let mut out = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut out, pw, ph);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| error(fig, e))?;
        writer.write_image_data(&rgb).map_err(|e| error(fig, e))?;
    }
    Ok(out)
}
