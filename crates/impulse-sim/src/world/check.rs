//! Checking a pair: closest features piece by piece, the pair's next key, and resolving a
//! collision at the top of the heap (with the fallback when the response fails).

use glam::DVec3;
use impulse_collide::schedule::{Mover, free_coefficients};
use impulse_collide::{Closest, Convex, FeaturePair, Motion, depth, manifold, patch, shape};

use super::quick_bounds::{LastQuery, SlotGap};
use super::{ContactEvent, ContactFailure, MAX_FAILURES_KEPT, Material, World};
use crate::contact::{self, ContactKind};
use crate::error::SimError;

/// Closest points closer than this, relative to the sum of the two bodies' radii, give no
/// contact normal: their direction would be rounding noise (two faces exactly touching
/// report points 1e-17 apart in any direction); the separating axis
/// ([`impulse_collide::depth::separating_axis`]) gives it instead. Default `1e-9`.
pub const NORMAL_FROM_POINTS_REL: f64 = 1e-9;

/// An overlapping pair keeps its contact normal while the separating axis has turned from it
/// by at most this angle (rad): a body resting or rolling on another within the envelope
/// keeps the same normal to the bit (a normal recomputed at every check differs in rounding,
/// and a hopping ball's trajectory is sensitive to it), while a tipping body's normal
/// follows it. Default `1e-6`.
pub const OVERLAP_NORMAL_TURN: f64 = 1e-6;

/// The event loop holds a pair only with room to spare: [`World::pair_contact`] asked with
/// this margin on each of its limits (the slow regime's turn speed, an impact's speed at a
/// point, the turning acceleration, and the shortest step, which in turn caps the
/// acceleration at a quarter of its limit), so that a pair just held is not released at its
/// first island step and a rocking body does not switch at every step. Default `0.5`.
pub const HOLD_ROTATION_FRACTION: f64 = 0.5;

/// The result of checking a pair: the closest piece pair, and the distance and normal of
/// every piece pair examined (for the time-of-impact bound, eq. 2.1).
pub(super) struct Scan {
    /// Smallest distance (0 when touching or penetrating).
    distance: f64,
    /// Closest point on the first body (world).
    point_a: DVec3,
    /// Closest point on the second body (world).
    point_b: DVec3,
    /// Contact normal of the closest piece pair, from the second body toward the first.
    normal: Option<DVec3>,
    /// Every piece pair's slot and key (absolute time), in the order examined.
    keys: Vec<(usize, f64)>,
    /// The other piece pairs within ε_c (a table's legs on the floor), closest first: each
    /// may be where the bodies press when the closest one does not.
    near: Vec<NearPiece>,
    /// The closest piece pair (piece indices of the two bodies).
    pieces: (usize, usize),
    /// Its slot in the pair's per-piece-pair tables.
    slot: usize,
    /// How deep the bodies interpenetrate along the normal when touching (0 otherwise).
    depth: f64,
    /// The two bodies' motions at the check (for their time-of-impact bound).
    motions: (Motion, Motion),
}

/// A piece pair within ε_c other than the closest ([`Scan::near`]).
#[derive(Clone, Copy, Debug)]
struct NearPiece {
    pieces: (usize, usize),
    slot: usize,
    distance: f64,
    point_a: DVec3,
    point_b: DVec3,
    normal: Option<DVec3>,
    /// Its interpenetration along its normal (0 when apart).
    depth: f64,
}

impl Scan {
    /// The closest piece pair as a [`NearPiece`].
    fn closest(&self) -> NearPiece {
        NearPiece {
            pieces: self.pieces,
            slot: self.slot,
            distance: self.distance,
            point_a: self.point_a,
            point_b: self.point_b,
            normal: self.normal,
            depth: self.depth,
        }
    }

    /// The smallest key of the piece pairs other than the closest and those in `except`.
    fn others_key(&self, except: &[NearPiece]) -> f64 {
        self.keys
            .iter()
            .filter(|(s, _)| *s != self.slot && except.iter().all(|e| e.slot != *s))
            .map(|(_, k)| *k)
            .fold(f64::INFINITY, f64::min)
    }
}

