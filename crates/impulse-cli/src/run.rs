//! `impulse run`: simulate a scene file, print a summary, write the trajectory and plots.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use impulse_sim::{ContactMode, Recording, Scene, TrajectoryFormat, TrajectoryWriter, World};

use crate::plot;
use crate::progress::Progress;
use crate::text;

/// What `impulse run` was asked to do.
pub struct RunArgs<'a> {
    /// The scene file.
    pub scene: &'a Path,
    /// Simulated end time (default: the scene's duration).
    pub until: Option<f64>,
    /// Trajectory output (.csv or .json).
    pub out: Option<&'a Path>,
    /// Impact events output (.csv or .json).
    pub events: Option<&'a Path>,
    /// Joint coordinates output (.csv or .json).
    pub joints: Option<&'a Path>,
    /// Directory for SVG plots.
    pub plot: Option<&'a Path>,
    /// Animated glTF binary output (.glb).
    pub gltf: Option<&'a Path>,
    /// Self-contained replay page output (.html).
    pub html: Option<&'a Path>,
    /// Rayon threads (default: all cores).
    pub threads: Option<usize>,
    /// Contact model overriding the scene's.
    pub contact_model: Option<ContactModelArg>,
    /// Print the wall-time profile of the loop's parts.
    pub profile: bool,
    /// Wall seconds after which the run stops at its next frame, its outputs valid.
    pub max_wall: Option<f64>,
}

/// The contact model named on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ContactModelArg {
    /// Impacts as impulses, sustained contact as constraints.
    Switching,
    /// Every contact an impulse (thesis chapters 2–3).
    Impulse,
}

