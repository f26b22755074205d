//! Reduced dynamics (FORK⁻¹S §6): backward Euler on the coupled end-effector system with the
//! system matrix factored once, frictional contact of the end effectors against fixed
//! geometry by projected Gauss–Seidel, and a free base (§6.1).
//!
//! **\[fix\] eq. 23.** The paper prints `A = M − h²K − hD`, the force-derivative sign convention.
//! With eq. 8 as written (`M φ̇ + D φ + K ξ = w`), backward Euler is
//! `(M + hD + h²K) φₙ₊₁ = M φₙ + h (w − b − K ξₙ)`, `ξₙ₊₁ = ξₙ + h φₙ₊₁` (eq. 24 for `b`); it is
//! unconditionally stable (tested at h = 1 s). `A` is truncated-SVD inverted once (it has the
//! rank of the admissible directions), so a step costs dense products only.
//!
//! **Contact.** Each end-effector shape point near an obstacle is a contact with rows
//! `G = (n, t₁, t₂)ᵀ·(point velocity)`. With `φ = φ* + A⁻¹Gᵀλ`, projected Gauss–Seidel on the
//! Delassus matrix `G A⁻¹ Gᵀ` (Erleben) finds impulses with `λₙ ≥ 0` and the tangential
//! impulse in the Coulomb disk `|λ_t| ≤ μ λₙ`, targeting a normal velocity that closes at most
//! the current gap within the step (penetration is removed at rate `erp`).
//!
//! **Free base (§6.1).** The base is one rigid body with the whole structure's rest inertia,
//! driven by gravity and by every external wrench applied at the end effectors (loads and
//! contact impulses); end-effector twists stay relative to the base; Coriolis coupling is
//! ignored, as in the paper. Gravity then acts on the base only (in the base's falling frame
//! the end effectors feel none), so the structure's linear momentum changes exactly by the
//! external impulses.
//!
//! **\[fix\] §6.1 "Free-body base link" (the section has no numbered equation; it follows
//! eq. 23).** Read literally, the base moves its *rest* centre of mass with `P/m` while the end
//! effectors (eq. 8, stepped by eq. 23) and internal links
//! (eq. 22) move relative to it: the springs and dampers push the end effectors without any
//! reaction on the base, so the momentum of the whole mechanism, `Σ_l m_l v_l`, swings with
//! the internal motion (0.12 kg·m/s for the `floating` test mechanism with its tip released
//! from 1 cm). Internal forces cannot move the centre of mass, so here the base's momentum `P`
//! is the whole mechanism's and the base is placed each step so that the centre of mass of the
//! *deformed* mechanism (end effectors by eq. 6, internal links by eqs. 22 and 6, each with its
//! own mass) moves by exactly `h P/m`: the base recoils against the internal motion and
//! `Σ_l m_l v_l = P` up to rounding. The recoil is kept out of the base twist used for contact
//! (that still follows `P/m` at the rest centre of mass, as in the paper's `ᶜφ_{k+b}`). Cost:
//! one internal-link update per step for a free base (at the end of the step; the start
//! reuses the last step's unless ξ was edited in between); none for a fixed base.

use faer::Mat;
use glam::DVec3;
use impulse_geom::{Mat6, Pose, SpatialInertia, Twist, Wrench};

use crate::construct::ReducedModel;
use crate::error::Error;
use crate::internal::InternalLinks;
use crate::linalg::{Tsvd, pinv};
use crate::mechanism::{Mechanism, Shape};
use crate::obstacle::Obstacle;
use crate::tol;

/// Threads the internal links' pool may have per core of this machine, at most
/// ([`ReducedSim::set_threads`]): a pool of more threads than cores only makes them wait, and
/// a very large count would hang while its threads start. Default `4`.
pub const MAX_THREADS_PER_CORE: usize = 4;

/// The most threads [`ReducedSim::set_threads`] accepts on this machine:
/// [`MAX_THREADS_PER_CORE`] times its cores (1 if it cannot tell).
#[must_use]
pub fn max_threads() -> usize {
    MAX_THREADS_PER_CORE * std::thread::available_parallelism().map_or(1, usize::from)
}

