//! Runs a scene and prints a body's trajectory (a development probe).
use impulse_sim::{Scene, World, run};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = Scene::read(std::path::Path::new(&args[1])).unwrap();
    let body = &args[2];
    let until: f64 = args
        .get(3)
        .map_or(scene.desc.duration, |s| s.parse().unwrap());
    let mut w = World::from_scene(&scene).unwrap();
    let b = w.body_index(body).unwrap();
    let rec = run(&mut w, until, scene.desc.output_rate, |_| {}).unwrap();
    for f in rec.frames.iter().step_by(10) {
        let s = f.bodies[b];
        println!(
            "{:.3} p {:.4} v {:.4} w {:.4} ke {:.6e}",
            f.time, s.position, s.velocity, s.omega, f.kinetic_energy
        );
    }
    println!("{:?} wall {:.3}s", rec.counters, rec.wall_time);
}
