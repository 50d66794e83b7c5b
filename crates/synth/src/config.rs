//! The scene configuration (`configs/scenes/*.toml`): people, static scene, rig, depth
//! faults, parsing errors and DSA sources. Every field has a default; unknown keys are
//! errors so that a typo never silently falls back to a default.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Why a scene configuration cannot be used. Always names the field.
#[derive(Debug, Error)]
pub enum SynthError {
    /// The TOML text does not parse or has an unknown key / wrong type.
    #[error("scene config: {0}")]
    Parse(String),
    /// A field has a value outside its domain.
    #[error("scene config: `{field}` {reason}")]
    Invalid {
        /// Dotted path of the field (`rig.cameras`).
        field: String,
        /// What is wrong, e.g. "must be > 0, got 0".
        reason: String,
    },
    /// No preset of that name.
    #[error("unknown scene preset `{0}` (known: {1})")]
    UnknownPreset(String, String),
}

/// A whole synthetic scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SceneConfig {
    /// Name written into the recording's `scene.toml`.
    pub name: String,
    /// Frames per second of the sequence (people move between frames).
    pub fps: f64,
    /// The people.
    pub people: PeopleConfig,
    /// Floor, walls and occluders.
    pub scene: StaticSceneConfig,
    /// The camera network.
    pub rig: RigConfig,
    /// Kinect-v2-like depth faults.
    pub depth: DepthFaultsConfig,
    /// Errors of the simulated 2D parser (the `parsing/` images).
    pub parsing: ParserMistakesConfig,
    /// Sources of depth-segmentation association errors.
    pub dsa: DsaConfig,
}

impl Default for SceneConfig {
    fn default() -> Self {
        SceneConfig {
            name: "custom".into(),
            fps: 15.0,
            people: PeopleConfig::default(),
            scene: StaticSceneConfig::default(),
            rig: RigConfig::default(),
            depth: DepthFaultsConfig::default(),
            parsing: ParserMistakesConfig::default(),
            dsa: DsaConfig::default(),
        }
    }
}

/// How people are placed and posed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PeopleConfig {
    /// Number of people, 1–3.
    pub count: u32,
    /// Body height range, metres (sampled uniformly per person).
    pub height_m: [f64; 2],
    /// Girth factor range (1 = average build; scales torso and limb radii).
    pub girth: [f64; 2],
    /// Poses people are drawn from: any of `standing`, `walking`, `reaching`,
    /// `handing_over`, `arms_crossed`, `hands_on_hips`, `pointing`, `crouching`.
    pub poses: Vec<String>,
    /// Standard deviation of the random perturbation of every joint angle, degrees.
    pub joint_noise_deg: f64,
    /// Two people (the first two) face each other and pass an object hand to hand.
    pub handover: bool,
    /// Distance between the two people's pelvis centres in a hand-over, metres.
    pub handover_distance_m: f64,
    /// People stand inside this square around the workspace centre (half side, metres).
    pub area_half_m: f64,
    /// Minimum distance between people (pelvis centres) outside a hand-over, metres.
    pub min_spacing_m: f64,
    /// Walking speed of people in the `walking` pose, metres per second.
    pub walk_speed_m_s: f64,
    /// Fraction of people with short sleeves (bare forearms).
    pub short_sleeves: f64,
}

impl Default for PeopleConfig {
    fn default() -> Self {
        PeopleConfig {
            count: 1,
            height_m: [1.50, 1.95],
            girth: [0.85, 1.25],
            poses: [
                "standing",
                "walking",
                "reaching",
                "arms_crossed",
                "hands_on_hips",
                "pointing",
                "crouching",
            ]
            .map(String::from)
            .to_vec(),
            joint_noise_deg: 6.0,
            handover: false,
            handover_distance_m: 0.7,
            area_half_m: 0.8,
            min_spacing_m: 0.9,
            walk_speed_m_s: 0.6,
            short_sleeves: 0.5,
        }
    }
}

/// The names [`PeopleConfig::poses`] accepts.
pub const POSE_NAMES: [&str; 8] = [
    "standing",
    "walking",
    "reaching",
    "handing_over",
    "arms_crossed",
    "hands_on_hips",
    "pointing",
    "crouching",
];

