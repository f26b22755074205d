//! The internal-link update as it was before the batched kernel (`InternalLinks`), kept
//! verbatim so a bench run times old and new side by side: equivalent wrenches `K ξ`, each
//! link's twist map product (eq. 22), an exponential with one `sin_cos` per link above 0.01
//! rad, the quaternion product with the reference, rayon batches of 32 links.

use glam::DQuat;
use impulse_geom::pose::SE3_SERIES_ANGLE;
use impulse_geom::{Pose, Twist};
use impulse_reduced::ReducedModel;
use impulse_reduced::internal::{LINK_BATCH, equivalent_wrenches, link_twist};
use rayon::prelude::*;

fn fast_exp(xi: &Twist) -> Pose {
    let w = xi.w;
    let t2 = w.length_squared();
    let theta = t2.sqrt();
    let (k, c, a, b) = if theta < SE3_SERIES_ANGLE {
        (
            0.5 + t2 * (-1.0 / 48.0 + t2 * (1.0 / 3840.0 - t2 / 645_120.0)),
            1.0 + t2
                * (-1.0 / 8.0 + t2 * (1.0 / 384.0 + t2 * (-1.0 / 46_080.0 + t2 / 10_321_920.0))),
            0.5 + t2 * (-1.0 / 24.0 + t2 * (1.0 / 720.0 - t2 / 40_320.0)),
            1.0 / 6.0 + t2 * (-1.0 / 120.0 + t2 * (1.0 / 5040.0 - t2 / 362_880.0)),
        )
    } else {
        let (sh, ch) = (0.5 * theta).sin_cos();
        let k = sh / theta;
        (k, ch, 2.0 * k * k, (theta - 2.0 * sh * ch) / (t2 * theta))
    };
    let xyz = w * k;
    let wv = w.cross(xi.v);
    Pose {
        rotation: DQuat::from_xyzw(xyz.x, xyz.y, xyz.z, c),
        translation: xi.v + wv * a + w.cross(wv) * b,
    }
}

fn place(reference: &Pose, xi: &Twist) -> Pose {
    let e = fast_exp(xi);
    Pose {
        rotation: reference.rotation * e.rotation,
        translation: reference.rotation * e.translation + reference.translation,
    }
}

/// The previous `update_internal_links`.
pub fn update_internal_links(model: &ReducedModel, xi: &[f64], frame: &Pose, out: &mut [Pose]) {
    let w = equivalent_wrenches(model, xi);
    let moving = *frame != Pose::IDENTITY;
    out.par_chunks_mut(LINK_BATCH)
        .enumerate()
        .for_each(|(batch, chunk)| {
            for (i, pose) in chunk.iter_mut().enumerate() {
                let k = batch * LINK_BATCH + i;
                let xi_l = link_twist(model, k, &w);
                let local = place(&model.internal_reference[k], &xi_l);
                *pose = if moving { *frame * local } else { local };
            }
        });
}
