//! The bundled mechanisms of FORK⁻¹S §8 as descriptions (the files in `fixtures/mechanisms/`
//! are these, written out): helix, spring ladder, "Y" with a cross-bar, loop structure (ring),
//! robot arm and a multi-legged robot. Every joint has compliance `C_θ = 0.001` as in Fig. 5
//! unless said otherwise; links are 0.1 kg rods.

use core::f64::consts::PI;

use crate::desc::{BaseDesc, JointDesc, LinkDesc, MechanismDesc, ShapeDesc};

/// Joint compliance of the Fig. 5 mechanisms (rad/(N·m)).
pub const COMPLIANCE: f64 = 0.001;
/// Joint damping of the bundled mechanisms (N·m·s/rad): light, a few percent of critical.
pub const DAMPING: f64 = 0.05;
/// Mass of one link (kg).
pub const LINK_MASS: f64 = 0.1;

fn rod(name: &str, p: [f64; 3], length: f64) -> LinkDesc {
    // A 0.1 kg rod of the given length: I = m l²/12 about its transverse axes.
    let it = LINK_MASS * length * length / 12.0;
    LinkDesc::new(name, p).mass(LINK_MASS, [it, it, it * 0.1 + 1e-6])
}

fn ball(name: &str, parent: &str, child: &str, anchor: [f64; 3]) -> JointDesc {
    JointDesc::ball(name, parent, child, anchor)
        .compliance(&[COMPLIANCE])
        .damping(&[DAMPING])
}

fn hinge(name: &str, parent: &str, child: &str, anchor: [f64; 3], axis: [f64; 3]) -> JointDesc {
    JointDesc::hinge(name, parent, child, anchor, axis)
        .compliance(&[COMPLIANCE])
        .damping(&[DAMPING])
}

/// A helix of `n` links joined by ball joints, base at the bottom, the top link the end
/// effector; 8 links per turn of radius 0.2 m, rising 0.05 m per link.
#[must_use]
pub fn helix(n: usize) -> MechanismDesc {
    let mut d = MechanismDesc::new(&format!("helix-{n}"));
    d.description = "FORK⁻¹S Fig. 5 (left): a helix of ball-jointed links".to_owned();
    let (radius, rise, per_turn) = (0.2, 0.05, 8.0);
    let at = |i: usize| {
        let a = 2.0 * PI * i as f64 / per_turn;
        [radius * a.cos(), radius * a.sin(), rise * i as f64]
    };
    let step = ((2.0 * radius * (PI / per_turn).sin()).powi(2) + rise * rise).sqrt();
    d.link(LinkDesc::new("base", at(0)));
    for i in 1..=n {
        let name = format!("l{i}");
        let mut link = rod(&name, at(i), step);
        if i == n {
            link = link.shape(ShapeDesc::Sphere {
                radius: 0.03,
                center: [0.0; 3],
            });
        }
        d.link(link);
        let parent = if i == 1 {
            "base".to_owned()
        } else {
            format!("l{}", i - 1)
        };
        d.joint(ball(&format!("j{i}"), &parent, &name, at(i - 1)));
    }
    d.end_effector(&format!("l{n}"));
    d
}

/// A spring ladder of `n` post links (n even): two rails of n/2 ball-jointed posts, a hinge
/// rung between the posts at every level, and a top bar (the end effector) closing the last
/// level. Every rung and the top bar close a loop.
#[must_use]
pub fn ladder(n: usize) -> MechanismDesc {
    let k = n.div_ceil(2);
    let mut d = MechanismDesc::new(&format!("ladder-{n}"));
    d.description = "FORK⁻¹S Fig. 5 (middle): a spring ladder, one loop per rung".to_owned();
    let (w, h) = (0.3, 0.1);
    d.link(LinkDesc::new("base", [0.0; 3]));
    for i in 0..k {
        let z = h * (i as f64 + 0.5);
        d.link(rod(&format!("L{i}"), [-w / 2.0, 0.0, z], h));
        d.link(rod(&format!("R{i}"), [w / 2.0, 0.0, z], h));
    }
    let top_z = h * k as f64;
    d.link(rod("top", [0.0, 0.0, top_z], w).shape(ShapeDesc::Box {
        half_extents: [w / 2.0, 0.02, 0.02],
        center: [0.0; 3],
    }));
    for i in 0..k {
        let z = h * i as f64;
        let (pl, pr) = if i == 0 {
            ("base".to_owned(), "base".to_owned())
        } else {
            (format!("L{}", i - 1), format!("R{}", i - 1))
        };
        d.joint(ball(
            &format!("rail_l{i}"),
            &pl,
            &format!("L{i}"),
            [-w / 2.0, 0.0, z],
        ));
        d.joint(ball(
            &format!("rail_r{i}"),
            &pr,
            &format!("R{i}"),
            [w / 2.0, 0.0, z],
        ));
        // Rung: a compliant hinge about the ladder's normal, mid-way between the posts.
        d.joint(hinge(
            &format!("rung{i}"),
            &format!("L{i}"),
            &format!("R{i}"),
            [0.0, 0.0, z + h / 2.0],
            [0.0, 1.0, 0.0],
        ));
    }
    d.joint(ball(
        "top_l",
        &format!("L{}", k - 1),
        "top",
        [-w / 2.0, 0.0, top_z],
    ));
    d.joint(ball(
        "top_r",
        &format!("R{}", k - 1),
        "top",
        [w / 2.0, 0.0, top_z],
    ));
    d.end_effector("top");
    d
}

