//! `cargo xtask bench --peers`: the same scenes in `impulse` and in a peer engine (rapier3d-f64,
//! behind the `peers` feature), side by side: speed against accuracy of both contact models
//! (`docs/sustained-contact.md`) beside an established engine.
//!
//! Scenes ([`peer_scenes`]): stacks of 2, 4, 8, 16 and 32 blocks (the geometry of
//! [`crate::stacks`], aligned, run for [`STACK_DURATION`]), and the bundled `dominos`,
//! `block-on-ramp`, `sliding-to-rolling` and `pool-break`. Every engine starts from the same
//! [`impulse_sim::SceneDesc`], so geometry, masses, μ, e, gravity and the initial state are
//! the same; a shape the peer is not given is reported, not approximated.
//!
//! `impulse` runs once per mode of [`our_modes`]; the peer once per configuration of its time
//! step. For each run the table gives the wall time per simulated second (median of [`RUNS`]
//! runs in this process, release build) and the scene's headline error, measured from the
//! recorded trajectory by [`measure()`] (the same function for every engine). A run stops early
//! when it exceeds [`WALL_BUDGET`]: its row says how far it got, and it is not repeated.
//! Output: the table on stdout, `peers.csv` and `peers.svg` (error against speed, one panel
//! per scene) in the output directory.

pub mod measure;
#[cfg(feature = "peers")]
pub mod rapier;

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use impulse_sim::{ContactMode, Scene, SceneDesc, World};

use crate::Result;
use measure::{Frame, Measure, State, Trajectory};

/// Stack sizes of the side-by-side table: doubling from 2 to 32 blocks, so the cost's growth
/// per doubling can be read (`docs/sustained-contact.md`, "Stack cost per block").
pub const PEER_STACK_SIZES: [usize; 5] = [2, 4, 8, 16, 32];
/// Simulated time of a stack (s): a stack must stand for 10 s, as in the unit tests of
/// sustained contact (`docs/sustained-contact.md`, "Measured").
pub const STACK_DURATION: f64 = 10.0;
/// Runs per engine and scene; the wall time reported is their median.
pub const RUNS: usize = 3;
/// Wall-clock budget of one run (s): a run still going then stops where it is, and its row
/// reports the simulated time reached (the 16- and 32-block stacks take `impulse` minutes per
/// simulated second today).
pub const WALL_BUDGET: f64 = 60.0;
/// Errors below this are plotted at this value (log axis).
const PLOT_ERROR_FLOOR: f64 = 1e-12;

/// Which headline measurement a scene gets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// A stack of blocks.
    Stack,
    /// The domino row.
    Dominos,
    /// The block launched down a ramp.
    Ramp,
    /// The ball sliding into rolling.
    Rolling,
    /// The pool break.
    Pool,
}

/// A scene of the peer bench.
pub struct PeerScene {
    /// Name in the table.
    pub name: String,
    /// Its measurement.
    pub kind: Kind,
    /// The scene every engine runs.
    pub scene: Scene,
}

