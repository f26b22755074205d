//! Recording a run: frames at a fixed rate, the penetration monitor's findings, a trajectory
//! hash, CSV and JSON output.

use std::fmt::Write as _;

use serde::Serialize;

use crate::monitor::{PenetrationMonitor, PenetrationReport};
use crate::world::{BodyHandle, BodyState, Counters, World};

/// The state of the world at one instant.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Simulated time.
    pub time: f64,
    /// Every body's state, in the order of [`Recording::names`].
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
    /// Body names, in the order of every frame's states.
    pub names: Vec<String>,
    /// Body handles, in the same order.
    pub handles: Vec<BodyHandle>,
    /// Frames, in time order (the first at the start time).
    pub frames: Vec<Frame>,
    /// Counters at the end.
    pub counters: Counters,
    /// Wall-clock time of the run (s).
    pub wall_time: f64,
    /// The independent penetration monitor, sampled at every frame.
    pub penetration: PenetrationReport,
    /// The world's checking mode (every loop step), when it was on.
    pub checked: Option<PenetrationReport>,
}

/// Column names of a body state in CSV and JSON, after `time` and `body`.
pub const STATE_COLUMNS: [&str; 16] = [
    "x", "y", "z", "qx", "qy", "qz", "qw", "vx", "vy", "vz", "wx", "wy", "wz", "cx", "cy", "cz",
];

/// Why a run could not be recorded.
fn invalid(field: &str, problem: String) -> crate::SimError {
    crate::SimError::Invalid {
        what: "run".into(),
        field: field.into(),
        problem,
    }
}

/// Runs `world` to `until`, recording a frame every `1/rate` of simulated time (and at the
/// end) and sampling the [`PenetrationMonitor`] at every frame. `progress` is called after
/// every frame with the current simulated time.
///
/// # Errors
/// [`crate::SimError::Invalid`] for an `until` that is not a finite time after now, a rate
/// that is not positive, or more than [`crate::scene::MAX_FRAMES`] frames; otherwise as
/// [`World::step_until`].
pub fn run(
    world: &mut World,
    until: f64,
    rate: f64,
    mut progress: impl FnMut(f64),
) -> Result<Recording, crate::SimError> {
    let t0 = world.time();
    if !(until.is_finite() && until > t0) {
        return Err(invalid(
            "until",
            format!("{until} must be a finite time after the current time {t0}"),
        ));
    }
    if !(rate.is_finite() && rate > 0.0) {
        return Err(invalid("rate", format!("{rate} must be finite and > 0")));
    }
    crate::scene::check_frames(until - t0, rate).map_err(|p| invalid("rate", p))?;
    let start = std::time::Instant::now();
    let (handles, names): (Vec<_>, Vec<_>) =
        world.bodies().map(|(h, b)| (h, b.name.clone())).unzip();
    let mut monitor = PenetrationMonitor::new();
    monitor.sample(world);
    let mut frames = vec![Frame::of(world)];
    let mut k = 1u64;
    loop {
        let t = (t0 + k as f64 / rate).min(until);
        world.step_until(t)?;
        monitor.sample(world);
        frames.push(Frame::of(world));
        progress(t);
        if t >= until {
            break;
        }
        k += 1;
    }
    Ok(Recording {
        names,
        handles,
        frames,
        counters: world.counters(),
        wall_time: start.elapsed().as_secs_f64(),
        penetration: monitor.report().clone(),
        checked: world.checked_penetration().cloned(),
    })
}

impl Recording {
    /// The position of body `name` in every frame's states.
    #[must_use]
    pub fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// The largest penetration any monitor measured: at the frames, and at every loop step
    /// when the checking mode was on (length).
    #[must_use]
    pub fn max_penetration(&self) -> f64 {
        self.checked
            .as_ref()
            .map_or(0.0, |c| c.max_depth)
            .max(self.penetration.max_depth)
    }

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
                state_numbers(b).into_iter().for_each(&mut eat);
            }
        }
        h
    }

    /// The trajectory as CSV: a header, then one row per frame and body: `time, body`, the
    /// body's own frame (`x, y, z` its origin, `qx, qy, qz, qw` its orientation), the
    /// velocity of its centre of mass `vx, vy, vz`, its angular velocity `wx, wy, wz`, and its
    /// centre of mass `cx, cy, cz` (all world). Names are quoted when they need it.
    #[must_use]
    pub fn to_csv(&self) -> String {
        let mut s = format!("time,body,{}\n", STATE_COLUMNS.join(","));
        let names: Vec<String> = self.names.iter().map(|n| csv_field(n)).collect();
        for f in &self.frames {
            for (name, b) in names.iter().zip(&f.bodies) {
                let _ = write!(s, "{},{}", f.time, name);
                for x in state_numbers(b) {
                    let _ = write!(s, ",{x}");
                }
                s.push('\n');
            }
        }
        s
    }

    /// The trajectory as JSON: `{"bodies": [names], "columns": [the state columns of
    /// [`Recording::to_csv`]], "frames": [{"t", "kinetic_energy", "potential_energy",
    /// "states": [[16 numbers per body], …]}, …], "max_penetration": …}`. Written by
    /// `serde_json`: any name is valid JSON; a non-finite number is `null`.
    #[must_use]
    pub fn to_json(&self) -> String {
        #[derive(Serialize)]
        struct JsonFrame {
            t: f64,
            kinetic_energy: f64,
            potential_energy: f64,
            states: Vec<[f64; 16]>,
        }
        #[derive(Serialize)]
        struct Json<'a> {
            bodies: &'a [String],
            columns: [&'static str; 16],
            frames: Vec<JsonFrame>,
            max_penetration: f64,
        }
        let json = Json {
            bodies: &self.names,
            columns: STATE_COLUMNS,
            frames: self
                .frames
                .iter()
                .map(|f| JsonFrame {
                    t: f.time,
                    kinetic_energy: f.kinetic_energy,
                    potential_energy: f.potential_energy,
                    states: f.bodies.iter().map(state_numbers).collect(),
                })
                .collect(),
            max_penetration: self.max_penetration(),
        };
        serde_json::to_string(&json)
            .map_or_else(|e| format!("{{\"error\": \"{e}\"}}"), |s| s + "\n")
    }
}

/// A body state as its 16 numbers, in the order of [`STATE_COLUMNS`].
fn state_numbers(b: &BodyState) -> [f64; 16] {
    let (p, q, v, w, c) = (b.position, b.rotation, b.velocity, b.omega, b.com);
    [
        p.x, p.y, p.z, q.x, q.y, q.z, q.w, v.x, v.y, v.z, w.x, w.y, w.z, c.x, c.y, c.z,
    ]
}

/// A CSV field: quoted (quotes doubled) when it holds a comma, quote or line break.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}
