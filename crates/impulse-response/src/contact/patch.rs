//! A stack-wide jump for islands Gauss–Seidel crosses slowly: every patch of three or more
//! contacts between two bodies solved as one wrench, all at once.
//!
//! A tall stack is Gauss–Seidel's worst case: a load travels one contact per sweep, and a
//! stack of ten boxes, each resting on four corners, took 900 to 11 000 sweeps from its warm
//! start (40 contacts; measured on solves replayed from a pile of 1000 boxes). The direct
//! solve on the active set (`direct.rs`) should reach it in one stroke, but on those stacks
//! it diverged: four sticking corners carry twelve unknowns for six relative degrees of
//! freedom, and the near-null directions of the corners' redundant rows amplify whatever
//! the right-hand side has in them (measured: the first round's impulses 4 700 times the
//! largest the iterate had).
//!
//! Here the unknowns are what the bodies can feel. A patch (the contacts between the same two
//! bodies along the same normal that the iterate has sticking, three or more, not on one
//! line) gets one wrench (f, τ) about its centre c: six unknowns for six relative degrees of
//! freedom, no redundancy; smaller patches (an edge, a point) keep one impulse per contact.
//! Contacts that slide or lift keep the impulses the sweeps gave them. An island needs
//! [`MIN_PATCHES`] patches. The relative motion each patch is asked for is the
//! rigid twist nearest, by least squares, to what its contacts are asked for (u = target
//! along the normal, no slip, less each contact's velocity bias) — every contact sticking.
//! The linear system W_P·Δλ = b (W_P the Delassus matrix of the wrenches, dense, small) is
//! solved once; each patch's new total wrench is spread over its contacts by the least-norm
//! distribution (p_k = f/n + y × r_k, A·y = τ, A = Σ(|r|²·1 − r·rᵀ), r_k = x_k − c), which
//! carries no internal stress. The result is a warm start, not a solution: it ignores the
//! cones and p_n ≥ 0, and the caller's sweeps enforce the laws from it.
//!
//! **Must not know** where the contacts came from; it groups them by their two bodies.

use glam::{DMat3, DVec3};

use super::{Contact, IslandBody, Row, apply};
use crate::body::Body;

/// Largest number of unknowns of the patch system (6 per patch, 3 per lone contact): it is
/// factorised dense (O(m³)). Default `120`: a stack of 20 boxes on four corners each.
pub const PATCH_MAX_UNKNOWNS: usize = 120;

/// Fewest patches an island needs for the jump. Default `2`: the jump is for loads that
/// cross several patches (a stack), which sweeps carry one patch per sweep; a body resting on
/// one patch converges by sweeps and the active-set solve (the feeder chute's caps on the
/// tray took three jumps on one patch, each converged, and those few changes of rounding
/// sent the chaotic chute elsewhere).
pub const MIN_PATCHES: usize = 2;

/// A patch's contacts are taken as one wrench when the smallest eigenvalue of A =
/// Σ(|r|²·1 − r·rᵀ) exceeds this fraction of its trace (the points span a plane, not a
/// line). Default `1e-6`.
pub const PATCH_SPREAD_REL: f64 = 1e-6;

/// One group of unknowns.
enum Group {
    /// Contacts `members` between the same two bodies, one wrench about `centre`, their
    /// points' offsets `arms` from it (r_k), and `inverse_spread` A⁻¹.
    Patch {
        members: Vec<usize>,
        centre: DVec3,
        arms: Vec<DVec3>,
        inverse_spread: DMat3,
    },
    /// One contact's impulse (its frame).
    Lone(usize),
}

/// Body indices of a contact: (body 1, body 2 if any), and whether each moves.
fn ends(bodies: &[IslandBody], c: &Contact) -> [(Option<usize>, f64); 2] {
    let moving = |i: usize| !matches!(bodies[i].body, Body::Fixed);
    [
        (Some(c.body1).filter(|&i| moving(i)), 1.0),
        (c.body2.filter(|&i| moving(i)), -1.0),
    ]
}

/// Where contact k's impulse acts on body 1 (world point), from its row's lever arm.
fn point_of(bodies: &[IslandBody], c: &Contact, row: &Row) -> DVec3 {
    bodies[c.body1].com + row.r1
}

/// What makes contacts one patch: the same body 1, body 2 and normal (to the bit: a
/// manifold's points share their normal).
type PatchKey = (usize, Option<usize>, [u64; 3]);

