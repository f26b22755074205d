use glam::DVec3;

use super::*;
use crate::batch::Shard;
use crate::scene::{Scene, ShapeDesc};
use crate::world::World;

const G: f64 = 9.81;

/// The ideal path without spin is the thesis's sliding-to-rolling case (V7): sliding for
/// t* = 2v₀/(7μg) over s* = 12v₀²/(49μg), then rolling at 5v₀/7.
#[test]
fn ideal_crossing_matches_the_sliding_to_rolling_formulas() {
    let (v0, mu, r) = (8.0, 0.2, 0.108);
    let (t_star, s_star) = (2.0 * v0 / (7.0 * mu * G), 12.0 * v0 * v0 / (49.0 * mu * G));
    for distance in [18.288, 25.0] {
        let (x, t) =
            ideal_crossing(DVec3::new(0.0, v0, 0.0), DVec3::ZERO, r, mu, G, distance).unwrap();
        let expected = t_star + (distance - s_star) / (5.0 * v0 / 7.0);
        assert!((t - expected).abs() < 1e-12 * expected, "{t} vs {expected}");
        assert_eq!(x, 0.0);
    }
    // Still sliding at the line: v₀t − μgt²/2 = d.
    let d = 0.5 * s_star;
    let (_, t) = ideal_crossing(DVec3::new(0.0, v0, 0.0), DVec3::ZERO, r, mu, G, d).unwrap();
    let expected = (v0 - (v0 * v0 - 2.0 * mu * G * d).sqrt()) / (mu * G);
    assert!((t - expected).abs() < 1e-12, "{t} vs {expected}");
    // No friction: a straight line at v₀; a ball thrown backwards never gets there.
    let (_, t) = ideal_crossing(DVec3::new(0.0, v0, 0.0), DVec3::ZERO, r, 0.0, G, 8.0).unwrap();
    assert!((t - 1.0).abs() < 1e-15);
    assert!(ideal_crossing(DVec3::new(0.0, -1.0, 0.0), DVec3::ZERO, r, 0.2, G, 1.0).is_none());
}

/// Brute force: a hook's path from integrating the sliding sphere's equations in small
/// steps (force −μmg along the slip, torque r × F), against the closed form.
#[test]
fn ideal_crossing_matches_integration_of_a_sliding_hook() {
    let s = ThrowSettings::default();
    let (v0, w0) = s.launch(ThrowKind::Hook);
    let (r, mu, m, distance) = (0.108, 0.2, 7.26, 18.288);
    let inertia = 0.4 * m * r * r;
    let (mut p, mut v, mut w, mut t) = (DVec3::ZERO, v0, w0, 0.0);
    let dt = 1e-6;
    let arm = DVec3::new(0.0, 0.0, -r);
    while p.y < distance {
        let slip = v + w.cross(arm);
        if slip.length() > 2.0 * 3.5 * mu * G * dt {
            let f = -mu * m * G * slip.normalize();
            v += f / m * dt;
            w += arm.cross(f) / inertia * dt;
        }
        p += v * dt;
        t += dt;
    }
    let back = (p.y - distance) / v.y;
    let (x, tc) = ideal_crossing(v0, w0, r, mu, G, distance).unwrap();
    assert!((p.x - v.x * back - x).abs() < 1e-4, "{} vs {x}", p.x);
    assert!((t - back - tc).abs() < 1e-4, "{t} vs {tc}");
    // The hook comes back left: it crosses well left of where it was released.
    assert!(x < -0.1, "{x}");
}

