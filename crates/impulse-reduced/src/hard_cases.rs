//! The hard cases of the reduction as seeded random families, with the independent references
//! that judge them: chains, trees, loops, ladders, near-singular chains (joints nearly on one
//! line) and stiff mechanisms (compliances over eight decades). `cargo xtask validate` runs
//! the set of fifty ([`acceptance_set`], case `F1-random-mechanisms`) and the tests a part of
//! it.
//!
//! Two checks per mechanism:
//! - **Linear statics**: the reduced model's static end-effector displacement `C w`
//!   ([`ReducedModel::static_twists`]) against an independent Schur complement at rest,
//!   [`schur_compliance`]: the joints' spatial screws written from the anchors and axes (not
//!   the crate's Jacobians), the loop closures as equality constraints, `C_θ = Z (ZᵀKZ)⁻¹ Zᵀ`
//!   over the null space Z of the closures.
//! - **Nonlinear statics**: [`crate::reference::solve_statics`] (what `impulse reduce
//!   --static` runs) against a plain Newton on the same equations ([`plain_newton`]: central
//!   differences for the tangent, fixed load increments, full steps, a truncated-SVD solve —
//!   the kind of solve a user writes to check it), under growing loads: the solver must
//!   converge wherever the plain one does, and agree with it there.
//!
//! The generator is its own (SplitMix64), so the families are the same on every platform and
//! need no random-number crate outside the tests.

use faer::Mat;
use glam::DVec3;
use impulse_geom::Twist;

use crate::construct::{ConstructOptions, ReducedModel};
use crate::desc::{JointDesc, LinkDesc, MechanismDesc};
use crate::error::Error;
use crate::linalg::{Tsvd, pinv};
use crate::mechanism::{Direction, Mechanism};
use crate::reference::kinematics::{
    Configuration, body_jacobian, link_poses, loop_jacobian, loop_residual,
};
use crate::reference::{Load, StaticOptions, solve_statics};

/// SplitMix64 (Steele, Lea & Flood): a seeded 64-bit generator, enough for test families.
#[derive(Clone, Debug)]
pub struct SplitMix(u64);

impl SplitMix {
    /// A generator from `seed`.
    #[must_use]
    pub fn new(seed: u64) -> Self {
        SplitMix(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        // 53 random bits as a fraction of 2⁵³.
        let u = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * u
    }

    /// Uniform in `lo..hi` (integers; `lo < hi`).
    pub fn below(&mut self, lo: usize, hi: usize) -> usize {
        lo + (self.next_u64() % (hi - lo) as u64) as usize
    }

    /// A unit vector, uniform on the sphere.
    pub fn direction(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                self.uniform(-1.0, 1.0),
                self.uniform(-1.0, 1.0),
                self.uniform(-1.0, 1.0),
            );
            let n = v.length();
            if n > 0.1 && n <= 1.0 {
                return v / n;
            }
        }
    }

    /// `10^x`, x uniform in `decades`.
    pub fn log_uniform(&mut self, decades: (f64, f64)) -> f64 {
        10f64.powf(self.uniform(decades.0, decades.1))
    }
}

/// The kinds of mechanism in the families.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Family {
    /// A serial chain of random joints (hinge, slider, ball, weld).
    Chain,
    /// A branching tree, end effectors among its leaves.
    Tree,
    /// A tree with one or two loops closed between branches by a hinge or a ball.
    Loop,
    /// A spring ladder with tilted rungs and jittered anchors (near-redundant closures).
    Ladder,
    /// A chain of ball joints whose last anchor is off the line of the others by 1e-3 to
    /// 1e-8 m (near-singular: the end effector can hardly stretch along it).
    NearSingular,
    /// A tree with compliances over eight decades (1e-9 to 1e-1).
    Stiff,
}

impl Family {
    /// Its name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Family::Chain => "chain",
            Family::Tree => "tree",
            Family::Loop => "loop",
            Family::Ladder => "ladder",
            Family::NearSingular => "near-singular",
            Family::Stiff => "stiff",
        }
    }
}

