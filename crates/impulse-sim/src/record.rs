//! Recording a run: frames at a fixed rate, a summary, a trajectory hash, CSV and JSON output.

use std::fmt::Write as _;

use crate::world::{BodyState, Counters, World};

/// The state of the world at one instant.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Simulated time.
    pub time: f64,
    /// Every body's state, in scene order.
    pub bodies: Vec<BodyState>,
    /// Total kinetic energy.
    pub kinetic_energy: f64,
    /// Total potential energy (zero at the world origin).
    pub potential_energy: f64,
    /// Event counters so far.
    pub counters: Counters,
}

impl Frame {
    /// The world's current state.
    #[must_use]
    pub fn of(world: &World) -> Self {
        Self {
            time: world.time(),
            bodies: world.states(),
            kinetic_energy: world.kinetic_energy(),
            potential_energy: world.potential_energy(),
            counters: world.counters(),
        }
    }
}

/// A recorded run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Recording {
    /// Body names, in scene order.
    pub names: Vec<String>,
    /// Frames, in time order (the first at the start time).
    pub frames: Vec<Frame>,
    /// Counters at the end.
    pub counters: Counters,
    /// Wall-clock time of the run (s).
    pub wall_time: f64,
}

/// Runs `world` to `until`, recording a frame every `1/rate` of simulated time (and at the
/// end). `progress` is called after every frame with the current simulated time.
///
/// # Errors
/// As [`World::step_until`].
pub fn run(
    world: &mut World,
    until: f64,
    rate: f64,
    mut progress: impl FnMut(f64),
) -> Result<Recording, crate::SimError> {
    let start = std::time::Instant::now();
    let names = world.bodies().iter().map(|b| b.name.clone()).collect();
    let mut frames = vec![Frame::of(world)];
    let t0 = world.time();
    let mut k = 1u64;
    loop {
        let t = (t0 + k as f64 / rate).min(until);
        world.step_until(t)?;
        frames.push(Frame::of(world));
        progress(t);
        if t >= until {
            break;
        }
        k += 1;
    }
    Ok(Recording {
        names,
        frames,
        counters: world.counters(),
        wall_time: start.elapsed().as_secs_f64(),
    })
}

impl Recording {
    /// FNV-1a hash of every recorded number's bits: equal hashes mean bit-identical
    /// trajectories (the determinism check).
    #[must_use]
    pub fn hash(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |x: f64| {
            for byte in x.to_bits().to_le_bytes() {
                h ^= u64::from(byte);
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        for f in &self.frames {
            eat(f.time);
            for b in &f.bodies {
                state_numbers(b).for_each(&mut eat);
            }
        }
        h
    }

    /// The trajectory as CSV: one row per frame and body: `time, body, x, y, z, qx, qy, qz,
    /// qw, vx, vy, vz, wx, wy, wz` (centre of mass, orientation, velocity, angular velocity).
    #[must_use]
    pub fn to_csv(&self) -> String {
        let mut s = String::from("time,body,x,y,z,qx,qy,qz,qw,vx,vy,vz,wx,wy,wz\n");
        for f in &self.frames {
            for (name, b) in self.names.iter().zip(&f.bodies) {
                let _ = write!(s, "{},{}", f.time, name);
                for x in state_numbers(b) {
                    let _ = write!(s, ",{x}");
                }
                s.push('\n');
            }
        }
        s
    }

    /// The trajectory as JSON: `{"bodies": [names], "frames": [{"t", "kinetic_energy",
    /// "potential_energy", "states": [[x, y, z, qx, qy, qz, qw, vx, vy, vz, wx, wy, wz], …]}]}`.
    #[must_use]
    pub fn to_json(&self) -> String {
        let mut s = String::from("{\"bodies\": [");
        for (k, n) in self.names.iter().enumerate() {
            if k > 0 {
                s.push_str(", ");
            }
            let _ = write!(s, "{n:?}");
        }
        s.push_str("],\n\"frames\": [\n");
        for (k, f) in self.frames.iter().enumerate() {
            if k > 0 {
                s.push_str(",\n");
            }
            let _ = write!(
                s,
                "{{\"t\": {}, \"kinetic_energy\": {}, \"potential_energy\": {}, \"states\": [",
                json_num(f.time),
                json_num(f.kinetic_energy),
                json_num(f.potential_energy)
            );
            for (j, b) in f.bodies.iter().enumerate() {
                if j > 0 {
                    s.push_str(", ");
                }
                s.push('[');
                let nums: Vec<String> = state_numbers(b).map(json_num).collect();
                s.push_str(&nums.join(", "));
                s.push(']');
            }
            s.push_str("]}");
        }
        s.push_str("\n]}\n");
        s
    }
}

/// A body state as its 13 numbers, in the order of the CSV and JSON columns: position,
/// quaternion (x, y, z, w), velocity, angular velocity.
fn state_numbers(b: &BodyState) -> impl Iterator<Item = f64> {
    b.position
        .to_array()
        .into_iter()
        .chain(b.rotation.to_array())
        .chain(b.velocity.to_array())
        .chain(b.omega.to_array())
}

/// A JSON number (JSON has no NaN or infinity: those become `null`).
fn json_num(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        "null".into()
    }
}
