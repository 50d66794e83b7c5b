//! The entity paths and timelines of a bodyseg `.rrd` file (README "Rerun"). One place, so
//! the writer, the tests and the docs spell them the same.

/// The world frame (z up); holds the class `AnnotationContext`.
pub const WORLD: &str = "world";
/// The projected cloud's labelled points (class ids).
pub const PROJECTED: &str = "world/projected";
/// The projected cloud's unknown points.
pub const PROJECTED_UNKNOWN: &str = "world/projected_unknown";
/// The refined cloud's labelled points (class ids).
pub const REFINED: &str = "world/refined";
/// The refined cloud's unknown points.
pub const REFINED_UNKNOWN: &str = "world/refined_unknown";
/// The DBSCAN clusters of the refinement (one colour per cluster, noise grey); hidden by
/// the file's blueprint.
pub const CLUSTERS: &str = "world/clusters";
/// The person boxes (`Boxes3D`, labelled with their ids).
pub const BOXES: &str = "world/boxes";
/// The frame's scores: `scores/<configuration>/biou`, `…/miou`, `…/iou/<class>`.
pub const SCORES: &str = "scores";
/// The frame index timeline (sequence).
pub const FRAME_TIMELINE: &str = "frame";
/// The time stamp timeline (when the recording has `stamps.csv`).
pub const TIME_TIMELINE: &str = "time";

/// The camera's colour sensor: `Transform3D` world_from_color and `Pinhole`.
pub fn color(camera: &str) -> String {
    format!("world/cameras/{camera}/color")
}

/// The colour image (`Image`, RGB).
pub fn color_image(camera: &str) -> String {
    format!("world/cameras/{camera}/color/image")
}

/// The 2D parser's labels (`SegmentationImage`).
pub fn parsed_labels(camera: &str) -> String {
    format!("world/cameras/{camera}/color/labels")
}

/// The refined labels drawn back into the colour image (`SegmentationImage`).
pub fn refined_labels(camera: &str) -> String {
    format!("world/cameras/{camera}/color/refined_labels")
}

/// The camera's depth sensor: `Transform3D` world_from_depth and `Pinhole`.
pub fn depth(camera: &str) -> String {
    format!("world/cameras/{camera}/depth")
}

/// The depth image (`DepthImage`, raw values with `meter` = depth_scale).
pub fn depth_image(camera: &str) -> String {
    format!("world/cameras/{camera}/depth/image")
}

/// A score's entity path: `scores/<name>`.
pub fn score(name: &str) -> String {
    format!("{SCORES}/{name}")
}