/// Runs the scene; returns the summary text.
pub fn run(args: &RunArgs<'_>) -> Result<String, String> {
    let mut scene = Scene::read(args.scene).map_err(|e| e.to_string())?;
    if let Some(m) = args.contact_model {
        scene.desc.contact_model = match m {
            ContactModelArg::Switching => ContactMode::Switching,
            ContactModelArg::Impulse => ContactMode::Impulse,
        };
    }
    let until = match (args.until, scene.desc.duration) {
        (Some(t), _) => t,
        (None, Some(d)) => d,
        (None, None) => {
            return Err(format!(
                "{}: the scene gives no `duration`; pass --until T (seconds)",
                args.scene.display()
            ));
        }
    };
    if !(until.is_finite() && until > 0.0) {
        return Err(format!("--until {until}: must be a finite time > 0"));
    }
    if let Some(w) = args.max_wall
        && !(w.is_finite() && w > 0.0)
    {
        return Err(format!(
            "--max-wall {w}: must be a finite number of seconds > 0"
        ));
    }
    impulse_sim::scene::check_frames(until, scene.desc.output_rate)
        .map_err(|e| format!("--until {until}: {e} (lower the scene's output_rate)"))?;
    if let Some(out) = args.out {
        format_of(out)?;
        directory_exists("--out", out)?;
    }
    if let Some(path) = args.events {
        crate::events::EventSink::check(path)?;
    }
    if let Some(path) = args.gltf {
        crate::glb::check_path(path)?;
        directory_exists("--gltf", path)?;
    }
    if let Some(path) = args.html {
        crate::html::check_path(path)?;
        directory_exists("--html", path)?;
    }
    // The outputs' places are checked before the run, not after it: a long run whose
    // results cannot be written is lost.
    if let Some(dir) = args.plot {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("--plot {}: cannot create it: {e}", dir.display()))?;
    }
    let mut world = World::from_scene(&scene).map_err(|e| e.to_string())?;
    for w in scene.warnings() {
        eprintln!("warning: {w}");
    }
    if let Some(path) = args.joints {
        crate::joints::JointSink::check(path, &world)?;
    }
    if let Some(n) = args.threads {
        if n == 0 {
            return Err("--threads 0: need at least one thread".into());
        }
        world
            .set_threads(n)
            .map_err(|e| format!("--threads {n}: {e}"))?;
    }
    world.set_profiling(args.profile);
    // The page shows the impacts: keep them all.
    world.set_event_log(args.html.is_some());
    let progress = Progress::time("impulse run", until);
    // The trajectory is written as it is made, into a file beside the output that takes its
    // name only when the run has ended well: a failed or interrupted run leaves the file the
    // user had (or none), never half of one.
    crate::interrupt::install();
    let wall = std::time::Instant::now();
    let mut sink = match args.out {
        Some(out) => Some(Sink::create(out, &world)?),
        None => None,
    };
    let mut events = match args.events {
        Some(path) => Some(crate::events::EventSink::create(path, &world)?),
        None => None,
    };
    let mut joints = match args.joints {
        Some(path) => Some(crate::joints::JointSink::create(path, &world)?),
        None => None,
    };
    let rec = impulse_sim::run_streaming(
        &mut world,
        until,
        scene.desc.output_rate,
        // Only the plots, the page and the glTF file read the frames after the run; the
        // summary reads the first and the last.
        if args.plot.is_some() || args.html.is_some() || args.gltf.is_some() {
            KEPT_FRAMES
        } else {
            2
        },
        |f| {
            if let Some(s) = sink.as_mut() {
                s.frame(f)?;
            }
            if let Some(e) = events.as_mut() {
                e.frame(f)?;
            }
            if let Some(j) = joints.as_mut() {
                j.frame(f)?;
            }
            Ok(!crate::interrupt::requested()
                && args
                    .max_wall
                    .is_none_or(|w| wall.elapsed().as_secs_f64() < w))
        },
        |t| progress.set_time(t),
    );
    let rec = match rec {
        Ok(rec) => rec,
        Err(e) => {
            if let Some(s) = sink {
                s.abandon();
            }
            if let Some(s) = events {
                s.abandon();
            }
            if let Some(s) = joints {
                s.abandon();
            }
            return Err(e.to_string());
        }
    };
    progress.finish();
    if let Some(s) = sink {
        s.finish(rec.max_penetration())?;
    }
    if let Some(s) = events {
        s.finish()?;
    }
    if let Some(s) = joints {
        s.finish()?;
    }
    if let Some(path) = args.gltf {
        crate::glb::write(path, &rec, &world)?;
    }
    if let Some(path) = args.html {
        crate::html::write(path, &rec, &world, &scene)?;
    }
    if let Some(dir) = args.plot {
        // Created before the run.
        let energy = dir.join("energy.svg");
        std::fs::write(&energy, plot::energy_plot(&rec, &scene)?)
            .map_err(|e| format!("cannot write {}: {e}", energy.display()))?;
        let paths = dir.join("paths.svg");
        std::fs::write(&paths, plot::paths_plot(&rec, &world, &scene)?)
            .map_err(|e| format!("cannot write {}: {e}", paths.display()))?;
    }
    let reached = rec.frames.last().map_or(until, |f| f.time);
    let mut text = summary(&scene, &rec, reached);
    if reached < until {
        if !text.ends_with('\n') {
            text.push('\n');
        }
        let why = if crate::interrupt::requested() {
            "interrupted (Ctrl-C or SIGTERM)".to_owned()
        } else {
            format!(
                "at the wall-time limit of {} s (--max-wall)",
                text::significant(args.max_wall.unwrap_or(f64::NAN))
            )
        };
        let _ = write!(
            text,
            "stopped:          {why}, after {} of {} simulated seconds; the outputs hold the \
             run up to there",
            text::significant(reached),
            text::significant(until)
        );
    }
    if let Some(p) = world.profile() {
        text.push_str(&profile_text(&p, &world));
    }
    Ok(text)
}

/// The profile as lines of the summary: each part's share of the loop's wall time (thesis
/// Table 7.2), and the multibodies' redone steps.
fn profile_text(p: &impulse_sim::Profile, world: &World) -> String {
    let mut text = format!(
        "\nprofile:          {} in the event loop\n",
        text::duration(p.total.as_secs_f64())
    );
    for (name, share) in p.shares() {
        text.push_str(&format!("  {name:<28} {:5.1} %\n", 100.0 * share));
    }
    let c = world.counters();
    if !world.multibody_handles().is_empty() {
        text.push_str(&format!(
            "  multibody steps redone:      {} ({} box, {} slack violations; {} link contacts)\n",
            c.rollbacks, c.box_violations, c.slack_violations, c.link_contacts
        ));
    }
    for h in world.multibody_handles() {
        let (Some(sim), Some(name)) = (world.multibody(h), world.multibody_name(h)) else {
            continue;
        };
        let (s, l) = (sim.stats(), sim.limit_stats());
        text.push_str(&format!(
            "  multibody {name}: {} steps ({} rejected, {} derivative evaluations), {} resting on stops, {} stops struck ({} trial steps locating them)\n",
            s.steps, s.rejected_steps, s.derivative_evaluations, l.resting_steps, l.strikes, l.locating_steps
        ));
    }
    text
}