impl World {
    /// Checks a pair now, piece pair by piece pair (thesis eq. 2.1): the closest piece pair
    /// decides contact, and every piece pair gets its own time-of-impact bound along its own
    /// separating direction, since a non-convex body can approach another at several places in
    /// different directions. Piece pairs that cannot matter are pruned
    /// ([`impulse_collide::schedule::Schedule::can_skip`]). A piece pair found touching or
    /// overlapping with no normal seen before (bodies placed touching) gets its normal from
    /// [`impulse_collide::depth`].
    fn query(&mut self, (a, b): (u32, u32)) -> Scan {
        debug_assert!(
            self.is_synced(a) && self.is_synced(b),
            "a pair is checked with its bodies at now"
        );
        let time = self.time;
        let schedule = self.schedule;
        #[cfg(test)]
        let toi_scale = self.faults.toi_scale;
        #[cfg(not(test))]
        let toi_scale = 1.0;
        // Direct field access: the bodies and the pair table are borrowed at once.
        let live = "internal ids name live bodies";
        let ba = self.slots[a as usize].body.as_ref().expect(live);
        let bb = self.slots[b as usize].body.as_ref().expect(live);
        let (pieces_a, pieces_b) = (ba.shape.pieces(), bb.shape.pieces());
        let (na, nb) = (pieces_a.len(), pieces_b.len());
        let (motion_a, motion_b) = (ba.motion(self.gravity), bb.motion(self.gravity));
        let free = free_coefficients(&motion_a, ba.max_reach())
            .zip(free_coefficients(&motion_b, bb.max_reach()));
        let state = self.pairs.entry((a, b)).or_default();
        if state.features.len() != na * nb {
            state.features = vec![FeaturePair::default(); na * nb];
            state.normals = vec![None; na * nb];
        }
        // What each piece pair was found at, for a compound pair that a cached bound may key
        // (one with a link: `quick_bounds.rs`).
        let compound = na * nb > 1 && (ba.is_link() || bb.is_link());
        if compound {
            state.gaps.clear();
            state.gaps.resize(na * nb, SlotGap::Skipped);
        }
        // Piece pairs by increasing bounding-sphere lower bound on their distance.
        let mut order: Vec<(f64, usize, usize)> = Vec::with_capacity(na * nb);
        for (i, pa) in pieces_a.iter().enumerate() {
            let ca = ba.pose.transform_point(pa.center);
            for (j, pb) in pieces_b.iter().enumerate() {
                let lb = ca.distance(bb.pose.transform_point(pb.center)) - pa.radius - pb.radius;
                order.push((lb, i, j));
            }
        }
        order.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
        let mut best: Option<(f64, Closest, usize)> = None;
        let mut keys: Vec<(usize, f64)> = Vec::with_capacity(order.len());
        let mut min_key = f64::INFINITY;
        let mut checks = 0u64;
        let mut depth = 0.0f64;
        let mut touching = false;
        let eps = schedule.collision_epsilon;
        let mut near: Vec<NearPiece> = Vec::new();
        for &(lb, i, j) in &order {
            if let Some((fa, fb)) = free {
                if schedule.can_skip(lb, best.as_ref().map(|x| x.0), fa, fb, min_key - time) {
                    continue;
                }
            }
            let (pa, pb) = (&pieces_a[i], &pieces_b[j]);
            let (pose_a, pose_b) = (ba.pose * pa.pose, bb.pose * pb.pose);
            let slot = i * nb + j;
            let mut piece_depth = 0.0;
            let c = shape::convex_closest(
                &pa.convex,
                &pose_a,
                &pb.convex,
                &pose_b,
                state.features[slot],
            );
            checks += 1;
            state.features[slot] = c.features;
            let mut gap = SlotGap::Unknown;
            if !c.penetrating && c.distance > NORMAL_FROM_POINTS_REL * (ba.r_max + bb.r_max) {
                if let Some(dir) = c.direction() {
                    state.normals[slot] = Some(-dir);
                    gap = SlotGap::Apart(c.distance, -dir);
                }
            } else {
                // Touching, or so close that the closest points' direction is rounding noise:
                // the normal last seen at a clear gap, or, with none (bodies placed touching),
                // the separating axis. Overlapping: the separating axis (least overlap) at
                // every check, since a body that turns makes the normal of the last clear gap
                // stale (a tipping box's face comes down across the other's edge at a growing
                // angle); a normal it has not turned from by [`OVERLAP_NORMAL_TURN`] is kept.
                // The depth along it.
                let n = match state.normals[slot] {
                    Some(n) if !c.penetrating => n,
                    old => {
                        let p = depth::separating_axis(&pa.convex, &pose_a, &pb.convex, &pose_b);
                        let n = match old {
                            Some(o) if o.angle_between(p.normal) <= OVERLAP_NORMAL_TURN => o,
                            _ => p.normal,
                        };
                        if n.is_finite() {
                            state.normals[slot] = Some(n);
                        }
                        n
                    }
                };
                if c.penetrating {
                    touching = true;
                    let along = depth::overlap_along(&pa.convex, &pose_a, &pb.convex, &pose_b, n);
                    if along.is_finite() {
                        depth = depth.max(along);
                        piece_depth = along;
                    }
                }
            }
            if compound {
                state.gaps[slot] = gap;
            }
            let d = if c.penetrating { 0.0 } else { c.distance };
            if d < eps {
                near.push(NearPiece {
                    pieces: (i, j),
                    slot,
                    distance: d,
                    point_a: c.point_a,
                    point_b: c.point_b,
                    normal: state.normals[slot],
                    depth: piece_depth,
                });
            }
            let key = match state.normals[slot] {
                None => time,
                Some(n) => {
                    let (ma, mb) = (
                        Mover {
                            motion: &motion_a,
                            reach: ba.reach[i],
                        },
                        Mover {
                            motion: &motion_b,
                            reach: bb.reach[j],
                        },
                    );
                    time + toi_scale * schedule.piece_toi(d, 0.0, n, false, ma, mb)
                }
            };
            min_key = min_key.min(key);
            keys.push((slot, key));
            if best.as_ref().is_none_or(|bst| d < bst.0) {
                best = Some((d, c, slot));
            }
        }
        self.counters.pair_checks += checks.max(1);
        let Some((d, c, slot)) = best else {
            unreachable!("a shape has at least one piece")
        };
        state.last =
            state.normals[slot].map(|normal| LastQuery::new(time, [ba, bb], d, normal, slot));
        near.retain(|p| p.slot != slot);
        near.sort_by(|x, y| x.distance.total_cmp(&y.distance).then(x.slot.cmp(&y.slot)));
        let normal = state.normals[slot];
        if touching {
            self.counters.touching_checks += 1;
            self.counters.max_penetration = self.counters.max_penetration.max(depth);
        }
        self.counters.min_distance = self.counters.min_distance.min(d);
        Scan {
            distance: d,
            point_a: c.point_a,
            point_b: c.point_b,
            normal,
            keys,
            near,
            pieces: (slot / nb, slot % nb),
            slot,
            depth,
            motions: (motion_a, motion_b),
        }
    }

