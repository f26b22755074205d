//! Validation cases V22–V24 of the chapter-7 digest (thesis §7.5, pose statistics), and the
//! thick coin's quasi-static edge share. Parts are read from `fixtures/parts/`, the thesis's
//! tables from `fixtures/parts/thesis-tables.ron`.
//!
//! - V22: the 1 × 2 × 3 box's quasi-static probabilities per face pair against the closed-form
//!   solid angle of a rectangle (1e-9) and the thesis's printed 64.50 / 24.27 / 11.23 %.
//! - V23: the cube dropped 2000 times from starts uniform on SO(3) (the thesis's drop: 12 cm,
//!   5 cm/s, μ = e = 0.3): every face within the worst-case 95 % interval of 1/6 (eq. 7.3).
//! - V24: eq. 7.2's error recomputed from every column of Tables 7.3–7.6 against the printed
//!   error rows (to their rounding, 0.05), and eq. 7.3's sample sizes for δ = 0.05.
//! - coin: the thick coin's edge share against the sum of its 48 side rectangles' closed-form
//!   solid angles, and against the cylinder's 1/2.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use impulse_massprops::stats;
use impulse_sim::poses::{self, DropSettings, PosePart, Shard};
use impulse_sim::scene::ShapeDesc;
use serde::Deserialize;

use crate::validate::case::{Case, Check, Metric};

/// Drops of V23 (the thesis's count per part).
const V23_DROPS: u64 = 2000;
/// Confidence of V23's interval.
const V23_CONFIDENCE: f64 = 0.95;
/// The thesis's printed quasi-static shares of the 1 × 2 × 3 box (digest V22), to their
/// rounding.
const V22_PRINTED: [(usize, f64); 3] = [(0, 0.6450), (1, 0.2427), (2, 0.1123)];
/// Half a unit of the last digit of Tables 7.3–7.6's error rows (%).
const PRINTED_ROUNDING: f64 = 0.05;
/// Half a unit of the last digit of V22's printed shares (%, two decimals).
const V22_ROUNDING: f64 = 0.005;
/// Exact agreement of two closed forms.
const EXACT_ABS: f64 = 1e-9;

/// The pose-statistics cases.
pub fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "V22-quasi-static-box",
            description: "quasi-static pose shares of the 1x2x3 box vs the rectangle solid-angle closed form and thesis §7.5's 64.50/24.27/11.23 %",
            run: Box::new(v22),
        },
        Case {
            name: "V23-cube-drops",
            description: "2000 drops of a cube (12 cm, 5 cm/s, mu = e = 0.3) from uniform starts: every face within the 95 % interval of 1/6",
            run: Box::new(v23),
        },
        Case {
            name: "V24-error-metric",
            description: "eq. 7.2 recomputed from Tables 7.3-7.6 vs their printed error rows; eq. 7.3 sample sizes 271 (90 %) and 385 (95 %)",
            run: Box::new(v24),
        },
        Case {
            name: "coin-quasi-static",
            description: "thick 48-gon coin (thickness/diameter 1/sqrt3): edge share vs its side rectangles' closed form and the cylinder's 1/2",
            run: Box::new(coin),
        },
    ]
}

fn parts_dir() -> PathBuf {
    crate::workspace_root().join("fixtures").join("parts")
}

fn part(name: &str) -> Result<PosePart, String> {
    PosePart::load(&parts_dir().join(name)).map_err(|e| e.to_string())
}

/// Solid angle of a centred a × b rectangle at distance d.
fn rectangle_solid_angle(a: f64, b: f64, d: f64) -> f64 {
    4.0 * (a * b / ((a * a + 4.0 * d * d) * (b * b + 4.0 * d * d)).sqrt()).asin()
}

fn v22() -> Result<Vec<Metric>, String> {
    let p = part("box-1x2x3.ron")?;
    let ShapeDesc::Box { half_extents: h } = p.body.shape else {
        return Err("box-1x2x3.ron is not a Box".into());
    };
    let qs = p.analysis.quasi_static();
    let mut out = Vec::new();
    let mut total = 0.0;
    for (axis, printed) in V22_PRINTED {
        let share: f64 = p
            .analysis
            .facets()
            .iter()
            .filter(|f| p.normal_in_part_frame(f.face).abs().max_position() == axis)
            .map(|f| qs[f.face as usize])
            .sum();
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let exact = 2.0 * rectangle_solid_angle(2.0 * h[u], 2.0 * h[v], h[axis]) / (4.0 * PI);
        out.push(Metric::new(
            format!("axis{axis}.closed_form"),
            share,
            exact,
            Check::Abs(EXACT_ABS),
        ));
        out.push(Metric::new(
            format!("axis{axis}.thesis_percent"),
            100.0 * share,
            100.0 * printed,
            Check::Abs(V22_ROUNDING),
        ));
        total += share;
    }
    out.push(Metric::new("sum", total, 1.0, Check::Abs(EXACT_ABS)));
    Ok(out)
}

