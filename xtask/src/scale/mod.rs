//! `cargo xtask bench --scale [--peers] [--only NAME] [--budget S] [--out DIR]`: how the cost
//! of contact-rich scenes grows with the number of bodies.
//!
//! The scenes ([`scenes::all`]): piles of 27, 216 and 1000 boxes and of spheres, and a
//! pyramid of 20 rows, written as RON files into `<out>/scenes/` (so that `impulse run` and
//! anyone else can run the same geometry). `impulse` runs each on one thread, and the pile of
//! 1000 boxes again on two, whose trajectory must be bit for bit the one-thread run's; with
//! `--peers` rapier3d-f64 runs each at dt 1/60 and 1 ms. Every run records frames at
//! [`scenes::FRAME_RATE`] and is judged from its frames alone ([`judge::judge`]: deepest overlap,
//! depth below the ground, speed at the end, drift), the same judge for every engine.
//!
//! Output: a table on stdout with the cost (wall time of the stepping ÷ simulated time) and
//! the verdicts, each engine's cost exponent per kind (the slope of log cost against log
//! bodies from 27 to 1000), `scale.csv`, and `scale.svg` (cost against bodies, log–log). A run
//! stops when it passes `--budget` wall seconds (default [`DEFAULT_BUDGET`]); its row says how
//! far it got, and its cost is the wall time over the simulated time reached.

pub mod judge;
pub mod scenes;

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use impulse_sim::{Scene, World};

use crate::Result;
use crate::peers::measure::{Frame, State, Trajectory};
use judge::{REST_SPEED, Verdict, judge};
use scenes::{EPSILON, Kind, ScaleScene};

/// Wall-clock budget of one run (s).
pub const DEFAULT_BUDGET: f64 = 600.0;
/// The pyramid stands when no cube's centre has moved more than this from its start (m).
pub const PYRAMID_DRIFT: f64 = 1e-3;
/// The scene run again on two threads, whose trajectory must equal the one-thread run's.
pub const THREADS_SCENE: &str = "boxes-1000";

/// MuJoCo 4.0's cost at dt 2 ms on this machine kind (wall s per simulated s), measured from
/// the same geometry when the bench was specified: the targets `impulse` is held to. The
/// pile of 1000 spheres was not measured.
pub const MUJOCO_2MS: [(&str, f64); 6] = [
    ("boxes-27", 0.063),
    ("boxes-216", 0.72),
    ("boxes-1000", 4.84),
    ("spheres-27", 0.059),
    ("spheres-216", 6.4),
    ("pyramid-20", 2.0),
];

/// Options of the scale bench.
#[derive(Debug, Default, PartialEq)]
pub struct Options {
    /// Output directory (default `target/bench`).
    pub out: Option<PathBuf>,
    /// Only the scenes whose name contains this.
    pub only: Option<String>,
    /// Wall budget of one run (s).
    pub budget: Option<f64>,
    /// Run rapier too.
    pub peers: bool,
}

/// One engine on one scene.
#[derive(Clone, Debug)]
struct Row {
    scene: String,
    kind: Kind,
    bodies: usize,
    engine: String,
    duration: f64,
    reached: f64,
    wall: f64,
    verdict: std::result::Result<Verdict, String>,
    /// Our counters: pair checks, island solves, sweeps, unconverged solves, loop steps.
    counters: Option<impulse_sim::Counters>,
}

impl Row {
    fn cost(&self) -> f64 {
        if self.reached > 0.0 {
            self.wall / self.reached
        } else {
            f64::INFINITY
        }
    }

    fn finished(&self) -> bool {
        self.reached >= self.duration * (1.0 - 1e-9)
    }
}

/// Runs `scene` in `impulse` on `threads` threads for its duration or until `budget` wall
/// seconds pass; returns the frames (at the scene's output rate), the wall time of the
/// stepping and the world's counters.
fn run_ours(
    scene: &Scene,
    threads: usize,
    budget: f64,
) -> Result<(Trajectory, f64, impulse_sim::Counters)> {
    let duration = scene.desc.duration.ok_or("the scene has no duration")?;
    let mut world = World::from_scene(scene).map_err(|e| e.to_string())?;
    world.set_threads(threads).map_err(|e| e.to_string())?;
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
    let mut wall = 0.0;
    let mut k = 1u64;
    loop {
        let t = (k as f64 / rate).min(duration);
        let start = Instant::now();
        world.step_until(t).map_err(|e| e.to_string())?;
        wall += start.elapsed().as_secs_f64();
        frames.push(frame(&world));
        if t >= duration || wall > budget {
            break;
        }
        k += 1;
    }
    Ok((Trajectory { names, frames }, wall, world.counters()))
}

