//! What the points of a held contact patch are asked for: the patches of an island's contact
//! list, and gaps and end-of-step normal speeds made consistent per patch (a plane over the
//! patch: what a relative motion of two rigid bodies can meet).
//!
//! **Must not know** how islands are formed or solved ([`super::island`]).

use glam::DVec3;
use impulse_response::Contact;

/// Relative size below which a patch's point layout is treated as degenerate (collinear or a
/// single point) when fitting a plane to its gaps. Default `1e-6`.
const PATCH_FIT_DEGENERATE: f64 = 1e-6;

/// The index ranges of an island's patches: the contacts of one manifold (pair and manifold
/// index of `origin`), which are consecutive.
pub(super) fn patch_ranges(origin: &[((u32, u32), usize, usize)]) -> Vec<std::ops::Range<usize>> {
    let mut ranges = Vec::new();
    let mut k = 0;
    while k < origin.len() {
        let patch = (origin[k].0, origin[k].1);
        let mut end = k;
        while end < origin.len() && (origin[end].0, origin[end].1) == patch {
            end += 1;
        }
        ranges.push(k..end);
        k = end;
    }
    ranges
}

/// Each contact's value (a gap, a speed) replaced by the value at its point of the plane (a
/// line for collinear points, the mean for one point) fitted by least squares to the values of
/// its patch.
pub(super) fn patch_plane_fit(
    contacts: &[Contact],
    patches: &[std::ops::Range<usize>],
    values: &[f64],
) -> Vec<f64> {
    let mut out = values.to_vec();
    for range in patches {
        let points: Vec<DVec3> = contacts[range.clone()].iter().map(|c| c.point).collect();
        let fit = fit_plane(
            &points,
            contacts[range.start].normal,
            &values[range.clone()],
        );
        out[range.clone()].copy_from_slice(&fit);
    }
    out
}

/// The end-of-step normal speed each contact is asked for: `speed` of its gap, made
/// consistent per patch. The points of a patch belong to the same two rigid bodies, so the
/// normal speeds a relative motion can give them lie on a plane over the patch (a
/// translation along the normal and two tilts). The stabilisation's speed is piecewise linear
/// in the gap (the rest band, the overlap term), so a patch whose gaps straddle a kink — a
/// tilted face with one corner below the rest gap and the others inside the band — asks for
/// speeds no rigid motion meets, and the direct solve answers such a system with impulses
/// 10⁴ times the island's momentum (under the heavy ball of the tower of light boxes every
/// direct solve diverged so, and the sweeps never converged). Each patch is asked instead for
/// the least-squares plane of its points' speeds, raised until it meets every point's own
/// speed: no point gets less than it asks (an overlap is still pushed out in full).
pub(super) fn patch_targets(
    contacts: &[Contact],
    patches: &[std::ops::Range<usize>],
    gaps: &[f64],
    speed: impl Fn(f64) -> f64,
) -> Vec<f64> {
    let own: Vec<f64> = gaps.iter().map(|&g| speed(g)).collect();
    let mut plane = patch_plane_fit(contacts, patches, &own);
    for range in patches {
        let short = range
            .clone()
            .map(|k| own[k] - plane[k])
            .fold(0.0_f64, f64::max);
        for target in &mut plane[range.clone()] {
            *target += short;
        }
    }
    plane
}

