//! What a hybrid event loop needs to know of a multibody's links (thesis §5.2): each link's
//! motion at the current instant, from which it predicts swept boxes and time-of-impact
//! coefficients ([`LinkKinematics`]), and the worst-case travel actually seen during an
//! integration, against which it checks those predictions ([`LinkTravel`], Figs. 5.3 and 5.4).
//!
//! Every quantity refers to a link's **frame origin**, not its centre of mass: a bound of the
//! form `B = v_p·d̂ + r ‖ω‖` holds for any point p fixed in the link when r is the link's
//! largest distance from p, and the frame origin is where a link's collision shapes are given.
//! Travel is recorded at every derivative evaluation of the integrator (the thesis's
//! "treeFwdDynamics knows the link positions"), so it is exact at the sampled states only.

use glam::DVec3;
use impulse_geom::{Pose, Twist};

use crate::dynamics::Workspace;
use crate::model::Model;
use crate::spatial::Xform;

/// A link's motion at one instant, world frame: what the thesis's second-order c.o.m. model
/// (§5.2.1) and its TOI coefficients (§5.2.2) are made from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkKinematics {
    /// The link frame in the world.
    pub pose: Pose,
    /// Velocity of the link frame's origin (m/s).
    pub velocity: DVec3,
    /// Angular velocity (rad/s).
    pub omega: DVec3,
    /// Acceleration of the link frame's origin (m/s², gravity included).
    pub acceleration: DVec3,
    /// Angular acceleration (rad/s²).
    pub angular_acceleration: DVec3,
}

/// One sampled state of a link (world frame, link frame origin).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TravelSample {
    /// The simulation's time of the sample (s).
    pub t: f64,
    /// Position of the origin.
    pub origin: DVec3,
    /// Velocity of the origin.
    pub velocity: DVec3,
    /// Angular velocity.
    pub omega: DVec3,
}

impl TravelSample {
    /// The largest speed along `d` of any point within `reach` of the origin at this state:
    /// `v·d + r ‖ω × d‖` (the largest `(ω × arm)·d = arm·(d × ω)` over arms of length r). Exact
    /// for one state, and never above the prediction's `v·d + r ‖ω‖ ‖d‖`; Fig. 5.4's
    /// componentwise form ([`LinkTravel::speed_along`]) is for ω known only by per-axis
    /// bounds, and exceeds ‖ω‖ for a turn about a skew axis (by up to √2 per sample: it made
    /// a triple pendulum's links fail their slack at rest).
    #[must_use]
    pub fn speed_along(&self, d: DVec3, reach: f64) -> f64 {
        self.velocity.dot(d) + reach * self.omega.cross(d).length()
    }
}

/// The range of a link's motion over the derivative evaluations of one or more integration
/// steps (world frame, link frame origin): Fig. 5.3's min/max of the position, Fig. 5.4's
/// componentwise min/max of the linear velocity and max of each |ω| component, and every
/// sampled state with its time (in the order sampled).
#[derive(Clone, Debug, PartialEq)]
pub struct LinkTravel {
    /// Componentwise least position of the origin seen.
    pub origin_min: DVec3,
    /// Componentwise greatest position of the origin seen.
    pub origin_max: DVec3,
    /// Componentwise least velocity of the origin seen.
    pub velocity_min: DVec3,
    /// Componentwise greatest velocity of the origin seen.
    pub velocity_max: DVec3,
    /// Greatest |ω_x|, |ω_y|, |ω_z| seen.
    pub omega_abs_max: DVec3,
    /// States sampled (0: nothing recorded, every range empty).
    pub samples: u64,
    /// The sampled states.
    pub path: Vec<TravelSample>,
}

impl Default for LinkTravel {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl LinkTravel {
    /// No sample yet: every range is empty.
    pub const EMPTY: LinkTravel = LinkTravel {
        origin_min: DVec3::INFINITY,
        origin_max: DVec3::NEG_INFINITY,
        velocity_min: DVec3::INFINITY,
        velocity_max: DVec3::NEG_INFINITY,
        omega_abs_max: DVec3::ZERO,
        samples: 0,
        path: Vec::new(),
    };

    /// Adds one sampled state at time `t`.
    pub fn add(&mut self, t: f64, origin: DVec3, velocity: DVec3, omega: DVec3) {
        self.path.push(TravelSample {
            t,
            origin,
            velocity,
            omega,
        });
        self.origin_min = self.origin_min.min(origin);
        self.origin_max = self.origin_max.max(origin);
        self.velocity_min = self.velocity_min.min(velocity);
        self.velocity_max = self.velocity_max.max(velocity);
        self.omega_abs_max = self.omega_abs_max.max(omega.abs());
        self.samples += 1;
    }

