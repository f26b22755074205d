//! The SVG plots: `impulse run --plot` (`energy.svg`, `paths.svg`), `impulse bowling --svg`
//! and `impulse reduce --plot` (`error.svg`), drawn with [`plotters`]' SVG backend (text stays
//! `<text>`: the files are small and searchable, and no font is needed to write them).
//!
//! Ticks are round (1, 2 or 5 × 10^k, all with the same number of decimals), every axis title
//! names its unit, SI units take a prefix when the values are very small or large (energies of
//! a few mJ are shown in mJ), the grid is drawn, and the legend is inside the frame. Scene files
//! carry no unit: the bundled ones are SI (m, kg, s), so times are in s, positions in m and
//! energies in J, except the thesis's cm, g, s scenes, told by their gravity (981 cm/s²).

use std::ops::Range;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use impulse_sim::{Recording, Scene, World};

/// Size of a one-panel plot in SVG user units (pixels).
const PLOT_SIZE: (u32, u32) = (720, 440);
/// Size of the paths plot: four panels (three views and the legend) in two rows.
const PATHS_SIZE: (u32, u32) = (900, 760);
/// Space around a panel's frame, and between the legend's lines and its border (pixels).
const MARGIN: u32 = 12;
/// Space right of a panel's frame: half the widest last x tick label fits in it (pixels).
const RIGHT_MARGIN: u32 = 28;
/// Height of the area under the frame: tick labels and the axis title (pixels).
const X_LABEL_AREA: u32 = 44;
/// Width of the area left of the frame: tick labels and the axis title (pixels).
const Y_LABEL_AREA: u32 = 72;
/// Font sizes in plotters' units (the SVG's font-size is this / 1.24): title, axis titles and
/// tick and legend labels.
const TITLE_FONT: f64 = 20.0;
/// Axis titles.
const AXIS_FONT: f64 = 16.0;
/// Tick labels and legend entries.
const LABEL_FONT: f64 = 15.0;
/// The font family written into the SVG.
const FONT: &str = "sans-serif";
/// At most this many ticks on an axis (fewer where the round step gives fewer).
const MAX_TICKS: usize = 8;
/// An axis whose values all lie within this fraction of the largest axis span of the same plot
/// (or within 1e-12 of 0 when every span is 0) is widened to it: a body that never moves
/// along y still gets a readable y axis.
const MIN_SPAN_FRACTION: f64 = 0.02;
/// Values at or above this (in the axis's unit) get the next SI prefix (k, M, G…), or a power
/// of ten (×10³…) on an axis whose unit takes no prefix.
const PREFIX_ABOVE: f64 = 1e4;
/// Values all below this get a smaller SI prefix (m, µ, n…), or a power of ten (×10⁻³…).
const PREFIX_BELOW: f64 = 1e-2;
/// Units that take SI prefixes (others, cm and erg of the cm, g, s scenes, take a power of ten).
const SI_UNITS: [&str; 3] = ["s", "m", "J"];
/// Line colours, in order (the usual ten-colour palette's first eight).
const COLOURS: [RGBColor; 8] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xd6, 0x27, 0x28),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x94, 0x67, 0xbd),
    RGBColor(0x8c, 0x56, 0x4b),
    RGBColor(0xe3, 0x77, 0xc2),
    RGBColor(0x17, 0xbe, 0xcf),
];
/// Width of the plotted lines (pixels).
const LINE_WIDTH: u32 = 2;
/// Grid line colour.
const GRID: RGBColor = RGBColor(0xdd, 0xdd, 0xdd);
/// Length of a legend entry's line sample (pixels).
const LEGEND_SAMPLE: i32 = 24;
/// Height of one legend line on the paths plot's legend panel (pixels).
const LEGEND_LINE: i32 = 22;

/// One axis of a plot: what it shows and its unit (empty for none).
#[derive(Clone, Copy)]
pub(crate) struct Axis<'a> {
    /// The quantity ("time").
    pub name: &'a str,
    /// Its unit ("s"); SI units in [`SI_UNITS`] take a prefix where the values need one.
    pub unit: &'a str,
}

/// One named line of points (x, y), in the axes' units.
pub(crate) type Series = (String, Vec<(f64, f64)>);

