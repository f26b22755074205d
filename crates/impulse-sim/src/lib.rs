//! # impulse-sim — layer 4 of the `impulse` workspace
//!
//! **Owns** the impulse-based simulator of thesis §1.2 and chapter 7 (Mirtich 1996):
//! - [`World`]: fixed, dynamic (ballistic between collisions) and scripted bodies; the event
//!   loop that takes the critical pair from the collision heap, advances every body to its
//!   time (in parallel, deterministically), checks the pair and resolves a collision or
//!   microcollision ([`world`]);
//! - bodies and their torque-free motion ([`body`]), contact resolution through
//!   `impulse-response` ([`contact`]);
//! - scene files in RON with validation that names the body and field ([`scene`]);
//! - recording at a fixed frame rate, trajectory hashes, CSV and JSON ([`record`]).
//!
//! **Must not know** command lines, terminals or plotting: those belong to `impulse-cli`.
#![forbid(unsafe_code)]

pub mod body;
mod build;
pub mod contact;
mod error;
pub mod record;
pub mod scene;
pub mod world;

pub use error::SimError;
pub use record::{Frame, Recording, run};
pub use scene::{Scene, SceneDesc};
pub use world::{BodyState, ContactEvent, Counters, World};

#[cfg(test)]
mod hostile;
#[cfg(test)]
mod tests;
