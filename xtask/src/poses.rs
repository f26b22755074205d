//! `cargo xtask bench --case poses`: pose studies (thesis §7.5) — drops per second on 1 and
//! 2 threads for a 60-facet part, the thesis's sequential feedback sampling against
//! independent drops on a cube, the thick coin's edge share at two drop heights against the
//! quasi-static one, and the estimates for the thesis's four parts (approximate shapes).
//! Writes `poses.csv`.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use impulse_sim::poses::{self, DropSettings, PosePart, Shard};

use crate::Result;

/// The `--case` name.
pub const CASE: &str = "poses";

/// Drops per study (the thesis's count per part).
const DROPS: u64 = 2000;

/// The speed part: an irregular pebble, 60 hull facets (a part of about 50 facets, as the
/// speed study asks; the 50-facet coin rolls on its edge for seconds, see [`COIN_MAX_TIME`]).
const SPEED_PART: &str = "pebble.ron";

/// The coin.
const COIN_PART: &str = "thick-coin.ron";

/// Drops of the coin per height: a coin that lands on its edge rolls (a 48-gon loses a
/// little at each side it rolls over), so its drops cost far more than a part's.
const COIN_DROPS: u64 = 400;

/// A coin still rolling after this long (s) is counted as rolling, not as a pose.
const COIN_MAX_TIME: f64 = 5.0;

/// The coin's two drop heights (m): the thesis's 12 cm and a low 2 cm.
const COIN_HEIGHTS: [f64; 2] = [0.12, 0.02];

/// The thesis's four parts, in table order.
const THESIS_PARTS: [(&str, &str); 4] = [
    ("insulator-cap.ron", "7.3"),
    ("button-white.ron", "7.4"),
    ("button-rect-black.ron", "7.5"),
    ("button-square-black.ron", "7.6"),
];

fn load(name: &str) -> Result<PosePart> {
    PosePart::load(&crate::workspace_root().join("fixtures/parts").join(name))
        .map_err(|e| e.to_string())
}

fn study(
    part: &PosePart,
    settings: &DropSettings,
    threads: usize,
    drops: u64,
) -> Result<(Vec<poses::DropOutcome>, f64)> {
    let t = Instant::now();
    let out = poses::run_drops(part, settings, 1, drops, Shard::ALL, threads, &|_| {})
        .map_err(|e| e.to_string())?;
    Ok((out, t.elapsed().as_secs_f64()))
}

/// Seeds of the thesis-feedback comparison on the cube.
const FEEDBACK_SEEDS: [u64; 4] = [1, 2, 3, 4];

/// The cube's face shares by the thesis's sequential feedback sampling, one study per seed,
/// against independent uniform drops: how far the feedback's result depends on its luck.
fn feedback_spread(csv: &mut String) -> Result<()> {
    let cube = load("cube.ron")?;
    println!(
        "\ncube, {DROPS} drops per study: smallest and largest face share (symmetry: 16.67 %)"
    );
    let faces = |outcomes: &[poses::DropOutcome]| {
        let shares: Vec<f64> = cube
            .analysis
            .facets()
            .iter()
            .map(|f| {
                outcomes.iter().filter(|o| o.facet == Some(f.face)).count() as f64
                    / outcomes.len() as f64
            })
            .collect();
        (
            shares.iter().copied().fold(1.0, f64::min),
            shares.iter().copied().fold(0.0, f64::max),
        )
    };
    for seed in FEEDBACK_SEEDS {
        let t = Instant::now();
        let fed = poses::run_thesis_feedback(&cube, &DropSettings::default(), seed, DROPS, &|_| {})
            .map_err(|e| e.to_string())?;
        let wall = t.elapsed().as_secs_f64();
        let uniform = DropSettings {
            belt_fed: false,
            ..DropSettings::default()
        };
        let ind = poses::run_drops(&cube, &uniform, seed, DROPS, Shard::ALL, 2, &|_| {})
            .map_err(|e| e.to_string())?;
        let ((flo, fhi), (ilo, ihi)) = (faces(&fed), faces(&ind));
        println!(
            "  seed {seed}: thesis feedback {:.1}–{:.1} %   independent uniform drops {:.1}–{:.1} %",
            100.0 * flo,
            100.0 * fhi,
            100.0 * ilo,
            100.0 * ihi
        );
        let _ = writeln!(
            csv,
            "feedback,cube,seed={seed},min..max,,,,{ilo:.4}..{ihi:.4},{flo:.4}..{fhi:.4},{wall:.3},"
        );
    }
    Ok(())
}

