//! `cargo xtask bench --case poses`: pose studies (thesis §7.5) — drops per second on 1 and
//! 2 threads for a 50-facet part, the thick coin's edge share at two drop heights against
//! the quasi-static one, and the three estimates for the thesis's four parts (approximate
//! shapes) beside the thesis's tables. Writes `poses.csv`.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use impulse_sim::poses::{self, DropSettings, PosePart, Shard};

use crate::Result;

/// The `--case` name.
pub const CASE: &str = "poses";

/// Drops per study (the thesis's count per part).
const DROPS: u64 = 2000;

/// The speed part: a 48-gon coin, 50 hull facets (the "50-facet part").
const SPEED_PART: &str = "thick-coin.ron";

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
) -> Result<(Vec<poses::DropOutcome>, f64)> {
    let t = Instant::now();
    let out = poses::run_drops(part, settings, 1, DROPS, Shard::ALL, threads, &|_| {})
        .map_err(|e| e.to_string())?;
    Ok((out, t.elapsed().as_secs_f64()))
}

/// Runs the pose bench and writes `poses.csv` into `out`.
pub fn run(out: &Path) -> Result<()> {
    let mut csv = String::from(
        "study,part,setting,pose,facets,quasi_static,perturbed,uniform,belt_fed,wall_s,drops_per_s\n",
    );
    let coin = load(SPEED_PART)?;
    println!(
        "speed: {DROPS} drops of {} ({} hull facets), thesis defaults",
        coin.name,
        coin.analysis.facets().len()
    );
    let mut walls = Vec::new();
    for threads in [1, 2] {
        let (outcomes, wall) = study(&coin, &DropSettings::default(), threads)?;
        walls.push((threads, wall, outcomes));
    }
    let same = walls[0].2 == walls[1].2;
    for (threads, wall, _) in &walls {
        println!(
            "  {threads} thread(s): {wall:.2} s, {:.1} drops/s",
            DROPS as f64 / wall
        );
        let _ = writeln!(
            csv,
            "speed,{},threads={threads},,,,,,,{wall:.3},{:.2}",
            coin.name,
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
    println!("\nthick coin, edge share (uniform starts on SO(3)):");
    let qs_edge: f64 = coin
        .analysis
        .facets()
        .iter()
        .filter(|f| coin.normal_in_part_frame(f.face).z.abs() < 0.5)
        .map(|f| coin.analysis.quasi_static()[f.face as usize])
        .sum();
    println!("  quasi-static: {:.2} %", 100.0 * qs_edge);
    for height in COIN_HEIGHTS {
        let settings = DropSettings {
            height,
            belt_fed: false,
            ..DropSettings::default()
        };
        let (outcomes, wall) = study(&coin, &settings, 2)?;
        let edge = outcomes
            .iter()
            .filter(|o| {
                o.facet
                    .is_some_and(|f| coin.normal_in_part_frame(f).z.abs() < 0.5)
            })
            .count() as f64
            / DROPS as f64;
        let unsettled = outcomes.iter().filter(|o| o.facet.is_none()).count();
        println!(
            "  dropped from {:.0} cm: {:.2} % on the edge ({unsettled} not classified; {wall:.1} s)",
            100.0 * height,
            100.0 * edge
        );
        let _ = writeln!(
            csv,
            "coin,{},height={height},edge,,{qs_edge:.5},,{edge:.5},,{wall:.3},",
            coin.name
        );
    }
    for (file, table) in THESIS_PARTS {
        let part = load(file)?;
        let (outcomes, wall) = study(&part, &DropSettings::default(), 2)?;
        let s = poses::summarize(&part, &outcomes, 20f64.to_radians(), 0.95)
            .map_err(|e| e.to_string())?;
        println!(
            "\n{} (approximate shape; thesis Table {table}), {} stable facets in {} poses, {DROPS} drops in {wall:.1} s, {} not classified",
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
