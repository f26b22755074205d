use super::*;
use crate::Tsvd;
use crate::construct::ConstructOptions;
use crate::reference::{Configuration, LinearStatics};
use rand::{RngExt, SeedableRng};

/// Bit patterns of every pose component.
fn bits(p: &[Pose]) -> Vec<u64> {
    p.iter()
        .flat_map(|x| {
            x.rotation
                .to_array()
                .into_iter()
                .chain(x.translation.to_array())
                .map(f64::to_bits)
        })
        .collect()
}

/// [`fast_exp`] against `impulse_geom`'s `Pose::exp` (rotation quaternion components,
/// translation relative to `|v|`) and [`place`] against the renormalising product (and its
/// quaternion's norm against 1), angles from 1e-8 to 3 rad across both series switches.
const FAST_EXP_REL: f64 = 1e-14;

/// [`InternalLinks::update`] against `frame · H_l · Pose::exp(T_l K ξ)` computed link by link
/// through the model's own twist maps: quaternion components, and translation relative to the
/// mechanism's bounding radius (or the translation, if larger), both per `max(1, θ_l)` (the
/// round-off of a twist grows with it and turns the pose by as much). The kernel forms `(R_l T_l K) ξ` instead of `T_l (K ξ)`, so
/// the twists agree to the round-off of those products (a few ulp of `|T||K||ξ|`), not bitwise.
const KERNEL_REL: f64 = 1e-13;

fn random_vec(rng: &mut rand::rngs::Xoshiro256PlusPlus, scale: f64) -> glam::DVec3 {
    glam::DVec3::new(
        rng.random_range(-scale..scale),
        rng.random_range(-scale..scale),
        rng.random_range(-scale..scale),
    )
}

#[test]
fn fast_exp_equals_pose_exp() {
    let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(6);
    let mut worst = 0.0_f64;
    for i in 0..20_000 {
        let dir = random_vec(&mut rng, 1.0).normalize();
        // Log-uniform angles, and every tenth one within 1e-6 of the series switch.
        let angle = if i % 10 == 0 {
            EXP_POLY_ANGLE * (1.0 + rng.random_range(-1e-6..1e-6))
        } else {
            10f64.powf(rng.random_range(-8.0..0.5))
        };
        let v = random_vec(&mut rng, 2.0);
        let xi = Twist::new(v, dir * angle);
        let (a, b) = (fast_exp(&xi), Pose::exp(&xi));
        let dq = (a.rotation - b.rotation).length();
        let dp = (a.translation - b.translation).length() / v.length();
        // `place` against Pose's renormalising product, from a random reference.
        let axis = random_vec(&mut rng, 1.0);
        let reference = Pose::exp(&Twist::new(glam::DVec3::new(v.y, v.z, v.x), axis * 3.0));
        let (c, d) = (place(&reference, &xi), reference * Pose::exp(&xi));
        let dc = (c.rotation - d.rotation).length() + (c.rotation.length() - 1.0).abs();
        let dt = (c.translation - d.translation).length() / (1.0 + v.length());
        worst = worst.max(dq).max(dp).max(dc).max(dt);
    }
    println!("fast_exp against Pose::exp: {worst:e}");
    assert!(worst <= FAST_EXP_REL, "{worst:e}");
}

/// The batched kernel against `Pose::exp` link by link, for one and several end effectors,
/// a fixed and a moving frame, and end-effector twists from tiny to large enough that some
/// links turn past [`EXP_POLY_ANGLE`] (the trigonometric lanes).
#[test]
fn kernel_equals_pose_exp_of_twist_maps() {
    let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(14);
    let scenes = [
        crate::scenes::helix(50),
        crate::scenes::y_shape(3),
        crate::scenes::legged_robot(4),
    ];
    for desc in scenes {
        let m = desc.build().unwrap();
        let q = Configuration::rest(&m);
        let model = ReducedModel::build(&m, &q, &[], &ConstructOptions::default()).unwrap();
        let kernel = InternalLinks::new(&model);
        assert_eq!(kernel.len(), model.internal.len());
        let n = 6 * model.end_effectors.len();
        let radius = m.bounding_radius();
        let (mut worst, mut largest_angle, mut norm_err) = (0.0_f64, 0.0_f64, 0.0_f64);
        for scale in [1e-9, 1e-4, 1e-2, 0.3, 3.0, 30.0] {
            for moving in [false, true] {
                // Displacements in the model's range: ξ = C w for a random wrench.
                let w: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
                let mut xi: Vec<f64> = (0..n)
                    .map(|r| (0..n).map(|c| model.compliance[(r, c)] * w[c]).sum())
                    .collect();
                let size = xi.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
                for x in &mut xi {
                    *x *= scale / size;
                }
                let frame = if moving {
                    Pose::exp(&Twist::new(
                        random_vec(&mut rng, 1.0),
                        random_vec(&mut rng, 1.0),
                    ))
                } else {
                    Pose::IDENTITY
                };
                let mut out = vec![Pose::IDENTITY; kernel.len()];
                kernel.update(&xi, &frame, &mut out);
                let wk = equivalent_wrenches(&model, &xi);
                for (k, got) in out.iter().enumerate() {
                    let t = link_twist(&model, k, &wk);
                    largest_angle = largest_angle.max(t.w.length());
                    let want = frame * (model.internal_reference[k] * Pose::exp(&t));
                    let turns = t.w.length().max(1.0);
                    let dq = (got.rotation - want.rotation).length() / turns;
                    let dp = (got.translation - want.translation).length()
                        / (radius.max(want.translation.length()) * turns);
                    worst = worst.max(dq).max(dp);
                    if !moving {
                        norm_err = norm_err.max((got.rotation.length() - 1.0).abs());
                    }
                }
            }
        }
        println!(
            "{}: kernel vs Pose::exp {worst:.1e}, |q| − 1 {norm_err:.1e}, angles up to {largest_angle:.2} rad",
            m.name
        );
        assert!(worst <= KERNEL_REL, "{}: {worst:e}", m.name);
        assert!(norm_err <= FAST_EXP_REL, "{}: {norm_err:e}", m.name);
        assert!(
            largest_angle > EXP_POLY_ANGLE,
            "{}: trigonometric lanes not reached",
            m.name
        );
    }
}

