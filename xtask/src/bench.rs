//! `cargo xtask bench [--out DIR] [--case NAME]`: speed against error for every bundled scene.
//!
//! Each scene of [`crate::cases::scenes::scene_checks`] runs at three accuracy settings
//! ([`SETTINGS`]: the collision epsilon and the integrator tolerances together), in a release
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
}

/// The settings each scene runs at, coarse to fine.
pub const SETTINGS: [Setting; 3] = [
    Setting {
        name: "coarse",
        epsilon_factor: 4.0,
        rotation_tolerance: 1e-8,
        collision_tolerance: 1e-6,
    },
    Setting {
        name: "default",
        epsilon_factor: 1.0,
        rotation_tolerance: 1e-12,
        collision_tolerance: 1e-10,
    },
    Setting {
        name: "fine",
        epsilon_factor: 0.25,
        rotation_tolerance: 1e-13,
        collision_tolerance: 1e-12,
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
    pub peers: bool,
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
        "{:<26} {:<8} {:>9} {:>8} {:>9} {:>10} {:>9} {:>8} {:>10} {:>5}",
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
                "{:<26} {:<8} {:>9.2e} {:>8.2} {:>9.3} {:>10.4} {:>9} {:>8} {:>10.2e} {:>5}  {}",
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
        std::fs::write(&path, plot(check.case, &mine))
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

/// Error against slowdown, log–log, one labelled point per setting.
fn plot(case: &str, rows: &[&Row]) -> String {
    let (w, h, m) = (560.0, 380.0, 64.0);
    let pts: Vec<(f64, f64, &str)> = rows
        .iter()
        .map(|r| {
            (
                (r.wall / r.simulated).log10(),
                r.error.max(PLOT_ERROR_FLOOR).log10(),
                r.setting,
            )
        })
        .collect();
    let (mut x0, mut x1) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.0), b.max(p.0))
        });
    let (mut y0, mut y1) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.1), b.max(p.1))
        });
    (x0, x1) = (x0.floor(), x1.ceil().max(x0.floor() + 1.0));
    (y0, y1) = (y0.floor(), y1.ceil().max(y0.floor() + 1.0));
    let sx = |x: f64| m + (x - x0) / (x1 - x0) * (w - 2.0 * m);
    let sy = |y: f64| h - m - (y - y0) / (y1 - y0) * (h - 2.0 * m);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n<text x=\"{}\" y=\"20\" text-anchor=\"middle\" font-size=\"14\">{case}: error against slowdown</text>\n<rect x=\"{m}\" y=\"{m}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#888\"/>\n",
        w / 2.0,
        w - 2.0 * m,
        h - 2.0 * m
    );
    let mut k = x0;
    while k <= x1 {
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">1e{k}</text>",
            sx(k),
            h - m + 16.0
        );
        k += 1.0;
    }
    let mut k = y0;
    while k <= y1 {
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">1e{k}</text>",
            m - 4.0,
            sy(k) + 4.0
        );
        k += 1.0;
    }
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">slowdown (wall / simulated)</text>",
        w / 2.0,
        h - 16.0
    );
    let _ = writeln!(
        s,
        "<text x=\"16\" y=\"{0}\" text-anchor=\"middle\" transform=\"rotate(-90 16 {0})\">error (largest relative deviation)</text>",
        h / 2.0
    );
    let line: Vec<String> = pts
        .iter()
        .map(|p| format!("{:.1},{:.1}", sx(p.0), sy(p.1)))
        .collect();
    let _ = writeln!(
        s,
        "<polyline fill=\"none\" stroke=\"#1f77b4\" points=\"{}\"/>",
        line.join(" ")
    );
    for p in &pts {
        let _ = writeln!(
            s,
            "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"3.5\" fill=\"#1f77b4\"/><text x=\"{:.1}\" y=\"{:.1}\">{}</text>",
            sx(p.0),
            sy(p.1),
            sx(p.0) + 6.0,
            sy(p.1) - 6.0,
            p.2
        );
    }
    s.push_str("</svg>\n");
    s
}
