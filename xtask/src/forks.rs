//! `cargo xtask bench --case forks`: the FORK⁻¹S study (`docs/forks.md`), in a release build.
//!
//! - **Table 1**: µs per step (end-effector step and every internal link's pose) of the bundled
//!   helix, ladder and robot arm on 1 and 2 threads, next to the paper's Vortex and FORK⁻¹S
//!   figures (Intel i7 2.8 GHz, 4 cores, 2014–16); our full nonlinear reference
//!   ([`FullSim`]) at the same step, the ratio, and the reduced model's end-effector pose
//!   error against the full model under the same held force (dynamic, from rest).
//! - **Table 2**: µs per blended step (Algorithm 5: weights, Algorithm 3 on three matrices,
//!   eq. 28, the step, Algorithm 4) with 1, 2 and 4 models, next to the paper's.
//! - **Fig. 7**: relative constraint error against relative end-effector displacement, single
//!   and blended, for the "Y" and the ladder, each curve against its own end effector's
//!   displacement (as in the paper), with each curve read at displacement 1 and the blend's
//!   worst ratio to the single model load by load over the sampled range (the study's target:
//!   at most a third; Shepard p, the models carrying weight and the samples as in
//!   `impulse_reduced::study`); written as
//!   `fig7-<name>.csv` and `fig7-<name>.svg`. The same rows give reduced-vs-full end-effector
//!   pose error at equal loads (the full solution's displacement is a column too).
//! - **Fig. 7 across the rank change**: the blended statics' largest errors between N evenly
//!   spaced samples against N (1 to 16), for the "Y", the ladder-36 and a straight robot arm,
//!   whose rest models have a lower rank than their loaded ones
//!   (`impulse_reduced::convergence`); `fig7-convergence.csv`.
//!
//! Output directory: `--out DIR` (default `target/bench`).

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use glam::DVec3;
use impulse_geom::Pose;
use impulse_reduced::blend::{BlendedModel, scaled_norm};
use impulse_reduced::convergence::static_convergence;
use impulse_reduced::reference::{
    Configuration, FullOptions, FullSim, Load, StaticOptions, solve_statics,
};
use impulse_reduced::study::{
    FIG7_BLEND_RATIO, FIG7_SAMPLE_RATIO, FIG7_SHEPARD_POWER, FIG7_SUPPORT, Fig7Options, Fig7Row,
    NEAR_REST_DISPLACEMENT, PAPER_SINGLE_BAND, curve_at, fig7, geometric, subdivide,
    worst_blend_ratio,
};
use impulse_reduced::timing::StepClock;
use impulse_reduced::{ConstructOptions, MassModel, Mechanism, ReducedModel, ReducedSim, scenes};

use crate::Result;

/// The `--case` name of this study.
pub const CASE: &str = "forks";