/// A mode `impulse` runs in: its name in the table and what it changes in the scene.
pub type Mode = (&'static str, fn(&mut SceneDesc));

/// The modes `impulse` runs in: the thesis's pure impulse model and the switching model
/// (impulses for impacts, constraints for sustained contact; `impulse_sim::sustained`).
pub fn our_modes() -> Vec<Mode> {
    vec![
        ("impulse", |d| d.contact_model = ContactMode::Impulse),
        ("switching", |d| d.contact_model = ContactMode::Switching),
    ]
}

/// The scenes, in table order.
///
/// # Errors
/// A bundled scene that cannot be read.
pub fn peer_scenes() -> Result<Vec<PeerScene>> {
    let mut scenes = Vec::new();
    for n in PEER_STACK_SIZES {
        let desc = crate::stacks::stack_scene(n).with_duration(STACK_DURATION);
        scenes.push(PeerScene {
            name: format!("stack of {n}"),
            kind: Kind::Stack,
            scene: Scene::new(desc, Path::new(".")),
        });
    }
    for (file, kind) in [
        ("dominos", Kind::Dominos),
        ("block-on-ramp", Kind::Ramp),
        ("sliding-to-rolling", Kind::Rolling),
        ("pool-break", Kind::Pool),
    ] {
        scenes.push(PeerScene {
            name: file.to_string(),
            kind,
            scene: crate::cases::scenes::load_scene(file)?,
        });
    }
    Ok(scenes)
}

/// The headline measurement of a scene of `kind` on a trajectory.
///
/// # Errors
/// What the measurement could not find in the scene or the trajectory.
pub fn measure(kind: Kind, scene: &SceneDesc, traj: &Trajectory) -> Result<Measure> {
    match kind {
        Kind::Stack => measure::stack(scene, traj),
        Kind::Dominos => measure::dominos(scene, traj),
        Kind::Ramp => measure::ramp(scene, traj),
        Kind::Rolling => measure::rolling(scene, traj),
        Kind::Pool => measure::pool(scene, traj),
    }
}

/// Runs `scene` in `impulse` until its duration or until `budget` wall seconds have passed,
/// recording a frame at the scene's output rate; returns the frames and the wall time of the
/// stepping (the world is built before the clock starts).
///
/// # Errors
/// A scene the world refuses, or a failed step.
pub fn run_ours(scene: &Scene, budget: f64) -> Result<(Trajectory, f64)> {
    let duration = crate::cases::scenes::duration(scene)?;
    let mut world = World::from_scene(scene).map_err(|e| e.to_string())?;
    // The run stops at its first error, as `impulse run` does (`run_streaming`), so no step
    // keeps a copy of the world to restore: with the copy, each of the pool break's 2 000
    // frames cloned the world, and the bench measured 0.052 wall per simulated second where
    // `impulse run` took 0.029.
    world.set_rollback(false);
    let names = world.bodies().map(|(_, b)| b.name.clone()).collect();
    let frame = |world: &World| Frame {
        time: world.time(),
        bodies: world
            .states()
            .into_iter()
            .map(|s| State {
                position: s.position,
                rotation: s.rotation,
                com: s.com,
                velocity: s.velocity,
                omega: s.omega,
            })
            .collect(),
    };
    let rate = scene.desc.output_rate;
    let mut frames = vec![frame(&world)];
    let start = Instant::now();
    let mut k = 1u64;
    loop {
        let t = (k as f64 / rate).min(duration);
        world.step_until(t).map_err(|e| e.to_string())?;
        frames.push(frame(&world));
        if t >= duration || start.elapsed().as_secs_f64() > budget {
            break;
        }
        k += 1;
    }
    Ok((Trajectory { names, frames }, start.elapsed().as_secs_f64()))
}

/// One engine on one scene.
struct Row {
    scene: String,
    engine: String,
    /// Simulated time reached (s), of the scene's duration.
    reached: f64,
    duration: f64,
    runs: usize,
    /// Median wall seconds per simulated second.
    speed: f64,
    /// The measurement, or why there is none.
    measure: std::result::Result<Measure, String>,
}

/// Runs an engine [`RUNS`] times (once if the first run hits the budget) and measures the
/// first run's trajectory.
fn bench_engine(
    ps: &PeerScene,
    engine: &str,
    scene: &Scene,
    mut once: impl FnMut(&Scene) -> Result<(Trajectory, f64)>,
) -> Row {
    let duration = scene.desc.duration.unwrap_or(f64::NAN);
    let failed = |why: String| Row {
        scene: ps.name.clone(),
        engine: engine.to_string(),
        reached: 0.0,
        duration,
        runs: 0,
        speed: f64::NAN,
        measure: Err(why),
    };
    let (traj, wall) = match once(scene) {
        Ok(r) => r,
        Err(why) => return failed(why),
    };
    let reached = traj.frames.last().map_or(0.0, |f| f.time);
    let mut walls = vec![wall];
    if reached >= duration {
        for _ in 1..RUNS {
            match once(scene) {
                Ok((_, w)) => walls.push(w),
                Err(why) => return failed(why),
            }
        }
    }
    walls.sort_by(f64::total_cmp);
    let speed = walls[walls.len() / 2] / reached;
    Row {
        scene: ps.name.clone(),
        engine: engine.to_string(),
        reached,
        duration,
        runs: walls.len(),
        speed,
        measure: measure(ps.kind, &scene.desc, &traj),
    }
}

/// The peer engine's runs of a scene: one row per configuration.
/// The peer's configurations of the scale bench ([`crate::scale`]).
#[cfg(feature = "peers")]
pub fn rapier_configs() -> &'static [rapier::Config] {
    &rapier::SCALE_CONFIGS
}

