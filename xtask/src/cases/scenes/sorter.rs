//! V21 part sorter (thesis §7.2; digest row V21): parts of three types slide down switchback
//! tracks past two spring-loaded trap doors, each a one-link multibody hinged to the fixed
//! track. Each type must end in its own bin; the doors must be closed whenever a part comes
//! to them and at the end; nothing interpenetrates (the same trajectory on 1 and 2 threads: `determinism-hybrid`).
//!
//! Everything geometric is read from `fixtures/scenes/part-sorter.ron`: the hinges and door
//! lengths from the multibodies, the bins from the fixed bodies named in [`ROUTES`], the
//! parts' sizes from their shapes. Why each type takes its route (the weight moment of a
//! part about a hinge against the door spring's preload) is argued with numbers in the scene
//! file's header.

use glam::{DQuat, DVec3};
use impulse_sim::Frame;
use impulse_sim::scene::{BodyDesc, MultibodyDesc, ShapeDesc};

use super::{Run, SceneCheck, no_penetration, rotation};
use crate::validate::case::{Check, Metric};

/// The expected route of each part type: the part's body name and the bin (a fixed body of
/// the scene, its floor) it must end in. The one place the routes are stated: type A glides
/// over door 1 into bin A; type B falls through door 1 onto the lower track and glides over
/// door 2 into bin B; type C falls through both doors into bin C.
const ROUTES: [(&str, &str); 3] = [
    ("part A", "bin A"),
    ("part B", "bin B"),
    ("part C", "bin C"),
];

/// The trap doors (multibodies of the scene), in the order a part meets them.
const DOORS: [&str; 2] = ["door 1", "door 2"];

/// A door counts as closed when its free edge is within this many ε_c of where the closed
/// stop holds it (the hinge angle within `DOOR_CLOSED_EDGE_OVER_EPS_C · ε_c / L`, L the door's
/// length): a closed door presents a step of less than the contact tolerance to a part.
const DOOR_CLOSED_EDGE_OVER_EPS_C: f64 = 1.0;

pub(super) fn checks() -> Vec<SceneCheck> {
    vec![SceneCheck {
        case: "V21-part-sorter",
        scene: "part-sorter",
        description: "three part types (one light, one medium, one heavy T section) slide down switchback tracks past two spring-loaded trap doors (one-link multibodies): each ends in its own bin, each door is closed whenever a part comes to it and at the end, no interpenetration",
        headline: "routes_taken",
        event_log: false,
        thesis: Some(("part sorter", 21.5)),
        metrics: v21_part_sorter,
    }]
}

/// A trap door as the scene places it: its hinge point, the world rotation of its joint
/// frame when closed (x along the door away from the hinge, z out of its top face), its
/// length and half width, and its flap's index in the recording.
struct Door {
    name: &'static str,
    hinge: DVec3,
    frame: DQuat,
    length: f64,
    half_width: f64,
    flap: usize,
}

impl Door {
    fn read(r: &Run<'_>, name: &'static str) -> Result<Self, String> {
        let desc: &MultibodyDesc = r
            .scene
            .desc
            .multibodies
            .iter()
            .find(|m| m.name == name)
            .ok_or_else(|| format!("no multibody \"{name}\" in the scene"))?;
        let [joint] = desc.joints.as_slice() else {
            return Err(format!("door \"{name}\" must have exactly one joint"));
        };
        let flap = desc
            .links
            .iter()
            .find(|l| l.name == joint.child)
            .ok_or_else(|| format!("door \"{name}\": no link \"{}\"", joint.child))?;
        let Some(ShapeDesc::Box { half_extents }) = flap.shape else {
            return Err(format!("door \"{name}\": the flap must be a box"));
        };
        let placement = rotation(&desc.rotation);
        Ok(Door {
            name,
            hinge: DVec3::from_array(desc.position) + placement * DVec3::from_array(joint.position),
            frame: placement * rotation(&joint.rotation),
            length: 2.0 * half_extents[0],
            half_width: half_extents[1],
            flap: r.index(&format!("{name}/{}", joint.child))?,
        })
    }

    /// The door's angle away from its closed pose (its pose in the first frame, where the
    /// scene starts it on its stop).
    fn angle(&self, r: &Run<'_>, f: &Frame) -> f64 {
        let q0 = r.rec.frames[0].bodies[self.flap].rotation;
        let q = f.bodies[self.flap].rotation;
        2.0 * q0.dot(q).abs().min(1.0).acos()
    }

