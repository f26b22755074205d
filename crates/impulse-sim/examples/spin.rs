//! Prints every dynamic body's vertical spin and tilt at a fixed interval (development probe).
use impulse_sim::{Scene, World, run};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .ok_or("usage: spin <scene.ron> [until] [every]")?;
    let scene = Scene::read(std::path::Path::new(path))?;
    let until: f64 = args
        .get(2)
        .map_or(Ok(scene.desc.duration.unwrap_or(10.0)), |s| s.parse())?;
    let every: usize = args.get(3).map_or(Ok(20), |s| s.parse())?;
    let mut w = World::from_scene(&scene)?;
    let rec = run(&mut w, until, scene.desc.output_rate, |_| {})?;
    let dynamic: Vec<usize> = w
        .bodies()
        .enumerate()
        .filter(|(_, (_, b))| b.is_dynamic())
        .map(|(i, _)| i)
        .collect();
    for f in rec.frames.iter().step_by(every) {
        print!("{:6.2}", f.time);
        for &i in &dynamic {
            let s = f.bodies[i];
            let up = s.rotation * glam::DVec3::Z;
            print!(
                "  wz {:+8.4} tilt {:6.3}",
                s.omega.z,
                up.z.clamp(-1.0, 1.0).acos().to_degrees()
            );
        }
        println!(" ke {:.4e}", f.kinetic_energy);
    }
    println!("{:?} wall {:.3}s", rec.counters, rec.wall_time);
    Ok(())
}