/// A Fig. 7 study: name, mechanism, force direction, first sample (N) and sample count (the
/// samples grow by [`FIG7_SAMPLE_RATIO`]), loads beyond the last sample (N), Newton tolerance.
type Study = (&'static str, Mechanism, DVec3, (f64, usize), Vec<f64>, f64);

/// Parts each span between two Fig. 7 samples is split into (quarter points and the
/// midpoint, where the blend is weakest).
const FIG7_PARTS: usize = 4;

/// Parts the span from rest to the first Fig. 7 sample is split into: finer, to show where
/// the blend, worse than the single model there, hands over near
/// [`NEAR_REST_DISPLACEMENT`].
const FIG7_NEAR_REST_PARTS: usize = 8;

/// Newton tolerance of the ladder's full solves: the default since the statics have their
/// exact tangent (with the finite-difference tangent they stalled between 1e-9 and 1e-8 of
/// the force scale at the larger loads, and this was 1e-7).
const LADDER_STATIC_TOLERANCE: f64 = impulse_reduced::tol::STATIC_RESIDUAL_REL;

/// Steps timed per measurement (after as many warm-up steps).
const STEPS: usize = 2000;

/// Wall time the full reference is timed for, per mechanism (s): its steps cost milliseconds
/// to a second, so it runs until this budget is spent (at least [`FULL_MIN_STEPS`] steps).
const FULL_BUDGET_S: f64 = 2.0;

/// Fewest full-reference steps timed (after one warm-up step).
const FULL_MIN_STEPS: usize = 3;

/// Steps of the reduced-vs-full trajectory comparison at h = 1 ms (0.1 s simulated: several
/// periods of the end effector's lowest modes in the bundled mechanisms).
const ERROR_STEPS: usize = 100;

/// World force on the first end effector in the reduced-vs-full comparison (N), the load of
/// the timing runs. Under 10 N the helix-400's tip whips after ~0.1 s and the full reference's
/// Newton stalls even at h/16 (its tangent leaves out terms of order h·|v|).
const ERROR_FORCE: f64 = 1.0;

/// Paper Table 1: (example, links, Vortex µs, N=1, N=4, N=8).
const TABLE1: [(&str, usize, f64, f64, f64, f64); 5] = [
    ("helix-50", 50, 240.0, 20.0, 12.0, 15.0),
    ("helix-100", 100, 470.0, 32.0, 16.0, 21.0),
    ("helix-400", 400, 2150.0, 112.0, 84.0, 76.0),
    ("ladder-48", 48, 334.0, 22.0, 14.0, 18.0),
    ("robot-arm-20", 20, 121.0, 24.0, 18.0, 21.0),
];

/// Paper Table 2: (example, Vortex µs, 1, 2, 4 models; 4 threads).
const TABLE2: [(&str, f64, f64, f64, f64); 3] = [
    ("helix-200", 1048.0, 78.0, 96.0, 160.0),
    ("ladder-36", 302.0, 37.0, 82.0, 99.0),
    ("robot-arm-20", 121.0, 26.0, 47.0, 86.0),
];

fn mechanism(name: &str) -> Result<Mechanism> {
    let desc = scenes::bundled()
        .into_iter()
        .find(|(n, _)| *n == name)
        .map(|(_, d)| d)
        .or_else(|| (name == "helix-200").then(|| scenes::helix(200)))
        .ok_or_else(|| format!("no bundled mechanism {name}"))?;
    desc.build().map_err(|e| format!("{name}: {e}"))
}

fn err<E: std::fmt::Display>(what: &str) -> impl Fn(E) -> String + '_ {
    move |e| format!("{what}: {e}")
}

/// µs per single-model step with `threads` threads: the end-effector step and every internal
/// link's pose, [`STEPS`] steps timed after as many of warm-up, by the clock `impulse reduce`
/// reports `us_per_step` with ([`StepClock`]: the mean of the timed steps).
fn time_single(m: &Mechanism, model: &ReducedModel, threads: usize) -> Result<f64> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(err("thread pool"))?;
    let mut s = ReducedSim::new(m, model.clone(), 1e-3).map_err(err("sim"))?;
    s.external[0] = 1.0;
    let mut out = vec![Pose::IDENTITY; s.model.internal.len()];
    let mut clock = StepClock::new(STEPS);
    pool.install(|| {
        for _ in 0..2 * STEPS {
            clock.step(|| {
                s.step();
                s.internal_poses(&mut out);
            });
        }
    });
    clock
        .mean_us()
        .ok_or_else(|| "no step was timed".to_owned())
}

/// µs per step of the full reference at step `h`, with the bench's 1 N load on the first end
/// effector; and the number of steps timed.
fn time_full(m: &Mechanism, h: f64) -> Result<(f64, usize)> {
    let mut s = FullSim::new(m, h, FullOptions::default()).map_err(err("full"))?;
    s.loads = vec![Load {
        link: m.end_effectors[0],
        force: DVec3::X,
        torque: DVec3::ZERO,
    }];
    s.step().map_err(err("full step"))?;
    let t = Instant::now();
    let mut steps = 0;
    while steps < FULL_MIN_STEPS || t.elapsed().as_secs_f64() < FULL_BUDGET_S {
        s.step().map_err(err("full step"))?;
        steps += 1;
    }
    Ok((t.elapsed().as_secs_f64() * 1e6 / steps as f64, steps))
}