/// Floor, walls and occluders.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StaticSceneConfig {
    /// A floor at z = 0.
    pub floor: bool,
    /// Four walls around the room.
    pub walls: bool,
    /// Half side of the square room, metres (walls stand there).
    pub room_half_m: f64,
    /// A table near the people.
    pub table: bool,
    /// A robot arm made of cylinders, on a pedestal, moving over the frames.
    pub robot_arm: bool,
    /// Number of boxes standing on the floor.
    pub boxes: u32,
}

impl Default for StaticSceneConfig {
    fn default() -> Self {
        StaticSceneConfig {
            floor: true,
            walls: true,
            room_half_m: 3.5,
            table: false,
            robot_arm: false,
            boxes: 0,
        }
    }
}

/// One camera placed by hand (overrides the automatic ring).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraPlacement {
    /// Direction from the workspace centre to the camera, degrees about z (0 = +x).
    pub azimuth_deg: f64,
    /// Horizontal distance to the workspace centre, metres.
    pub distance_m: f64,
    /// Mounting height, metres.
    pub height_m: f64,
}

/// The camera network.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RigConfig {
    /// Number of cameras (ignored when `placements` is given).
    pub cameras: u32,
    /// Horizontal distance of the cameras to the workspace centre, metres.
    pub distance_m: f64,
    /// Mounting height range, metres (camera `i` of `n` at an evenly spread height).
    pub height_m: [f64; 2],
    /// Height of the point the cameras look at, metres.
    pub look_at_height_m: f64,
    /// Azimuth of the first camera, degrees; the others are evenly spread around.
    pub first_azimuth_deg: f64,
    /// Colour image width: 1920 (Kinect v2) or a scaled width (960) with scaled
    /// intrinsics; the height follows the 16:9 aspect ratio.
    pub color_width: u32,
    /// Cameras placed by hand; empty = the automatic ring above.
    pub placements: Vec<CameraPlacement>,
}

impl Default for RigConfig {
    fn default() -> Self {
        RigConfig {
            cameras: 3,
            distance_m: 2.6,
            height_m: [1.8, 2.5],
            look_at_height_m: 0.9,
            first_azimuth_deg: -90.0,
            color_width: 960,
            placements: Vec::new(),
        }
    }
}

/// Kinect-v2-like depth faults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DepthFaultsConfig {
    /// Gaussian depth noise at 1 m, millimetres; σ(z) = σ₁·z² (grows with distance).
    /// Default 1 mm: 4 mm at 2 m, 16 mm at 4 m, the order of the Kinect v2's axial
    /// noise near the image centre (~1–2 mm up to 2 m) made pessimistic at long range.
    pub noise_mm_at_1m: f64,
    /// Probability that a pixel on a depth discontinuity becomes a flying pixel (a depth
    /// between foreground and background).
    pub flying_pixel_prob: f64,
    /// A neighbour depth jump larger than this fraction of the depth is a discontinuity.
    pub edge_jump_ratio: f64,
    /// Surfaces seen at more than this angle from their normal give no measurement,
    /// degrees.
    pub grazing_angle_deg: f64,
    /// Depths outside `[min, max]` metres give no measurement (Kinect v2: 0.5–4.5 m).
    pub range_m: [f64; 2],
    /// Fraction of valid pixels dropped at random (IR speckle, dark materials).
    pub dropout: f64,
}

impl Default for DepthFaultsConfig {
    fn default() -> Self {
        DepthFaultsConfig {
            noise_mm_at_1m: 1.0,
            flying_pixel_prob: 0.5,
            edge_jump_ratio: 0.04,
            grazing_angle_deg: 80.0,
            range_m: [0.5, 4.5],
            dropout: 0.002,
        }
    }
}

/// Errors of the simulated 2D parser. All zero: the prediction equals the truth.
///
/// Pixel sizes are for a 1920-wide colour image and scale with `rig.color_width`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ParserMistakesConfig {
    /// Lower arms and lower legs grow by this many pixels into their neighbours and the
    /// background (the paper reports SCHP over-segmenting small parts).
    pub small_part_dilation_px: f64,
    /// Other body parts grow by this many pixels into the background.
    pub part_dilation_px: f64,
    /// Boundaries between labels move by up to this many pixels (smooth random field).
    pub boundary_jitter_px: f64,
    /// Probability per limb and frame that the upper/lower label is swapped in a band
    /// around the elbow or knee.
    pub swap_prob: f64,
    /// Half width of that band along the limb, pixels.
    pub swap_band_px: f64,
    /// Probability per small part (forearm+hand, shin+foot) and frame that the parser
    /// misses it (labels it background).
    pub miss_prob: f64,
}