/// A joint of `kind` (0 hinge, 1 slider, 2 ball, 3 weld) from `parent` to `child` at
/// `anchor`, random axis, each direction's compliance log-uniform in `decades`.
fn joint(
    rng: &mut SplitMix,
    kind: usize,
    [name, parent, child]: [&str; 3],
    anchor: DVec3,
    decades: (f64, f64),
) -> JointDesc {
    let a = anchor.to_array();
    let j = match kind {
        0 => JointDesc::hinge(name, parent, child, a, rng.direction().to_array()),
        1 => JointDesc::slider(name, parent, child, a, rng.direction().to_array()),
        2 => JointDesc::ball(name, parent, child, a),
        _ => JointDesc::weld(name, parent, child, a),
    };
    let dof = [1, 1, 3, 6][kind];
    let c: Vec<f64> = (0..dof).map(|_| rng.log_uniform(decades)).collect();
    j.compliance(&c)
}

fn link_name(i: usize) -> String {
    if i == 0 {
        "base".to_owned()
    } else {
        format!("l{i}")
    }
}

/// A random link at `p` with a random orientation, mass and inertia.
fn random_link(rng: &mut SplitMix, i: usize, p: DVec3) -> LinkDesc {
    let axis = rng.direction();
    let angle = rng.uniform(-3.0, 3.0);
    let (s, c) = (0.5 * angle).sin_cos();
    let m = rng.uniform(0.1, 2.0);
    LinkDesc::new(&link_name(i), p.to_array())
        .rotation([axis.x * s, axis.y * s, axis.z * s, c])
        .mass(
            m,
            [
                m * rng.uniform(0.01, 0.1),
                m * rng.uniform(0.01, 0.1),
                m * rng.uniform(0.01, 0.1),
            ],
        )
}

/// Whether link `a` is a tree ancestor of link `b` (`parent[k]` is link k's parent, the base
/// 0 its own root).
pub(crate) fn is_tree_ancestor(parent: &[usize], a: usize, mut b: usize) -> bool {
    while b != 0 {
        b = parent[b];
        if b == a {
            return true;
        }
    }
    false
}

/// Adds joint number `*joints` of `kind` between links `links.0` (parent) and `links.1` at
/// `anchor`, and counts it.
fn add_joint(
    d: &mut MechanismDesc,
    rng: &mut SplitMix,
    joints: &mut usize,
    kind: usize,
    links: (usize, usize),
    anchor: DVec3,
    decades: (f64, f64),
) {
    let names = [format!("j{joints}"), link_name(links.0), link_name(links.1)];
    *joints += 1;
    d.joint(joint(
        rng,
        kind,
        [&names[0], &names[1], &names[2]],
        anchor,
        decades,
    ));
}

/// A tree of `n` links (parents drawn among the earlier links; `chain` forces a chain), joint
/// compliances in `decades`, `loops` extra joints between branches, up to `max_ee` end
/// effectors among the leaves.
fn tree(
    rng: &mut SplitMix,
    name: &str,
    n: usize,
    chain: bool,
    loops: usize,
    max_ee: usize,
    decades: (f64, f64),
) -> MechanismDesc {
    let mut d = MechanismDesc::new(name);
    d.link(LinkDesc::new("base", [0.0; 3]));
    let mut pos = vec![DVec3::ZERO];
    let mut parent = vec![0usize];
    let mut has_child = vec![false; n + 1];
    let mut joints = 0;
    for i in 1..=n {
        let p = if chain { i - 1 } else { rng.below(0, i) };
        let at = pos[p]
            + DVec3::new(
                rng.uniform(-0.6, 0.6),
                rng.uniform(-0.6, 0.6),
                rng.uniform(-0.6, 0.6),
            );
        pos.push(at);
        parent.push(p);
        d.link(random_link(rng, i, at));
        let t = rng.uniform(0.0, 1.0);
        let anchor = pos[p] + (at - pos[p]) * t;
        let kind = rng.below(0, 4);
        add_joint(&mut d, rng, &mut joints, kind, (p, i), anchor, decades);
        has_child[p] = true;
    }
    let mut made = 0;
    for _ in 0..20 * loops {
        if made == loops || n < 3 {
            break;
        }
        let c = rng.below(2, n + 1);
        let p = rng.below(1, c);
        if is_tree_ancestor(&parent, p, c) {
            continue;
        }
        let anchor = pos[p] + (pos[c] - pos[p]) * rng.uniform(0.0, 1.0);
        let kind = [0, 2][rng.below(0, 2)];
        add_joint(&mut d, rng, &mut joints, kind, (p, c), anchor, decades);
        has_child[p] = true;
        made += 1;
    }
    let mut leaves: Vec<usize> = (1..=n).filter(|&i| !has_child[i]).collect();
    let k = rng.below(1, max_ee.min(leaves.len()) + 1);
    while leaves.len() > k {
        let i = rng.below(0, leaves.len());
        leaves.remove(i);
    }
    for l in leaves {
        d.end_effector(&link_name(l));
    }
    d
}

