//! Line charts: curves against a linear or logarithmic x axis, the legend in a column of its
//! own so it never hides data.

use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use super::{
    bounds, decade_label, decades, font, tick, Area, DrawResult, COLORS, LABEL_PX, TICK_PX,
    TITLE_PX,
};

/// One named curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// Its legend entry.
    pub name: String,
    /// (x, y) points; non-finite ones (and x ≤ 0 on a log axis) are skipped.
    pub points: Vec<(f64, f64)>,
}

/// A line chart.
#[derive(Debug, Clone, PartialEq)]
pub struct LineChart {
    /// Title.
    pub title: String,
    /// x-axis label with its unit.
    pub x_label: String,
    /// y-axis label with its unit.
    pub y_label: String,
    /// Declared size [px].
    pub size: (u32, u32),
    /// A logarithmic x axis (running estimates over long horizons).
    pub log_x: bool,
    /// The curves.
    pub curves: Vec<Curve>,
}

/// Least width of the legend column [px at 1×]; wider when a name needs it.
const LEGEND_W: u32 = 150;

impl LineChart {
    /// A chart of `curves` with these labels and size, linear axes.
    pub fn new(
        title: &str,
        x_label: &str,
        y_label: &str,
        size: (u32, u32),
        curves: Vec<Curve>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            size,
            log_x: false,
            curves,
        }
    }

    fn usable(&self, (x, y): &(f64, f64)) -> bool {
        x.is_finite() && y.is_finite() && (!self.log_x || *x > 0.0)
    }

    /// Draws onto `area` (of this chart's size times `k`).
    pub(crate) fn draw<DB: DrawingBackend>(&self, area: &Area<DB>, k: u32) -> DrawResult<DB> {
        area.fill(&WHITE)?;
        let root = area
            .margin(6 * k, 0, 0, 0)
            .titled(&self.title, font(TITLE_PX, k))?;
        let kept: Vec<Vec<(f64, f64)>> = self
            .curves
            .iter()
            .map(|c| {
                c.points
                    .iter()
                    .filter(|p| self.usable(p))
                    .copied()
                    .collect()
            })
            .collect();
        let legend = self.curves.len() > 1;
        let width = root.dim_in_pixel().0;
        // The line sample (6 + 24 + 6 px), the longest name as the font renders it, a margin.
        let longest = self
            .curves
            .iter()
            .filter_map(|c| {
                root.estimate_text_size(&c.name, &font(LABEL_PX, k).into_text_style(&root))
                    .ok()
            })
            .map(|(w, _)| w)
            .max()
            .unwrap_or(0);
        let legend_w = (LEGEND_W * k).max(longest + 44 * k).min(width / 3);
        let (plot, side) = if legend {
            root.split_horizontally(width.saturating_sub(legend_w))
        } else {
            root.split_horizontally(width)
        };
        let ((x0, x1), (y0, y1)) = bounds(kept.iter().flatten());
        let mut builder = ChartBuilder::on(&plot);
        builder
            .margin(8 * k)
            .x_label_area_size(50 * k)
            .y_label_area_size(75 * k);
        if self.log_x {
            let xs = kept.iter().flatten().map(|p| p.0);
            let lo = xs.clone().fold(f64::INFINITY, f64::min);
            let hi = xs.fold(0.0, f64::max);
            let (lo, hi) = if lo.is_finite() && hi > lo {
                decades(lo, hi)
            } else {
                (1.0, 10.0)
            };
            // A hair beyond the end decades: plotters finds its key points from ln(lo)/ln(10),
            // which for lo = 0.1 rounds to just above −1 and skips the first decade's label.
            let (lo, hi) = (lo * (1.0 - 1e-9), hi * (1.0 + 1e-9));
            let ctx = builder.build_cartesian_2d((lo..hi).log_scale(), y0..y1)?;
            self.draw_series(ctx, &kept, k)?;
        } else {
            let ctx = builder.build_cartesian_2d(x0..x1, y0..y1)?;
            self.draw_series(ctx, &kept, k)?;
        }
        if legend {
            let row = ((LABEL_PX + 8) * k) as i32;
            let top = (60 * k) as i32;
            for (i, c) in self.curves.iter().enumerate() {
                let color = COLORS[i % COLORS.len()];
                let y = top + i as i32 * row;
                let (x, len) = (6 * k as i32, 24 * k as i32);
                side.draw(&PathElement::new(
                    vec![(x, y), (x + len, y)],
                    color.stroke_width(3 * k),
                ))?;
                side.draw(&Text::new(
                    c.name.clone(),
                    (x + len + 6 * k as i32, y - (LABEL_PX * k / 2) as i32),
                    font(LABEL_PX, k),
                ))?;
            }
        }
        Ok(())
    }

    /// The mesh and the curves on a chart whose x axis is linear or logarithmic.
    fn draw_series<DB, X>(
        &self,
        mut ctx: ChartContext<'_, DB, Cartesian2d<X, RangedCoordf64>>,
        series: &[Vec<(f64, f64)>],
        k: u32,
    ) -> DrawResult<DB>
    where
        DB: DrawingBackend,
        X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        // About one x label per 64 px (at 1×): plotters' default of ten ran labels such as
        // "-0.06-0.04" into each other on a narrow panel (a phase portrait beside its legend).
        let width = ctx.plotting_area().dim_in_pixel().0 / k.max(1);
        let x_labels = (width / 64).clamp(3, 10) as usize;
        let mut mesh = ctx.configure_mesh();
        if self.log_x {
            // A logarithmic axis is labelled at its decades (plotters' key points).
            mesh.x_label_formatter(&decade_label);
        } else {
            mesh.x_label_formatter(&tick).x_labels(x_labels);
        }
        mesh.y_label_formatter(&tick)
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .label_style(font(TICK_PX, k))
            .axis_desc_style(font(LABEL_PX, k))
            .light_line_style(RGBColor(235, 235, 235).stroke_width(k))
            .bold_line_style(RGBColor(210, 210, 210).stroke_width(k))
            .axis_style(BLACK.stroke_width(k))
            .draw()?;
        for (i, pts) in series.iter().enumerate() {
            let color = COLORS[i % COLORS.len()];
            ctx.draw_series(LineSeries::new(
                pts.iter().copied(),
                color.stroke_width(2 * k),
            ))?;
        }
        Ok(())
    }
}