/// Contact settings.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ContactParams {
    /// Coulomb friction coefficient μ.
    pub friction: f64,
    /// Gauss–Seidel sweeps allowed per step.
    pub iterations: usize,
    /// Sweeps stop when no impulse changes by more than this fraction of the largest.
    pub tolerance: f64,
    /// Fraction of a penetration removed per step (dimensionless, 0–1).
    pub erp: f64,
    /// Shape points closer than this to an obstacle are contacts (m).
    pub margin: f64,
}

impl Default for ContactParams {
    fn default() -> Self {
        ContactParams {
            friction: 0.5,
            iterations: tol::PGS_ITERATIONS,
            tolerance: tol::PGS_TOLERANCE,
            erp: tol::CONTACT_ERP,
            margin: tol::CONTACT_MARGIN,
        }
    }
}

/// The state of a free base: pose and momentum (the base integrates its momentum in the world
/// frame, so external impulses change it exactly and it is conserved without them).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct BaseState {
    /// Pose (world).
    pub pose: Pose,
    /// Linear momentum of the structure (world, kg·m/s).
    pub momentum: DVec3,
    /// Angular momentum about the structure's centre of mass (world, kg·m²/s).
    pub angular_momentum: DVec3,
}

impl BaseState {
    /// Body twist of the base (base frame) for inertia `inertia` (base frame): from
    /// `v_com = P/m`, `ω = (R I_c Rᵀ)⁻¹ L`.
    #[must_use]
    pub fn twist(&self, inertia: &SpatialInertia) -> Twist {
        let r = self.pose.rotation_matrix();
        let iw = r * inertia.inertia_com * r.transpose();
        let w = iw.inverse() * self.angular_momentum;
        let v_com = self.momentum / inertia.mass;
        let c = self.pose.transform_vector(inertia.com);
        Twist::new(
            self.pose.inverse_transform_vector(v_com - w.cross(c)),
            self.pose.inverse_transform_vector(w),
        )
    }

    /// Sets the momenta from a base body twist.
    pub fn set_twist(&mut self, inertia: &SpatialInertia, twist: &Twist) {
        let h = inertia.mul_twist(twist);
        self.add_body_impulse(inertia, &h);
    }

    /// Adds an impulse given as a body wrench (base frame, about the base origin).
    pub fn add_body_impulse(&mut self, inertia: &SpatialInertia, j: &Wrench) {
        let f = self.pose.transform_vector(j.f);
        let tau_com = self.pose.transform_vector(j.tau - inertia.com.cross(j.f));
        self.momentum += f;
        self.angular_momentum += tau_com;
    }
}

/// What a step did.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Active contacts.
    pub contacts: usize,
    /// Gauss–Seidel sweeps used.
    pub sweeps: usize,
}

/// One contact row triple.
struct Contact {
    /// End effector index.
    ee: usize,
    /// Point in the end effector's body frame.
    point: DVec3,
    /// Normal and tangents (world).
    frame: [DVec3; 3],
    /// Signed gap (m).
    gap: f64,
}

/// Where a simulation places its internal links ([`ReducedSim::set_threads`]).
enum Threads {
    /// On the calling thread.
    Caller,
    /// On a pool of its own.
    Pool(rayon::ThreadPool),
}

