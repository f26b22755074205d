//! Test support: random multibodies and dense references computed independently of the
//! recursions (world poses by composing `Pose`s of the builder's description, Jacobians from
//! world joint axes, `M = Σ Jᵀ M_link J`).

use faer::Mat;
use glam::{DMat3, DQuat, DVec3};
use impulse_geom::{Pose, SpatialInertia, Twist};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use crate::model::{BaseKind, JointSpec, JointType, Model, ModelBuilder};

pub fn rng(seed: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

pub fn vec3(rng: &mut Xoshiro256PlusPlus, s: f64) -> DVec3 {
    DVec3::new(
        rng.random_range(-s..s),
        rng.random_range(-s..s),
        rng.random_range(-s..s),
    )
}

pub fn unit(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
    loop {
        let v = vec3(rng, 1.0);
        let n = v.length();
        if n > 0.1 && n <= 1.0 {
            return v / n;
        }
    }
}

pub fn quat(rng: &mut Xoshiro256PlusPlus) -> DQuat {
    loop {
        let q = DQuat::from_xyzw(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let n = q.length();
        if n > 0.1 && n <= 1.0 {
            return q / n;
        }
    }
}

/// A random physical inertia: box-like principal moments (triangle inequality holds), random
/// orientation and centre of mass.
pub fn inertia(rng: &mut Xoshiro256PlusPlus) -> SpatialInertia {
    let m = rng.random_range(0.2..5.0);
    let (a, b, c) = (
        rng.random_range(0.05..0.6),
        rng.random_range(0.05..0.6),
        rng.random_range(0.05..0.6),
    );
    let d = DVec3::new(b * b + c * c, a * a + c * c, a * a + b * b) * (m / 12.0);
    let r = DMat3::from_quat(quat(rng));
    SpatialInertia::new(
        m,
        vec3(rng, 0.3),
        r * DMat3::from_diagonal(d) * r.transpose(),
    )
}

/// The builder's description of a random model, kept for the references.
#[derive(Clone, Debug)]
pub struct Spec {
    pub base: BaseKind,
    pub gravity: DVec3,
    pub links: Vec<(String, SpatialInertia)>,
    /// (parent link index, child link index, joint).
    pub joints: Vec<(usize, usize, JointSpec)>,
}

impl Spec {
    pub fn builder(&self) -> ModelBuilder {
        let mut b = ModelBuilder::new(self.base);
        b.gravity(self.gravity);
        for (n, i) in &self.links {
            b.link(n, *i);
        }
        for (_, _, j) in &self.joints {
            b.joint(j.clone());
        }
        b
    }

    pub fn model(&self) -> Model {
        self.builder().build().expect("valid random model")
    }
}

/// Floating base for even cases, fixed for odd ones (random tests cover both alike).
pub fn alternating_base(case: usize) -> BaseKind {
    if case % 2 == 0 {
        BaseKind::Floating
    } else {
        BaseKind::Fixed
    }
}

/// A random tree (or chain) with `n_moving` moving joints; about one link in eight is welded
/// on by a fixed joint. Joint types: 70 % revolute, 30 % prismatic (if `prismatic`).
pub fn random_spec(
    rng: &mut Xoshiro256PlusPlus,
    n_moving: usize,
    base: BaseKind,
    chain: bool,
    prismatic: bool,
) -> Spec {
    let mut links = vec![("root".to_owned(), inertia(rng))];
    let mut joints = Vec::new();
    let mut moving = 0;
    let mut k = 0;
    while moving < n_moving {
        k += 1;
        let parent = if chain {
            links.len() - 1
        } else {
            rng.random_range(0..links.len())
        };
        let child = links.len();
        let name = format!("l{k}");
        links.push((name.clone(), inertia(rng)));
        let origin = Pose::new(quat(rng), vec3(rng, 0.5));
        let pname = links[parent].0.clone();
        let jname = format!("j{k}");
        let fixed = rng.random_range(0.0..1.0) < 0.125;
        let spec = if fixed {
            JointSpec::fixed(&jname, &pname, &name, origin)
        } else {
            moving += 1;
            let axis = unit(rng) * rng.random_range(0.5..2.0);
            if prismatic && rng.random_range(0.0..1.0) < 0.3 {
                JointSpec::prismatic(&jname, &pname, &name, origin, axis)
            } else {
                JointSpec::revolute(&jname, &pname, &name, origin, axis)
            }
        };
        joints.push((parent, child, spec));
    }
    Spec {
        base,
        gravity: DVec3::new(0.3, -0.2, -9.81),
        links,
        joints,
    }
}

/// A random state `(q, v)` for `model`.
pub fn random_state(rng: &mut Xoshiro256PlusPlus, model: &Model) -> (Vec<f64>, Vec<f64>) {
    let mut q: Vec<f64> = (0..model.nq())
        .map(|_| rng.random_range(-3.0..3.0))
        .collect();
    let v: Vec<f64> = (0..model.nv())
        .map(|_| rng.random_range(-2.0..2.0))
        .collect();
    if model.is_floating() {
        let r = quat(rng);
        q[3..7].copy_from_slice(&[r.x, r.y, r.z, r.w]);
    }
    (q, v)
}

/// Independent kinematics of a [`Spec`]: world pose of every link, and for every link the
/// 6 × nv Jacobian of its frame's twist in world axes (linear part = velocity of the link-frame
/// origin, angular part = angular velocity).
pub struct Reference {
    pub poses: Vec<Pose>,
    pub jacobians: Vec<Mat<f64>>,
}

pub fn reference(spec: &Spec, model: &Model, q: &[f64]) -> Reference {
    let nl = spec.links.len();
    let nv = model.nv();
    let qo = model.nq() - model.joint_count();
    let vo = model.base_dofs();
    let mut poses = vec![Pose::IDENTITY; nl];
    // Joint (world axis point, world axis, kind, v index) on the path of each link.
    let mut chain: Vec<Vec<(DVec3, DVec3, bool, usize)>> = vec![Vec::new(); nl];
    if spec.base == BaseKind::Floating {
        poses[0] = Pose::new(
            DQuat::from_xyzw(q[3], q[4], q[5], q[6]),
            DVec3::new(q[0], q[1], q[2]),
        );
    }
    // Joints are listed parent-before-child by construction.
    for (p, c, j) in &spec.joints {
        let base = poses[*p] * j.origin;
        let mut path = chain[*p].clone();
        poses[*c] = match j.joint_type {
            JointType::Fixed => base,
            JointType::Revolute { axis } => {
                let idx = model.joint_index(&j.name).unwrap();
                let u = axis.normalize();
                path.push((base.translation, base.rotation * u, true, vo + idx));
                base * Pose::from_rotation(DQuat::from_axis_angle(u, q[qo + idx]))
            }
            JointType::Prismatic { axis } => {
                let idx = model.joint_index(&j.name).unwrap();
                let u = axis.normalize();
                path.push((base.translation, base.rotation * u, false, vo + idx));
                base * Pose::from_translation(u * q[qo + idx])
            }
        };
        chain[*c] = path;
    }
    let mut jacobians = Vec::with_capacity(nl);
    for l in 0..nl {
        let mut jac = Mat::<f64>::zeros(6, nv);
        let o = poses[l].translation;
        let mut set = |col: usize, t: Twist| {
            for (r, x) in t.to_array().iter().enumerate() {
                jac[(r, col)] += *x;
            }
        };
        if spec.base == BaseKind::Floating {
            let rb = poses[0].rotation_matrix();
            let ob = poses[0].translation;
            for k in 0..3 {
                set(k, Twist::new(rb.col(k), DVec3::ZERO));
                set(3 + k, Twist::new(rb.col(k).cross(o - ob), rb.col(k)));
            }
        }
        for (point, axis, revolute, col) in &chain[l] {
            if *revolute {
                set(*col, Twist::new(axis.cross(o - *point), *axis));
            } else {
                set(*col, Twist::new(*axis, DVec3::ZERO));
            }
        }
        jacobians.push(jac);
    }
    Reference { poses, jacobians }
}

/// `M = Σ_links J_lᵀ M_l J_l` with `M_l` the link's inertia in world axes at its frame origin.
pub fn reference_mass_matrix(spec: &Spec, r: &Reference) -> Mat<f64> {
    let nv = r.jacobians[0].ncols();
    let mut m = Mat::<f64>::zeros(nv, nv);
    let start = usize::from(spec.base == BaseKind::Fixed);
    for l in start..spec.links.len() {
        let i = &spec.links[l].1;
        let rot = r.poses[l].rotation_matrix();
        let world_axes =
            SpatialInertia::new(i.mass, rot * i.com, rot * i.inertia_com * rot.transpose());
        let m6 = world_axes.to_mat6().to_rows();
        let m6 = Mat::<f64>::from_fn(6, 6, |a, b| m6[a][b]);
        let j = &r.jacobians[l];
        m += j.transpose() * &m6 * j;
    }
    m
}

/// Gravity forces `G = −Σ J_comᵀ m g` (nv), from the reference Jacobians.
pub fn reference_gravity(spec: &Spec, r: &Reference) -> Vec<f64> {
    let nv = r.jacobians[0].ncols();
    let mut g = vec![0.0; nv];
    let start = usize::from(spec.base == BaseKind::Fixed);
    for l in start..spec.links.len() {
        let i = &spec.links[l].1;
        let c = r.poses[l].rotation_matrix() * i.com;
        let j = &r.jacobians[l];
        for (col, gc) in g.iter_mut().enumerate() {
            let lin = DVec3::new(j[(0, col)], j[(1, col)], j[(2, col)]);
            let ang = DVec3::new(j[(3, col)], j[(4, col)], j[(5, col)]);
            *gc -= (lin + ang.cross(c)).dot(spec.gravity * i.mass);
        }
    }
    g
}

pub fn mat_max_abs(m: &Mat<f64>) -> f64 {
    let mut s = 0.0f64;
    for r in 0..m.nrows() {
        for c in 0..m.ncols() {
            s = s.max(m[(r, c)].abs());
        }
    }
    s
}

pub fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

pub fn mat_vec(m: &Mat<f64>, x: &[f64]) -> Vec<f64> {
    (0..m.nrows())
        .map(|r| (0..m.ncols()).map(|c| m[(r, c)] * x[c]).sum())
        .collect()
}