/// A spring ladder of `levels` levels (as `testutil::random_ladder` in the tests): ball-jointed
/// posts, a hinge rung per level tilted up to ~6° from the ladder's normal, a top bar on two
/// balls; anchors jittered by up to 1 cm; compliances over 1e-4 … 1e-1.
fn ladder(rng: &mut SplitMix, name: &str, levels: usize) -> MechanismDesc {
    let mut d = MechanismDesc::new(name);
    let w = rng.uniform(0.1, 0.5);
    let h = rng.uniform(0.05, 0.2);
    let jitter = |rng: &mut SplitMix| {
        DVec3::new(
            rng.uniform(-0.01, 0.01),
            rng.uniform(-0.01, 0.01),
            rng.uniform(-0.01, 0.01),
        )
    };
    d.link(LinkDesc::new("base", [0.0; 3]));
    for i in 0..levels {
        let z = h * (i as f64 + 0.5);
        for (s, x) in [("L", -w / 2.0), ("R", w / 2.0)] {
            d.link(LinkDesc::new(&format!("{s}{i}"), [x, 0.0, z]).mass(0.1, [1e-3, 1e-3, 1e-4]));
        }
    }
    let top = h * levels as f64;
    d.link(LinkDesc::new("top", [0.0, 0.0, top]).mass(0.1, [1e-3, 1e-3, 1e-4]));
    let ball = |rng: &mut SplitMix, name: &str, p: &str, c: &str, at: DVec3| {
        let a = (at + jitter(rng)).to_array();
        JointDesc::ball(name, p, c, a).compliance(&[rng.log_uniform((-4.0, -1.0))])
    };
    for i in 0..levels {
        let z = h * i as f64;
        for (s, x) in [("L", -w / 2.0), ("R", w / 2.0)] {
            let below = if i == 0 {
                "base".to_owned()
            } else {
                format!("{s}{}", i - 1)
            };
            let j = ball(
                rng,
                &format!("rail_{s}{i}"),
                &below,
                &format!("{s}{i}"),
                DVec3::new(x, 0.0, z),
            );
            d.joint(j);
        }
        let a = jitter(rng);
        let rung = JointDesc::hinge(
            &format!("rung{i}"),
            &format!("L{i}"),
            &format!("R{i}"),
            [a.x, a.y, z + h / 2.0 + a.z],
            [10.0 * a.x, 1.0, 10.0 * a.z],
        )
        .compliance(&[rng.log_uniform((-4.0, -1.0))]);
        d.joint(rung);
    }
    for (s, x) in [("L", -w / 2.0), ("R", w / 2.0)] {
        let j = ball(
            rng,
            &format!("top_{s}"),
            &format!("{s}{}", levels - 1),
            "top",
            DVec3::new(x, 0.0, top),
        );
        d.joint(j);
    }
    d.end_effector("top");
    d
}

/// A chain of `n` ball joints along z, 0.1 m apart, the last anchor `offset` m off the line in
/// a random perpendicular direction; compliances over 1e-4 … 1e-2.
fn near_singular(rng: &mut SplitMix, name: &str, n: usize, offset: f64) -> MechanismDesc {
    let mut d = MechanismDesc::new(name);
    d.link(LinkDesc::new("base", [0.0; 3]));
    let side = {
        let a = rng.uniform(0.0, core::f64::consts::TAU);
        DVec3::new(a.cos(), a.sin(), 0.0)
    };
    for i in 1..=n {
        d.link(
            LinkDesc::new(&link_name(i), [0.0, 0.0, 0.1 * i as f64 - 0.05])
                .mass(0.1, [1e-4, 1e-4, 1e-5]),
        );
        let mut anchor = DVec3::new(0.0, 0.0, 0.1 * (i - 1) as f64);
        if i == n {
            anchor += side * offset;
        }
        d.joint(
            JointDesc::ball(
                &format!("j{i}"),
                &link_name(i - 1),
                &link_name(i),
                anchor.to_array(),
            )
            .compliance(&[rng.log_uniform((-4.0, -2.0))]),
        );
    }
    d.end_effector(&link_name(n));
    d
}

