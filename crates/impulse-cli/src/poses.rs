//! `impulse poses`: how often a part comes to rest in each stable pose (thesis §7.5): the
//! quasi-static, perturbed quasi-static and dynamic estimates side by side, from drops run in
//! parallel and, for a batch scheduler, in shards (`--shard K/N`, then `impulse poses merge`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use impulse_sim::poses::{self, DropOutcome, DropSettings, PosePart, Shard, StudyFile};

/// Options of `impulse poses`.
#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct PosesArgs {
    #[command(subcommand)]
    command: Option<PosesCommand>,
    /// The part: a `.ron` part file (`Part(name, shape, mass)`) or a convex `.obj` mesh; see
    /// fixtures/parts/.
    part: Option<PathBuf>,
    /// Number of drops of the whole study (all shards).
    #[arg(long, default_value_t = 2000)]
    drops: u64,
    /// Height of the part's lowest point above the belt at release (m).
    #[arg(long, allow_negative_numbers = true, default_value_t = DropSettings::default().height)]
    height: f64,
    /// Horizontal speed at release (m/s).
    #[arg(long, allow_negative_numbers = true, default_value_t = DropSettings::default().exit_speed)]
    exit_speed: f64,
    /// Coulomb friction between part and belt.
    #[arg(long, allow_negative_numbers = true, default_value_t = DropSettings::default().friction)]
    friction: f64,
    /// Restitution between part and belt.
    #[arg(long, allow_negative_numbers = true, default_value_t = DropSettings::default().restitution)]
    restitution: f64,
    /// Collision epsilon ε_c (m); default 1e-3 of the part's diameter.
    #[arg(long, allow_negative_numbers = true)]
    epsilon: Option<f64>,
    /// Largest tilt of a belt drop's start away from its rest pose (degrees).
    #[arg(long, allow_negative_numbers = true, default_value_t = DropSettings::default().jitter_degrees)]
    jitter: f64,
    /// Every drop starts uniform on SO(3): no belt drops, no belt-fed estimate.
    #[arg(long)]
    uniform_only: bool,
    /// A drop not at rest after this long (simulated s) is counted as unsettled.
    #[arg(long, allow_negative_numbers = true, default_value_t = DropSettings::default().max_time)]
    max_time: f64,
    /// Random seed: drop i's start depends only on (seed, i).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Worker threads (default: every core). Results do not depend on it.
    #[arg(long)]
    threads: Option<usize>,
    /// Run only drops K, K+N, K+2N, … (K in 0…N−1), for a batch scheduler; combine the
    /// shards' `--out` files with `impulse poses merge`.
    #[arg(long, value_name = "K/N")]
    shard: Option<String>,
    /// Write every drop's outcome to this JSON file (the input of `merge` and `--from`).
    /// While the study runs, each finished drop is kept in OUT.partial: a study stopped by
    /// Ctrl-C, `--max-wall` or a kill and run again with the same arguments runs only the
    /// drops it had not finished.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Stop cleanly after this many wall-clock seconds: no drop starts after it, the drops
    /// done are summarised, and with `--out` kept in OUT.partial for the same command to
    /// finish the study. Ctrl-C does the same (exit 130).
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    max_wall: Option<f64>,
    /// Summarise the drops of this JSON file (a run's or a merge's `--out`) instead of
    /// dropping.
    #[arg(long, conflicts_with_all = [
        "shard", "out", "drops", "height", "exit_speed", "friction", "restitution", "epsilon",
        "jitter", "uniform_only", "max_time", "seed", "threads",
    ])]
    from: Option<PathBuf>,
    /// Print the scene (RON) of drop N of this study instead of running it: `impulse run` on
    /// the saved scene replays that drop exactly, with plots and a trajectory.
    #[arg(long, value_name = "N", conflicts_with_all = ["shard", "out", "from"])]
    scene: Option<u64>,
    /// Half-angle of the perturbed quasi-static estimate's cone (degrees; the thesis used 20).
    #[arg(long, allow_negative_numbers = true, default_value_t = 20.0)]
    cone: f64,
    /// Confidence level of the intervals.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.95)]
    confidence: f64,
}

#[derive(clap::Subcommand)]
enum PosesCommand {
    /// Combine the `--out` files of the shards of one study into the file of the whole
    /// study (equal, byte for byte, to the file of the unsharded run).
    Merge {
        /// The shard files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// The merged file.
        #[arg(long)]
        out: PathBuf,
    },
}

