//! What became of every input in a directory: `cargo run -p fuzz-check --example tally --
//! TARGET DIR` prints how many were refused by the library, out of the check's bounds, and run
//! through every check (with or without the energy assertion), and the slowest input: how far a
//! fuzzer's corpus gets past the parsers.

use std::time::Instant;

use fuzz_check::{Outcome, Violation};

type Check = fn(&[u8]) -> Result<Outcome, Violation>;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [target, dir] = args.as_slice() else {
        return Err("usage: tally TARGET DIR".into());
    };
    let check: Check = match target.as_str() {
        "scene" => fuzz_check::check_scene,
        "obj" => fuzz_check::check_mesh,
        "urdf" => fuzz_check::check_urdf,
        "mechanism" => fuzz_check::check_mechanism,
        "part" => fuzz_check::check_part,
        other => return Err(format!("unknown target {other}")),
    };
    let (mut rejected, mut out, mut checked, mut energy, mut violations) = (0, 0, 0, 0, 0);
    let mut slowest = (0.0, String::new());
    let entries = std::fs::read_dir(dir).map_err(|e| format!("{dir}: {e}"))?;
    for entry in entries {
        let path = entry.map_err(|e| e.to_string())?.path();
        let bytes = std::fs::read(&path).map_err(|e| e.to_string())?;
        let start = Instant::now();
        match check(&bytes) {
            Ok(Outcome::Rejected(_)) => rejected += 1,
            Ok(Outcome::OutOfBounds(_)) => out += 1,
            Ok(Outcome::Checked { energy_checked }) => {
                checked += 1;
                energy += usize::from(energy_checked);
            }
            Err(v) => {
                violations += 1;
                println!("{}: {v}", path.display());
            }
        }
        let s = start.elapsed().as_secs_f64();
        if s > slowest.0 {
            slowest = (s, path.display().to_string());
        }
    }
    println!(
        "{target}: {rejected} rejected, {out} out of bounds, {checked} checked \
         ({energy} with energy), {violations} violations; slowest {:.3} s ({})",
        slowest.0, slowest.1
    );
    Ok(())
}
