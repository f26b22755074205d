//! `impulse bowling`: the bowling study of thesis §7.4 (Fig. 7.10): straight and hooking
//! throws, pins felled against the pin-line crossing, run in parallel and, for a batch
//! scheduler, in shards (`--shard K/N`, then `impulse bowling merge`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use impulse_sim::batch::Shard;
use impulse_sim::bowling::{
    self, AlleyDesc, BIN_WIDTH, BowlingFile, HEAD_ON, Mean, POCKET, SHOULDERS, ThrowOutcome,
    ThrowSettings,
};

use crate::plot::{self, Axis};

/// Bins averaged together for the smoothed curves of the plot (5 bins of 5 mm: 2.5 cm).
const SMOOTH_BINS: usize = 5;

/// Options of `impulse bowling`.
#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct BowlingArgs {
    #[command(subcommand)]
    command: Option<BowlingCommand>,
    /// The alley (`Alley(…)` RON: lane, gutters, pins, ball, contacts); default: the USBC
    /// alley that `--print-alley` prints.
    #[arg(long)]
    alley: Option<PathBuf>,
    /// Print the default alley file and exit (a starting point for `--alley`).
    #[arg(long, conflicts_with_all = ["alley", "from", "scene", "out"])]
    print_alley: bool,
    /// Throws of each kind (straight and hook) in the whole study (all shards); the thesis
    /// threw 320 of each.
    #[arg(long, default_value_t = 320)]
    throws: u64,
    /// Release speed of the ball (m/s).
    #[arg(long, allow_negative_numbers = true, default_value_t = ThrowSettings::default().speed)]
    speed: f64,
    /// A hook's spin about +y (rad/s; the ball spins at −SPIN about +y).
    #[arg(long, allow_negative_numbers = true, default_value_t = ThrowSettings::default().hook_spin)]
    spin: f64,
    /// A hook's release direction, degrees to the right of straight down the lane.
    #[arg(long, allow_negative_numbers = true, default_value_t = ThrowSettings::default().hook_angle_degrees)]
    angle: f64,
    /// Centre of the window of pin-line crossings (m; 0 is the head pin, + to the right).
    #[arg(long, allow_negative_numbers = true, default_value_t = ThrowSettings::default().window_center)]
    center: f64,
    /// Width of the window of crossings (m).
    #[arg(long, allow_negative_numbers = true, default_value_t = ThrowSettings::default().window_width)]
    width: f64,
    /// Longest run after the ball crosses the pin line (simulated s).
    #[arg(long, allow_negative_numbers = true, default_value_t = ThrowSettings::default().settle_time)]
    settle: f64,
    /// Random seed: throw i's aim depends only on (seed, i).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Worker threads (default: every core). Results do not depend on it.
    #[arg(long)]
    threads: Option<usize>,
    /// Run only throws K, K+N, K+2N, … (K in 0…N−1), for a batch scheduler; combine the
    /// shards' `--out` files with `impulse bowling merge`.
    #[arg(long, value_name = "K/N")]
    shard: Option<String>,
    /// Write every throw's outcome to this JSON file (the input of `merge` and `--from`).
    /// While the study runs, each finished throw is kept in OUT.partial: a study stopped by
    /// Ctrl-C, `--max-wall` or a kill and run again with the same arguments runs only the
    /// throws it had not finished.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Stop cleanly after this many wall-clock seconds: no throw starts after it, the throws
    /// done are summarised, and with `--out` kept in OUT.partial for the same command to
    /// finish the study. Ctrl-C does the same (exit 130).
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    max_wall: Option<f64>,
    /// Summarise the throws of this JSON file (a run's or a merge's `--out`) instead of
    /// throwing.
    #[arg(long, conflicts_with_all = [
        "alley", "shard", "out", "throws", "speed", "spin", "angle", "center", "width",
        "settle", "seed", "threads",
    ])]
    from: Option<PathBuf>,
    /// Print the scene (RON) of throw N of this study instead of running it: `impulse run`
    /// on the saved scene replays that throw exactly.
    #[arg(long, value_name = "N", conflicts_with_all = ["shard", "out", "from"])]
    scene: Option<u64>,
    /// Write the mean pins felled per 5 mm bin of crossings, both kinds, as CSV.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Write the plot of mean pins felled against the crossing (thesis Fig. 7.10) as SVG.
    #[arg(long)]
    svg: Option<PathBuf>,
}

