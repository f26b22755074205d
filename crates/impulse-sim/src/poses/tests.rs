use std::path::Path;

use glam::{DQuat, DVec3};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

use super::study::uniform_rotation;
use super::summary::belt_fed_limit;
use super::*;
use crate::scene::{MassDesc, PointMassDesc, ShapeDesc};

fn parts_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/parts")
}

fn fixture(name: &str) -> PosePart {
    PosePart::load(&parts_dir().join(name)).unwrap()
}

fn quick() -> DropSettings {
    DropSettings {
        max_time: 3.0,
        ..DropSettings::default()
    }
}

/// A study's outcomes do not depend on the thread count or on the shard split: shards run
/// apart and merged equal the whole run, field for field.
#[test]
fn drops_are_identical_for_any_thread_count_and_shard_split() {
    let part = fixture("box-1x2x3.ron");
    let s = quick();
    let whole = run_drops(&part, &s, 7, 12, Shard::ALL, 1, &|_| {}).unwrap();
    assert_eq!(whole.len(), 12);
    assert!(whole.iter().enumerate().all(|(i, o)| o.index == i as u64));
    assert_eq!(
        run_drops(&part, &s, 7, 12, Shard::ALL, 2, &|_| {}).unwrap(),
        whole
    );
    let file = |outcomes| StudyFile {
        part: part.name.clone(),
        settings: s,
        seed: 7,
        drops: 12,
        stable: StudyFile::fingerprint(&part),
        outcomes,
    };
    let shards: Vec<StudyFile> = [2, 0, 1]
        .iter()
        .map(|&k| {
            file(run_drops(&part, &s, 7, 12, Shard { index: k, count: 3 }, 1, &|_| {}).unwrap())
        })
        .collect();
    assert_eq!(merge(&shards).unwrap(), file(whole.clone()));
    // A shard merged twice, or a file of another study, is refused.
    assert!(merge(&[shards[0].clone(), shards[0].clone()]).is_err());
    let mut other = shards[1].clone();
    other.seed = 8;
    assert!(merge(&[shards[0].clone(), other]).is_err());
    // Another seed gives other drops.
    assert_ne!(
        run_drops(&part, &s, 8, 12, Shard::ALL, 1, &|_| {}).unwrap(),
        whole
    );
}

/// A part set down at rest on a stable facet (no drop, no tilt, no push) stays on it: every
/// belt drop ends where it started, and it is found at rest, not at the time limit.
#[test]
fn a_part_set_down_on_a_stable_facet_stays_on_it() {
    for name in ["box-1x2x3.ron", "cube.ron"] {
        let part = fixture(name);
        let s = DropSettings {
            height: 0.0,
            exit_speed: 0.0,
            jitter_degrees: 0.0,
            ..quick()
        };
        let stable = part.analysis.stable().len() as u64;
        let out = run_drops(&part, &s, 3, 2 * stable, Shard::ALL, 2, &|_| {}).unwrap();
        for o in out.iter().filter(|o| o.start.is_some()) {
            assert!(
                o.settled,
                "{name}: drop {} did not come to rest in {} s",
                o.index, o.time
            );
            assert_eq!(o.facet, o.start, "{name}: drop {}", o.index);
        }
        assert_eq!(
            out.iter().filter(|o| o.start.is_some()).count() as u64,
            stable,
            "one belt drop per stable facet"
        );
    }
}

/// Shoemake's rotations are uniform on SO(3): a body axis turned by them is uniform on the
/// sphere, so its z component is uniform on [−1, 1] (Archimedes) and its mean is zero; 20 000
/// samples in 10 bins, each within 5 standard deviations of 2000.
#[test]
fn uniform_starts_cover_the_sphere_evenly() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
    let n = 20_000;
    let mut bins = [0usize; 10];
    let mut mean = DVec3::ZERO;
    for _ in 0..n {
        let q: DQuat = uniform_rotation(&mut rng);
        assert!((q.length() - 1.0).abs() < 1e-12);
        let v = q * DVec3::new(0.3, -0.5, 0.81).normalize();
        bins[(((v.z + 1.0) / 2.0 * 10.0) as usize).min(9)] += 1;
        mean += v / n as f64;
    }
    let expect = n as f64 / 10.0;
    let sd = (n as f64 * 0.1 * 0.9).sqrt();
    for (k, &b) in bins.iter().enumerate() {
        assert!((b as f64 - expect).abs() < 5.0 * sd, "bin {k}: {b}");
    }
    assert!(mean.length() < 5.0 / (3.0 * n as f64).sqrt(), "{mean}");
}

