//! Recording a run: frames at a fixed rate, the penetration monitor's findings, a trajectory
//! hash, CSV and JSON output.

use serde::Serialize;

use crate::monitor::{PenetrationMonitor, PenetrationReport};
use crate::world::{BodyHandle, BodyState, ContactEvent, Counters, World};

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
    /// The contacts resolved since the frame before ([`World::contacts`]: collisions and
    /// microcollisions, each with its impulse and normal speeds), in the order resolved.
    pub contacts: Vec<ContactEvent>,
    /// The multibodies' generalized coordinates ([`World::joint_values`], named by
    /// [`World::joint_columns`]).
    pub joints: Vec<f64>,
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
            contacts: world.contacts().to_vec(),
            joints: world.joint_values(),
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
/// every frame with the current simulated time. Every frame is kept: see [`run_streaming`]
/// for a run whose memory must not grow with its length.
///
/// # Errors
/// [`crate::SimError::Invalid`] for an `until` that is not a finite time after now, a rate
/// that is not positive, or more than [`crate::scene::MAX_FRAMES`] frames; otherwise as
/// [`World::step_until`].
pub fn run(
    world: &mut World,
    until: f64,
    rate: f64,
    progress: impl FnMut(f64),
) -> Result<Recording, crate::SimError> {
    check_run(world, until, rate)?;
    crate::scene::check_frames(until - world.time(), rate).map_err(|p| invalid("rate", p))?;
    run_streaming(world, until, rate, usize::MAX, |_| Ok(true), progress)
}

/// [`run`] in memory that does not grow with the run's length: every frame is handed to
/// `on_frame` as it is made (to be written out; it answers whether to go on: `false` ends the
/// run at that frame, its last, as a time limit does), and the [`Recording`] keeps at most `kept`
/// frames (at least 2): every frame while they fit, then every second, fourth, … (the stride
/// doubles each time they fill), always the first and the last. Its counters, penetration
/// reports and wall time cover the whole run.
///
/// The run stops at its first error, so its steps keep no copy of the world to restore
/// ([`World::set_rollback`] is off for its duration): after an error the world is where the
/// failure was found, and the frames handed out so far are the run's.
///
/// # Errors
/// As [`run`], without the frame-count limit (no frame is kept beyond `kept`); the first
/// error `on_frame` returns, which ends the run.
pub fn run_streaming(
    world: &mut World,
    until: f64,
    rate: f64,
    kept: usize,
    on_frame: impl FnMut(&Frame) -> Result<bool, crate::SimError>,
    progress: impl FnMut(f64),
) -> Result<Recording, crate::SimError> {
    let rollback = world.rollback();
    world.set_rollback(false);
    let result = stream(world, until, rate, kept, on_frame, progress);
    world.set_rollback(rollback);
    result
}

/// [`run_streaming`] with the world's rollback off.
fn stream(
    world: &mut World,
    until: f64,
    rate: f64,
    kept: usize,
    mut on_frame: impl FnMut(&Frame) -> Result<bool, crate::SimError>,
    mut progress: impl FnMut(f64),
) -> Result<Recording, crate::SimError> {
    check_run(world, until, rate)?;
    let kept = kept.max(2);
    let t0 = world.time();
    let start = std::time::Instant::now();
    let (handles, names): (Vec<_>, Vec<_>) =
        world.bodies().map(|(h, b)| (h, b.name.clone())).unzip();
    let mut monitor = PenetrationMonitor::new();
    monitor.sample(world);
    let first = Frame::of(world);
    let mut go_on = on_frame(&first)?;
    let mut frames = Kept::new(kept, first);
    let mut k = 1u64;
    while go_on {
        let t = (t0 + k as f64 / rate).min(until);
        world.step_until(t)?;
        monitor.sample(world);
        let frame = Frame::of(world);
        go_on = on_frame(&frame)?;
        progress(t);
        if t >= until || !go_on {
            frames.finish(k, frame);
            break;
        }
        frames.offer(k, frame);
        k += 1;
    }
    Ok(Recording {
        names,
        handles,
        frames: frames.frames,
        counters: world.counters(),
        wall_time: start.elapsed().as_secs_f64(),
        penetration: monitor.report().clone(),
        checked: world.checked_penetration().cloned(),
    })
}

/// Checks a run's end time and rate.
fn check_run(world: &World, until: f64, rate: f64) -> Result<(), crate::SimError> {
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
    Ok(())
}

/// The frames a streamed run keeps: those whose index is a multiple of `stride`, the stride
/// doubled whenever they would exceed `cap`, and the last.
struct Kept {
    cap: usize,
    stride: u64,
    frames: Vec<Frame>,
    /// The index of each kept frame.
    index: Vec<u64>,
}

impl Kept {
    fn new(cap: usize, first: Frame) -> Self {
        Self {
            cap,
            stride: 1,
            frames: vec![first],
            index: vec![0],
        }
    }

