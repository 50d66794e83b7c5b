//! `bodyseg synth`: a synthetic recording (FORMATS.md layout) with exact ground truth.
//!
//! The recording is written into a staging folder beside the destination and moved into
//! place when every frame is written, so a crash or an error never leaves a half-written
//! recording under the requested name.

use crate::layers::Setting;
use crate::outputs::write_text;
use crate::recording::{Layer, RecordingWriter};
use crate::stage::{Stage, plural};
use anyhow::{Context, Result};
use bodyseg_calib::write_rig_toml;
use bodyseg_io::{discard_folder, publish_folder, staging_folder, write_gray8_png, write_rgb_png};
use bodyseg_synth::{
    ChessboardConfig, SceneConfig, Synth, SynthFrame, chessboard_set, preset, preview,
};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// `preview/<stem>.png` of a synthetic recording: colour | depth | truth | prediction per
/// camera (no layer of a recording: for people to look at).
const PREVIEW_FOLDER: &str = "preview";

/// The IR (depth sensor) views of a chessboard calibration set, beside `color/`.
const IR_FOLDER: &str = "ir";

/// Where the scene configuration comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneSource {
    /// A bundled preset (`single`, `handover`, `robot_cell`).
    Preset(String),
    /// A scene TOML file.
    File(PathBuf),
}

/// What [`synth_recording`] writes and how.
#[derive(Clone, Debug)]
pub struct SynthOptions {
    /// The scene.
    pub scene: SceneSource,
    /// `KEY=VALUE` overrides of the scene (dotted keys, e.g. `rig.cameras=4`).
    pub overrides: Vec<String>,
    /// Seed: the same seed gives the same bytes.
    pub seed: u64,
    /// Number of frames.
    pub frames: usize,
    /// The recording folder to create.
    pub out: PathBuf,
    /// Replace `out` if it exists.
    pub force: bool,
    /// Write `preview/<stem>.png` per frame.
    pub previews: bool,
    /// Instead of people, write chessboard calibration views for the scene's rig
    /// (see `bodyseg synth --chessboard`).
    pub chessboard: Option<ChessboardConfig>,
}

/// What [`synth_recording`] did.
#[derive(Clone, Debug)]
pub struct SynthSummary {
    /// The resolved scene configuration.
    pub scene: SceneConfig,
    /// Frames written.
    pub frames: usize,
    /// Cameras per frame.
    pub cameras: usize,
    /// Per stage: time and a one-line summary.
    pub stages: Vec<Stage>,
}

/// The scene configuration of `source` with `overrides` (`KEY=VALUE`, dotted keys) applied,
/// validated.
pub(crate) fn load_scene(source: &SceneSource, overrides: &[String]) -> Result<SceneConfig> {
    let (text, name) = match source {
        SceneSource::Preset(name) => {
            let base = preset(name)?;
            if overrides.is_empty() {
                return Ok(base);
            }
            (base.to_toml(), format!("preset `{name}`"))
        }
        SceneSource::File(path) => (bodyseg_io::read_text(path)?, path.display().to_string()),
    };
    let mut table: toml::Table = toml::from_str(&text)
        .map_err(|e| anyhow::anyhow!("{name}: scene config: {}", e.message().trim()))?;
    for item in overrides {
        Setting::parse(item)
            .and_then(|s| s.apply(&mut table))
            .with_context(|| format!("--set {item}"))?;
    }
    SceneConfig::from_table(table).with_context(|| name.clone())
}

