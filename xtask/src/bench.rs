//! `cargo xtask bench [--out DIR] [--case NAME]`: speed against error for every bundled scene.
//!
//! Each scene of [`crate::cases::scenes::scene_checks`] runs at six accuracy settings
//! ([`SETTINGS`]: the collision epsilon and the integrator tolerances together, coarse to fine;
//! then the island step tolerance alone, `accuracy.step_tolerance`, 1e-2, 0.1 and 1 ε_c
//! beside the default's 1e-3), in a release
//! build (the command re-runs itself with `--release`). For each run it prints the wall time,
//! the slowdown (wall / simulated), the thesis's Table 7.1 slowdown for the same example (SGI
//! Indigo II, 200 MHz R4400, 1996) and the ratio between the two, and the error: the relative
//! deviation of the scene's headline metric from its reference (one of the metrics of
//! `cargo xtask validate`, named in [`SceneCheck::headline`]; its value when the reference is
//! 0), and whether all the scene's metrics pass. It writes `bench.csv` and one `<scene>.svg`
//! (error against slowdown, log–log) per scene into the output directory (default
//! `target/bench`). Then it runs the stack study ([`crate::stacks`], also alone with
//! `--case stacks`) and writes `stacks.csv`, and the pose studies ([`crate::poses`], also
//! alone with `--case poses`), which write `poses.csv`, and the bowling study
//! ([`crate::bowling`], alone with `--case bowling`: `bowling.csv`, `bowling.json`). With `--peers` it runs [`crate::peers`] instead
//! (re-running itself with the `peers` feature, which builds the peer engine).

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

use impulse_sim::{Recording, World, run};

use crate::Result;
use crate::cases::scenes::{Run, SceneCheck, duration, load_scene, scene_checks};

use crate::validate::case::Metric;
use crate::validate::check::evaluate;

/// An accuracy setting: a name, the factor applied to the scene's ε_c, and the rotation and
/// collision integrator tolerances.
pub struct Setting {
    /// Name in the table.
    pub name: &'static str,
    /// Factor on the scene's collision epsilon.
    pub epsilon_factor: f64,
    /// Rotation integrator tolerance (see `impulse_sim::body::Integrator`).
    pub rotation_tolerance: f64,
    /// Collision integrator relative tolerance (`impulse-response`).
    pub collision_tolerance: f64,
    /// Island step tolerance in units of ε_c (`impulse_sim::sustained::SustainedSettings`).
    pub step_tolerance: f64,
}

/// The default island step tolerance (`impulse_sim::sustained::DEFAULT_STEP_TOLERANCE`).
const STEP_TOLERANCE: f64 = impulse_sim::sustained::DEFAULT_STEP_TOLERANCE;

/// The settings each scene runs at: coarse to fine, then the island step tolerance alone
/// (a work–precision sweep of the switching model's step policy).
pub const SETTINGS: [Setting; 6] = [
    Setting {
        name: "coarse",
        epsilon_factor: 4.0,
        rotation_tolerance: 1e-8,
        collision_tolerance: 1e-6,
        step_tolerance: STEP_TOLERANCE,
    },
    Setting {
        name: "default",
        epsilon_factor: 1.0,
        rotation_tolerance: 1e-12,
        collision_tolerance: 1e-10,
        step_tolerance: STEP_TOLERANCE,
    },
    Setting {
        name: "fine",
        epsilon_factor: 0.25,
        rotation_tolerance: 1e-13,
        collision_tolerance: 1e-12,
        step_tolerance: STEP_TOLERANCE,
    },
    Setting {
        name: "step 1e-2",
        epsilon_factor: 1.0,
        rotation_tolerance: 1e-12,
        collision_tolerance: 1e-10,
        step_tolerance: 1e-2,
    },
    Setting {
        name: "step 0.1",
        epsilon_factor: 1.0,
        rotation_tolerance: 1e-12,
        collision_tolerance: 1e-10,
        step_tolerance: 0.1,
    },
    Setting {
        name: "step 1",
        epsilon_factor: 1.0,
        rotation_tolerance: 1e-12,
        collision_tolerance: 1e-10,
        step_tolerance: 1.0,
    },
];

/// The `--case` name that runs only the stack study ([`crate::stacks`]).
pub const STACKS_CASE: &str = "stacks";

/// Errors below this are plotted at this value (log axis).
const PLOT_ERROR_FLOOR: f64 = 1e-16;

