//! `impulse reduce`: a FORK⁻¹S reduced model of a `Mechanism(...)` file, under a constant load:
//! the static response against the full nonlinear statics (`--static`), or a simulation that
//! writes end-effector and link trajectories with the columns of `impulse run`. Both print the
//! model's rank decisions and conditioning (`impulse_reduced::rank`; warnings also on stderr);
//! `--compliance` writes the model's matrices with their frames and units
//! (`impulse_reduced::export`). The conventions are stated in docs/forks.md, "Conventions".

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use impulse_geom::{DQuat, DVec3, Pose, Twist};
use impulse_massprops::MassProperties;
use impulse_reduced::reference::kinematics::link_poses;
use impulse_reduced::reference::{Configuration, Load, StaticOptions, solve_statics};
use impulse_reduced::timing::StepClock;
use impulse_reduced::{
    ConstructOptions, Mechanism, MechanismDesc, ModelExport, Obstacle, ReducedModel, ReducedSim,
    Tsvd,
};

use crate::html::{Kind, Replay, ReplayBody, ReplayFrame};
use crate::mesh::{self, Triangles};
use crate::plot::{self, Axis};
use crate::progress::Progress;

/// Options of `impulse reduce`.
#[derive(clap::Args)]
pub struct ReduceArgs {
    /// The mechanism file (RON, `Mechanism(...)`); see fixtures/mechanisms/.
    mechanism: PathBuf,
    /// A constant force (and torque) on an end effector: `LINK:fx,fy,fz[,tx,ty,tz]` (N, N·m),
    /// given in world axes at the link's origin at rest. The reduced model holds it in the end
    /// effector's body frame at rest (it turns with the end effector); the full model of
    /// `--static` holds it fixed in the world. Repeatable.
    #[arg(
        long,
        allow_hyphen_values = true,
        value_name = "LINK:FX,FY,FZ[,TX,TY,TZ]"
    )]
    load: Vec<String>,
    /// Print the static response of the reduced model and of the full nonlinear statics
    /// (globalised Newton with load continuation) instead of simulating. The base is held at
    /// rest in both, a free base too.
    #[arg(long = "static")]
    statics: bool,
    /// Relative truncated-SVD threshold τ, 0 < τ < 1: singular values at or below τ times the
    /// largest are dropped (FORK⁻¹S eq. 9). Default: eq. 9, 100·max(m,n)·ε (~1.3e-13 for one
    /// end effector). Raise it to treat nearly rigid end-effector directions as rigid; the
    /// output reports every map's singular values around the cut, the gap, the rank and
    /// cond(C). See docs/forks.md, "Rank and conditioning".
    #[arg(long, allow_negative_numbers = true, value_name = "TAU")]
    tsvd: Option<f64>,
    /// Write the model as JSON: the compliance C, stiffness, accelerability, mass, damping,
    /// static wrench and internal twist maps, with their frames, units and rank decisions.
    #[arg(long, value_name = "FILE.json")]
    compliance: Option<PathBuf>,
    /// Threads that place the internal links (default: every core). One is the fastest on
    /// the bundled mechanisms (docs/forks.md, Table 1).
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    /// Stop cleanly after this many wall-clock seconds: the outputs hold the run up to there
    /// and the report says where it stopped (`"stopped"`). Ctrl-C does the same (exit 130).
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    max_wall: Option<f64>,
    /// Most joint degrees of freedom (and links) the mechanism may have: a larger one is
    /// refused before any work (the reduction's matrices grow as dof², its factorisations as
    /// dof³).
    #[arg(long, value_name = "N", default_value_t = impulse_reduced::MAX_DOF)]
    max_dof: usize,
    /// Simulated end time (s), > 0.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    until: f64,
    /// Time step (s), > 0: backward Euler, stable for any step, accurate well below the
    /// model's fastest period. There is no automatic step: 0, negative or non-finite values
    /// are refused.
    #[arg(long, default_value_t = 1e-3, allow_negative_numbers = true)]
    dt: f64,
    /// A ground plane z = Z under the mechanism (friction 0.5).
    #[arg(long, allow_hyphen_values = true)]
    ground: Option<f64>,
    /// Write the trajectory (one row per frame and link) to this .csv or .json file.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write an SVG plot (error.svg: the per-step error estimate) into this directory.
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Write the run as a self-contained replay page (the page of `impulse run --html`): the
    /// links drawn from their collision shapes, or as the box with their inertia when they
    /// have none.
    #[arg(long, value_name = "OUT.html")]
    html: Option<PathBuf>,
}

