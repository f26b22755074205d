//! Acceptance tests of the wrench maps: equilibrium at every link (eq. 15) and at the base,
//! power invariance of eq. 18, and the joint wrenches of the full linearised statics.

use glam::DVec3;
use impulse_geom::Twist;
use rand::RngExt;
use rand::rngs::Xoshiro256PlusPlus;

use super::*;
use crate::reference::LinearStatics;
use crate::testutil::{random_diamonds, random_mechanism, rng};

/// Equilibrium at a link: Σ over parents of the mapped wrenches equals the child's wrench
/// (eq. 15), relative to the largest wrench at that link; an identity, so only rounding.
const EQ15_REL: f64 = 1e-12;
/// Power invariance (eq. 18): `ξᵀw` is the same in any frame, relative to `|ξ|·|w|`.
const POWER_REL: f64 = 1e-12;
/// Trees: every joint's wrench equals the equilibrium of the subtree below it, and its free
/// components the full linearised statics' spring forces `δθ/c`, relative to the largest
/// joint wrench (sums of a few hundred products of unit-size numbers: ~1e-14).
const TREE_REL: f64 = 1e-12;
/// Loops fed through their merge: free components against the full statics' `δθ/c`, relative
/// to the largest spring force. The reference's `C_θ = Z (Zᵀ K Z)⁻¹ Zᵀ` divided back by
/// compliances over three decades carries ~1e-12 of round-off; the merges' KKT solves another
/// few 1e-13 of the split.
const LOOP_REL: f64 = 1e-9;

fn random_wrenches(rng: &mut Xoshiro256PlusPlus, n: usize) -> Vec<Wrench> {
    (0..n)
        .map(|_| Wrench::from_array(core::array::from_fn(|_| rng.random_range(-1.0..1.0))))
        .collect()
}

fn size(w: &Wrench) -> f64 {
    w.f.abs().max_element().max(w.tau.abs().max_element())
}

/// The mechanisms every equilibrium test runs on: random trees, random loop DAGs, the bundled
/// loop scenes.
fn mechanisms(seed: u64) -> Vec<Mechanism> {
    let mut rng = rng(seed);
    let mut out: Vec<Mechanism> = (0..150)
        .map(|k| {
            random_mechanism(&mut rng, 1 + k % 40, 0, 4, 6.0)
                .build()
                .unwrap()
        })
        .collect();
    out.extend((0..150).map(|k| {
        random_mechanism(&mut rng, 3 + k % 25, 1 + k % 3, 3, 3.0)
            .build()
            .unwrap()
    }));
    for d in [
        crate::scenes::ladder(36),
        crate::scenes::y_shape(4),
        crate::scenes::ring(10),
    ] {
        out.push(d.build().unwrap());
    }
    out
}

/// Eq. 15 at every link, both ways: the in-joints' wrenches sum to the link's (the merge's
/// split, frame k), and a link transmits its own load plus what its children pass to it,
/// re-expressed by `Pose::transform_wrench` (not by the maps' adjoints).
#[test]
fn every_link_is_in_equilibrium() {
    let mut rng = rng(15);
    let mut worst = 0.0_f64;
    let mut merges = 0;
    for m in mechanisms(150) {
        let maps = WrenchMaps::build(&m, &Configuration::rest(&m), Tsvd::default()).unwrap();
        let w = random_wrenches(&mut rng, m.end_effectors.len());
        let joint: Vec<Wrench> = (0..m.joints.len())
            .map(|j| maps.joint_wrench(j, &w).unwrap())
            .collect();
        for l in 0..m.links.len() {
            let own = maps.link_wrench(l, &w).unwrap();
            let scale = size(&own).max(f64::MIN_POSITIVE);
            if l != m.base {
                // Split (eq. 15 in frame k).
                let sum = m.joints_in[l]
                    .iter()
                    .fold(Wrench::ZERO, |acc, &j| acc + joint[j]);
                let e = size(&(sum - own)) / scale;
                assert!(e <= EQ15_REL, "{} link {l}: split off by {e:e}", m.name);
                worst = worst.max(e);
                merges += usize::from(m.joints_in[l].len() > 1);
            }
            // Gather (eq. 15 at the parent, eq. 18 by an independent transform).
            let mut gathered = m
                .end_effectors
                .iter()
                .position(|&e| e == l)
                .map_or(Wrench::ZERO, |i| w[i]);
            for &j in &m.joints_out[l] {
                let c = m.joints[j].child;
                let to_l = maps.poses[l].inverse() * maps.poses[c];
                gathered += to_l.transform_wrench(&joint[j]);
            }
            let scale = size(&own).max(size(&gathered)).max(f64::MIN_POSITIVE);
            let e = size(&(gathered - own)) / scale;
            assert!(e <= EQ15_REL, "{} link {l}: gather off by {e:e}", m.name);
            worst = worst.max(e);
        }
    }
    assert!(merges > 100, "only {merges} merges tested");
    println!("eq. 15 at every link of 303 mechanisms ({merges} merges): worst {worst:e}");
}