/// Groups the contacts that stick: patches of three or more non-collinear contacts between
/// the same two bodies along the same normal, and lone contacts.
fn groups(bodies: &[IslandBody], contacts: &[Contact], rows: &[Row]) -> Vec<Group> {
    let mut by_pair: Vec<(PatchKey, Vec<usize>)> = Vec::new();
    for (k, c) in contacts.iter().enumerate().filter(|(_, c)| sticks(c)) {
        let key = (c.body1, c.body2, c.normal.to_array().map(f64::to_bits));
        match by_pair.iter_mut().find(|(p, _)| *p == key) {
            Some((_, v)) => v.push(k),
            None => by_pair.push((key, vec![k])),
        }
    }
    let mut out = Vec::new();
    for (_, members) in by_pair {
        if members.len() >= 3 {
            let points: Vec<DVec3> = members
                .iter()
                .map(|&k| point_of(bodies, &contacts[k], &rows[k]))
                .collect();
            let centre = points.iter().copied().sum::<DVec3>() / points.len() as f64;
            let arms: Vec<DVec3> = points.iter().map(|&x| x - centre).collect();
            let spread = arms.iter().fold(DMat3::ZERO, |a, &r| {
                a + DMat3::from_diagonal(DVec3::splat(r.length_squared()))
                    - DMat3::from_cols(r * r.x, r * r.y, r * r.z)
            });
            let trace = spread.x_axis.x + spread.y_axis.y + spread.z_axis.z;
            if smallest_eigenvalue(spread) > PATCH_SPREAD_REL * trace && trace > 0.0 {
                out.push(Group::Patch {
                    members,
                    centre,
                    arms,
                    inverse_spread: spread.inverse(),
                });
                continue;
            }
        }
        out.extend(members.into_iter().map(Group::Lone));
    }
    out
}

/// Whether the iterate has a contact pressing and sticking strictly inside its cone: only
/// those are unknowns of the jump (a sliding contact's or a lifting one's impulse stays as
/// the sweeps left it; asked to stick, a sliding cap of the feeder chute was held back and
/// the scene did not come to rest).
fn sticks(c: &Contact) -> bool {
    c.impulse.z > 0.0
        && c.impulse.truncate().length() < c.friction * c.impulse.z * (1.0 - STICK_MARGIN)
}

/// A contact counts as sticking when its friction is below this fraction short of its
/// cone's radius. Default `1e-9`.
pub const STICK_MARGIN: f64 = 1e-9;

