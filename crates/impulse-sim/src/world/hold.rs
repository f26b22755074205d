//! Which pairs the islands hold, and how long an island may step with them (module
//! documentation of [`crate::sustained`], "Step rate and turning" in
//! `docs/sustained-contact.md`).
//!
//! A held pair is in one of two regimes ([`World::pair_contact`]):
//! - **slow**: its bodies turn slowly enough that no feature outside its points within ε_c can
//!   come through the rest of the envelope within the shortest step; it steps at the rate
//!   that keeps it so ([`World::rotation_step`]);
//! - **fast**: its manifold reaches a margin beyond ε_c ([`World::speculative_margin`]), its
//!   unheld vertices over the other's contact face are points too
//!   ([`impulse_collide::manifold::shape_outside`]), and its step is bounded by the curvature
//!   of its turning ([`World::curvature_step`]), by the clearance of what its manifold
//!   leaves out, and by the angle its bodies may turn in a step ([`TURN_ANGLE_STEP`]).
//!
//! A pair slow enough for the first is held the second way whenever that allows a longer
//! step: a domino tipping at 0.15 m/s would step every 60 µs held by its points within ε_c,
//! every 1 ms with speculative points.
//!
//! A pair needing a step below the shortest one, or whose points within ε_c meet or part
//! like an impact, is too fast to hold: the event loop takes it back.

use glam::DVec3;
use impulse_collide::manifold::{self, Clearances, ContactPoint, Manifold, ManifoldCache};
use impulse_collide::shape::Convex;

use super::World;
use crate::error::SimError;

/// Fraction of the envelope left above the rest gap that turning may use up within one
/// island step: the rest covers the angular acceleration within the step (the step is chosen
/// from the speeds at its start). Default `0.5`.
pub(super) const TURN_STEP_SAFETY: f64 = 0.5;

/// Largest angle (rad) a held pair's bodies may turn within one island step in the fast
/// regime. With the held load's arms at mid-step the step is second order in time (a box
/// tipping over its edge from 4 rad/s reaches 10°, 25°, 40° within 6e-5 of the rigid pivot's
/// times even with 1 ms steps; with the arms at the start it was late by 0.72 % at 1 ms), so
/// this bounds what the linear prediction of a fast-turning face does to its speculative
/// points: coins slapping flat sank 0.58 ε_c (checking monitor) at `2e-3`, 0.67 at `5e-3`,
/// 6.7 at `1e-2`. Default `5e-3`.
pub(super) const TURN_ANGLE_STEP: f64 = 5e-3;

/// Relative margin by which a piece pair's gap measured within ε_c must exceed a wider
/// reach for [`World::pair_contact`]'s fast way to take it as holding no manifold there
/// without measuring it again (a second measurement from other warm-start features may
/// differ by rounding). Default `1e-9`.
const NEAR_GAP_REL: f64 = 1e-9;

