//! Articulated synthetic people: body shape, clothing, a pose library, joint perturbation
//! and smooth motion over the frames of a sequence.
//!
//! (Stub: filled in by the people work; the public API below is the contract.)

use crate::config::PeopleConfig;
use crate::geometry::Primitive;

/// A circle on the floor people must keep out of (table, robot pedestal): centre (x, y)
/// and radius, metres, world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FloorObstacle {
    /// Centre, world x y, metres.
    pub center_m: [f32; 2],
    /// Radius, metres.
    pub radius_m: f32,
}

/// One synthetic person for a whole sequence: shape, clothing and motion.
#[derive(Clone, Debug)]
pub struct Person {
    /// 1-based id (written in `depth_person` images).
    pub id: u8,
}

impl Person {
    /// The person's primitives at time `t_s` (seconds from the first frame), appended
    /// to `out`; every primitive has `Owner::Person { person: self.id, .. }`.
    pub fn primitives_at(&self, t_s: f64, out: &mut Vec<Primitive>) {
        let _ = (t_s, out);
    }

    /// The direction the person faces at `t_s` (yaw about z, radians; 0 = +x).
    pub fn yaw_rad_at(&self, t_s: f64) -> f32 {
        let _ = t_s;
        0.0
    }
}

/// The people of a sequence, drawn from `config` with `seed` (same seed, same people),
/// standing in the workspace around the world origin and outside `obstacles`.
pub fn make_people(config: &PeopleConfig, seed: u64, obstacles: &[FloorObstacle]) -> Vec<Person> {
    let _ = (config, seed, obstacles);
    Vec::new()
}

/// The object passed between the first two people in a hand-over at `t_s` (class
/// background: `Owner::Scene`), `None` when the sequence has no hand-over.
pub fn handover_object(people: &[Person], config: &PeopleConfig, t_s: f64) -> Option<Primitive> {
    let _ = (people, config, t_s);
    None
}
