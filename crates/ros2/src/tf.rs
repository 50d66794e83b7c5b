//! The transform tree of `/tf_static` and `/tf`: each child frame has one parent, and a
//! transform `parent_from_child` (a `geometry_msgs/TransformStamped` maps points of its
//! `child_frame_id` into its `header.frame_id`).
//!
//! A rig is static, so one transform per frame is kept: the first of `/tf_static`, else
//! the first of `/tf` (a moving camera is not a rig; the caller says which was used).

use crate::Ros2Error;
use crate::msg::TransformMsg;
use bodyseg_calib::Pose;
use std::collections::BTreeMap;

/// Where a transform came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TfSource {
    /// `/tf_static`.
    Static,
    /// `/tf` (the first message of the frame).
    Dynamic,
}

#[derive(Clone, Debug)]
struct Edge {
    parent: String,
    parent_from_child: Pose,
    source: TfSource,
}

/// The frames of a bag's tf messages and their parents.
#[derive(Clone, Debug, Default)]
pub struct TfTree {
    edges: BTreeMap<String, Edge>,
}

impl TfTree {
    /// Adds the transforms of one TFMessage (`topic` and `source` say where it came from).
    /// A frame keeps its first transform; one from `/tf_static` replaces one from `/tf`.
    ///
    /// # Errors
    /// A transform whose quaternion is not a unit quaternion or whose values are not
    /// finite, naming the topic, the stamp and the frames.
    pub fn add(
        &mut self,
        transforms: &[TransformMsg],
        topic: &str,
        source: TfSource,
    ) -> Result<(), Ros2Error> {
        for t in transforms {
            if let Some(e) = self.edges.get(&t.child_frame_id)
                && (e.source == TfSource::Static || source == TfSource::Dynamic)
            {
                continue;
            }
            let [x, y, z, w] = t.rotation_xyzw;
            let pose = Pose::from_quaternion_wxyz([w, x, y, z], t.translation_m).map_err(|e| {
                Ros2Error::Transform {
                    reason: format!(
                        "transform {} → {}: {e}",
                        t.header.frame_id, t.child_frame_id
                    ),
                }
                .at(topic, t.header.stamp)
            })?;
            self.edges.insert(
                t.child_frame_id.clone(),
                Edge {
                    parent: t.header.frame_id.clone(),
                    parent_from_child: pose,
                    source,
                },
            );
        }
        Ok(())
    }

    /// Whether no transform was read.
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }

    /// `root_from_frame` and the root of `frame`'s tree (the frame itself when it has no
    /// parent), and whether any transform on the way came from `/tf`.
    fn to_root(&self, frame: &str) -> (String, Pose, bool) {
        let mut pose = Pose::identity();
        let mut current = frame.to_string();
        let mut dynamic = false;
        // A cycle (malformed tf) stops after every frame was visited once.
        for _ in 0..=self.edges.len() {
            let Some(edge) = self.edges.get(&current) else {
                break;
            };
            pose = edge.parent_from_child.compose(&pose);
            dynamic |= edge.source == TfSource::Dynamic;
            current = edge.parent.clone();
        }
        (current, pose, dynamic)
    }

    /// The root of `frame`'s tree.
    pub fn root(&self, frame: &str) -> String {
        self.to_root(frame).0
    }

    /// `target_from_source`, when both frames are in one tree, and whether a transform of
    /// `/tf` was used.
    pub fn lookup(&self, target: &str, source: &str) -> Option<(Pose, bool)> {
        if target == source {
            return Some((Pose::identity(), false));
        }
        let (root_s, root_from_source, dyn_s) = self.to_root(source);
        let (root_t, root_from_target, dyn_t) = self.to_root(target);
        (root_s == root_t).then(|| {
            (
                root_from_target.inverse().compose(&root_from_source),
                dyn_s || dyn_t,
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msg::{Header, Stamp};

    fn tf(parent: &str, child: &str, t: [f64; 3], q_xyzw: [f64; 4]) -> TransformMsg {
        TransformMsg {
            header: Header {
                stamp: Stamp::default(),
                frame_id: parent.into(),
            },
            child_frame_id: child.into(),
            translation_m: t,
            rotation_xyzw: q_xyzw,
        }
    }

    #[test]
    fn lookups_compose_through_the_common_root() {
        let mut tree = TfTree::default();
        let half = std::f64::consts::FRAC_1_SQRT_2;
        // world → a: 1 m along x, turned 90° about z; a → b: 1 m along x of a.
        tree.add(
            &[
                tf("world", "a", [1.0, 0.0, 0.0], [0.0, 0.0, half, half]),
                tf("a", "b", [1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]),
                tf("world", "c", [0.0, 0.0, 2.0], [0.0, 0.0, 0.0, 1.0]),
            ],
            "/tf_static",
            TfSource::Static,
        )
        .expect("add");
        assert_eq!(tree.root("b"), "world");
        let (world_from_b, dynamic) = tree.lookup("world", "b").expect("path");
        assert!(!dynamic);
        let p = world_from_b.transform_point([0.0; 3]);
        // b's origin: a's x axis is world's y, so (1, 1, 0).
        for (got, want) in p.iter().zip([1.0, 1.0, 0.0]) {
            assert!((got - want).abs() < 1e-12, "{p:?}");
        }
        let (c_from_b, _) = tree.lookup("c", "b").expect("path");
        let q = c_from_b.transform_point([0.0; 3]);
        assert!(
            (q[2] + 2.0).abs() < 1e-12 && (q[0] - 1.0).abs() < 1e-12,
            "{q:?}"
        );
        assert!(tree.lookup("world", "elsewhere").is_none());
    }

    #[test]
    fn static_transforms_win_and_bad_quaternions_are_errors() {
        let mut tree = TfTree::default();
        tree.add(
            &[tf("w", "a", [5.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])],
            "/tf",
            TfSource::Dynamic,
        )
        .expect("dynamic");
        tree.add(
            &[tf("w", "a", [1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])],
            "/tf_static",
            TfSource::Static,
        )
        .expect("static");
        let (pose, dynamic) = tree.lookup("w", "a").expect("path");
        assert_eq!(pose.translation_m(), [1.0, 0.0, 0.0]);
        assert!(!dynamic);
        let e = tree
            .add(
                &[tf("w", "b", [0.0; 3], [0.0, 0.0, 0.0, 2.0])],
                "/tf_static",
                TfSource::Static,
            )
            .expect_err("not unit");
        let text = e.to_string();
        assert!(
            text.starts_with("/tf_static at stamp 0.000000000: transform w → b"),
            "{text}"
        );
    }
}
