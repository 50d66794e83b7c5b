//! Which topics make up which camera.
//!
//! **iai_kinect2** (kinect2_bridge, and its ROS 2 ports): `/<name>/<res>/<stream>` with
//! `res` one of `sd` (512x424, the IR sensor's frame), `qhd` (960x540) and `hd`
//! (1920x1080), both in the colour sensor's frame, and `stream` one of `image_depth`
//! (sd only: the raw depth), `image_depth_rect` (sd: undistorted; qhd/hd: registered to
//! the colour image), `image_color` (qhd/hd: raw colour), `image_color_rect` (sd:
//! registered to the depth image; qhd/hd: undistorted), each with `/compressed` or
//! `/compressedDepth` variants, and one `/<name>/<res>/camera_info` per resolution.
//!
//! Per camera one depth and one colour stream are taken, by preference:
//! - depth: `sd/image_depth` (raw, IR frame), `sd/image_depth_rect`, `qhd/image_depth_rect`,
//!   `hd/image_depth_rect`;
//! - colour: for a registered depth stream (qhd/hd) the `image_color_rect` of the same
//!   resolution first; then `qhd/image_color`, `hd/image_color`, `qhd/image_color_rect`,
//!   `hd/image_color_rect`, `sd/image_color_rect`;
//! - an uncompressed stream before its compressed variant.
//!
//! So a bag with `sd/image_depth` and `qhd/image_color` gives two sensors (IR and colour
//! with the tf between them), one with only `qhd/*_rect` streams one registered sensor
//! (colour_from_depth the identity).
//!
//! **Other layouts** (`--camera NAME=PREFIX`, or the first topic component as the camera
//! name): the image topics under the prefix; a stream's role comes from its first
//! message (encoding or compressed format), and among several candidates of one role
//! the uncompressed one, then the first by name, is taken (a note names the others).
//! A stream's CameraInfo is `camera_info` beside it (`/a/b/image_raw` → `/a/b/camera_info`),
//! as image_transport publishes them.

use crate::Ros2Error;
use crate::pixels::ImageRole;

/// iai_kinect2's resolutions, in preference order for depth.
const RESOLUTIONS: [&str; 3] = ["sd", "qhd", "hd"];

/// An image topic's name, taken apart.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StreamName {
    /// The topic.
    pub topic: String,
    /// The topic without a `/compressed` or `/compressedDepth` suffix.
    pub base: String,
    /// Whether the topic is a compressed variant.
    pub compressed: bool,
    /// `Some((prefix, resolution, stream))` for iai_kinect2's layout.
    pub iai: Option<(String, String, String)>,
}

impl StreamName {
    /// Parses `topic`.
    pub fn parse(topic: &str) -> StreamName {
        let (base, compressed) = match topic.rsplit_once('/') {
            Some((b, "compressed" | "compressedDepth")) => (b.to_string(), true),
            _ => (topic.to_string(), false),
        };
        let parts: Vec<&str> = base.split('/').collect();
        let iai = match parts.as_slice() {
            [prefix @ .., res, stream]
                if RESOLUTIONS.contains(res)
                    && matches!(
                        *stream,
                        "image_depth" | "image_depth_rect" | "image_color" | "image_color_rect"
                    ) =>
            {
                Some((prefix.join("/"), res.to_string(), stream.to_string()))
            }
            _ => None,
        };
        StreamName {
            topic: topic.to_string(),
            base,
            compressed,
            iai,
        }
    }

    /// Whether the images are rectified (ROS: use CameraInfo's `p`, no distortion): the
    /// stream's name ends with `_rect` or starts with `image_rect`.
    pub fn is_rect(&self) -> bool {
        let last = self.base.rsplit('/').next().unwrap_or("");
        last.ends_with("_rect") || last.starts_with("image_rect")
    }

    /// The CameraInfo topic of the stream: `camera_info` beside it.
    pub fn info_topic(&self) -> String {
        match self.base.rsplit_once('/') {
            Some((parent, _)) => format!("{parent}/camera_info"),
            None => "camera_info".into(),
        }
    }