/// The alley with its pins taken away: the engine's ball, thrown as each kind, crosses the
/// pin line where the ideal model says (the aim of every throw rests on this). Measured:
/// 4 µm and 3 µs off for the hook, against 0.1 mm and 0.1 ms allowed.
#[test]
fn the_engine_rolls_the_ball_where_the_ideal_model_says() {
    let alley = AlleyDesc::default();
    let s = ThrowSettings::default();
    for kind in [ThrowKind::Straight, ThrowKind::Hook] {
        let (v, w) = s.launch(kind);
        let mut d = alley.scene(0.0);
        d.bodies.retain(|b| !b.name.starts_with("pin"));
        d.contacts.retain(|c| c.a != "pin" && c.b != "pin");
        let ball = d.bodies.last_mut().unwrap();
        ball.velocity = v.to_array();
        ball.angular_velocity = w.to_array();
        let mut world = World::from_scene(&Scene::new(d, ".")).unwrap();
        let h = world.handle("ball").unwrap();
        let line = alley.pin_line();
        let (mut last, mut t) = (DVec3::ZERO, 0.0);
        let crossing = loop {
            t += 1.0 / POLL_RATE;
            world.step_until(t).unwrap();
            let p = world.body(h).unwrap().pose.translation;
            if p.y >= line {
                let f = (line - last.y) / (p.y - last.y);
                break (last.x + f * (p.x - last.x), t - (1.0 - f) / POLL_RATE);
            }
            last = p;
            assert!(t < 10.0, "{kind:?}: the ball did not reach the pin line");
        };
        let (x, tc) = ideal_crossing(
            v,
            w,
            alley.ball.radius,
            alley.contacts.ball_lane.friction,
            G,
            line,
        )
        .unwrap();
        assert!(
            (crossing.0 - x).abs() < 1e-4,
            "{kind:?}: crossed at x = {} m, ideal {x}",
            crossing.0
        );
        assert!(
            (crossing.1 - tc).abs() < 1e-4,
            "{kind:?}: crossed at t = {} s, ideal {tc}",
            crossing.1
        );
    }
}

/// Analytic mass properties of the pin (stacked frusta over inscribed regular polygons)
/// against the engine's, and the rack's geometry by brute force.
#[test]
fn pins_have_the_profiles_mass_centre_and_stand_in_a_triangle() {
    let alley = AlleyDesc::default();
    let n = f64::from(alley.pin.sides);
    let area = |d: f64| n / 2.0 * (d / 2.0).powi(2) * (std::f64::consts::TAU / n).sin();
    let (mut volume, mut moment) = (0.0, 0.0);
    for w in alley.pin.profile.windows(2) {
        let (h, a1, a2) = (w[1][0] - w[0][0], area(w[0][1]), area(w[1][1]));
        let m = (a1 * a2).sqrt();
        let v = h / 3.0 * (a1 + m + a2);
        let c = h * (a1 + 2.0 * m + 3.0 * a2) / (4.0 * (a1 + m + a2));
        volume += v;
        moment += v * (w[0][0] + c);
    }
    let com_height = moment / volume;
    let world = World::from_scene(&Scene::new(alley.scene(0.0), ".")).unwrap();
    let gap = PLACE_GAP_REL * alley.collision_epsilon;
    let mut spots = Vec::new();
    for k in 1..=PIN_COUNT {
        let b = world
            .body(world.handle(&format!("pin{k}")).unwrap())
            .unwrap();
        let mass = b.mass.as_ref().unwrap().mass;
        assert!((mass - alley.pin.mass).abs() < 1e-12, "pin{k} mass {mass}");
        let c = b.pose.translation;
        assert!(
            (c.z - gap - com_height).abs() < 1e-9,
            "pin{k}: centre of mass {} m up, analytic {com_height}",
            c.z - gap
        );
        spots.push(c);
    }
    // Ten spots, 18 neighbouring pairs exactly one spacing apart, none closer.
    let mut close = 0;
    for i in 0..PIN_COUNT {
        for j in i + 1..PIN_COUNT {
            let d = (spots[i] - spots[j]).length();
            assert!(d > alley.pin.spacing - 1e-12, "pins {i}, {j}: {d}");
            if d < alley.pin.spacing + 1e-12 {
                close += 1;
            }
        }
    }
    assert_eq!(close, 18);
    assert!((spots[0].truncate() - glam::DVec2::new(0.0, alley.pin_line())).length() < 1e-12);
    // The rack is symmetric about x = 0: pin 2 mirrors 3, 7 mirrors 10.
    assert!((spots[1].x + spots[2].x).abs() < 1e-12);
    assert!((spots[6].x + spots[9].x).abs() < 1e-12);
    // Numbered as bowlers do: 2, 4, 7 on the left (−x), 3, 6, 10 on the right, 7 to 10 in
    // the back row.
    assert!(spots[1].x < 0.0 && spots[3].x < 0.0 && spots[6].x < 0.0);
    assert!(spots[2].x > 0.0 && spots[5].x > 0.0 && spots[9].x > 0.0);
    assert!(spots[6].y == spots[9].y && spots[6].y > spots[3].y);
    assert_eq!(alley.pin_spot(0), None);
    assert_eq!(alley.pin_spot(PIN_COUNT + 1), None);
}

