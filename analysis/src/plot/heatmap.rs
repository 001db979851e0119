//! Heat maps of a scalar over a rectangular grid (a stability map over two gains), with a
//! colour bar and a boundary drawn as the zero contour of a second field (marching squares).

use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{font, tick, Area, DrawResult, LABEL_PX, TICK_PX, TITLE_PX};

/// A heat map's data and labels. `values` and `boundary` are row-major over (`ys`, `xs`):
/// entry `j·xs.len() + i` belongs to (xs[i], ys[j]). A cell without a value (NaN) is drawn in
/// the colour of its `missing` label (`fell`, `blew up`, …), which the legend names; the
/// boundary is where `boundary` changes sign (NaN cells are skipped).
#[derive(Debug, Clone, PartialEq)]
pub struct HeatMap {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub value_label: String,
    pub xs: Vec<f64>,
    pub ys: Vec<f64>,
    pub values: Vec<f64>,
    /// Why a cell has no value (`None` where it has one).
    pub missing: Vec<Option<&'static str>>,
    pub boundary: Vec<f64>,
    /// A signed quantity whose sign means stable (< 0) or unstable (> 0): drawn on a diverging
    /// scale centred on 0 (blue stable, red unstable); otherwise a sequential scale.
    pub signed: bool,
    /// Vertical lines at these x values, labelled (a bicycle's weave and capsize speeds).
    pub marks: Vec<Mark>,
    pub size: (u32, u32),
}

/// A labelled vertical line across a heat map.
#[derive(Debug, Clone, PartialEq)]
pub struct Mark {
    pub x: f64,
    pub label: String,
}

/// A line segment in data coordinates.
pub type Segment = [(f64, f64); 2];

/// The zero contour of `field` (row-major over (`ys`, `xs`)) by marching squares with linear
/// interpolation along cell edges; saddle cells are resolved by the cell-centre average.
/// "Negative" is the stable side (< 0), zero counts as non-negative.
pub fn zero_contour(xs: &[f64], ys: &[f64], field: &[f64]) -> Vec<Segment> {
    let nx = xs.len();
    let at = |i: usize, j: usize| field[j * nx + i];
    let mut out = Vec::new();
    for j in 0..ys.len().saturating_sub(1) {
        for i in 0..nx.saturating_sub(1) {
            // Corners counter-clockwise from bottom-left.
            let p = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let v = p.map(|(i, j)| at(i, j));
            if v.iter().any(|v| v.is_nan()) {
                continue;
            }
            let pt = |(i, j): (usize, usize)| (xs[i], ys[j]);
            // Edges bottom, right, top, left as corner pairs.
            let mut cross = [None; 4];
            for (e, (a, b)) in [(0, 1), (1, 2), (3, 2), (0, 3)].into_iter().enumerate() {
                if (v[a] < 0.0) != (v[b] < 0.0) {
                    let t = v[a] / (v[a] - v[b]);
                    let (pa, pb) = (pt(p[a]), pt(p[b]));
                    cross[e] = Some((pa.0 + t * (pb.0 - pa.0), pa.1 + t * (pb.1 - pa.1)));
                }
            }
            let found: Vec<(usize, (f64, f64))> = cross
                .iter()
                .enumerate()
                .filter_map(|(e, c)| c.map(|c| (e, c)))
                .collect();
            match found.len() {
                2 => out.push([found[0].1, found[1].1]),
                4 => {
                    let c = |e: usize| cross[e].expect("four crossings");
                    let centre = v.iter().sum::<f64>() / 4.0;
                    if (centre < 0.0) == (v[0] < 0.0) {
                        out.push([c(0), c(1)]);
                        out.push([c(2), c(3)]);
                    } else {
                        out.push([c(0), c(3)]);
                        out.push([c(1), c(2)]);
                    }
                }
                _ => {}
            }
        }
    }
    out
}

/// Viridis, by five stops: the sequential scale.
fn viridis(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    ramp(&STOPS, t)
}