/// End-effector pose errors of reduced models against the full reference under the same held
/// world force (along (1, 1, 1): in the ladder's plane a force meets locked rungs), all from
/// rest at step `h`: per model the largest `‖(v/r, ω/π)‖` of `log(H_full⁻¹ H_reduced)` over
/// [`ERROR_STEPS`] steps (§8.2's scaling), and the largest displacement of the full model's
/// end effector on the same scale.
fn pose_errors(m: &Mechanism, models: &[ReducedModel], h: f64) -> Result<(Vec<f64>, f64)> {
    let e = m.end_effectors[0];
    let force = DVec3::ONE.normalize() * ERROR_FORCE;
    let mut reduced = Vec::new();
    for model in models {
        let mut red = ReducedSim::new(m, model.clone(), h).map_err(err("sim"))?;
        let body = model.reference[0].inverse_transform_vector(force);
        red.external[..3].copy_from_slice(&body.to_array());
        reduced.push(red);
    }
    let mut full = FullSim::new(m, h, FullOptions::default()).map_err(err("full"))?;
    full.loads = vec![Load {
        link: e,
        force,
        torque: DVec3::ZERO,
    }];
    let rest = m.links[e].rest;
    let r = m.bounding_radius();
    let norm = |p: &Pose| {
        let x = p.log();
        ((x.v / r).length_squared() + (x.w / std::f64::consts::PI).length_squared()).sqrt()
    };
    let mut worst = vec![0.0_f64; models.len()];
    let mut disp = 0.0_f64;
    for _ in 0..ERROR_STEPS {
        full.step().map_err(err("full step"))?;
        let pf = full.poses()[e];
        for (red, w) in reduced.iter_mut().zip(&mut worst) {
            red.step();
            *w = w.max(norm(&(pf.inverse() * red.end_effector_pose(0))));
        }
        disp = disp.max(norm(&(rest.inverse() * pf)));
    }
    Ok((worst, disp))
}

/// Models at the rest pose and at static equilibria under a sideways force on the first end
/// effector growing to `max_force`.
fn models(m: &Mechanism, count: usize, max_force: f64) -> Result<Vec<ReducedModel>> {
    let options = ConstructOptions::default();
    let mut out =
        vec![ReducedModel::build(m, &Configuration::rest(m), &[], &options).map_err(err("model"))?];
    let link = m.end_effectors[0];
    let mut warm = None;
    for k in 1..count {
        let load = Load {
            link,
            force: DVec3::new(max_force * k as f64 / (count - 1) as f64, 0.0, 0.0),
            torque: DVec3::ZERO,
        };
        let statics = StaticOptions {
            load_steps: 4,
            tolerance: LADDER_STATIC_TOLERANCE,
            ..StaticOptions::default()
        };
        let sol = solve_statics(m, &[load], warm.as_ref(), &statics).map_err(err("statics"))?;
        out.push(ReducedModel::build(m, &sol.config, &[load], &options).map_err(err("model"))?);
        warm = Some(sol);
    }
    Ok(out)
}

/// Largest relative end-effector displacement `‖(v/r, ω/π)‖` from rest accepted at the end of
/// a blended timing run (the bench's 1 N moves the bundled mechanisms by ~1e-3): beyond it the
/// run timed a diverged state, not a step (the robot-arm-20's 2- and 4-model runs did until
/// the blended step was solved at the closest model's rank: 1e27 m).
const BLENDED_MAX_DISPLACEMENT: f64 = 1.0;

/// µs per blended step (Algorithm 5 and 4) with the given models, 2 threads; an error if the
/// end effector ends further than [`BLENDED_MAX_DISPLACEMENT`] from rest.
fn time_blended(m: &Mechanism, set: &BlendedModel) -> Result<f64> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .map_err(err("thread pool"))?;
    let mut ee: Vec<Pose> = set.models[0].reference.clone();
    let mut phi = vec![0.0; 6 * ee.len()];
    let mut w = vec![0.0; phi.len()];
    w[0] = 1.0;
    let steps = STEPS / 4;
    let us = pool.install(|| -> Result<f64> {
        let t = Instant::now();
        for _ in 0..steps {
            let b = set
                .step(&mut ee, &mut phi, &w, 1e-3)
                .map_err(err("blended step"))?;
            let internal = set.internal_poses(&ee, &b.alpha);
            std::hint::black_box(internal);
        }
        Ok(t.elapsed().as_secs_f64() * 1e6 / steps as f64)
    })?;
    let rest = m.links[m.end_effectors[0]].rest;
    let moved = scaled_norm(&(rest.inverse() * ee[0]).log(), m.bounding_radius());
    if moved.is_finite() && moved <= BLENDED_MAX_DISPLACEMENT {
        Ok(us)
    } else {
        Err(format!(
            "{} models: the blended run diverged (end effector {moved:e} from rest)",
            set.models.len()
        ))
    }
}