/// Whether two trajectories are equal bit for bit.
fn identical(a: &Trajectory, b: &Trajectory) -> bool {
    let bits = |s: &State| {
        [
            s.position.to_array(),
            s.com.to_array(),
            s.velocity.to_array(),
            s.omega.to_array(),
        ]
        .into_iter()
        .flatten()
        .chain(s.rotation.to_array())
        .map(f64::to_bits)
        .collect::<Vec<u64>>()
    };
    a.frames.len() == b.frames.len()
        && a.frames.iter().zip(&b.frames).all(|(fa, fb)| {
            fa.time.to_bits() == fb.time.to_bits()
                && fa.bodies.len() == fb.bodies.len()
                && fa
                    .bodies
                    .iter()
                    .zip(&fb.bodies)
                    .all(|(x, y)| bits(x) == bits(y))
        })
}

/// Runs the scale bench.
///
/// # Errors
/// A scene that cannot be written or built, or an output file that cannot be written.
pub fn run(options: &Options) -> Result<()> {
    let out = options
        .out
        .clone()
        .unwrap_or_else(|| crate::workspace_root().join("target/bench"));
    let scene_dir = out.join("scenes");
    std::fs::create_dir_all(&scene_dir)
        .map_err(|e| format!("cannot create {}: {e}", scene_dir.display()))?;
    let budget = options.budget.unwrap_or(DEFAULT_BUDGET);
    let chosen: Vec<ScaleScene> = scenes::all()
        .into_iter()
        .filter(|s| {
            options
                .only
                .as_ref()
                .is_none_or(|o| s.name.contains(o.as_str()))
        })
        .collect();
    if chosen.is_empty() {
        return Err(format!("no scale scene matches {:?}", options.only));
    }
    let mut rows = Vec::new();
    println!(
        "{:<12} {:>6}  {:<18} {:>10} {:>9}  {:>9} {:>9} {:>9} {:>9}  counters",
        "scene", "bodies", "engine", "wall/sim", "reached", "overlap", "sunk", "end v", "drift"
    );
    for s in &chosen {
        let path = scene_dir.join(format!("{}.ron", s.name));
        let text = s.scene.to_ron().map_err(|e| e.to_string())?;
        std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        let scene = Scene {
            desc: s.scene.clone(),
            base_dir: scene_dir.clone(),
        };
        let duration = s.scene.duration.unwrap_or_default();
        let (traj, wall, counters) = run_ours(&scene, 1, budget)?;
        let row = |engine: String, traj: &Trajectory, wall: f64, counters| Row {
            scene: s.name.clone(),
            kind: s.kind,
            bodies: s.bodies,
            engine,
            duration,
            reached: traj.frames.last().map_or(0.0, |f| f.time),
            wall,
            verdict: judge(&s.scene, traj),
            counters,
        };
        let one = row("impulse".into(), &traj, wall, Some(counters));
        print_row(&one);
        rows.push(one);
        if s.name == THREADS_SCENE {
            let (traj2, wall2, counters2) = run_ours(&scene, 2, budget)?;
            let two = row("impulse 2 threads".into(), &traj2, wall2, Some(counters2));
            print_row(&two);
            let reached = traj.frames.len().min(traj2.frames.len());
            let same = identical(
                &Trajectory {
                    names: traj.names.clone(),
                    frames: traj.frames[..reached].to_vec(),
                },
                &Trajectory {
                    names: traj2.names.clone(),
                    frames: traj2.frames[..reached].to_vec(),
                },
            );
            println!(
                "{:<12} 2 threads: {:.2}× the speed of one; trajectories {} over {reached} frames",
                s.name,
                wall / traj.frames.last().map_or(1.0, |f| f.time) * two.reached / wall2,
                if same { "bit-identical" } else { "DIFFER" }
            );
            rows.push(two);
        }
        #[cfg(feature = "peers")]
        if options.peers {
            for config in crate::peers::rapier_configs() {
                let (traj, wall) =
                    crate::peers::run_rapier(&scene, config, budget, Some(scenes::FRAME_RATE))?;
                let r = row(config.name.to_owned(), &traj, wall, None);
                print_row(&r);
                rows.push(r);
            }
        }
    }
    let summary = summarise(&rows);
    print!("{summary}");
    let csv = out.join("scale.csv");
    std::fs::write(&csv, to_csv(&rows))
        .map_err(|e| format!("cannot write {}: {e}", csv.display()))?;
    let svg = out.join("scale.svg");
    std::fs::write(&svg, plot(&rows)?)
        .map_err(|e| format!("cannot write {}: {e}", svg.display()))?;
    println!(
        "wrote {}, {} and the scenes in {}",
        csv.display(),
        svg.display(),
        scene_dir.display()
    );
    Ok(())
}