/// The fifty mechanisms of the acceptance (seeded): ten chains, ten trees, ten loops, ten
/// ladders, five near-singular chains and five stiff trees.
#[must_use]
pub fn acceptance_set() -> Vec<(Family, MechanismDesc)> {
    let mut rng = SplitMix::new(0x00F0_4B15);
    let mut out = Vec::with_capacity(50);
    for k in 0..10 {
        let n = 2 + k % 9;
        out.push((
            Family::Chain,
            tree(&mut rng, &format!("chain-{k}"), n, true, 0, 1, (-4.0, -1.0)),
        ));
    }
    for k in 0..10 {
        let n = 3 + k % 10;
        out.push((
            Family::Tree,
            tree(&mut rng, &format!("tree-{k}"), n, false, 0, 3, (-4.0, -1.0)),
        ));
    }
    for k in 0..10 {
        let n = 4 + k % 9;
        out.push((
            Family::Loop,
            tree(
                &mut rng,
                &format!("loop-{k}"),
                n,
                false,
                1 + k % 2,
                2,
                (-4.0, -1.0),
            ),
        ));
    }
    for k in 0..10 {
        let levels = 2 + k % 6;
        out.push((
            Family::Ladder,
            ladder(&mut rng, &format!("ladder-{k}"), levels),
        ));
    }
    for k in 0..5 {
        let offset = 10f64.powf(-3.0 - 1.25 * k as f64);
        out.push((
            Family::NearSingular,
            near_singular(&mut rng, &format!("near-singular-{k}"), 3 + k % 3, offset),
        ));
    }
    for k in 0..5 {
        let n = 3 + 2 * k;
        out.push((
            Family::Stiff,
            tree(
                &mut rng,
                &format!("stiff-{k}"),
                n,
                false,
                0,
                2,
                (-9.0, -1.0),
            ),
        ));
    }
    out
}

/// The spatial screws (world, about the origin) of every joint coordinate at rest, written
/// from the anchors and axes: a rotation about unit axis u through anchor a is `(a × u, u)`, a
/// translation along u is `(u, 0)` (a weld's translations, then its rotations about the
/// anchor).
fn rest_screws(m: &Mechanism) -> Vec<[f64; 6]> {
    let mut s = vec![[0.0; 6]; m.ndof];
    for j in &m.joints {
        let frame = m.links[j.parent].rest * j.in_parent;
        let a = frame.translation;
        for (k, (d, axis)) in j.directions.iter().enumerate() {
            let u = frame.transform_vector(*axis);
            s[j.offset + k] = match d {
                Direction::Rotation => {
                    let v = a.cross(u);
                    [v.x, v.y, v.z, u.x, u.y, u.z]
                }
                Direction::Translation => [u.x, u.y, u.z, 0.0, 0.0, 0.0],
            };
        }
    }
    s
}

/// The tree joints from link `l` to the base.
fn path(m: &Mechanism, mut l: usize) -> Vec<usize> {
    let mut out = Vec::new();
    while let Some(j) = m.tree_joint[l] {
        out.push(j);
        l = m.joints[j].parent;
    }
    out
}