/// The belt-fed limit against closed forms: a two-pose chain leaving pose 1 with probability
/// a and pose 2 with b has the stationary distribution (b, a)/(a + b) from any start; a pose
/// that is never left keeps what reaches it.
#[test]
fn belt_fed_limit_is_the_stationary_distribution() {
    // The counts as a dense matrix, handed over as the pairs with drops.
    let belt_fed_limit = |dense: &[Vec<u64>], p: Vec<f64>| {
        let sparse: Vec<(usize, usize, u64)> = dense
            .iter()
            .enumerate()
            .flat_map(|(a, row)| row.iter().enumerate().map(move |(b, &n)| (a, b, n)))
            .filter(|&(_, _, n)| n > 0)
            .collect();
        belt_fed_limit(dense.len(), &sparse, p)
    };
    // a = 30/100, b = 10/50.
    let p = belt_fed_limit(&[vec![70, 30], vec![10, 40]], vec![1.0, 0.0]);
    let (a, b) = (0.3, 0.2);
    assert!(
        (p[0] - b / (a + b)).abs() < 1e-10 && (p[1] - a / (a + b)).abs() < 1e-10,
        "{p:?}"
    );
    // Periodic chain (always swap): the lazy chain still converges, to (½, ½).
    let p = belt_fed_limit(&[vec![0, 5], vec![5, 0]], vec![1.0, 0.0]);
    assert!((p[0] - 0.5).abs() < 1e-10, "{p:?}");
    // Pose 2 absorbing, pose 3 never dropped from: 1 → 2 always; the start's share of 3 stays.
    let p = belt_fed_limit(
        &[vec![0, 4, 0], vec![0, 9, 0], vec![0, 0, 0]],
        vec![0.5, 0.3, 0.2],
    );
    assert!(
        (p[0]).abs() < 1e-10 && (p[1] - 0.8).abs() < 1e-10 && (p[2] - 0.2).abs() < 1e-10,
        "{p:?}"
    );
}

/// On a chain of 20 000 facets of which the drops touched three, the limit is that of the
/// three alone (z absorbs all that x and y hold), every other facet keeps its share, and
/// nothing of size m² is made (the dense chain took 3.2 GB per matrix here).
#[test]
fn belt_fed_limit_touches_only_the_facets_the_drops_touched() {
    let m = 20_000;
    let mut p = vec![0.5 / (m - 3) as f64; m];
    let (x, y, z) = (17, 9_000, 19_999);
    p[x] = 0.25;
    p[y] = 0.25;
    p[z] = 0.0;
    // x → y with probability 0.3 and → z with 0.1, y → x with 0.2; z is never dropped from.
    let counts = [(x, x, 60), (x, y, 30), (x, z, 10), (y, x, 10), (y, y, 40)];
    let limit = belt_fed_limit(m, &counts, p.clone());
    // z absorbs everything x and y hold: 0.5.
    assert!((limit[z] - 0.5).abs() < 1e-9, "{}", limit[z]);
    assert!(limit[x].abs() < 1e-9 && limit[y].abs() < 1e-9);
    for f in [0, 5_000, 19_998] {
        assert_eq!(limit[f], p[f]);
    }
    assert!((limit.iter().sum::<f64>() - 1.0).abs() < 1e-9);
}