fn v23() -> Result<Vec<Metric>, String> {
    let p = part("cube.ron")?;
    let settings = DropSettings {
        belt_fed: false,
        ..DropSettings::default()
    };
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let outcomes = poses::run_drops(&p, &settings, 1, V23_DROPS, Shard::ALL, threads, &|_| {})
        .map_err(|e| e.to_string())?;
    let half = stats::worst_half_width(V23_DROPS, V23_CONFIDENCE).map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    let expect = 1.0 / 6.0;
    for f in p.analysis.facets() {
        let n = outcomes.iter().filter(|o| o.facet == Some(f.face)).count();
        let freq = n as f64 / V23_DROPS as f64;
        let axis = p.normal_in_part_frame(f.face);
        out.push(Metric::new(
            format!("face({:+.0},{:+.0},{:+.0})", axis.x, axis.y, axis.z),
            freq,
            expect,
            Check::Between(expect - half, expect + half),
        ));
    }
    let unsettled = outcomes.iter().filter(|o| o.facet.is_none()).count();
    out.push(Metric::new(
        "not_on_a_face",
        unsettled as f64,
        0.0,
        Check::Abs(0.0),
    ));
    Ok(out)
}

/// One table of `thesis-tables.ron`.
#[derive(Deserialize)]
struct Table {
    table: String,
    #[allow(dead_code)]
    part: String,
    #[allow(dead_code)]
    trials: u64,
    quasi_static: Vec<f64>,
    perturbed: Vec<f64>,
    dynamic: Vec<f64>,
    physical: Vec<f64>,
    error: (f64, f64, f64),
}

#[derive(Deserialize)]
struct ThesisTables {
    tables: Vec<Table>,
}

fn thesis_tables(path: &Path) -> Result<Vec<Table>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let t: ThesisTables = ron::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(t.tables)
}

fn v24() -> Result<Vec<Metric>, String> {
    let mut out = Vec::new();
    for t in thesis_tables(&parts_dir().join("thesis-tables.ron"))? {
        let p: Vec<f64> = t.physical.iter().map(|x| x / 100.0).collect();
        for (name, column, printed) in [
            ("quasi_static", &t.quasi_static, t.error.0),
            ("perturbed", &t.perturbed, t.error.1),
            ("dynamic", &t.dynamic, t.error.2),
        ] {
            let a: Vec<f64> = column.iter().map(|x| x / 100.0).collect();
            let e = stats::pose_error(&p, &a).map_err(|e| format!("table {}: {e}", t.table))?;
            out.push(Metric::new(
                format!("table{}.{name}", t.table),
                e,
                printed,
                Check::Abs(PRINTED_ROUNDING),
            ));
        }
    }
    for (confidence, n) in [(0.90, 271.0), (0.95, 385.0)] {
        let got = stats::sample_size(0.05, confidence).map_err(|e| e.to_string())? as f64;
        out.push(Metric::new(
            format!("sample_size.{confidence}"),
            got,
            n,
            Check::Abs(0.0),
        ));
    }
    Ok(out)
}

fn coin() -> Result<Vec<Metric>, String> {
    let p = part("thick-coin.ron")?;
    let ShapeDesc::Prism {
        sides,
        radius,
        half_height,
    } = p.body.shape
    else {
        return Err("thick-coin.ron is not a Prism".into());
    };
    let qs = p.analysis.quasi_static();
    let edge: f64 = p
        .analysis
        .facets()
        .iter()
        .filter(|f| p.normal_in_part_frame(f.face).z.abs() < 0.5)
        .map(|f| qs[f.face as usize])
        .sum();
    let half_angle = PI / f64::from(sides);
    let side = rectangle_solid_angle(
        2.0 * radius * half_angle.sin(),
        2.0 * half_height,
        radius * half_angle.cos(),
    );
    let exact = f64::from(sides) * side / (4.0 * PI);
    // A cylinder of the same radius and thickness: the band of latitudes ±atan(h/r).
    let cylinder = (half_height / radius).atan().sin();
    Ok(vec![
        Metric::new("edge.closed_form", edge, exact, Check::Abs(EXACT_ABS)),
        Metric::new("edge.cylinder", edge, cylinder, Check::Abs(0.005)),
    ])
}