    /// The role the name gives (iai_kinect2 only).
    fn iai_role(&self) -> Option<ImageRole> {
        let (_, _, stream) = self.iai.as_ref()?;
        Some(if stream.starts_with("image_depth") {
            ImageRole::Depth
        } else {
            ImageRole::Color
        })
    }
}

/// An image topic found in the bag, with the role its first message suggests.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImageTopic {
    /// Its name.
    pub name: StreamName,
    /// The role of its first message's encoding or format, if any.
    pub role_by_content: Option<ImageRole>,
}

impl ImageTopic {
    /// The topic's role: by name in iai_kinect2's layout, else by content.
    pub fn role(&self) -> Option<ImageRole> {
        self.name.iai_role().or(self.role_by_content)
    }
}

/// The depth and colour topic of one camera.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CameraTopics {
    /// The camera's name (its folder in the recording).
    pub name: String,
    /// The depth stream.
    pub depth: StreamName,
    /// The colour stream.
    pub color: StreamName,
    /// Other candidates that were not taken, for the user.
    pub notes: Vec<String>,
}

/// Preference of a depth stream (smaller first).
fn depth_rank(s: &StreamName) -> (u32, bool, String) {
    let rank = match s.iai.as_ref().map(|(_, r, st)| (r.as_str(), st.as_str())) {
        Some(("sd", "image_depth")) => 0,
        Some(("sd", "image_depth_rect")) => 1,
        Some(("qhd", "image_depth_rect")) => 2,
        Some(("hd", "image_depth_rect")) => 3,
        _ => 10,
    };
    (rank, s.compressed, s.topic.clone())
}

/// Preference of a colour stream given the chosen depth stream.
fn color_rank(s: &StreamName, depth: &StreamName) -> (u32, bool, String) {
    let registered_res = depth
        .iai
        .as_ref()
        .filter(|(_, r, _)| r != "sd")
        .map(|(_, r, _)| r.as_str());
    let rank = match s.iai.as_ref().map(|(_, r, st)| (r.as_str(), st.as_str())) {
        Some((r, "image_color_rect")) if Some(r) == registered_res => 0,
        Some(("qhd", "image_color")) => 1,
        Some(("hd", "image_color")) => 2,
        Some(("qhd", "image_color_rect")) => 3,
        Some(("hd", "image_color_rect")) => 4,
        Some(("sd", "image_color_rect")) => 5,
        _ => 10,
    };
    (rank, s.compressed, s.topic.clone())
}