/// Runs `scene` in the peer (see `rapier::run`).
///
/// # Errors
/// A body the peer cannot take.
#[cfg(feature = "peers")]
pub fn run_rapier(
    scene: &Scene,
    config: &rapier::Config,
    budget: f64,
    record_rate: Option<f64>,
) -> Result<(Trajectory, f64)> {
    rapier::run(scene, config, budget, record_rate)
}

#[cfg(feature = "peers")]
fn peer_rows(ps: &PeerScene) -> Vec<Row> {
    rapier::CONFIGS
        .iter()
        .map(|config| {
            bench_engine(ps, config.name, &ps.scene, |s| {
                rapier::run(s, config, WALL_BUDGET, None)
            })
        })
        .collect()
}

/// Runs every scene in every engine, prints the table and writes `peers.csv` and `peers.svg`
/// into `out`.
///
/// # Errors
/// Built without the `peers` feature (the message says which command to run), a bundled
/// scene that cannot be read, or an output file that cannot be written.
pub fn run(out: &Path) -> Result<()> {
    #[cfg(not(feature = "peers"))]
    {
        let _ = out;
        Err("this xtask was built without the peer engine: run `cargo run --release -p xtask --features peers -- bench --peers --in-release` (`cargo xtask bench --peers` does this)".to_string())
    }
    #[cfg(feature = "peers")]
    {
        let scenes = peer_scenes()?;
        println!(
            "peers: wall s per simulated s (median of {RUNS} runs, budget {WALL_BUDGET} s a run) and headline error of the same scene descriptions"
        );
        println!(
            "impulse on rayon's default pool ({} threads); rapier3d-f64 on one thread (no `parallel` feature), its defaults but dt, length_unit from gravity",
            rayon::current_num_threads()
        );
        println!(
            "{:<20} {:<16} {:>11} {:>4} {:>12} {:>10}  headline: what happened",
            "scene", "engine", "sim s", "runs", "wall/sim s", "error"
        );
        let mut rows = Vec::new();
        for ps in &scenes {
            let mut mine = Vec::new();
            for (mode, change) in our_modes() {
                let mut scene = ps.scene.clone();
                change(&mut scene.desc);
                mine.push(bench_engine(ps, mode, &scene, |s| run_ours(s, WALL_BUDGET)));
            }
            mine.extend(peer_rows(ps));
            for r in &mine {
                println!("{}", table_line(r));
            }
            rows.extend(mine);
        }
        println!();
        print!("{}", side_by_side(&rows));
        let csv = out.join("peers.csv");
        std::fs::write(&csv, to_csv(&rows)).map_err(|e| format!("{}: {e}", csv.display()))?;
        let svg = out.join("peers.svg");
        std::fs::write(&svg, plot(&rows)).map_err(|e| format!("{}: {e}", svg.display()))?;
        println!("wrote {} and {}", csv.display(), svg.display());
        Ok(())
    }
}

fn table_line(r: &Row) -> String {
    let (error, what) = match &r.measure {
        Ok(m) => (
            format!("{:.2e}", m.error),
            format!("{}: {}", m.headline, m.note),
        ),
        Err(why) => ("-".to_string(), format!("not measured: {why}")),
    };
    let reached = if r.reached < r.duration {
        format!("{:.2}/{}", r.reached, r.duration)
    } else {
        format!("{}", r.duration)
    };
    format!(
        "{:<20} {:<16} {:>11} {:>4} {:>12.5} {:>10}  {}",
        r.scene, r.engine, reached, r.runs, r.speed, error, what
    )
}