fn parse_loads(m: &Mechanism, specs: &[String]) -> Result<Vec<Load>, String> {
    specs
        .iter()
        .map(|s| {
            let (name, nums) = s
                .split_once(':')
                .ok_or_else(|| format!("--load {s:?}: expected LINK:fx,fy,fz[,tx,ty,tz]"))?;
            let link = m
                .link_index(name)
                .ok_or_else(|| format!("--load {s:?}: no link {name:?}"))?;
            let v: Vec<f64> = nums
                .split(',')
                .map(|x| {
                    x.trim()
                        .parse::<f64>()
                        .map_err(|e| format!("--load {s:?}: {e}"))
                })
                .collect::<Result<_, _>>()?;
            if !(v.len() == 3 || v.len() == 6) || v.iter().any(|x| !x.is_finite()) {
                return Err(format!("--load {s:?}: give 3 or 6 finite numbers"));
            }
            let t = if v.len() == 6 {
                DVec3::new(v[3], v[4], v[5])
            } else {
                DVec3::ZERO
            };
            Ok(Load {
                link,
                force: DVec3::new(v[0], v[1], v[2]),
                torque: t,
            })
        })
        .collect()
}

/// Most steps a dynamics run may take (`--until` / `--dt`): at 3.8 µs a step, the fastest
/// measured (docs/forks.md, helix-400 on one thread), about an hour; a count past it is a
/// mistake in `--dt` or `--until` (`--dt 1e-300` asked for 1e300 steps and overflowed a
/// buffer's size). Default `1e9`.
pub const MAX_STEPS: f64 = 1e9;

/// Steps between two polls of a stop request (Ctrl-C, `--max-wall`). Default `64`: a poll is
/// a clock read, about a small mechanism's step; 64 steps of the largest bundled mechanism
/// take well under a second.
pub const STOP_POLL_STEPS: usize = 64;