fn print_row(r: &Row) {
    let (overlap, sunk, end, drift) = match &r.verdict {
        Ok(v) => (
            format!("{:.3} mm", v.max_penetration * 1e3),
            format!("{:.3} mm", v.below_ground * 1e3),
            format!("{:.1e}", v.end_speed),
            format!("{:.3} mm", v.max_drift * 1e3),
        ),
        Err(e) => (e.clone(), String::new(), String::new(), String::new()),
    };
    let counters = r.counters.map_or(String::new(), |c| {
        format!(
            "steps {} checks {} solves {} sweeps {} unconverged {}",
            c.steps, c.pair_checks, c.island_solves, c.island_sweeps, c.unconverged_solves
        )
    });
    println!(
        "{:<12} {:>6}  {:<18} {:>10.4} {:>5.2}/{:<3} {:>9} {:>9} {:>9} {:>9}  {counters}",
        r.scene,
        r.bodies,
        r.engine,
        r.cost(),
        r.reached,
        r.duration,
        overlap,
        sunk,
        end,
        drift
    );
}

/// The slope of log cost against log bodies over `points` (least squares); `None` with
/// fewer than two points.
fn exponent(points: &[(usize, f64)]) -> Option<f64> {
    if points.len() < 2 {
        return None;
    }
    let xy: Vec<(f64, f64)> = points
        .iter()
        .map(|&(n, c)| ((n as f64).ln(), c.ln()))
        .collect();
    let n = xy.len() as f64;
    let (mx, my) = (
        xy.iter().map(|p| p.0).sum::<f64>() / n,
        xy.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx).powi(2)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The verdict lines: per engine and kind the cost exponent; per run of ours the targets.
fn summarise(rows: &[Row]) -> String {
    let mut s = String::from("\ncost exponents (log cost / log bodies, finished runs only):\n");
    let mut engines: Vec<&str> = rows.iter().map(|r| r.engine.as_str()).collect();
    engines.dedup();
    engines.sort_unstable();
    engines.dedup();
    for engine in &engines {
        for kind in [Kind::Boxes, Kind::Spheres] {
            let points: Vec<(usize, f64)> = rows
                .iter()
                .filter(|r| r.engine == *engine && r.kind == kind && r.finished())
                .map(|r| (r.bodies, r.cost()))
                .collect();
            if let Some(e) = exponent(&points) {
                let _ = writeln!(
                    s,
                    "  {engine:<18} {kind:?}: {e:.2} over {} sizes",
                    points.len()
                );
            }
        }
    }
    s.push_str("\ntargets (impulse, one thread):\n");
    for r in rows.iter().filter(|r| r.engine == "impulse") {
        let mujoco = MUJOCO_2MS.iter().find(|m| m.0 == r.scene).map(|m| m.1);
        let cost = match mujoco {
            Some(m) => format!(
                "cost {:.4} against MuJoCo's {m}: {}",
                r.cost(),
                if r.finished() && r.cost() <= m {
                    "met"
                } else {
                    "NOT met"
                }
            ),
            None => format!("cost {:.4} (no MuJoCo figure)", r.cost()),
        };
        let verdict = match &r.verdict {
            Ok(v) => {
                let mut parts = vec![
                    format!(
                        "overlap {:.3} ε_c {}",
                        v.max_penetration / EPSILON,
                        if v.max_penetration <= EPSILON {
                            "ok"
                        } else {
                            "TOO DEEP"
                        }
                    ),
                    format!(
                        "below ground {:.3} mm {}",
                        v.below_ground * 1e3,
                        if v.below_ground <= EPSILON {
                            "ok"
                        } else {
                            "SUNK"
                        }
                    ),
                ];
                match r.kind {
                    Kind::Boxes => parts.push(format!(
                        "end speed {:.1e} m/s {}",
                        v.end_speed,
                        if v.end_speed <= REST_SPEED {
                            "at rest"
                        } else {
                            "NOT AT REST"
                        }
                    )),
                    Kind::Pyramid => parts.push(format!(
                        "drift {:.3} mm {}",
                        v.max_drift * 1e3,
                        if v.max_drift <= PYRAMID_DRIFT {
                            "stands"
                        } else {
                            "MOVED"
                        }
                    )),
                    Kind::Spheres => {}
                }
                parts.join(", ")
            }
            Err(e) => e.clone(),
        };
        let _ = writeln!(s, "  {:<12} {cost}; {verdict}", r.scene);
    }
    s
}

fn to_csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "scene,kind,bodies,engine,duration_s,reached_s,wall_s,wall_per_sim,max_overlap_m,below_ground_m,end_speed_m_s,max_drift_m,loop_steps,pair_checks,island_solves,island_sweeps,unconverged_solves\n",
    );
    for r in rows {
        let v = r.verdict.as_ref().ok();
        let num = |x: Option<f64>| x.map_or(String::new(), |x| format!("{x:.6e}"));
        let count = |f: fn(&impulse_sim::Counters) -> u64| {
            r.counters
                .as_ref()
                .map_or(String::new(), |c| f(c).to_string())
        };
        let _ = writeln!(
            s,
            "{},{:?},{},{},{},{},{:.6},{:.6e},{},{},{},{},{},{},{},{},{}",
            r.scene,
            r.kind,
            r.bodies,
            r.engine,
            r.duration,
            r.reached,
            r.wall,
            r.cost(),
            num(v.map(|v| v.max_penetration)),
            num(v.map(|v| v.below_ground)),
            num(v.map(|v| v.end_speed)),
            num(v.map(|v| v.max_drift)),
            count(|c| c.steps),
            count(|c| c.pair_checks),
            count(|c| c.island_solves),
            count(|c| c.island_sweeps),
            count(|c| c.unconverged_solves),
        );
    }
    s
}

