//! Articulated synthetic people: body shape, clothing, a pose library, joint perturbation
//! and smooth motion over the frames of a sequence.
//!
//! # Conventions
//! - World frame: metres, z up, floor at z = 0. A person's body frame has x forward, y to
//!   the person's left, z up; its yaw is the angle of x about world z (0 = +x).
//! - The skeleton is a pelvis root (midpoint of the hip joints) with position and yaw, a
//!   spine of lumbar and thoracic joints, neck and head, shoulders, elbows and wrists, hips,
//!   knees and ankles. Trunk and arms use forward kinematics on joint angles (radians
//!   inside); legs are solved with two-bone inverse kinematics from planted feet, so feet
//!   stay on the floor and knees always bend forward. In a hand-over the handing arms are
//!   solved the same way towards a shared meeting point, so the hands stay together.
//! - Segment lengths follow Drillis & Contini's anthropometric ratios of body height
//!   (Winter, *Biomechanics and Motor Control of Human Movement*, fig. 4.1).
//! - Everything is drawn from `rand_chacha::ChaCha8Rng` streams of the sequence seed: person
//!   `i` uses stream `i + 1`, placement its own stream, so the same seed gives the same
//!   people and poses.

mod body;
mod clothes;
mod draw;
mod math;
mod motion;
mod person;
mod placement;
mod pose;

pub use person::Person;
pub use placement::{handover_object, make_people};
pub use pose::{BodyPose, FloorObstacle, HANDOVER_OBJECT_SIZE_M, PERSON_RADIUS_M};

#[cfg(test)]
mod tests;