    /// Whether a part whose centre of mass is at `p` (and whose circumscribed radius about it
    /// is `radius`) has come to the closed door: it may touch the door's face (its centre
    /// no farther upstream of the hinge than its radius, not past the free edge, across the
    /// door, above the door's plane by at most its radius). The frame before, no part of it
    /// can have been on the door.
    fn reached_by(&self, p: DVec3, radius: f64) -> bool {
        let l = self.frame.inverse() * (p - self.hinge);
        (-radius..=self.length).contains(&l.x)
            && l.y.abs() <= self.half_width
            && l.z > 0.0
            && l.z <= radius
    }
}

/// The radius about its body origin of a sphere holding every piece of a box or a compound
/// of boxes (the parts' shapes).
fn circumradius(b: &BodyDesc) -> Result<f64, String> {
    let piece = |s: &ShapeDesc, at: [f64; 3]| match s {
        ShapeDesc::Box { half_extents } => {
            Ok(DVec3::from_array(at).length() + DVec3::from_array(*half_extents).length())
        }
        _ => Err(format!("part \"{}\": only boxes are supported", b.name)),
    };
    match &b.shape {
        ShapeDesc::Compound { parts } => parts
            .iter()
            .map(|p| piece(&p.shape, p.position))
            .try_fold(0.0_f64, |m, x| x.map(|x| m.max(x))),
        s => piece(s, [0.0; 3]),
    }
}

/// Whether `p` lies in the bin whose floor is box body `bin`: over its footprint and no
/// higher above its top face than `radius` (a part resting on the floor, in any pose).
fn in_bin(bin: &BodyDesc, p: DVec3, radius: f64) -> Result<bool, String> {
    let h = super::half_extents(bin)?;
    let l = rotation(&bin.rotation).inverse() * (p - DVec3::from_array(bin.position));
    Ok(l.x.abs() <= h.x && l.y.abs() <= h.y && l.z > h.z && l.z <= h.z + radius)
}

/// V21. Per part: the bin it ends in (its index in [`ROUTES`], −1 for none) against its
/// route. Per door: how many parts came to it, and the largest hinge angle at the frame
/// before each part came to it (see [`Door::reached_by`]) and at the end, over the closed
/// tolerance. The monitor's penetration (determinism on 1 and
/// 2 threads: the case `determinism-hybrid`).
fn v21_part_sorter(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let last = r.last()?;
    let bins: Vec<&BodyDesc> = ROUTES
        .iter()
        .map(|(_, bin)| r.desc(bin))
        .collect::<Result<_, _>>()?;
    let doors: Vec<Door> = DOORS
        .iter()
        .map(|d| Door::read(r, d))
        .collect::<Result<_, _>>()?;
    let eps = r.world.collision_epsilon();
    let mut metrics = Vec::new();
    let mut taken = 0;
    // Per door: the worst angle at an arrival or at the end, and the number of arrivals.
    let mut worst: Vec<f64> = doors.iter().map(|d| d.angle(r, last)).collect();
    let mut arrivals = vec![0_u32; doors.len()];
    for (k, (part, _)) in ROUTES.iter().enumerate() {
        let i = r.index(part)?;
        let radius = circumradius(r.desc(part)?)?;
        let end = last.bodies[i].com;
        let mut bin = -1.0;
        for (b, desc) in bins.iter().enumerate() {
            if in_bin(desc, end, radius)? {
                bin = b as f64;
            }
        }
        if bin == k as f64 {
            taken += 1;
        }
        let letter = part.trim_start_matches("part ");
        metrics.push(Metric::new(
            format!("part_{letter}_bin"),
            bin,
            k as f64,
            Check::Exact,
        ));
        for (d, door) in doors.iter().enumerate() {
            let first = r
                .rec
                .frames
                .iter()
                .position(|f| door.reached_by(f.bodies[i].com, radius));
            if let Some(n) = first {
                arrivals[d] += 1;
                let before = &r.rec.frames[n.saturating_sub(1)];
                worst[d] = worst[d].max(door.angle(r, before));
            }
        }
    }
    metrics.push(Metric::new(
        "routes_taken",
        f64::from(taken),
        ROUTES.len() as f64,
        Check::Exact,
    ));
    for (d, door) in doors.iter().enumerate() {
        let tag = door.name.replace(' ', "_");
        let tolerance = DOOR_CLOSED_EDGE_OVER_EPS_C * eps / door.length;
        metrics.push(Metric::new(
            format!("{tag}_arrivals"),
            f64::from(arrivals[d]),
            // Every part meets door 1; door 2 is met by the parts that fell through door 1.
            ROUTES.len().saturating_sub(d) as f64,
            Check::Exact,
        ));
        metrics.push(Metric::new(
            format!("{tag}_angle_when_met_over_tol"),
            worst[d] / tolerance,
            0.0,
            Check::Between(0.0, 1.0),
        ));
    }
    metrics.push(no_penetration(r));
    Ok(metrics)
}