    /// A check plus a conservative time-of-impact bound (absolute time); no response. Used
    /// for pairs that are not at the top of the heap (new pairs, re-keyed pairs).
    ///
    /// In the switching model a pair found within ε_c that would be held is due now: bodies
    /// placed touching (or a pair re-keyed while resting) are in sustained contact from this
    /// instant. Its time-of-impact bound would only bring it to the top once the gap had
    /// closed further, and bodies that fall together (a stack placed with small gaps) have
    /// no relative motion until the one below stops: they would land one after another as
    /// collisions, each making its island take a cold impulsive solve.
    pub(super) fn bound(&mut self, pair: (u32, u32)) -> Result<f64, SimError> {
        self.sync_pair(pair)?;
        if let Some(key) = self.far_bound(pair) {
            return Ok(key);
        }
        if let Some(key) = self.cached_bound(pair) {
            return Ok(key);
        }
        let scan = self.query(pair);
        if scan.distance < self.collision_epsilon() {
            if let Some(n) = scan.normal {
                let mid = self.witness_point(pair, &scan.closest(), n);
                if self.holds(pair, mid, n) {
                    self.far_keyed.remove(&pair);
                    return Ok(self.time);
                }
            }
        }
        let key = self.key_for(pair, &scan, false, &[]);
        self.note_slack(pair, scan.normal, scan.pieces, scan.motions, scan.distance);
        self.far_keyed.remove(&pair);
        Ok(key)
    }

    /// A pair's new key, as [`World::bound`] gives it but without the hold-at-once rule: a pair
    /// found within ε_c is left to its key (`None`), since checking a pair ahead of its key
    /// must not decide what its check at the key would (a pair held as soon as a pass starts
    /// instead of when its key comes is held at another speed).
    pub(super) fn rebound(&mut self, pair: (u32, u32)) -> Result<Option<f64>, SimError> {
        self.sync_pair(pair)?;
        if let Some(key) = self.far_bound(pair) {
            return Ok(Some(key));
        }
        if let Some(key) = self.cached_bound(pair) {
            return Ok(Some(key));
        }
        let scan = self.query(pair);
        if scan.distance < self.collision_epsilon() {
            return Ok(None);
        }
        let key = self.key_for(pair, &scan, false, &[]);
        self.note_slack(pair, scan.normal, scan.pieces, scan.motions, scan.distance);
        self.far_keyed.remove(&pair);
        Ok(Some(key))
    }

