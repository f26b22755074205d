//! Time-of-impact bounds that need no closest-features query: a far pair's from its bounding
//! spheres, a near pair's from its last query and how far its bodies have moved since.
//! Both are the thesis's eq. 2.1 bound for a separation known without a query; a pair that
//! may be in contact (within ε_c) is always queried.
//!
//! Must not know: contact handling, islands or the heap (a bound in, the caller keys it).

use glam::{DQuat, DVec3};
use impulse_collide::schedule::Mover;

use super::World;
use crate::body::{Body, BodyKind};

/// A pair whose bounding spheres (about the centres of mass, radius r_max) are farther apart
/// than this fraction of the sum of their radii is bounded by its spheres alone
/// ([`World::far_bound`]), without a closest-features query: for bodies that far apart the
/// spheres' gap is within a small factor of the real one. Default `0.25`: a pile's cube
/// (r_max = 0.43 m for a 0.5 m edge) is queried against its neighbours up to 1.08 m apart,
/// and bounded by spheres beyond.
pub const FAR_PAIR_REL: f64 = 0.25;

/// A pair re-keyed after its bodies moved (an island step, an impulse on a neighbour) is
/// bounded from its last query's distance, less how far each body's points can have moved
/// since, while that lower bound keeps at least this fraction of the queried distance
/// ([`World::cached_bound`]); beyond, it is queried again. The bound's key is earlier than a
/// fresh query's by about the distance lost, so a fraction near 1 queries as often as before
/// and one near 0 lets keys come early. Default `0.5`.
pub const CACHED_GAP_FRACTION: f64 = 0.5;

/// Relative margin by which a piece pair's target gap must exceed what both bodies'
/// direction-free coefficients can close before the pair's bound for that piece pair's own
/// bound to be skipped ([`World::compound_cached_tau`]): far above the rounding of the
/// comparison, far below anything a bound is judged by. Default `1e-9`.
pub const FREE_SKIP_MARGIN: f64 = 1e-9;

/// Direction-free TOI coefficients `(A, B)` of a motion with reach `r_max`: along any unit
/// direction its own coefficients (the ones a piece pair's bound uses, with a piece's reach
/// up to `r_max`) are no larger. A fixed body's and a rigid body's are the schedule's
/// ([`impulse_collide::schedule::free_coefficients`]), a link's its prediction's
/// ([`impulse_collide::motion::LinkMotion::free_coefficients`]); any other motion: unbounded
/// (`(∞, ∞)`, nothing skipped).
fn free_along_any(motion: &impulse_collide::Motion, r_max: f64) -> (f64, f64) {
    match motion {
        impulse_collide::Motion::Link(link) => link.free_coefficients(r_max),
        other => impulse_collide::schedule::free_coefficients(other, r_max)
            .unwrap_or((f64::INFINITY, f64::INFINITY)),
    }
}

/// A pair's last query, for [`World::cached_bound`]: when it was made, where both bodies were
/// (centre and orientation of each pose), the closest piece pair's distance, its normal and
/// its slot.
#[derive(Clone, Copy, Debug)]
pub(super) struct LastQuery {
    time: f64,
    poses: [(DVec3, DQuat); 2],
    distance: f64,
    normal: DVec3,
    slot: usize,
}

/// What a pair's last query found of one piece pair of a compound pair
/// ([`World::cached_bound`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) enum SlotGap {
    /// Not examined: pruned because it could neither be the closest nor key the pair
    /// ([`impulse_collide::schedule::Schedule::can_skip`]).
    #[default]
    Skipped,
    /// Apart by this distance, with this normal (from the second piece toward the first)
    /// from the closest points.
    Apart(f64, DVec3),
    /// Examined, but with no normal from closest points (touching, overlapping or degenerate).
    Unknown,
}

impl LastQuery {
    /// A pair's query at `time`: the two bodies' poses then, the closest piece pair's
    /// distance, normal and slot.
    pub(super) fn new(
        time: f64,
        bodies: [&Body; 2],
        distance: f64,
        normal: DVec3,
        slot: usize,
    ) -> Self {
        let pose = |x: &Body| (x.pose.translation, x.pose.rotation);
        Self {
            time,
            poses: [pose(bodies[0]), pose(bodies[1])],
            distance,
            normal,
            slot,
        }
    }

