//! Runs a scene and prints one body's path every tenth frame, the counters, and every contact
//! that gained energy (a development probe): `cargo run --release -p impulse-sim --example
//! probe -- <scene.ron> <body> [until]`.
use impulse_sim::{Scene, World, run};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (Some(path), Some(body)) = (args.get(1), args.get(2)) else {
        return Err("usage: probe <scene.ron> <body> [until]".into());
    };
    let scene = Scene::read(std::path::Path::new(path))?;
    let until: f64 = match args.get(3) {
        Some(s) => s.parse()?,
        None => scene
            .desc
            .duration
            .ok_or("the scene has no duration: give one")?,
    };
    let mut w = World::from_scene(&scene)?;
    w.set_event_log(true);
    w.handle(body).ok_or("no such body")?;
    let rec = run(&mut w, until, scene.desc.output_rate, |_| {})?;
    let b = rec.index(body).ok_or("no such body")?;
    for f in rec.frames.iter().step_by(10) {
        let s = f.bodies[b];
        println!(
            "{:.3} p {:.4} v {:.4} w {:.4} ke {:.6e}",
            f.time, s.position, s.velocity, s.omega, f.kinetic_energy
        );
    }
    let gains: Vec<_> = w
        .events()
        .iter()
        .filter(|e| e.energy_after > e.energy_before * (1.0 + 1e-3))
        .collect();
    println!(
        "{} contacts, {} gained more than 0.1 % energy",
        w.events().len(),
        gains.len()
    );
    for e in gains.iter().take(5) {
        println!("  {e:?}");
    }
    println!("{:?} wall {:.3}s", rec.counters, rec.wall_time);
    Ok(())
}