/// An axis laid out: its range, round ticks, and the factor its values are divided by.
struct Ticks {
    /// Range in shown units (after dividing by `factor`), from tick to tick.
    lo: f64,
    hi: f64,
    /// The ticks, in shown units.
    ticks: Vec<f64>,
    /// Decimals of every tick label.
    decimals: usize,
    /// Values are divided by this (10^(3k)) and the unit takes `prefix`.
    factor: f64,
    prefix: &'static str,
}

impl Ticks {
    /// Round ticks covering `lo..=hi` (in `unit`).
    fn new(mut lo: f64, mut hi: f64, unit: &str) -> Ticks {
        if !(lo.is_finite() && hi.is_finite()) {
            (lo, hi) = (0.0, 1.0);
        }
        let largest = lo.abs().max(hi.abs());
        let (factor, prefix) = prefix_of(largest, unit);
        let (l, h) = (lo / factor, hi / factor);
        let raw = (h - l) / MAX_TICKS as f64;
        let magnitude = 10f64.powf(raw.log10().floor());
        let step = [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|m| m * magnitude)
            .find(|&s| s * (1.0 + 1e-9) >= raw)
            .unwrap_or(10.0 * magnitude);
        let (first, last) = ((l / step).floor() as i64, (h / step).ceil() as i64);
        let ticks: Vec<f64> = (first..=last).map(|k| k as f64 * step).collect();
        let decimals = (-(step.log10() + 1e-9).floor()).max(0.0) as usize;
        Ticks {
            lo: ticks[0],
            hi: *ticks.last().unwrap_or(&ticks[0]),
            ticks,
            decimals,
            factor,
            prefix,
        }
    }

    /// A tick's label.
    fn label(&self, v: f64) -> String {
        let s = format!("{v:.*}", self.decimals);
        // No "-0.00".
        if s.trim_start_matches('-')
            .chars()
            .all(|c| c == '0' || c == '.')
        {
            s.trim_start_matches('-').to_string()
        } else {
            s
        }
    }

    /// The axis title with its (prefixed) unit.
    fn title(&self, axis: Axis<'_>) -> String {
        match (self.prefix, axis.unit) {
            ("", "") => axis.name.to_string(),
            (p, "") => format!("{} ({p})", axis.name),
            (p, u) if p.starts_with('×') => format!("{} ({p} {u})", axis.name),
            (p, u) => format!("{} ({p}{u})", axis.name),
        }
    }
}

/// A linear axis from `.0` to `.1` with our ticks `.2` (plotters' own f64 axis picks its
/// ticks itself).
struct Linear(f64, f64, Vec<f64>);

impl Ranged for Linear {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let f = (v - self.0) / (self.1 - self.0);
        limit.0 + (f * f64::from(limit.1 - limit.0)).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        // Grid lines at the ticks only (no lighter lines between them).
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.2.clone()
        }
    }

    fn range(&self) -> Range<f64> {
        self.0..self.1
    }
}

/// The SI prefix for values up to `largest` in `unit`, or the power of ten for an axis without
/// a unit or with one that takes no prefix (cm, erg): (the factor to divide by, its symbol).
fn prefix_of(largest: f64, unit: &str) -> (f64, &'static str) {
    const PREFIXES: [(i32, &str); 9] = [
        (-12, "p"),
        (-9, "n"),
        (-6, "µ"),
        (-3, "m"),
        (0, ""),
        (3, "k"),
        (6, "M"),
        (9, "G"),
        (12, "T"),
    ];
    /// Powers of ten for other axes: the title says "(×10⁻⁶)" or "(×10⁶ erg)".
    const POWERS: [(i32, &str); 9] = [
        (-12, "×10⁻¹²"),
        (-9, "×10⁻⁹"),
        (-6, "×10⁻⁶"),
        (-3, "×10⁻³"),
        (0, ""),
        (3, "×10³"),
        (6, "×10⁶"),
        (9, "×10⁹"),
        (12, "×10¹²"),
    ];
    let table = if SI_UNITS.contains(&unit) {
        PREFIXES
    } else {
        POWERS
    };
    if largest == 0.0 || (PREFIX_BELOW..PREFIX_ABOVE).contains(&largest) {
        return (1.0, "");
    }
    let exp = ((largest.log10() / 3.0).floor() as i32 * 3).clamp(-12, 12);
    let symbol = table.iter().find(|p| p.0 == exp).map_or("", |p| p.1);
    (10f64.powi(exp), symbol)
}