/// What the fast way of holding a pair knows before it looks at the reach.
enum Known<'a> {
    /// The pair's manifolds at the reach (two single polyhedra: made first).
    Wide(&'a [Manifold]),
    /// The piece pairs measured within ε_c that hold no manifold there (compounds).
    Near(&'a Clearances),
}

/// What [`World::pair_contact`] found.
pub(super) enum PairContact {
    /// No point within the envelope: the pair lifted off.
    Apart,
    /// The pair turns or approaches too fast to be held even over the shortest step.
    TooFast,
    /// The pair can be held: its manifolds and the island step it needs; `fast`: it turns too
    /// fast to be held by its points within ε_c alone (speculative points, a looser solve).
    Held {
        manifolds: Vec<Manifold>,
        /// Per manifold, the vertex–face points of vertices outside its contact features
        /// ([`impulse_collide::manifold::shape_outside`]).
        outside: Vec<Vec<ContactPoint>>,
        /// The piece pairs of two compounds held by their touching pieces that do not
        /// touch, and how close they are: the step keeps them apart ([`World::clearance_step`]);
        /// [`Clearances::NONE`] for single pieces and the fast regime.
        near: Clearances,
        step: f64,
        fast: bool,
    },
}

impl PairContact {
    /// The island step a held pair needs (zero when it is not held).
    fn step(&self) -> f64 {
        match self {
            Self::Held { step, .. } => *step,
            _ => 0.0,
        }
    }
}

impl World {
    /// What is left of the contact envelope above a held contact's rest gap,
    /// (1 − g_r/ε_c)·ε_c: rotation must not bring another feature through it within a step.
    pub(super) fn envelope_left(&self) -> f64 {
        (1.0 - self.islands.settings.rest_gap_fraction) * self.collision_epsilon()
    }

    /// The turning acceleration ([`spin_accel`]) for which the shortest island step is needed
    /// ([`TURN_STEP_SAFETY`]): above it the pair is released to the event loop (and the event
    /// loop holds it again only below a quarter of it, the shortest step taken with the hold
    /// margin). A held pair's contact points include every feature its turning
    /// can bring within reach over a step (speculative points, [`Self::speculative_margin`]),
    /// so only the curvature of the motion, which a step's linear prediction misses, bounds
    /// the step: ½·a·h² within the envelope left above the rest gap.
    pub(super) fn spin_limit(&self) -> f64 {
        let h = self.islands.settings.min_step;
        2.0 * TURN_STEP_SAFETY * self.envelope_left() / (h * h)
    }

    /// The turning speed ([`turn_speed`]) for which the shortest island step is needed when
    /// a pair is held by its points within ε_c alone ([`TURN_STEP_SAFETY`]). A pair turning
    /// faster is held with speculative points ([`Self::pair_contact`]).
    pub(super) fn rotation_limit(&self) -> f64 {
        TURN_STEP_SAFETY * self.envelope_left() / self.islands.settings.min_step
    }

    /// The island step a pair whose surfaces rotation moves at `speed` needs when it is held by
    /// its points within ε_c alone: short enough that no other feature comes through the rest
    /// of the envelope, within [`crate::sustained::SustainedSettings::min_step`] and [`crate::sustained::SustainedSettings::step`].
    fn rotation_step(&self, speed: f64) -> f64 {
        let s = &self.islands.settings;
        if speed > 0.0 {
            (TURN_STEP_SAFETY * self.envelope_left() / speed).clamp(s.min_step, s.step)
        } else {
            s.step
        }
    }

    /// The island step a pair whose surfaces turning accelerates at `accel` needs: short
    /// enough that the curvature of the motion over the step, ½·a·h², stays within
    /// [`TURN_STEP_SAFETY`] of the envelope left, within [`crate::sustained::SustainedSettings::min_step`] and
    /// [`crate::sustained::SustainedSettings::step`].
    fn curvature_step(&self, accel: f64) -> f64 {
        let s = &self.islands.settings;
        if accel > 0.0 {
            (2.0 * TURN_STEP_SAFETY * self.envelope_left() / accel)
                .sqrt()
                .clamp(s.min_step, s.step)
        } else {
            s.step
        }
    }

    /// How far beyond ε_c a held pair's manifold reaches for points: the distance another
    /// feature can close at the pair's approach speed `turn` ([`turn_speed`]) over the
    /// nominal step.
    fn speculative_margin(&self, turn: f64) -> f64 {
        turn * self.islands.settings.step
    }

    /// A pair's contact as the islands would hold it (module documentation): its manifolds,
    /// with speculative and outside points in the fast regime, and the island step it needs.
    /// A pair that needs less than [`crate::sustained::SustainedSettings::min_step`], or whose
    /// points within ε_c meet or part faster than the slow regime allows (an impact), is too
    /// fast to hold. `struck`: the pair's approach is a strike about to be stopped (only
    /// rotation counts). `margin`: 1 for the island's own decision, `HOLD_ROTATION_FRACTION`
    /// (in `check.rs`) when the event loop asks whether to hold, so that every limit has room
    /// to spare.
    pub(super) fn pair_contact(
        &self,
        (a, b): (u32, u32),
        struck: bool,
        margin: f64,
        cache: &mut ManifoldCache,
    ) -> Result<PairContact, SimError> {
        let (ba, bb) = (self.b(a), self.b(b));
        let s = &self.islands.settings;
        let eps = self.collision_epsilon();
        // The fast way is tried only for single polyhedra, whose turning brings vertices
        // within reach. A compound's clearance is bounded by its pieces' bounding spheres and
        // its turn speed by its whole sliding speed, and a smooth piece has no vertex to
        // hold: the fast way seldom steps longer there and costs a manifold at the reach and
        // the outside points (balls rolling in the dish: 2.09 s with the attempt, 1.27 s
        // without; the rattleback 5.6 s against 3.9).
        let polyhedron = |x: &crate::body::Body| {
            matches!(
                x.shape.pieces(),
                [piece] if matches!(piece.convex, Convex::Polyhedron(_))
            )
        };
        let turn0 = pair_turn(ba, bb, struck, None);
        if polyhedron(ba) && polyhedron(bb) && self.rotation_step(turn0) < s.step {
            return self.turning_polyhedra((a, b), struck, turn0, margin, cache);
        }
        // Lift-off: no point within the envelope.
        let compound = ba.shape.pieces().len() > 1 || bb.shape.pieces().len() > 1;
        let mut near = Clearances::NONE;
        let found = if compound {
            self.pair_manifolds_near((a, b), eps, cache, &mut near)?
        } else {
            self.pair_manifolds((a, b), eps, cache)?
        };
        if found.iter().all(|m| m.min_gap() > eps) {
            return Ok(PairContact::Apart);
        }
        // Slow: no other feature can come through the envelope within the shortest step.
        // A smooth body's turning brings no other feature (turn speed zero on its side): its
        // step is bounded by the curvature of its surface's motion. Each touching piece pair
        // approaches along its own normal; the other piece pairs of two compounds bound the
        // step by their clearance ([`Self::clearance_step`]).
        let (mut turn, mut curve) = (0.0_f64, smooth_accel(ba) + smooth_accel(bb));
        for m in &found {
            let (sa, sb) = (
                TurnSide::of_piece(ba, m.pieces.0, ba.velocity, ba.omega),
                TurnSide::of_piece(bb, m.pieces.1, bb.velocity, bb.omega),
            );
            turn = turn.max(if struck {
                sa.spin_reach + sb.spin_reach
            } else {
                approach_speed(&sa, &sb, Some(m.normal))
            });
            curve =
                curve.max(sphere_piece_accel(ba, m.pieces.0) + sphere_piece_accel(bb, m.pieces.1));
        }
        // Whether the pair is held at all is judged as before the clearance bound was known:
        // a compound by the whole relative speed of the centres. Judged by its touching
        // pieces' normals, more sliding compounds are held instead of given microcollisions,
        // and the feeder chute's caps jam at its opening in 18 of 40 seeded variants (7 of
        // 40 judged by the whole speed; `docs/sustained-contact.md`, Open).
        let hold_turn = if compound {
            pair_turn(ba, bb, struck, None)
        } else {
            turn
        };
        let clear = self.clearance_step(ba, bb, &near);
        if hold_turn <= margin * self.rotation_limit() && clear * margin >= s.min_step {
            let outside = vec![Vec::new(); found.len()];
            let step = self
                .rotation_step(turn)
                .min(self.curvature_step(curve))
                .min(clear);
            return Ok(PairContact::Held {
                manifolds: found,
                outside,
                near,
                step,
                fast: false,
            });
        }
        Ok(self
            .fast_contact((a, b), &found, Known::Near(&near), turn0, margin, cache)?
            .unwrap_or(PairContact::TooFast))
    }

    /// [`Self::pair_contact`] for two single polyhedra that may be turning (`turn0`, the turn
    /// speed without a normal, asks for less than the nominal step): held the fast way
    /// whenever that allows a longer step than the slow way — its speculative and outside
    /// points cover what the turning brings within reach, so its step is bounded by the
    /// curvature and the clearance, not by the envelope (a domino tipping at 0.15 m/s steps
    /// every 60 µs the slow way, every 1 ms the fast way). The manifold at the reach comes
    /// first, and serves for lift-off and the normal too; the one within ε_c is computed only
    /// when the slow way is taken.
    fn turning_polyhedra(
        &self,
        (a, b): (u32, u32),
        struck: bool,
        turn0: f64,
        margin: f64,
        cache: &mut ManifoldCache,
    ) -> Result<PairContact, SimError> {
        let eps = self.collision_epsilon();
        let wide = self.pair_manifolds((a, b), eps + self.speculative_margin(turn0), cache)?;
        // Lift-off: no point within the envelope (a manifold keeps its deepest point).
        if wide.iter().all(|m| m.min_gap() > eps) {
            return Ok(PairContact::Apart);
        }
        let turn = pair_turn(self.b(a), self.b(b), struck, Some(wide[0].normal));
        let slow = (turn <= margin * self.rotation_limit()).then(|| self.rotation_step(turn));
        let fast = self.fast_contact((a, b), &wide, Known::Wide(&wide), turn0, margin, cache)?;
        let step = match (slow, fast) {
            (Some(step), Some(fast)) if fast.step() <= step => step,
            (_, Some(fast)) => return Ok(fast),
            (None, None) => return Ok(PairContact::TooFast),
            (Some(step), None) => step,
        };
        let found = self.pair_manifolds((a, b), eps, cache)?;
        if found.iter().all(|m| m.min_gap() > eps) {
            return Ok(PairContact::Apart);
        }
        let outside = vec![Vec::new(); found.len()];
        Ok(PairContact::Held {
            manifolds: found,
            outside,
            near: Clearances::NONE,
            step,
            fast: false,
        })
    }

    /// The manifolds of a pair's pieces within `tolerance`.
    fn pair_manifolds(
        &self,
        (a, b): (u32, u32),
        tolerance: f64,
        cache: &mut ManifoldCache,
    ) -> Result<Vec<Manifold>, SimError> {
        let (ba, bb) = (self.b(a), self.b(b));
        manifold::shape_manifolds(&ba.shape, &ba.pose, &bb.shape, &bb.pose, tolerance, cache)
            .map_err(|e| {
                self.runtime(format!(
                    "contact manifold of {} / {}: {e}",
                    ba.name, bb.name
                ))
            })
    }

    /// [`Self::pair_manifolds`], with the clearances of the piece pairs that do not touch.
    fn pair_manifolds_near(
        &self,
        (a, b): (u32, u32),
        tolerance: f64,
        cache: &mut ManifoldCache,
        near: &mut Clearances,
    ) -> Result<Vec<Manifold>, SimError> {
        let (ba, bb) = (self.b(a), self.b(b));
        manifold::shape_manifolds_near(
            &ba.shape, &ba.pose, &bb.shape, &bb.pose, tolerance, cache, near,
        )
        .map_err(|e| {
            self.runtime(format!(
                "contact manifold of {} / {}: {e}",
                ba.name, bb.name
            ))
        })
    }

    /// The island step that keeps the piece pairs of two compounds that do not touch (`near`)
    /// from touching unheld: each uses at most [`TURN_STEP_SAFETY`] of its clearance above the
    /// rest gap, closing at its [`clearance_closing`] speed; `step` when there are none
    /// (within [`crate::sustained::SustainedSettings::step`], not clamped below: a caller
    /// compares it with the shortest step). Sliding along the contact plane brings no other
    /// feature of two convex pieces closer, but it brings another piece of a compound: a
    /// ball rolling from a dish's slope onto its floor, a table's leg toward a wall.
    pub(super) fn clearance_step(
        &self,
        a: &crate::body::Body,
        b: &crate::body::Body,
        near: &Clearances,
    ) -> f64 {
        let s = &self.islands.settings;
        let rest = s.rest_gap_fraction * self.collision_epsilon();
        let (sa, sb) = (
            TurnSide::of(a, a.velocity, a.omega),
            TurnSide::of(b, b.velocity, b.omega),
        );
        clearance_bound(near, rest, TURN_STEP_SAFETY, |d| {
            clearance_closing(&sa, &sb, d)
        })
        .min(s.step)
    }

    /// A pair held the fast way ([`Self::pair_contact`]: speculative and outside points, a
    /// step the curvature and the clearance allow), or `None` when it is too fast for that.
    /// `found`: its manifolds within ε_c (or any wider: only their points within ε_c count
    /// here); `known`: its manifolds at the reach `turn` gives, when already computed, or else
    /// the piece pairs measured within ε_c without a manifold (for a bound on the clearance
    /// that may make the manifolds at the reach unnecessary); `turn`:
    /// how fast another feature can approach ([`turn_speed`] without a normal, or
    /// [`rotation_speed`] for a struck pair).
    fn fast_contact(
        &self,
        (a, b): (u32, u32),
        found: &[Manifold],
        known: Known<'_>,
        turn: f64,
        margin: f64,
        cache: &mut ManifoldCache,
    ) -> Result<Option<PairContact>, SimError> {
        let (ba, bb) = (self.b(a), self.b(b));
        let s = &self.islands.settings;
        let eps = self.collision_epsilon();
        // Only a turning contact. A point within the envelope whose surfaces meet or
        // part faster than the first-order limit is an impact (a ball of the rack struck by
        // the cue ball): even the shortest step could not hold it inside the envelope, and
        // it is the event loop's, as a collision with its restitution.
        let normal_speed = found
            .iter()
            .flat_map(|m| m.points().iter().map(move |p| (m.normal, p)))
            .filter(|(_, p)| p.gap <= eps)
            .map(|(n, p)| {
                let x = p.midpoint();
                (bb.point_velocity(x) - ba.point_velocity(x)).dot(n).abs()
            })
            .fold(0.0, f64::max);
        if normal_speed > margin * self.rotation_limit() {
            return Ok(None);
        }
        // Then speculative points, and a step the curvature and the clearance allow.
        let accel = spin_accel(ba, bb);
        if accel > margin * self.spin_limit() {
            return Ok(None);
        }
        let reach = eps + self.speculative_margin(turn);
        let spin_step = TURN_ANGLE_STEP / spin(ba).max(spin(bb)).max(f64::MIN_POSITIVE);
        #[cfg(test)]
        let bounded = !self.faults.no_clearance_bound;
        #[cfg(not(test))]
        let bounded = true;
        if let (true, Known::Near(near)) = (bounded && turn > 0.0, &known) {
            // The clearance is at most that of the piece pairs measured beyond the reach
            // within ε_c (`near`): they hold no manifold at the reach either, and count by
            // their bounding spheres. When that bound already makes the step too short, the
            // manifolds at the reach and the outside points are not made (the feeder chute:
            // 41 713 of its hold checks, each two manifold sets for a step that failed on a
            // clearance of 0, a cap's second piece whose sphere dips into the tray).
            let bound = near
                .measured
                .iter()
                .filter(|p| p.gap > reach * (1.0 + NEAR_GAP_REL))
                .map(|p| {
                    let (i, j) = (p.pieces.0 as usize, p.pieces.1 as usize);
                    manifold::piece_sphere_clearance(&ba.shape, &ba.pose, i, &bb.shape, &bb.pose, j)
                })
                .fold(f64::INFINITY, f64::min);
            let most = self
                .curvature_step(accel)
                .min(TURN_STEP_SAFETY * bound / turn)
                .min(spin_step);
            if most * margin < s.min_step {
                #[cfg(test)]
                self.faults
                    .clearance_bound_exits
                    .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                return Ok(None);
            }
        }
        let found = match known {
            Known::Wide(w) => w.to_vec(),
            Known::Near(_) => self.pair_manifolds((a, b), reach, cache)?,
        };
        let (outside, clearance) =
            manifold::shape_outside(&ba.shape, &ba.pose, &bb.shape, &bb.pose, &found, reach);
        let step = self
            .curvature_step(accel)
            .min(TURN_STEP_SAFETY * clearance / turn)
            .min(spin_step);
        if step * margin < s.min_step {
            return Ok(None);
        }
        Ok(Some(PairContact::Held {
            manifolds: found,
            outside,
            near: Clearances::NONE,
            step,
            fast: true,
        }))
    }
}

/// Whether a body moves on its own (not fixed, scripted or asleep): only its motion brings
/// features of a held pair closer.
fn moves(x: &crate::body::Body) -> bool {
    x.takes_impulses() && !x.asleep
}

/// ‖ω‖ of a body, zero for a fixed or sleeping one.
fn spin(x: &crate::body::Body) -> f64 {
    if moves(x) { x.omega.length() } else { 0.0 }
}

/// ‖ω‖²·r of a body, r its rotational reach (the centripetal acceleration of its farthest
/// point: an estimate of the curvature of its surface's motion), or for `k` = 1 how fast its
/// turning can bring another feature closer ([`crate::body::Body::surface_speed`]: ‖ω‖·r,
/// but for a solid of revolution turning about its axis, and nothing for a smooth body,
/// [`crate::body::Body::is_smooth`]); zero for a fixed or sleeping body.
fn spin_power(x: &crate::body::Body, k: i32) -> f64 {
    if !moves(x) {
        0.0
    } else if k == 1 {
        if x.is_smooth() {
            0.0
        } else {
            x.surface_speed(x.omega)
        }
    } else {
        x.omega.length().powi(k) * x.max_reach()
    }
}

/// [`spin_power`]`(x, 2)` of a smooth body ([`crate::body::Body::is_smooth`]), zero for any
/// other: what bounds the step of a smooth body held by its one support point.
fn smooth_accel(x: &crate::body::Body) -> f64 {
    if x.is_smooth() { spin_power(x, 2) } else { 0.0 }
}

/// How fast the turning of body `x` accelerates the surface of its piece `piece` when that
/// piece is a sphere ([`TurnSide::of_piece`]): ‖ω‖² times the piece's reach (its centre's
/// centripetal acceleration about the centre of mass, and its surface's about its centre);
/// zero for any other piece, or a body that does not move.
fn sphere_piece_accel(x: &crate::body::Body, piece: u32) -> f64 {
    match (
        x.shape.pieces().get(piece as usize),
        x.reach.get(piece as usize),
    ) {
        (Some(p), Some(&r)) if moves(x) && matches!(p.convex, Convex::Sphere(_)) => {
            x.omega.length_squared() * r
        }
        _ => 0.0,
    }
}

/// How fast rotation can accelerate the two bodies' surfaces: Σ ‖ω‖²·r over both (the
/// centripetal acceleration of the farthest point of each), the curvature of the motion a
/// step's linear prediction misses.
pub(super) fn spin_accel(a: &crate::body::Body, b: &crate::body::Body) -> f64 {
    spin_power(a, 2) + spin_power(b, 2)
}

/// How fast rotation can move the two bodies' surfaces: ‖ω‖ times the rotational reach
/// (zero for a ball turning about its centre, which keeps its distance to everything).
pub(super) fn rotation_speed(a: &crate::body::Body, b: &crate::body::Body) -> f64 {
    spin_power(a, 1) + spin_power(b, 1)
}

/// The turn speed a held pair is judged by: [`rotation_speed`] alone for a pair struck at
/// this instant (its approach is the strike the island is about to stop), else
/// [`turn_speed`] along the contact normal `n` (when known).
fn pair_turn(a: &crate::body::Body, b: &crate::body::Body, struck: bool, n: Option<DVec3>) -> f64 {
    if struck {
        rotation_speed(a, b)
    } else {
        turn_speed(a, b, n)
    }
}

/// How fast another feature of a held pair's touching pieces can approach: its bodies'
/// rotation ([`rotation_speed`]) plus their centres' relative speed along the contact normal
/// `n` (a body pivoting on an edge moves its centre toward the other body as it turns);
/// without a normal, the whole relative speed. Sliding along the contact plane brings no
/// feature of two convex pieces closer; the other pieces of a compound are kept apart by the
/// step's clearance bound ([`World::clearance_step`]).
pub(super) fn turn_speed(a: &crate::body::Body, b: &crate::body::Body, n: Option<DVec3>) -> f64 {
    approach_speed(
        &TurnSide::of(a, a.velocity, a.omega),
        &TurnSide::of(b, b.velocity, b.omega),
        n,
    )
}

/// What [`approach_speed`] reads of one side of a pair.
pub(super) struct TurnSide {
    /// The centre's velocity (zero for a fixed, scripted or sleeping body).
    velocity: DVec3,
    /// How fast its turning moves its surface ([`crate::body::Body::surface_speed`]: ‖ω‖
    /// times the rotational reach, but for a solid of revolution turning about its axis;
    /// zero for a fixed, scripted or sleeping body: a platter spinning under a ball turns its
    /// face in its own plane; zero for a smooth body, whose turning brings no other feature:
    /// its support point's own motion is the contact's, [`crate::body::Body::is_smooth`]).
    spin_reach: f64,
    /// ‖ω‖ times the rotational reach, for any body that moves (zero for a fixed, scripted or
    /// sleeping body): how fast its turning moves a point of another of its pieces.
    piece_reach: f64,
}

impl TurnSide {
    /// No body (the fixed world).
    pub(super) const NONE: Self = Self {
        velocity: DVec3::ZERO,
        spin_reach: 0.0,
        piece_reach: 0.0,
    };

    /// [`Self::of`] for the side of a contact on piece `piece` of body `x`. A sphere piece
    /// anywhere on its body (a mallet's head on its rod) turns about its own centre without
    /// bringing any other feature of itself: its side is its centre's velocity, with no turn
    /// (what another piece of the body brings is the clearance bound's,
    /// [`World::clearance_step`], and the curvature of the centre's path is
    /// [`sphere_piece_accel`]'s).
    pub(super) fn of_piece(
        x: &crate::body::Body,
        piece: u32,
        velocity: DVec3,
        omega: DVec3,
    ) -> Self {
        let side = Self::of(x, velocity, omega);
        match x.shape.pieces().get(piece as usize) {
            Some(p) if moves(x) && matches!(p.convex, Convex::Sphere(_)) => {
                let arm = x.pose.rotation * p.pose.translation;
                Self {
                    velocity: velocity + omega.cross(arm),
                    spin_reach: 0.0,
                    ..side
                }
            }
            _ => side,
        }
    }

    /// Body `x` moving at `velocity` and `omega` (its own, or a step's trial velocities).
    pub(super) fn of(x: &crate::body::Body, velocity: DVec3, omega: DVec3) -> Self {
        let moving = moves(x);
        Self {
            velocity: if moving { velocity } else { DVec3::ZERO },
            spin_reach: if moving && !x.is_smooth() {
                x.surface_speed(omega)
            } else {
                0.0
            },
            piece_reach: if moving {
                omega.length() * x.max_reach()
            } else {
                0.0
            },
        }
    }
}

/// [`turn_speed`] of two sides: their rotation plus the relative speed of their centres
/// along `n` (all of it without a normal).
pub(super) fn approach_speed(a: &TurnSide, b: &TurnSide, n: Option<DVec3>) -> f64 {
    let dv = a.velocity - b.velocity;
    let normal = match n {
        Some(n) => dv.dot(n.normalize_or_zero()).abs(),
        None => dv.length(),
    };
    a.spin_reach + b.spin_reach + normal
}

/// How fast a piece pair of sides `a` and `b` that does not touch closes its distance, at
/// most: the translation of `b` relative to `a` along `direction` (from `a`'s closest point
/// to `b`'s; the distance of two convex pieces is a convex function of their relative
/// translation, so it falls no faster than along its gradient), or the whole relative speed
/// without a direction, plus how fast each side's turning moves its points
/// (`TurnSide::piece_reach`: a smooth body's other pieces move too).
pub(super) fn clearance_closing(a: &TurnSide, b: &TurnSide, direction: Option<DVec3>) -> f64 {
    let dv = b.velocity - a.velocity;
    let translation = match direction {
        Some(d) => (-dv.dot(d)).max(0.0),
        None => dv.length(),
    };
    a.piece_reach + b.piece_reach + translation
}

/// The least `safety`·(gap − `rest`)/`closing` over the clearances of `near` whose
/// `closing(direction)` is positive (∞ when none closes): with `closing` a speed, the time
/// within which each keeps `safety` of its clearance above the rest gap
/// ([`World::clearance_step`]); with a distance, the fraction of it that fits (`clearance_fit`
/// in `island.rs`).
pub(super) fn clearance_bound(
    near: &Clearances,
    rest: f64,
    safety: f64,
    closing: impl Fn(Option<DVec3>) -> f64,
) -> f64 {
    near_gaps(near)
        .map(|(gap, direction)| {
            let c = closing(direction);
            if c > 0.0 {
                safety * (gap - rest) / c
            } else {
                f64::INFINITY
            }
        })
        .fold(f64::INFINITY, f64::min)
}

/// Each clearance of `near` as (gap, direction from `a` toward `b`): the measured piece pairs
/// (without a direction when their closest points coincide), then the bound on the others.
fn near_gaps(near: &Clearances) -> impl Iterator<Item = (f64, Option<DVec3>)> + '_ {
    near.measured
        .iter()
        .map(|c| (c.gap, (c.direction != DVec3::ZERO).then_some(c.direction)))
        .chain(
            near.unmeasured
                .is_finite()
                .then_some((near.unmeasured, None)),
        )
}