/// A running reduced simulation of one model.
pub struct ReducedSim {
    /// The model. The factored system matrix and the internal links' kernel are derived from
    /// it in [`ReducedSim::new`]: edit a model before making a simulation of it, not after.
    pub model: ReducedModel,
    /// Time step (s).
    pub h: f64,
    /// End-effector displacement twists ξ (stacked, body frames at the reference poses).
    pub xi: Vec<f64>,
    /// End-effector body velocities φ (stacked).
    pub phi: Vec<f64>,
    /// External body wrenches on the end effectors (stacked), held until changed.
    pub external: Vec<f64>,
    /// Free base state (`None` for a fixed base).
    pub base: Option<BaseState>,
    /// Obstacles.
    pub obstacles: Vec<Obstacle>,
    /// Contact settings.
    pub contact: ContactParams,
    /// Gravity (world).
    pub gravity: DVec3,
    /// `A⁻¹ = (M + hD + h²K)⁺`, factored once.
    a_inv: Mat<f64>,
    /// End-effector inertias and shapes.
    ee_inertia: Vec<SpatialInertia>,
    ee_shapes: Vec<Vec<Shape>>,
    /// Rest pose of the base and its inverse inertia (free base).
    base_rest: Pose,
    base_mass_inv: Mat6,
    /// The internal links' per-step kernel, built once like `a_inv`.
    links: InternalLinks,
    /// Mass and centre of mass (body frame) of every link (free base: the centre of mass of
    /// the deformed mechanism, see [`ReducedSim::deformed_com`]).
    link_mass: Vec<(f64, DVec3)>,
    /// The base link's index.
    base_link: usize,
    /// Links that are neither the base, an end effector nor an internal link, with their rest
    /// poses (carried rigidly with the base frame, as [`crate::study::assemble`] places them).
    other_links: Vec<(usize, Pose)>,
    /// The deformed centre of mass (base frame) computed at the end of the last step, and the
    /// ξ it belongs to: the next step starts from it unless ξ was edited in between.
    com_at: Option<(Vec<f64>, DVec3)>,
    /// The threads that place the internal links ([`ReducedSim::set_threads`]): `None`,
    /// rayon's global pool (every core); one thread, the calling one; more, a pool of them.
    pool: Option<Threads>,
}