/// One line per scene: speed and error of every engine, in the order they ran.
fn side_by_side(rows: &[Row]) -> String {
    let mut engines: Vec<&str> = Vec::new();
    let mut scenes: Vec<&str> = Vec::new();
    for r in rows {
        if !engines.contains(&r.engine.as_str()) {
            engines.push(&r.engine);
        }
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    let mut s = format!("{:<20}", "wall/sim s | error");
    for e in &engines {
        let _ = write!(s, " | {e:^21}");
    }
    s.push('\n');
    for scene in scenes {
        let _ = write!(s, "{scene:<20}");
        for e in &engines {
            match rows.iter().find(|r| r.scene == scene && r.engine == *e) {
                Some(r) => {
                    let error = r
                        .measure
                        .as_ref()
                        .map_or("-".to_string(), |m| format!("{:.2e}", m.error));
                    let _ = write!(s, " | {:>10.5} {:>10}", r.speed, error);
                }
                None => {
                    let _ = write!(s, " | {:>21}", "-");
                }
            }
        }
        s.push('\n');
    }
    s
}

fn to_csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "scene,engine,duration_s,simulated_s,runs,wall_per_sim_s,headline,error,details,note\n",
    );
    for r in rows {
        let (headline, error, details, note) = match &r.measure {
            Ok(m) => (
                m.headline.to_string(),
                m.error.to_string(),
                m.details
                    .iter()
                    .map(|(k, v)| format!("{k}={v}"))
                    .collect::<Vec<_>>()
                    .join(";"),
                m.note.clone(),
            ),
            Err(why) => (String::new(), String::new(), String::new(), why.clone()),
        };
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},\"{}\"",
            r.scene,
            r.engine,
            r.duration,
            r.reached,
            r.runs,
            r.speed,
            headline,
            error,
            details,
            note.replace('"', "'")
        );
    }
    s
}