/// The finite range of the values `v`, or `None`.
fn range(v: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    v.filter(|x| x.is_finite()).fold(None, |r, x| match r {
        None => Some((x, x)),
        Some((a, b)) => Some((x.min(a), x.max(b))),
    })
}

/// `(lo, hi)` widened to at least `min_span` about its middle.
fn widened((lo, hi): (f64, f64), min_span: f64) -> (f64, f64) {
    if hi - lo >= min_span {
        (lo, hi)
    } else {
        let mid = 0.5 * (lo + hi);
        (mid - 0.5 * min_span, mid + 0.5 * min_span)
    }
}

/// The style of text of `size` in plotters' units.
fn font(size: f64) -> TextStyle<'static> {
    (FONT, size).into_font().into()
}

/// A plotters error as our error text.
fn err(e: impl std::fmt::Display) -> String {
    format!("cannot draw the plot: {e}")
}

/// Draws one panel: a frame with round ticks, grid, axis titles with units and the series;
/// with `legend`, their names in a box inside the frame at its upper right.
fn panel(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    title: &str,
    (x, y): (Axis<'_>, Axis<'_>),
    (xr, yr): ((f64, f64), (f64, f64)),
    series: &[Series],
    legend: bool,
) -> Result<(), String> {
    let (tx, ty) = (
        Ticks::new(xr.0, xr.1, x.unit),
        Ticks::new(yr.0, yr.1, y.unit),
    );
    let mut chart = ChartBuilder::on(area)
        .caption(title, font(TITLE_FONT))
        .margin(MARGIN)
        .margin_right(RIGHT_MARGIN)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d(
            Linear(tx.lo, tx.hi, tx.ticks.clone()),
            Linear(ty.lo, ty.hi, ty.ticks.clone()),
        )
        .map_err(err)?;
    let (fx, fy) = (|v: &f64| tx.label(*v), |v: &f64| ty.label(*v));
    chart
        .configure_mesh()
        .bold_line_style(GRID)
        .x_desc(tx.title(x))
        .y_desc(ty.title(y))
        .axis_desc_style(font(AXIS_FONT))
        .label_style(font(LABEL_FONT))
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .draw()
        .map_err(err)?;
    for (k, (name, points)) in series.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        let shown = points
            .iter()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .map(|&(a, b)| (a / tx.factor, b / ty.factor));
        let drawn = chart
            .draw_series(LineSeries::new(shown, colour.stroke_width(LINE_WIDTH)))
            .map_err(err)?;
        if legend {
            drawn.label(name.as_str()).legend(move |(px, py)| {
                PathElement::new(
                    vec![(px, py), (px + LEGEND_SAMPLE, py)],
                    colour.stroke_width(LINE_WIDTH),
                )
            });
        }
    }
    if legend {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .margin(MARGIN)
            .legend_area_size(LEGEND_SAMPLE + MARGIN as i32)
            .label_font(font(LABEL_FONT))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .draw()
            .map_err(err)?;
    }
    Ok(())
}