/// Runs the command; returns the text to print (warnings go to stderr).
pub fn run(args: &ReduceArgs) -> Result<String, String> {
    // Numbers first: a bad value is refused before anything is read or built.
    let tsvd = match args.tsvd {
        Some(t) => Tsvd::with_relative(t).map_err(|e| format!("--tsvd {t}: {e}"))?,
        None => Tsvd::default(),
    };
    if !args.statics {
        if !(args.dt.is_finite() && args.dt > 0.0) {
            return Err(format!(
                "--dt {}: the time step must be a positive number of seconds (backward Euler \
                 is stable for any step; there is no automatic step)",
                args.dt
            ));
        }
        if !(args.until.is_finite() && args.until > 0.0) {
            return Err(format!(
                "--until {}: the end time must be a positive number of seconds",
                args.until
            ));
        }
        if args.threads == Some(0) {
            return Err("--threads 0: need at least one thread".into());
        }
        if let Some(n) = args.threads
            && n > impulse_reduced::max_threads()
        {
            return Err(format!(
                "--threads {n}: at most {} on this machine ({} per core): more threads than \
                 cores only wait for one another",
                impulse_reduced::max_threads(),
                impulse_reduced::MAX_THREADS_PER_CORE
            ));
        }
        if let Some(w) = args.max_wall
            && !(w.is_finite() && w > 0.0)
        {
            return Err(format!(
                "--max-wall {w}: must be a finite number of seconds > 0"
            ));
        }
        let steps = (args.until / args.dt).ceil();
        if steps > MAX_STEPS {
            return Err(format!(
                "--dt {} with --until {}: {steps:.3e} steps, over the limit of {MAX_STEPS:.0e} \
                 (about an hour at the fastest step measured): raise --dt or lower --until",
                crate::text::significant(args.dt),
                crate::text::significant(args.until)
            ));
        }
    }
    let text = std::fs::read_to_string(&args.mechanism)
        .map_err(|e| format!("{}: {e}", args.mechanism.display()))?;
    let desc =
        MechanismDesc::from_ron(&text).map_err(|e| format!("{}: {e}", args.mechanism.display()))?;
    let m = desc
        .build_with_max_dof(args.max_dof)
        .map_err(|e| format!("{}: {e}", args.mechanism.display()))?;
    let loads = parse_loads(&m, &args.load)?;
    if let Some(path) = &args.html {
        if args.statics {
            return Err("--html replays a simulation: leave out --static".into());
        }
        crate::html::check_path(path)?;
        crate::run::directory_exists("--html", path)?;
    }
    // The outputs' places are checked before the run, not after it.
    if let Some(path) = &args.out {
        crate::run::directory_exists("--out", path)?;
    }
    if let Some(path) = &args.compliance {
        crate::run::directory_exists("--compliance", path)?;
    }
    let t0 = Instant::now();
    let options = ConstructOptions {
        tsvd,
        ..ConstructOptions::default()
    };
    let model = ReducedModel::build(&m, &Configuration::rest(&m), &[], &options)
        .map_err(|e| format!("{}: {e}", args.mechanism.display()))?;
    let build_ms = t0.elapsed().as_secs_f64() * 1e3;
    for w in &model.diagnostics.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(path) = &args.compliance {
        let pretty = serde_json::to_string_pretty(&ModelExport::new(&m, &model))
            .map_err(|e| format!("{}: {e}", path.display()))?;
        let mut json = compact_rows(&pretty);
        json.push('\n');
        std::fs::write(path, json).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    let ne = model.end_effectors.len();
    let w = model.end_effector_wrenches(&loads).map_err(|link| {
        format!(
            "--load: link {:?} is not an end effector",
            m.links[link].name
        )
    })?;
    if args.statics {
        let (ee, _) = model.static_twists(&w);
        let sol = solve_statics(&m, &loads, None, &StaticOptions::default())
            .map_err(|e| e.to_string())?;
        let full = link_poses(&m, &sol.config);
        let r = m.bounding_radius();
        let mut s = format!(
            "{{\n  \"mechanism\": {},\n  \"build_ms\": {build_ms:.3},\n{}  \"full_statics\": \
             {{\"load_steps\": {}, \"newton_iterations\": {}, \"relative_residual\": {:.2e}}},\n  \
             \"end_effectors\": [\n",
            json_string(&m.name),
            rank_lines(&m, &model),
            sol.load_steps,
            sol.iterations,
            sol.residual
        );
        for (i, &e) in model.end_effectors.iter().enumerate() {
            let red = model.reference[i] * Pose::exp(&ee[i]);
            let d = (full[e].inverse() * red).log();
            let err =
                ((d.v / r).length_squared() + (d.w / std::f64::consts::PI).length_squared()).sqrt();
            let _ = writeln!(
                s,
                "    {{\"link\": {}, \"reduced\": {:?}, \"full\": {:?}, \"relative_error\": {err:.3e}}}{}",
                json_string(&m.links[e].name),
                red.translation.to_array(),
                full[e].translation.to_array(),
                if i + 1 < ne { "," } else { "" }
            );
        }
        let _ = write!(s, "  ],\n{}\n}}", map_lines(&model));
        return Ok(s);
    }
    simulate(args, &m, model, &w, build_ms)
}

/// Pretty JSON (serde_json's, fields in declaration order) with every array of scalars —
/// a matrix row, a position — collapsed onto one line, so that a matrix reads as its rows.
fn compact_rows(pretty: &str) -> String {
    let lines: Vec<&str> = pretty.lines().collect();
    let mut out: Vec<String> = Vec::with_capacity(lines.len());
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        if line.ends_with('[') {
            // The array's items, up to its closing line, if all are scalars on their own lines.
            let items: Vec<&str> = lines[i + 1..]
                .iter()
                .take_while(|l| !l.trim_start().starts_with(']'))
                .copied()
                .collect();
            let scalar = |l: &&str| !l.contains(['[', '{', ']', '}']);
            let close = lines.get(i + 1 + items.len());
            if let Some(close) = close.filter(|_| items.iter().all(scalar)) {
                let joined: Vec<&str> = items.iter().map(|l| l.trim()).collect();
                out.push(format!(
                    "{}{}{}",
                    line,
                    joined.join(" "),
                    close.trim_start()
                ));
                i += items.len() + 2;
                continue;
            }
        }
        out.push(line.to_owned());
        i += 1;
    }
    out.join("\n")
}