/// Smallest eigenvalue of a symmetric positive semi-definite 3 × 3 matrix (closed form).
fn smallest_eigenvalue(m: DMat3) -> f64 {
    let (a, b, c) = (m.x_axis.x, m.y_axis.y, m.z_axis.z);
    let (d, e, f) = (m.y_axis.x, m.z_axis.y, m.z_axis.x);
    let p1 = d * d + e * e + f * f;
    let q = (a + b + c) / 3.0;
    let p2 = (a - q).powi(2) + (b - q).powi(2) + (c - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    if p == 0.0 {
        return q;
    }
    let bm = (m - DMat3::from_diagonal(DVec3::splat(q))) * (1.0 / p);
    let r = (bm.determinant() / 2.0).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos()
}

/// A unit of one unknown as impulses on its bodies: for each moving end, (body, linear,
/// angular impulse).
type Push = Vec<(usize, DVec3, DVec3)>;

/// The pushes of a group's unknowns (6 for a patch: force x, y, z, then torque x, y, z
/// about the centre; 3 for a lone contact: its frame's axes at its lever arms).
fn pushes(bodies: &[IslandBody], contacts: &[Contact], rows: &[Row], g: &Group) -> Vec<Push> {
    match g {
        Group::Patch {
            members, centre, ..
        } => {
            let c = &contacts[members[0]];
            (0..6)
                .map(|q| {
                    let unit = DVec3::AXES[q % 3];
                    ends(bodies, c)
                        .into_iter()
                        .filter_map(|(b, sign)| b.map(|b| (b, sign)))
                        .map(|(b, sign)| {
                            if q < 3 {
                                let arm = *centre - bodies[b].com;
                                (b, unit * sign, arm.cross(unit) * sign)
                            } else {
                                (b, DVec3::ZERO, unit * sign)
                            }
                        })
                        .collect()
                })
                .collect()
        }
        Group::Lone(k) => {
            let (c, row) = (&contacts[*k], &rows[*k]);
            let axes = row.frame.axes();
            (0..3)
                .map(|q| {
                    let unit = axes.col(q);
                    ends(bodies, c)
                        .into_iter()
                        .filter_map(|(b, sign)| b.map(|b| (b, sign)))
                        .map(|(b, sign)| {
                            let arm = if b == c.body1 { row.r1 } else { row.r2 };
                            (b, unit * sign, arm.cross(unit) * sign)
                        })
                        .collect()
                })
                .collect()
        }
    }
}

/// The velocity each unknown of a group measures (the dual of its push), for body velocity
/// changes `dv`, `dw` (indexed by body).
fn measure(
    bodies: &[IslandBody],
    contacts: &[Contact],
    rows: &[Row],
    g: &Group,
    v: &dyn Fn(usize) -> (DVec3, DVec3),
) -> Vec<f64> {
    let side = |b: Option<usize>| b.map_or((DVec3::ZERO, DVec3::ZERO), v);
    match g {
        Group::Patch {
            members, centre, ..
        } => {
            let c = &contacts[members[0]];
            let [(b1, _), (b2, _)] = ends(bodies, c);
            let at = |b: Option<usize>| {
                let (lin, ang) = side(b);
                let arm = b.map_or(DVec3::ZERO, |b| *centre - bodies[b].com);
                (lin + ang.cross(arm), ang)
            };
            let ((l1, a1), (l2, a2)) = (at(b1), at(b2));
            let (lin, ang) = (l1 - l2, a1 - a2);
            vec![lin.x, lin.y, lin.z, ang.x, ang.y, ang.z]
        }
        Group::Lone(k) => {
            let (c, row) = (&contacts[*k], &rows[*k]);
            let [(b1, _), (b2, _)] = ends(bodies, c);
            let (l1, a1) = side(b1);
            let (l2, a2) = side(b2);
            let u = (l1 + a1.cross(row.r1)) - (l2 + a2.cross(row.r2));
            row.frame.to_contact(u).to_array().to_vec()
        }
    }
}

/// The jump (module documentation): moves every contact's impulse to the all-sticking
/// patch-wrench solution and the bodies' velocities with it. Returns false (changing
/// nothing) when the island has fewer patches than `min_patches`, too many unknowns, or a
/// system that cannot be solved or whose solution dwarfs the iterate.
/// `min_patches`: the fewest patches the island must have ([`MIN_PATCHES`] in a solve).
pub(super) fn jump(
    bodies: &mut [IslandBody],
    contacts: &mut [Contact],
    rows: &[Row],
    min_patches: usize,
) -> bool {
    let groups = groups(bodies, contacts, rows);
    let patches = groups
        .iter()
        .filter(|g| matches!(g, Group::Patch { .. }))
        .count();
    if patches < min_patches.max(1) {
        return false;
    }
    let sizes: Vec<usize> = groups
        .iter()
        .map(|g| match g {
            Group::Patch { .. } => 6,
            Group::Lone(_) => 3,
        })
        .collect();
    let m: usize = sizes.iter().sum();
    if m > PATCH_MAX_UNKNOWNS {
        return false;
    }
    let offsets: Vec<usize> = sizes
        .iter()
        .scan(0, |s, &n| {
            let o = *s;
            *s += n;
            Some(o)
        })
        .collect();
    // Columns of W_P: each unknown's unit push, measured by every group sharing a body.
    let mut w = faer::Mat::<f64>::zeros(m, m);
    let inverse = |b: usize, lin: DVec3, ang: DVec3| {
        let body = &bodies[b].body;
        (lin * body.inverse_mass(), body.inverse_inertia() * ang)
    };
    let all_pushes: Vec<Vec<Push>> = groups
        .iter()
        .map(|g| pushes(bodies, contacts, rows, g))
        .collect();
    for (gj, pj) in all_pushes.iter().enumerate() {
        for (q, push) in pj.iter().enumerate() {
            let col = offsets[gj] + q;
            let dv = |b: usize| -> (DVec3, DVec3) {
                push.iter()
                    .filter(|(pb, _, _)| *pb == b)
                    .map(|&(pb, lin, ang)| inverse(pb, lin, ang))
                    .fold((DVec3::ZERO, DVec3::ZERO), |a, x| (a.0 + x.0, a.1 + x.1))
            };
            for (gi, g) in groups.iter().enumerate() {
                let touches = all_pushes[gi][0]
                    .iter()
                    .any(|(b, _, _)| push.iter().any(|(pb, _, _)| pb == b));
                if !touches {
                    continue;
                }
                for (r, value) in measure(bodies, contacts, rows, g, &dv)
                    .into_iter()
                    .enumerate()
                {
                    w[(offsets[gi] + r, col)] = value;
                }
            }
        }
    }
    // Right-hand side: what each group is asked for, less what it does now.
    let now = |b: usize| (bodies[b].velocity, bodies[b].omega);
    let mut rhs = faer::Mat::<f64>::zeros(m, 1);
    for (gi, g) in groups.iter().enumerate() {
        let current = measure(bodies, contacts, rows, g, &now);
        let wanted: Vec<f64> = match g {
            Group::Lone(k) => {
                let (c, row) = (&contacts[*k], &rows[*k]);
                (DVec3::new(0.0, 0.0, c.target_normal_velocity) - row.bias)
                    .to_array()
                    .to_vec()
            }
            Group::Patch {
                members,
                arms,
                inverse_spread,
                ..
            } => {
                // The rigid twist nearest to the contacts' wishes (least squares about the
                // centroid: V the mean, Ω = A⁻¹·Σ r × (d − V)).
                let wish: Vec<(DVec3, DVec3)> = members
                    .iter()
                    .zip(arms)
                    .map(|(&k, &r)| {
                        let (c, row) = (&contacts[k], &rows[k]);
                        let d = row
                            .frame
                            .to_world(DVec3::new(0.0, 0.0, c.target_normal_velocity) - row.bias);
                        (r, d)
                    })
                    .collect();
                let mean = wish.iter().map(|(_, d)| *d).sum::<DVec3>() / wish.len() as f64;
                let turn =
                    *inverse_spread * wish.iter().map(|(r, d)| r.cross(*d - mean)).sum::<DVec3>();
                vec![mean.x, mean.y, mean.z, turn.x, turn.y, turn.z]
            }
        };
        for r in 0..sizes[gi] {
            rhs[(offsets[gi] + r, 0)] = wanted[r] - current[r];
        }
    }
    // Sequential, as the active-set solve's: the result must not depend on the thread count.
    let solution = super::direct::dense_solve(w, rhs);
    if !(0..m).all(|i| solution[(i, 0)].is_finite()) {
        return false;
    }
    // New impulses: a patch's total wrench plus the change, spread least-norm; a lone
    // contact's impulse plus its change. Computed first, applied only if none dwarfs the
    // largest the iterate had (a near-singular system: a loop of patches asked for motions
    // no rigid bodies meet).
    let p_max = contacts.iter().map(|c| c.impulse.z).fold(0.0_f64, f64::max);
    let mut new: Vec<(usize, DVec3)> = Vec::with_capacity(contacts.len());
    for (gi, g) in groups.iter().enumerate() {
        let x = |r: usize| solution[(offsets[gi] + r, 0)];
        match g {
            Group::Lone(k) => {
                new.push((*k, contacts[*k].impulse + DVec3::new(x(0), x(1), x(2))));
            }
            Group::Patch {
                members,
                arms,
                inverse_spread,
                ..
            } => {
                let mut force = DVec3::new(x(0), x(1), x(2));
                let mut torque = DVec3::new(x(3), x(4), x(5));
                for (&k, r) in members.iter().zip(arms) {
                    let p = rows[k].frame.to_world(contacts[k].impulse);
                    force += p;
                    torque += r.cross(p);
                }
                let y = *inverse_spread * torque;
                let n = members.len() as f64;
                for (&k, r) in members.iter().zip(arms) {
                    let p = force / n + y.cross(*r);
                    new.push((k, rows[k].frame.to_contact(p)));
                }
            }
        }
    }
    let largest = new.iter().map(|(_, p)| p.length()).fold(0.0_f64, f64::max);
    if !(largest.is_finite() && largest <= JUMP_DIVERGED * p_max.max(f64::MIN_POSITIVE)) {
        return false;
    }
    for (k, p) in new {
        let dp = p - contacts[k].impulse;
        apply(bodies, &contacts[k], &rows[k], dp);
        contacts[k].impulse = p;
    }
    true
}

/// A jump whose impulses exceed this multiple of the largest normal impulse the iterate had
/// is not taken. Default `10`.
pub const JUMP_DIVERGED: f64 = 10.0;