    /// How far the two bodies' points can have moved toward each other since, summed: each
    /// body's points have moved by at most |Δc| + 2·sin(θ/2)·r_max (θ its turn since, r_max
    /// its reach about the origin of its pose). A slab of width w that separated any two
    /// parts of the bodies along a fixed direction still separates them by w less this, since
    /// a body's extent along a fixed direction moves no more than its points.
    fn moved(&self, now: [&Body; 2]) -> f64 {
        let moved = |x: &Body, (c, q): (DVec3, DQuat)| {
            // |vector part| of the turn since = sin(θ/2), whichever sign the quaternion has.
            let turn = (x.pose.rotation * q.inverse()).xyz().length();
            (x.pose.translation - c).length() + 2.0 * turn * x.r_max
        };
        moved(now[0], self.poses[0]) + moved(now[1], self.poses[1])
    }

    /// The width of the slab along the last normal that still separates the closest piece
    /// pair now (negative: none is known): the distance less [`LastQuery::moved`].
    fn slab(&self, now: [&Body; 2]) -> f64 {
        self.distance - self.moved(now)
    }
}

impl World {
    /// The key of a near pair, neither body scripted, from its last query without a new
    /// one: along the last normal n the bodies are still separated by a slab of width at
    /// least the queried distance less both bodies' moves since ([`LastQuery::slab`]);
    /// eq. 2.1's bound along n from that slab, with the bodies' motions now, is a
    /// time-of-impact lower bound as a fresh query's is (only earlier). `None` — query —
    /// when there is no last query, when the slab has shrunk below [`CACHED_GAP_FRACTION`]
    /// of the queried distance or below ε_c (the pair may be in contact, which only a query
    /// can tell). Records the pair as keyed near. A link's side records the prediction the
    /// key rests on (its slack along the closest piece pair's last normal, thesis §5.2.2),
    /// as a queried bound's does: its multibody's trial steps are checked against it. (The
    /// triple pendulum re-keys its links' pairs at every island step: 1.27 M closest-feature
    /// checks in 6 s, most of them of pairs a few centimetres apart.)
    ///
    /// A pair of bodies of several pieces with a link is bounded piece pair by piece pair,
    /// as its query does ([`World::compound_cached_tau`]); the slack noted is the closest
    /// piece pair's, as a query notes it (`no_collision_of_a_link_is_missed` runs links past
    /// a body of two pieces; without that note its steps go unchecked).
    pub(super) fn cached_bound(&mut self, (a, b): (u32, u32)) -> Option<f64> {
        let last = self.pairs.get(&(a, b))?.last?;
        let (ba, bb) = (self.b(a), self.b(b));
        let plain =
            |x: &Body| matches!(x.kind, BodyKind::Dynamic | BodyKind::Fixed | BodyKind::Link);
        let single = ba.shape.pieces().len() * bb.shape.pieces().len() == 1;
        if !(plain(ba) && plain(bb)) || last.time > self.time {
            return None;
        }
        // A compound pair with a link: the triple pendulum's links against the 49-piece dish,
        // 1.20 M closest-feature checks in 6 s, 40 k with this (0.72× its wall time). Two
        // rigid bodies' compound pairs keep their queries: bounded so, the feeder chute's caps
        // meet in other places and two of them jam in its funnel (14 of 40 perturbed copies
        // jammed against 9; the chute's check is a lottery, see docs/sustained-contact.md,
        // "Open"), for 0.87× its wall time.
        if !(single || ba.is_link() || bb.is_link()) {
            return None;
        }
        let slab = last.slab([ba, bb]);
        if !(slab >= CACHED_GAP_FRACTION * last.distance && slab >= self.collision_epsilon()) {
            return None;
        }
        #[cfg(test)]
        let toi_scale = self.faults.toi_scale;
        #[cfg(not(test))]
        let toi_scale = 1.0;
        let (ma, mb) = (ba.motion(self.gravity), bb.motion(self.gravity));
        let nb = bb.shape.pieces().len();
        let pieces = (last.slot / nb, last.slot % nb);
        let tau = if single {
            self.schedule.piece_toi(
                slab,
                0.0,
                last.normal,
                false,
                Mover {
                    motion: &ma,
                    reach: ba.reach[0],
                },
                Mover {
                    motion: &mb,
                    reach: bb.reach[0],
                },
            )
        } else {
            self.compound_cached_tau((a, b), slab - last.distance, (&ma, &mb))?
        };
        self.counters.cached_bounds += 1;
        self.far_keyed.remove(&(a, b));
        self.note_slack((a, b), Some(last.normal), pieces, (ma, mb), slab);
        Some(self.time + toi_scale * tau)
    }