/// The end-effector compliance at rest from first principles (see the module doc): body
/// twists of the end effectors (their frames at rest) per wrench, 6|E| square.
///
/// # Errors
/// [`Error::LinearAlgebra`] if a factorisation fails.
pub fn schur_compliance(m: &Mechanism) -> Result<Mat<f64>, Error> {
    let s = rest_screws(m);
    let n = m.ndof;
    let ne = m.end_effectors.len();
    // End-effector rows: Ad_{H_e⁻¹} Σ_{path(e)} s_i θ_i.
    let mut je = Mat::<f64>::zeros(6 * ne, n);
    for (i, &e) in m.end_effectors.iter().enumerate() {
        let inv = m.links[e].rest.inverse();
        for j in path(m, e) {
            let joint = &m.joints[j];
            for k in 0..joint.dof() {
                let c = joint.offset + k;
                // Ad_{H_e⁻¹} s: the world screw seen in the end effector's body frame.
                let t = inv.transform_twist(&Twist::from_array(s[c])).to_array();
                for r in 0..6 {
                    je[(6 * i + r, c)] = t[r];
                }
            }
        }
    }
    // Closures: Σ_{path(child)} s_i θ_i − Σ_{path(parent)} s_i θ_i − Σ_own s_k θ_k = 0.
    let nl = m.loop_joints.len();
    let mut g = Mat::<f64>::zeros(6 * nl, n);
    for (k, &ji) in m.loop_joints.iter().enumerate() {
        let j = &m.joints[ji];
        let mut add = |joint: usize, sign: f64| {
            let jj = &m.joints[joint];
            for d in 0..jj.dof() {
                for r in 0..6 {
                    g[(6 * k + r, jj.offset + d)] += sign * s[jj.offset + d][r];
                }
            }
        };
        for x in path(m, j.child) {
            add(x, 1.0);
        }
        for x in path(m, j.parent) {
            add(x, -1.0);
        }
        add(ji, -1.0);
    }
    let c: Vec<f64> = m
        .joints
        .iter()
        .flat_map(|j| j.compliance.iter().copied())
        .collect();
    // Z: the closures' null space (SVD, singular values below 1e-12 of the largest dropped:
    // redundant closures are exact zeros here, written from the anchors).
    let z = if nl == 0 {
        Mat::<f64>::identity(n, n)
    } else {
        let svd = g
            .svd()
            .map_err(|e| Error::LinearAlgebra(format!("closures: {e:?}")))?;
        let k = g.nrows().min(n);
        let smax = (0..k).fold(0.0_f64, |a, i| a.max(svd.S()[i]));
        let r = (0..k).filter(|&i| svd.S()[i] > CLOSURE_RANK * smax).count();
        Mat::from_fn(n, n - r, |i, j| svd.V()[(i, r + j)])
    };
    // C_θ = Z (Zᵀ K Z)⁻¹ Zᵀ, K = diag(1/c).
    let kz = Mat::from_fn(z.ncols(), z.ncols(), |a, b| {
        (0..n).map(|i| z[(i, a)] * z[(i, b)] / c[i]).sum::<f64>()
    });
    let kinv = pinv(kz.as_ref(), Tsvd::default())?.inverse;
    let jz = &je * &z;
    Ok(&jz * kinv * jz.transpose())
}

/// Singular values of the closures' Jacobian below this fraction of the largest are
/// redundant closures in [`schur_compliance`] (exactly zero up to the rounding of the screws,
/// ~1e-16; the near-redundant closures of the ladders sit at 1e-3 and above).
pub const CLOSURE_RANK: f64 = 1e-12;

/// Load increments of [`plain_newton`].
pub const PLAIN_INCREMENTS: usize = 10;
/// Newton iterations per increment of [`plain_newton`].
pub const PLAIN_ITERATIONS: usize = 40;
/// Relative step of [`plain_newton`]'s central differences (times `1 + |θ|`).
pub const PLAIN_FD_STEP: f64 = 1e-6;

