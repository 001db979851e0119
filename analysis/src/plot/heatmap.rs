//! Heat maps of a scalar over a rectangular grid (a stability map over two gains), with a
//! colour bar and a boundary drawn as the zero contour of a second field (marching squares).

use plotters::prelude::*;

use super::PlotError;

/// A heat map's data and labels. `values` and `boundary` are row-major over (`ys`, `xs`):
/// entry `j·xs.len() + i` belongs to (xs[i], ys[j]). NaN values are drawn grey; the boundary is
/// where `boundary` changes sign (NaN cells are skipped).
pub struct HeatMap<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub value_label: &'a str,
    pub xs: &'a [f64],
    pub ys: &'a [f64],
    pub values: &'a [f64],
    pub boundary: &'a [f64],
    pub size: (u32, u32),
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

/// Viridis, by five stops.
fn colour(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let s = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let k = (s.floor() as usize).min(STOPS.len() - 2);
    let f = s - k as f64;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    let mix = |x: f64, y: f64| (x + f * (y - x)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Half the distance to the neighbours of `v[i]` on each side (a cell around each grid value).
fn cell(v: &[f64], i: usize) -> (f64, f64) {
    let step = |a: usize, b: usize| (v[b] - v[a]).abs() / 2.0;
    let default = if v.len() > 1 { step(0, 1) } else { 0.5 };
    let lo = if i > 0 { step(i - 1, i) } else { default };
    let hi = if i + 1 < v.len() { step(i, i + 1) } else { lo };
    (v[i] - lo, v[i] + hi)
}

/// The heat map as an SVG document: cells coloured by value (viridis, grey where NaN), the
/// zero contour of `boundary` in black, and a colour bar.
pub fn heat_map(h: &HeatMap) -> Result<String, PlotError> {
    let err = |e: &dyn std::fmt::Display| PlotError {
        title: h.title.to_string(),
        message: e.to_string(),
    };
    let (nx, ny) = (h.xs.len(), h.ys.len());
    if nx == 0 || ny == 0 || h.values.len() != nx * ny || h.boundary.len() != nx * ny {
        return Err(err(&"grid and values differ in size"));
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
    let (x0, x1) = (cell(h.xs, 0).0, cell(h.xs, nx - 1).1);
    let (y0, y1) = (cell(h.ys, 0).0, cell(h.ys, ny - 1).1);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, h.size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let root = root
            .titled(h.title, ("sans-serif", 18))
            .map_err(|e| err(&e))?;
        let (main, bar) = root.split_horizontally(h.size.0.saturating_sub(130));
        let mut ctx = ChartBuilder::on(&main)
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| err(&e))?;
        ctx.configure_mesh()
            .disable_mesh()
            .x_desc(h.x_label)
            .y_desc(h.y_label)
            .draw()
            .map_err(|e| err(&e))?;
        let grey = RGBColor(190, 190, 190);
        let cells = (0..ny)
            .flat_map(|j| (0..nx).map(move |i| (i, j)))
            .map(|(i, j)| {
                let v = h.values[j * nx + i];
                let c = if v.is_finite() {
                    colour((v - lo) / (hi - lo))
                } else {
                    grey
                };
                let ((a, b), (c0, d)) = (cell(h.xs, i), cell(h.ys, j));
                Rectangle::new([(a, c0), (b, d)], c.filled())
            });
        ctx.draw_series(cells).map_err(|e| err(&e))?;
        let lines = zero_contour(h.xs, h.ys, h.boundary)
            .into_iter()
            .map(|[p, q]| PathElement::new(vec![p, q], BLACK.stroke_width(2)));
        ctx.draw_series(lines).map_err(|e| err(&e))?;

        let mut cb = ChartBuilder::on(&bar)
            .margin(12)
            .margin_left(4)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..1.0, lo..hi)
            .map_err(|e| err(&e))?;
        cb.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_desc(h.value_label)
            .draw()
            .map_err(|e| err(&e))?;
        let n = 64;
        let steps = (0..n).map(|k| {
            let (a, b) = (k as f64 / n as f64, (k + 1) as f64 / n as f64);
            let (va, vb) = (lo + a * (hi - lo), lo + b * (hi - lo));
            Rectangle::new([(0.0, va), (1.0, vb)], colour((a + b) / 2.0).filled())
        });
        cb.draw_series(steps).map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    Ok(svg)
}