/// Frames a run keeps in memory for its plots, page and glTF file: a longer run's are every
/// second, fourth, … frame (and the last), so that memory does not grow with the run's length
/// while `--out` gets every frame ([`impulse_sim::run_streaming`]). Default `10_000`: a page of
/// ten bodies at that many frames is about 13 MB.
pub const KEPT_FRAMES: usize = 10_000;

/// The `--out` file being written: a temporary file beside it, renamed at the end.
struct Sink {
    writer: TrajectoryWriter<std::io::BufWriter<std::fs::File>>,
    partial: PathBuf,
    out: PathBuf,
}

impl Sink {
    fn create(out: &Path, world: &World) -> Result<Self, String> {
        let format = match format_of(out)? {
            Format::Csv => TrajectoryFormat::Csv,
            Format::Json => TrajectoryFormat::Json,
        };
        let mut name = out.file_name().unwrap_or_default().to_os_string();
        name.push(".partial");
        let partial = out.with_file_name(name);
        let file = std::fs::File::create(&partial)
            .map_err(|e| format!("--out: cannot write {}: {e}", partial.display()))?;
        let names: Vec<String> = world.bodies().map(|(_, b)| b.name.clone()).collect();
        let writer = TrajectoryWriter::new(std::io::BufWriter::new(file), format, &names)
            .map_err(|e| format!("--out: cannot write {}: {e}", partial.display()))?;
        Ok(Self {
            writer,
            partial,
            out: out.to_path_buf(),
        })
    }

    fn frame(&mut self, f: &impulse_sim::Frame) -> Result<(), impulse_sim::SimError> {
        self.writer
            .frame(f)
            .map_err(|e| impulse_sim::SimError::Runtime {
                time: f.time,
                message: format!("cannot write {}: {e}", self.partial.display()),
            })
    }

    /// Ends the file and gives it its name.
    fn finish(self, max_penetration: f64) -> Result<(), String> {
        let cannot = |e: std::io::Error| format!("cannot write {}: {e}", self.out.display());
        let file = self
            .writer
            .finish(max_penetration)
            .map_err(cannot)?
            .into_inner()
            .map_err(|e| cannot(e.into_error()))?;
        file.sync_all().map_err(cannot)?;
        std::fs::rename(&self.partial, &self.out).map_err(cannot)
    }

    /// Removes the temporary file of a run that failed.
    fn abandon(self) {
        let _ = std::fs::remove_file(&self.partial);
    }
}

enum Format {
    Csv,
    Json,
}

/// Refuses an output file whose directory does not exist (named with its option `flag`).
pub(crate) fn directory_exists(flag: &str, file: &Path) -> Result<(), String> {
    let dir = match file.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if dir.is_dir() {
        Ok(())
    } else {
        Err(format!(
            "{flag} {}: the directory {} does not exist",
            file.display(),
            dir.display()
        ))
    }
}

fn format_of(out: &Path) -> Result<Format, String> {
    match out.extension().and_then(|e| e.to_str()) {
        Some("csv") => Ok(Format::Csv),
        Some("json") => Ok(Format::Json),
        _ => Err(format!(
            "--out {}: the file name must end in .csv or .json",
            out.display()
        )),
    }
}

