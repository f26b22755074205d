//! Spheres, ellipsoids and compound shapes.

use super::*;

/// A sphere on the floor (touching, apart, sunk; either order): the point straight below its
/// centre; against a box's edge: the edge point and the sphere's point on the line to it;
/// two spheres: the line of centres.
#[test]
fn spheres_touch_at_one_point() {
    let (fl, pf) = floor();
    let r = 0.1;
    let ball = Convex::Sphere(Sphere::new(r).unwrap());
    let top = face_along(&fl, DVec3::Z);
    for gap in [0.0, 0.5 * TOL, -0.3 * TOL] {
        let c = DVec3::new(0.2, -0.1, r + gap);
        let ps = Pose::from_translation(c);
        for ball_first in [true, false] {
            let m = if ball_first {
                manifold(&ball, &ps, &fl, &pf)
            } else {
                manifold(&fl, &pf, &ball, &ps)
            }
            .unwrap();
            assert_eq!(m.points().len(), 1);
            let p = m.points()[0];
            let (on_ball, on_floor, ids) = if ball_first {
                (p.point_a, p.point_b, (p.id.a, p.id.b))
            } else {
                (p.point_b, p.point_a, (p.id.b, p.id.a))
            };
            assert!(on_ball.distance(DVec3::new(c.x, c.y, gap)) < EXACT, "{m:?}");
            assert!(on_floor.distance(DVec3::new(c.x, c.y, 0.0)) < EXACT);
            assert!((p.gap - gap).abs() < EXACT);
            assert_eq!(ids, (Feature::Vertex(0), top));
        }
    }
    // Against the edge x = z = 0.5 of a unit cube.
    let cube = cuboid(DVec3::splat(0.5));
    let d = DVec3::new(1.0, 0.0, 1.0).normalize();
    let edge_point = DVec3::new(0.5, 0.1, 0.5);
    for gap in [0.0, 0.7 * TOL, -0.2 * TOL] {
        let ps = Pose::from_translation(edge_point + d * (r + gap));
        let m = manifold(&ball, &ps, &cube, &Pose::IDENTITY).unwrap();
        let p = m.points()[0];
        assert!((m.normal + d).length() < EXACT, "{m:?}");
        assert!(p.point_b.distance(edge_point) < EXACT, "{p:?}");
        assert!(p.point_a.distance(edge_point + d * gap) < EXACT);
        assert!((p.gap - gap).abs() < EXACT);
        assert!(matches!(m.features.b, Feature::Edge(_)));
    }
    let m = manifold(
        &ball,
        &Pose::IDENTITY,
        &Convex::Sphere(Sphere::new(0.2).unwrap()),
        &Pose::from_translation(DVec3::new(0.0, 0.3 + 0.5 * TOL, 0.0)),
    )
    .unwrap();
    let p = m.points()[0];
    assert!((p.gap - 0.5 * TOL).abs() < EXACT);
    assert!(p.point_a.distance(DVec3::new(0.0, r, 0.0)) < EXACT);
    assert!(p.point_b.distance(DVec3::new(0.0, r + 0.5 * TOL, 0.0)) < EXACT);
}

/// An ellipsoid resting on the floor, tilted: its lowest point from the closed form (body
/// frame: A²d/|Ad| for the downward direction d, A the semi-axes), the floor's straight below;
/// an ellipsoid against a sphere along its long axis: gap d − a − r.
#[test]
fn ellipsoids_touch_at_one_point() {
    let (fl, pf) = floor();
    let axes = DVec3::new(0.1, 0.03, 0.02);
    let e = Convex::Ellipsoid(Ellipsoid::new(axes).unwrap());
    for (tilt, gap) in [(0.0, 0.0), (0.4, 0.5 * TOL), (1.1, -0.4 * TOL)] {
        let q = DQuat::from_rotation_z(0.3) * DQuat::from_rotation_x(tilt);
        let d = q.inverse() * -DVec3::Z;
        let low = q * (axes * axes * d / (axes * d).length());
        let c = DVec3::new(0.1, 0.05, -low.z + gap);
        let pe = Pose::new(q, c);
        let m = manifold(&e, &pe, &fl, &pf).unwrap();
        let p = m.points()[0];
        assert_eq!(m.points().len(), 1);
        assert!(p.point_a.distance(c + low) < EXACT, "{p:?} vs {}", c + low);
        assert!(
            p.point_b
                .distance(DVec3::new(c.x + low.x, c.y + low.y, 0.0))
                < EXACT
        );
        assert!((p.gap - gap).abs() < EXACT);
    }
    let s = Convex::Sphere(Sphere::new(0.05).unwrap());
    for gap in [0.3 * TOL, -0.3 * TOL] {
        let ps = Pose::from_translation(DVec3::new(0.15 + gap, 0.0, 0.0));
        let m = manifold(&e, &Pose::IDENTITY, &s, &ps).unwrap();
        let p = m.points()[0];
        assert!((p.gap - gap).abs() < EXACT, "{p:?}");
        assert!(p.point_a.distance(DVec3::new(0.1, 0.0, 0.0)) < EXACT);
        assert!(p.point_b.distance(DVec3::new(0.1 + gap, 0.0, 0.0)) < EXACT);
    }
}