/// Options of `cargo xtask bench`.
#[derive(Debug, Default, PartialEq)]
pub struct Options {
    /// Output directory.
    pub out: Option<PathBuf>,
    /// Only this case.
    pub case: Option<String>,
    /// Set when already running in the release build.
    pub in_release: bool,
    /// Run the peer comparison ([`crate::peers`]) instead: built with the `peers` feature.
    /// With `scale`, the peer runs the scale scenes too.
    pub peers: bool,
    /// Run the scale bench ([`crate::scale`]) instead.
    pub scale: bool,
    /// With `scale`: only the scenes whose name contains this.
    pub only: Option<String>,
    /// With `scale`: the wall budget of one run (s).
    pub budget: Option<f64>,
}

/// One row of the table.
struct Row {
    case: &'static str,
    headline: &'static str,
    setting: &'static str,
    epsilon: f64,
    simulated: f64,
    wall: f64,
    thesis: Option<(&'static str, f64)>,
    error: f64,
    all_pass: bool,
    events: u64,
}

/// Runs the benchmark (re-running itself in release mode first).
pub fn run_bench(options: &Options) -> Result<()> {
    if !options.in_release {
        let mut cmd = Command::new(crate::cargo());
        cmd.current_dir(crate::workspace_root())
            .args(["run", "--release", "--quiet", "--package", "xtask"])
            .args(if options.peers {
                &["--features", "peers"][..]
            } else {
                &[]
            })
            .args(["--", "bench", "--in-release"]);
        if options.peers {
            cmd.arg("--peers");
        }
        if let Some(out) = &options.out {
            cmd.arg("--out").arg(out);
        }
        if let Some(case) = &options.case {
            cmd.args(["--case", case]);
        }
        if options.scale {
            cmd.arg("--scale");
        }
        if let Some(only) = &options.only {
            cmd.args(["--only", only]);
        }
        if let Some(budget) = options.budget {
            cmd.args(["--budget", &budget.to_string()]);
        }
        let status = cmd
            .status()
            .map_err(|e| format!("cannot start the release build: {e}"))?;
        return if status.success() {
            Ok(())
        } else {
            Err(format!("bench (release child process): {status}"))
        };
    }
    let out = options
        .out
        .clone()
        .unwrap_or_else(|| crate::workspace_root().join("target").join("bench"));
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    if options.scale {
        return crate::scale::run(&crate::scale::Options {
            out: Some(out),
            only: options.only.clone(),
            budget: options.budget,
            peers: options.peers,
        });
    }
    if options.peers {
        return crate::peers::run(&out);
    }
    if options.case.as_deref() == Some(crate::forks::CASE) {
        return crate::forks::run(&out);
    }
    if options.case.as_deref() == Some(crate::poses::CASE) {
        return crate::poses::run(&out);
    }
    if options.case.as_deref() == Some(crate::bowling::CASE) {
        return crate::bowling::run(&out);
    }
    let stacks_only = options.case.as_deref() == Some(STACKS_CASE);
    let checks: Vec<SceneCheck> = scene_checks()
        .into_iter()
        .filter(|c| options.case.as_deref().is_none_or(|n| n == c.case))
        .collect();
    if checks.is_empty() && !stacks_only {
        return Err(format!("no scene case {:?}", options.case));
    }
    println!(
        "{:<26} {:<9} {:>9} {:>8} {:>9} {:>10} {:>9} {:>8} {:>10} {:>5}",
        "scene",
        "setting",
        "eps_c",
        "sim s",
        "wall s",
        "slowdown",
        "T7.1",
        "ratio",
        "error",
        "pass"
    );
    let mut rows = Vec::new();
    for check in &checks {
        for setting in &SETTINGS {
            let row = bench_one(check, setting)?;
            let (t, ratio) = match row.thesis {
                Some((_, s)) => (
                    format!("{s:.1}"),
                    format!("{:.4}", row.wall / row.simulated / s),
                ),
                None => ("-".into(), "-".into()),
            };
            println!(
                "{:<26} {:<9} {:>9.2e} {:>8.2} {:>9.3} {:>10.4} {:>9} {:>8} {:>10.2e} {:>5}  {}",
                row.case,
                row.setting,
                row.epsilon,
                row.simulated,
                row.wall,
                row.wall / row.simulated,
                t,
                ratio,
                row.error,
                if row.all_pass { "ok" } else { "FAIL" },
                row.headline
            );
            rows.push(row);
        }
    }
    let csv = out.join("bench.csv");
    std::fs::write(&csv, to_csv(&rows)).map_err(|e| format!("{}: {e}", csv.display()))?;
    for check in &checks {
        let mine: Vec<&Row> = rows.iter().filter(|r| r.case == check.case).collect();
        let path = out.join(format!("{}.svg", check.case));
        std::fs::write(&path, plot(check.case, &mine)?)
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    println!("wrote {} and one SVG per scene", csv.display());
    if options.case.is_none() || stacks_only {
        let path = out.join("stacks.csv");
        std::fs::write(&path, crate::stacks::study()?)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        println!("wrote {}", path.display());
    }
    if options.case.is_none() {
        crate::poses::run(&out)?;
        crate::bowling::run(&out)?;
    }
    Ok(())
}

fn bench_one(check: &SceneCheck, setting: &Setting) -> Result<Row> {
    let mut scene = load_scene(check.scene)?;
    scene.desc.collision_epsilon *= setting.epsilon_factor;
    scene.desc.accuracy.rotation_tolerance = setting.rotation_tolerance;
    scene.desc.accuracy.collision_tolerance = setting.collision_tolerance;
    scene.desc.accuracy.step_tolerance = setting.step_tolerance;
    let mut world = World::from_scene(&scene).map_err(|e| format!("{}: {e}", check.case))?;
    world.set_event_log(check.event_log);
    let start = Instant::now();
    let simulated = duration(&scene)?;
    let rec: Recording = run(&mut world, simulated, scene.desc.output_rate, |_| {})
        .map_err(|e| format!("{} ({}): {e}", check.case, setting.name))?;
    let wall = start.elapsed().as_secs_f64();
    let metrics = (check.metrics)(&Run {
        scene: &scene,
        world: &world,
        rec: &rec,
    })?;
    Ok(Row {
        case: check.case,
        headline: check.headline,
        setting: setting.name,
        epsilon: scene.desc.collision_epsilon,
        simulated,
        wall,
        thesis: check.thesis,
        error: error_of(&metrics, check.headline)?,
        all_pass: metrics.iter().all(|m| evaluate(m).pass),
        events: rec.counters.collisions + rec.counters.microcollisions,
    })
}

/// The scene's error: the headline metric's relative deviation from its reference (its
/// value when the reference is 0).
fn error_of(metrics: &[Metric], headline: &str) -> Result<f64> {
    let m = metrics
        .iter()
        .find(|m| m.name == headline)
        .ok_or_else(|| format!("no metric {headline}"))?;
    let d = (m.value - m.reference).abs();
    Ok(if m.reference != 0.0 {
        d / m.reference.abs()
    } else {
        d
    })
}

fn to_csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "scene,setting,epsilon,simulated_s,wall_s,slowdown,thesis_example,thesis_slowdown,ratio,error_metric,error,pass,events\n",
    );
    for r in rows {
        let slowdown = r.wall / r.simulated;
        let (name, ts, ratio) = match r.thesis {
            Some((n, t)) => (n.to_string(), t.to_string(), (slowdown / t).to_string()),
            None => (String::new(), String::new(), String::new()),
        };
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.case,
            r.setting,
            r.epsilon,
            r.simulated,
            r.wall,
            slowdown,
            name,
            ts,
            ratio,
            r.headline,
            r.error,
            r.all_pass,
            r.events
        );
    }
    s
}