impl Default for ParserMistakesConfig {
    fn default() -> Self {
        ParserMistakesConfig {
            small_part_dilation_px: 6.0,
            part_dilation_px: 2.0,
            boundary_jitter_px: 4.0,
            swap_prob: 0.15,
            swap_band_px: 30.0,
            miss_prob: 0.03,
        }
    }
}

impl ParserMistakesConfig {
    /// All knobs at zero: predictions equal the truth.
    pub fn none() -> Self {
        ParserMistakesConfig {
            small_part_dilation_px: 0.0,
            part_dilation_px: 0.0,
            boundary_jitter_px: 0.0,
            swap_prob: 0.0,
            swap_band_px: 0.0,
            miss_prob: 0.0,
        }
    }
}

/// Sources of depth-segmentation association errors beyond depth noise.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DsaConfig {
    /// The rig written to `rig.toml` differs from the true one by a rotation of this many
    /// degrees (random axis per camera) of `color_from_depth`.
    pub color_from_depth_rotation_deg: f64,
    /// … and a translation of this length (random direction) of `color_from_depth`, metres.
    pub color_from_depth_translation_m: f64,
    /// Same for `world_from_depth`, degrees.
    pub world_from_depth_rotation_deg: f64,
    /// Same for `world_from_depth`, metres.
    pub world_from_depth_translation_m: f64,
    /// The colour image is exposed this long after the depth image, seconds (people move
    /// in between).
    pub color_time_offset_s: f64,
}

impl Default for DsaConfig {
    fn default() -> Self {
        DsaConfig {
            color_from_depth_rotation_deg: 0.0,
            color_from_depth_translation_m: 0.0,
            world_from_depth_rotation_deg: 0.0,
            world_from_depth_translation_m: 0.0,
            color_time_offset_s: 0.0,
        }
    }
}

fn invalid(field: &str, reason: impl Into<String>) -> SynthError {
    SynthError::Invalid {
        field: field.into(),
        reason: reason.into(),
    }
}

fn check_range(field: &str, v: f64, lo: f64, hi: f64) -> Result<(), SynthError> {
    if !(v >= lo && v <= hi) {
        return Err(invalid(field, format!("must be in [{lo}, {hi}], got {v}")));
    }
    Ok(())
}

fn check_positive(field: &str, v: f64) -> Result<(), SynthError> {
    if !(v > 0.0 && v.is_finite()) {
        return Err(invalid(field, format!("must be > 0, got {v}")));
    }
    Ok(())
}

fn check_non_negative(field: &str, v: f64) -> Result<(), SynthError> {
    if !(v >= 0.0 && v.is_finite()) {
        return Err(invalid(field, format!("must be >= 0, got {v}")));
    }
    Ok(())
}

fn check_interval(field: &str, v: [f64; 2], lo: f64, hi: f64) -> Result<(), SynthError> {
    check_range(field, v[0], lo, hi)?;
    check_range(field, v[1], lo, hi)?;
    if v[0] > v[1] {
        return Err(invalid(
            field,
            format!("must be [min, max] with min <= max, got {v:?}"),
        ));
    }
    Ok(())
}

impl SceneConfig {
    /// Parses a scene TOML (unknown keys are errors) and validates it.
    pub fn from_toml(text: &str) -> Result<SceneConfig, SynthError> {
        let config: SceneConfig =
            toml::from_str(text).map_err(|e| SynthError::Parse(e.message().to_string()))?;
        config.validate()?;
        Ok(config)
    }

    /// A scene from a TOML table (a file's, with the caller's settings applied: bodyseg
    /// pipeline's `synth --set`), validated.
    pub fn from_table(table: toml::Table) -> Result<SceneConfig, SynthError> {
        let config: SceneConfig = toml::Value::Table(table)
            .try_into()
            .map_err(|e: toml::de::Error| SynthError::Parse(e.message().to_string()))?;
        config.validate()?;
        Ok(config)
    }