    /// The key of a pair: the earliest time any of its piece pairs could close the gap to the
    /// target (`impulse_collide::schedule`). Of a pair just checked at the top of the heap
    /// (`at_top`), the closest piece pair gets the gap floor, which guarantees progress, and
    /// so do the other piece pairs within ε_c the check found not pressing (`calm`: a table
    /// standing on four legs has four piece pairs at one gap, and with the floor for the
    /// closest alone the other three were due at the same instant for ever, measured);
    /// elsewhere the bound stays conservative, so a pair re-keyed while touching comes back
    /// to the top at once.
    fn key_for(&self, (a, b): (u32, u32), scan: &Scan, at_top: bool, calm: &[NearPiece]) -> f64 {
        let Some(n) = scan.normal else {
            return self.time; // touching with no known normal: check again now.
        };
        #[cfg(test)]
        let toi_scale = self.faults.toi_scale;
        #[cfg(not(test))]
        let toi_scale = 1.0;
        let (ba, bb) = (self.b(a), self.b(b));
        let tau = |p: &NearPiece, n: DVec3| {
            self.schedule.piece_toi(
                p.distance,
                p.depth,
                n,
                at_top,
                Mover {
                    motion: &scan.motions.0,
                    reach: ba.reach[p.pieces.0],
                },
                Mover {
                    motion: &scan.motions.1,
                    reach: bb.reach[p.pieces.1],
                },
            )
        };
        let mut key = self.time + toi_scale * tau(&scan.closest(), n);
        for p in calm {
            if let Some(pn) = p.normal {
                key = key.min(self.time + toi_scale * tau(p, pn));
            }
        }
        key.min(scan.others_key(calm))
    }

    /// Checks the top pair, resolves a collision, re-keys, and applies the hysteresis rule.
    pub(super) fn check_top(&mut self, pair: (u32, u32)) -> Result<(), SimError> {
        self.sync_pair(pair)?;
        // A far pair cannot touch: its next key from its spheres, without a query.
        if let Some(key) = self.far_bound(pair) {
            return self.settle(pair, key);
        }
        self.far_keyed.remove(&pair);
        let scan = self.query(pair);
        let mut hit = false;
        let mut held = false;
        // Piece pairs within ε_c found not pressing (they get the progress floor).
        let mut calm: Vec<NearPiece> = Vec::new();
        if scan.distance < self.collision_epsilon() {
            if let Some(n) = scan.normal {
                let x = self.contact_point(pair, &scan.closest(), n);
                let mid = self.witness_point(pair, &scan.closest(), n);
                // In the switching model a pair that is neither approaching nor separating
                // faster than the switching speed is held, pressing or not (a body placed
                // touching, or sliding along a surface, is in sustained contact from now).
                let hold = self.holds(pair, x.unwrap_or(mid), n);
                // Where the bodies press: the closest piece pair, or else the closest other
                // piece pair within ε_c that does (a table standing on four legs).
                let press = match x {
                    _ if hold => None,
                    Some(x) => Some((x, n, scan.distance)),
                    None => {
                        let mut found = None;
                        for p in &scan.near {
                            let Some(pn) = p.normal else { continue };
                            match self.contact_point(pair, p, pn) {
                                Some(x) => {
                                    found = Some((x, pn, p.distance));
                                    break;
                                }
                                None => calm.push(*p),
                            }
                        }
                        found
                    }
                };
                let struck = !hold && press.is_some() && self.struck_again(pair);
                if hold || press.is_some() {
                    // A sleeping island touched by something approaching wakes first.
                    let mut woken = self.wake(pair.0);
                    woken.extend(self.wake(pair.1));
                    if !woken.is_empty() {
                        self.rekey(&woken, Some(pair))?;
                    }
                }
                if hold {
                    self.hold(pair);
                    held = true;
                } else if struck {
                    self.hold_struck(pair);
                    held = true;
                } else if let Some((x, n, d)) = press {
                    // A slow contact that is not held because a body turns too fast makes
                    // that body wholly impulse-driven: a body half held would be pressed by a
                    // held load its microcollisions do not know of.
                    if self.switching() && self.is_slow(pair, x, n) {
                        let limit = HOLD_ROTATION_FRACTION * self.spin_limit();
                        for i in [pair.0, pair.1] {
                            let b = self.b(i);
                            let turning = super::hold::spin_accel(b, b) >= limit;
                            if turning && self.is_held_body(i) {
                                self.release_all_of(i)?;
                            }
                        }
                        let stale = std::mem::take(&mut self.stale);
                        self.rekey(&stale, Some(pair))?;
                    }
                    hit = self.resolve(pair, x, n, d);
                    if hit {
                        let time = self.time;
                        if let Some(state) = self.pairs.get_mut(&pair) {
                            state.last_hit = Some(time);
                        }
                    }
                }
            }
            // With no normal at all (not even from the penetration query), the pair is checked
            // again at once; the stall guard ends that if it persists.
        }
        if hit {
            self.rekey_others(pair)?;
            // A body of an island was struck (for a link, its whole multibody): its island
            // reacts now, through its constraints, before its held contacts can be driven
            // through.
            for i in [pair.0, pair.1] {
                for j in self.moved_with(i) {
                    if self.is_held_body(j) {
                        self.step_now(j);
                    }
                }
            }
        }
        let key = if held {
            f64::INFINITY
        } else {
            let scan = if hit { self.query(pair) } else { scan };
            let calm = if hit { &[][..] } else { &calm[..] };
            let key = self.key_for(pair, &scan, true, calm);
            self.note_slack(pair, scan.normal, scan.pieces, scan.motions, scan.distance);
            key
        };
        self.settle(pair, key)
    }