/// A "Y": a trunk of `k` links from the base, splitting into two arms of `k` links whose tips
/// are the end effectors, with a cross-bar link joining the arms' middle links (a loop).
#[must_use]
pub fn y_shape(k: usize) -> MechanismDesc {
    let mut d = MechanismDesc::new(&format!("y-{k}"));
    d.description = "FORK⁻¹S Fig. 5 (right): a \"Y\" with a cross-bar".to_owned();
    let h = 0.1;
    d.link(LinkDesc::new("base", [0.0; 3]));
    for i in 0..k {
        d.link(rod(&format!("t{i}"), [0.0, 0.0, h * (i as f64 + 0.5)], h));
        let parent = if i == 0 {
            "base".to_owned()
        } else {
            format!("t{}", i - 1)
        };
        d.joint(hinge(
            &format!("jt{i}"),
            &parent,
            &format!("t{i}"),
            [0.0, 0.0, h * i as f64],
            if i % 2 == 0 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            },
        ));
    }
    let fork = [0.0, 0.0, h * k as f64];
    let s = h / 2f64.sqrt();
    for (side, sx) in [("a", -1.0), ("b", 1.0)] {
        for i in 0..k {
            let c = [
                sx * s * (i as f64 + 0.5),
                0.0,
                fork[2] + s * (i as f64 + 0.5),
            ];
            let mut link = rod(&format!("{side}{i}"), c, h);
            if i == k - 1 {
                link = link.shape(ShapeDesc::Sphere {
                    radius: 0.02,
                    center: [0.0; 3],
                });
            }
            d.link(link);
            let parent = if i == 0 {
                format!("t{}", k - 1)
            } else {
                format!("{side}{}", i - 1)
            };
            let anchor = [sx * s * i as f64, 0.0, fork[2] + s * i as f64];
            d.joint(ball(
                &format!("j{side}{i}"),
                &parent,
                &format!("{side}{i}"),
                anchor,
            ));
        }
    }
    // Cross-bar between the middle links of the arms.
    let mid = k / 2;
    let za = fork[2] + s * (mid as f64 + 0.5);
    let xa = s * (mid as f64 + 0.5);
    d.link(rod("bar", [0.0, 0.0, za], 2.0 * xa));
    d.joint(ball("bar_a", &format!("a{mid}"), "bar", [-xa, 0.0, za]));
    d.joint(ball("bar_b", &format!("b{mid}"), "bar", [xa, 0.0, za]));
    d.end_effector(&format!("a{}", k - 1));
    d.end_effector(&format!("b{}", k - 1));
    d
}

