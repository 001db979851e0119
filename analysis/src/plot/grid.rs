//! Several line charts of one size side by side, row by row (the study's four phase portraits).

use plotters::prelude::*;

use super::line::LineChart;
use super::{Area, DrawResult};

/// Panels of equal size, `columns` to a row.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// The panels, row by row.
    pub panels: Vec<LineChart>,
    /// Panels per row.
    pub columns: usize,
}

impl Grid {
    fn shape(&self) -> (usize, usize) {
        let cols = self.columns.clamp(1, self.panels.len().max(1));
        (self.panels.len().div_ceil(cols).max(1), cols)
    }

    /// The first panel's title (for errors).
    pub fn title(&self) -> &str {
        self.panels.first().map_or("", |p| p.title.as_str())
    }

    /// The declared size: the panels' size times the grid's shape.
    pub fn size(&self) -> (u32, u32) {
        let (rows, cols) = self.shape();
        let (w, h) = self.panels.first().map_or((1, 1), |p| p.size);
        (w * cols as u32, h * rows as u32)
    }

    pub(crate) fn draw<DB: DrawingBackend>(&self, area: &Area<DB>, k: u32) -> DrawResult<DB> {
        area.fill(&WHITE)?;
        let (rows, cols) = self.shape();
        for (panel, cell) in self.panels.iter().zip(area.split_evenly((rows, cols))) {
            panel.draw(&cell, k)?;
        }
        Ok(())
    }
}