/// Least-squares plane g ≈ a + b·s + c·t over the points' coordinates (s, t) in the plane
/// normal to `normal`; a line or the mean when the points do not span a plane.
fn fit_plane(points: &[DVec3], normal: DVec3, gaps: &[f64]) -> Vec<f64> {
    let n = points.len();
    let mean = gaps.iter().sum::<f64>() / n as f64;
    if n < 2 {
        return vec![mean; n];
    }
    let centre = points.iter().copied().sum::<DVec3>() / n as f64;
    let radius = points
        .iter()
        .map(|p| (*p - centre).length())
        .fold(0.0_f64, f64::max);
    if radius <= 0.0 {
        return vec![mean; n];
    }
    let (t1, t2) = normal.normalize_or_zero().any_orthonormal_pair();
    let coords: Vec<(f64, f64)> = points
        .iter()
        .map(|p| {
            (
                (*p - centre).dot(t1) / radius,
                (*p - centre).dot(t2) / radius,
            )
        })
        .collect();
    // Normal equations of (a, b, c); the coordinates are centred and scaled to O(1).
    let mut m = glam::DMat3::ZERO;
    let mut r = DVec3::ZERO;
    for (&(s, t), &g) in coords.iter().zip(gaps) {
        let x = DVec3::new(1.0, s, t);
        m += glam::DMat3::from_cols(x * x.x, x * x.y, x * x.z);
        r += x * g;
    }
    if m.determinant().abs() > PATCH_FIT_DEGENERATE * (n * n * n) as f64 {
        let c = m.inverse() * r;
        return coords
            .iter()
            .map(|&(s, t)| c.x + c.y * s + c.z * t)
            .collect();
    }
    // Collinear: a line along the direction of the largest spread.
    let (ss, st, tt) = coords.iter().fold((0.0, 0.0, 0.0), |(a, b, c), &(s, t)| {
        (a + s * s, b + s * t, c + t * t)
    });
    let angle = 0.5 * (2.0 * st).atan2(ss - tt);
    let (dir_s, dir_t) = (angle.cos(), angle.sin());
    let u: Vec<f64> = coords.iter().map(|&(s, t)| s * dir_s + t * dir_t).collect();
    let uu: f64 = u.iter().map(|x| x * x).sum();
    if uu <= PATCH_FIT_DEGENERATE * n as f64 {
        return vec![mean; n];
    }
    let slope = u.iter().zip(gaps).map(|(x, g)| x * (g - mean)).sum::<f64>() / uu;
    u.iter().map(|x| mean + slope * x).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rest gap, upper edge of the rest band (m), rate and step of the stabilisation the tests
    /// ask speeds of (the defaults at ε_c = 1e-4 m).
    const REST: f64 = 1e-5;
    const PULL: f64 = 5e-5;
    const BETA: f64 = 0.01;
    const STEP: f64 = 1e-3;

    /// The stabilisation's speed of a gap, as `World::stabilisation_speed` defines it: a push
    /// below the rest gap (the whole overlap within the step), nothing inside the band, a
    /// pull above it.
    fn speed(gap: f64) -> f64 {
        let error = if gap < REST {
            REST - gap
        } else {
            (PULL - gap).min(0.0)
        };
        (BETA * error + (1.0 - BETA) * (-gap).max(0.0)) / STEP
    }

    fn contact(x: f64, y: f64) -> Contact {
        Contact {
            body1: 0,
            body2: None,
            point: DVec3::new(x, y, 0.0),
            normal: DVec3::Z,
            friction: 0.5,
            target_normal_velocity: 0.0,
            velocity_bias: DVec3::ZERO,
            lever_arms: None,
            impulse: DVec3::ZERO,
        }
    }

    /// A square patch's corners, in the order (−,−), (+,−), (+,+), (−,+).
    fn square(half: f64) -> Vec<Contact> {
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .iter()
            .map(|&(x, y)| contact(half * x, half * y))
            .collect()
    }

    #[test]
    fn a_tilted_face_straddling_the_rest_band_is_asked_for_a_rigid_motion_meeting_every_corner() {
        // A face tilted about both axes: one corner overlaps, one lies below the rest gap,
        // two inside the band.
        let contacts = square(0.1);
        let gaps = [-2e-6, 0.6e-5, 2.2e-5, 1.4e-5];
        let own: Vec<f64> = gaps.iter().map(|&g| speed(g)).collect();
        // Two bodies' relative motion gives a square's corners normal speeds whose diagonal
        // sums agree (a plane over the square); the gaps' own speeds do not.
        let skew = |v: &[f64]| (v[0] + v[2]) - (v[1] + v[3]);
        assert!(skew(&own).abs() > 1e-3, "the case must straddle a kink");
        let targets = patch_targets(&contacts, std::slice::from_ref(&(0..4)), &gaps, speed);
        let scale = own.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(
            skew(&targets).abs() <= 1e-12 * scale,
            "targets {targets:?} are no rigid motion"
        );
        for (k, (t, o)) in targets.iter().zip(&own).enumerate() {
            assert!(
                *t >= o - 1e-15 * scale,
                "corner {k} asked {t}, less than its own {o}"
            );
        }
        // Raised no further than the corner that needs it most.
        let slack = targets
            .iter()
            .zip(&own)
            .map(|(t, o)| t - o)
            .fold(f64::INFINITY, f64::min);
        assert!(slack.abs() <= 1e-15 * scale, "raised {slack} too far");
    }

    #[test]
    fn speeds_a_rigid_motion_meets_are_asked_as_they_are() {
        // Every gap inside the rest band: nothing is asked of any corner.
        let contacts = square(0.1);
        let inside = [1.2e-5, 3e-5, 4.9e-5, 2e-5];
        assert_eq!(
            patch_targets(&contacts, std::slice::from_ref(&(0..4)), &inside, speed),
            vec![0.0; 4]
        );
        // Two points (an edge) and one point (a ball): a line and a mean fit them exactly.
        let edge = [contact(-0.1, 0.0), contact(0.1, 0.0), contact(0.0, 0.0)];
        let gaps = [-1e-6, 3e-5, 2e-6];
        let targets = patch_targets(&edge, &[0..2, 2..3], &gaps, speed);
        for (t, g) in targets.iter().zip(gaps) {
            assert!((t - speed(g)).abs() <= 1e-15, "{t} against {}", speed(g));
        }
    }
}