    /// Frame `k` (not the last).
    fn offer(&mut self, k: u64, frame: Frame) {
        // Room for the first and the last only.
        if self.cap <= 2 || k % self.stride != 0 {
            return;
        }
        // One place is kept free for the last frame.
        if self.frames.len() + 1 >= self.cap {
            self.stride *= 2;
            let stride = self.stride;
            let mut i = 0;
            self.frames.retain(|_| {
                let keep = self.index[i] % stride == 0;
                i += 1;
                keep
            });
            self.index.retain(|&j| j % stride == 0);
            if k % self.stride != 0 {
                return;
            }
        }
        self.frames.push(frame);
        self.index.push(k);
    }

    /// The last frame, `k`: always kept.
    fn finish(&mut self, k: u64, frame: Frame) {
        self.frames.push(frame);
        self.index.push(k);
    }
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
        self.written(TrajectoryFormat::Csv)
    }

    /// The trajectory as JSON: `{"bodies": [names], "columns": [the state columns of
    /// [`Recording::to_csv`]], "frames": [{"t", "kinetic_energy", "potential_energy",
    /// "states": [[16 numbers per body], …]}, …], "max_penetration": …}`. Written by
    /// `serde_json`: any name is valid JSON; a non-finite number is `null`.
    #[must_use]
    pub fn to_json(&self) -> String {
        self.written(TrajectoryFormat::Json)
    }

    /// The frames through a [`TrajectoryWriter`] into a string.
    fn written(&self, format: TrajectoryFormat) -> String {
        let mut out = Vec::new();
        let mut w = TrajectoryWriter::new(&mut out, format, &self.names)
            .expect("writing to memory does not fail");
        for f in &self.frames {
            w.frame(f).expect("writing to memory does not fail");
        }
        w.finish(self.max_penetration())
            .expect("writing to memory does not fail");
        String::from_utf8(out).expect("the writer writes UTF-8")
    }
}

/// The file formats of a trajectory ([`Recording::to_csv`], [`Recording::to_json`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TrajectoryFormat {
    /// One row per frame and body.
    Csv,
    /// One object, its frames an array.
    Json,
}

/// Writes a trajectory frame by frame as it is made, in the layout of [`Recording::to_csv`]
/// or [`Recording::to_json`] (byte for byte: those are written by it), so that a long run's
/// output needs no memory that grows with it ([`run_streaming`]).
pub struct TrajectoryWriter<W: std::io::Write> {
    out: W,
    format: TrajectoryFormat,
    /// CSV: the names as fields; JSON: unused.
    names: Vec<String>,
    frames: u64,
}

impl<W: std::io::Write> TrajectoryWriter<W> {
    /// Starts a trajectory of bodies `names` (the order of every frame's states): writes the
    /// header.
    ///
    /// # Errors
    /// The writer's error.
    pub fn new(mut out: W, format: TrajectoryFormat, names: &[String]) -> std::io::Result<Self> {
        match format {
            TrajectoryFormat::Csv => writeln!(out, "time,body,{}", STATE_COLUMNS.join(","))?,
            TrajectoryFormat::Json => write!(
                out,
                "{{\"bodies\":{},\"columns\":{},\"frames\":[",
                serde_json::to_string(names).map_err(std::io::Error::other)?,
                serde_json::to_string(&STATE_COLUMNS).map_err(std::io::Error::other)?
            )?,
        }
        Ok(Self {
            out,
            format,
            names: match format {
                TrajectoryFormat::Csv => names.iter().map(|n| csv_field(n)).collect(),
                TrajectoryFormat::Json => Vec::new(),
            },
            frames: 0,
        })
    }

    /// Writes one frame.
    ///
    /// # Errors
    /// The writer's error.
    pub fn frame(&mut self, f: &Frame) -> std::io::Result<()> {
        match self.format {
            TrajectoryFormat::Csv => {
                for (name, b) in self.names.iter().zip(&f.bodies) {
                    write!(self.out, "{},{}", f.time, name)?;
                    for x in state_numbers(b) {
                        write!(self.out, ",{x}")?;
                    }
                    writeln!(self.out)?;
                }
            }
            TrajectoryFormat::Json => {
                #[derive(Serialize)]
                struct JsonFrame {
                    t: f64,
                    kinetic_energy: f64,
                    potential_energy: f64,
                    states: Vec<[f64; 16]>,
                }
                if self.frames > 0 {
                    write!(self.out, ",")?;
                }
                let frame = JsonFrame {
                    t: f.time,
                    kinetic_energy: f.kinetic_energy,
                    potential_energy: f.potential_energy,
                    states: f.bodies.iter().map(state_numbers).collect(),
                };
                serde_json::to_writer(&mut self.out, &frame).map_err(std::io::Error::other)?;
            }
        }
        self.frames += 1;
        Ok(())
    }