    /// After the top pair's check: its new key, or, when the broad phase no longer calls it
    /// close, it leaves the heap (the hysteresis of thesis §2.4.3).
    fn settle(&mut self, pair: (u32, u32), key: f64) -> Result<(), SimError> {
        let still_close = self
            .hash
            .as_ref()
            .is_some_and(|(h, _)| h.is_close(pair.0, pair.1).unwrap_or(false));
        self.heap
            .settle_after_check(pair, still_close, key)
            .map_err(|e| self.runtime(format!("collision heap: {e}")))?;
        if !still_close {
            self.pairs.remove(&pair);
            self.far_keyed.remove(&pair);
        }
        Ok(())
    }

    /// The midpoint of a piece pair's closest points, or, when a piece is an ellipsoid, its
    /// point farthest along the contact normal toward the other (the midpoint of both such
    /// points for two smooth pieces). GJK's closest points on an ellipsoid touching a face
    /// are a witness: their distance is right, but the point on the face is a combination of
    /// its far corners and rounding puts it anywhere on the face (a wheel-shaped ellipsoid
    /// standing on its rim on a floor took its microcollisions 0.49 m away from itself, at
    /// the floor's edge, and fell through the floor; measured). A smooth convex piece has
    /// exactly one point farthest along a direction.
    fn witness_point(&self, (a, b): (u32, u32), piece: &NearPiece, n: DVec3) -> DVec3 {
        let (ba, bb) = (self.b(a), self.b(b));
        let (pa, pb) = (
            &ba.shape.pieces()[piece.pieces.0],
            &bb.shape.pieces()[piece.pieces.1],
        );
        let smooth = |c: &Convex| matches!(c, Convex::Ellipsoid(_));
        let (sa, sb) = (smooth(&pa.convex), smooth(&pb.convex));
        if !(sa || sb) {
            return 0.5 * (piece.point_a + piece.point_b);
        }
        let (pose_a, pose_b) = (ba.pose * pa.pose, bb.pose * pb.pose);
        // The normal points from b toward a: a's point toward b lies along −n.
        let on_a = pa.convex.placed(&pose_a).support_point(-n);
        let on_b = pb.convex.placed(&pose_b).support_point(n);
        match (sa, sb) {
            (true, false) => on_a,
            (false, true) => on_b,
            _ => 0.5 * (on_a + on_b),
        }
    }

    /// Where the contact of a checked pair acts. For two polyhedral pieces: the centre of
    /// their near vertices that approach ([`impulse_collide::patch::near_vertices`]: every
    /// vertex within ε_c of the other or inside it), so that a body resting flat is pushed
    /// through its support rather than at a corner, a rocking one where it comes down, and a
    /// sinking corner is found even when the closest-features query returns only a witness;
    /// the closest points' midpoint joins them when it lies apart (an edge across an edge), and
    /// when the pair overlaps, so do its manifold's points (edges crossing edges, no vertex
    /// near);
    /// `None` when none of them approaches (nothing presses). Without near vertices, and for
    /// smooth pieces, the closest points' midpoint ([`World::witness_point`]) — `None` too
    /// when it does not approach: a ball touching a dish's piece and not pressing it gets the
    /// progress floor of a calm pair (without it, a ball held against its neighbours and
    /// sliding along a dish had its pair checked at keys converging to one instant until
    /// the loop stalled, V11 in checking mode).
    fn contact_point(&self, (a, b): (u32, u32), scan: &NearPiece, n: DVec3) -> Option<DVec3> {
        let mid = self.witness_point((a, b), scan, n);
        let (ba, bb) = (self.b(a), self.b(b));
        let (pa, pb) = (
            &ba.shape.pieces()[scan.pieces.0],
            &bb.shape.pieces()[scan.pieces.1],
        );
        let eps = self.collision_epsilon();
        let rest = contact::APPROACH_FLOOR_REL * (2.0 * self.gravity.length() * eps).sqrt();
        let presses = |p: DVec3| (ba.point_velocity(p) - bb.point_velocity(p)).dot(n) < -rest;
        let (Convex::Polyhedron(x), Convex::Polyhedron(y)) = (&pa.convex, &pb.convex) else {
            return presses(mid).then_some(mid);
        };
        let (pose_a, pose_b) = (ba.pose * pa.pose, bb.pose * pb.pose);
        let mut near = patch::near_vertices(x, &pose_a, y, &pose_b, n, eps);
        if scan.depth > 0.0 {
            // Overlapping: the closest points are only a witness, and where two faces'
            // edges cross (boxes turned against each other, no corner of either inside the
            // other) no vertex is near. The manifold's points along the normal are the
            // deepest feature clipped against the other's face: where the overlap sinks.
            let warm = self
                .pairs
                .get(&(a, b))
                .and_then(|s| s.features.get(scan.slot))
                .copied()
                .unwrap_or_default();
            if let Ok(Some(m)) =
                manifold::manifold_along(&pa.convex, &pose_a, &pb.convex, &pose_b, -n, warm, eps)
            {
                near.extend(m.points().iter().map(|p| p.midpoint()));
            }
        }
        if near.is_empty() {
            return Some(mid);
        }
        // The closest points' midpoint is another contact place when it lies outside the near
        // vertices' circle: an edge crossing an edge (no vertex there), as a block landing
        // askew on another. Inside it, it is one of them or between them.
        let centre = near.iter().sum::<DVec3>() / near.len() as f64;
        let spread = near.iter().map(|p| p.distance(centre)).fold(0.0, f64::max);
        if mid.distance(centre) > spread + eps {
            near.push(mid);
        }
        let pressing: Vec<DVec3> = near.into_iter().filter(|&p| presses(p)).collect();
        if pressing.is_empty() {
            return None;
        }
        Some(pressing.iter().sum::<DVec3>() / pressing.len() as f64)
    }