/// A plain Newton on the full statics' equations (the kind a user writes to check a solver):
/// the residual `−K θ + Σ J_lᵀ w_l + Σ G_kᵀ λ_k`, `r_k` from the crate's kinematics, its
/// tangent by central differences, [`PLAIN_INCREMENTS`] equal load increments, full Newton
/// steps solved by truncated SVD, stopping at `tolerance` (force rows relative to their
/// largest term, closure relative to `1 + r`). `None` when it does not converge.
#[must_use]
pub fn plain_newton(m: &Mechanism, loads: &[Load], tolerance: f64) -> Option<Configuration> {
    let n = m.ndof;
    let nl = m.loop_joints.len();
    let length = 1.0 + m.bounding_radius();
    let c: Vec<f64> = m
        .joints
        .iter()
        .flat_map(|j| j.compliance.iter().copied())
        .collect();
    let residual = |q: &Configuration, lambda: &[f64], s: f64| -> (Vec<f64>, f64) {
        let poses = link_poses(m, q);
        let mut f: Vec<f64> = (0..n).map(|i| -q.theta[i] / c[i]).collect();
        let mut scale = f.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        for l in loads {
            let w = Load {
                force: l.force * s,
                torque: l.torque * s,
                ..*l
            }
            .body_wrench(&poses[l.link])
            .to_array();
            let jac = body_jacobian(m, q, &poses, l.link);
            for (i, x) in f.iter_mut().enumerate() {
                let g: f64 = (0..6).map(|r| jac[(r, i)] * w[r]).sum();
                *x += g;
                scale = scale.max(g.abs());
            }
        }
        let mut closure = Vec::with_capacity(6 * nl);
        for (k, &ji) in m.loop_joints.iter().enumerate() {
            let g = loop_jacobian(m, q, &poses, ji);
            for (i, x) in f.iter_mut().enumerate() {
                *x += (0..6).map(|r| g[(r, i)] * lambda[6 * k + r]).sum::<f64>();
            }
            closure.extend(loop_residual(m, q, &poses, ji).to_array());
        }
        f.extend(closure);
        (f, scale)
    };
    let done = |f: &[f64], scale: f64| {
        let force = f[..n].iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        let closure = f[n..].iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        force <= tolerance * scale.max(f64::MIN_POSITIVE) && closure <= tolerance * length
    };
    let mut q = Configuration::rest(m);
    let mut lambda = vec![0.0; 6 * nl];
    for step in 1..=PLAIN_INCREMENTS {
        let s = step as f64 / PLAIN_INCREMENTS as f64;
        let mut converged = false;
        for _ in 0..PLAIN_ITERATIONS {
            let (f, scale) = residual(&q, &lambda, s);
            if f.iter().any(|x| !x.is_finite()) {
                return None;
            }
            if done(&f, scale) {
                converged = true;
                break;
            }
            let dim = n + 6 * nl;
            let mut t = Mat::<f64>::zeros(dim, dim);
            for col in 0..dim {
                let (mut qp, mut qm) = (q.clone(), q.clone());
                let (mut lp, mut lm) = (lambda.clone(), lambda.clone());
                let h = if col < n {
                    let h = PLAIN_FD_STEP * (1.0 + q.theta[col].abs());
                    qp.theta[col] += h;
                    qm.theta[col] -= h;
                    h
                } else {
                    let h = PLAIN_FD_STEP * (1.0 + lambda[col - n].abs());
                    lp[col - n] += h;
                    lm[col - n] -= h;
                    h
                };
                let (fp, _) = residual(&qp, &lp, s);
                let (fm, _) = residual(&qm, &lm, s);
                for row in 0..dim {
                    t[(row, col)] = (fp[row] - fm[row]) / (2.0 * h);
                }
            }
            let rhs = Mat::from_fn(dim, 1, |i, _| -f[i]);
            let step = pinv(t.as_ref(), Tsvd::default()).ok()?.inverse * rhs;
            for i in 0..n {
                q.theta[i] += step[(i, 0)];
            }
            for k in 0..6 * nl {
                lambda[k] += step[(n + k, 0)];
            }
        }
        if !converged {
            let (f, scale) = residual(&q, &lambda, s);
            if !done(&f, scale) {
                return None;
            }
        }
    }
    Some(q)
}

/// The loads of a case's nonlinear check: a force along a random direction on every end
/// effector, of the magnitudes that turn the most compliant joint by about 0.01, 0.1, 0.5
/// and 1.5 rad over the bounding radius (`θ / (c_max r)`); for ladders 1, 10, 100 and
/// 1000 N (four decades of load).
#[must_use]
pub fn case_loads(m: &Mechanism, family: Family, rng: &mut SplitMix) -> Vec<Vec<Load>> {
    let dirs: Vec<DVec3> = m.end_effectors.iter().map(|_| rng.direction()).collect();
    let c_max = m
        .joints
        .iter()
        .flat_map(|j| j.compliance.iter().copied())
        .fold(0.0_f64, f64::max);
    let magnitudes: Vec<f64> = if family == Family::Ladder {
        vec![1.0, 10.0, 100.0, 1000.0]
    } else {
        let unit = 1.0 / (c_max * m.bounding_radius());
        [0.01, 0.1, 0.5, 1.5].iter().map(|t| t * unit).collect()
    };
    magnitudes
        .iter()
        .map(|&f| {
            m.end_effectors
                .iter()
                .zip(&dirs)
                .map(|(&link, d)| Load {
                    link,
                    force: *d * f,
                    torque: DVec3::ZERO,
                })
                .collect()
        })
        .collect()
}