    /// Both ranges together.
    #[must_use]
    pub fn union(&self, other: &LinkTravel) -> LinkTravel {
        LinkTravel {
            origin_min: self.origin_min.min(other.origin_min),
            origin_max: self.origin_max.max(other.origin_max),
            velocity_min: self.velocity_min.min(other.velocity_min),
            velocity_max: self.velocity_max.max(other.velocity_max),
            omega_abs_max: self.omega_abs_max.max(other.omega_abs_max),
            samples: self.samples + other.samples,
            path: self.path.iter().chain(&other.path).copied().collect(),
        }
    }

    /// The largest speed along `d` (world; its length scales the result) of any point within
    /// `reach` of the origin, over the sampled states: thesis Fig. 5.4's
    /// `k = Σ_c (d_c < 0 ? v_min,c : v_max,c)·d_c + r Σ_c |ω|_max,c ‖e_c × d‖`
    /// (`‖e_c × d‖ = √(‖d‖² − d_c²)` bounds the part of a rotation about axis c seen along
    /// d). `−∞` before any sample.
    #[must_use]
    pub fn speed_along(&self, d: DVec3, reach: f64) -> f64 {
        if self.samples == 0 {
            return f64::NEG_INFINITY;
        }
        let mut k = 0.0;
        let dd = d.length_squared();
        for c in 0..3 {
            let v = if d[c] < 0.0 {
                self.velocity_min[c]
            } else {
                self.velocity_max[c]
            };
            k += v * d[c] + reach * self.omega_abs_max[c] * (dd - d[c] * d[c]).max(0.0).sqrt();
        }
        k
    }
}

/// World transforms of every moving body from the per-body joint transforms a recursion
/// left in `ws` (the composition of `Workspace::update_kinematics`).
fn compose_world(model: &Model, ws: &mut Workspace) {
    for i in 0..model.body_count() {
        let x = ws.bodies[i].x;
        ws.world[i] = match model.bodies[i].parent {
            Some(p) => ws.world[p].compose(&x),
            None => x,
        };
    }
}

/// The world frame and world twist (at the world origin) of link `l`, after
/// [`compose_world`]; a link welded to the ground does not move.
fn link_frame(model: &Model, ws: &Workspace, l: usize) -> (Xform, Twist) {
    let info = &model.links[l];
    match info.body {
        Some(b) => (
            ws.world[b].compose(&info.offset),
            ws.world[b].motion_to_parent(&ws.bodies[b].v),
        ),
        None => (info.offset, Twist::ZERO),
    }
}

/// Records the state of every link (indexed as the model's links) into `travel`, after a
/// forward-dynamics pass filled `ws` with the state's joint transforms and velocities at time
/// `t`.
pub(crate) fn record(model: &Model, ws: &mut Workspace, t: f64, travel: &mut [LinkTravel]) {
    compose_world(model, ws);
    for (l, tr) in travel.iter_mut().enumerate() {
        let (x, twist) = link_frame(model, ws, l);
        tr.add(t, x.p, twist.v + twist.w.cross(x.p), twist.w);
    }
}

/// Every link's kinematics after a forward-dynamics pass at the state: the spatial
/// accelerations it left in `ws` carry the fictitious base acceleration −g (Featherstone's
/// gravity trick), so the true one is `â + (g, 0)`; the classical acceleration of the origin p
/// is `â.v + â.ω × p + ω × v_p` (the derivative of `v_p = v̂.v + ω × p`).
pub(crate) fn kinematics(model: &Model, ws: &mut Workspace) -> Vec<LinkKinematics> {
    compose_world(model, ws);
    let g = Twist::new(model.gravity, DVec3::ZERO);
    (0..model.links.len())
        .map(|l| {
            let (x, twist) = link_frame(model, ws, l);
            let p = x.p;
            let velocity = twist.v + twist.w.cross(p);
            let (acceleration, angular_acceleration) = match model.links[l].body {
                Some(b) => {
                    let a = ws.world[b].motion_to_parent(&ws.bodies[b].a) + g;
                    (a.v + a.w.cross(p) + twist.w.cross(velocity), a.w)
                }
                None => (DVec3::ZERO, DVec3::ZERO),
            };
            LinkKinematics {
                pose: x.to_pose(),
                velocity,
                omega: twist.w,
                acceleration,
                angular_acceleration,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests;