/// The standing rule by construction: upright on the spot stands; tipped past 10°, lifted,
/// in the pit or off the deck's end does not.
#[test]
fn a_pin_stands_only_upright_on_the_deck() {
    use glam::DQuat;
    use impulse_geom::Pose;
    let alley = AlleyDesc::default();
    let spot = alley.pin_spot(5).unwrap();
    let at = |x: f64, y: f64, z: f64, tilt_degrees: f64| Pose {
        translation: DVec3::new(x, y, z),
        rotation: DQuat::from_rotation_x(tilt_degrees.to_radians()),
    };
    assert!(pin_stands(&alley, at(spot[0], spot[1], 0.0, 0.0)));
    assert!(pin_stands(&alley, at(spot[0] + 0.1, spot[1], 0.002, 9.0)));
    assert!(!pin_stands(&alley, at(spot[0], spot[1], 0.0, 11.0)));
    assert!(!pin_stands(&alley, at(spot[0], spot[1], 0.0, 90.0)));
    assert!(!pin_stands(&alley, at(spot[0], spot[1], 0.05, 0.0)));
    assert!(!pin_stands(
        &alley,
        at(0.0, alley.deck_end() + 0.5, -PIT_DEPTH, 0.0)
    ));
    assert!(!pin_stands(
        &alley,
        at(0.0, alley.deck_end() + 0.01, 0.0, 0.0)
    ));
    assert!(!pin_stands(&alley, at(alley.lane_width, spot[1], 0.0, 0.0)));
}

/// The gutter's cross-section: every facet corner on the circle through the lane's edge,
/// the bottom and the outer edge; the edges at lane height, nothing below the depth.
#[test]
fn the_gutter_is_the_circular_arc_of_its_width_and_depth() {
    let alley = AlleyDesc::default();
    let (half, depth) = (alley.gutter_width / 2.0, alley.gutter_depth);
    let rho = (half * half + depth * depth) / (2.0 * depth);
    let ShapeDesc::Compound { parts } = alley.gutter_shape(1.0) else {
        panic!("a gutter is a compound");
    };
    assert_eq!(parts.len() as u32, GUTTER_FACETS);
    let mut top: Vec<[f64; 3]> = Vec::new();
    for part in &parts {
        let ShapeDesc::Hull { points } = &part.shape else {
            panic!("a gutter facet is a hull");
        };
        assert_eq!(points.len(), 8);
        top.extend(points.iter().filter(|p| p[1] == 1.0).take(2));
    }
    for p in &top {
        let r = (p[0] * p[0] + (p[2] - (rho - depth)).powi(2)).sqrt();
        assert!(
            (r - rho).abs() < 1e-12,
            "{p:?} is {r} from the centre, not {rho}"
        );
        assert!(p[2] >= -depth - 1e-12 && p[2] <= 1e-12, "{p:?}");
    }
    let x_max = top.iter().map(|p| p[0]).fold(f64::MIN, f64::max);
    let x_min = top.iter().map(|p| p[0]).fold(f64::MAX, f64::min);
    assert!((x_max - half).abs() < 1e-12 && (x_min + half).abs() < 1e-12);
    assert!(top.iter().filter(|p| p[2].abs() < 1e-12).count() >= 2);
}

/// A hook aimed at the window's right edge drifts into the right gutter (the closed form's
/// drift: it is released 24 cm right of its aim and goes 10 cm further before it turns) and
/// rolls down the gutter's middle past the pins: all ten still stand at the end, counted
/// from their poses.
#[test]
fn a_gutter_ball_fells_no_pin() {
    let alley = AlleyDesc::default();
    let gutter = alley.lane_width / 2.0 + alley.gutter_width / 2.0;
    let s = ThrowSettings {
        window_center: 0.195,
        window_width: 1e-3,
        ..ThrowSettings::default()
    };
    let o = run_throw(&alley, &s, 1, 1, 1).unwrap();
    assert_eq!(o.kind, ThrowKind::Hook);
    assert_eq!((o.felled, o.standing.len()), (0, PIN_COUNT), "{o:?}");
    let x = o.crossing.unwrap();
    assert!(
        (x - gutter).abs() < 0.02,
        "crossed at {x}, the gutter's middle is {gutter}"
    );
    assert!(o.settled);
}