/// A loop structure: a ring of `n` links (n even) standing on the base, its two halves meeting
/// at the top link, with a handle link on top as the end effector.
#[must_use]
pub fn ring(n: usize) -> MechanismDesc {
    let mut d = MechanismDesc::new(&format!("ring-{n}"));
    d.description = "FORK⁻¹S Fig. 6 (bottom left): a loop structure".to_owned();
    let r = 0.3;
    let half = n / 2;
    let at = |a: f64| [r * a.sin(), 0.0, r * (1.0 - a.cos())];
    d.link(LinkDesc::new("base", [0.0; 3]));
    let dl = 2.0 * r * (PI / (2.0 * half as f64 + 2.0)).sin();
    for (side, sx) in [("p", 1.0), ("q", -1.0)] {
        for i in 0..half {
            let a = sx * PI * (i as f64 + 0.5) / (half as f64 + 1.0);
            d.link(rod(&format!("{side}{i}"), at(a), dl));
            let parent = if i == 0 {
                "base".to_owned()
            } else {
                format!("{side}{}", i - 1)
            };
            let anchor = at(sx * PI * i as f64 / (half as f64 + 1.0));
            d.joint(ball(
                &format!("j{side}{i}"),
                &parent,
                &format!("{side}{i}"),
                anchor,
            ));
        }
    }
    d.link(rod("crown", [0.0, 0.0, 2.0 * r], dl));
    let last = PI * half as f64 / (half as f64 + 1.0);
    d.joint(ball(
        "crown_p",
        &format!("p{}", half - 1),
        "crown",
        at(last),
    ));
    d.joint(ball(
        "crown_q",
        &format!("q{}", half - 1),
        "crown",
        at(-last),
    ));
    d.link(
        rod("handle", [0.0, 0.0, 2.0 * r + 0.05], 0.1).shape(ShapeDesc::Sphere {
            radius: 0.03,
            center: [0.0; 3],
        }),
    );
    d.joint(hinge(
        "handle",
        "crown",
        "handle",
        [0.0, 0.0, 2.0 * r],
        [1.0, 0.0, 0.0],
    ));
    d.end_effector("handle");
    d
}

/// A robot arm of `n` links on hinges whose axes cycle z, y, y, x (a 6-axis-like wrist
/// pattern), the last link a gripper tip.
#[must_use]
pub fn robot_arm(n: usize) -> MechanismDesc {
    let mut d = MechanismDesc::new(&format!("robot-arm-{n}"));
    d.description = "FORK⁻¹S Table 1: a robot arm of PD-servoed hinges".to_owned();
    let h = 0.08;
    d.link(LinkDesc::new("base", [0.0; 3]));
    let axes = [
        [0.0, 0.0, 1.0],
        [0.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 0.0, 0.0],
    ];
    for i in 0..n {
        let mut link = rod(&format!("a{i}"), [0.0, 0.0, h * (i as f64 + 0.5)], h);
        if i == n - 1 {
            link = link.shape(ShapeDesc::Box {
                half_extents: [0.02, 0.02, 0.02],
                center: [0.0; 3],
            });
        }
        d.link(link);
        let parent = if i == 0 {
            "base".to_owned()
        } else {
            format!("a{}", i - 1)
        };
        d.joint(hinge(
            &format!("q{i}"),
            &parent,
            &format!("a{i}"),
            [0.0, 0.0, h * i as f64],
            axes[i % 4],
        ));
    }
    d.end_effector(&format!("a{}", n - 1));
    d
}

/// A multi-legged robot: a free 2 kg body with `legs` legs of three hinge-jointed links
/// (hip yaw, hip pitch, knee), feet (spheres) as end effectors, under gravity.
#[must_use]
pub fn legged_robot(legs: usize) -> MechanismDesc {
    let mut d = MechanismDesc::new(&format!("legged-{legs}"));
    d.description = "FORK⁻¹S Fig. 1: a multi-legged robot on a free base".to_owned();
    d.base(BaseDesc::Free).gravity([0.0, 0.0, -9.81]);
    let body_z = 0.25;
    d.link(
        LinkDesc::new("body", [0.0, 0.0, body_z])
            .mass(2.0, [0.02, 0.02, 0.04])
            .shape(ShapeDesc::Box {
                half_extents: [0.15, 0.1, 0.03],
                center: [0.0; 3],
            }),
    );
    for leg in 0..legs {
        let a = 2.0 * PI * (leg as f64 + 0.5) / legs as f64;
        let (c, s) = (a.cos(), a.sin());
        let hip = [0.15 * c, 0.15 * s, body_z];
        let knee = [0.3 * c, 0.3 * s, body_z];
        let foot = [0.35 * c, 0.35 * s, 0.02];
        let mid = |p: [f64; 3], q: [f64; 3]| {
            [
                (p[0] + q[0]) / 2.0,
                (p[1] + q[1]) / 2.0,
                (p[2] + q[2]) / 2.0,
            ]
        };
        let names = [
            format!("hip{leg}"),
            format!("thigh{leg}"),
            format!("shin{leg}"),
        ];
        d.link(rod(&names[0], hip, 0.02));
        d.link(rod(&names[1], mid(hip, knee), 0.15));
        d.link(
            rod(&names[2], mid(knee, foot), 0.24).shape(ShapeDesc::Sphere {
                radius: 0.02,
                center: [
                    foot[0] - mid(knee, foot)[0],
                    foot[1] - mid(knee, foot)[1],
                    foot[2] - mid(knee, foot)[2],
                ],
            }),
        );
        let tangent = [-s, c, 0.0];
        d.joint(hinge(
            &format!("yaw{leg}"),
            "body",
            &names[0],
            hip,
            [0.0, 0.0, 1.0],
        ));
        d.joint(hinge(
            &format!("pitch{leg}"),
            &names[0],
            &names[1],
            hip,
            tangent,
        ));
        d.joint(hinge(
            &format!("knee{leg}"),
            &names[1],
            &names[2],
            knee,
            tangent,
        ));
        d.end_effector(&names[2]);
    }
    d
}