/// Radius of a setting's point, and its label's offset from it (pixels).
const PLOT_POINT: (u32, i32) = (4, 7);
/// Line and point colour.
const PLOT_COLOUR: plotters::style::RGBColor = plotters::style::RGBColor(0x1f, 0x77, 0xb4);

/// A logarithmic axis over whole decades `10^.0 ..= 10^.1`: ticks and grid at the decades,
/// lighter grid at 2..9 times them. (plotters' own log axis also labels 2, 5… when there is
/// room, which crowds a short axis.)
#[derive(Clone, Copy)]
pub(crate) struct Decades(pub i32, pub i32);

impl Decades {
    /// The decades covering the positive values `v` (at least one decade).
    pub(crate) fn covering(v: impl Iterator<Item = f64>) -> Decades {
        let (lo, hi) = v
            .filter(|x| x.is_finite() && *x > 0.0)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
        if !lo.is_finite() {
            return Decades(0, 1);
        }
        let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        Decades(a, b.max(a + 1))
    }

    /// A tick label: the power of ten with a superscript exponent (10⁻³).
    pub(crate) fn label(v: &f64) -> String {
        const SUPERSCRIPT: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
        let k = v.log10().round() as i32;
        let digits: String = k
            .unsigned_abs()
            .to_string()
            .chars()
            .map(|c| SUPERSCRIPT[c as usize - '0' as usize])
            .collect();
        format!("10{}{digits}", if k < 0 { "⁻" } else { "" })
    }
}

impl plotters::coord::ranged1d::Ranged for Decades {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let f = (v.log10() - f64::from(self.0)) / f64::from(self.1 - self.0);
        limit.0 + (f * f64::from(limit.1 - limit.0)).round() as i32
    }

    fn key_points<H: plotters::coord::ranged1d::KeyPointHint>(&self, hint: H) -> Vec<f64> {
        let light = hint.weight().allow_light_points();
        (self.0..=self.1)
            .flat_map(|k| {
                let d = 10f64.powi(k);
                let m: &[f64] = if light && k < self.1 {
                    &[2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]
                } else if light {
                    &[]
                } else {
                    &[1.0]
                };
                m.iter().map(move |m| m * d)
            })
            .collect()
    }

    fn range(&self) -> std::ops::Range<f64> {
        10f64.powi(self.0)..10f64.powi(self.1)
    }
}