#[test]
fn bad_alleys_and_settings_are_refused_naming_the_field() {
    let field_of = |e: crate::SimError| match e {
        crate::SimError::Invalid { field, .. } => field,
        other => panic!("{other}"),
    };
    let good = AlleyDesc::default();
    type Edit = Box<dyn Fn(&mut AlleyDesc)>;
    let cases: Vec<(&str, Edit)> = vec![
        ("lane_width", Box::new(|a| a.lane_width = -1.0)),
        ("lane_width", Box::new(|a| a.lane_width = 0.5)),
        ("ball.mass", Box::new(|a| a.ball.mass = 0.0)),
        ("ball.radius", Box::new(|a| a.ball.radius = f64::NAN)),
        ("pin.profile", Box::new(|a| a.pin.profile.truncate(1))),
        ("pin.profile", Box::new(|a| a.pin.profile[3][0] = 0.0)),
        ("pin.profile", Box::new(|a| a.pin.profile[0][0] = 0.01)),
        ("pin.profile", Box::new(|a| a.pin.profile[0][1] = 0.0)),
        ("pin.sides", Box::new(|a| a.pin.sides = 2)),
        ("pin.spacing", Box::new(|a| a.pin.spacing = 0.1)),
        (
            "deck_beyond_head_pin",
            Box::new(|a| a.deck_beyond_head_pin = 0.5),
        ),
        (
            "contacts.ball_pin",
            Box::new(|a| a.contacts.ball_pin.restitution = 2.0),
        ),
        (
            "gutter_depth",
            Box::new(|a| a.gutter_depth = a.gutter_width),
        ),
    ];
    for (field, edit) in cases {
        let mut a = good.clone();
        edit(&mut a);
        assert_eq!(field_of(a.validate().unwrap_err()), field);
        // The study refuses it before running anything.
        let err = run_throws(&a, &ThrowSettings::default(), 1, 1, Shard::ALL, 1, &|_| {});
        assert_eq!(field_of(err.unwrap_err()), field);
    }
    let settings: Vec<(&str, ThrowSettings)> = vec![
        (
            "speed",
            ThrowSettings {
                speed: 0.0,
                ..Default::default()
            },
        ),
        (
            "window_width",
            ThrowSettings {
                window_width: -0.4,
                ..Default::default()
            },
        ),
        (
            "hook_angle_degrees",
            ThrowSettings {
                hook_angle_degrees: 90.0,
                ..Default::default()
            },
        ),
        (
            "settle_time",
            ThrowSettings {
                settle_time: f64::INFINITY,
                ..Default::default()
            },
        ),
    ];
    for (field, s) in settings {
        assert_eq!(field_of(s.validate().unwrap_err()), field);
    }
    // A window whose hooks would start beyond the gutters.
    let far = ThrowSettings {
        window_center: 0.6,
        ..Default::default()
    };
    let run = |s: &ThrowSettings, n| run_throws(&good, s, 1, n, Shard::ALL, 1, &|_| {});
    assert_eq!(
        field_of(run(&far, 1).unwrap_err()),
        "window_center/window_width"
    );
    let normal = ThrowSettings::default();
    assert_eq!(
        field_of(run(&normal, MAX_THROWS_PER_KIND + 1).unwrap_err()),
        "throws"
    );
    assert_eq!(
        field_of(
            run_throws(
                &good,
                &ThrowSettings::default(),
                1,
                0,
                Shard::ALL,
                1,
                &|_| {}
            )
            .unwrap_err()
        ),
        "throws"
    );
    assert_eq!(
        field_of(throw_scene(&good, &ThrowSettings::default(), 1, 3, 6).unwrap_err()),
        "throw"
    );
    // The file round-trips; a malformed file is a parse error, not a panic.
    let text = good.to_ron().unwrap();
    assert_eq!(AlleyDesc::from_ron(&text, "alley").unwrap(), good);
    assert!(matches!(
        AlleyDesc::from_ron("Alley(lane_width: 1.0)", "bad.ron"),
        Err(crate::SimError::Parse { .. })
    ));
}