    /// Whether a contact found at `x` along `n` becomes a held (sustained) contact instead of
    /// a collision: in the switching model, when a body of the pair is dynamic, the contact
    /// neither approaches nor separates faster than the switching speed, and the islands can
    /// hold the pair with room to spare ([`HOLD_ROTATION_FRACTION`]; [`crate::sustained`]).
    fn holds(&self, (a, b): (u32, u32), x: DVec3, n: DVec3) -> bool {
        if !self.switching() {
            return false;
        }
        let (ba, bb) = (self.b(a), self.b(b));
        // A link joins its island with its multibody (`held_links.rs`).
        if !(ba.takes_impulses() || bb.takes_impulses()) {
            return false;
        }
        self.is_slow((a, b), x, n) && self.can_hold((a, b), false)
    }

    /// Whether a pair found approaching within ε_c is held instead of struck again: in the
    /// switching model, when it took a collision impulse at this very instant and a body of it
    /// is dynamic and the islands can hold it ([`HOLD_ROTATION_FRACTION`]). Bodies pressed together
    /// by other impacts at one instant (a heavy ball landing on a stack of light boxes) would
    /// otherwise trade collisions without end: each exchange between a body 1000 times lighter
    /// and a heavier one passes on a thousandth of the momentum. Held, the pairs are solved
    /// together by their island's impulsive solve (e = 0 between held contacts), which is the
    /// limit such a train of collisions tends to; each pair's first collision keeps its
    /// restitution.
    fn struck_again(&self, (a, b): (u32, u32)) -> bool {
        if !self.switching() || self.pairs.get(&(a, b)).and_then(|s| s.last_hit) != Some(self.time)
        {
            return false;
        }
        let (ba, bb) = (self.b(a), self.b(b));
        (ba.takes_impulses() || bb.takes_impulses()) && self.can_hold((a, b), true)
    }

    /// Whether the islands could hold a pair with room to spare: held as
    /// [`World::pair_contact`] would hold it with every limit (turning, speeds, the shortest
    /// step) tightened by [`HOLD_ROTATION_FRACTION`], so that a pair just held is not released
    /// at its first island step.
    fn can_hold(&self, pair: (u32, u32), struck: bool) -> bool {
        matches!(
            self.pair_contact(
                pair,
                struck,
                HOLD_ROTATION_FRACTION,
                &mut Default::default()
            ),
            Ok(super::hold::PairContact::Held { .. })
        )
    }

    /// Whether a contact at `x` along `n` neither approaches nor separates faster than the
    /// switching speed.
    fn is_slow(&self, (a, b): (u32, u32), x: DVec3, n: DVec3) -> bool {
        let (ba, bb) = (self.b(a), self.b(b));
        let approach = -(ba.point_velocity(x) - bb.point_velocity(x)).dot(n);
        approach.abs() < self.switch_speed()
    }

    /// After an impulse on a pair, every other heap pair of its two bodies is stale (thesis
    /// §2.4.3) — of the bodies whose motion the impulse changed: a fixed or scripted body's
    /// pairs stay valid.
    fn rekey_others(&mut self, pair: (u32, u32)) -> Result<(), SimError> {
        let mut moved = Vec::new();
        for i in [pair.0, pair.1] {
            match self.b(i).link {
                // An impulse on a link moves its whole multibody.
                Some((m, _)) => moved.extend(self.link_slots(m as usize)),
                None if self.b(i).is_dynamic() => moved.push(i),
                None => {}
            }
        }
        self.rekey(&moved, Some(pair))
    }