    /// The time-of-impact bound (s from now) of a pair of bodies of several pieces from its
    /// last query ([`SlotGap`]), whose bodies' points have come at most `-shift` nearer
    /// since ([`LastQuery::moved`]; `shift` ≤ 0): each piece pair found apart by d along n is
    /// separated by a slab of d + shift along n, and bounded along n from it as the query
    /// bounded it from d, with the same pieces' reaches. `None` — query — when the query
    /// examined a piece pair without a normal, or pruned one (the query prunes none of a
    /// pair with a link: [`impulse_collide::schedule::free_coefficients`] has none for it).
    fn compound_cached_tau(
        &self,
        (a, b): (u32, u32),
        shift: f64,
        (ma, mb): (&impulse_collide::Motion, &impulse_collide::Motion),
    ) -> Option<f64> {
        let state = self.pairs.get(&(a, b))?;
        let last = state.last?;
        let (ba, bb) = (self.b(a), self.b(b));
        let nb = bb.shape.pieces().len();
        let tau_of = |slot: usize| {
            let SlotGap::Apart(d, n) = state.gaps[slot] else {
                return None;
            };
            Some(self.schedule.piece_toi(
                d + shift,
                0.0,
                n,
                false,
                Mover {
                    motion: ma,
                    reach: ba.reach[slot / nb],
                },
                Mover {
                    motion: mb,
                    reach: bb.reach[slot % nb],
                },
            ))
        };
        // The closest piece pair first: its bound is usually the pair's.
        let mut tau = tau_of(last.slot)?;
        // Both bodies' direction-free coefficients: a piece pair whose target gap they
        // cannot close before `tau` cannot bound the pair earlier along its own normal
        // either, whose coefficients are no larger ([`free_along_any`]); its bound is skipped.
        let (fa, fb) = (
            free_along_any(ma, ba.max_reach()),
            free_along_any(mb, bb.max_reach()),
        );
        let (qa, qb) = (fa.0 + fb.0, fa.1 + fb.1);
        #[cfg(test)]
        let skip_off = self.faults.no_free_skip;
        #[cfg(not(test))]
        let skip_off = false;
        let free = qa >= 0.0 && qb >= 0.0 && !skip_off;
        for (slot, gap) in state.gaps.iter().enumerate() {
            let SlotGap::Apart(d, _) = *gap else {
                return None;
            };
            if slot == last.slot {
                continue;
            }
            if free {
                let target = self.schedule.target_gap(d + shift);
                if target >= (qa * tau * tau + qb * tau) * (1.0 + FREE_SKIP_MARGIN) {
                    #[cfg(test)]
                    self.faults
                        .free_skips
                        .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    continue;
                }
            }
            tau = tau.min(tau_of(slot)?);
        }
        Some(tau)
    }