/// Runs the pose bench and writes `poses.csv` into `out`.
pub fn run(out: &Path) -> Result<()> {
    let mut csv = String::from(
        "study,part,setting,pose,facets,quasi_static,perturbed,uniform,belt_fed,wall_s,drops_per_s\n",
    );
    let speed = load(SPEED_PART)?;
    println!(
        "speed: {DROPS} drops of {} ({} hull facets), thesis defaults",
        speed.name,
        speed.analysis.facets().len()
    );
    let mut walls = Vec::new();
    for threads in [1, 2] {
        let (outcomes, wall) = study(&speed, &DropSettings::default(), threads, DROPS)?;
        walls.push((threads, wall, outcomes));
    }
    let same = walls[0].2 == walls[1].2;
    for (threads, wall, outcomes) in &walls {
        let unsettled = outcomes.iter().filter(|o| !o.settled).count();
        println!(
            "  {threads} thread(s): {wall:.2} s, {:.1} drops/s, {unsettled} unsettled",
            DROPS as f64 / wall
        );
        let _ = writeln!(
            csv,
            "speed,{},threads={threads},,,,,,,{wall:.3},{:.2}",
            speed.name,
            DROPS as f64 / wall
        );
    }
    println!(
        "  2 threads / 1 thread: {:.3} of the time; outcomes identical: {same}",
        walls[1].1 / walls[0].1
    );
    if !same {
        return Err("the 1- and 2-thread studies differ".into());
    }
    feedback_spread(&mut csv)?;
    let coin = load(COIN_PART)?;
    println!(
        "\nthick coin, edge share ({COIN_DROPS} uniform starts on SO(3) per height, rolling after {COIN_MAX_TIME} s counted apart):"
    );
    let qs = coin.analysis.quasi_static();
    let qs_edge: f64 = coin
        .analysis
        .facets()
        .iter()
        .filter(|f| coin.normal_in_part_frame(f.face).z.abs() < 0.5)
        .map(|f| qs[f.face as usize])
        .sum();
    println!("  quasi-static: {:.2} %", 100.0 * qs_edge);
    for height in COIN_HEIGHTS {
        let settings = DropSettings {
            height,
            belt_fed: false,
            max_time: COIN_MAX_TIME,
            ..DropSettings::default()
        };
        let (outcomes, wall) = study(&coin, &settings, 2, COIN_DROPS)?;
        let on_edge = |f: u32| coin.normal_in_part_frame(f).z.abs() < 0.5;
        let share = |keep: &dyn Fn(&poses::DropOutcome) -> bool| {
            outcomes.iter().filter(|o| keep(o)).count() as f64 / COIN_DROPS as f64
        };
        let edge = share(&|o| o.facet.is_some_and(on_edge));
        let face = share(&|o| o.facet.is_some_and(|f| !on_edge(f)));
        let rolling = share(&|o| !o.settled);
        println!(
            "  dropped from {:.0} cm: {:.1} % at rest on the edge, {:.1} % on a face, {:.1} % still rolling ({wall:.1} s)",
            100.0 * height,
            100.0 * edge,
            100.0 * face,
            100.0 * rolling
        );
        let _ = writeln!(
            csv,
            "coin,{},height={height},edge,,{qs_edge:.5},,{edge:.5},,{wall:.3},",
            coin.name
        );
    }
    for (file, table) in THESIS_PARTS {
        let part = load(file)?;
        let (outcomes, wall) = study(&part, &DropSettings::default(), 2, DROPS)?;
        let s = poses::summarize(&part, &outcomes, 20f64.to_radians(), 0.95)
            .map_err(|e| e.to_string())?;
        println!(
            "\n{} (approximate shape, not comparable pose by pose with thesis Table {table}), {} stable facets in {} poses, {DROPS} drops in {wall:.1} s, {} not classified",
            part.name,
            part.analysis.stable().len(),
            s.rows.len(),
            s.unsettled + s.unclassified
        );
        println!("  pose  facets  quasi-static  perturbed  uniform  belt-fed");
        for r in &s.rows {
            let belt = r.belt_fed.unwrap_or(f64::NAN);
            println!(
                "  {:>4}  {:>6}  {:>11.1}%  {:>8.1}%  {:>6.1}%  {:>7.1}%",
                r.pose,
                r.facets.len(),
                100.0 * r.quasi_static,
                100.0 * r.perturbed,
                100.0 * r.uniform,
                100.0 * belt
            );
            let _ = writeln!(
                csv,
                "thesis-part,{},table={table},{},{},{:.5},{:.5},{:.5},{:.5},{wall:.3},{:.2}",
                part.name,
                r.pose,
                r.facets.len(),
                r.quasi_static,
                r.perturbed,
                r.uniform,
                belt,
                DROPS as f64 / wall
            );
        }
    }
    let path = out.join("poses.csv");
    std::fs::write(&path, csv).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    println!("\nwrote {}", path.display());
    Ok(())
}
