//! Part file → [`DROPS`] drops of the pose study (thesis §7.5, `impulse_sim::poses`).
//!
//! The part is read as `impulse poses` reads a `.ron` part file and built into a
//! [`PosePart`] (its hull, mass properties and stable poses). Asserted: the quasi-static
//! estimate (eq. 7.1) is a distribution (non-negative shares summing to 1 within
//! [`SHARE_SUM`]); then drops 0..[`DROPS`] of a study with the default settings (the scene
//! [`drop_scene`] gives, exactly what `impulse poses` runs), each run for [`DROP_TIME`] in
//! steps of [`STEP`] under the checks of a scene ([`crate::scene`]): finite states,
//! penetration within ε_c by the independent monitor, and energy within
//! [`crate::energy::EnergyBound`] (a drop has gravity, a fixed belt and restitution 0.3: no
//! source the bound does not cover).
//!
//! Out of bounds: shapes beyond the scene check's bounds, OBJ shapes (the obj target covers
//! OBJ; a fuzzed path must not reach the file system), hulls of more than [`MAX_FACETS`]
//! faces, more than [`MAX_POINT_MASSES`] point masses.

use std::path::Path;

use impulse_sim::poses::{DropSettings, PartFileDesc, PosePart, drop_scene};
use impulse_sim::{Scene, World, WorldSettings};

use crate::{Outcome, Violation};

/// Drops per part. `5`.
pub const DROPS: u64 = 5;
/// Simulated time of one drop (s): the fall from the study's 0.12 m takes 0.16 s, and the
/// first bounces follow. `0.4`.
pub const DROP_TIME: f64 = 0.4;
/// Step between checks of a drop (s). `2e-3`.
pub const STEP: f64 = 2e-3;
/// The study's seed (any fixed value: a drop's start depends only on it and the index). `1`.
pub const SEED: u64 = 1;
/// Most hull faces of a fuzzed part. `256`.
pub const MAX_FACETS: usize = 256;
/// Most point masses of a fuzzed part. `8`.
pub const MAX_POINT_MASSES: usize = 8;
/// How far the quasi-static shares may sum from 1. The solid angles about an interior point
/// cover the sphere exactly, but the hull merges faces coplanar within
/// `impulse_geom::tol::POLYHEDRON_REL` (1e-7) of its diameter, so a facet's corners may lie
/// that far off its plane and neighbouring facets' solid angles overlap or leave gaps of that
/// order (1.3e-8 measured on a pebble with a 1.8 km spike). `1e-6`.
pub const SHARE_SUM: f64 = 1e-6;

/// Checks one part file's bytes (module documentation).
///
/// # Errors
/// The [`Violation`] found.
pub fn check_part(bytes: &[u8]) -> Result<Outcome, Violation> {
    let Some(text) = crate::text(bytes) else {
        return Ok(Outcome::Rejected("not UTF-8".into()));
    };
    let desc: PartFileDesc = match ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(text)
    {
        Ok(d) => d,
        Err(e) => return Ok(Outcome::Rejected(e.to_string())),
    };
    if let Some(r) = crate::scene::shape_out_of_bounds(&desc.shape, true) {
        return Ok(Outcome::OutOfBounds(r));
    }
    if desc.point_masses.len() > MAX_POINT_MASSES {
        return Ok(Outcome::OutOfBounds(format!(
            "{} point masses > {MAX_POINT_MASSES}",
            desc.point_masses.len()
        )));
    }
    let part = match PosePart::new(&desc, Path::new("/nonexistent-fuzz-base")) {
        Ok(p) => p,
        Err(e) => return Ok(Outcome::Rejected(e.to_string())),
    };
    if part.hull.face_count() > MAX_FACETS {
        return Ok(Outcome::OutOfBounds(format!(
            "{} hull faces > {MAX_FACETS}",
            part.hull.face_count()
        )));
    }
    let shares = part.analysis.quasi_static();
    let sum: f64 = shares.iter().sum();
    if shares.iter().any(|s| s.is_nan() || *s < 0.0) || (sum - 1.0).abs() > SHARE_SUM {
        return Err(Violation::Inconsistent(format!(
            "quasi-static shares sum to {sum} ({shares:?})"
        )));
    }
    let settings = DropSettings {
        max_time: DROP_TIME,
        ..DropSettings::default()
    };
    let steps = (DROP_TIME / STEP).round() as usize;
    for i in 0..DROPS {
        let scene = match drop_scene(&part, &settings, SEED, i) {
            Ok(s) => s,
            Err(e) => return Ok(Outcome::Rejected(e.to_string())),
        };
        let sustained = WorldSettings::from_desc(&scene).sustained;
        let mut world = match World::from_scene(&Scene::new(scene, part.base_dir.clone())) {
            Ok(w) => w,
            Err(e) => return Ok(Outcome::Rejected(format!("drop {i}: {e}"))),
        };
        world.set_parallel_min_bodies(usize::MAX);
        match crate::scene::run_checked(&mut world, &sustained, true, steps, STEP) {
            Ok(Outcome::Checked { .. }) => {}
            Ok(other) => return Ok(other),
            Err(v) => return Err(annotate(v, i)),
        }
    }
    Ok(Outcome::Checked {
        energy_checked: true,
    })
}

/// The violation with the drop's index in its message.
fn annotate(v: Violation, drop: u64) -> Violation {
    match v {
        Violation::NotFinite(m) => Violation::NotFinite(format!("drop {drop}: {m}")),
        Violation::EnergyGained(m) => Violation::EnergyGained(format!("drop {drop}: {m}")),
        Violation::Penetration(m) => Violation::Penetration(format!("drop {drop}: {m}")),
        Violation::MassProperties(m) => Violation::MassProperties(format!("drop {drop}: {m}")),
        Violation::Geometry(m) => Violation::Geometry(format!("drop {drop}: {m}")),
        Violation::Inconsistent(m) => Violation::Inconsistent(format!("drop {drop}: {m}")),
    }
}
