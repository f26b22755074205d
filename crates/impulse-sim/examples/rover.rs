//! The bundled rover standing (or driven at a wheel speed): chassis drift, penetration by the
//! checking monitor, counters (a development probe):
//! `cargo run --release -p impulse-sim --example rover -- [seconds] [wheel rad/s] [impulse]`.
use impulse_sim::{ContactMode, Scene, World};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let until: f64 = args.get(1).map_or(Ok(5.0), |s| s.parse())?;
    let omega: f64 = args.get(2).map_or(Ok(0.0), |s| s.parse())?;
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/scenes/rover.ron");
    let mut scene = Scene::read(&path)?;
    scene.desc.bodies.retain(|b| !b.name.starts_with("block"));
    for c in &mut scene.desc.multibodies[0].controllers {
        if let impulse_sim::scene::ControllerDesc::Pd { target_rate, .. } = c {
            *target_rate = omega;
        }
    }
    if args.get(3).is_some_and(|s| s == "impulse") {
        scene.desc.contact_model = ContactMode::Impulse;
    }
    let mut w = World::from_scene(&scene)?;
    w.set_checking(true);
    let h = w.multibody_handle("rover").ok_or("rover")?;
    let chassis = w.link_body(h, "chassis").ok_or("chassis")?;
    let start = w.state(chassis)?.position;
    let t0 = std::time::Instant::now();
    let mut t = 0.0;
    while t < until - 1e-12 {
        t = (t + 0.5).min(until);
        w.step_until(t)?;
        let p = w.state(chassis)?.position;
        let c = w.counters();
        println!(
            "t {t:.1}: chassis at {:.6?} moved {:.3e} m ({:.2} eps), z {:.6}, island steps {}, link contacts {}, rollbacks {} (box {}, slack {}), pen {:.3} eps",
            p,
            (p - start).length(),
            (p - start).length() / w.collision_epsilon(),
            p.z,
            c.island_steps,
            c.link_contacts,
            c.rollbacks,
            c.box_violations,
            c.slack_violations,
            w.checked_penetration()
                .map_or(f64::NAN, |r| r.max_depth / w.collision_epsilon())
        );
    }
    println!("wall {:.3} s", t0.elapsed().as_secs_f64());
    Ok(())
}
