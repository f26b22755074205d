//! Hybrid scenes (thesis §7.2: multibodies in the impulse-based world): V19 triple pendulum,
//! V20 see-saw.

use impulse_multibody::Workspace;

use super::{Run, SceneCheck, no_penetration};
use crate::validate::case::{Check, Metric};

/// V19: the pendulum counts as at rest at its minimum-energy pose when its energy above that
/// pose's is below this fraction of what it was released with (the mallet may come to rest
/// against a ball, a little off the lowest pose).
const V19_REST_ENERGY_REL: f64 = 0.02;

pub(super) fn checks() -> Vec<SceneCheck> {
    vec![
        SceneCheck {
            case: "V20-see-saw",
            scene: "see-saw",
            description: "eight balls roll down a tray onto a see-saw hinged in its opening: all eight are below the opening at the end, the plank's hinge point never leaves its pivot (reduced coordinates), no interpenetration",
            headline: "hinge_drift_over_eps_c",
            event_log: false,
            thesis: Some(("see-saw", 3.2)),
            metrics: v20_see_saw,
        },
        SceneCheck {
            case: "V19-triple-pendulum",
            scene: "triple-pendulum",
            description: "an undamped triple pendulum swinging into six balls in a dish: total energy never rises by more than one microcollision kick (Σm·g·ε_c), the pendulum ends at rest at its minimum-energy pose, no interpenetration",
            headline: "pendulum_rest_energy_rel",
            event_log: false,
            thesis: Some(("triple pendulum", 25.9)),
            metrics: v19_triple_pendulum,
        },
    ]
}

/// V20. The pivot is where the scene puts the hinge (the multibody's placement composed with
/// the joint's position, both read from the scene); the plank's link frame sits on it and
/// turns about the joint's axis only. A ball
/// has passed when its centre is below the opening by more than its radius.
fn v20_see_saw(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let desc = multibody_desc(r, "see-saw")?;
    let joint = desc.joints.first().ok_or("the see-saw has no joint")?;
    let pivot = glam::DVec3::from_array(desc.position) + glam::DVec3::from_array(joint.position);
    let axis = glam::DVec3::from_array(joint.axis).normalize();
    let plank = r.index(&format!("see-saw/{}", joint.child))?;
    // Two points of the plank on its hinge axis, 10 cm either side of the pivot (the scene
    // places the multibody and the joint without rotation): a revolute joint keeps both where
    // they started; any other motion of the plank moves one of them.
    let drift = r
        .rec
        .frames
        .iter()
        .flat_map(|f| {
            let b = &f.bodies[plank];
            [-0.1, 0.1].map(|s| (b.position + b.rotation * (axis * s)).distance(pivot + axis * s))
        })
        .fold(0.0, f64::max);
    let balls: Vec<(usize, f64)> = r
        .scene
        .desc
        .bodies
        .iter()
        .filter_map(|b| match b.shape {
            impulse_sim::scene::ShapeDesc::Sphere { radius } => Some((b.name.as_str(), radius)),
            _ => None,
        })
        .map(|(n, radius)| r.index(n).map(|i| (i, radius)))
        .collect::<Result<_, _>>()?;
    let last = r.rec.frames.last().ok_or("no frames")?;
    let below = balls
        .iter()
        .filter(|&&(i, radius)| last.bodies[i].com.z < pivot.z - radius)
        .count();
    let n = balls.len() as f64;
    Ok(vec![
        Metric::new("balls_below_opening", below as f64, n, Check::Between(n, n)),
        Metric::new(
            "hinge_drift_over_eps_c",
            drift / r.world.collision_epsilon(),
            0.0,
            Check::Between(0.0, 1e-9),
        ),
        no_penetration(r),
    ])
}

/// The description of multibody `name` in the scene that was run.
fn multibody_desc<'a>(
    r: &'a Run<'_>,
    name: &str,
) -> Result<&'a impulse_sim::scene::MultibodyDesc, String> {
    r.scene
        .desc
        .multibodies
        .iter()
        .find(|m| m.name == name)
        .ok_or_else(|| format!("no multibody \"{name}\" in the scene"))
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
    let desc = multibody_desc(r, "pendulum")?;
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