    /// New bounds for every heap pair of `bodies` (but `except`).
    pub(super) fn rekey(
        &mut self,
        bodies: &[u32],
        except: Option<(u32, u32)>,
    ) -> Result<(), SimError> {
        // A body whose centre moves outside its far envelope needs new keys for its far
        // pairs too; inside it, they keep theirs (`envelope.rs`).
        let (t, g) = (self.time, self.gravity);
        for &b in bodies {
            self.sync(b)?;
            self.expire_box(b);
            let x = self.b(b);
            let (v, a) = (x.velocity, x.acceleration(g));
            let held = self.islands.held.holds_body(b);
            if x.far.is_some_and(|f| !f.holds(t, v, a, held)) {
                self.b_mut(b).far = None;
            }
        }
        let far_ok = |w: &World, i: u32| w.b(i).far.is_some() || !w.b(i).is_dynamic();
        let mut pairs: Vec<(u32, u32)> = bodies
            .iter()
            .flat_map(|&b| self.heap.pairs_of(b))
            .filter(|p| Some(*p) != except && !self.is_held(*p))
            .filter(|p| !(self.far_keyed.contains(p) && far_ok(self, p.0) && far_ok(self, p.1)))
            .collect();
        pairs.sort_unstable();
        pairs.dedup();
        for p in pairs {
            let key = self.bound(p)?;
            self.heap
                .set_toi(p, key)
                .map_err(|e| self.runtime(format!("collision heap: {e}")))?;
        }
        Ok(())
    }

    /// Resolves a contact of pair `(i, j)` at world point `x` with normal `n` (from j toward
    /// i) and distance `d`: the response of `impulse-response`, or, when it fails or its
    /// result is not finite, the fallback (a frictionless Newton impulse along the normal),
    /// reported. Returns whether an impulse was applied.
    fn resolve(&mut self, pair: (u32, u32), x: DVec3, n: DVec3, d: f64) -> bool {
        let start = self.tick();
        let hit = self.resolve_timed(pair, x, n, d);
        self.charge(super::profile::Part::Response, start);
        hit
    }

    fn resolve_timed(&mut self, (i, j): (u32, u32), x: DVec3, n: DVec3, d: f64) -> bool {
        if self.b(i).is_link() || self.b(j).is_link() {
            return self.resolve_link((i, j), x, n, d);
        }
        let (eps, gravity) = (self.collision_epsilon(), self.gravity);
        let g = gravity.length();
        let mat = self.material(i, j);
        let model = self.model;
        #[cfg(test)]
        let forced = self
            .faults
            .fail_pair
            .is_some_and(|(p, q)| (p, q) == (i, j) || (q, p) == (i, j));
        #[cfg(not(test))]
        let forced = false;
        let (bi, bj) = self.two_mut(i, j);
        let saved = ((bi.velocity, bi.omega), (bj.velocity, bj.omega));
        let before = (
            bi.kinetic_energy() + bj.kinetic_energy(),
            bi.linear_momentum() + bj.linear_momentum(),
            (bi.point_velocity(x) - bj.point_velocity(x)).dot(n),
        );
        let outcome = if forced {
            Err("fault injected by a test".to_string())
        } else {
            contact::resolve(bi, bj, x, n, d, eps, gravity, mat, &model)
        };
        let finite = bi.velocity.is_finite()
            && bi.omega.is_finite()
            && bj.velocity.is_finite()
            && bj.omega.is_finite();
        let (kind, impulse) = match outcome {
            Ok(None) => return false,
            Ok(Some(r)) if finite => r,
            failed => {
                // Undo whatever was applied, then the fallback.
                (bi.velocity, bi.omega) = saved.0;
                (bj.velocity, bj.omega) = saved.1;
                let why = match failed {
                    Err(e) => e,
                    _ => "the impulse made a velocity non-finite".to_string(),
                };
                // A microcollision (thesis eq. 3.18) reverses the normal velocity, as the
                // reversing impulse would; anything faster keeps the material's restitution.
                let micro = g > 0.0
                    && -(bi.point_velocity(x) - bj.point_velocity(x)).dot(n)
                        < (2.0 * g * eps).sqrt();
                let e = if micro { 1.0 } else { mat.restitution };
                let p = contact::resolve_fallback(bi, bj, x, n, e);
                let message = match p {
                    Some(p) => format!(
                        "{why}; resolved by a frictionless impulse {:.6e} along the normal",
                        p.length()
                    ),
                    None => format!("{why}; no impulse applied (the bodies are not approaching)"),
                };
                self.unresolved(i, j, message);
                match p {
                    Some(p) => (ContactKind::Fallback, p),
                    None => return false,
                }
            }
        };
        self.record_contact((i, j), kind, impulse, x, n, before);
        true
    }