/// Error against wall time per simulated second, log–log, one panel per scene, one colour per
/// engine; an error of 0 sits at [`PLOT_ERROR_FLOOR`], an infinite one (never rolled, never
/// struck) on the panel's top edge as a hollow circle.
fn plot(rows: &[Row]) -> String {
    const COLOURS: [&str; 4] = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd"];
    let mut engines: Vec<&str> = Vec::new();
    let mut scenes: Vec<&str> = Vec::new();
    for r in rows {
        if !engines.contains(&r.engine.as_str()) {
            engines.push(&r.engine);
        }
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    let (pw, ph, m, cols) = (300.0, 220.0, 46.0, 3usize);
    let rows_n = scenes.len().div_ceil(cols);
    let (w, h) = (pw * cols as f64, ph * rows_n as f64 + 40.0);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"10\">\n<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n"
    );
    for (k, e) in engines.iter().enumerate() {
        let _ = writeln!(
            s,
            "<circle cx=\"{0}\" cy=\"14\" r=\"4\" fill=\"{1}\"/><text x=\"{2}\" y=\"18\">{e}</text>",
            16.0 + 170.0 * k as f64,
            COLOURS[k % COLOURS.len()],
            24.0 + 170.0 * k as f64
        );
    }
    for (n, scene) in scenes.iter().enumerate() {
        let (ox, oy) = ((n % cols) as f64 * pw, (n / cols) as f64 * ph + 30.0);
        let pts: Vec<(f64, f64, bool, usize)> = rows
            .iter()
            .filter(|r| r.scene == *scene && r.speed.is_finite() && r.speed > 0.0)
            .filter_map(|r| {
                let error = r.measure.as_ref().ok()?.error;
                let k = engines.iter().position(|e| *e == r.engine)?;
                Some((
                    r.speed.log10(),
                    error.max(PLOT_ERROR_FLOOR).log10(),
                    error.is_finite(),
                    k,
                ))
            })
            .collect();
        let finite =
            |f: fn(f64, f64) -> f64, init: f64, sel: fn(&(f64, f64, bool, usize)) -> f64| {
                pts.iter().filter(|p| p.2).map(sel).fold(init, f)
            };
        let x0 = pts
            .iter()
            .map(|p| p.0)
            .fold(f64::INFINITY, f64::min)
            .floor();
        let x1 = pts
            .iter()
            .map(|p| p.0)
            .fold(f64::NEG_INFINITY, f64::max)
            .ceil();
        let y0 = finite(f64::min, f64::INFINITY, |p| p.1).floor();
        let y1 = finite(f64::max, f64::NEG_INFINITY, |p| p.1).ceil();
        let (x0, x1) = if x0.is_finite() {
            (x0, x1.max(x0 + 1.0))
        } else {
            (-3.0, 0.0)
        };
        let (y0, y1) = if y0.is_finite() {
            (y0, y1.max(y0 + 1.0))
        } else {
            (-3.0, 0.0)
        };
        let headline = rows
            .iter()
            .filter(|r| r.scene == *scene)
            .find_map(|r| r.measure.as_ref().ok())
            .map_or("-", |m| m.headline);
        let sx = |x: f64| ox + m + (x - x0) / (x1 - x0) * (pw - 1.5 * m);
        let sy = |y: f64| oy + ph - m - (y.min(y1) - y0) / (y1 - y0) * (ph - 1.7 * m);
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" font-size=\"12\">{scene}</text>\n<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" font-size=\"9\">error: {headline}</text>\n<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"none\" stroke=\"#888\"/>",
            ox + m + 0.5 * (pw - 1.5 * m),
            oy + 0.5 * m - 12.0,
            ox + m + 0.5 * (pw - 1.5 * m),
            oy + 0.5 * m,
            sx(x0),
            sy(y1),
            sx(x1) - sx(x0),
            sy(y0) - sy(y1)
        );
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\">1e{}</text><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">1e{} wall/sim s</text><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">1e{}</text><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">1e{}</text>",
            sx(x0),
            sy(y0) + 12.0,
            x0 as i64,
            sx(x1),
            sy(y0) + 12.0,
            x1 as i64,
            sx(x0) - 3.0,
            sy(y0),
            y0 as i64,
            sx(x0) - 3.0,
            sy(y1) + 8.0,
            y1 as i64
        );
        for p in &pts {
            let colour = COLOURS[p.3 % COLOURS.len()];
            let fill = if p.2 { colour } else { "none" };
            let _ = writeln!(
                s,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"4\" fill=\"{fill}\" stroke=\"{colour}\"/>",
                sx(p.0),
                sy(p.1)
            );
        }
    }
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every scene of the bench loads and has a duration; stacks are 10 s long.
    #[test]
    fn peer_scenes_load() {
        let scenes = peer_scenes().unwrap();
        assert_eq!(scenes.len(), PEER_STACK_SIZES.len() + 4);
        for s in &scenes {
            assert!(s.scene.desc.duration.is_some(), "{}", s.name);
        }
        assert_eq!(scenes[0].scene.desc.duration, Some(STACK_DURATION));
    }

    /// Our engine's trajectory of a two-block stack over a short run is measured as standing
    /// with the penetration the independent monitor allows (≤ ε_c).
    #[test]
    fn our_two_block_stack_stands_by_the_peer_measure() {
        let desc = crate::stacks::stack_scene(2).with_duration(0.2);
        let scene = Scene::new(desc, Path::new("."));
        let (traj, _) = run_ours(&scene, f64::INFINITY).unwrap();
        let m = measure(Kind::Stack, &scene.desc, &traj).unwrap();
        assert!(m.note.starts_with("stands"), "{}", m.note);
        assert!(
            m.detail("max_penetration_over_eps_c").unwrap() <= 1.0,
            "{m:?}"
        );
    }
}