/// `x` as a JSON number with four significant digits (`1.330e-13`; JSON has no NaN or
/// infinity: those are written as `null`).
fn num(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.3e}")
    } else {
        "null".to_owned()
    }
}

/// A JSON array of [`num`]s.
fn nums(v: &[f64]) -> String {
    format!(
        "[{}]",
        v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(", ")
    )
}

/// The model's rank decision and conditioning as JSON lines (each ending with `,\n`):
/// `rank` (relative threshold, directions the joints allow and the rank kept, the ones treated
/// as rigid with their twist per end effector), `conditioning` (cond(C), the measured
/// round-off of C, the estimated accuracy of K, cond(A)) and `warnings`.
fn rank_lines(m: &Mechanism, model: &ReducedModel) -> String {
    let d = &model.diagnostics;
    let rigid: Vec<String> = d
        .dropped
        .iter()
        .map(|x| {
            let per: Vec<String> = model
                .end_effectors
                .iter()
                .enumerate()
                .map(|(i, &e)| {
                    format!(
                        "{}: {}",
                        json_string(&m.links[e].name),
                        nums(&x.twist[6 * i..6 * i + 6])
                    )
                })
                .collect();
            format!(
                "{{\"compliance_relative\": {}, \"twist\": {{{}}}}}",
                num(x.compliance),
                per.join(", ")
            )
        })
        .collect();
    let c = &d.conditioning;
    let warnings: Vec<String> = d
        .warnings
        .iter()
        .map(|w| json_string(&w.to_string()))
        .collect();
    format!(
        "  \"rank\": {{\"tsvd\": {}, \"allowed\": {}, \"rank\": {}, \"treated_as_rigid\": [{}]}},\n  \
         \"conditioning\": {{\"cond_C\": {}, \"C_round_off\": {}, \"K_accuracy\": {}, \"cond_A\": {}}},\n  \
         \"warnings\": [{}],\n",
        num(d.relative_threshold),
        d.allowed,
        model.rank,
        rigid.join(", "),
        num(c.compliance_condition),
        num(c.compliance_error),
        num(c.stiffness_error),
        num(c.accelerability_condition),
        warnings.join(", ")
    )
}

/// Number of singular values shown on each side of a map's cut in the printed `maps`.
const AROUND_CUT: usize = 2;

/// Every truncated SVD of the construction as a `"maps"` JSON field, one map per line: size,
/// rank, the singular values around the cut (relative to the largest), threshold, gap, cond.
fn map_lines(model: &ReducedModel) -> String {
    let lines: Vec<String> = model
        .diagnostics
        .maps
        .iter()
        .map(|r| {
            let (kept, dropped) = r.around_cut(AROUND_CUT);
            format!(
                "{{\"map\": {}, \"size\": [{}, {}], \"rank\": {}, \"kept\": {}, \"dropped\": {}, \
                 \"threshold\": {}, \"gap\": {}, \"cond\": {}}}",
                json_string(&r.map),
                r.rows,
                r.cols,
                r.rank,
                nums(&kept),
                nums(&dropped),
                num(r.relative_threshold()),
                num(r.gap()),
                num(r.condition())
            )
        })
        .collect();
    format!("  \"maps\": [\n    {}\n  ]", lines.join(",\n    "))
}

