//! Hybrid scenes (thesis §7.2: multibodies in the impulse-based world): V19 triple pendulum.

use impulse_multibody::Workspace;

use super::{Run, SceneCheck, no_penetration};
use crate::validate::case::{Check, Metric};

/// V19: the pendulum counts as at rest at its minimum-energy pose when its energy above that
/// pose's is below this fraction of what it was released with (the mallet may come to rest
/// against a ball, a little off the lowest pose).
const V19_REST_ENERGY_REL: f64 = 0.02;

pub(super) fn checks() -> Vec<SceneCheck> {
    vec![SceneCheck {
        case: "V19-triple-pendulum",
        scene: "triple-pendulum",
        description: "an undamped triple pendulum swinging into six balls in a dish: total energy never rises by more than one microcollision kick (Σm·g·ε_c), the pendulum ends at rest at its minimum-energy pose, no interpenetration",
        headline: "pendulum_rest_energy_rel",
        event_log: false,
        thesis: Some(("triple pendulum", 25.9)),
        metrics: v19_triple_pendulum,
    }]
}

/// Kinetic and potential energy of a multibody at `(q, v)`.
fn energy(model: &impulse_multibody::Model, q: &[f64], v: &[f64]) -> Result<(f64, f64), String> {
    let mut ws = Workspace::new(model);
    ws.update_kinematics(model, q, v)
        .map_err(|e| e.to_string())?;
    Ok((ws.kinetic_energy(model), ws.potential_energy(model)))
}

/// V19. The kick bound: a microcollision's rebound limit (thesis eq. 3.18) caps the normal
/// speed after at √(2 g ε_c), a kinetic energy of at most m g ε_c for the body that rebounds;
/// total energy may rise above its lowest value so far by at most the sum over every moving
/// body (balls and the pendulum's links). The pendulum's release energy and its minimum
/// (hanging straight down, every joint at zero) are computed from its model.
fn v19_triple_pendulum(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let eps = r.world.collision_epsilon();
    let h = r.world.multibody_handle("pendulum").ok_or("no pendulum")?;
    let sim = r.world.multibody(h).ok_or("no pendulum")?;
    let model = sim.model();
    let balls: f64 = r
        .world
        .bodies()
        .filter_map(|(_, b)| b.mass.map(|m| m.mass))
        .sum();
    let kick = (balls + model.total_mass()) * r.g() * eps;
    let (mut lowest, mut rise) = (f64::INFINITY, 0.0_f64);
    for f in &r.rec.frames {
        let e = f.kinetic_energy + f.potential_energy;
        rise = rise.max(e - lowest);
        lowest = lowest.min(e);
    }
    let desc = r
        .scene
        .desc
        .multibodies
        .iter()
        .find(|m| m.name == "pendulum")
        .ok_or("no pendulum in the scene")?;
    let (released, _) = desc
        .build(
            glam::DVec3::from_array(r.scene.desc.gravity),
            &r.scene.base_dir,
        )
        .map_err(|e| e.to_string())?;
    let (_, p0) = energy(model, released.q(), released.v())?;
    let zero = model.neutral_configuration();
    let (_, p_min) = energy(model, &zero, &vec![0.0; model.nv()])?;
    let (k_end, p_end) = energy(model, sim.q(), sim.v())?;
    let rest = (k_end + p_end - p_min) / (p0 - p_min);
    Ok(vec![
        Metric::new(
            "energy_rise_over_kick",
            rise / kick,
            0.0,
            Check::Between(0.0, 1.0),
        ),
        Metric::new(
            "pendulum_rest_energy_rel",
            rest,
            0.0,
            Check::Between(0.0, V19_REST_ENERGY_REL),
        ),
        no_penetration(r),
    ])
}