/// Runs `impulse poses`; returns the text to print.
pub fn run(args: &PosesArgs) -> Result<String, String> {
    if let Some(PosesCommand::Merge { files, out }) = &args.command {
        return merge(files, out);
    }
    let part_path = args
        .part
        .as_deref()
        .ok_or("a part file is needed: `impulse poses PART.ron` (or `impulse poses merge …`)")?;
    let part = PosePart::load(part_path).map_err(|e| e.to_string())?;
    let settings = DropSettings {
        height: args.height,
        exit_speed: args.exit_speed,
        friction: args.friction,
        restitution: args.restitution,
        collision_epsilon: args.epsilon,
        belt_fed: !args.uniform_only,
        jitter_degrees: args.jitter,
        max_time: args.max_time,
    };
    settings.validate().map_err(|e| e.to_string())?;
    if !(args.cone.is_finite() && (0.0..90.0).contains(&args.cone)) {
        return Err(format!("--cone {}: must be in [0, 90) degrees", args.cone));
    }
    if !(args.confidence > 0.0 && args.confidence < 1.0) {
        return Err(format!(
            "--confidence {}: must be in (0, 1)",
            args.confidence
        ));
    }
    if let Some(n) = args.scene {
        if n >= args.drops {
            return Err(format!(
                "--scene {n}: the study has drops 0 to {}",
                args.drops.saturating_sub(1)
            ));
        }
        let desc = poses::drop_scene(&part, &settings, args.seed, n).map_err(|e| e.to_string())?;
        let text =
            ron::ser::to_string_pretty(&desc, ron::ser::PrettyConfig::default().struct_names(true))
                .map_err(|e| e.to_string())?;
        return Ok(format!(
            "// Drop {n} of a study of \"{}\" (seed {}): `impulse run` on this file replays it.\n{text}",
            part.name, args.seed
        ));
    }
    let shard = crate::study_io::shard_arg(args.shard.as_deref())?;
    let started = Instant::now();
    let (mut stopped, mut resumed_note): (Option<String>, Option<String>) = (None, None);
    let (file, ran) = match &args.from {
        Some(path) => (read_study(path)?, false),
        None => {
            if args.drops == 0 {
                return Err("--drops 0: a study needs at least one drop".into());
            }
            let threads = args
                .threads
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
            let mut file = StudyFile {
                part: part.name.clone(),
                settings,
                seed: args.seed,
                drops: args.drops,
                stable: StudyFile::fingerprint(&part),
                outcomes: Vec::new(),
            };
            let study = crate::study_io::StudyRun {
                command: "impulse poses",
                runs: "drops",
                header: serde_json::to_value(&file).map_err(|e| e.to_string())?,
                shard,
                mine: shard.runs_of(args.drops),
                out: args.out.as_deref(),
                max_wall: args.max_wall,
            };
            let done = crate::study_io::run_journaled(
                &study,
                |d: &DropOutcome| d.index,
                |hooks| {
                    poses::run_drops_with(
                        &part, &settings, args.seed, args.drops, shard, threads, hooks,
                    )
                    .map_err(|e| e.to_string())
                },
            )?;
            file.outcomes = done.outcomes;
            if let Some(journal) = done.journal.filter(|_| done.complete) {
                journal.finish(&file)?;
            }
            (stopped, resumed_note) = (done.stopped, done.resumed);
            (file, true)
        }
    };
    if file.part != part.name || file.stable != StudyFile::fingerprint(&part) {
        return Err(format!(
            "{}: its drops are of part \"{}\", not of this \"{}\" (another part, or the part file changed: its stable facets or their solid angles differ)",
            args.from.as_deref().unwrap_or(Path::new("")).display(),
            file.part,
            part.name,
        ));
    }
    if file.outcomes.is_empty()
        && let Some(note) = &stopped
    {
        // Nothing to summarise: say where it stopped.
        return Ok(note.clone());
    }
    let wall = started.elapsed().as_secs_f64();
    let summary = poses::summarize(
        &part,
        &file.outcomes,
        args.cone.to_radians(),
        args.confidence,
    )
    .map_err(|e| e.to_string())?;
    let mut t = String::new();
    let a = &part.analysis;
    let _ = writeln!(
        t,
        "part:             {} ({} hull facets, {} stable, in {} told apart by shape)",
        part.name,
        a.facets().len(),
        a.stable().len(),
        match a.classes().len() {
            1 => "1 pose".to_string(),
            n => format!("{n} poses"),
        }
    );
    let _ = writeln!(
        t,
        "drops:            {} of {} (seed {}{}), {} uniform on SO(3), {} from rest on the belt",
        summary.drops,
        file.drops,
        file.seed,
        if shard == Shard::ALL {
            String::new()
        } else {
            format!(", shard {}/{}", shard.index, shard.count)
        },
        summary.uniform_drops,
        summary.drops - summary.uniform_drops
    );
    if ran {
        let _ = writeln!(
            t,
            "wall time:        {} ({:.1} drops per second)",
            crate::text::duration(wall),
            summary.drops as f64 / wall.max(1e-9)
        );
    }
    let interval = |x: f64| {
        if x.is_finite() {
            format!("{:5.1}", 100.0 * x)
        } else {
            "    –".to_string()
        }
    };
    let pct = |x: f64| {
        if x.is_finite() {
            format!("{:6.2} %", 100.0 * x)
        } else {
            "     –  ".into()
        }
    };
    let _ = writeln!(
        t,
        "\npose  facets  normal (part frame)        quasi-static  perturbed({:.0}°)  uniform   {:.0} % interval      belt-fed  drops",
        args.cone,
        100.0 * args.confidence
    );
    for r in &summary.rows {
        let _ = writeln!(
            t,
            "{:>4}  {:>6}  ({:>6.3}, {:>6.3}, {:>6.3})  {}      {}         {}  [{}, {}] %   {}  {:>5}",
            r.pose,
            r.facets.len(),
            r.normal[0],
            r.normal[1],
            r.normal[2],
            pct(r.quasi_static),
            pct(r.perturbed),
            pct(r.uniform),
            interval(r.interval.0),
            interval(r.interval.1),
            r.belt_fed.map_or_else(|| "     –  ".into(), pct),
            r.uniform_count
        );
    }
    if let Some(h) = summary.half_width {
        let _ = writeln!(
            t,
            "\nuniform drops: every interval within ±{:.2} % (worst case, eq. 7.3); {} drops give ±5 % at {:.0} %",
            100.0 * h,
            impulse_massprops::stats::sample_size(0.05, args.confidence)
                .map_err(|e| e.to_string())?,
            100.0 * args.confidence
        );
    }
    let changes: u64 = summary
        .transitions
        .iter()
        .filter(|(a, b, _)| a != b)
        .map(|(_, _, n)| n)
        .sum();
    if summary.drops > summary.uniform_drops {
        let _ = writeln!(
            t,
            "belt drops: {changes} of {} changed pose; the belt-fed estimate is only as good as those changes",
            summary.drops - summary.uniform_drops
        );
    }
    let _ = write!(
        t,
        "not classified: {} unsettled after {} s, {} at rest off every facet",
        summary.unsettled, file.settings.max_time, summary.unclassified
    );
    if let Some(note) = &resumed_note {
        let _ = write!(t, "\n{note}");
    }
    match &stopped {
        Some(note) => {
            let _ = write!(t, "\n{note}");
        }
        None => {
            if let Some(out) = &args.out {
                let _ = write!(t, "\noutcomes:         {}", out.display());
            }
        }
    }
    Ok(t)
}

fn read_study(path: &Path) -> Result<StudyFile, String> {
    crate::study_io::read_json(path, "pose study")
}

fn merge(files: &[PathBuf], out: &Path) -> Result<String, String> {
    let studies = files
        .iter()
        .map(|f| read_study(f))
        .collect::<Result<Vec<_>, _>>()?;
    let merged = poses::merge(&studies).map_err(|e| e.to_string())?;
    crate::study_io::write_json(out, &merged)?;
    let have = merged.outcomes.len() as u64;
    let mut t = format!(
        "merged {} files: {have} of {} drops of \"{}\" into {}",
        files.len(),
        merged.drops,
        merged.part,
        out.display()
    );
    if have < merged.drops {
        let _ = write!(
            t,
            "\nwarning: {} drops are missing (a shard not merged?)",
            merged.drops - have
        );
    }
    Ok(t)
}