#[test]
fn parallel_update_is_bit_identical_and_matches_serial_statics() {
    let m = crate::scenes::helix(102).build().unwrap();
    let q = Configuration::rest(&m);
    let model = ReducedModel::build(&m, &q, &[], &ConstructOptions::default()).unwrap();
    // 101 internal links: the last batch and the last group of lanes are short.
    assert_ne!(model.internal.len() % LANES, 0);
    assert_ne!(model.internal.len() % LINK_BATCH, 0);
    // A displacement produced by a static wrench: then ξ_l = T_l K C w = T_l w.
    let w: Vec<f64> = (0..6)
        .map(|k| [3.0, -2.0, 1.0, 0.2, 0.1, -0.3][k])
        .collect();
    let xi: Vec<f64> = (0..6)
        .map(|r| (0..6).map(|c| model.compliance[(r, c)] * w[c]).sum())
        .collect();
    let kernel = InternalLinks::new(&model);
    let frame = Pose::exp(&Twist::new(
        glam::DVec3::new(0.1, 0.2, -0.3),
        glam::DVec3::new(0.5, -0.2, 0.1),
    ));
    for frame in [Pose::IDENTITY, frame] {
        // One thread takes the serial path; more threads the parallel batches.
        let mut reference = vec![Pose::IDENTITY; model.internal.len()];
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| kernel.update(&xi, &frame, &mut reference));
        for threads in [2, 3, 7] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut out = vec![Pose::IDENTITY; model.internal.len()];
            pool.install(|| kernel.update(&xi, &frame, &mut out));
            assert_eq!(bits(&out), bits(&reference), "{threads} threads");
        }
        // The convenience function is the same kernel.
        let mut out = vec![Pose::IDENTITY; model.internal.len()];
        update_internal_links(&model, &xi, &frame, &mut out);
        assert_eq!(bits(&out), bits(&reference));
    }
    // Against the full linearised statics: every internal link's twist.
    let lin = LinearStatics::new(&m, &q, Tsvd::default()).unwrap();
    let full = lin.link_twists(
        &m.end_effectors,
        &[impulse_geom::Wrench::from_array(core::array::from_fn(
            |k| w[k],
        ))],
    );
    let wk = equivalent_wrenches(&model, &xi);
    let mut worst = 0.0_f64;
    let mut size = 0.0_f64;
    for (k, &l) in model.internal.iter().enumerate() {
        let d = link_twist(&model, k, &wk) - full[l];
        worst = worst.max(d.v.abs().max_element().max(d.w.abs().max_element()));
        size = size.max(
            full[l]
                .v
                .abs()
                .max_element()
                .max(full[l].w.abs().max_element()),
        );
    }
    println!(
        "helix-102 internal links vs linearised full statics: {:.2e} relative",
        worst / size
    );
    assert!(worst <= 1e-9 * size);
}

/// The AVX kernel (where the processor has it) and the plain-array kernel give the same bits
/// for every link, for end-effector twists from 1e-6 to 1e7 (series, reduced-trigonometry and,
/// at the largest, libm lanes).
#[test]
fn avx_and_portable_kernels_are_bit_identical() {
    let m = crate::scenes::helix(50).build().unwrap();
    let q = Configuration::rest(&m);
    let model = ReducedModel::build(&m, &q, &[], &ConstructOptions::default()).unwrap();
    let kernel = InternalLinks::new(&model);
    let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(3);
    for scale in [1e-6, 0.1, 10.0, 1e3, 1e7] {
        let xi: Vec<f64> = (0..6).map(|_| rng.random_range(-scale..scale)).collect();
        let mut fast = vec![Pose::IDENTITY; kernel.len()];
        kernel.place_groups(0, &xi, &mut fast);
        let mut plain = vec![Pose::IDENTITY; kernel.len()];
        kernel.place_groups_with(crate::lanes::Portable, 0, &xi, &mut plain);
        assert_eq!(bits(&fast), bits(&plain), "scale {scale}");
    }
}