/// What one mechanism of the set gave.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseResult {
    /// Its name.
    pub name: String,
    /// Its family.
    pub family: Family,
    /// The model's rank and the directions the joints allow.
    pub rank: (usize, usize),
    /// Largest relative difference of the reduced static displacement `C w` from the
    /// independent Schur complement's, `|Δ|∞ / |C_ref w|∞`, over three random wrenches.
    pub linear: f64,
    /// The rounding bound of that difference from the conditioning: [`LINEAR_ROUNDING`] ε
    /// times the spanning tree's compliance (what the walk's merges subtract from) times the
    /// wrench, over the displacement.
    pub linear_bound: f64,
    /// Per load level: (the plain Newton converged, the solver converged, their largest
    /// end-effector position difference over the bounding radius when both did).
    pub nonlinear: Vec<(bool, bool, f64)>,
}

/// Rounding of the walk's compliance in units of ε times the spanning tree's compliance: a
/// few ε per congruence, over the tens of links of the set (the bound of
/// [`CaseResult::linear_bound`]).
pub const LINEAR_ROUNDING: f64 = 1e3;

/// Runs both checks on one mechanism (see the module doc); `rng` draws the wrenches and load
/// directions.
///
/// # Errors
/// Errors of the construction or of the independent Schur complement (the nonlinear solves'
/// failures are results, not errors).
pub fn run_case(
    family: Family,
    desc: &MechanismDesc,
    rng: &mut SplitMix,
) -> Result<CaseResult, Error> {
    let m = desc.build()?;
    let q = Configuration::rest(&m);
    let model = ReducedModel::build(&m, &q, &[], &ConstructOptions::default())?;
    let reference = schur_compliance(&m)?;
    let ne = m.end_effectors.len();
    // The spanning tree's compliance: the Schur complement without the closures.
    let tree_size = {
        let mut open = m.clone();
        open.loop_joints.clear();
        let t = schur_compliance(&open)?;
        crate::linalg::max_abs(t.as_ref())
    };
    let (mut linear, mut bound) = (0.0_f64, 0.0_f64);
    for _ in 0..3 {
        let w: Vec<f64> = (0..6 * ne).map(|_| rng.uniform(-1.0, 1.0)).collect();
        let (twists, _) = model.static_twists(&w);
        let got: Vec<f64> = twists.iter().flat_map(|t| t.to_array()).collect();
        let want: Vec<f64> = (0..6 * ne)
            .map(|r| (0..6 * ne).map(|c| reference[(r, c)] * w[c]).sum())
            .collect();
        let size = want.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        let diff = got
            .iter()
            .zip(&want)
            .fold(0.0_f64, |a, (x, y)| a.max((x - y).abs()));
        let wmax = w.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        linear = linear.max(diff / size);
        bound =
            bound.max(LINEAR_ROUNDING * f64::EPSILON * tree_size * 6.0 * ne as f64 * wmax / size);
    }
    let r = m.bounding_radius();
    let mut nonlinear = Vec::new();
    for loads in case_loads(&m, family, rng) {
        let plain = plain_newton(&m, &loads, crate::tol::STATIC_RESIDUAL_REL);
        let solved = solve_statics(&m, &loads, None, &StaticOptions::default()).ok();
        let diff = match (&plain, &solved) {
            (Some(a), Some(b)) => {
                let (pa, pb) = (link_poses(&m, a), link_poses(&m, &b.config));
                m.end_effectors
                    .iter()
                    .map(|&e| (pa[e].translation - pb[e].translation).length() / r)
                    .fold(0.0, f64::max)
            }
            _ => f64::NAN,
        };
        nonlinear.push((plain.is_some(), solved.is_some(), diff));
    }
    Ok(CaseResult {
        name: m.name.clone(),
        family,
        rank: (model.rank, model.diagnostics.allowed),
        linear,
        linear_bound: bound,
        nonlinear,
    })
}

#[cfg(test)]
#[path = "hard_cases_tests.rs"]
mod tests;