/// Global equilibrium: the wrench reaching the base is the resultant of the end-effector
/// loads moved to the base frame (the ground's reaction), for trees and loops alike.
#[test]
fn base_carries_the_resultant_of_the_loads() {
    let mut rng = rng(16);
    let mut worst = 0.0_f64;
    for m in mechanisms(151) {
        let maps = WrenchMaps::build(&m, &Configuration::rest(&m), Tsvd::default()).unwrap();
        let w = random_wrenches(&mut rng, m.end_effectors.len());
        let inv_base = maps.poses[m.base].inverse();
        let resultant = m
            .end_effectors
            .iter()
            .zip(&w)
            .fold(Wrench::ZERO, |acc, (&e, we)| {
                acc + (inv_base * maps.poses[e]).transform_wrench(we)
            });
        let got = maps.link_wrench(m.base, &w).unwrap();
        let e = size(&(got - resultant)) / size(&resultant);
        assert!(e <= EQ15_REL, "{}: base reaction off by {e:e}", m.name);
        worst = worst.max(e);
    }
    println!("base reaction of 303 mechanisms: worst {worst:e}");
}

/// Eq. 18 keeps power: a joint's wrench in its child's frame paired with a twist there equals
/// the wrench passed to the parent paired with the same twist in the parent's frame; and a
/// link's static twist (twist maps) paired with its transmitted wrench is the same in its body
/// frame and in world axes.
#[test]
fn power_is_frame_invariant() {
    let mut rng = rng(18);
    let mut worst = 0.0_f64;
    for m in mechanisms(152).into_iter().step_by(3) {
        let q = Configuration::rest(&m);
        let maps = WrenchMaps::build(&m, &q, Tsvd::default()).unwrap();
        let w = random_wrenches(&mut rng, m.end_effectors.len());
        for j in 0..m.joints.len() {
            let (p, c) = (m.joints[j].parent, m.joints[j].child);
            let xi_p = Twist::from_array(core::array::from_fn(|_| rng.random_range(-1.0..1.0)));
            let xi_c = (maps.poses[c].inverse() * maps.poses[p]).transform_twist(&xi_p);
            let wc = maps.joint_wrench(j, &w).unwrap();
            let wp = maps.parent_wrench(&m, j, &w).unwrap();
            let scale = size(&wc).max(size(&wp)) * 6.0 * (xi_p.v.length() + xi_p.w.length());
            let e = (wc.power(&xi_c) - wp.power(&xi_p)).abs() / scale.max(f64::MIN_POSITIVE);
            assert!(e <= POWER_REL, "{} joint {j}: power off by {e:e}", m.name);
            worst = worst.max(e);
        }
        let Ok(model) = crate::ReducedModel::build(&m, &q, &[], &Default::default()) else {
            continue;
        };
        let (_, twists) = model.static_twists(&crate::ReducedModel::stack_wrenches(&w));
        for (k, &l) in model.internal.iter().enumerate() {
            let (xi, wl) = (twists[k], maps.link_wrench(l, &w).unwrap());
            let pose = maps.poses[l];
            let world = pose.transform_wrench(&wl).power(&pose.transform_twist(&xi));
            let scale = 6.0
                * (xi.v.length() + xi.w.length())
                * size(&wl)
                * (1.0 + pose.translation.length());
            let e = (world - wl.power(&xi)).abs() / scale.max(f64::MIN_POSITIVE);
            assert!(e <= POWER_REL, "{} link {l}: power off by {e:e}", m.name);
            worst = worst.max(e);
        }
    }
    println!("power across eq. 18 and into world axes: worst {worst:e}");
}

/// Free components `Jᵀw` of every joint's wrench against the spring forces `δθ/c` of the full
/// linearised statics; returns the worst error relative to the largest spring force.
fn spring_force_error(m: &Mechanism, q: &Configuration, maps: &WrenchMaps, w: &[Wrench]) -> f64 {
    let lin = LinearStatics::new(m, q, Tsvd::default()).unwrap();
    let dtheta = lin.deflection(&m.end_effectors, w);
    let cols = all_columns(m, q);
    let spring: Vec<f64> = m
        .joints
        .iter()
        .flat_map(|j| (0..j.dof()).map(move |k| (j, k)))
        .map(|(j, k)| dtheta[j.offset + k] / j.compliance[k])
        .collect();
    let scale = spring.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    let mut worst = 0.0_f64;
    for (ji, j) in m.joints.iter().enumerate() {
        let wj = maps.joint_wrench(ji, w).unwrap().to_array();
        for k in 0..j.dof() {
            let free: f64 = (0..6).map(|r| cols[ji][(r, k)] * wj[r]).sum();
            worst = worst.max((free - spring[j.offset + k]).abs() / scale);
        }
    }
    worst
}

