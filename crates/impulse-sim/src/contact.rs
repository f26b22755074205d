//! From a detected contact to impulses on two bodies, through `impulse-response`.
//!
//! The contact frame's z axis is the contact normal, pointing from the second body of the pair
//! toward the first (thesis §3.2); the contact point is the midpoint of the closest points.
//! The collision matrix is eq. (3.4) from the two bodies' inverse masses and world inverse
//! inertias (fixed and scripted bodies contribute nothing: infinite mass). A contact that is
//! not approaching (`u_z ≥ 0`) gets no impulse. One that approaches slower than
//! `√(2·g·ε_c)` is a microcollision (thesis §3.5, eq. 3.18): the reversing impulse when it lies
//! in the friction cone, otherwise a collision with restitution boosted by the depth reached
//! into the ε_c envelope, within a rebound limit set by gravity's component along the normal
//! (`impulse_response::MicrocollisionParams::rebound_limit`). Anything faster is an ordinary
//! collision with Stronge's law.

use glam::DVec3;
use impulse_response::{
    CollisionMatrix, ContactFrame, MicrocollisionParams, ResponseKind, Restitution, Settings,
};

use crate::body::Body;
pub use crate::world::Material;

/// Normal approach speeds below this fraction of the microcollision speed √(2·g·ε_c) (thesis
/// eq. 3.18) count as no approach: rounding, not motion (without gravity, only a strictly
/// negative approach counts). Default `1e-6`.
pub const APPROACH_FLOOR_REL: f64 = 1e-6;

/// Settings of the contact model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactModel {
    /// Relative tolerance of the collision integrator (impulse-response's `rtol`).
    pub collision_tolerance: f64,
    /// Largest boosted restitution of a microcollision, e_max (thesis: 5.0).
    pub max_restitution: f64,
    /// Whether microcollisions try the reversing impulse first (thesis §3.5: yes).
    pub reversing: bool,
}

impl ContactModel {
    /// Checks the tolerance and e_max (as `impulse-response` requires).
    ///
    /// # Errors
    /// A sentence naming the value that is out of range.
    pub fn validate(&self) -> Result<(), String> {
        let tol = self.collision_tolerance;
        if !(tol.is_finite() && tol > 0.0 && tol <= 1e-2) {
            return Err(format!("collision_tolerance {tol} must lie in (0, 1e-2]"));
        }
        if !(self.max_restitution.is_finite() && self.max_restitution >= 1.0) {
            return Err(format!(
                "max_restitution {} must be finite and ≥ 1",
                self.max_restitution
            ));
        }
        Ok(())
    }
}

impl Default for ContactModel {
    fn default() -> Self {
        Self {
            collision_tolerance: 1e-10,
            max_restitution: 5.0,
            reversing: true,
        }
    }
}

/// What a resolved contact was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactKind {
    /// An ordinary collision.
    Collision,
    /// A microcollision with boosted restitution.
    Microcollision,
    /// A microcollision resolved by the reversing impulse.
    Reversing,
    /// A contact the response could not resolve, resolved by the fallback: a frictionless
    /// Newton impulse along the normal, with e = 1 for a microcollision (see the module
    /// documentation of [`crate::world`]).
    Fallback,
}

/// The response's view of a body.
pub(crate) fn response_body(b: &Body) -> impulse_response::Body {
    if b.is_dynamic() {
        impulse_response::Body::Moving {
            inverse_mass: b.inverse_mass(),
            inverse_inertia: b.inverse_inertia_world(),
        }
    } else {
        impulse_response::Body::Fixed
    }
}