/// Runs the study and writes its files into `out`.
pub fn run(out: &Path) -> Result<()> {
    println!("FORK⁻¹S Table 1: µs per step (end effectors + every internal link), h = 1 ms");
    println!(
        "(full: our nonlinear reference, backward Euler + Newton, same h; error: reduced vs full \
         end-effector pose under {ERROR_FORCE} N over {ERROR_STEPS} steps, ‖(v/r, ω/π)‖, with the \
         exact J M⁻¹ Jᵀ mass and with the paper's eq. 7 projection)"
    );
    println!(
        "{:<14} {:>5} {:>9} {:>9} {:>10} {:>8} {:>9} {:>9} {:>9} | paper: {:>7} {:>6} {:>6} {:>6}",
        "example",
        "links",
        "ours N=1",
        "ours N=2",
        "full",
        "full/N=1",
        "EE error",
        "(eq. 7)",
        "EE disp",
        "Vortex",
        "N=1",
        "N=4",
        "N=8"
    );
    let mut csv = String::from(
        "example,links,ours_n1_us,ours_n2_us,full_us,full_steps_timed,full_over_n1,ee_pose_error,ee_pose_error_paper_mass,ee_displacement,paper_vortex_us,paper_n1_us,paper_n4_us,paper_n8_us\n",
    );
    for (name, links, vortex, p1, p4, p8) in TABLE1 {
        let m = mechanism(name)?;
        let model = ReducedModel::build(
            &m,
            &Configuration::rest(&m),
            &[],
            &ConstructOptions::default(),
        )
        .map_err(err(name))?;
        let t1 = time_single(&m, &model, 1)?;
        let t2 = time_single(&m, &model, 2)?;
        let (tf, steps) = time_full(&m, 1e-3)?;
        let paper = ReducedModel::build(
            &m,
            &Configuration::rest(&m),
            &[],
            &ConstructOptions {
                mass: MassModel::Paper,
                ..ConstructOptions::default()
            },
        )
        .map_err(err(name))?;
        let (errors, disp) = pose_errors(&m, &[model.clone(), paper], 1e-3)?;
        let (error, error_paper) = (errors[0], errors[1]);
        let ratio = tf / t1;
        println!(
            "{name:<14} {links:>5} {t1:>9.1} {t2:>9.1} {tf:>10.0} {ratio:>7.0}× {error:>9.2e} {error_paper:>9.2e} {disp:>9.2e} | paper: {vortex:>7.0} {p1:>6.0} {p4:>6.0} {p8:>6.0}"
        );
        let _ = writeln!(
            csv,
            "{name},{links},{t1:.2},{t2:.2},{tf:.1},{steps},{ratio:.1},{error:.4e},{error_paper:.4e},{disp:.4e},{vortex},{p1},{p4},{p8}"
        );
    }
    write(out, "table1.csv", &csv)?;

    println!("\nFORK⁻¹S Table 2: µs per blended step (Algorithm 5 + 4), 2 threads");
    println!(
        "{:<14} {:>8} {:>8} {:>8} | paper (4 threads): {:>7} {:>5} {:>5} {:>5}",
        "example", "1 model", "2", "4", "Vortex", "1", "2", "4"
    );
    let mut csv =
        String::from("example,ours_1,ours_2,ours_4,paper_vortex,paper_1,paper_2,paper_4\n");
    for (name, vortex, p1, p2, p4) in TABLE2 {
        let m = mechanism(name)?;
        let all = models(&m, 4, 10.0)?;
        let rest: Vec<Pose> = m.end_effectors.iter().map(|&e| m.links[e].rest).collect();
        let mut t = Vec::new();
        for k in [1, 2, 4] {
            let set = BlendedModel::new(all[..k].to_vec(), rest.clone(), m.bounding_radius())
                .map_err(err("blend"))?;
            t.push(time_blended(&m, &set)?);
        }
        println!(
            "{name:<14} {:>8.1} {:>8.1} {:>8.1} | paper (4 threads): {vortex:>7.0} {p1:>5.0} {p2:>5.0} {p4:>5.0}",
            t[0], t[1], t[2]
        );
        let _ = writeln!(
            csv,
            "{name},{:.2},{:.2},{:.2},{vortex},{p1},{p2},{p4}",
            t[0], t[1], t[2]
        );
    }
    write(out, "table2.csv", &csv)?;

    println!(
        "\nFORK⁻¹S Fig. 7: relative constraint error against relative end-effector displacement"
    );
    println!(
        "(paper: single model {}–{} at displacement 1; blended zero at the samples; target: \
         blended ≤ {FIG7_BLEND_RATIO:.3} of single at every load of the sampled range; Shepard \
         p = {FIG7_SHEPARD_POWER}, models carrying weight {}, samples × {FIG7_SAMPLE_RATIO} \
         from near rest)",
        PAPER_SINGLE_BAND.0,
        PAPER_SINGLE_BAND.1,
        FIG7_SUPPORT.map_or_else(|| "all".to_owned(), |k| format!("the {k} nearest"))
    );
    // The ladder's full solves stop at LADDER_STATIC_TOLERANCE (see there).
    let studies: [Study; 2] = [
        (
            "y",
            mechanism("y")?,
            // Samples 40 N (relative displacement 0.057) to 683 N; to 720 N, where the
            // single model's own displacement passes 1.
            DVec3::X,
            (40.0, 8),
            vec![720.0],
            impulse_reduced::tol::STATIC_RESIDUAL_REL,
        ),
        (
            "ladder-36",
            mechanism("ladder-36")?,
            // Out of the ladder's plane: in its plane the rung hinges lock every level.
            // Samples 4 N (relative displacement 0.042) to 102.5 N (a tenth, at 153.8 N,
            // leaves the blended statics unsettled after their 2000 passes below 160 N); to
            // 160 N, where the single model's own displacement passes 1.
            DVec3::Y,
            (4.0, 9),
            vec![110.0, 120.0, 130.0, 140.0, 150.0, 160.0],
            LADDER_STATIC_TOLERANCE,
        ),
    ];
    for (name, m, direction, (first, count), tail, tolerance) in studies {
        let settings = Fig7Options {
            statics: StaticOptions {
                load_steps: 4,
                tolerance,
                ..StaticOptions::default()
            },
            power: FIG7_SHEPARD_POWER,
            ..Fig7Options::default()
        };
        let samples = geometric(first, FIG7_SAMPLE_RATIO, count);
        let mut loads = subdivide(&samples, FIG7_PARTS);
        loads.extend(subdivide(&samples[..1], FIG7_NEAR_REST_PARTS));
        loads.extend(tail);
        loads.sort_by(f64::total_cmp);
        loads.dedup();
        let (rows, _) = fig7(&m, 0, direction, &loads, &samples, &settings).map_err(err(name))?;
        println!(
            "{name}: load N, displacement (full, single, blended), error (single, blended), EE pose error (single, blended)"
        );
        let mut csv = String::from(
            "load,displacement,single_displacement,blended_displacement,single,blended,single_pose_error,blended_pose_error\n",
        );
        for r in &rows {
            let [
                load,
                full,
                single_d,
                blended_d,
                single,
                blended,
                single_pose,
                blended_pose,
            ] = [
                r.load,
                r.displacement,
                r.single_displacement,
                r.blended_displacement,
                r.single,
                r.blended,
                r.single_pose,
                r.blended_pose,
            ];
            println!(
                "  {load:7.1} {full:7.3} {single_d:7.3} {blended_d:7.3} {single:10.3e} {blended:10.3e} {single_pose:10.3e} {blended_pose:10.3e}"
            );
            let _ = writeln!(
                csv,
                "{load},{full},{single_d},{blended_d},{single},{blended},{single_pose},{blended_pose}"
            );
        }
        let read = |d: fn(&Fig7Row) -> f64, e: fn(&Fig7Row) -> f64| {
            curve_at(&rows, d, e, 1.0)
                .map_or_else(|| "not reached".to_owned(), |x| format!("{x:.3}"))
        };
        println!(
            "  at relative displacement 1 (paper: single 0.1–0.15): single {}, blended {}; single at the full model's displacement 1 (the old abscissa) {}",
            read(|r| r.single_displacement, |r| r.single),
            read(|r| r.blended_displacement, |r| r.blended),
            read(|r| r.displacement, |r| r.single)
        );
        if let Some((load, ratio)) = worst_blend_ratio(&rows, &samples, NEAR_REST_DISPLACEMENT) {
            let below = rows
                .iter()
                .filter(|r| r.load < first && r.displacement < NEAR_REST_DISPLACEMENT)
                .map(|r| (r.load, r.blended / r.single))
                .max_by(|a, b| a.1.total_cmp(&b.1));
            println!(
                "  blended / single, load by load, from displacement {NEAR_REST_DISPLACEMENT} to the last sample: worst {ratio:.3} at {load:.1} N ({}); below it (rest model to first sample): worst {}",
                if ratio <= FIG7_BLEND_RATIO {
                    "within the target of a third"
                } else {
                    "ABOVE the target of a third"
                },
                below.map_or_else(|| "—".to_owned(), |(l, r)| format!("{r:.2} at {l:.1} N"))
            );
        }
        let mean = |f: fn(&Fig7Row) -> f64| rows.iter().map(f).sum::<f64>() / rows.len() as f64;
        println!(
            "  mean constraint error: single {:.3e}, blended {:.3e} (ratio {:.2}); samples at {} N",
            mean(|r| r.single),
            mean(|r| r.blended),
            mean(|r| r.blended) / mean(|r| r.single),
            samples
                .iter()
                .map(|s| format!("{s:.1}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        write(out, &format!("fig7-{name}.csv"), &csv)?;
        write(out, &format!("fig7-{name}.svg"), &plot(name, &rows)?)?;
    }
    convergence(out)?;
    println!(
        "\nwrote table1.csv, table2.csv, fig7-*.csv, fig7-*.svg, fig7-convergence.csv to {}",
        out.display()
    );
    Ok(())
}

/// Sample counts of the convergence sweeps (samples evenly up to the largest load).
const CONVERGENCE_COUNTS: [usize; 5] = [1, 2, 4, 8, 16];

/// Fig. 7 across the rank change at rest: the blended statics' largest errors at the
/// midpoints between N evenly spaced samples, against N (`impulse_reduced::convergence`), for
/// the "Y" and the ladder-36 (pulled as in Fig. 7) and a straight six-link robot arm; written
/// as `fig7-convergence.csv`.
fn convergence(out: &Path) -> Result<()> {
    println!(
        "\nFig. 7 across the rank change at rest: blended statics against the full statics at the \
         midpoints between N samples (evenly up to the largest load; p = {FIG7_SHEPARD_POWER}, \
         the two nearest models)"
    );
    println!(
        "{:<12} {:>4} {:>8} {:>11} {:>11} {:>11} {:>9}",
        "mechanism", "N", "ranks", "EE error", "EE / disp", "constraint", "at (N)"
    );
    let mut csv = String::from(
        "mechanism,samples,rest_rank,loaded_rank,ee_error,ee_relative,constraint,at\n",
    );
    let sweeps = [
        ("y", mechanism("y")?, DVec3::X, 400.0),
        ("ladder-36", mechanism("ladder-36")?, DVec3::Y, 60.0),
        (
            "robot-arm-6",
            scenes::robot_arm(6).build().map_err(err("robot-arm-6"))?,
            DVec3::X,
            4.0,
        ),
    ];
    for (name, m, direction, max) in sweeps {
        let rows = static_convergence(
            &m,
            0,
            direction,
            max,
            &CONVERGENCE_COUNTS,
            &Fig7Options::default(),
        )
        .map_err(err(name))?;
        for r in rows {
            println!(
                "{name:<12} {:>4} {:>3} → {:<2} {:>11.3e} {:>11.3e} {:>11.3e} {:>9.2}",
                r.points, r.ranks.0, r.ranks.1, r.pose, r.relative_pose, r.constraint, r.worst_load
            );
            let _ = writeln!(
                csv,
                "{name},{},{},{},{:.4e},{:.4e},{:.4e},{}",
                r.points, r.ranks.0, r.ranks.1, r.pose, r.relative_pose, r.constraint, r.worst_load
            );
        }
    }
    write(out, "fig7-convergence.csv", &csv)
}

fn write(dir: &Path, name: &str, text: &str) -> Result<()> {
    let path = dir.join(name);
    std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Width of the legend's line samples and the space after them (pixels).
const PLOT_LEGEND_AREA: i32 = 36;
/// Tick labels are rounded to this many decimals (plotters' ticks are 1, 2 or 5 × 10^k; this
/// only hides binary rounding, 0.30000000000000004).
const PLOT_LABEL_DECIMALS: i32 = 9;

/// Fig. 7 as an SVG: constraint error against displacement, single (red) and blended (blue),
/// each against its own end effector's displacement.
fn plot(name: &str, rows: &[Fig7Row]) -> Result<String> {
    use plotters::prelude::*;
    let what = format!("fig7-{name}");
    let err = crate::plot::cannot_draw(&what);
    let xmax = rows
        .iter()
        .map(|r| r.single_displacement.max(r.blended_displacement))
        .fold(0.0, f64::max)
        .max(1e-9);
    let ymax = rows
        .iter()
        .map(|r| r.single.max(r.blended))
        .fold(0.0, f64::max)
        .max(1e-12);
    let label = |v: &f64| {
        let scale = 10f64.powi(PLOT_LABEL_DECIMALS);
        format!("{}", (v * scale).round() / scale)
    };
    /// A curve: its name, colour, and (x, y) of a row.
    type Curve = (&'static str, RGBColor, fn(&Fig7Row) -> (f64, f64));
    let curves: [Curve; 2] = [
        ("single model", RGBColor(0xcc, 0x33, 0x33), |r| {
            (r.single_displacement, r.single)
        }),
        ("blended", RGBColor(0x33, 0x33, 0xcc), |r| {
            (r.blended_displacement, r.blended)
        }),
    ];
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, crate::plot::SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = crate::plot::chart(
            &root,
            format!("{name}: constraint error against displacement"),
        )
        .build_cartesian_2d(0.0..xmax, 0.0..ymax)
        .map_err(&err)?;
        chart
            .configure_mesh()
            .x_desc("relative end-effector displacement ‖(v/r, ω/π)‖")
            .y_desc("relative constraint error")
            .axis_desc_style(crate::plot::font(crate::plot::FONTS.1))
            .label_style(crate::plot::font(crate::plot::FONTS.2))
            .x_label_formatter(&label)
            .y_label_formatter(&label)
            .bold_line_style(RGBColor(0xdd, 0xdd, 0xdd))
            .light_line_style(WHITE)
            .draw()
            .map_err(&err)?;
        for (title, colour, point) in curves {
            chart
                .draw_series(LineSeries::new(
                    rows.iter().map(point),
                    colour.stroke_width(2),
                ))
                .map_err(&err)?
                .label(title)
                .legend(move |(x, y)| {
                    PathElement::new(
                        vec![
                            (x, y),
                            (x + PLOT_LEGEND_AREA - crate::plot::MARGIN.0 as i32, y),
                        ],
                        colour.stroke_width(2),
                    )
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .margin(crate::plot::MARGIN.0)
            .legend_area_size(PLOT_LEGEND_AREA)
            .label_font(crate::plot::font(crate::plot::FONTS.2))
            .background_style(WHITE)
            .border_style(BLACK)
            .draw()
            .map_err(&err)?;
        root.present().map_err(&err)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fig. 7's plot: both curves in the legend, round tick labels up to the largest values.
    #[test]
    fn the_fig7_plot_has_round_ticks_and_a_legend() {
        let rows: Vec<Fig7Row> = (0..=8)
            .map(|k| {
                let d = 0.15 * f64::from(k);
                Fig7Row {
                    load: 40.0 * f64::from(k),
                    displacement: d,
                    single_displacement: d,
                    blended_displacement: 0.98 * d,
                    single: 0.12 * d,
                    blended: 0.002 * d,
                    single_pose: 0.0,
                    blended_pose: 0.0,
                }
            })
            .collect();
        let svg = plot("y", &rows).unwrap();
        if let Some(dir) = std::env::var_os("XTASK_PLOT_DIR") {
            std::fs::write(std::path::Path::new(&dir).join("fig7.svg"), &svg).unwrap();
        }
        for label in ["\nsingle model\n", "\nblended\n", "\n0.1\n", "\n1.2\n"] {
            assert!(svg.contains(label), "no {label:?}");
        }
        // Each text's content is the line after its <text …> tag.
        let texts: Vec<&str> = svg
            .lines()
            .zip(svg.lines().skip(1))
            .filter(|(tag, _)| tag.starts_with("<text"))
            .map(|(_, text)| text)
            .collect();
        assert!(
            texts.iter().all(|t| t.len() <= 60 && !t.contains("0000")),
            "an unrounded tick label: {texts:?}"
        );
    }
}