impl ReducedSim {
    /// Prepares a simulation of `model` (built from `m`) with step `h`, at rest.
    ///
    /// # Errors
    /// [`Error::Argument`] for a non-positive or non-finite `h`; [`Error::LinearAlgebra`] if
    /// the system matrix cannot be factored.
    pub fn new(m: &Mechanism, model: ReducedModel, h: f64) -> Result<Self, Error> {
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::Argument(format!("time step {h} is not positive")));
        }
        let n = model.mass.nrows();
        // [fix] eq. 23: A = M + hD + h²K for eq. 8 as written.
        let a = &model.mass + &model.damping * h + &model.stiffness * (h * h);
        let a_inv = pinv(a.as_ref(), Tsvd::default())?.inverse;
        let base = match m.base_kind {
            crate::desc::BaseDesc::Fixed => None,
            crate::desc::BaseDesc::Free => Some(BaseState {
                pose: model.base_pose,
                momentum: DVec3::ZERO,
                angular_momentum: DVec3::ZERO,
            }),
        };
        let base_mass_inv = model
            .base_inertia
            .to_mat6()
            .try_inverse()
            .unwrap_or(Mat6::ZERO);
        if base.is_some() && base_mass_inv == Mat6::ZERO {
            return Err(Error::Argument(
                "free base: the structure's inertia is singular".to_owned(),
            ));
        }
        Ok(ReducedSim {
            h,
            xi: vec![0.0; n],
            phi: vec![0.0; n],
            external: vec![0.0; n],
            base,
            obstacles: Vec::new(),
            contact: ContactParams::default(),
            gravity: m.gravity,
            a_inv,
            ee_inertia: model
                .end_effectors
                .iter()
                .map(|&e| m.links[e].inertia)
                .collect(),
            ee_shapes: model
                .end_effectors
                .iter()
                .map(|&e| m.links[e].shapes.clone())
                .collect(),
            base_rest: model.base_pose,
            base_mass_inv,
            links: InternalLinks::new(&model),
            link_mass: m
                .links
                .iter()
                .map(|l| (l.inertia.mass, l.inertia.com))
                .collect(),
            base_link: m.base,
            other_links: (0..m.links.len())
                .filter(|l| {
                    *l != m.base && !model.end_effectors.contains(l) && !model.internal.contains(l)
                })
                .map(|l| (l, m.links[l].rest))
                .collect(),
            com_at: None,
            pool: None,
            model,
        })
    }

    /// Places the internal links on `threads` threads of the simulation's own (instead of
    /// rayon's global pool, every core). On a small mechanism one thread is the fastest
    /// (docs/forks.md, Table 1), and its step time does not wait on a second core.
    ///
    /// # Errors
    /// [`Error::Argument`] for zero threads, more than [`max_threads`], or when the pool
    /// cannot be built.
    pub fn set_threads(&mut self, threads: usize) -> Result<(), Error> {
        if threads == 0 {
            return Err(Error::Argument("threads: need at least one".to_owned()));
        }
        let most = max_threads();
        if threads > most {
            return Err(Error::Argument(format!(
                "threads: {threads} asked, at most {most} on this machine \
                 ({MAX_THREADS_PER_CORE} per core): more threads than cores only wait"
            )));
        }
        self.pool = Some(if threads == 1 {
            Threads::Caller
        } else {
            Threads::Pool(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .map_err(|e| Error::Argument(format!("threads: {e}")))?,
            )
        });
        Ok(())
    }

    /// `self.links.update` on the simulation's threads.
    fn update_links(&self, frame: &Pose, out: &mut [Pose]) {
        match &self.pool {
            Some(Threads::Caller) => self.links.update_on(true, &self.xi, frame, out),
            Some(Threads::Pool(pool)) => pool.install(|| self.links.update(&self.xi, frame, out)),
            None => self.links.update(&self.xi, frame, out),
        }
    }

    /// World pose of end effector `i`: `H_b H_b0⁻¹ H_e exp(ξ_e)` (eq. 6; `H_b = H_b0` for a
    /// fixed base).
    #[must_use]
    pub fn end_effector_pose(&self, i: usize) -> Pose {
        let local = self.end_effector_local(i);
        match &self.base {
            Some(b) => b.pose * self.base_rest.inverse() * local,
            None => local,
        }
    }

    fn twist(&self, v: &[f64], i: usize) -> Twist {
        Twist::from_array(core::array::from_fn(|r| v[6 * i + r]))
    }

    /// Writes every internal link's world pose (one per `model.internal`) from the current
    /// end-effector twists, in parallel (see [`crate::internal`]).
    pub fn internal_poses(&self, out: &mut [Pose]) {
        let frame = self
            .base
            .map_or(Pose::IDENTITY, |b| b.pose * self.base_rest.inverse());
        self.update_links(&frame, out);
    }

    /// Per-step error estimate: the relative constraint error (§8.2) of the reconstructed
    /// mechanism (end effectors and every internal link), so a user sees when the reduced
    /// model leaves its range. Costs one internal-link update.
    #[must_use]
    pub fn constraint_error(&self, m: &Mechanism) -> f64 {
        let mut internal = vec![Pose::IDENTITY; self.model.internal.len()];
        self.internal_poses(&mut internal);
        let ee: Vec<Pose> = (0..self.model.end_effectors.len())
            .map(|i| self.end_effector_pose(i))
            .collect();
        let mut poses = crate::study::assemble(m, &self.model, &ee, &internal);
        if let Some(b) = &self.base {
            poses[m.base] = b.pose;
        }
        crate::study::constraint_error(m, &poses)
    }

    /// Pose of end effector `i` relative to the base at rest, `H_e exp(ξ_e)` (eq. 6).
    fn end_effector_local(&self, i: usize) -> Pose {
        self.model.reference[i] * Pose::exp(&self.twist(&self.xi, i))
    }

    /// Centre of mass of the deformed mechanism in the base's body frame, for the current ξ:
    /// `Σ_l m_l H_b0⁻¹ H_l(ξ) c_l / Σ_l m_l`, with `H_l` the end effectors' poses of eq. 6 and
    /// the internal links' of eqs. 22 and 6 (relative to the base at rest), and `c_l` each
    /// link's own centre of mass. Costs one internal-link update.
    fn deformed_com(&self) -> DVec3 {
        let mut internal = vec![Pose::IDENTITY; self.model.internal.len()];
        self.update_links(&Pose::IDENTITY, &mut internal);
        let mass_com = |l: usize, pose: &Pose| {
            let (mass, com) = self.link_mass[l];
            pose.transform_point(com) * mass
        };
        let mut sum = mass_com(self.base_link, &self.base_rest);
        let mut mass = self.link_mass[self.base_link].0;
        for (i, &e) in self.model.end_effectors.iter().enumerate() {
            sum += mass_com(e, &self.end_effector_local(i));
            mass += self.link_mass[e].0;
        }
        for (k, &l) in self.model.internal.iter().enumerate() {
            sum += mass_com(l, &internal[k]);
            mass += self.link_mass[l].0;
        }
        for (l, rest) in &self.other_links {
            let l = *l;
            sum += mass_com(l, rest);
            mass += self.link_mass[l].0;
        }
        self.base_rest.inverse_transform_point(sum / mass)
    }

    /// Total energy of the end-effector system, `½φᵀMφ + ½ξᵀKξ` (J), relative to the bias.
    #[must_use]
    pub fn energy(&self) -> f64 {
        let quad = |m: &Mat<f64>, x: &[f64]| -> f64 {
            let n = x.len();
            (0..n)
                .map(|i| x[i] * (0..n).map(|j| m[(i, j)] * x[j]).sum::<f64>())
                .sum::<f64>()
                * 0.5
        };
        quad(&self.model.mass, &self.phi) + quad(&self.model.stiffness, &self.xi)
    }

    /// Linear momentum of the structure (world, kg·m/s): the free base carries the whole
    /// structure's mass (§6.1); zero for a fixed base.
    #[must_use]
    pub fn linear_momentum(&self) -> DVec3 {
        self.base.map_or(DVec3::ZERO, |b| b.momentum)
    }

    /// The contacts at the current state.
    fn contacts(&self) -> Vec<Contact> {
        let mut out = Vec::new();
        for (i, shapes) in self.ee_shapes.iter().enumerate() {
            if shapes.is_empty() || self.obstacles.is_empty() {
                continue;
            }
            let pose = self.end_effector_pose(i);
            let mut points: Vec<(DVec3, f64)> = Vec::new();
            for s in shapes {
                match s {
                    Shape::Sphere { center, radius } => points.push((*center, *radius)),
                    Shape::Box {
                        center,
                        half_extents,
                    } => {
                        for k in 0..8 {
                            let sgn = DVec3::new(
                                if k & 1 == 0 { -1.0 } else { 1.0 },
                                if k & 2 == 0 { -1.0 } else { 1.0 },
                                if k & 4 == 0 { -1.0 } else { 1.0 },
                            );
                            points.push((*center + *half_extents * sgn, 0.0));
                        }
                    }
                }
            }
            for (local, radius) in points {
                let world = pose.transform_point(local);
                for ob in &self.obstacles {
                    let (d, n) = ob.distance(world);
                    let gap = d - radius;
                    if gap < self.contact.margin {
                        let t1 = n.any_orthonormal_vector();
                        let t2 = n.cross(t1);
                        let contact_world = world - n * radius;
                        out.push(Contact {
                            ee: i,
                            point: pose.inverse_transform_point(contact_world),
                            frame: [n, t1, t2],
                            gap,
                        });
                    }
                }
            }
        }
        out
    }

    /// Advances one step of length `h`.
    pub fn step(&mut self) -> StepReport {
        let n = self.xi.len();
        let ne = self.model.end_effectors.len();
        let h = self.h;
        // Free base: where the deformed mechanism's centre of mass is now (world).
        let com_now = self.base.map(|b| {
            let local = match &self.com_at {
                Some((xi, com)) if *xi == self.xi => *com,
                _ => self.deformed_com(),
            };
            b.pose.transform_point(local)
        });
        // Wrenches on the end effectors: held external loads, gravity (fixed base only).
        let mut w = self.external.clone();
        if self.base.is_none() {
            for i in 0..ne {
                let pose = self.end_effector_pose(i);
                let inertia = &self.ee_inertia[i];
                let f = pose.inverse_transform_vector(self.gravity * inertia.mass);
                let g = Wrench::new(f, inertia.com.cross(f)).to_array();
                for r in 0..6 {
                    w[6 * i + r] += g[r];
                }
            }
        }
        // Free velocity (eq. 24 with the [fix]ed eq. 23).
        let mut rhs = vec![0.0; n];
        for (r, x) in rhs.iter_mut().enumerate() {
            let mut s = 0.0;
            for c in 0..n {
                s += self.model.mass[(r, c)] * self.phi[c]
                    - h * self.model.stiffness[(r, c)] * self.xi[c];
            }
            *x = s + h * (w[r] - self.model.bias[r]);
        }
        let mut phi: Vec<f64> = (0..n)
            .map(|r| (0..n).map(|c| self.a_inv[(r, c)] * rhs[c]).sum())
            .collect();
        // Free base: gravity on the whole structure and the external wrenches at the end
        // effectors change its momentum (world); its twist follows from the momentum.
        let mut base_twist = None;
        if let Some(b) = self.base.as_mut() {
            let inertia = &self.model.base_inertia;
            let f = b.pose.inverse_transform_vector(self.gravity * inertia.mass);
            let mut wb = Wrench::new(f, inertia.com.cross(f));
            for i in 0..ne {
                let rel = self.base_rest.inverse() * self.model.reference[i];
                wb += rel.transform_wrench(&Wrench::from_array(core::array::from_fn(|r| {
                    self.external[6 * i + r]
                })));
            }
            b.add_body_impulse(inertia, &(wb * h));
            base_twist = Some(b.twist(inertia));
        }
        let contacts = self.contacts();
        let mut report = StepReport {
            contacts: contacts.len(),
            sweeps: 0,
        };
        if !contacts.is_empty() {
            let before = base_twist;
            report.sweeps = self.solve_contacts(&contacts, &mut phi, base_twist.as_mut());
            if let (Some(b), Some(t0), Some(t1)) = (self.base.as_mut(), before, base_twist) {
                // The contact impulse on the base: M_b Δφ_b (body frame).
                let j = self.model.base_inertia.mul_twist(&(t1 - t0));
                b.add_body_impulse(&self.model.base_inertia, &j);
            }
        }
        for (x, p) in self.xi.iter_mut().zip(&phi) {
            *x += h * p;
        }
        self.phi = phi;
        if let Some(com_now) = com_now {
            let com_new = self.deformed_com();
            self.com_at = Some((self.xi.clone(), com_new));
            let b = self.base.as_mut().expect("free base");
            // [fix] §6.1: the centre of mass of the whole deformed mechanism moves with P/m,
            // exactly over the step for a constant momentum, whatever the internal motion did
            // (internal forces do not move it); the base turns with ω (world) and is placed
            // so that its deformed centre of mass `com_new` (base frame, at ξₙ₊₁) lands there.
            let inertia = &self.model.base_inertia;
            let t = b.twist(inertia);
            let com = com_now + b.momentum * (h / inertia.mass);
            let w = b.pose.transform_vector(t.w);
            let rotation = (impulse_geom::se3::so3_exp(w * h) * b.pose.rotation).normalize();
            b.pose = Pose {
                rotation,
                translation: com - rotation * com_new,
            };
        }
        report
    }

    /// Projected Gauss–Seidel on `G A⁻¹ Gᵀ`; applies the impulses to `phi` (and the base).
    fn solve_contacts(
        &self,
        contacts: &[Contact],
        phi: &mut [f64],
        mut base: Option<&mut Twist>,
    ) -> usize {
        let n = phi.len();
        let nc = contacts.len();
        // Rows of G: (ee columns: 6-vector) and (base columns: 6-vector).
        let mut g_ee = vec![[0.0; 6]; 3 * nc];
        let mut g_base = vec![[0.0; 6]; 3 * nc];
        for (k, c) in contacts.iter().enumerate() {
            let pose = self.end_effector_pose(c.ee);
            for (d, dir) in c.frame.iter().enumerate() {
                // Point velocity along dir: dir·R(v + ω × p) = (Rᵀdir)·v + (p × Rᵀdir)·ω.
                let local = pose.inverse_transform_vector(*dir);
                let row = Wrench::new(local, c.point.cross(local)).to_array();
                g_ee[3 * k + d] = row;
                if let Some(b) = &self.base {
                    let pb = b
                        .pose
                        .inverse_transform_point(pose.transform_point(c.point));
                    let lb = b.pose.inverse_transform_vector(*dir);
                    g_base[3 * k + d] = Wrench::new(lb, pb.cross(lb)).to_array();
                }
            }
        }
        // A⁻¹Gᵀ columns for the end effectors (n-vectors) and M_b⁻¹ Gᵀ for the base.
        let ainv_gt: Vec<Vec<f64>> = (0..3 * nc)
            .map(|row| {
                let e = contacts[row / 3].ee;
                (0..n)
                    .map(|r| {
                        (0..6)
                            .map(|c| self.a_inv[(r, 6 * e + c)] * g_ee[row][c])
                            .sum()
                    })
                    .collect()
            })
            .collect();
        let minv_gt: Vec<[f64; 6]> = g_base
            .iter()
            .map(|g| self.base_mass_inv.mul_array(g))
            .collect();
        let rowv = |row: usize, phi: &[f64], base: &Option<&mut Twist>| -> f64 {
            let e = contacts[row / 3].ee;
            let mut v: f64 = (0..6).map(|c| g_ee[row][c] * phi[6 * e + c]).sum();
            if let Some(b) = base {
                let t = b.to_array();
                v += (0..6).map(|c| g_base[row][c] * t[c]).sum::<f64>();
            }
            v
        };
        // Delassus diagonal.
        let diag: Vec<f64> = (0..3 * nc)
            .map(|row| {
                let e = contacts[row / 3].ee;
                let a: f64 = (0..6).map(|c| g_ee[row][c] * ainv_gt[row][6 * e + c]).sum();
                let b: f64 = (0..6).map(|c| g_base[row][c] * minv_gt[row][c]).sum();
                a + b
            })
            .collect();
        let mut lambda = vec![0.0; 3 * nc];
        let apply = |row: usize, dl: f64, phi: &mut [f64], base: &mut Option<&mut Twist>| {
            for (p, a) in phi.iter_mut().zip(&ainv_gt[row]) {
                *p += a * dl;
            }
            if let Some(b) = base {
                **b += Twist::from_array(minv_gt[row]) * dl;
            }
        };
        let h = self.h;
        let mut sweeps = 0;
        for _ in 0..self.contact.iterations {
            sweeps += 1;
            let mut change = 0.0_f64;
            let mut largest = 0.0_f64;
            for (k, c) in contacts.iter().enumerate() {
                let rn = 3 * k;
                // Normal: close at most the gap this step; push out a fraction of penetration.
                let target = if c.gap >= 0.0 {
                    -c.gap / h
                } else {
                    -self.contact.erp * c.gap / h
                };
                let vn = rowv(rn, phi, &base);
                if diag[rn] > 0.0 {
                    let new = (lambda[rn] - (vn - target) / diag[rn]).max(0.0);
                    let dl = new - lambda[rn];
                    lambda[rn] = new;
                    apply(rn, dl, phi, &mut base);
                    change = change.max(dl.abs());
                }
                // Friction: both tangents, projected on the Coulomb disk.
                let limit = self.contact.friction * lambda[rn];
                let mut lt = [lambda[rn + 1], lambda[rn + 2]];
                for (d, l) in lt.iter_mut().enumerate() {
                    let row = rn + 1 + d;
                    if diag[row] > 0.0 {
                        *l -= rowv(row, phi, &base) / diag[row];
                    }
                }
                let norm = (lt[0] * lt[0] + lt[1] * lt[1]).sqrt();
                if norm > limit {
                    let s = if norm > 0.0 { limit / norm } else { 0.0 };
                    lt = [lt[0] * s, lt[1] * s];
                }
                for (d, l) in lt.iter().enumerate() {
                    let row = rn + 1 + d;
                    let dl = l - lambda[row];
                    lambda[row] = *l;
                    apply(row, dl, phi, &mut base);
                    change = change.max(dl.abs());
                }
                largest = largest.max(lambda[rn]);
            }
            if change <= self.contact.tolerance * largest.max(f64::MIN_POSITIVE) {
                break;
            }
        }
        sweeps
    }
}

#[cfg(test)]
#[path = "dynamics_tests.rs"]
mod tests;
