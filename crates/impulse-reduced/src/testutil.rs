//! Test helpers: random mechanisms (trees and loops) with random joint kinds, axes, offsets and
//! compliances over six decades; block comparisons.

use faer::Mat;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use crate::desc::{BaseDesc, JointDesc, LinkDesc, MechanismDesc};
use crate::mechanism::Mechanism;

/// A seeded generator.
pub fn rng(seed: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

fn v3(rng: &mut Xoshiro256PlusPlus, s: f64) -> [f64; 3] {
    [
        rng.random_range(-s..s),
        rng.random_range(-s..s),
        rng.random_range(-s..s),
    ]
}

/// A joint of `kind` (0 hinge, 1 slider, 2 ball, 3 weld) named `[joint, parent, child]` at
/// `anchor`, random axis, each free direction's compliance 10^x with x uniform in `decades`.
fn random_joint(
    rng: &mut Xoshiro256PlusPlus,
    kind: usize,
    [name, pn, cn]: [&str; 3],
    anchor: [f64; 3],
    decades: std::ops::Range<f64>,
) -> JointDesc {
    let joint = match kind {
        0 => JointDesc::hinge(name, pn, cn, anchor, unit(rng)),
        1 => JointDesc::slider(name, pn, cn, anchor, unit(rng)),
        2 => JointDesc::ball(name, pn, cn, anchor),
        _ => JointDesc::weld(name, pn, cn, anchor),
    };
    let dof = [1, 1, 3, 6][kind];
    let c: Vec<f64> = (0..dof)
        .map(|_| 10f64.powf(rng.random_range(decades.clone())))
        .collect();
    joint.compliance(&c)
}

fn unit(rng: &mut Xoshiro256PlusPlus) -> [f64; 3] {
    loop {
        let v = v3(rng, 1.0);
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if n > 0.1 && n <= 1.0 {
            return [v[0] / n, v[1] / n, v[2] / n];
        }
    }
}

/// A random mechanism of `n` moving links (plus the base) and `loops` extra joints closing
/// loops (closed by hinges or balls); at most `max_ee` end effectors, chosen among the leaves;
/// compliances log-uniform over `decades` decades from 1e-4.
pub fn random_mechanism(
    rng: &mut Xoshiro256PlusPlus,
    n: usize,
    loops: usize,
    max_ee: usize,
    decades: f64,
) -> MechanismDesc {
    let mut d = MechanismDesc::new("random");
    let mut pos = vec![[0.0; 3]];
    d.link(LinkDesc::new("base", [0.0; 3]));
    let mut has_child = vec![false; n + 1];
    let mut joints = 0;
    let mut add_joint = |d: &mut MechanismDesc,
                         rng: &mut Xoshiro256PlusPlus,
                         p: usize,
                         c: usize,
                         pos: &[[f64; 3]],
                         closes_loop: bool| {
        let anchor = {
            let t = rng.random_range(0.0..1.0);
            let j = v3(rng, 0.05);
            core::array::from_fn(|k| pos[p][k] + t * (pos[c][k] - pos[p][k]) + j[k])
        };
        let name = format!("j{joints}");
        joints += 1;
        let pn = if p == 0 {
            "base".to_owned()
        } else {
            format!("l{p}")
        };
        let cn = format!("l{c}");
        // Loop-closing joints are hinges or balls, as in real mechanisms: a closing weld or
        // slider makes the loop nearly rigid in most directions.
        let kind = if closes_loop {
            [0, 2][rng.random_range(0..2)]
        } else {
            rng.random_range(0..4)
        };
        d.joint(random_joint(
            rng,
            kind,
            [&name, &pn, &cn],
            anchor,
            -4.0..(decades - 4.0),
        ));
    };
    let mut parent = vec![0usize];
    for i in 1..=n {
        let p = rng.random_range(0..i);
        parent.push(p);
        let off = v3(rng, 0.6);
        let q = {
            let a = unit(rng);
            let ang: f64 = rng.random_range(-3.0..3.0);
            let s = (ang / 2.0).sin();
            [a[0] * s, a[1] * s, a[2] * s, (ang / 2.0).cos()]
        };
        let p3: [f64; 3] = core::array::from_fn(|k| pos[p][k] + off[k]);
        pos.push(p3);
        let m = rng.random_range(0.1..2.0);
        let inertia = [
            m * rng.random_range(0.01..0.1),
            m * rng.random_range(0.01..0.1),
            m * rng.random_range(0.01..0.1),
        ];
        d.link(
            LinkDesc::new(&format!("l{i}"), p3)
                .rotation(q)
                .mass(m, inertia)
                .com(v3(rng, 0.1)),
        );
        add_joint(&mut d, rng, p, i, &pos, false);
        has_child[p] = true;
    }
    // Loops join two branches, as the rungs of a ladder do: the closing joint's parent is
    // never a tree ancestor of its child (a closure back onto one's own ancestor makes a short
    // stiff cycle that locks most directions).
    let mut made = 0;
    for _ in 0..20 * loops {
        if made == loops || n < 3 {
            break;
        }
        let c = rng.random_range(2..=n);
        let p = rng.random_range(1..c);
        if crate::hard_cases::is_tree_ancestor(&parent, p, c) {
            continue;
        }
        add_joint(&mut d, rng, p, c, &pos, true);
        has_child[p] = true;
        made += 1;
    }
    let leaves: Vec<usize> = (1..=n).filter(|&i| !has_child[i]).collect();
    let k = rng.random_range(1..=max_ee.min(leaves.len()));
    let mut chosen = leaves.clone();
    while chosen.len() > k {
        let i = rng.random_range(0..chosen.len());
        chosen.remove(i);
    }
    for l in chosen {
        d.end_effector(&format!("l{l}"));
    }
    d
}

/// Largest absolute entry.
pub fn max_abs(a: &Mat<f64>) -> f64 {
    crate::linalg::max_abs(a.as_ref())
}

/// Largest block-by-block relative difference of two 6k × 6k matrices: each block's max entry
/// error over that block's max reference entry (floored at `floor` of the whole matrix, for
/// blocks that are exactly zero in the reference).
pub fn block_rel_error(a: &Mat<f64>, reference: &Mat<f64>, floor: f64) -> f64 {
    let whole = max_abs(reference);
    let (br, bc) = (reference.nrows() / 6, reference.ncols() / 6);
    let mut worst = 0.0_f64;
    for i in 0..br {
        for j in 0..bc {
            let (mut num, mut den) = (0.0_f64, 0.0_f64);
            for r in 0..6 {
                for c in 0..6 {
                    let (x, y) = (a[(6 * i + r, 6 * j + c)], reference[(6 * i + r, 6 * j + c)]);
                    num = num.max((x - y).abs());
                    den = den.max(y.abs());
                }
            }
            worst = worst.max(num / den.max(floor * whole).max(f64::MIN_POSITIVE));
        }
    }
    worst
}

/// Builder state of [`random_diamonds`].
struct Diamonds {
    d: MechanismDesc,
    pos: Vec<[f64; 3]>,
    joints: usize,
    leaves: Vec<usize>,
}

impl Diamonds {
    fn name(l: usize) -> String {
        if l == 0 {
            "base".to_owned()
        } else {
            format!("l{l}")
        }
    }

    fn link(&mut self, rng: &mut Xoshiro256PlusPlus, near: usize) -> usize {
        let off = v3(rng, 0.6);
        let p: [f64; 3] = core::array::from_fn(|k| self.pos[near][k] + off[k]);
        self.pos.push(p);
        let l = self.pos.len() - 1;
        let m = rng.random_range(0.1..2.0);
        self.d.link(
            LinkDesc::new(&Self::name(l), p)
                .mass(m, [m * 0.05, m * 0.04, m * 0.03])
                .com(v3(rng, 0.1)),
        );
        l
    }

    /// A joint from `p` to `c`; `kinds` indexes hinge, slider, ball, weld.
    fn joint(&mut self, rng: &mut Xoshiro256PlusPlus, p: usize, c: usize, kinds: &[usize]) {
        let t = rng.random_range(0.0..1.0);
        let j = v3(rng, 0.05);
        let anchor =
            core::array::from_fn(|k| self.pos[p][k] + t * (self.pos[c][k] - self.pos[p][k]) + j[k]);
        let name = format!("j{}", self.joints);
        self.joints += 1;
        let (pn, cn) = (Self::name(p), Self::name(c));
        let kind = kinds[rng.random_range(0..kinds.len())];
        let names = [name.as_str(), pn.as_str(), cn.as_str()];
        self.d
            .joint(random_joint(rng, kind, names, anchor, -4.0..-1.0));
    }

    fn chain(&mut self, rng: &mut Xoshiro256PlusPlus, from: usize, len: usize) -> usize {
        let mut at = from;
        for _ in 0..len {
            let c = self.link(rng, at);
            self.joint(rng, at, c, &[0, 1, 2, 3]);
            at = c;
        }
        at
    }

    fn block(&mut self, rng: &mut Xoshiro256PlusPlus, root: usize, depth: usize) {
        let choice = if depth == 0 {
            0
        } else {
            rng.random_range(0..3)
        };
        match choice {
            0 => {
                let len = rng.random_range(1..4);
                let end = self.chain(rng, root, len);
                if depth == 0 {
                    self.leaves.push(end);
                } else {
                    self.block(rng, end, depth - 1);
                }
            }
            1 => {
                // Two chains from `root` welded at a merge link: tree joint from the first, a
                // closing ball or weld from the second (random hinges and sliders around one
                // short loop would often lock it).
                let (la, lb) = (rng.random_range(1..3), rng.random_range(1..3));
                let a = self.chain(rng, root, la);
                let b = self.chain(rng, root, lb);
                let k = self.link(rng, a);
                self.joint(rng, a, k, &[0, 1, 2, 3]);
                self.joint(rng, b, k, &[2, 3]);
                self.block(rng, k, depth - 1);
            }
            _ => {
                self.block(rng, root, depth - 1);
                self.block(rng, root, depth - 1);
            }
        }
    }
}

/// A random mechanism of nested "diamonds": chains, splits, and loops made of two chains from
/// one link welded at a merge link, with everything else hanging below that merge, so that
/// every load enters every loop through its merge link. End effectors: a random non-empty set
/// of the leaves. Compliances log-uniform over three decades from 1e-4.
pub fn random_diamonds(rng: &mut Xoshiro256PlusPlus, depth: usize) -> MechanismDesc {
    let mut g = Diamonds {
        d: MechanismDesc::new("diamonds"),
        pos: vec![[0.0; 3]],
        joints: 0,
        leaves: Vec::new(),
    };
    g.d.link(LinkDesc::new("base", [0.0; 3]));
    g.block(rng, 0, depth);
    let mut chosen = g.leaves.clone();
    let k = rng.random_range(1..=chosen.len());
    while chosen.len() > k {
        let i = rng.random_range(0..chosen.len());
        chosen.remove(i);
    }
    for l in chosen {
        g.d.end_effector(&Diamonds::name(l));
    }
    g.d
}

/// A free 2 kg body with a ball-jointed compliant arm and a hinged tip (the end effector).
pub fn floating(gravity: [f64; 3]) -> Mechanism {
    let mut d = MechanismDesc::new("floating");
    d.base(BaseDesc::Free).gravity(gravity);
    d.link(
        LinkDesc::new("body", [0.0; 3])
            .mass(2.0, [0.02, 0.03, 0.04])
            .com([0.01, 0.0, 0.0]),
    )
    .link(LinkDesc::new("arm", [0.2, 0.0, 0.0]).mass(0.1, [1e-3; 3]))
    .link(LinkDesc::new("tip", [0.4, 0.0, 0.0]).mass(0.1, [1e-3; 3]))
    .joint(JointDesc::ball("shoulder", "body", "arm", [0.1, 0.0, 0.0]).compliance(&[1e-2]))
    .joint(
        JointDesc::hinge("elbow", "arm", "tip", [0.3, 0.0, 0.0], [0.0, 0.0, 1.0])
            .compliance(&[1e-2]),
    )
    .end_effector("tip");
    d.build().unwrap()
}

/// A rod on a hinge about z through the origin: mass 1 kg, COM 0.5 m out, 0.01 kg·m² about the
/// COM, so I = 0.26 kg·m² about the hinge; no gravity; `damping` as [`JointDesc::damping`]
/// (empty: none).
pub fn hinge_rod(compliance: f64, damping: &[f64]) -> Mechanism {
    let mut d = MechanismDesc::new("hinge");
    d.link(LinkDesc::new("base", [0.0; 3]))
        .link(
            LinkDesc::new("rod", [0.0; 3])
                .mass(1.0, [0.01; 3])
                .com([0.5, 0.0, 0.0]),
        )
        .joint(
            JointDesc::hinge("h", "base", "rod", [0.0; 3], [0.0, 0.0, 1.0])
                .compliance(&[compliance])
                .damping(damping),
        )
        .end_effector("rod");
    d.build().unwrap()
}

/// A lever: a 1 kg link whose frame (and COM) sits `length` out along x from a hinge about z
/// at the origin, hinge compliance `compliance`; no gravity. A world force `F` along y at the
/// link's origin holds it at the angle θ with `θ = compliance · length · F · cos θ` — exactly,
/// for the full model and for its one-hinge reduced model alike (the reduced twist is the
/// hinge's own screw), which makes it a closed-form check of the Fig. 7 statics.
pub fn lever(compliance: f64, length: f64) -> Mechanism {
    let mut d = MechanismDesc::new("lever");
    d.link(LinkDesc::new("base", [0.0; 3]))
        .link(LinkDesc::new("arm", [length, 0.0, 0.0]).mass(1.0, [0.01; 3]))
        .joint(
            JointDesc::hinge("h", "base", "arm", [0.0; 3], [0.0, 0.0, 1.0])
                .compliance(&[compliance]),
        )
        .end_effector("arm");
    d.build().unwrap()
}

/// Root of `θ = k cos θ` in `[0, π/2]` by bisection (the lever's equilibrium angle under a
/// constant world force, `k = c·L·F`), to [`BISECTION_TOL`].
pub fn lever_angle(k: f64) -> f64 {
    let (mut lo, mut hi) = (0.0_f64, core::f64::consts::FRAC_PI_2);
    while hi - lo > BISECTION_TOL {
        let mid = 0.5 * (lo + hi);
        if mid - k * mid.cos() > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Width (rad) at which [`lever_angle`]'s bisection stops.
pub const BISECTION_TOL: f64 = 1e-15;

/// A random spring ladder of `levels` levels (the hard family of the statics): two rails of
/// ball-jointed posts, a hinge rung per level about an axis tilted up to ~6° from the
/// ladder's normal, a top bar on two balls (the end effector); width 0.1–0.5 m, level height
/// 0.05–0.2 m, every anchor jittered by up to 1 cm, compliances log-uniform over
/// `1e-4 … 1e-1`. The tilts and jitters make the loops' closures nearly (not exactly)
/// redundant: the KKT systems of the statics are near-singular.
pub fn random_ladder(rng: &mut Xoshiro256PlusPlus, levels: usize) -> MechanismDesc {
    let mut d = MechanismDesc::new(&format!("random-ladder-{levels}"));
    let w = rng.random_range(0.1..0.5);
    let h = rng.random_range(0.05..0.2);
    let c = |rng: &mut Xoshiro256PlusPlus| [10f64.powf(rng.random_range(-4.0..-1.0))];
    let jitter = |rng: &mut Xoshiro256PlusPlus| v3(rng, 0.01);
    d.link(LinkDesc::new("base", [0.0; 3]));
    for i in 0..levels {
        let z = h * (i as f64 + 0.5);
        for (name, x) in [("L", -w / 2.0), ("R", w / 2.0)] {
            d.link(LinkDesc::new(&format!("{name}{i}"), [x, 0.0, z]).mass(0.1, [1e-3, 1e-3, 1e-4]));
        }
    }
    let top = h * levels as f64;
    d.link(LinkDesc::new("top", [0.0, 0.0, top]).mass(0.1, [1e-3, 1e-3, 1e-4]));
    for i in 0..levels {
        let z = h * i as f64;
        let below = |s: &str| {
            if i == 0 {
                "base".to_owned()
            } else {
                format!("{s}{}", i - 1)
            }
        };
        for (s, x) in [("L", -w / 2.0), ("R", w / 2.0)] {
            let a = jitter(rng);
            d.joint(
                JointDesc::ball(
                    &format!("rail_{s}{i}"),
                    &below(s),
                    &format!("{s}{i}"),
                    [x + a[0], a[1], z + a[2]],
                )
                .compliance(&c(rng)),
            );
        }
        let a = jitter(rng);
        let axis = [10.0 * a[0], 1.0, 10.0 * a[2]];
        d.joint(
            JointDesc::hinge(
                &format!("rung{i}"),
                &format!("L{i}"),
                &format!("R{i}"),
                [a[0], a[1], z + h / 2.0 + a[2]],
                axis,
            )
            .compliance(&c(rng)),
        );
    }
    for (s, x) in [("L", -w / 2.0), ("R", w / 2.0)] {
        let a = jitter(rng);
        d.joint(
            JointDesc::ball(
                &format!("top_{s}"),
                &format!("{s}{}", levels - 1),
                "top",
                [x + a[0], a[1], top + a[2]],
            )
            .compliance(&c(rng)),
        );
    }
    d.end_effector("top");
    d
}

/// A unit vector drawn uniformly from the sphere.
pub fn random_direction(rng: &mut Xoshiro256PlusPlus) -> glam::DVec3 {
    let u = unit(rng);
    glam::DVec3::new(u[0], u[1], u[2])
}
