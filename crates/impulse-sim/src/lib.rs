//! # impulse-sim — layer 4 of the `impulse` workspace
//!
//! A world of rigid bodies that collide by impulses (Mirtich 1996, chapters 1–3 and 7): built
//! in code or from a scene file, stepped to any time, read between steps.
//!
//! ```
//! use glam::DVec3;
//! use impulse_sim::scene::{BodyDesc, ShapeDesc};
//! use impulse_sim::{World, WorldSettings};
//!
//! // A 10 cm box resting exactly on a floor whose top is z = 0, ε_c = 0.1 mm.
//! let mut world = World::new(WorldSettings::new(1e-4))?;
//! world.add_body(&BodyDesc::fixed("floor", ShapeDesc::cuboid([1.0, 1.0, 0.1])).at([0.0, 0.0, -0.1]))?;
//! let cube = world.add_body(
//!     &BodyDesc::new("box", ShapeDesc::cuboid([0.05, 0.05, 0.05]))
//!         .at([0.0, 0.0, 0.05])
//!         .with_density(700.0),
//! )?;
//! // A ball dropped beside it.
//! let ball = world.add_body(&BodyDesc::new("ball", ShapeDesc::sphere(0.02)).at([0.3, 0.0, 0.2]))?;
//! let report = world.step_until(1.0)?;
//! let resting = world.state(cube)?;
//! assert!((resting.position - DVec3::new(0.0, 0.0, 0.05)).length() < 1e-3);
//! assert!(world.state(ball)?.position.z < 0.03); // it fell and bounced down to the floor
//! assert!(report.counters.collisions > 0);
//! # Ok::<(), impulse_sim::SimError>(())
//! ```
//!
//! **Owns**
//! - [`World`]: fixed, dynamic (ballistic between collisions) and scripted bodies named by
//!   [`BodyHandle`]s; adding, removing, moving and pushing them (impulses, constant loads, load
//!   functions); the event loop that takes the critical pair from the collision heap,
//!   advances every body to its time (in parallel, deterministically), checks the pair and
//!   resolves a collision or microcollision ([`world`]); contacts of the last step and a
//!   per-step report; a fallback for contacts the response cannot resolve;
//! - bodies and their motion under gravity, loads and torques ([`body`]), contact
//!   resolution through `impulse-response` ([`contact`]);
//! - scene descriptions in RON, with validation that names the body and field, and builders
//!   that make the same descriptions in code ([`scene`]);
//! - an independent penetration monitor ([`monitor`]);
//! - recording at a fixed frame rate, trajectory hashes, CSV and JSON ([`record`]);
//! - collisions of multibody links with rigid bodies, fixed bodies and other multibodies'
//!   links (thesis §5.3: K from the impulse-space articulated-body recursion, the impulse from
//!   `impulse-response`, propagation through the tree), and, as an option off by default,
//!   between non-adjacent links of one multibody ([`articulated`]); multibodies as
//!   members of a [`World`] (`World::add_multibody`, `multibodies` in scene files, inline or
//!   from URDF files: integrated to the heap's top with checked predictions, thesis §5.2);
//! - high-level controllers called at their own rate with the world to read and commands to
//!   give (`World::add_controller`, [`WorldController`]), and the built-in steering and
//!   launching of the furniture scene ([`controllers`]).
//!
//! **Must not know** command lines, terminals or plotting: those belong to `impulse-cli`.
#![forbid(unsafe_code)]

pub mod articulated;
pub mod batch;
pub mod body;
pub mod bowling;
mod build;
mod builder;
pub mod contact;
pub mod controllers;
mod error;
pub mod monitor;
pub mod poses;
pub mod record;
pub mod scene;
pub mod sustained;
pub mod threads;
pub mod world;

pub use error::SimError;
pub use monitor::{PenetrationMonitor, PenetrationReport};
pub use record::{Frame, Recording, TrajectoryFormat, TrajectoryWriter, run, run_streaming};
pub use scene::{Scene, SceneDesc};
pub use sustained::{ContactMode, SustainedSettings};
pub use world::{
    BodyHandle, BodyState, ContactEvent, ContactFailure, Control, ControllerHandle, Counters,
    HeldContact, LinkShape, Load, LoadFn, Material, MultibodyHandle, MultibodyOptions, Profile,
    StepReport, World, WorldController, WorldSettings,
};

#[cfg(test)]
mod hostile;
#[cfg(test)]
mod tests;