/// Resolves a contact between `b1` and `b2` at world point `x` with unit normal `n` (from b2
/// toward b1), current distance `distance` (< ε_c), under `gravity` (world acceleration;
/// microcollisions use its magnitude in (3.18) and its component along `n` in the rebound
/// limit). Applies the impulses and returns what kind
/// of contact it was with the impulse on `b1` (world), or `None` when the bodies are not
/// approaching.
///
/// # Errors
/// The response's error message when the collision cannot be resolved.
#[allow(clippy::too_many_arguments)]
pub(crate) fn resolve(
    b1: &mut Body,
    b2: &mut Body,
    x: DVec3,
    n: DVec3,
    distance: f64,
    eps_c: f64,
    gravity: DVec3,
    mat: Material,
    model: &ContactModel,
) -> Result<Option<(ContactKind, DVec3)>, String> {
    let frame = ContactFrame::from_normal(n).map_err(|e| e.to_string())?;
    let u_world = b1.point_velocity(x) - b2.point_velocity(x);
    let u0 = frame.to_contact(u_world);
    // An approach slower than rounding is no approach (bodies resting exactly against each
    // other would otherwise trade impulses of 1e-20 m/s at one instant for ever).
    let g = gravity.length();
    let rest = APPROACH_FLOOR_REL * (2.0 * g * eps_c).sqrt();
    if u0.z >= -rest {
        return Ok(None);
    }
    let (r1, r2) = (x - b1.pose.translation, x - b2.pose.translation);
    let k = CollisionMatrix::rigid(&response_body(b1), r1, &response_body(b2), r2, &frame)
        .map_err(|e| e.to_string())?;
    let settings = Settings {
        rtol: model.collision_tolerance,
        ..Settings::default()
    };
    let response = if g > 0.0 {
        let params = MicrocollisionParams {
            gravity: g,
            normal_gravity: gravity.dot(n).abs(),
            collision_epsilon: eps_c,
            max_restitution: model.max_restitution,
            reversing: model.reversing,
        };
        impulse_response::resolve_with_microcollisions(
            &k,
            u0,
            mat.friction,
            mat.restitution,
            distance.max(0.0),
            &params,
            &settings,
        )
    } else {
        // Without gravity the candidate speed √(2gε_c) is 0: every contact is a collision.
        impulse_response::resolve(
            &k,
            u0,
            mat.friction,
            mat.restitution,
            Restitution::Stronge,
            &settings,
        )
    }
    .map_err(|e| {
        format!(
            "{e} (contact frame: K = {:?}, u0 = {u0:?}, μ = {}, e = {}, separation = {distance:e})",
            k.k().to_cols_array(),
            mat.friction,
            mat.restitution
        )
    })?;
    let p = response.impulse_world(&frame);
    b1.apply_impulse(p, x);
    b2.apply_impulse(-p, x);
    let micro = g > 0.0 && -u0.z < (2.0 * g * eps_c).sqrt();
    let kind = match response.kind {
        ResponseKind::Reversing => ContactKind::Reversing,
        _ if micro => ContactKind::Microcollision,
        _ => ContactKind::Collision,
    };
    Ok(Some((kind, p)))
}

/// The fallback when the response cannot resolve a contact: a frictionless impulse along the
/// normal `n` (from b2 toward b1) at world point `x` with Newton's restitution `e`,
/// `j = −(1 + e)·u_n / (nᵀ K n)` with `nᵀ K n = 1/m₁ + 1/m₂ + (r₁×n)·I₁⁻¹(r₁×n) +
/// (r₂×n)·I₂⁻¹(r₂×n)` computed from the bodies directly (thesis eq. 3.4 projected on the
/// normal). It never adds energy for e ≤ 1 and conserves momentum. Applies it and returns the
/// impulse on `b1`; `None` (nothing applied) when the bodies are not approaching or `nᵀ K n`
/// is not a positive finite number.
pub(crate) fn resolve_fallback(
    b1: &mut Body,
    b2: &mut Body,
    x: DVec3,
    n: DVec3,
    e: f64,
) -> Option<DVec3> {
    let u_n = (b1.point_velocity(x) - b2.point_velocity(x)).dot(n);
    if u_n.is_nan() || u_n >= 0.0 {
        return None;
    }
    let term = |b: &Body| {
        let rn = (x - b.pose.translation).cross(n);
        b.inverse_mass() + rn.dot(b.inverse_inertia_world() * rn)
    };
    let k_nn = term(b1) + term(b2);
    if !(k_nn.is_finite() && k_nn > 0.0) {
        return None;
    }
    let p = n * (-(1.0 + e) * u_n / k_nn);
    if !p.is_finite() {
        return None;
    }
    b1.apply_impulse(p, x);
    b2.apply_impulse(-p, x);
    Some(p)
}