/// Writes every file of one frame of `synth` into a recording being written: per camera
/// its six layers, the true boxes, and with `with_preview` `preview/<stem>.png`.
pub(crate) fn write_frame(
    rec: &RecordingWriter,
    synth: &Synth,
    frame: &SynthFrame,
    with_preview: bool,
) -> Result<()> {
    let stem = frame.stem();
    for (index, images) in frame.cameras.iter().enumerate() {
        rec.write_color(index, &stem, &images.color)?;
        rec.write_depth(index, &stem, &images.depth_mm)?;
        rec.write_ids(index, Layer::Parsing, &stem, &images.parsing)?;
        rec.write_ids(index, Layer::Labels, &stem, &images.labels)?;
        rec.write_ids(index, Layer::DepthLabels, &stem, &images.depth_labels)?;
        rec.write_ids(index, Layer::DepthPerson, &stem, &images.depth_person)?;
    }
    rec.write_boxes(&stem, &frame.boxes)?;
    if with_preview {
        let image = preview(frame, synth.true_rig());
        write_rgb_png(
            &rec.root().join(PREVIEW_FOLDER).join(format!("{stem}.png")),
            image.width,
            image.height,
            &image.rgb,
        )?;
    }
    Ok(())
}

/// Renders and writes a synthetic recording; `progress` is called with the number of
/// frames done after each frame.
pub fn synth_recording(
    options: &SynthOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<SynthSummary> {
    if let Some(board) = &options.chessboard {
        return synth_chessboard(options, board);
    }
    let start = Instant::now();
    let scene = load_scene(&options.scene, &options.overrides)?;
    let synth = Synth::new(scene.clone(), options.seed)?;
    let mut stages = vec![Stage::new(
        "setup",
        start.elapsed(),
        format!(
            "scene `{}`, {}, {}",
            scene.name,
            plural(synth.people().len(), "person", "people"),
            plural(synth.true_rig().cameras.len(), "camera", "cameras")
        ),
    )];
    if options.out.exists() && !options.force {
        anyhow::bail!(
            "{}: already exists (use --force to replace it)",
            options.out.display()
        );
    }
    let staging = staging_folder(&options.out)?;
    let result = (|| -> Result<()> {
        let render_start = Instant::now();
        let rec = RecordingWriter::create(&staging, synth.written_rig(), &Layer::ALL)?;
        if synth.written_rig() != synth.true_rig() {
            write_rig_toml(synth.true_rig(), &staging.join("rig_true.toml"))?;
        }
        write_text(
            &staging.join("scene.toml"),
            &format!(
                "# bodyseg synth: the scene of this recording (seed {}, {} frames)\n{}",
                options.seed,
                options.frames,
                scene.to_toml()
            ),
        )?;
        if options.previews {
            bodyseg_io::create_folder(&staging.join(PREVIEW_FOLDER))?;
        }
        let done = AtomicUsize::new(0);
        (0..options.frames)
            .into_par_iter()
            .try_for_each(|i| -> Result<()> {
                let frame = synth.frame(i);
                write_frame(&rec, &synth, &frame, options.previews)
                    .with_context(|| format!("frame {}", frame.stem()))?;
                progress(done.fetch_add(1, Ordering::Relaxed) + 1);
                Ok(())
            })?;
        let secs = render_start.elapsed().as_secs_f64();
        stages.push(Stage::new(
            "render",
            render_start.elapsed(),
            format!(
                "{} ({:.1} frames/s)",
                plural(options.frames, "frame", "frames"),
                options.frames as f64 / secs.max(1e-9)
            ),
        ));
        Ok(())
    })();
    let t = Instant::now();
    stages.push(finish_staged(result, &staging, options, t)?);
    Ok(SynthSummary {
        frames: options.frames,
        cameras: synth.true_rig().cameras.len(),
        scene,
        stages,
    })
}

/// Writes a chessboard calibration set for the rig of `options`' scene into
/// `options.out` (staged, then moved into place):
///
/// ```text
/// OUT/board.toml               the boards (inner corners, square sizes) and conventions
/// OUT/rig_true.toml            the true rig; its world frame is the floor board's frame
/// OUT/<cam>/color/<NNNNNN>.png hand-held board views, colour sensor
/// OUT/<cam>/ir/<NNNNNN>.png    the same instants, IR (depth) sensor, 8-bit grey
/// OUT/<cam>/board_poses.json   true depth_from_board of each view
/// OUT/floor/<cam>/color.png    the floor board seen by every camera at once
/// OUT/floor/<cam>/ir.png
/// ```
pub(crate) fn synth_chessboard(
    options: &SynthOptions,
    board: &ChessboardConfig,
) -> Result<SynthSummary> {
    let start = Instant::now();
    let scene = load_scene(&options.scene, &options.overrides)?;
    let set = chessboard_set(&scene.rig, board, options.seed)?;
    let mut stages = vec![Stage::new(
        "render",
        start.elapsed(),
        format!(
            "{} hand-held views per camera, {}",
            board.views,
            plural(set.rig.cameras.len(), "camera", "cameras")
        ),
    )];
    if options.out.exists() && !options.force {
        anyhow::bail!(
            "{}: already exists (use --force to replace it)",
            options.out.display()
        );
    }
    let t = Instant::now();
    let staging = staging_folder(&options.out)?;
    let result = (|| -> Result<()> {
        write_rig_toml(&set.rig, &staging.join("rig_true.toml"))?;
        write_text(
            &staging.join("board.toml"),
            &format!(
                "# bodyseg synth --chessboard: the calibration boards of this set (seed {}).\n\
                 # Object points: inner corner (i, j) at (i*square_m, j*square_m, 0), z = x cross y.\n\
                 # The floor board's frame is the world frame of rig_true.toml (z up).\n\
                 inner_corners = [{}, {}]\nsquare_m = {}\nfloor_square_m = {}\n",
                options.seed,
                board.inner_corners[0],
                board.inner_corners[1],
                board.square_m,
                board.floor_square_m
            ),
        )?;
        for (c, camera) in set.rig.cameras.iter().enumerate() {
            let dir = staging.join(&camera.name);
            for kind in [Layer::Color.folder(), IR_FOLDER] {
                bodyseg_io::create_folder(&dir.join(kind))?;
            }
            let floor = staging.join("floor").join(&camera.name);
            bodyseg_io::create_folder(&floor)?;
            let (cw, ch) = (camera.color.width, camera.color.height);
            let (dw, dh) = (camera.depth.width, camera.depth.height);
            let mut poses = Vec::new();
            for (k, view) in set.views.iter().filter(|v| v.camera == c).enumerate() {
                let stem = format!("{k:06}");
                write_rgb_png(
                    &dir.join(Layer::Color.folder()).join(format!("{stem}.png")),
                    cw,
                    ch,
                    &view.images.color,
                )?;
                write_gray8_png(
                    &dir.join(IR_FOLDER).join(format!("{stem}.png")),
                    dw,
                    dh,
                    &view.images.ir,
                )?;
                poses.push(format!(
                    "  {{\"view\": \"{stem}\", \"rotation\": {:?}, \"translation_m\": {:?}}}",
                    view.depth_from_board.rotation(),
                    view.depth_from_board.translation_m()
                ));
            }
            write_text(
                &dir.join("board_poses.json"),
                &format!("[\n{}\n]\n", poses.join(",\n")),
            )?;
            let images = &set.floor[c];
            write_rgb_png(&floor.join("color.png"), cw, ch, &images.color)?;
            write_gray8_png(&floor.join("ir.png"), dw, dh, &images.ir)?;
        }
        Ok(())
    })();
    stages.push(finish_staged(result, &staging, options, t)?);
    Ok(SynthSummary {
        frames: board.views as usize,
        cameras: set.rig.cameras.len(),
        scene,
        stages,
    })
}

/// Moves a staged output into place when `result` is Ok (else discards it and returns the
/// error); the stage line of the move, timed from `since`.
fn finish_staged(
    result: Result<()>,
    staging: &Path,
    options: &SynthOptions,
    since: Instant,
) -> Result<Stage> {
    if let Err(e) = result {
        discard_folder(staging);
        return Err(e);
    }
    publish_folder(staging, &options.out, options.force)?;
    Ok(Stage::new(
        "write",
        since.elapsed(),
        options.out.display().to_string(),
    ))
}
