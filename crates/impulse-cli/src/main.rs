//! # impulse — the command-line program (layer 5)
//!
//! **Owns** the user-facing commands: argument parsing, reading input files, printing results
//! as JSON, and turning every error into one line on stderr that starts with `error: ` (as
//! clap's usage errors do; [`text::error_line`]) with a non-zero exit status.
//!
//! **Must not know** any algorithm: each command is a thin shell over a library crate.
//!
//! Commands:
//! - `impulse run <scene.ron> [--until T] [--out traj.csv|traj.json] [--plot DIR]
//!   [--gltf out.glb] [--html out.html]`: simulate a scene file (thesis chapters 1–3 and 7)
//!   and print a summary.
//! - `impulse massprops <mesh.obj> [--density D | --mass M]`: exact mass properties of a closed
//!   polygon mesh (thesis chapter 6), printed as JSON.
//! - `impulse dynamics <model.urdf> [--q … --qd … --tau …] [--gravity gx,gy,gz]`: forward
//!   dynamics `{"qdd": [...]}` of a URDF multibody (thesis chapter 4); `--mass-matrix` prints
//!   `{"M": [[...]]}`, `--inverse --qdd …` prints `{"tau": [...]}`, `--joints` the joint order.
//! - `impulse reduce <mechanism.ron> [--load LINK:fx,fy,fz] [--static] [--out …] [--plot DIR]`:
//!   a FORK⁻¹S reduced model under a load (static, or simulated).
#![forbid(unsafe_code)]

mod bowling;
mod dynamics;
mod events;
mod glb;
mod html;
mod interrupt;
mod joints;
mod mesh;
mod partial;
mod plot;
mod poses;
mod progress;
mod reduce;
mod run;
mod study_io;
mod text;

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use impulse_massprops::{MassProperties, VolumeIntegrals};

#[derive(Parser)]
#[command(
    name = "impulse",
    version,
    about = "Physically accurate rigid-body simulation."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene file (RON) and print a summary: simulated and wall time, slowdown,
    /// collisions, microcollisions, energy, penetration.
    Run {
        /// The scene file (.ron); see fixtures/scenes/ for examples.
        scene: PathBuf,
        /// Simulated end time in seconds (default: the scene's `duration`).
        #[arg(long, allow_negative_numbers = true)]
        until: Option<f64>,
        /// Write the trajectory (one row per frame and body) to this .csv or .json file. It is
        /// written as the run goes, into FILE.partial, renamed to FILE when the run ends well:
        /// memory does not grow with the run's length.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Write every impact (collisions and microcollisions: time, the two bodies or links,
        /// kind, impulse, point, normal, the normal speed before and after, the energies) to
        /// this .csv or .json file, as the run goes (FILE.partial until the run ends).
        #[arg(long, value_name = "FILE")]
        events: Option<PathBuf>,
        /// Write the multibodies' joint coordinates and rates (one column per degree of
        /// freedom, `<multibody>/<joint>.q` and `.qd`) at every frame to this .csv or .json
        /// file, as the run goes.
        #[arg(long, value_name = "FILE")]
        joints: Option<PathBuf>,
        /// Write SVG plots (energy.svg, paths.svg) into this directory.
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Write the run as an animated glTF 2.0 binary (.glb) for Blender or any glTF
        /// viewer: one node per body with its mesh, translation and rotation keyframes at the
        /// scene's output rate (the frames of --out), +Y up.
        #[arg(long, value_name = "OUT.glb")]
        gltf: Option<PathBuf>,
        /// Write the run as one self-contained web page (no network needed to open it) that
        /// replays it with WebGL: every body from its real geometry, orbit/zoom/pan camera,
        /// play/pause/step/scrub, playback speed, a body list with speed and energy, impacts
        /// on the time line and as flashes, and the energy plot.
        #[arg(long, value_name = "OUT.html")]
        html: Option<PathBuf>,
        /// Worker threads for the per-body work (default: every core). Results do not depend
        /// on it.
        #[arg(long)]
        threads: Option<usize>,
        /// Stop cleanly after this many wall-clock seconds, at the next frame: the outputs are
        /// written and valid up to there, and the summary says where the run stopped.
        #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
        max_wall: Option<f64>,
        /// Contact model, overriding the scene's `contact_model`: `switching` (impacts as
        /// impulses, sustained contact as constraints; the default) or `impulse` (every
        /// contact an impulse, the thesis's pure model).
        #[arg(long, value_enum)]
        contact_model: Option<run::ContactModelArg>,
        /// Print where the wall time went: multibody dynamics, rigid bodies, collision
        /// detection, collision response, sustained contact, high-level control (thesis Table
        /// 7.2).
        #[arg(long)]
        profile: bool,
    },
    /// How often a part comes to rest in each stable pose when dropped on a belt (thesis
    /// §7.5): quasi-static, perturbed quasi-static and dynamic estimates side by side, from
    /// drops run in parallel or in shards (`--shard K/N`, then `impulse poses merge`).
    Poses(poses::PosesArgs),
    /// The bowling study (thesis §7.4, Fig. 7.10): straight and hooking throws into ten
    /// pins, mean pins felled against where the ball crosses the pin line, run in parallel
    /// or in shards (`--shard K/N`, then `impulse bowling merge`); CSV and SVG out.
    Bowling(bowling::BowlingArgs),
    /// Exact mass properties of a closed polygon mesh (Wavefront OBJ), printed as JSON.
    ///
    /// The mesh must be closed and consistently oriented with faces counter-clockwise seen
    /// from outside; it may be non-convex, of any genus, with polygonal faces. Output fields:
    /// `volume`, `mass`, `com` (3 numbers), `inertia` (3×3, about the centre of mass, with the
    /// file's axes), `principal_moments` (3, increasing) and `principal_axes` (3×3), where
    /// `principal_axes[k]` is the unit axis of `principal_moments[k]` (a right-handed set).
    Massprops {
        /// The mesh file (.obj).
        mesh: PathBuf,
        /// Uniform density (mass per unit volume). Default 1.
        #[arg(long, conflicts_with = "mass", allow_negative_numbers = true)]
        density: Option<f64>,
        /// Total mass instead of a density (the density becomes mass / volume).
        #[arg(long, allow_negative_numbers = true)]
        mass: Option<f64>,
    },
    /// Forward dynamics, inverse dynamics or the mass matrix of a URDF multibody, as JSON.
    ///
    /// Vectors are comma-separated numbers in the model's joint order: depth-first from the
    /// root link, the children of a link in the order their joints appear in the file; fixed
    /// joints have no coordinate (`--joints` lists the order). Default output: the joint
    /// accelerations `{"qdd": [...]}` for `--q`, `--qd`, `--tau` (each defaults to zeros).
    /// Passive joint damping and friction from `<dynamics>` are not applied.
    Dynamics(dynamics::DynamicsArgs),
    /// FORK⁻¹S reduced model of a Mechanism(...) file under constant end-effector loads: the
    /// static response against the full nonlinear statics (--static), or a simulation writing
    /// link trajectories (the columns of `impulse run`) and the per-step error estimate.
    Reduce(reduce::ReduceArgs),
}