/// Cost against bodies, log–log: one line per engine and kind of pile, the pyramid a point.
fn plot(rows: &[Row]) -> Result<String> {
    use plotters::prelude::*;
    const COLOURS: [RGBColor; 6] = [
        RGBColor(0x1f, 0x77, 0xb4),
        RGBColor(0xd6, 0x27, 0x28),
        RGBColor(0x2c, 0xa0, 0x2c),
        RGBColor(0x94, 0x67, 0xbd),
        RGBColor(0xff, 0x7f, 0x0e),
        RGBColor(0x8c, 0x56, 0x4b),
    ];
    let err = crate::plot::cannot_draw("scale");
    let x = crate::bench::Decades::covering(rows.iter().map(|r| r.bodies as f64));
    let y = crate::bench::Decades::covering(rows.iter().map(Row::cost));
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for r in rows.iter().filter(|r| r.cost().is_finite()) {
        let name = format!("{} {:?}", r.engine, r.kind).to_lowercase();
        match series.iter_mut().find(|s| s.0 == name) {
            Some(s) => s.1.push((r.bodies as f64, r.cost())),
            None => series.push((name, vec![(r.bodies as f64, r.cost())])),
        }
    }
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, crate::plot::SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = crate::plot::chart(&root, "cost against bodies".to_owned())
            .build_cartesian_2d(x, y)
            .map_err(&err)?;
        chart
            .configure_mesh()
            .x_desc("dynamic bodies")
            .y_desc("wall time / simulated time")
            .axis_desc_style(crate::plot::font(crate::plot::FONTS.1))
            .label_style(crate::plot::font(crate::plot::FONTS.2))
            .x_label_formatter(&crate::bench::Decades::label)
            .y_label_formatter(&crate::bench::Decades::label)
            .bold_line_style(RGBColor(0xcc, 0xcc, 0xcc))
            .light_line_style(RGBColor(0xee, 0xee, 0xee))
            .draw()
            .map_err(&err)?;
        for (k, (name, points)) in series.iter().enumerate() {
            let colour = COLOURS[k % COLOURS.len()];
            chart
                .draw_series(LineSeries::new(points.iter().copied(), colour))
                .map_err(&err)?
                .label(name.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour));
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                .map_err(&err)?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(crate::plot::font(crate::plot::FONTS.2))
            .background_style(WHITE.mix(0.8))
            .border_style(RGBColor(0xcc, 0xcc, 0xcc))
            .draw()
            .map_err(&err)?;
        root.present().map_err(&err)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_exponent_of_a_power_law_is_its_power() {
        let points: Vec<(usize, f64)> = [27usize, 216, 1000]
            .iter()
            .map(|&n| (n, 3e-3 * (n as f64).powf(1.2)))
            .collect();
        assert!((exponent(&points).unwrap() - 1.2).abs() < 1e-12);
        assert_eq!(exponent(&points[..1]), None);
    }
}