/// Trees: every joint carries exactly the loads of the subtree below it (brute force over
/// end effectors and ancestors), and its spring forces are those of the full statics.
#[test]
fn trees_carry_what_the_full_statics_carries() {
    let mut rng = rng(19);
    let (mut worst_sub, mut worst_spring) = (0.0_f64, 0.0_f64);
    for case in 0..200 {
        let m = random_mechanism(&mut rng, 1 + case % 40, 0, 4, 6.0)
            .build()
            .unwrap();
        // A general configuration, not only the rest pose.
        let q = Configuration {
            base: m.links[m.base].rest,
            theta: (0..m.ndof).map(|_| rng.random_range(-0.5..0.5)).collect(),
        };
        let maps = WrenchMaps::build(&m, &q, Tsvd::default()).unwrap();
        let w = random_wrenches(&mut rng, m.end_effectors.len());
        let below = |c: usize, mut e: usize| loop {
            if e == c {
                return true;
            }
            match m.tree_joint[e] {
                Some(j) => e = m.joints[j].parent,
                None => return false,
            }
        };
        let joint: Vec<Wrench> = (0..m.joints.len())
            .map(|j| maps.joint_wrench(j, &w).unwrap())
            .collect();
        let scale = joint.iter().map(size).fold(0.0, f64::max);
        for (ji, j) in m.joints.iter().enumerate() {
            let c = j.child;
            let reference = m
                .end_effectors
                .iter()
                .zip(&w)
                .filter(|(e, _)| below(c, **e))
                .fold(Wrench::ZERO, |acc, (&e, we)| {
                    acc + (maps.poses[c].inverse() * maps.poses[e]).transform_wrench(we)
                });
            let e = size(&(joint[ji] - reference)) / scale;
            assert!(
                e <= TREE_REL,
                "case {case} joint {ji}: subtree off by {e:e}"
            );
            worst_sub = worst_sub.max(e);
        }
        let e = spring_force_error(&m, &q, &maps, &w);
        assert!(e <= TREE_REL, "case {case}: spring forces off by {e:e}");
        worst_spring = worst_spring.max(e);
    }
    println!("200 random trees: subtree {worst_sub:e}, spring forces {worst_spring:e}");
}

/// Loops whose loads enter through their merge link (nested diamonds, the "Y" with its
/// cross-bar below the load path): the merges' split (eqs. 16–17) gives every joint, loop
/// joints included, the spring forces of the full linearised statics.
#[test]
fn loops_fed_through_their_merge_match_the_full_statics() {
    let mut rng = rng(20);
    let mut worst = 0.0_f64;
    let mut loops = 0;
    for case in 0..120 {
        let m = random_diamonds(&mut rng, 2 + case % 3).build().unwrap();
        loops += m.loop_joints.len();
        let q = Configuration::rest(&m);
        let maps = WrenchMaps::build(&m, &q, Tsvd::default()).unwrap();
        let w = random_wrenches(&mut rng, m.end_effectors.len());
        let e = spring_force_error(&m, &q, &maps, &w);
        assert!(e <= LOOP_REL, "case {case}: spring forces off by {e:e}");
        worst = worst.max(e);
    }
    assert!(loops > 60, "only {loops} loops tested");
    println!("120 random diamond mechanisms ({loops} loops): spring forces {worst:e}");
}

#[test]
fn bad_input_is_an_error() {
    let m = crate::scenes::y_shape(4).build().unwrap();
    let mut q = Configuration::rest(&m);
    let maps = WrenchMaps::build(&m, &q, Tsvd::default()).unwrap();
    let ne = m.end_effectors.len();
    let w = vec![Wrench::new(DVec3::X, DVec3::ZERO); ne];
    assert!(maps.link_wrench(0, &w[1..]).is_err());
    assert!(maps.link_wrench(m.links.len(), &w).is_err());
    assert!(maps.joint_wrench(m.joints.len(), &w).is_err());
    assert!(maps.parent_wrench(&m, m.joints.len(), &w).is_err());
    let mut nan = w.clone();
    nan[0].f.x = f64::NAN;
    assert!(maps.joint_wrench(0, &nan).is_err());
    q.theta.pop();
    assert!(WrenchMaps::build(&m, &q, Tsvd::default()).is_err());
    q.theta.push(f64::NAN);
    assert!(WrenchMaps::build(&m, &q, Tsvd::default()).is_err());
}