    /// The TOML text of this configuration (what `scene.toml` in a recording holds).
    pub fn to_toml(&self) -> String {
        // Serialising plain structs of numbers, strings and vectors cannot fail.
        toml::to_string_pretty(self).unwrap_or_default()
    }

    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), SynthError> {
        check_positive("fps", self.fps)?;
        let p = &self.people;
        check_range("people.count", f64::from(p.count), 1.0, 3.0)?;
        check_interval("people.height_m", p.height_m, 1.0, 2.2)?;
        check_interval("people.girth", p.girth, 0.5, 2.0)?;
        if p.poses.is_empty() {
            return Err(invalid("people.poses", "must name at least one pose"));
        }
        for pose in &p.poses {
            if !POSE_NAMES.contains(&pose.as_str()) {
                return Err(invalid(
                    "people.poses",
                    format!("unknown pose `{pose}` (known: {})", POSE_NAMES.join(", ")),
                ));
            }
        }
        check_range("people.joint_noise_deg", p.joint_noise_deg, 0.0, 45.0)?;
        if p.handover && p.count < 2 {
            return Err(invalid(
                "people.handover",
                "needs people.count >= 2 (two people pass the object)",
            ));
        }
        check_range(
            "people.handover_distance_m",
            p.handover_distance_m,
            0.3,
            1.5,
        )?;
        check_positive("people.area_half_m", p.area_half_m)?;
        check_non_negative("people.min_spacing_m", p.min_spacing_m)?;
        check_non_negative("people.walk_speed_m_s", p.walk_speed_m_s)?;
        check_range("people.short_sleeves", p.short_sleeves, 0.0, 1.0)?;

        let s = &self.scene;
        check_positive("scene.room_half_m", s.room_half_m)?;
        if s.boxes > 16 {
            return Err(invalid(
                "scene.boxes",
                format!("must be <= 16, got {}", s.boxes),
            ));
        }

        let r = &self.rig;
        if r.placements.is_empty() {
            if r.cameras == 0 {
                return Err(invalid("rig.cameras", "must be >= 1, got 0"));
            }
            if r.cameras > 16 {
                return Err(invalid(
                    "rig.cameras",
                    format!("must be <= 16, got {}", r.cameras),
                ));
            }
            check_positive("rig.distance_m", r.distance_m)?;
            check_interval("rig.height_m", r.height_m, 0.1, 10.0)?;
        } else if r.placements.len() > 16 {
            return Err(invalid(
                "rig.placements",
                format!("at most 16 cameras, got {}", r.placements.len()),
            ));
        }
        for (i, c) in r.placements.iter().enumerate() {
            check_positive(&format!("rig.placements[{i}].distance_m"), c.distance_m)?;
            check_range(
                &format!("rig.placements[{i}].height_m"),
                c.height_m,
                0.1,
                10.0,
            )?;
            if !c.azimuth_deg.is_finite() {
                return Err(invalid(
                    &format!("rig.placements[{i}].azimuth_deg"),
                    "must be finite",
                ));
            }
        }
        check_range("rig.look_at_height_m", r.look_at_height_m, 0.0, 5.0)?;
        if !r.first_azimuth_deg.is_finite() {
            return Err(invalid("rig.first_azimuth_deg", "must be finite"));
        }
        if !(64..=3840).contains(&r.color_width) || !r.color_width.is_multiple_of(16) {
            return Err(invalid(
                "rig.color_width",
                format!(
                    "must be a multiple of 16 in 64..=3840 (1920 = Kinect v2, 960 = half), got {}",
                    r.color_width
                ),
            ));
        }

        let d = &self.depth;
        check_non_negative("depth.noise_mm_at_1m", d.noise_mm_at_1m)?;
        check_range("depth.flying_pixel_prob", d.flying_pixel_prob, 0.0, 1.0)?;
        check_positive("depth.edge_jump_ratio", d.edge_jump_ratio)?;
        check_range("depth.grazing_angle_deg", d.grazing_angle_deg, 0.0, 90.0)?;
        check_interval("depth.range_m", d.range_m, 0.0, 65.0)?;
        check_range("depth.dropout", d.dropout, 0.0, 1.0)?;

        // Simulated-mistake sizes and probabilities, and the DSA perturbations: each a value
        // with its inclusive range, checked in this order (a table: one line a field).
        let (e, a) = (&self.parsing, &self.dsa);
        #[rustfmt::skip]
        let ranges = [
            ("parsing.small_part_dilation_px", e.small_part_dilation_px, 0.0, 100.0),
            ("parsing.part_dilation_px", e.part_dilation_px, 0.0, 100.0),
            ("parsing.boundary_jitter_px", e.boundary_jitter_px, 0.0, 100.0),
            ("parsing.swap_prob", e.swap_prob, 0.0, 1.0),
            ("parsing.swap_band_px", e.swap_band_px, 0.0, 500.0),
            ("parsing.miss_prob", e.miss_prob, 0.0, 1.0),
            ("dsa.color_from_depth_rotation_deg", a.color_from_depth_rotation_deg, 0.0, 30.0),
            ("dsa.color_from_depth_translation_m", a.color_from_depth_translation_m, 0.0, 1.0),
            ("dsa.world_from_depth_rotation_deg", a.world_from_depth_rotation_deg, 0.0, 30.0),
            ("dsa.world_from_depth_translation_m", a.world_from_depth_translation_m, 0.0, 1.0),
            ("dsa.color_time_offset_s", a.color_time_offset_s, -1.0, 1.0),
        ];
        for (field, value, lo, hi) in ranges {
            check_range(field, value, lo, hi)?;
        }
        Ok(())
    }
}