/// An L-shaped compound of two bars lying on the floor: one manifold per bar, each its four
/// bottom corners; raised on one end beyond the tolerance, only the other bar's.
#[test]
fn a_compound_has_a_manifold_per_touching_piece() {
    let (fl, pf) = floor();
    let floor_shape = Shape::compound(vec![(pf, fl)]).unwrap();
    let bar = |h: DVec3| cuboid(h);
    let l = Shape::compound(vec![
        (Pose::IDENTITY, bar(DVec3::new(0.2, 0.02, 0.02))),
        (
            Pose::from_translation(DVec3::new(-0.18, 0.12, 0.0)),
            bar(DVec3::new(0.02, 0.1, 0.02)),
        ),
    ])
    .unwrap();
    let mut cache = ManifoldCache::default();
    let pl = Pose::from_translation(DVec3::new(0.0, 0.0, 0.02));
    let ms = shape_manifolds(&l, &pl, &floor_shape, &Pose::IDENTITY, TOL, &mut cache).unwrap();
    assert_eq!(ms.len(), 2);
    assert_eq!((ms[0].pieces, ms[1].pieces), ((0, 0), (1, 0)));
    for m in &ms {
        assert_eq!(m.points().len(), 4);
        assert!(
            m.points()
                .iter()
                .all(|p| p.gap.abs() < EXACT && p.point_a.z.abs() < EXACT)
        );
    }
    // Tilted about the long bar's far end: the upright bar lifts off.
    let q = DQuat::from_rotation_y(0.01);
    let pivot = DVec3::new(0.2, 0.0, 0.0);
    let pt = Pose::new(q, pivot - q * (pivot - DVec3::new(0.0, 0.0, 0.02)));
    let ms = shape_manifolds(&l, &pt, &floor_shape, &Pose::IDENTITY, TOL, &mut cache).unwrap();
    assert_eq!(ms.len(), 1, "{ms:?}");
    assert_eq!(ms[0].pieces, (0, 0));
    assert_eq!(ms[0].points().len(), 2);
}

/// A compound of a bar lying on the floor within the tolerance, a block raised above it and a
/// block above a far tile: [`shape_manifolds_near`] gives the bar's manifold, the raised
/// block's distance to the floor and its direction exactly (a face over a face: its height
/// above the floor), and for the piece pairs it did not measure a bound no greater than their
/// brute-force distance and above the tolerance.
#[test]
fn a_compound_reports_how_close_its_other_pieces_are() {
    let (fl, pf) = floor();
    let tile = cuboid(DVec3::splat(0.05));
    let tile_pose = Pose::from_translation(DVec3::new(3.0, 0.0, 0.05));
    let ground = Shape::compound(vec![(pf, fl), (tile_pose, tile.clone())]).unwrap();
    let (bar, block) = (
        cuboid(DVec3::new(0.2, 0.02, 0.02)),
        cuboid(DVec3::splat(0.02)),
    );
    let block_at = DVec3::new(0.3, 0.0, 0.03);
    let l = Shape::compound(vec![
        (Pose::IDENTITY, bar.clone()),
        (Pose::from_translation(block_at), block.clone()),
    ])
    .unwrap();
    let pl = Pose::from_translation(DVec3::new(0.0, 0.0, 0.02 + 0.5 * TOL));
    let mut cache = ManifoldCache::default();
    let mut near = Clearances::NONE;
    let ms = shape_manifolds_near(
        &l,
        &pl,
        &ground,
        &Pose::IDENTITY,
        TOL,
        &mut cache,
        &mut near,
    )
    .unwrap();
    assert_eq!(ms.len(), 1);
    assert_eq!(ms[0].pieces, (0, 0));
    // The raised block's bottom face is 0.03 + 0.5·TOL above the floor's top face.
    let raised: Vec<_> = near
        .measured
        .iter()
        .filter(|c| c.pieces == (1, 0))
        .collect();
    assert_eq!(raised.len(), 1, "{near:?}");
    assert!(
        (raised[0].gap - (0.03 + 0.5 * TOL)).abs() < EXACT,
        "{near:?}"
    );
    assert!(
        (raised[0].direction - DVec3::NEG_Z).length() < EXACT,
        "{near:?}"
    );
    // Every pair with the far tile went unmeasured: its bound is a lower bound.
    assert!(near.measured.iter().all(|c| c.pieces.1 == 0), "{near:?}");
    let world_tile = Pose::IDENTITY * tile_pose;
    let truth = [
        (Pose::IDENTITY, &bar),
        (Pose::from_translation(block_at), &block),
    ]
    .iter()
    .map(|(p, c)| brute::closest(poly(c), &(pl * *p), poly(&tile), &world_tile).distance)
    .fold(f64::INFINITY, f64::min);
    assert!(
        near.unmeasured > TOL && near.unmeasured <= truth,
        "bound {} against the distance {truth}",
        near.unmeasured
    );
    // Without asking, the manifolds are the same.
    let plain = shape_manifolds(&l, &pl, &ground, &Pose::IDENTITY, TOL, &mut cache).unwrap();
    assert_eq!(plain, ms);
}