    /// The key of a far pair ([`FAR_PAIR_REL`]) from its bounding spheres and its bodies' far
    /// envelopes (`envelope.rs`: bounds on their centres' speed and acceleration, made here
    /// for a body that has none); `None` for a near pair or one with a link or a scripted
    /// body (whose motion is not bounded so). The bodies are at least |c_b − c_a| − r_a − r_b
    /// apart (rotation about a centre keeps a body inside its sphere), and that gap closes no
    /// faster than the two centres can travel, s·τ + ½·a·τ² each: the thesis's bound (eq.
    /// 2.1) for the spheres, direction-free, so it holds through every change of the bodies'
    /// motion that stays inside their envelopes. Records the pair as far-keyed.
    pub(super) fn far_bound(&mut self, (a, b): (u32, u32)) -> Option<f64> {
        let (ba, bb) = (self.b(a), self.b(b));
        let bounded = |x: &Body| matches!(x.kind, BodyKind::Dynamic | BodyKind::Fixed);
        if !(bounded(ba) && bounded(bb)) {
            return None;
        }
        let between = bb.pose.translation - ba.pose.translation;
        let centres = between.length();
        let reach = ba.r_max + bb.r_max;
        let gap = centres - reach;
        if !(gap > FAR_PAIR_REL * reach && gap > self.collision_epsilon()) {
            return None;
        }
        let (t, g) = (self.time, self.gravity);
        // Each side's travel bound: nothing for a body that does not move.
        let mut speed = 0.0;
        let mut accel = 0.0;
        for i in [a, b] {
            let x = self.b(i);
            if !x.is_dynamic() || x.asleep {
                continue;
            }
            let far = match x.far {
                Some(far) => match far.tightened(x, t, g) {
                    // Tighter, inside: the keys made with the old one still hold.
                    Some(tight) => {
                        self.b_mut(i).far = Some(tight);
                        tight
                    }
                    None => far,
                },
                None => {
                    let far = super::envelope::FarEnvelope::about(x, t, g);
                    self.b_mut(i).far = Some(far);
                    far
                }
            };
            speed += far.speed_at(t);
            accel += far.accel;
        }
        #[cfg(test)]
        let toi_scale = self.faults.toi_scale;
        #[cfg(not(test))]
        let toi_scale = 1.0;
        let target = self.schedule.target_gap(gap);
        let tau = impulse_collide::root::closing_time(target, 0.5 * accel, speed);
        self.far_keyed.insert((a, b));
        Some(t + toi_scale * tau)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use impulse_collide::{Shape, shape};
    use impulse_geom::Pose;
    use rand::{RngExt, SeedableRng};

    fn body(half: DVec3, pose: Pose) -> Body {
        Body::new(
            "box".into(),
            Shape::polyhedron(impulse_geom::primitives::cuboid(half).unwrap()),
            BodyKind::Dynamic,
            pose,
            DVec3::ZERO,
            DVec3::ZERO,
            Some(crate::body::Mass {
                mass: 1.0,
                moments: DVec3::ONE,
            }),
            0,
            None,
        )
    }

    /// The exact distance of two single-piece bodies (V-Clip from cold features), the
    /// independent reference, and the normal from b toward a where they are apart.
    fn distance(a: &Body, b: &Body) -> (f64, Option<DVec3>) {
        let (pa, pb) = (&a.shape.pieces()[0], &b.shape.pieces()[0]);
        let c = shape::convex_closest(
            &pa.convex,
            &(a.pose * pa.pose),
            &pb.convex,
            &(b.pose * pb.pose),
            Default::default(),
        );
        if c.penetrating {
            (0.0, None)
        } else {
            (c.distance, c.direction().map(|d| -d))
        }
    }

    /// The slab a cached bound starts from never exceeds the true distance: 2 000 random
    /// pairs of boxes (elongated, so that a turn moves their corners far), queried, then each
    /// moved by a random translation and a turn of up to 0.3 rad about a random axis: the
    /// slab is at most the exact distance after the move. Without the turn's term
    /// (2·sin(θ/2)·r_max) it exceeds the distance in some of them (0.57 against 0.53).
    #[test]
    fn the_slab_of_a_moved_pair_is_below_its_distance() {
        type Rng = rand::rngs::Xoshiro256PlusPlus;
        let mut rng = Rng::seed_from_u64(17);
        let v = |r: &mut Rng, s: f64| {
            DVec3::new(
                r.random_range(-s..s),
                r.random_range(-s..s),
                r.random_range(-s..s),
            )
        };
        let place = |r: &mut Rng, at: DVec3| {
            let turn = v(r, 3.0);
            Pose::new(DQuat::from_scaled_axis(turn), at)
        };
        let mut used = 0;
        for _ in 0..2000 {
            let half = DVec3::new(0.5, 0.1, 0.05);
            let mut a = body(half, place(&mut rng, DVec3::ZERO));
            let offset = DVec3::new(0.0, 0.0, 1.2) + v(&mut rng, 0.3);
            let mut b = body(half, place(&mut rng, offset));
            let (d0, Some(normal)) = distance(&a, &b) else {
                continue;
            };
            let last = LastQuery::new(0.0, [&a, &b], d0, normal, 0);
            for x in [&mut a, &mut b] {
                let axis = v(&mut rng, 1.0).normalize_or(DVec3::Z);
                let turn = DQuat::from_scaled_axis(axis * rng.random_range(0.0..0.3));
                x.pose = Pose::new(
                    turn * x.pose.rotation,
                    x.pose.translation + v(&mut rng, 0.1),
                );
            }
            let slab = last.slab([&a, &b]);
            let now = distance(&a, &b).0;
            assert!(slab <= now + 1e-12, "slab {slab} above the distance {now}");
            used += usize::from(slab > 0.0);
        }
        assert!(used > 200, "only {used} cases kept a positive slab");
    }
}
