//! `impulse dynamics`: forward dynamics, inverse dynamics or the mass matrix of a URDF model.

use std::path::{Path, PathBuf};

use impulse_geom::DVec3;
use impulse_multibody::{
    BaseKind, Mat, Model, Workspace, forward_dynamics, inverse_dynamics, mass_matrix, urdf,
};

/// Options of `impulse dynamics`.
#[derive(clap::Args)]
pub struct DynamicsArgs {
    /// The model file (URDF).
    model: PathBuf,
    /// Joint positions q (rad or m), comma-separated, in the model's joint order. With
    /// --floating-base, q starts with the base position and quaternion: x,y,z,qx,qy,qz,qw.
    /// Default: all zero (identity base orientation).
    #[arg(long, allow_hyphen_values = true, value_name = "Q1,Q2,...")]
    q: Option<String>,
    /// Joint velocities q̇ (rad/s or m/s), comma-separated. With --floating-base, starts with
    /// the base twist in base coordinates: vx,vy,vz,wx,wy,wz. Default: all zero.
    #[arg(long, allow_hyphen_values = true, value_name = "QD1,QD2,...")]
    qd: Option<String>,
    /// Joint torques/forces τ (N·m or N), comma-separated (forward dynamics only). With
    /// --floating-base, starts with a wrench on the base in base coordinates. Default: zero.
    #[arg(long, allow_hyphen_values = true, value_name = "T1,T2,...")]
    tau: Option<String>,
    /// Joint accelerations q̈ for --inverse, comma-separated.
    #[arg(long, allow_hyphen_values = true, value_name = "QDD1,QDD2,...")]
    qdd: Option<String>,
    /// World gravity vector (m/s²).
    #[arg(
        long,
        allow_hyphen_values = true,
        value_name = "GX,GY,GZ",
        default_value = "0,0,-9.81"
    )]
    gravity: String,
    /// Print the joint-space mass matrix {"M": [[...]]} at --q instead of accelerations.
    #[arg(long, conflicts_with_all = ["inverse", "joints"])]
    mass_matrix: bool,
    /// Inverse dynamics: print the torques {"tau": [...]} that produce --qdd at (--q, --qd).
    #[arg(long, requires = "qdd", conflicts_with = "joints")]
    inverse: bool,
    /// Print the joint names in coordinate order {"joints": [...]} and exit.
    #[arg(long)]
    joints: bool,
    /// Let the URDF's root link float freely (6 extra coordinates) instead of fixing it.
    #[arg(long)]
    floating_base: bool,
}

/// Comma-separated numbers; `option` names the flag in messages.
fn parse_list(option: &str, text: &str) -> Result<Vec<f64>, String> {
    let text = text.trim();
    if text.is_empty() {
        return Ok(Vec::new());
    }
    text.split(',')
        .map(|s| {
            let s = s.trim();
            match s.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                Ok(_) => Err(format!("{option}: `{s}` is not a finite number")),
                Err(_) => Err(format!("{option}: `{s}` is not a number")),
            }
        })
        .collect()
}

/// The vector given for `option`, or `default`; its length must be `expected`.
fn vector(
    option: &str,
    text: Option<&str>,
    expected: usize,
    what: &str,
    default: Vec<f64>,
) -> Result<Vec<f64>, String> {
    let Some(text) = text else {
        return Ok(default);
    };
    let v = parse_list(option, text)?;
    if v.len() != expected {
        return Err(format!(
            "{option}: expected {expected} comma-separated values ({what}), got {}",
            v.len()
        ));
    }
    Ok(v)
}

fn describe(model: &Model, floating_extra: usize) -> String {
    let names = model.joint_names().join(", ");
    if model.is_floating() {
        format!("{floating_extra} base values, then joints [{names}]")
    } else {
        format!("one per joint: [{names}]")
    }
}

/// Runs `impulse dynamics` and returns its JSON text.
pub fn run(args: &DynamicsArgs) -> Result<String, String> {
    let base = if args.floating_base {
        BaseKind::Floating
    } else {
        BaseKind::Fixed
    };
    let mut model = load(&args.model, base)?;
    let g = parse_list("--gravity", &args.gravity)?;
    let [gx, gy, gz] = g[..] else {
        return Err(format!(
            "--gravity: expected 3 comma-separated values, got {}",
            g.len()
        ));
    };
    model.set_gravity(DVec3::new(gx, gy, gz));
    if args.joints {
        return to_json("joints", serde_json::json!(model.joint_names()));
    }
    let (nq, nv) = (model.nq(), model.nv());
    let q = vector(
        "--q",
        args.q.as_deref(),
        nq,
        &describe(&model, 7),
        model.neutral_configuration(),
    )?;
    let mut ws = Workspace::new(&model);
    if args.mass_matrix {
        let mut m = Mat::<f64>::zeros(nv, nv);
        mass_matrix(&model, &mut ws, &q, &mut m).map_err(|e| e.to_string())?;
        let rows: Vec<Vec<f64>> = (0..nv)
            .map(|r| (0..nv).map(|c| m[(r, c)]).collect())
            .collect();
        for row in &rows {
            finite(&model, "mass matrix entry", row)?;
        }
        return to_json("M", serde_json::json!(rows));
    }
    let qd = vector(
        "--qd",
        args.qd.as_deref(),
        nv,
        &describe(&model, 6),
        vec![0.0; nv],
    )?;
    if args.inverse {
        let qdd = vector(
            "--qdd",
            args.qdd.as_deref(),
            nv,
            &describe(&model, 6),
            vec![0.0; nv],
        )?;
        let mut tau = vec![0.0; nv];
        inverse_dynamics(&model, &mut ws, &q, &qd, &qdd, None, &mut tau)
            .map_err(|e| e.to_string())?;
        finite(&model, "tau", &tau)?;
        return to_json("tau", serde_json::json!(tau));
    }
    if args.qdd.is_some() {
        return Err("--qdd is only used with --inverse".to_owned());
    }
    let tau = vector(
        "--tau",
        args.tau.as_deref(),
        nv,
        &describe(&model, 6),
        vec![0.0; nv],
    )?;
    let mut qdd = vec![0.0; nv];
    forward_dynamics(&model, &mut ws, &q, &qd, &tau, None, &mut qdd).map_err(|e| e.to_string())?;
    finite(&model, "qdd", &qdd)?;
    to_json("qdd", serde_json::json!(qdd))
}

/// Refuses a result with a non-number in it (JSON would print `null`), naming the quantity
/// and the coordinate: inputs whose products overflow double precision (a velocity of 1e200
/// squared in the Coriolis terms, torques near the largest double) give infinities.
fn finite(model: &Model, quantity: &str, values: &[f64]) -> Result<(), String> {
    let Some(k) = values.iter().position(|x| !x.is_finite()) else {
        return Ok(());
    };
    let base = if model.is_floating() { 6 } else { 0 };
    let coordinate = match k.checked_sub(base) {
        Some(j) => format!("joint `{}`", model.joint_names()[j]),
        None => format!("base coordinate {k}"),
    };
    Err(format!(
        "{quantity} of {coordinate} is {}: the inputs overflow double precision (every \
         input must be small enough that its squares and products stay finite)",
        values[k]
    ))
}

fn load(path: &Path, base: BaseKind) -> Result<Model, String> {
    urdf::from_file(path, base).map_err(|e| e.to_string())
}

fn to_json(key: &str, value: serde_json::Value) -> Result<String, String> {
    crate::to_json_lines(&[(key, value)])
}
