//! `impulse run --joints FILE`: the multibodies' generalized coordinates at every frame
//! (thesis ch. 4–5), written as the run goes.
//!
//! One row per frame (CSV: `time` then one column per coordinate; JSON: `{"columns": [...],
//! "frames": [[time, ...], ...]}`), the columns named by [`impulse_sim::World::joint_columns`]:
//! for each multibody, its joints' angles or displacements `<multibody>/<joint>.q` (rad or m),
//! then their rates `<multibody>/<joint>.qd`; a floating base's position and quaternion lead
//! the `q` block and its twist (base coordinates) the rate block. The trajectory (`--out`)
//! keeps one row per body; the coordinates have their own file because their columns differ
//! from scene to scene.

use std::io::Write;
use std::path::Path;

use impulse_sim::{Frame, SimError, World};

use crate::partial::{PartialFile, is_json};

/// The option's name in messages.
const FLAG: &str = "--joints";

/// The `--joints` file being written.
pub struct JointSink {
    file: PartialFile,
    json: bool,
    frames: u64,
}

impl JointSink {
    /// Refuses a file name that ends in neither .csv nor .json, a directory that does not
    /// exist, or a scene without multibodies: checked before the run.
    pub fn check(out: &Path, world: &World) -> Result<(), String> {
        is_json(FLAG, out)?;
        crate::run::directory_exists(FLAG, out)?;
        if world.multibody_handles().is_empty() {
            return Err(format!(
                "{FLAG} {}: the scene has no multibodies, so no joints to write",
                out.display()
            ));
        }
        Ok(())
    }

    /// Opens `out`'s temporary file and writes the header for `world`'s multibodies.
    pub fn create(out: &Path, world: &World) -> Result<Self, String> {
        let json = is_json(FLAG, out)?;
        let columns = world.joint_columns();
        let head = if json {
            format!(
                "{{\"columns\": {},\n \"frames\": [",
                serde_json::to_string(&columns).map_err(|e| e.to_string())?
            )
        } else {
            let cells: Vec<String> = columns
                .iter()
                .map(|c| impulse_sim::record::csv_field(c))
                .collect();
            format!("time,{}\n", cells.join(","))
        };
        let file = PartialFile::create(FLAG, out, &head)?;
        Ok(Self {
            file,
            json,
            frames: 0,
        })
    }

    /// Writes one frame's coordinates.
    pub fn frame(&mut self, frame: &Frame) -> Result<(), SimError> {
        // `{:?}` of an f64 reads back to the same number.
        let cells: Vec<String> = std::iter::once(frame.time)
            .chain(frame.joints.iter().copied())
            .map(|x| format!("{x:?}"))
            .collect();
        let line = if self.json {
            let sep = if self.frames == 0 { "\n  " } else { ",\n  " };
            format!("{sep}[{}]", cells.join(", "))
        } else {
            format!("{}\n", cells.join(","))
        };
        self.frames += 1;
        self.file
            .writer()
            .write_all(line.as_bytes())
            .map_err(|e| SimError::Runtime {
                time: frame.time,
                message: format!("cannot write {}: {e}", self.file.partial().display()),
            })
    }

    /// Ends the file and gives it its name.
    pub fn finish(self) -> Result<(), String> {
        self.file.finish(if self.json { b"\n]}\n" } else { b"" })
    }

    /// Removes the temporary file of a run that failed.
    pub fn abandon(self) {
        self.file.abandon();
    }
}
