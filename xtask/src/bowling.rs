//! `cargo xtask bench --case bowling`: the bowling study of thesis §7.4 (Fig. 7.10, V25) —
//! throws per second on 1 and 2 threads (the same outcomes on both), then the thesis's
//! 320 straight and 320 hooking throws on the default alley: the pocket (hook against
//! straight over +6 … +12 cm) and the head-on dip. Writes `bowling.json` (plot it with
//! `impulse bowling --from … --svg …`) and `bowling.csv`.

use std::time::Instant;

use impulse_sim::batch::Shard;
use impulse_sim::bowling::{
    self, AlleyDesc, BIN_WIDTH, BowlingFile, HEAD_ON, Mean, POCKET, SHOULDERS, ThrowSettings,
};

use crate::Result;

/// The `--case` name.
pub const CASE: &str = "bowling";

/// Throws of each kind of the speed runs.
const SPEED_THROWS: u64 = 8;

/// Throws of each kind of the study (the thesis's 320).
const STUDY_THROWS: u64 = 320;

/// Runs the case, writing into `out`.
pub fn run(out: &std::path::Path) -> Result<()> {
    let alley = AlleyDesc::default();
    let settings = ThrowSettings::default();
    let throws = |per_kind: u64, threads: usize| {
        let t = Instant::now();
        let o = bowling::run_throws(&alley, &settings, 1, per_kind, Shard::ALL, threads, &|_| {})
            .map_err(|e| e.to_string())?;
        Ok::<_, String>((o, t.elapsed().as_secs_f64()))
    };
    println!(
        "bowling: {SPEED_THROWS} straight and {SPEED_THROWS} hooking throws on the default alley"
    );
    let (one, wall1) = throws(SPEED_THROWS, 1)?;
    let (two, wall2) = throws(SPEED_THROWS, 2)?;
    let n = (2 * SPEED_THROWS) as f64;
    let simulated: f64 = one.iter().map(|o| o.time).sum();
    println!(
        "  1 thread:  {wall1:.1} s ({:.3} throws/s, slowdown {:.3} per simulated second; thesis Table 7.1: 3.6)",
        n / wall1,
        wall1 / simulated
    );
    println!(
        "  2 threads: {wall2:.1} s ({:.3} throws/s), wall ratio 2/1 threads {:.3}",
        n / wall2,
        wall2 / wall1
    );
    if one != two {
        return Err("the 1- and 2-thread throws differ".into());
    }
    println!("  the 1- and 2-thread outcomes are identical");
    println!("\nthe study: {STUDY_THROWS} throws of each kind, 2 threads");
    let (outcomes, wall) = throws(STUDY_THROWS, 2)?;
    let file = BowlingFile {
        alley: alley.clone(),
        settings,
        seed: 1,
        throws_per_kind: STUDY_THROWS,
        outcomes,
    };
    let s = bowling::summarize(&file.outcomes, settings.window());
    let m = |x: &Mean| format!("{:.2} ± {:.2} ({})", x.mean, x.se, x.n);
    println!(
        "  {wall:.0} s ({:.3} throws/s)",
        file.outcomes.len() as f64 / wall
    );
    println!(
        "  all crossings in the window: straight {}, hook {}",
        m(&s.all.0),
        m(&s.all.1)
    );
    println!(
        "  pocket {:+.0} … {:+.0} cm: straight {}, hook {}; hook − straight = {:.2} standard errors (thesis: hook clearly better)",
        100.0 * POCKET.0,
        100.0 * POCKET.1,
        m(&s.pocket_straight),
        m(&s.pocket_hook),
        s.pocket_hook.z_over(&s.pocket_straight)
    );
    println!(
        "  head on (|x| < {:.1} cm): straight {}, hook {}; shoulders ({:.0}–{:.0} cm either side): straight {}, hook {}; dip = {:.2} and {:.2} standard errors",
        100.0 * HEAD_ON,
        m(&s.head_on_straight),
        m(&s.head_on_hook),
        100.0 * SHOULDERS.0,
        100.0 * SHOULDERS.1,
        m(&s.shoulders_straight),
        m(&s.shoulders_hook),
        s.shoulders_straight.z_over(&s.head_on_straight),
        s.shoulders_hook.z_over(&s.head_on_hook)
    );
    println!(
        "  crossed outside the window (gutter or deflected) {}, never crossed {}, ended at the settle time {}",
        s.outside, s.no_crossing, s.unsettled
    );
    let (lo, hi) = settings.window();
    let csv = out.join("bowling.csv");
    std::fs::write(
        &csv,
        bowling::to_csv(&bowling::bins(&file.outcomes, lo, hi, BIN_WIDTH)),
    )
    .map_err(|e| format!("cannot write {}: {e}", csv.display()))?;
    let json = out.join("bowling.json");
    let text = serde_json::to_string_pretty(&file).map_err(|e| e.to_string())?;
    std::fs::write(&json, text + "\n")
        .map_err(|e| format!("cannot write {}: {e}", json.display()))?;
    println!(
        "\nwrote {} and {} (plot: impulse bowling --from {} --svg bowling.svg)",
        csv.display(),
        json.display(),
        json.display()
    );
    Ok(())
}