fn simulate(
    args: &ReduceArgs,
    m: &Mechanism,
    model: ReducedModel,
    w: &[f64],
    build_ms: f64,
) -> Result<String, String> {
    let t0 = Instant::now();
    let rank = rank_lines(m, &model);
    let maps = map_lines(&model);
    let mut sim = ReducedSim::new(m, model, args.dt).map_err(|e| e.to_string())?;
    if let Some(n) = args.threads {
        sim.set_threads(n)
            .map_err(|e| format!("--threads {n}: {e}"))?;
    }
    // Construction: the model and the factored system matrix of the step.
    let build_ms = build_ms + t0.elapsed().as_secs_f64() * 1e3;
    sim.external = w.to_vec();
    if let Some(z) = args.ground {
        sim.obstacles.push(Obstacle::Plane {
            normal: DVec3::Z,
            offset: z,
        });
    }
    let steps = (args.until / args.dt).ceil() as usize;
    let every = (steps / 100).max(1);
    let names: Vec<&str> = sim
        .model
        .end_effectors
        .iter()
        .chain(&sim.model.internal)
        .map(|&l| m.links[l].name.as_str())
        .collect();
    let mut internal = vec![Pose::IDENTITY; sim.model.internal.len()];
    let mut prev: Option<Vec<Pose>> = None;
    let mut frames: Vec<(f64, Vec<(Pose, Twist)>)> = Vec::new();
    // The base's pose at each frame (a free base moves; a fixed one stays at rest).
    let mut base_poses: Vec<Pose> = Vec::new();
    let mut errors: Vec<(f64, f64)> = Vec::new();
    let progress = Progress::time("impulse reduce", args.until);
    // µs per step: the step and every internal link's pose (a step as Table 1 counts it),
    // after a warm-up; the recording below is outside it.
    let mut clock = StepClock::for_run(steps);
    crate::interrupt::install();
    let wall = Instant::now();
    // Why the run ended before `steps`, and the step it ended at.
    let mut stopped: Option<(&str, usize)> = None;
    for k in 1..=steps {
        clock.step(|| {
            sim.step();
            sim.internal_poses(&mut internal);
        });
        // A state that left double precision (a load of 1e300 N) stays so: stop at once,
        // naming the link and the time, rather than print NaN for the end effector.
        let ends = (0..sim.model.end_effectors.len()).map(|i| sim.end_effector_pose(i));
        if let Some((n, _)) = ends
            .chain(internal.iter().copied())
            .enumerate()
            .find(|(_, p)| !(p.translation.is_finite() && p.rotation.is_finite()))
        {
            return Err(format!(
                "the reduced model's state is not finite at t = {} s (step {k}): link `{}` has \
                 no finite pose; the loads or the step are too large for double precision",
                crate::text::significant(k as f64 * args.dt),
                names[n]
            ));
        }
        // A stop request is polled every STOP_POLL_STEPS steps (a clock read costs about as
        // much as a small mechanism's step).
        if k % STOP_POLL_STEPS == 0 && k < steps {
            if crate::interrupt::requested() {
                stopped = Some(("interrupted (Ctrl-C or SIGTERM)", k));
            } else if args
                .max_wall
                .is_some_and(|w| wall.elapsed().as_secs_f64() >= w)
            {
                stopped = Some(("at the wall-time limit (--max-wall)", k));
            }
        }
        let last = k == steps || stopped.is_some();
        if k % every == 0 || last || k == every - 1 {
            let poses: Vec<Pose> = (0..sim.model.end_effectors.len())
                .map(|i| sim.end_effector_pose(i))
                .chain(internal.iter().copied())
                .collect();
            if k % every == 0 || last {
                let t = k as f64 * args.dt;
                let vel: Vec<Twist> = match &prev {
                    Some(p) => p
                        .iter()
                        .zip(&poses)
                        .map(|(a, b)| {
                            // World velocity of the origin and angular velocity over the last step.
                            let dw = crate::reduce::rotvec(a, b) / args.dt;
                            Twist::new((b.translation - a.translation) / args.dt, dw)
                        })
                        .collect(),
                    None => vec![Twist::ZERO; poses.len()],
                };
                errors.push((t, sim.constraint_error(m)));
                frames.push((t, poses.iter().copied().zip(vel).collect()));
                base_poses.push(sim.base.as_ref().map_or(m.links[m.base].rest, |b| b.pose));
                progress.set_time(t);
            }
            prev = Some(poses);
        }
        if stopped.is_some() {
            break;
        }
    }
    progress.finish();
    let wall = wall.elapsed().as_secs_f64();
    if let Some(path) = &args.out {
        write_trajectory(path, &names, &frames)?;
    }
    if let Some(path) = &args.html {
        let links: Vec<usize> = sim
            .model
            .end_effectors
            .iter()
            .chain(&sim.model.internal)
            .copied()
            .collect();
        let base = (sim.base.is_some(), base_poses.as_slice());
        let replay = replay(
            m,
            &links,
            &frames,
            base,
            args.ground,
            &crate::html::title_of(path),
        )?;
        crate::html::write_replay(path, &replay)?;
    }
    if let Some(dir) = &args.plot {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let path = dir.join("error.svg");
        std::fs::write(&path, plot_error(&errors)?)
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    let max_err = errors.iter().map(|e| e.1).fold(0.0, f64::max);
    let ee = sim.end_effector_pose(0).translation.to_array();
    let us = |x: Option<f64>| x.map_or_else(|| "null".to_owned(), |x| format!("{x:.3}"));
    let (mean, median) = (us(clock.mean_us()), us(clock.median_us()));
    let threads = args
        .threads
        .map_or_else(|| "\"every core\"".to_owned(), |n| n.to_string());
    let (steps, stopped) = match stopped {
        Some((why, k)) => (
            k,
            format!(
                "  \"stopped\": {},\n",
                json_string(&format!(
                    "{why}, after {} of {} simulated seconds",
                    crate::text::significant(k as f64 * args.dt),
                    crate::text::significant(args.until)
                ))
            ),
        ),
        None => (steps, String::new()),
    };
    Ok(format!(
        "{{\n  \"mechanism\": {},\n  \"links\": {},\n  \"build_ms\": {build_ms:.3},\n{rank}{stopped}  \"threads\": {threads},\n  \"steps\": {steps},\n  \"timed_steps\": {},\n  \"us_per_step\": {mean},\n  \"us_per_step_median\": {median},\n  \"wall_s\": {wall:.4},\n  \"end_effector_0\": {ee:?},\n  \"max_constraint_error\": {max_err:.3e},\n{maps}\n}}",
        json_string(&m.name),
        m.links.len(),
        clock.timed(),
    ))
}

/// Half extents of the ground slab drawn under a mechanism, beyond the links' reach, as a
/// multiple of that reach.
const GROUND_MARGIN: f64 = 1.5;
/// Half thickness of the drawn ground slab, as a share of its half width.
const GROUND_THICKNESS: f64 = 0.02;
/// Thinnest side of a link's inertia box, as a share of its longest (a rod's inertia box
/// would otherwise be a line).
const INERTIA_BOX_MIN: f64 = 0.05;

/// The triangles of a link in its frame: its collision shapes, or, without any, the box of
/// uniform density with the link's mass, centre of mass and principal moments (half extents
/// `a_k = √(3/(2m)·(I_j + I_l − I_k))`, along the principal axes); none for a massless link.
fn link_triangles(link: &impulse_reduced::Link) -> Vec<Triangles> {
    use impulse_reduced::Shape;
    if !link.shapes.is_empty() {
        return link
            .shapes
            .iter()
            .map(|s| match *s {
                Shape::Sphere { center, radius } => {
                    mesh::uv_ellipsoid(DVec3::splat(radius)).moved(&Pose::from_translation(center))
                }
                Shape::Box {
                    center,
                    half_extents,
                } => mesh::box_triangles(half_extents).moved(&Pose::from_translation(center)),
            })
            .collect();
    }
    let i = &link.inertia;
    let Ok(principal) = MassProperties {
        mass: i.mass,
        com: i.com,
        inertia: i.inertia_com,
    }
    .principal() else {
        return Vec::new();
    };
    if i.mass.is_nan() || i.mass <= 0.0 {
        return Vec::new();
    }
    let m = principal.moments;
    let half = DVec3::new(m.y + m.z - m.x, m.z + m.x - m.y, m.x + m.y - m.z).max(DVec3::ZERO)
        * (1.5 / i.mass);
    let half = DVec3::new(half.x.sqrt(), half.y.sqrt(), half.z.sqrt());
    let half = half.max(DVec3::splat(INERTIA_BOX_MIN * half.max_element()));
    let axes = impulse_geom::DQuat::from_mat3(&principal.axes);
    vec![mesh::box_triangles(half).moved(&Pose::new(axes, i.com))]
}

/// The reduced run as a replay: the `links` (end effectors, then internal links, the order
/// of `frames` and of `--out`) with their recorded poses and speeds, then the base (`base`:
/// whether it is free, and its pose at each frame), then a ground slab under the links when
/// there is a ground plane at `ground`. Energies are not recorded.
fn replay(
    m: &Mechanism,
    links: &[usize],
    frames: &[(f64, Vec<(Pose, Twist)>)],
    base: (bool, &[Pose]),
    ground: Option<f64>,
    title: &str,
) -> Result<Replay, String> {
    let mut bodies: Vec<ReplayBody> = links
        .iter()
        .map(|&l| ReplayBody {
            name: m.links[l].name.clone(),
            kind: Kind::Dynamic,
            triangles: link_triangles(&m.links[l]),
        })
        .collect();
    let mut frames: Vec<ReplayFrame> = frames
        .iter()
        .map(|(t, states)| ReplayFrame {
            time: *t,
            poses: states
                .iter()
                .map(|(p, _)| (p.translation, p.rotation))
                .collect(),
            speeds: states.iter().map(|(_, v)| v.v.length()).collect(),
            energies: vec![f64::NAN; states.len()],
            energy: (f64::NAN, f64::NAN),
        })
        .collect();
    let (free, base_poses) = base;
    bodies.push(ReplayBody {
        name: m.links[m.base].name.clone(),
        kind: if free { Kind::Dynamic } else { Kind::Fixed },
        triangles: link_triangles(&m.links[m.base]),
    });
    for (f, p) in frames.iter_mut().zip(base_poses) {
        f.poses.push((p.translation, p.rotation));
        f.speeds.push(f64::NAN);
        f.energies.push(f64::NAN);
    }
    if let Some(z) = ground {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for (p, _) in frames.iter().flat_map(|f| &f.poses) {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let centre = 0.5 * (lo + hi);
        let reach = GROUND_MARGIN * (0.5 * (hi - lo).max_element()).max(f64::EPSILON);
        let half = DVec3::new(reach, reach, GROUND_THICKNESS * reach);
        bodies.push(ReplayBody {
            name: "ground".into(),
            kind: Kind::Fixed,
            triangles: vec![mesh::box_triangles(half)],
        });
        for f in &mut frames {
            f.poses
                .push((DVec3::new(centre.x, centre.y, z - half.z), DQuat::IDENTITY));
            f.speeds.push(0.0);
            f.energies.push(f64::NAN);
        }
    }
    Ok(Replay {
        title: title.to_owned(),
        up: crate::html::up_of(m.gravity),
        model: "FORK⁻¹S reduced model".into(),
        bodies,
        frames,
        impacts: Vec::new(),
    })
}

/// `s` as a JSON string (quotes and control characters escaped as JSON wants, which Rust's
/// `{:?}` does not do).
fn json_string(s: &str) -> String {
    serde_json::Value::from(s).to_string()
}

/// Rotation vector (world) taking `a`'s orientation to `b`'s.
fn rotvec(a: &Pose, b: &Pose) -> DVec3 {
    impulse_geom::se3::so3_log(b.rotation * a.rotation.conjugate())
}

fn write_trajectory(
    path: &Path,
    names: &[&str],
    frames: &[(f64, Vec<(Pose, Twist)>)],
) -> Result<(), String> {
    let json = path.extension().is_some_and(|e| e == "json");
    let mut s = String::new();
    let nums = |p: &Pose, v: &Twist| -> [f64; 13] {
        let (t, q) = (p.translation, p.rotation);
        [
            t.x, t.y, t.z, q.x, q.y, q.z, q.w, v.v.x, v.v.y, v.v.z, v.w.x, v.w.y, v.w.z,
        ]
    };
    if json {
        // Through serde_json: link names may hold quotes or control characters.
        let frames: Vec<serde_json::Value> = frames
            .iter()
            .map(|(t, states)| {
                let rows: Vec<[f64; 13]> = states.iter().map(|(p, v)| nums(p, v)).collect();
                serde_json::json!({"t": t, "states": rows})
            })
            .collect();
        s = serde_json::to_string(&serde_json::json!({"bodies": names, "frames": frames}))
            .map_err(|e| format!("{}: {e}", path.display()))?;
        s.push('\n');
    } else {
        s.push_str("time,body,x,y,z,qx,qy,qz,qw,vx,vy,vz,wx,wy,wz\n");
        for (t, states) in frames {
            for (name, (p, v)) in names.iter().zip(states) {
                let _ = write!(s, "{t},{name}");
                for x in nums(p, v) {
                    let _ = write!(s, ",{x}");
                }
                s.push('\n');
            }
        }
    }
    std::fs::write(path, s).map_err(|e| format!("{}: {e}", path.display()))
}

/// The relative constraint error against time (`--plot DIR` writes it as `error.svg`).
fn plot_error(errors: &[(f64, f64)]) -> Result<String, String> {
    plot::line_plot(
        "relative constraint error (per-step estimate) against time",
        Axis {
            name: "time",
            unit: "s",
        },
        Axis {
            name: "relative constraint error",
            unit: "",
        },
        &[("constraint error".into(), errors.to_vec())],
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use impulse_geom::{DMat3, SpatialInertia};

    /// A link without shapes is drawn as the uniform box of its mass and inertia: the box the
    /// triangles span (its edges read from the vertices) has the link's inertia tensor,
    /// `Σ_k m/3·(h_j² + h_l²)·a_k a_kᵀ` over its axes `a_k` and half extents `h_k`, centred on
    /// the link's centre of mass — for a tensor whose principal axes are not the link's.
    #[test]
    fn a_link_without_shapes_is_its_inertia_box() {
        let turn = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.7);
        let r = DMat3::from_quat(turn);
        let (mass, half) = (0.3, DVec3::new(0.01, 0.04, 0.1));
        let moments = mass / 3.0
            * DVec3::new(
                half.y * half.y + half.z * half.z,
                half.z * half.z + half.x * half.x,
                half.x * half.x + half.y * half.y,
            );
        let inertia = r * DMat3::from_diagonal(moments) * r.transpose();
        let com = DVec3::new(0.02, -0.01, 0.05);
        let link = impulse_reduced::Link {
            name: "rod".into(),
            rest: Pose::IDENTITY,
            inertia: SpatialInertia {
                mass,
                com,
                inertia_com: inertia,
            },
            shapes: Vec::new(),
        };
        let t = link_triangles(&link);
        assert_eq!(t.len(), 1);
        let corners: Vec<DVec3> = t[0].positions.clone();
        let centre = corners.iter().copied().sum::<DVec3>() / corners.len() as f64;
        assert!(
            (centre - com).length() < 1e-12,
            "centre {centre}, com {com}"
        );
        // The three edges at one corner: its nearest other corners in three directions.
        let c0 = corners[0];
        let mut edges: Vec<DVec3> = Vec::new();
        let mut others: Vec<DVec3> = corners.iter().map(|&c| c - c0).collect();
        others.sort_by(|a, b| a.length().total_cmp(&b.length()));
        for e in others {
            if e.length() > 1e-12
                && edges
                    .iter()
                    .all(|f| e.normalize().dot(f.normalize()).abs() < 1e-9)
            {
                edges.push(e);
            }
        }
        assert_eq!(edges.len(), 3);
        let mut drawn = DMat3::ZERO;
        for k in 0..3 {
            let (j, l) = ((k + 1) % 3, (k + 2) % 3);
            let h = |i: usize| edges[i].length() / 2.0;
            let a = edges[k].normalize();
            let moment = mass / 3.0 * (h(j) * h(j) + h(l) * h(l));
            drawn += DMat3::from_cols(a * a.x, a * a.y, a * a.z) * moment;
        }
        let diff = (drawn - inertia).to_cols_array();
        let scale = moments.max_element();
        assert!(
            diff.iter().all(|d| d.abs() < 1e-9 * scale),
            "drawn {drawn:?}, link {inertia:?}"
        );
        let massless = impulse_reduced::Link {
            inertia: SpatialInertia::ZERO,
            ..link
        };
        assert!(link_triangles(&massless).is_empty());
    }
}