    /// Counts an unresolved contact of `(i, j)` ([`super::Counters::unresolved`]) and keeps its
    /// message among the first [`MAX_FAILURES_KEPT`].
    pub(super) fn unresolved(&mut self, i: u32, j: u32, message: String) {
        self.counters.unresolved += 1;
        if self.failures.len() < MAX_FAILURES_KEPT {
            let (a, b) = (self.handle_of(i), self.handle_of(j));
            self.failures.push(ContactFailure {
                time: self.time,
                a,
                b,
                message,
            });
        }
    }

    /// Counts a contact of `(i, j)` just resolved with `impulse` (on `i`, world) at `x` along
    /// `n`, and logs its event; `before` is the two sides' kinetic energy and linear momentum
    /// before the impulse (a link's side is its whole multibody) and the normal relative
    /// velocity at `x` then.
    pub(super) fn record_contact(
        &mut self,
        (i, j): (u32, u32),
        kind: ContactKind,
        impulse: DVec3,
        x: DVec3,
        n: DVec3,
        before: (f64, DVec3, f64),
    ) {
        match kind {
            ContactKind::Collision => self.counters.collisions += 1,
            ContactKind::Microcollision => self.counters.microcollisions += 1,
            ContactKind::Reversing => {
                self.counters.microcollisions += 1;
                self.counters.reversing += 1;
            }
            ContactKind::Fallback => {}
        }
        let after = self.pair_energy(i, j);
        let normal_speed_after = self.normal_speed((i, j), x, n);
        let event = ContactEvent {
            time: self.time,
            a: self.handle_of(i),
            b: self.handle_of(j),
            kind,
            impulse,
            point: x,
            normal: n,
            energy_before: before.0,
            energy_after: after.0,
            momentum_before: before.1,
            momentum_after: after.1,
            normal_speed_before: before.2,
            normal_speed_after,
        };
        if let Some(log) = &mut self.events {
            log.push(event);
        }
        self.recent.push(event);
    }

    /// The normal relative velocity (v_i(x) − v_j(x))·n of pair `(i, j)` at `x` now (a link's
    /// velocity is its multibody's, written to its body at every change).
    pub(super) fn normal_speed(&self, (i, j): (u32, u32), x: DVec3, n: DVec3) -> f64 {
        (self.b(i).point_velocity(x) - self.b(j).point_velocity(x)).dot(n)
    }

    /// A pair checked [`super::MAX_CHECKS_WITHOUT_PROGRESS`] times without time advancing:
    /// the two bodies get a separating push (the fallback impulse with restitution 1 along
    /// the last normal, or nothing if none is known), reported as unresolved, and the loop
    /// goes on.
    pub(super) fn break_stall(&mut self, pair: (u32, u32)) -> Result<(), SimError> {
        self.stalled_checks = 0;
        self.sync_pair(pair)?;
        let scan = self.query(pair);
        let (i, j) = pair;
        let message = match scan.normal {
            Some(n) => {
                let x = 0.5 * (scan.point_a + scan.point_b);
                let (bi, bj) = self.two_mut(i, j);
                let p = contact::resolve_fallback(bi, bj, x, n, 1.0);
                format!(
                    "the loop stalled on this pair ({} checks without time advancing); \
                     separating impulse {:.3e}",
                    super::MAX_CHECKS_WITHOUT_PROGRESS,
                    p.map_or(0.0, |p| p.length())
                )
            }
            None => "the loop stalled on this pair with no contact normal".to_string(),
        };
        self.unresolved(i, j, message);
        self.rekey_others(pair)?;
        self.check_top(pair)
    }

    pub(super) fn material(&self, i: u32, j: u32) -> Material {
        self.materials.get(self.b(i).material, self.b(j).material)
    }

    /// Two distinct bodies, mutably.
    fn two_mut(&mut self, i: u32, j: u32) -> (&mut crate::body::Body, &mut crate::body::Body) {
        assert_ne!(i, j, "a pair is two different bodies");
        let (i, j) = (i as usize, j as usize);
        let (x, y) = if i < j {
            let (lo, hi) = self.slots.split_at_mut(j);
            (&mut lo[i], &mut hi[0])
        } else {
            let (lo, hi) = self.slots.split_at_mut(i);
            (&mut hi[0], &mut lo[j])
        };
        (
            x.body.as_mut().expect("internal ids name live bodies"),
            y.body.as_mut().expect("internal ids name live bodies"),
        )
    }
}
