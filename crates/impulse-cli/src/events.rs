//! `impulse run --events FILE`: every impact of the run (collisions and microcollisions,
//! thesis chapter 3; §3.5's microcollisions included), written as the run goes.
//!
//! One row (CSV) or object (JSON) per resolved contact, in the order resolved: its time, the
//! two bodies or links by name, its kind, the impulse on the first (world, N·s), the contact
//! point and normal (world, from the second body toward the first), the normal relative
//! velocity at the point before and after the impulse (m/s, negative approaching: eq. 3.3),
//! and the two sides' kinetic energy before and after (J; a link's side is its whole
//! multibody). Impulses of held contact (sustained contact as constraints, §8.1) are not
//! impacts and are not listed. Like `--out`, the file is written into FILE.partial and takes
//! its name when the run ends; an interrupted run's file holds the events up to its last
//! frame.

use std::io::Write;
use std::path::Path;

use crate::partial::{PartialFile, is_json};

/// The option's name in messages.
const FLAG: &str = "--events";

use impulse_sim::contact::ContactKind;
use impulse_sim::{ContactEvent, Frame, SimError, World};

/// The CSV header (one line; the JSON objects use the same names).
pub const CSV_HEADER: &str = "time,kind,body_a,body_b,impulse_x,impulse_y,impulse_z,\
point_x,point_y,point_z,normal_x,normal_y,normal_z,normal_speed_before,normal_speed_after,\
energy_before,energy_after";

/// The `--events` file being written.
pub struct EventSink {
    file: PartialFile,
    json: bool,
    /// Events written so far (a JSON object after the first is preceded by a comma).
    written: u64,
    /// Body names by slot index ([`impulse_sim::BodyHandle::index`]).
    names: Vec<String>,
}

/// The name `--events` uses for a contact kind.
fn kind_name(kind: ContactKind) -> &'static str {
    match kind {
        ContactKind::Collision => "collision",
        ContactKind::Microcollision => "microcollision",
        ContactKind::Reversing => "microcollision (reversing)",
        ContactKind::Fallback => "fallback",
    }
}

impl EventSink {
    /// Refuses a file name that ends in neither .csv nor .json, or whose directory does not
    /// exist: checked before the run.
    pub fn check(out: &Path) -> Result<(), String> {
        is_json(FLAG, out)?;
        crate::run::directory_exists(FLAG, out)
    }

    /// Opens `out`'s temporary file for the bodies of `world`.
    pub fn create(out: &Path, world: &World) -> Result<Self, String> {
        let json = is_json(FLAG, out)?;
        let mut names = Vec::new();
        for (h, b) in world.bodies() {
            let i = h.index() as usize;
            if names.len() <= i {
                names.resize(i + 1, String::new());
            }
            names[i] = b.name.clone();
        }
        let head = if json {
            "[".to_owned()
        } else {
            format!("{CSV_HEADER}\n")
        };
        let file = PartialFile::create(FLAG, out, &head)?;
        Ok(Self {
            file,
            json,
            written: 0,
            names,
        })
    }

    /// Writes the contacts of `frame` (those resolved since the frame before).
    pub fn frame(&mut self, frame: &Frame) -> Result<(), SimError> {
        for e in &frame.contacts {
            self.event(e).map_err(|err| SimError::Runtime {
                time: frame.time,
                message: format!("cannot write {}: {err}", self.file.partial().display()),
            })?;
        }
        Ok(())
    }

    fn name(&self, h: impulse_sim::BodyHandle) -> &str {
        self.names
            .get(h.index() as usize)
            .map_or("?", String::as_str)
    }

    fn event(&mut self, e: &ContactEvent) -> std::io::Result<()> {
        let (a, b) = (self.name(e.a).to_owned(), self.name(e.b).to_owned());
        let numbers = [
            e.impulse.x,
            e.impulse.y,
            e.impulse.z,
            e.point.x,
            e.point.y,
            e.point.z,
            e.normal.x,
            e.normal.y,
            e.normal.z,
            e.normal_speed_before,
            e.normal_speed_after,
            e.energy_before,
            e.energy_after,
        ];
        // `{:?}` of an f64 reads back to the same number.
        if self.json {
            let fields = [
                "impulse",
                "point",
                "normal",
                "normal_speed_before",
                "normal_speed_after",
                "energy_before",
                "energy_after",
            ];
            let vec3 = |k: usize| {
                format!(
                    "[{:?}, {:?}, {:?}]",
                    numbers[k],
                    numbers[k + 1],
                    numbers[k + 2]
                )
            };
            let values = [
                vec3(0),
                vec3(3),
                vec3(6),
                format!("{:?}", numbers[9]),
                format!("{:?}", numbers[10]),
                format!("{:?}", numbers[11]),
                format!("{:?}", numbers[12]),
            ];
            let rest: Vec<String> = fields
                .iter()
                .zip(&values)
                .map(|(f, v)| format!("\"{f}\": {v}"))
                .collect();
            let sep = if self.written == 0 { "\n" } else { ",\n" };
            write!(
                self.file.writer(),
                "{sep}  {{\"time\": {:?}, \"kind\": \"{}\", \"body_a\": {}, \"body_b\": {}, {}}}",
                e.time,
                kind_name(e.kind),
                serde_json::to_string(&a).map_err(std::io::Error::other)?,
                serde_json::to_string(&b).map_err(std::io::Error::other)?,
                rest.join(", ")
            )?;
        } else {
            let cells: Vec<String> = numbers.iter().map(|x| format!("{x:?}")).collect();
            writeln!(
                self.file.writer(),
                "{:?},{},{},{},{}",
                e.time,
                impulse_sim::record::csv_field(kind_name(e.kind)),
                impulse_sim::record::csv_field(&a),
                impulse_sim::record::csv_field(&b),
                cells.join(",")
            )?;
        }
        self.written += 1;
        Ok(())
    }

    /// Ends the file and gives it its name.
    pub fn finish(self) -> Result<(), String> {
        self.file.finish(if self.json { b"\n]\n" } else { b"" })
    }

    /// Removes the temporary file of a run that failed.
    pub fn abandon(self) {
        self.file.abandon();
    }
}
