//! Runs a scene in checking mode and prints the worst penetration the monitor saw (a
//! development probe): `cargo run --release -p impulse-sim --example checkpen -- <scene.ron>`.
use impulse_sim::{Scene, World, run};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).ok_or("usage: checkpen <scene.ron>")?;
    let scene = Scene::read(std::path::Path::new(path))?;
    let until = scene.desc.duration.ok_or("no duration")?;
    let mut w = World::from_scene(&scene)?;
    w.set_checking(true);
    run(&mut w, until, scene.desc.output_rate, |_| {})?;
    let r = w.checked_penetration().ok_or("checking")?;
    println!(
        "max depth {:.3e} ({:.3} eps) at {:?}",
        r.max_depth,
        r.max_depth / w.collision_epsilon(),
        r.worst
    );
    Ok(())
}