/// Blue (t = 0) through white (½) to red (1): the diverging scale (ColorBrewer RdBu).
fn diverging(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (33.0, 102.0, 172.0),
        (146.0, 197.0, 222.0),
        (247.0, 247.0, 247.0),
        (244.0, 165.0, 130.0),
        (178.0, 24.0, 43.0),
    ];
    ramp(&STOPS, t)
}

fn ramp(stops: &[(f64, f64, f64); 5], t: f64) -> RGBColor {
    let s = t.clamp(0.0, 1.0) * (stops.len() - 1) as f64;
    let k = (s.floor() as usize).min(stops.len() - 2);
    let f = s - k as f64;
    let (a, b) = (stops[k], stops[k + 1]);
    let mix = |x: f64, y: f64| (x + f * (y - x)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// The colour scale of a map over [lo, hi]: diverging with 0 at its white centre (each side
/// stretched to its own extreme, so both are visible), or sequential.
struct Scale {
    lo: f64,
    hi: f64,
    signed: bool,
}

impl Scale {
    fn colour(&self, v: f64) -> RGBColor {
        if self.signed {
            let t = if v < 0.0 {
                0.5 - 0.5 * (v / self.lo.min(-f64::MIN_POSITIVE)).min(1.0)
            } else {
                0.5 + 0.5 * (v / self.hi.max(f64::MIN_POSITIVE)).min(1.0)
            };
            diverging(t)
        } else {
            viridis((v - self.lo) / (self.hi - self.lo))
        }
    }
}

/// The colour of a cell without a value, by why.
fn missing_colour(label: &str) -> RGBColor {
    match label {
        "fell" => RGBColor(64, 64, 64),
        "blew up" => RGBColor(0, 0, 0),
        "not settled" => RGBColor(170, 170, 170),
        _ => RGBColor(215, 200, 225),
    }
}

/// Half the distance to the neighbours of `v[i]` on each side (a cell around each grid value).
fn cell(v: &[f64], i: usize) -> (f64, f64) {
    let step = |a: usize, b: usize| (v[b] - v[a]).abs() / 2.0;
    let default = if v.len() > 1 { step(0, 1) } else { 0.5 };
    let lo = if i > 0 { step(i - 1, i) } else { default };
    let hi = if i + 1 < v.len() { step(i, i + 1) } else { lo };
    (v[i] - lo, v[i] + hi)
}

/// Width of the colour bar and legend column [px at 1×].
const SIDE_W: u32 = 210;

impl HeatMap {
    /// Draws onto `area` (of this map's size times `k`): cells coloured by value, cells without
    /// a value by why (named in the legend), the zero contour of `boundary` in black, and a
    /// colour bar.
    pub(crate) fn draw<DB: DrawingBackend>(&self, area: &Area<DB>, k: u32) -> DrawResult<DB> {
        let h = self;
        let (nx, ny) = (h.xs.len(), h.ys.len());
        let n = nx * ny;
        if nx == 0
            || ny == 0
            || h.values.len() != n
            || h.boundary.len() != n
            || h.missing.len() != n
        {
            return Err(DrawingAreaErrorKind::LayoutError);
        }
        let finite = h.values.iter().copied().filter(|v| v.is_finite());
        let (mut lo, mut hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        if !lo.is_finite() {
            (lo, hi) = (0.0, 1.0);
        } else if hi <= lo {
            (lo, hi) = (lo - 0.5, hi + 0.5);
        }
        if h.signed {
            (lo, hi) = (lo.min(0.0), hi.max(0.0));
        }
        let scale = Scale {
            lo,
            hi,
            signed: h.signed,
        };
        let (x0, x1) = (cell(&h.xs, 0).0, cell(&h.xs, nx - 1).1);
        let (y0, y1) = (cell(&h.ys, 0).0, cell(&h.ys, ny - 1).1);
        let mut labels: Vec<&str> = h.missing.iter().flatten().copied().collect();
        labels.sort_unstable();
        labels.dedup();
        let (width, height) = area.dim_in_pixel();
        area.fill(&WHITE)?;
        let root = area
            .margin(6 * k, 0, 0, 0)
            .titled(&h.title, font(TITLE_PX, k))?;
        let (main, side) = root.split_horizontally(width.saturating_sub(SIDE_W * k));
        let mut ctx = ChartBuilder::on(&main)
            .margin(8 * k)
            .x_label_area_size(50 * k)
            .y_label_area_size(80 * k)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        ctx.configure_mesh()
            .disable_mesh()
            .x_label_formatter(&tick)
            .y_label_formatter(&tick)
            .x_desc(&h.x_label)
            .y_desc(&h.y_label)
            .label_style(font(TICK_PX, k))
            .axis_desc_style(font(LABEL_PX, k))
            .axis_style(BLACK.stroke_width(k))
            .draw()?;
        let cells = (0..ny)
            .flat_map(|j| (0..nx).map(move |i| (i, j)))
            .map(|(i, j)| {
                let idx = j * nx + i;
                let v = h.values[idx];
                let c = match h.missing[idx] {
                    Some(label) => missing_colour(label),
                    None if v.is_finite() => scale.colour(v),
                    None => missing_colour(""),
                };
                let ((a, b), (c0, d)) = (cell(&h.xs, i), cell(&h.ys, j));
                Rectangle::new([(a, c0), (b, d)], c.filled())
            });
        ctx.draw_series(cells)?;
        let lines = zero_contour(&h.xs, &h.ys, &h.boundary)
            .into_iter()
            .map(|[p, q]| PathElement::new(vec![p, q], BLACK.stroke_width(3 * k)));
        ctx.draw_series(lines)?;
        for m in h.marks.iter().filter(|m| m.x >= x0 && m.x <= x1) {
            ctx.draw_series(std::iter::once(DashedPathElement::new(
                vec![(m.x, y0), (m.x, y1)],
                8 * k,
                6 * k,
                RGBColor(40, 40, 40).stroke_width(2 * k),
            )))?;
            ctx.draw_series(std::iter::once(Text::new(
                m.label.clone(),
                (m.x, y1),
                font(TICK_PX, k)
                    .into_font()
                    .color(&RGBColor(20, 20, 20))
                    .pos(Pos::new(HPos::Left, VPos::Top)),
            )))?;
        }

        // The colour bar above the legend of the cells without a value.
        let legend_h = (LABEL_PX + 10) * k * (labels.len() as u32 + 1);
        let (bar, legend) = side.split_vertically(height.saturating_sub(60 * k + legend_h));
        let mut cb = ChartBuilder::on(&bar)
            .margin(8 * k)
            .margin_left(4 * k)
            .x_label_area_size(10 * k)
            .y_label_area_size(90 * k)
            .build_cartesian_2d(0.0..1.0, lo..hi)?;
        cb.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_label_formatter(&tick)
            .y_desc(&h.value_label)
            .label_style(font(TICK_PX, k))
            .axis_desc_style(font(TICK_PX, k))
            .axis_style(BLACK.stroke_width(k))
            .draw()?;
        let steps = 128;
        let strips = (0..steps).map(|i| {
            let (a, b) = (i as f64 / steps as f64, (i + 1) as f64 / steps as f64);
            let (va, vb) = (lo + a * (hi - lo), lo + b * (hi - lo));
            Rectangle::new(
                [(0.0, va), (1.0, vb)],
                scale.colour(0.5 * (va + vb)).filled(),
            )
        });
        cb.draw_series(strips)?;
        let row = ((LABEL_PX + 10) * k) as i32;
        let mut y = (10 * k) as i32;
        let entries = labels
            .iter()
            .map(|l| (Some(missing_colour(l)), l.to_string()))
            .chain(std::iter::once((None, "stability boundary".to_string())));
        for (colour, text) in entries {
            let x = (12 * k) as i32;
            let s = (LABEL_PX * k) as i32;
            match colour {
                Some(c) => legend.draw(&Rectangle::new([(x, y), (x + s, y + s)], c.filled()))?,
                None => legend.draw(&PathElement::new(
                    vec![(x, y + s / 2), (x + s, y + s / 2)],
                    BLACK.stroke_width(3 * k),
                ))?,
            }
            legend.draw(&Text::new(
                text,
                (x + s + (6 * k) as i32, y),
                font(LABEL_PX, k),
            ))?;
            y += row;
        }
        Ok(())
    }
}