/// The bundled presets: name and TOML text (`configs/scenes/<name>.toml`).
pub const PRESETS: [(&str, &str); 3] = [
    (
        "single",
        include_str!("../../../configs/scenes/single.toml"),
    ),
    (
        "handover",
        include_str!("../../../configs/scenes/handover.toml"),
    ),
    (
        "robot_cell",
        include_str!("../../../configs/scenes/robot_cell.toml"),
    ),
];

/// The scene configuration of a bundled preset.
pub fn preset(name: &str) -> Result<SceneConfig, SynthError> {
    let Some((_, text)) = PRESETS.iter().find(|(n, _)| *n == name) else {
        let known: Vec<&str> = PRESETS.iter().map(|(n, _)| *n).collect();
        return Err(SynthError::UnknownPreset(name.into(), known.join(", ")));
    };
    SceneConfig::from_toml(text).map_err(|e| match e {
        SynthError::Parse(m) => SynthError::Parse(format!("preset `{name}`: {m}")),
        other => other,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_parse_and_validate() {
        for (name, _) in PRESETS {
            let c = preset(name).expect(name);
            assert_eq!(c.name, name);
        }
        assert_eq!(preset("handover").expect("handover").people.count, 2);
        assert!(preset("robot_cell").expect("robot_cell").scene.robot_arm);
        assert!(matches!(preset("nope"), Err(SynthError::UnknownPreset(..))));
    }

    #[test]
    fn bad_configs_name_the_field() {
        let err = |text: &str| SceneConfig::from_toml(text).expect_err(text).to_string();
        assert!(err("[people]\ncount = 2\nbogus = 1").contains("bogus"));
        assert!(err("[rig]\ncameras = 0").contains("rig.cameras"));
        assert!(err("[scene]\nroom_half_m = -1.0").contains("scene.room_half_m"));
        assert!(err("[people]\nheight_m = [1.9, 1.6]").contains("people.height_m"));
        assert!(err("[people]\nposes = [\"moonwalk\"]").contains("moonwalk"));
        assert!(err("[depth]\nrange_m = [-1.0, 4.5]").contains("depth.range_m"));
    }

    #[test]
    fn tables_are_read_as_text_is_and_round_trip() {
        let text = PRESETS[0].1;
        let mut table: toml::Table = toml::from_str(text).expect("preset TOML");
        let c = SceneConfig::from_table(table.clone()).expect("preset");
        assert_eq!(c, SceneConfig::from_toml(text).expect("preset"));
        assert_eq!(SceneConfig::from_toml(&c.to_toml()).expect("round trip"), c);
        let rig = table
            .entry("rig")
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        if let toml::Value::Table(rig) = rig {
            rig.insert("camras".into(), toml::Value::Integer(4));
        }
        let e = SceneConfig::from_table(table).expect_err("typo");
        assert!(e.to_string().contains("camras"), "{e}");
    }
}
