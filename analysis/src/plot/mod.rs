//! Figures: each one a value ([`Figure`]) that draws itself with plotters on any backend, so
//! the same drawing gives the SVG (text stays text; the HTML report inlines it) and the PNG
//! beside it (plotters' bitmap backend, glyphs by ab_glyph, encoded by the png crate).
//!
//! Every text is at least 12 px at the size a figure declares; the SVG is drawn at
//! [`SUPERSAMPLE`] times that size and scaled back by its viewBox, because plotters places
//! everything on whole pixels (at 1× lines look stepped).

mod grid;
mod heatmap;
mod line;
mod render;

pub use grid::Grid;
pub use heatmap::{zero_contour, HeatMap, Mark, Segment};
pub use line::{Curve, LineChart};

use plotters::coord::Shift;
use plotters::prelude::*;

/// Why a figure could not be drawn.
#[derive(Debug, thiserror::Error)]
#[error("cannot draw figure `{title}`: {message}")]
pub struct PlotError {
    pub title: String,
    pub message: String,
}

/// The SVG is drawn at this multiple of its declared size.
pub const SUPERSAMPLE: u32 = 4;

/// The PNG is this multiple of the declared size (sharp on high-density screens and in print).
pub const PNG_SCALE: u32 = 2;

/// Font sizes at the declared (1×) size, as plotters takes them: it draws text at 1/1.24 of
/// the size given, so these are 16.9, 13.7 and 12.1 px tall glyph boxes — at least 10 px even
/// where the report scales its widest figure (1120 px) to its 1000 px column
/// (`tests/all/report.rs` holds every figure to that).
pub(crate) const TITLE_PX: u32 = 21;
pub(crate) const LABEL_PX: u32 = 17;
pub(crate) const TICK_PX: u32 = 15;

/// A font of `px` (at 1×) on a canvas drawn at `k` ×.
pub(crate) fn font(px: u32, k: u32) -> (&'static str, u32) {
    ("sans-serif", px * k)
}

/// A tick label as plotters prints it, but never "-0.0": a key point a rounding error below zero
/// reads as zero.
///
/// ```
/// use twv_analysis::plot::tick;
/// assert_eq!(tick(&-1e-17), "0.0");
/// assert_eq!(tick(&-0.0), "0.0");
/// assert_eq!(tick(&-0.2), "-0.2");
/// assert_eq!(tick(&400.0), "400.0");
/// ```
pub fn tick(value: &f64) -> String {
    use plotters::coord::ranged1d::ValueFormatter;
    let text = plotters::coord::types::RangedCoordf64::format(value);
    match text.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
        _ => text,
    }
}

/// The whole decades around `lo..hi` (both > 0), the range of a logarithmic axis: its labels are
/// the decades, so a range that starts or ends between two would leave its ends unlabelled.
///
/// ```
/// use twv_analysis::plot::decades;
/// assert_eq!(decades(0.125, 30.0), (0.1, 100.0));
/// assert_eq!(decades(0.1, 10.0), (0.1, 10.0));
/// assert_eq!(decades(2.0, 3.0), (1.0, 10.0));
/// ```
pub fn decades(lo: f64, hi: f64) -> (f64, f64) {
    let decade = |e: f64| power_of_ten(e as i32);
    (decade(lo.log10().floor()), decade(hi.log10().ceil()))
}

/// A decade's label as a person writes it ("0.01", "1", "1000", "1e6"), whatever rounding its
/// key point carries.
///
/// ```
/// use twv_analysis::plot::decade_label;
/// assert_eq!(decade_label(&0.1), "0.1");
/// assert_eq!(decade_label(&(0.1 * 10.0 * 10.0)), "10");
/// assert_eq!(decade_label(&1e-5), "1e-5");
/// assert_eq!(decade_label(&1e6), "1e6");
/// ```
pub fn decade_label(value: &f64) -> String {
    let e = value.log10().round() as i32;
    if (-3..=4).contains(&e) {
        power_of_ten(e).to_string()
    } else {
        format!("1e{e}")
    }
}

/// 10^e, correctly rounded (the parse of its decimal text).
fn power_of_ten(e: i32) -> f64 {
    format!("1e{e}").parse().unwrap_or(f64::NAN)
}

/// A drawing area of any backend.
pub(crate) type Area<'a, DB> = DrawingArea<DB, Shift>;

/// A drawing error of any backend.
pub(crate) type DrawResult<DB> =
    Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// Any figure twv draws.
#[derive(Debug, Clone, PartialEq)]
pub enum Figure {
    /// Curves against one x axis.
    Line(LineChart),
    /// A heat map over a grid with its stability boundary.
    Heat(HeatMap),
    /// Several line charts side by side.
    Grid(Grid),
}

impl Figure {
    /// Its title (for errors).
    pub fn title(&self) -> &str {
        match self {
            Figure::Line(f) => &f.title,
            Figure::Heat(f) => &f.title,
            Figure::Grid(f) => f.title(),
        }
    }

    /// The declared size [px].
    pub fn size(&self) -> (u32, u32) {
        match self {
            Figure::Line(f) => f.size,
            Figure::Heat(f) => f.size,
            Figure::Grid(f) => f.size(),
        }
    }

    /// Draws onto `area` at `k` × the declared size.
    pub(crate) fn draw<DB: DrawingBackend>(&self, area: &Area<DB>, k: u32) -> DrawResult<DB> {
        match self {
            Figure::Line(f) => f.draw(area, k),
            Figure::Heat(f) => f.draw(area, k),
            Figure::Grid(f) => f.draw(area, k),
        }
    }

    /// The figure as an SVG document.
    pub fn svg(&self) -> Result<String, PlotError> {
        render::svg(self)
    }

    /// The figure as a PNG image at [`PNG_SCALE`] × its declared size.
    pub fn png(&self) -> Result<Vec<u8>, PlotError> {
        render::png(self)
    }
}

pub(crate) fn bounds<'a>(series: impl Iterator<Item = &'a (f64, f64)>) -> ((f64, f64), (f64, f64)) {
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in series.filter(|(x, y)| x.is_finite() && y.is_finite()) {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if !x0.is_finite() {
        return ((0.0, 1.0), (0.0, 1.0));
    }
    let pad = |a: f64, b: f64| {
        let span = if b > a { b - a } else { a.abs().max(1.0) };
        (a - 0.05 * span, b + 0.05 * span)
    };
    (pad(x0, x1), pad(y0, y1))
}

/// Palette that stays readable for up to ten curves.
pub(crate) const COLORS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];