    /// Ends the trajectory (JSON: with the run's largest penetration) and flushes.
    ///
    /// # Errors
    /// The writer's error.
    pub fn finish(mut self, max_penetration: f64) -> std::io::Result<W> {
        if self.format == TrajectoryFormat::Json {
            writeln!(
                self.out,
                "],\"max_penetration\":{}}}",
                serde_json::to_string(&max_penetration).map_err(std::io::Error::other)?
            )?;
        }
        self.out.flush()?;
        Ok(self.out)
    }
}

/// A body state as its 16 numbers, in the order of [`STATE_COLUMNS`].
fn state_numbers(b: &BodyState) -> [f64; 16] {
    let (p, q, v, w, c) = (b.position, b.rotation, b.velocity, b.omega, b.com);
    [
        p.x, p.y, p.z, q.x, q.y, q.z, q.w, v.x, v.y, v.z, w.x, w.y, w.z, c.x, c.y, c.z,
    ]
}

/// A CSV field: quoted (quotes doubled) when it holds a comma, quote or line break (RFC 4180),
/// as the trajectory CSV writes body names.
#[must_use]
pub fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ball dropped onto a floor: bounces, then rests.
    fn world() -> World {
        let desc = crate::SceneDesc::from_ron(
            "Scene(gravity: (0, 0, -9.81), collision_epsilon: 1e-4,
              bodies: [
                Body(name: \"floor\", shape: Box(half_extents: (1, 1, 0.1)), position: (0, 0, -0.1), motion: Fixed),
                Body(name: \"ball\", shape: Sphere(radius: 0.05), position: (0, 0, 0.3)),
              ])",
            "test",
        )
        .unwrap();
        World::from_scene(&crate::Scene::new(desc, ".")).unwrap()
    }

    /// A streamed run hands over every frame the unbounded run records, bit for bit (the
    /// reference: [`run`] on an identical world), and keeps at most its cap: the first, the
    /// last, and frames at one stride, a power of two, in between.
    #[test]
    fn a_streamed_run_hands_over_every_frame_and_keeps_a_bounded_evenly_strided_copy() {
        let full = run(&mut world(), 1.0, 100.0, |_| {}).unwrap();
        assert_eq!(full.frames.len(), 101);
        for cap in [2usize, 3, 10, 64, 1000] {
            let mut seen = Vec::new();
            let kept = run_streaming(
                &mut world(),
                1.0,
                100.0,
                cap,
                |f| {
                    seen.push(f.clone());
                    Ok(true)
                },
                |_| {},
            )
            .unwrap();
            assert_eq!(seen, full.frames, "cap {cap}");
            let frames = &kept.frames;
            assert!(frames.len() <= cap.max(2), "cap {cap}: {}", frames.len());
            assert_eq!(frames.first(), full.frames.first());
            assert_eq!(frames.last(), full.frames.last());
            // Interior frames sit at one stride, a power of two, with none skipped.
            let at: Vec<usize> = frames[..frames.len() - 1]
                .iter()
                .map(|f| full.frames.iter().position(|g| g == f).unwrap())
                .collect();
            if at.len() > 1 {
                let stride = at[1];
                assert!(stride.is_power_of_two(), "cap {cap}: {at:?}");
                assert!(
                    at.iter().enumerate().all(|(i, &k)| k == i * stride),
                    "cap {cap}: {at:?}"
                );
                // The next frame at that stride would not have fitted.
                assert!(
                    at.len() + 2 > cap || (at.len()) * stride > 99,
                    "cap {cap}: {at:?}"
                );
            }
            assert_eq!(kept.counters, full.counters);
        }
        // Everything kept when it fits.
        let all = run_streaming(&mut world(), 1.0, 100.0, 1000, |_| Ok(true), |_| {}).unwrap();
        assert_eq!(all.frames, full.frames);
        // Stopped by its handler at frame 30: that frame is the last, the run ends there.
        let mut n = 0;
        let stopped = run_streaming(
            &mut world(),
            1.0,
            100.0,
            1000,
            |_| {
                n += 1;
                Ok(n <= 30)
            },
            |_| {},
        )
        .unwrap();
        assert_eq!(stopped.frames, full.frames[..31]);
    }

    /// An error from the frame handler ends the run with it.
    #[test]
    fn a_failing_frame_handler_ends_the_run() {
        let mut n = 0;
        let err = run_streaming(
            &mut world(),
            1.0,
            100.0,
            10,
            |_| {
                n += 1;
                if n == 5 {
                    Err(invalid("out", "disk full".into()))
                } else {
                    Ok(true)
                }
            },
            |_| {},
        )
        .unwrap_err();
        assert!(err.to_string().contains("disk full"), "{err}");
        assert_eq!(n, 5);
    }
}