fn summary(scene: &Scene, rec: &Recording, until: f64) -> String {
    let c = rec.counters;
    let first = &rec.frames[0];
    let last = rec.frames.last().unwrap_or(first);
    let mut s = String::new();
    let name = if scene.desc.name.is_empty() {
        "(unnamed)"
    } else {
        &scene.desc.name
    };
    let _ = writeln!(s, "scene:            {name} ({} bodies)", rec.names.len());
    let _ = writeln!(s, "simulated time:   {until} s");
    let _ = writeln!(s, "wall time:        {}", text::duration(rec.wall_time));
    let slowdown = rec.wall_time / until;
    let _ = if slowdown.is_finite() {
        writeln!(
            s,
            "slowdown:         {} (wall / simulated; < 1 is faster than real time)",
            text::significant(slowdown)
        )
    } else {
        writeln!(
            s,
            "slowdown:         not measured (a run of {} s is too short to time)",
            text::significant(until)
        )
    };
    let _ = writeln!(s, "collisions:       {}", c.collisions);
    let _ = writeln!(
        s,
        "microcollisions:  {} ({} by the reversing impulse)",
        c.microcollisions, c.reversing
    );
    let _ = match scene.desc.contact_model {
        ContactMode::Switching => writeln!(
            s,
            "contact model:    switching: {} island steps, {} impulsive island solves, {} islands put to sleep\n\
             island steps:     {} long (at rest or steady), {} short for turning, {} after strikes, {} cut to fit the envelope, {} cut to a slip → stick transition; {} transitions taken at the step's end\n\
             contact solver:   {} solves, {} sweeps, {} stopped unconverged at the sweep cap, {} patch jumps, {} direct solves accepted",
            c.island_steps,
            c.transients,
            c.sleeps,
            c.long_steps,
            c.turning_steps,
            c.struck_steps,
            c.fitted_steps,
            c.located_steps,
            c.rounded_transitions,
            c.island_solves,
            c.island_sweeps,
            c.unconverged_solves,
            c.patch_jumps,
            c.direct_solves
        ),
        ContactMode::Impulse => writeln!(s, "contact model:    impulse"),
    };
    let _ = writeln!(
        s,
        "pair checks:      {} in {} steps; {} bounds from cached distances; heap operations {}",
        c.pair_checks, c.steps, c.cached_bounds, c.heap_operations
    );
    let _ = writeln!(
        s,
        "kinetic energy:   {:.6e} at start, {:.6e} at end",
        first.kinetic_energy, last.kinetic_energy
    );
    let _ = writeln!(
        s,
        "total energy:     {:.6e} at start, {:.6e} at end (kinetic + potential)",
        first.kinetic_energy + first.potential_energy,
        last.kinetic_energy + last.potential_energy
    );
    if c.unresolved > 0 {
        let _ = writeln!(
            s,
            "unresolved:       {} contacts the response could not resolve (fallback impulse used)",
            c.unresolved
        );
    }
    let p = &rec.penetration;
    let eps = scene.desc.collision_epsilon;
    let depth = rec.max_penetration();
    let _ = write!(
        s,
        "penetration:      {}: largest {depth:.3e} ({:.3} ε_c, ε_c = {eps:.3e}), measured \
         independently at {} frames ({} pair measurements)",
        penetration_verdict(depth, eps),
        depth / eps,
        p.samples,
        p.pairs_measured
    );
    if let Some((t, a, b)) = &p.worst {
        let _ = write!(s, "; worst: {a} / {b} at t = {t:.4} s");
    } else if p.min_distance.is_finite() {
        let _ = write!(s, "; closest approach {:.3e}", p.min_distance);
    }
    s
}

/// The penetration line's verdict in words: `none` (no overlap at any frame), `none beyond ε_c`
/// (bodies overlapped by at most ε_c: contact, which the simulator allows), or `yes, beyond ε_c`
/// (the promise broken; also for a depth that is not a number).
fn penetration_verdict(depth: f64, eps: f64) -> &'static str {
    if depth <= 0.0 {
        "none"
    } else if depth <= eps {
        "none beyond ε_c"
    } else {
        "yes, beyond ε_c"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The penetration line says in words whether the no-penetration promise held.
    #[test]
    fn penetration_is_judged_in_words() {
        let eps = 1e-4;
        assert_eq!(penetration_verdict(0.0, eps), "none");
        assert_eq!(penetration_verdict(0.5e-4, eps), "none beyond ε_c");
        assert_eq!(penetration_verdict(1e-4, eps), "none beyond ε_c");
        assert_eq!(penetration_verdict(1.01e-4, eps), "yes, beyond ε_c");
        assert_eq!(penetration_verdict(f64::NAN, eps), "yes, beyond ε_c");
    }
}