/// The bundled fixtures: file stem and generator.
#[must_use]
pub fn bundled() -> Vec<(&'static str, MechanismDesc)> {
    vec![
        ("helix-50", helix(50)),
        ("helix-100", helix(100)),
        ("helix-200", helix(200)),
        ("helix-400", helix(400)),
        ("ladder-36", ladder(36)),
        ("ladder-48", ladder(48)),
        ("y", y_shape(4)),
        ("loop", ring(10)),
        ("robot-arm-20", robot_arm(20)),
        ("legged-6", legged_robot(6)),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::construct::{ConstructOptions, ReducedModel};
    use crate::dynamics::ReducedSim;
    use crate::obstacle::{HeightField, Obstacle};
    use crate::reference::Configuration;

    fn fixture_dir() -> std::path::PathBuf {
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/mechanisms")
    }

    /// The files in `fixtures/mechanisms/` are exactly the generators' output (regenerate with
    /// `IMPULSE_UPDATE_FIXTURES=1 cargo test -p impulse-reduced fixtures`), and every one builds.
    #[test]
    fn fixtures_match_generators_and_build() {
        let dir = fixture_dir();
        for (stem, desc) in bundled() {
            let path = dir.join(format!("{stem}.ron"));
            let text = desc.to_ron().unwrap();
            if std::env::var_os("IMPULSE_UPDATE_FIXTURES").is_some() {
                std::fs::create_dir_all(&dir).unwrap();
                std::fs::write(&path, &text).unwrap();
            }
            let on_disk = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert_eq!(MechanismDesc::from_ron(&on_disk).unwrap(), desc, "{stem}");
            let m = desc.build().unwrap_or_else(|e| panic!("{stem}: {e}"));
            assert!(!m.end_effectors.is_empty());
        }
    }

    #[test]
    fn legged_robot_settles_on_uneven_terrain() {
        let m = legged_robot(6).build().unwrap();
        let model = ReducedModel::build(
            &m,
            &Configuration::rest(&m),
            &[],
            &ConstructOptions::default(),
        )
        .unwrap();
        let mut s = ReducedSim::new(&m, model, 1e-3).unwrap();
        // Bumpy ground: heights up to ±1.5 cm on a 5 cm grid, the feet start 1–3 cm above it.
        let (nx, ny) = (41, 41);
        let heights = (0..nx * ny)
            .map(|k| {
                let (i, j) = ((k % nx) as f64, (k / nx) as f64);
                0.015 * (0.9 * i).sin() * (0.7 * j).cos() - 0.01
            })
            .collect();
        s.obstacles.push(Obstacle::HeightField(HeightField {
            origin: [-1.0, -1.0],
            spacing: 0.05,
            nx,
            ny,
            heights,
        }));
        s.contact.friction = 0.8;
        let mass = s.model.base_inertia.mass;
        let mut last = crate::dynamics::StepReport::default();
        for _ in 0..3000 {
            last = s.step();
        }
        let p = s.linear_momentum();
        let speed = p.length() / mass;
        println!(
            "legged-6 after 3 s: {} contacts, base speed {speed:.2e} m/s, base height {:.4} m",
            last.contacts,
            s.base.unwrap().pose.translation.z
        );
        assert!(last.contacts >= 3, "the robot stands on its feet");
        assert!(speed < 1e-3, "settled: {speed}");
        // Standing, not sunk: the body stays well above the ground.
        assert!(s.base.unwrap().pose.translation.z > 0.1);
    }
}