fn outcome(index: u64, crossing: Option<f64>, felled: u32) -> ThrowOutcome {
    ThrowOutcome {
        index,
        kind: ThrowKind::of(index),
        start_x: 0.0,
        aim_x: 0.0,
        crossing,
        felled,
        standing: Vec::new(),
        time: 0.0,
        settled: true,
    }
}

#[test]
fn merge_rebuilds_the_study_and_refuses_strangers() {
    let file = |outcomes: Vec<ThrowOutcome>| BowlingFile {
        alley: AlleyDesc::default(),
        settings: ThrowSettings::default(),
        seed: 3,
        throws_per_kind: 3,
        outcomes,
    };
    let all: Vec<ThrowOutcome> = (0..6)
        .map(|i| outcome(i, Some(0.01 * i as f64), i as u32))
        .collect();
    let shard = |k: u64| {
        let s = Shard { index: k, count: 2 };
        file(all.iter().filter(|o| s.owns(o.index)).cloned().collect())
    };
    assert_eq!(merge(&[shard(1), shard(0)]).unwrap(), file(all.clone()));
    assert!(merge(&[shard(0), shard(0)]).is_err());
    assert!(merge(&[]).is_err());
    let mut other = shard(1);
    other.seed = 4;
    assert!(merge(&[shard(0), other]).is_err());
    let mut beyond = shard(1);
    beyond.outcomes.push(outcome(6, None, 0));
    assert!(merge(&[shard(0), beyond]).is_err());
}

#[test]
fn bands_and_bins_average_what_they_hold() {
    // Hand-computed: straight throws (even indices) at −0.05, 0.00, +0.05, +0.07 with
    // 6, 9, 7, 10 pins; hooks at +0.08 (9) and never crossing.
    let o = vec![
        outcome(0, Some(-0.05), 6),
        outcome(2, Some(0.0), 9),
        outcome(4, Some(0.05), 7),
        outcome(6, Some(0.07), 10),
        outcome(1, Some(0.08), 9),
        outcome(3, None, 0),
    ];
    let m = band(&o, ThrowKind::Straight, 0.04, 0.06, true);
    assert_eq!((m.n, m.mean), (2, 6.5));
    assert!((m.se - 0.5).abs() < 1e-15);
    let all = band(
        &o,
        ThrowKind::Straight,
        f64::NEG_INFINITY,
        f64::INFINITY,
        false,
    );
    assert_eq!((all.n, all.mean), (4, 8.0));
    let rows = bins(&o, -0.1, 0.1, BIN_WIDTH);
    assert_eq!(rows.len(), 40);
    assert_eq!(rows.iter().map(|r| r.straight.n + r.hook.n).sum::<u64>(), 5);
    let s = summarize(&o, (-0.06, 0.075));
    assert_eq!(
        (s.pocket_straight.n, s.pocket_hook.n, s.no_crossing),
        (1, 1, 1)
    );
    assert_eq!(
        (s.all.0.n, s.all.0.mean, s.all.1.n, s.outside),
        (4, 8.0, 0, 1)
    );
    // A window not a whole number of bins ends with a short bin; a silly one gives none.
    let odd = bins(&o, 0.0, 0.0123, BIN_WIDTH);
    assert_eq!(odd.len(), 3);
    assert_eq!(odd[2].hi, 0.0123);
    assert!(bins(&o, 0.0, 1e300, BIN_WIDTH).is_empty());
    assert!(bins(&o, 0.0, f64::NAN, BIN_WIDTH).is_empty());
    // No spread, no standard error: the difference in standard errors is unknown.
    let same = Mean::of([9.0, 9.0]);
    assert!(same.z_over(&same).is_nan());
    let z = Mean::of([9.0, 10.0]).z_over(&Mean::of([8.0, 9.0]));
    assert!((z - 2.0_f64.sqrt()).abs() < 1e-12, "{z}");
    let csv = to_csv(&rows);
    assert_eq!(csv.lines().count(), 41);
    assert!(csv.lines().any(|l| l == "0.0700,0.0750,1,10,0,"), "{csv}");
}