/// Error against slowdown, log–log, one labelled point per setting.
fn plot(case: &str, rows: &[&Row]) -> Result<String> {
    use plotters::prelude::*;
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    let err = crate::plot::cannot_draw(case);
    let pts: Vec<(f64, f64, &str)> = rows
        .iter()
        .map(|r| {
            (
                r.wall / r.simulated,
                r.error.max(PLOT_ERROR_FLOOR),
                r.setting,
            )
        })
        .collect();
    let x_decades = Decades::covering(pts.iter().map(|p| p.0));
    let y_decades = Decades::covering(pts.iter().map(|p| p.1));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, crate::plot::SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = crate::plot::chart(&root, format!("{case}: error against slowdown"))
            .build_cartesian_2d(x_decades, y_decades)
            .map_err(&err)?;
        chart
            .configure_mesh()
            .x_desc("slowdown (wall time / simulated time)")
            .y_desc("error (largest relative deviation)")
            .axis_desc_style(crate::plot::font(crate::plot::FONTS.1))
            .label_style(crate::plot::font(crate::plot::FONTS.2))
            .x_label_formatter(&Decades::label)
            .y_label_formatter(&Decades::label)
            .bold_line_style(RGBColor(0xcc, 0xcc, 0xcc))
            .light_line_style(RGBColor(0xee, 0xee, 0xee))
            .draw()
            .map_err(&err)?;
        chart
            .draw_series(LineSeries::new(pts.iter().map(|p| (p.0, p.1)), PLOT_COLOUR))
            .map_err(&err)?;
        let (radius, offset) = PLOT_POINT;
        let middle = |d: Decades| 10f64.powf(0.5 * f64::from(d.0 + d.1));
        let (x_middle, y_middle) = (middle(x_decades), middle(y_decades));
        chart
            .draw_series(pts.iter().map(|&(x, y, name)| {
                // A name goes toward the middle of the frame from its point (right of a point
                // in the left half, under a point in the upper half): it stays inside.
                let (dx, h) = if x < x_middle {
                    (offset, HPos::Left)
                } else {
                    (-offset, HPos::Right)
                };
                let (dy, v) = if y < y_middle {
                    (-offset, VPos::Bottom)
                } else {
                    (offset, VPos::Top)
                };
                let style = crate::plot::font(crate::plot::FONTS.2).pos(Pos::new(h, v));
                EmptyElement::at((x, y))
                    + Circle::new((0, 0), radius, PLOT_COLOUR.filled())
                    + Text::new(name, (dx, dy), style)
            }))
            .map_err(&err)?;
        root.present().map_err(&err)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bench row of one setting: slowdown `wall` (1 s simulated) and `error`.
    fn row(setting: &'static str, wall: f64, error: f64) -> Row {
        Row {
            case: "case",
            headline: "",
            setting,
            epsilon: 1e-4,
            simulated: 1.0,
            wall,
            thesis: None,
            error,
            all_pass: true,
            events: 0,
        }
    }

    /// The plot's axes are logarithmic over whole decades, labelled 10ᵏ, and each setting's
    /// point is named; an error of 0 sits at the floor.
    #[test]
    fn the_plot_is_log_log_with_named_points() {
        let rows = [
            row("coarse", 0.05, 3e-3),
            row("default", 0.4, 2e-6),
            row("fine", 7.0, 0.0),
        ];
        let svg = plot("case", &rows.iter().collect::<Vec<_>>()).unwrap();
        if let Some(dir) = std::env::var_os("XTASK_PLOT_DIR") {
            std::fs::write(std::path::Path::new(&dir).join("bench.svg"), &svg).unwrap();
        }
        // Slowdown 10⁻² … 10¹, error 10⁻¹⁶ (the floor) … 10⁻².
        for label in ["10⁻²", "10⁻¹", "10⁰", "10¹", "10⁻¹⁶", "10⁻⁸"] {
            assert!(svg.contains(&format!("\n{label}\n")), "no tick {label}");
        }
        assert!(!svg.contains("\n10²\n"), "the x axis goes past 10¹");
        for name in ["coarse", "default", "fine"] {
            assert!(
                svg.contains(&format!("\n{name}\n")),
                "no point named {name}"
            );
        }
        assert_eq!(Decades::covering([1.0].into_iter()).1, 1);
        assert_eq!(Decades::label(&1e-3), "10⁻³");
    }
}