fn massprops(mesh: &Path, density: Option<f64>, mass: Option<f64>) -> Result<String, String> {
    let mesh = impulse_geom::obj::read(mesh).map_err(|e| e.to_string())?;
    let props = match mass {
        Some(m) => MassProperties::from_mesh_with_mass(&mesh, m),
        None => MassProperties::from_mesh(&mesh, density.unwrap_or(1.0)),
    }
    .map_err(|e| e.to_string())?;
    let volume = VolumeIntegrals::integrate(&mesh, mesh.bounding_box_center()).volume;
    let frame = props.principal().map_err(|e| e.to_string())?;
    let i = props.inertia;
    let rows = |m: [[f64; 3]; 3]| serde_json::json!(m);
    to_json_lines(&[
        ("volume", serde_json::json!(volume)),
        ("mass", serde_json::json!(props.mass)),
        ("com", serde_json::json!(props.com.to_array())),
        (
            "inertia",
            rows([
                i.row(0).to_array(),
                i.row(1).to_array(),
                i.row(2).to_array(),
            ]),
        ),
        (
            "principal_moments",
            serde_json::json!(frame.moments.to_array()),
        ),
        (
            "principal_axes",
            rows([
                frame.axes.col(0).to_array(),
                frame.axes.col(1).to_array(),
                frame.axes.col(2).to_array(),
            ]),
        ),
    ])
}

/// A JSON object with one field per line, in the order given, each value compact (a 3×3
/// matrix on one line): it reads better than fully expanded JSON and parses the same. Negative
/// zeros are printed as 0.
fn to_json_lines(fields: &[(&str, serde_json::Value)]) -> Result<String, String> {
    let mut lines = Vec::with_capacity(fields.len());
    for (key, v) in fields {
        let v =
            serde_json::to_string(&without_negative_zero(v.clone())).map_err(|e| e.to_string())?;
        lines.push(format!(
            "  {}: {v}",
            serde_json::Value::String((*key).to_owned())
        ));
    }
    Ok(format!("{{\n{}\n}}", lines.join(",\n")))
}

fn without_negative_zero(v: serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    match v {
        Value::Number(n) if n.as_f64() == Some(0.0) && n.is_f64() => Value::from(0.0),
        Value::Array(a) => Value::Array(a.into_iter().map(without_negative_zero).collect()),
        other => other,
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Run {
            scene,
            until,
            out,
            events,
            joints,
            plot,
            gltf,
            html,
            threads,
            contact_model,
            profile,
            max_wall,
        } => run::run(&run::RunArgs {
            scene,
            until: *until,
            out: out.as_deref(),
            events: events.as_deref(),
            joints: joints.as_deref(),
            plot: plot.as_deref(),
            gltf: gltf.as_deref(),
            html: html.as_deref(),
            threads: *threads,
            contact_model: *contact_model,
            profile: *profile,
            max_wall: *max_wall,
        }),
        Command::Massprops {
            mesh,
            density,
            mass,
        } => massprops(mesh, *density, *mass),
        Command::Dynamics(args) => dynamics::run(args),
        Command::Reduce(args) => reduce::run(args),
        Command::Poses(args) => poses::run(args),
        Command::Bowling(args) => bowling::run(args),
    };
    match result {
        Ok(text) => {
            // A closed pipe (`impulse run … | head -3`) is the reader's choice, not an error.
            let mut out = std::io::stdout().lock();
            match writeln!(out, "{text}").and_then(|()| out.flush()) {
                Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
                    eprintln!(
                        "{}",
                        text::error_line(&format!("cannot write to standard output: {e}"))
                    );
                    ExitCode::FAILURE
                }
                // A run stopped by Ctrl-C or SIGTERM printed its summary and kept its outputs
                // valid; its exit code says it did not finish.
                _ if interrupt::requested() => ExitCode::from(interrupt::EXIT_INTERRUPTED),
                _ => ExitCode::SUCCESS,
            }
        }
        Err(message) => {
            eprintln!("{}", text::error_line(&message));
            ExitCode::FAILURE
        }
    }
}