/// Picks a camera's streams from its image topics.
fn choose(name: &str, topics: &[&ImageTopic], prefix: &str) -> Result<CameraTopics, Ros2Error> {
    let of_role = |role| -> Vec<&StreamName> {
        topics
            .iter()
            .filter(|t| t.role() == Some(role))
            .map(|t| &t.name)
            .collect()
    };
    let listed = || {
        topics
            .iter()
            .map(|t| t.name.topic.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let depths = of_role(ImageRole::Depth);
    let depth = depths
        .iter()
        .min_by_key(|s| depth_rank(s))
        .copied()
        .ok_or_else(|| Ros2Error::Camera {
            reason: format!(
                "camera {name}: no depth image topic under {prefix} (its image topics: {}; \
                 depth is sensor_msgs/Image 16UC1, mono16 or 32FC1, or a compressedDepth \
                 CompressedImage)",
                listed()
            ),
        })?
        .clone();
    let colors = of_role(ImageRole::Color);
    let color = colors
        .iter()
        .min_by_key(|s| color_rank(s, &depth))
        .copied()
        .ok_or_else(|| Ros2Error::Camera {
            reason: format!(
                "camera {name}: no colour image topic under {prefix} (its image topics: {})",
                listed()
            ),
        })?
        .clone();
    let others: Vec<&str> = depths
        .iter()
        .chain(&colors)
        .map(|s| s.topic.as_str())
        .filter(|t| *t != depth.topic && *t != color.topic)
        .collect();
    let notes = if others.is_empty() {
        Vec::new()
    } else {
        vec![format!(
            "camera {name}: depth from {}, colour from {}; not used: {}",
            depth.topic,
            color.topic,
            others.join(", ")
        )]
    };
    Ok(CameraTopics {
        name: name.to_string(),
        depth,
        color,
        notes,
    })
}

/// `/a/b/` → `/a/b`, `a` → `/a`.
fn normalise_prefix(prefix: &str) -> String {
    let trimmed = prefix.trim().trim_end_matches('/');
    if trimmed.starts_with('/') {
        trimmed.to_string()
    } else {
        format!("/{trimmed}")
    }
}

/// The cameras of a bag's image topics: those named by `chosen` (`(name, topic prefix)`,
/// in that order) or, when it is empty, found by layout (sorted by name).
///
/// # Errors
/// [`Ros2Error::Camera`]: a prefix matches no image topic; no camera is found; two
/// cameras get one name; a camera lacks a depth or a colour stream.
pub fn find_cameras(
    topics: &[ImageTopic],
    chosen: &[(String, String)],
) -> Result<Vec<CameraTopics>, Ros2Error> {
    let all = || {
        let mut names: Vec<&str> = topics.iter().map(|t| t.name.topic.as_str()).collect();
        names.sort_unstable();
        if names.is_empty() {
            "none".to_string()
        } else {
            names.join(", ")
        }
    };
    if !chosen.is_empty() {
        let mut cameras = Vec::new();
        for (name, prefix) in chosen {
            let prefix = normalise_prefix(prefix);
            let under: Vec<&ImageTopic> = topics
                .iter()
                .filter(|t| {
                    t.name.topic == prefix || t.name.topic.starts_with(&format!("{prefix}/"))
                })
                .collect();
            if under.is_empty() {
                return Err(Ros2Error::Camera {
                    reason: format!(
                        "--camera {name}={prefix}: no image topic under {prefix} (image topics: {})",
                        all()
                    ),
                });
            }
            cameras.push(choose(name, &under, &prefix)?);
        }
        check_unique(&cameras)?;
        return Ok(cameras);
    }
    // iai_kinect2 layout first: group by the prefix before the resolution.
    let mut groups: std::collections::BTreeMap<String, Vec<&ImageTopic>> = Default::default();
    for t in topics {
        if let Some((prefix, _, _)) = &t.name.iai {
            groups.entry(prefix.clone()).or_default().push(t);
        }
    }
    let iai = !groups.is_empty();
    if !iai {
        for t in topics.iter().filter(|t| t.role().is_some()) {
            let first = t.name.topic.trim_start_matches('/').split('/').next();
            if let Some(first) = first.filter(|f| !f.is_empty()) {
                groups.entry(format!("/{first}")).or_default().push(t);
            }
        }
    }
    let mut cameras = Vec::new();
    for (prefix, members) in &groups {
        let name = prefix
            .rsplit('/')
            .next()
            .filter(|n| !n.is_empty())
            .unwrap_or("camera");
        let has = |role| members.iter().any(|t| t.role() == Some(role));
        let rgbd = has(ImageRole::Depth) && has(ImageRole::Color);
        if !iai && !rgbd {
            // A colour-only or depth-only group in a free layout is not an RGB-D camera.
            continue;
        }
        cameras.push(choose(name, members, prefix)?);
    }
    if cameras.is_empty() {
        return Err(Ros2Error::Camera {
            reason: format!(
                "no RGB-D camera found (image topics: {}): bodyseg understands iai_kinect2's \
                 /<name>/<sd|qhd|hd>/image_* topics; name others with --camera NAME=TOPIC_PREFIX",
                all()
            ),
        });
    }
    cameras.sort_by(|a, b| a.name.cmp(&b.name));
    check_unique(&cameras)?;
    Ok(cameras)
}

fn check_unique(cameras: &[CameraTopics]) -> Result<(), Ros2Error> {
    for (i, c) in cameras.iter().enumerate() {
        if let Some(other) = cameras[..i].iter().find(|o| o.name == c.name) {
            return Err(Ros2Error::Camera {
                reason: format!(
                    "two cameras are named {} ({} and {}): name them with --camera NAME=TOPIC_PREFIX",
                    c.name, other.depth.topic, c.depth.topic
                ),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn topic(name: &str, role: Option<ImageRole>) -> ImageTopic {
        ImageTopic {
            name: StreamName::parse(name),
            role_by_content: role,
        }
    }

    #[test]
    fn iai_names_parse_with_their_camera_info_and_rect_flag() {
        let s = StreamName::parse("/kinect2_left/sd/image_depth_rect/compressedDepth");
        assert!(s.compressed && s.is_rect());
        assert_eq!(s.base, "/kinect2_left/sd/image_depth_rect");
        assert_eq!(
            s.iai,
            Some((
                "/kinect2_left".into(),
                "sd".into(),
                "image_depth_rect".into()
            ))
        );
        assert_eq!(s.info_topic(), "/kinect2_left/sd/camera_info");
        let raw = StreamName::parse("/cam/color/image_raw");
        assert!(raw.iai.is_none() && !raw.is_rect());
        assert_eq!(raw.info_topic(), "/cam/color/camera_info");
        assert!(StreamName::parse("/cam/color/image_rect_color").is_rect());
    }

    #[test]
    fn iai_cameras_take_raw_depth_and_raw_color_first() {
        use ImageRole::*;
        let topics = [
            topic("/k1/sd/image_depth", Some(Depth)),
            topic("/k1/sd/image_depth_rect", Some(Depth)),
            topic("/k1/qhd/image_color", Some(Color)),
            topic("/k1/qhd/image_color/compressed", Some(Color)),
            topic("/k1/sd/image_ir", Some(Depth)),
            topic("/k0/qhd/image_depth_rect", Some(Depth)),
            topic("/k0/qhd/image_color_rect", Some(Color)),
            topic("/k0/hd/image_color", Some(Color)),
        ];
        let cams = find_cameras(&topics, &[]).expect("cameras");
        let names: Vec<(&str, &str, &str)> = cams
            .iter()
            .map(|c| {
                (
                    c.name.as_str(),
                    c.depth.topic.as_str(),
                    c.color.topic.as_str(),
                )
            })
            .collect();
        assert_eq!(
            names,
            [
                ("k0", "/k0/qhd/image_depth_rect", "/k0/qhd/image_color_rect"),
                ("k1", "/k1/sd/image_depth", "/k1/qhd/image_color"),
            ]
        );
        assert!(
            cams[1].notes[0].contains("/k1/sd/image_depth_rect"),
            "{:?}",
            cams[1].notes
        );
    }

    #[test]
    fn chosen_prefixes_and_free_layouts() {
        use ImageRole::*;
        let topics = [
            topic("/cam/color/image_raw", Some(Color)),
            topic("/cam/depth/image_rect_raw", Some(Depth)),
            topic("/webcam/image_raw", Some(Color)),
        ];
        let cams = find_cameras(&topics, &[]).expect("found by first component");
        assert_eq!(cams.len(), 1);
        assert_eq!(cams[0].name, "cam");
        let chosen = [("front".to_string(), "cam/".to_string())];
        let cams = find_cameras(&topics, &chosen).expect("chosen");
        assert_eq!(cams[0].name, "front");
        assert_eq!(cams[0].depth.topic, "/cam/depth/image_rect_raw");
        let bad = [("x".to_string(), "/nothing".to_string())];
        let e = find_cameras(&topics, &bad).expect_err("no topic");
        assert!(e.to_string().contains("--camera x=/nothing"), "{e}");
        let e = find_cameras(&topics[2..], &[]).expect_err("no camera");
        assert!(e.to_string().contains("--camera NAME=TOPIC_PREFIX"), "{e}");
        let e =
            find_cameras(&[topic("/k/sd/image_depth", Some(Depth))], &[]).expect_err("no colour");
        assert!(
            e.to_string().contains("camera k: no colour image topic"),
            "{e}"
        );
    }
}
