//! What the SVG plots of `bench` and `forks` share (plotters): the page size, the frame's
//! margins and label areas, the fonts, and how a drawing error is named.

use plotters::coord::Shift;
use plotters::prelude::{ChartBuilder, DrawingArea, DrawingBackend, IntoFont, TextStyle};

/// Size of a plot (SVG user units, pixels).
pub const SIZE: (u32, u32) = (640, 420);
/// Space around the frame (pixels); right of it, half the last tick label fits.
pub const MARGIN: (u32, u32) = (12, 28);
/// Label areas under and left of the frame: tick labels and axis title (pixels).
pub const LABEL_AREAS: (u32, u32) = (48, 72);
/// Font sizes (plotters' units; the SVG's font-size is this / 1.24): title, axis titles, tick,
/// point and legend labels.
pub const FONTS: (f64, f64, f64) = (20.0, 16.0, 15.0);

/// The sans-serif font of `size`.
pub fn font(size: f64) -> TextStyle<'static> {
    ("sans-serif", size).into_font().into()
}

/// A chart on `root` titled `caption`, with the shared margins and label areas (the caller
/// gives its axes).
pub fn chart<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    caption: String,
) -> ChartBuilder<'_, 'static, DB> {
    let mut builder = ChartBuilder::on(root);
    builder
        .caption(caption, font(FONTS.0))
        .margin(MARGIN.0)
        .margin_right(MARGIN.1)
        .x_label_area_size(LABEL_AREAS.0)
        .y_label_area_size(LABEL_AREAS.1);
    builder
}

/// Names a drawing error of the plot `what`.
pub fn cannot_draw<E: std::fmt::Display>(what: &str) -> impl Fn(E) -> String + '_ {
    move |e| format!("{what}: cannot draw the plot: {e}")
}