#[derive(clap::Subcommand)]
enum BowlingCommand {
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

/// Runs `impulse bowling`; returns the text to print.
pub fn run(args: &BowlingArgs) -> Result<String, String> {
    if let Some(BowlingCommand::Merge { files, out }) = &args.command {
        return merge(files, out);
    }
    if args.print_alley {
        return AlleyDesc::default().to_ron().map_err(|e| e.to_string());
    }
    let alley = match &args.alley {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
            AlleyDesc::from_ron(&text, &path.display().to_string()).map_err(|e| e.to_string())?
        }
        None => AlleyDesc::default(),
    };
    let settings = ThrowSettings {
        speed: args.speed,
        hook_spin: args.spin,
        hook_angle_degrees: args.angle,
        window_center: args.center,
        window_width: args.width,
        settle_time: args.settle,
    };
    settings.validate().map_err(|e| e.to_string())?;
    if args.from.is_none() && !(1..=bowling::MAX_THROWS_PER_KIND).contains(&args.throws) {
        return Err(format!(
            "--throws {}: a study needs at least one throw of each kind, and at most {}",
            args.throws,
            bowling::MAX_THROWS_PER_KIND
        ));
    }
    if let Some(n) = args.scene {
        let desc = bowling::throw_scene(&alley, &settings, args.seed, args.throws, n)
            .map_err(|e| e.to_string())?;
        let text = desc.to_ron().map_err(|e| e.to_string())?;
        return Ok(format!(
            "// Throw {n} of a bowling study (seed {}, {} throws of each kind): `impulse run` on this file replays it.\n{text}",
            args.seed, args.throws
        ));
    }
    let shard = crate::study_io::shard_arg(args.shard.as_deref())?;
    let started = Instant::now();
    let mut notes: Vec<String> = Vec::new();
    let (file, ran) = match &args.from {
        Some(path) => (read_file(path)?, false),
        None => {
            let threads = args
                .threads
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
            let mut file = BowlingFile {
                alley,
                settings,
                seed: args.seed,
                throws_per_kind: args.throws,
                outcomes: Vec::new(),
            };
            let study = crate::study_io::StudyRun {
                command: "impulse bowling",
                runs: "throws",
                header: serde_json::to_value(&file).map_err(|e| e.to_string())?,
                shard,
                mine: shard.runs_of(2 * args.throws),
                out: args.out.as_deref(),
                max_wall: args.max_wall,
            };
            let done = crate::study_io::run_journaled(
                &study,
                |t: &ThrowOutcome| t.index,
                |hooks| {
                    bowling::run_throws_with(
                        &file.alley,
                        &settings,
                        args.seed,
                        args.throws,
                        shard,
                        threads,
                        hooks,
                    )
                    .map_err(|e| e.to_string())
                },
            )?;
            file.outcomes = done.outcomes;
            if let Some(journal) = done.journal.filter(|_| done.complete) {
                journal.finish(&file)?;
            }
            notes.extend(done.resumed);
            notes.extend(done.stopped);
            (file, true)
        }
    };
    let wall = started.elapsed().as_secs_f64();
    let (lo, hi) = file.settings.window();
    let rows = bowling::bins(&file.outcomes, lo, hi, BIN_WIDTH);
    if let Some(path) = &args.csv {
        std::fs::write(path, bowling::to_csv(&rows))
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    if let Some(path) = &args.svg {
        let series = |pick: fn(&bowling::BinRow) -> Mean| -> Vec<(f64, f64)> {
            rows.iter()
                .map(|r| (100.0 * (r.lo + r.hi) / 2.0, pick(r).mean))
                .collect()
        };
        let straight = series(|r| r.straight);
        let hook = series(|r| r.hook);
        let plot = plot::line_plot(
            "Pins felled against the pin-line crossing (thesis Fig. 7.10)",
            Axis {
                name: "ball's x at the pin line (0 = head pin, + = right)",
                unit: "cm",
            },
            Axis {
                name: "mean pins felled",
                unit: "",
            },
            &[
                ("straight, 5 mm".into(), straight.clone()),
                ("hook, 5 mm".into(), hook.clone()),
                ("straight, 2.5 cm".into(), smooth(&straight)),
                ("hook, 2.5 cm".into(), smooth(&hook)),
            ],
        )?;
        std::fs::write(path, plot).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    let mut text = report(&file, shard, ran.then_some(wall));
    for note in &notes {
        text.push('\n');
        text.push_str(note);
    }
    Ok(text)
}

/// The running mean of a series over [`SMOOTH_BINS`] bins (skipping empty bins).
fn smooth(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let half = SMOOTH_BINS / 2;
    (0..points.len())
        .map(|k| {
            let lo = k.saturating_sub(half);
            let hi = (k + half + 1).min(points.len());
            let m = Mean::of(points[lo..hi].iter().map(|p| p.1).filter(|y| y.is_finite()));
            (points[k].0, m.mean)
        })
        .collect()
}

/// A difference in standard errors, or `–` when it is unknown.
fn z(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.1}")
    } else {
        "–".into()
    }
}