/// A one-panel line plot of `series` (at most [`COLOURS`]`.len()` of them get distinct
/// colours), with the legend inside the frame.
pub(crate) fn line_plot(
    title: &str,
    x: Axis<'_>,
    y: Axis<'_>,
    series: &[Series],
) -> Result<String, String> {
    let points = || series.iter().flat_map(|s| s.1.iter());
    let xr = range(points().map(|p| p.0)).unwrap_or((0.0, 1.0));
    let yr = range(points().map(|p| p.1)).unwrap_or((0.0, 1.0));
    let xr = widened(
        xr,
        (xr.0.abs().max(xr.1.abs()) * MIN_SPAN_FRACTION).max(1e-12),
    );
    let yr = widened(
        yr,
        (yr.0.abs().max(yr.1.abs()) * MIN_SPAN_FRACTION).max(1e-12),
    );
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, PLOT_SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        panel(&root, title, (x, y), (xr, yr), series, true)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// Standard gravity in cm/s²: a scene whose gravity is this is in cm, g, s.
const CGS_GRAVITY: f64 = 980.665;
/// Relative tolerance on that match (the scenes write 981).
const CGS_GRAVITY_TOLERANCE: f64 = 0.01;

/// A scene's units of length and energy. Scene files carry no unit; the bundled ones are in
/// SI (m, kg, s) except those of the thesis's cm, g, s examples, whose gravity is 981 cm/s².
fn units(scene: &Scene) -> (&'static str, &'static str) {
    let g = scene.desc.gravity;
    let g = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    if (g / CGS_GRAVITY - 1.0).abs() <= CGS_GRAVITY_TOLERANCE {
        ("cm", "erg")
    } else {
        ("m", "J")
    }
}

/// Kinetic and total (kinetic + potential) energy against time.
pub(crate) fn energy_plot(rec: &Recording, scene: &Scene) -> Result<String, String> {
    let of = |e: fn(&impulse_sim::Frame) -> f64| -> Vec<(f64, f64)> {
        rec.frames.iter().map(|f| (f.time, e(f))).collect()
    };
    let name = if scene.desc.name.is_empty() {
        "energy".to_string()
    } else {
        format!("energy: {}", scene.desc.name)
    };
    line_plot(
        &name,
        Axis {
            name: "time",
            unit: "s",
        },
        Axis {
            name: "energy",
            unit: units(scene).1,
        },
        &[
            ("kinetic".into(), of(|f| f.kinetic_energy)),
            (
                "kinetic + potential".into(),
                of(|f| f.kinetic_energy + f.potential_energy),
            ),
        ],
    )
}

/// The dynamic bodies' centre-of-mass paths in three views (top x–y, side x–z and y–z) and a
/// panel naming the bodies in their colours.
pub(crate) fn paths_plot(rec: &Recording, world: &World, scene: &Scene) -> Result<String, String> {
    let dynamic: Vec<usize> = (0..rec.names.len())
        .filter(|&i| world.body(rec.handles[i]).is_some_and(|b| b.is_dynamic()))
        .collect();
    let along = |ax: usize| {
        range(
            dynamic
                .iter()
                .flat_map(|&i| rec.frames.iter().map(move |f| f.bodies[i].position[ax])),
        )
        .unwrap_or((0.0, 1.0))
    };
    let spans = [along(0), along(1), along(2)];
    let widest = spans.iter().map(|r| r.1 - r.0).fold(0.0, f64::max);
    let spans = spans.map(|r| widened(r, (widest * MIN_SPAN_FRACTION).max(1e-12)));
    let view = |a: usize, b: usize| -> Vec<Series> {
        dynamic
            .iter()
            .map(|&i| {
                let p = rec
                    .frames
                    .iter()
                    .map(|f| (f.bodies[i].position[a], f.bodies[i].position[b]));
                (rec.names[i].clone(), p.collect())
            })
            .collect()
    };
    let length = units(scene).0;
    let axis = |name| Axis { name, unit: length };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, PATHS_SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let panels = root.split_evenly((2, 2));
        let views = [
            (0, "top view (x–y)", (0, 1)),
            (2, "side view (x–z)", (0, 2)),
            (3, "side view (y–z)", (1, 2)),
        ];
        let names = ["x", "y", "z"];
        for (k, title, (a, b)) in views {
            panel(
                &panels[k],
                title,
                (axis(names[a]), axis(names[b])),
                (spans[a], spans[b]),
                &view(a, b),
                false,
            )?;
        }
        let names: Vec<&str> = dynamic.iter().map(|&i| rec.names[i].as_str()).collect();
        legend_panel(&panels[1], &names)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// The bodies' names in their line colours, one a line in as many columns as fit; names that
/// do not fit are counted on the last line.
fn legend_panel(area: &DrawingArea<SVGBackend<'_>, Shift>, names: &[&str]) -> Result<(), String> {
    let (w, h) = area.dim_in_pixel();
    let (w, h) = (w as i32, h as i32);
    let m = 3 * MARGIN as i32;
    let style = font(LABEL_FONT);
    area.draw(&Text::new(
        format!("centre-of-mass paths of {} moving bodies", names.len()),
        (m, m),
        font(TITLE_FONT),
    ))
    .map_err(err)?;
    let rows = ((h - 3 * m) / LEGEND_LINE).max(1) as usize;
    // Columns as wide as the longest name's estimate (plotters' rough text width).
    let widest = names
        .iter()
        .map(|n| area.estimate_text_size(n, &style).map_or(0, |s| s.0 as i32))
        .max()
        .unwrap_or(0);
    let column = widest + LEGEND_SAMPLE + 2 * MARGIN as i32;
    let columns = ((w - 2 * m) / column.max(1)).max(1) as usize;
    let room = rows * columns;
    let shown = if names.len() > room {
        room - 1
    } else {
        names.len()
    };
    let top = m + 2 * LEGEND_LINE;
    for (k, name) in names.iter().take(shown).enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        let (x, y) = (
            m + (k / rows) as i32 * column,
            top + (k % rows) as i32 * LEGEND_LINE,
        );
        area.draw(&PathElement::new(
            vec![(x, y), (x + LEGEND_SAMPLE, y)],
            colour.stroke_width(LINE_WIDTH),
        ))
        .map_err(err)?;
        area.draw(&Text::new(
            name.to_string(),
            (x + LEGEND_SAMPLE + MARGIN as i32 / 2, y),
            style.pos(Pos::new(HPos::Left, VPos::Center)),
        ))
        .map_err(err)?;
    }
    if shown < names.len() {
        let k = shown;
        area.draw(&Text::new(
            format!("… and {} more", names.len() - shown),
            (
                m + (k / rows) as i32 * column,
                top + (k % rows) as i32 * LEGEND_LINE,
            ),
            style.pos(Pos::new(HPos::Left, VPos::Center)),
        ))
        .map_err(err)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Labels of an axis from `lo` to `hi` in `unit`, and its title.
    fn labels(lo: f64, hi: f64, unit: &str) -> (Vec<String>, String) {
        let t = Ticks::new(lo, hi, unit);
        let title = t.title(Axis { name: "v", unit });
        (t.ticks.iter().map(|&v| t.label(v)).collect(), title)
    }

    /// The old plots' labels (`7.197e8`, `-3.866e7`, `1.250e0`, `3.286e-14`) become round
    /// ticks with one number of decimals, the unit prefixed where the values need it.
    #[test]
    fn ticks_are_round_with_units() {
        assert_eq!(
            labels(-3.866e7, 7.197e8, "J"),
            (
                [
                    "-100", "0", "100", "200", "300", "400", "500", "600", "700", "800"
                ]
                .map(String::from)
                .to_vec(),
                "v (MJ)".to_string()
            )
        );
        assert_eq!(
            labels(3.286e-14, 9.295e-3, "J"),
            (
                ["0", "2", "4", "6", "8", "10"].map(String::from).to_vec(),
                "v (mJ)".to_string()
            )
        );
        let (l, title) = labels(0.0, 1.25, "s");
        assert_eq!(l.first().map(String::as_str), Some("0.0"));
        assert_eq!(l.last().map(String::as_str), Some("1.4"));
        assert_eq!(title, "v (s)");
        assert_eq!(labels(-0.001, 0.2, "m").0[0], "-0.05");
        assert_eq!(labels(0.0, 4e-6, "").1, "v (×10⁻⁶)");
        // A power of ten on a unit that takes no prefix.
        assert_eq!(labels(0.0, 3e8, "erg").1, "v (×10⁶ erg)");
        assert_eq!(labels(0.0, 2e3, "cm").1, "v (cm)");
    }

    /// A zero-width axis is widened; one of no finite value is 0 to 1.
    #[test]
    fn degenerate_axes_still_have_ticks() {
        assert_eq!(widened((2.0, 2.0), 1.0), (1.5, 2.5));
        let t = Ticks::new(f64::NAN, f64::INFINITY, "m");
        assert_eq!((t.lo, t.hi), (0.0, 1.0));
    }
}