/// Bad parts and settings give errors that say what is wrong, never a panic.
#[test]
fn bad_parts_and_settings_are_refused() {
    let dir = parts_dir();
    let part = |shape: ShapeDesc, point_masses: Vec<PointMassDesc>| PartFileDesc {
        name: Some("p".into()),
        shape,
        mass: Some(MassDesc::Density(1000.0)),
        point_masses,
    };
    let cube = ShapeDesc::Box {
        half_extents: [0.01; 3],
    };
    let e = PosePart::new(&part(ShapeDesc::Sphere { radius: 0.01 }, vec![]), &dir).unwrap_err();
    assert!(e.to_string().contains("polyhedral"), "{e}");
    // A heavy point mass outside the box drags the centre of mass out of the hull.
    let e = PosePart::new(
        &part(
            cube.clone(),
            vec![PointMassDesc {
                mass: 100.0,
                position: [0.5, 0.0, 0.0],
            }],
        ),
        &dir,
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("not inside the part's convex hull"),
        "{e}"
    );
    let e = PosePart::new(
        &part(
            ShapeDesc::Box {
                half_extents: [0.01, 0.01, 0.0],
            },
            vec![],
        ),
        &dir,
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("half_extents") || e.to_string().contains("shape"),
        "{e}"
    );
    let tmp = std::env::temp_dir().join(format!("impulse-poses-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    // An open mesh: a tetrahedron with a face missing.
    std::fs::write(
        tmp.join("open.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\n",
    )
    .unwrap();
    let e = PosePart::load(&tmp.join("open.obj")).unwrap_err();
    assert!(
        e.to_string().to_lowercase().contains("open") || e.to_string().contains("edge"),
        "{e}"
    );
    std::fs::write(
        tmp.join("bad.ron"),
        "Part(shape: Box(half_extents: (0.01, 0.01)))",
    )
    .unwrap();
    let e = PosePart::load(&tmp.join("bad.ron")).unwrap_err();
    assert!(e.to_string().contains("bad.ron"), "{e}");
    assert!(
        PosePart::load(&tmp.join("part.stl"))
            .unwrap_err()
            .to_string()
            .contains(".ron part file or a .obj")
    );
    std::fs::remove_dir_all(&tmp).ok();
    let good = fixture("cube.ron");
    for s in [
        DropSettings {
            height: f64::NAN,
            ..quick()
        },
        DropSettings {
            friction: -1.0,
            ..quick()
        },
        DropSettings {
            restitution: 1.5,
            ..quick()
        },
        DropSettings {
            max_time: 0.0,
            ..quick()
        },
        DropSettings {
            collision_epsilon: Some(0.0),
            ..quick()
        },
    ] {
        assert!(
            run_drops(&good, &s, 1, 1, Shard::ALL, 1, &|_| {}).is_err(),
            "{s:?}"
        );
    }
    assert!(run_drops(&good, &quick(), 1, 1, Shard::ALL, 0, &|_| {}).is_err());
    for bad in ["3/2", "1/0", "a/2", "1", "-1/2", ""] {
        assert!(bad.parse::<Shard>().is_err(), "{bad}");
    }
    assert_eq!(
        "2/5".parse::<Shard>().unwrap(),
        Shard { index: 2, count: 5 }
    );
}

/// The thesis's sequential sampling: its first 20 drops are exactly the uniform drops of
/// `run_drops` (same streams), every later one starts tilted by at most the jitter from a rest
/// pose an earlier drop ended in, and it is reproducible.
#[test]
fn thesis_feedback_starts_from_earlier_rest_poses() {
    let part = fixture("box-1x2x3.ron");
    let s = DropSettings {
        belt_fed: false,
        ..quick()
    };
    let n = THESIS_PILOT + 10;
    let seq = run_thesis_feedback(&part, &s, 4, n, &|_| {}).unwrap();
    let uniform = run_drops(&part, &s, 4, THESIS_PILOT, Shard::ALL, 2, &|_| {}).unwrap();
    assert_eq!(&seq[..THESIS_PILOT as usize], &uniform[..]);
    for o in &seq[THESIS_PILOT as usize..] {
        let from = o.start.expect("a later drop starts from a rest pose");
        assert!(
            seq[..o.index as usize]
                .iter()
                .any(|e| e.facet == Some(from))
        );
    }
    assert_eq!(run_thesis_feedback(&part, &s, 4, n, &|_| {}).unwrap(), seq);
}

/// The summary against hand counts: 10 uniform drops (6 on the first 2 × 3 face, 3 on the
/// other, 1 unsettled) and belt drops that swap the two 2 × 3 faces half the time. The uniform
/// column counts all 10 drops (0.6, 0.3 and an unsettled one); the belt-fed shares start from
/// the 9 classified drops and sum to 1; the symmetric swap makes them ½, ½.
#[test]
fn summary_counts_and_the_belt_fed_shares_sum_to_one() {
    let part = fixture("box-1x2x3.ron");
    let big: Vec<u32> = part
        .analysis
        .facets()
        .iter()
        .filter(|f| part.normal_in_part_frame(f.face).x.abs() > 0.5)
        .map(|f| f.face)
        .collect();
    let (a, b) = (big[0], big[1]);
    let drop = |index: u64, start: Option<u32>, facet: Option<u32>| DropOutcome {
        index,
        start,
        facet,
        settled: facet.is_some(),
        time: 1.0,
        rotation: [0.0, 0.0, 0.0, 1.0],
    };
    let mut out: Vec<DropOutcome> = (0..6).map(|i| drop(i, None, Some(a))).collect();
    out.extend((6..9).map(|i| drop(i, None, Some(b))));
    out.push(drop(9, None, None));
    for (k, (from, to)) in [(a, a), (a, b), (b, b), (b, a)].into_iter().enumerate() {
        out.push(drop(10 + k as u64, Some(from), Some(to)));
    }
    let s = summarize(&part, &out, 0.3, 0.95).unwrap();
    assert_eq!(
        (s.drops, s.uniform_drops, s.unsettled, s.unclassified),
        (14, 10, 1, 0)
    );
    let row = s.rows.iter().find(|r| r.facets.contains(&a)).unwrap();
    assert_eq!(row.facets.len(), 2, "the two 2 × 3 faces are one pose");
    assert_eq!(row.uniform_count, 9);
    assert!((row.uniform - 0.9).abs() < 1e-15);
    let belt: f64 = s.rows.iter().map(|r| r.belt_fed.unwrap()).sum();
    assert!((belt - 1.0).abs() < 1e-12, "belt-fed shares sum to {belt}");
    assert!((row.belt_fed.unwrap() - 1.0).abs() < 1e-12);
    assert!(summarize(&part, &out, 0.3, 1.5).is_err());
    assert!(summarize(&part, &[], 0.3, 0.95).is_err());
}

/// A part whose own frame's origin lies far from its geometry (a piece placed 0.2 m below
/// it; its half sizes decrease along x, y, z so that its principal frame is its own frame and
/// the offset stays below) is dropped like any other: the world parks it by its geometry, not
/// by its origin (parked by its origin at 0.195 m, it overlapped the belt by 1 cm).
#[test]
fn a_part_far_from_its_frame_origin_is_dropped() {
    let desc = PartFileDesc {
        name: Some("offset".into()),
        shape: ShapeDesc::Compound {
            parts: vec![crate::scene::PartDesc {
                shape: ShapeDesc::Box {
                    half_extents: [0.015, 0.01, 0.005],
                },
                position: [0.0, 0.0, -0.2],
                rotation: crate::scene::RotationDesc::Identity,
            }],
        },
        mass: Some(MassDesc::Density(1000.0)),
        point_masses: vec![],
    };
    let part = PosePart::new(&desc, &parts_dir()).unwrap();
    let out = run_drops(&part, &quick(), 2, 4, Shard::ALL, 1, &|_| {}).unwrap();
    assert!(
        out.iter().all(|o| o.settled && o.facet.is_some()),
        "{out:?}"
    );
}

/// A drop's scene replays it: `drop_scene` run by `crate::run` at the scene's frame rate (what
/// `impulse run` does) ends with the part exactly (bit for bit) where the study's drop ended,
/// for uniform and belt starts alike.
#[test]
fn a_drops_scene_replays_the_drop_exactly() {
    let part = fixture("box-1x2x3.ron");
    let s = quick();
    let out = run_drops(&part, &s, 5, 6, Shard::ALL, 2, &|_| {}).unwrap();
    for o in &out {
        let desc = drop_scene(&part, &s, 5, o.index).unwrap();
        // Through the file format, as a user would save and run it.
        let text = ron::ser::to_string(&desc).unwrap();
        let desc = crate::SceneDesc::from_ron(&text, "drop").unwrap();
        let scene = crate::Scene {
            desc,
            base_dir: parts_dir(),
        };
        let mut world = crate::World::from_scene(&scene).unwrap();
        crate::run(&mut world, s.max_time, scene.desc.output_rate, |_| {}).unwrap();
        let h = world.handle(&part.name).unwrap();
        let rotation = world.body(h).unwrap().pose.rotation.to_array();
        assert_eq!(
            rotation, o.rotation,
            "drop {} (start {:?})",
            o.index, o.start
        );
    }
}

/// A study file holds no `null`: the outcomes' `start` and `facet` and the settings' ε_c are
/// left out when they are `None`, and read back as `None`; a file written with `null` (as
/// every study file was before) reads the same.
#[test]
fn a_study_file_holds_no_null_and_reads_the_old_form() {
    let outcome = |index: u64, start: Option<u32>, facet: Option<u32>| DropOutcome {
        index,
        start,
        facet,
        settled: facet.is_some(),
        time: 0.5,
        rotation: [0.0, 0.0, 0.0, 1.0],
    };
    let file = StudyFile {
        part: "cube".into(),
        settings: DropSettings::default(),
        seed: 1,
        drops: 3,
        stable: vec![(0, 0.5), (1, 0.5)],
        outcomes: vec![
            outcome(0, None, Some(1)),
            outcome(1, Some(0), None),
            outcome(2, None, None),
        ],
    };
    let text = serde_json::to_string_pretty(&file).unwrap();
    assert!(!text.contains("null"), "{text}");
    let back: StudyFile = serde_json::from_str(&text).unwrap();
    assert_eq!(back, file);
    let mut old: serde_json::Value = serde_json::from_str(&text).unwrap();
    old["settings"]["collision_epsilon"] = serde_json::Value::Null;
    for o in old["outcomes"].as_array_mut().unwrap() {
        for key in ["start", "facet"] {
            if o.get(key).is_none() {
                o[key] = serde_json::Value::Null;
            }
        }
    }
    let old: StudyFile = serde_json::from_value(old).unwrap();
    assert_eq!(old, file);
}