/// One cell of the summary: mean ± standard error (throws), a dash where a figure is unknown
/// (no throws; a standard error needs two).
fn mean_cell(x: &Mean) -> String {
    if x.n == 0 {
        "      –        (0)".to_string()
    } else if x.se.is_finite() {
        format!("{:5.2} ± {:4.2} ({:3})", x.mean, x.se, x.n)
    } else {
        format!("{:5.2} ±    – ({:3})", x.mean, x.n)
    }
}

/// The printed summary of a study.
fn report(file: &BowlingFile, shard: Shard, wall: Option<f64>) -> String {
    let sum = bowling::summarize(&file.outcomes, file.settings.window());
    let mut t = String::new();
    let s = file.settings;
    let _ = writeln!(
        t,
        "throws:      {} of {} (seed {}{}); straight and hooking ({} rad/s, {}° right) at {} m/s",
        file.outcomes.len(),
        2 * file.throws_per_kind,
        file.seed,
        if shard == Shard::ALL {
            String::new()
        } else {
            format!(", shard {}/{}", shard.index, shard.count)
        },
        s.hook_spin,
        s.hook_angle_degrees,
        s.speed
    );
    let _ = writeln!(
        t,
        "aimed at:    pin-line crossings {:+.1} … {:+.1} cm",
        100.0 * (s.window_center - s.window_width / 2.0),
        100.0 * (s.window_center + s.window_width / 2.0)
    );
    if let Some(w) = wall {
        let _ = writeln!(
            t,
            "wall time:   {} ({:.2} throws per second)",
            crate::text::duration(w),
            file.outcomes.len() as f64 / w.max(1e-9)
        );
    }
    let m = mean_cell;
    let _ = writeln!(
        t,
        "\nmean pins felled ± standard error (throws)   straight            hook"
    );
    let _ = writeln!(
        t,
        "all crossings in the window                  {}   {}",
        m(&sum.all.0),
        m(&sum.all.1)
    );
    let _ = writeln!(
        t,
        "pocket {:+.0} … {:+.0} cm                          {}   {}   hook − straight: {} standard errors",
        100.0 * POCKET.0,
        100.0 * POCKET.1,
        m(&sum.pocket_straight),
        m(&sum.pocket_hook),
        z(sum.pocket_hook.z_over(&sum.pocket_straight))
    );
    let _ = writeln!(
        t,
        "head on, |x| < {:.1} cm                        {}   {}",
        100.0 * HEAD_ON,
        m(&sum.head_on_straight),
        m(&sum.head_on_hook)
    );
    let _ = writeln!(
        t,
        "its shoulders, {:.0} ≤ |x| < {:.0} cm               {}   {}   dip (shoulders − head on): {} and {} standard errors",
        100.0 * SHOULDERS.0,
        100.0 * SHOULDERS.1,
        m(&sum.shoulders_straight),
        m(&sum.shoulders_hook),
        z(sum.shoulders_straight.z_over(&sum.head_on_straight)),
        z(sum.shoulders_hook.z_over(&sum.head_on_hook))
    );
    let _ = write!(
        t,
        "\nnot in the means: {} throws crossed outside the window (in a gutter, or deflected by the pins), {} never crossed the pin line\nin the means as the pins stood: {} throws ended at the settle time with something still moving",
        sum.outside, sum.no_crossing, sum.unsettled
    );
    t
}

fn read_file(path: &Path) -> Result<BowlingFile, String> {
    let file: BowlingFile = crate::study_io::read_json(path, "bowling study")?;
    file.check()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(file)
}

fn merge(files: &[PathBuf], out: &Path) -> Result<String, String> {
    let studies = files
        .iter()
        .map(|f| read_file(f))
        .collect::<Result<Vec<_>, _>>()?;
    let merged = bowling::merge(&studies).map_err(|e| e.to_string())?;
    crate::study_io::write_json(out, &merged)?;
    let have = merged.outcomes.len() as u64;
    let total = 2 * merged.throws_per_kind;
    let mut t = format!(
        "merged {} files: {have} of {total} throws into {}",
        files.len(),
        out.display()
    );
    if have < total {
        let _ = write!(
            t,
            "\nwarning: {} throws are missing (a shard not merged?)",
            total - have
        );
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cell of one throw has a mean but no standard error: a dash, not NaN, in the columns
    /// of the others.
    #[test]
    fn a_single_throw_prints_a_dash_for_its_standard_error() {
        let one = mean_cell(&Mean::of([9.0]));
        let two = mean_cell(&Mean::of([8.0, 9.0]));
        assert_eq!(one, " 9.00 ±    – (  1)");
        assert_eq!(two, " 8.50 ± 0.50 (  2)");
        assert_eq!(one.chars().count(), two.chars().count());
        assert_eq!(mean_cell(&Mean::of([])), "      –        (0)");
    }
}
