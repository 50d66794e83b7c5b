//! Helpers shared by the e2e modules: running the binary, writing scenes.

use bodyseg_core::{PersonBoxes, PointOrigin};
use bodyseg_io::{PlyWriteOptions, write_boxes, write_ply};
use bodyseg_testkit::{SyntheticPerson, human_cloud};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

/// Seed of the synthetic person of the happy-path tests.
pub const SEED: u64 = 20240;

/// Points of that person: enough for every part to form clusters at min_points 40.
pub const POINTS: usize = 20_000;

/// The finished run of `bodyseg ARGS` in `dir`, with logging at its default (warn).
pub fn bodyseg(dir: &Path, args: &[&str]) -> Output {
    bodyseg_env(dir, args, &[])
}

/// A command line's words, split at whitespace: `&words("rig show rig.toml")` for
/// arguments that are all plain words.
pub fn words(line: &str) -> Vec<&str> {
    line.split_whitespace().collect()
}

/// Runs `bodyseg` in `dir` with the words of `line` (see [`words`]).
pub fn bodyseg_line(dir: &Path, line: &str) -> Output {
    bodyseg(dir, &words(line))
}

/// Asserts exit status 1, exactly one stderr line `error: ...` holding every needle, and
/// the folder's files as `before` (no output, no temporary); returns stderr.
pub fn assert_one_error(out: &Output, d: &Path, before: &[String], needles: &[&str]) -> String {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "want one error line:\n{err}");
    assert!(lines[0].starts_with("error: "), "{err}");
    for needle in needles {
        assert!(lines[0].contains(needle), "{needle:?} not in: {err}");
    }
    assert_eq!(files_in(d), before, "files changed after: {err}");
    err
}

/// Runs `bodyseg ARGS` in `dir` and asserts success (showing stderr otherwise); the run.
pub fn succeeds_in(dir: &Path, args: &[&str]) -> Output {
    let out = bodyseg(dir, args);
    assert_ok(&out, &format!("bodyseg {args:?}"));
    out
}

/// Asserts that `bodyseg ARGS` (a `--help`) succeeds and its stdout mentions every word.
pub fn assert_help(args: &[&str], must_mention: &[&str]) {
    let dir = tempdir();
    assert_contains_all(&stdout(&succeeds_in(dir.path(), args)), must_mention);
}

/// Runs `bodyseg ARGS` in `dir` and asserts [`assert_one_error`] against the folder's
/// files just before the run; returns stderr.
pub fn fails_in(dir: &Path, args: &[&str], needles: &[&str]) -> String {
    let before = files_in(dir);
    let out = bodyseg(dir, args);
    assert_one_error(&out, dir, &before, needles)
}

/// [`fails_in`] with the words of `line` (see [`words`]).
pub fn fails_line_in(dir: &Path, line: &str, needles: &[&str]) -> String {
    fails_in(dir, &words(line), needles)
}

/// Asserts that `text` holds every needle, showing it otherwise.
pub fn assert_contains_all(text: &str, needles: &[&str]) {
    for needle in needles {
        assert!(text.contains(needle), "{needle:?} not in:\n{text}");
    }
}

/// stderr as text.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// stdout as text.
pub fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Asserts success, showing stderr otherwise.
pub fn assert_ok(out: &Output, what: &str) {
    assert!(
        out.status.success(),
        "{what} failed ({}):\n{}",
        out.status,
        stderr(out)
    );
}

/// The input files of a one-person scene, written in `dir`.
pub struct Scene {
    /// The generated person (predicted labels, truth, box).
    pub person: SyntheticPerson,
    /// Predicted cloud, `in.ply`.
    pub cloud: PathBuf,
    /// Ground truth (same points, true labels), `gt.ply`.
    pub gt: PathBuf,
    /// Person boxes, `boxes.json`.
    pub boxes: PathBuf,
}

/// Writes `in.ply`, `gt.ply` and `boxes.json` for `human_cloud(POINTS, SEED)` into `dir`.
pub fn write_scene(dir: &Path) -> Scene {
    let person = human_cloud(POINTS, SEED);
    let scene = Scene {
        cloud: dir.join("in.ply"),
        gt: dir.join("gt.ply"),
        boxes: dir.join("boxes.json"),
        person,
    };
    let opts = PlyWriteOptions::default();
    write_ply(&scene.cloud, &scene.person.cloud, &opts).expect("write in.ply");
    let gt = scene.person.cloud.with_labels(scene.person.truth.clone());
    write_ply(&scene.gt, &gt, &opts).expect("write gt.ply");
    let boxes = PersonBoxes {
        frame: "000000".into(),
        boxes: vec![scene.person.person_box.clone()],
        world_from_cloud: None,
    };
    write_boxes(&scene.boxes, &boxes).expect("write boxes.json");
    scene
}

/// A temporary folder holding the files of [`write_scene`], for tests that add a file or
/// two and run one command after another in it.
pub struct SceneDir {
    dir: tempfile::TempDir,
    /// The scene written in the folder.
    pub scene: Scene,
}

impl SceneDir {
    /// A new temporary folder with `in.ply`, `gt.ply` and `boxes.json`.
    pub fn new() -> Self {
        let dir = tempdir();
        let scene = write_scene(dir.path());
        Self { dir, scene }
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        self.dir.path()
    }

    /// Writes `contents` to the file `name` in the folder.
    pub fn write(&self, name: &str, contents: impl AsRef<[u8]>) -> &Self {
        std::fs::write(self.path().join(name), contents).expect("write a test file");
        self
    }

    /// [`fails_in`] the folder.
    pub fn fails(&self, args: &[&str], needles: &[&str]) -> String {
        fails_in(self.path(), args, needles)
    }

    /// [`SceneDir::fails`] with the words of `line` (see [`words`]).
    pub fn fails_line(&self, line: &str, needles: &[&str]) -> String {
        self.fails(&words(line), needles)
    }
}

/// The origins `human_cloud` gives its points: camera 0, pixel = index.
pub fn index_origins(n: usize) -> Vec<PointOrigin> {
    (0..n as u32)
        .map(|pixel| PointOrigin { camera: 0, pixel })
        .collect()
}

/// The file names in `dir`, sorted.
pub fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("read temp dir")
        .map(|e| {
            e.expect("dir entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    names.sort();
    names
}

/// `bodyseg refine --cloud in.ply --boxes boxes.json ARGS` in `dir` (the files of
/// [`write_scene`]).
pub fn refine_scene(dir: &Path, args: &[&str]) -> Output {
    let mut all = vec!["refine", "--cloud", "in.ply", "--boxes", "boxes.json"];
    all.extend_from_slice(args);
    bodyseg(dir, &all)
}

/// A temporary folder for one test.
pub fn tempdir() -> tempfile::TempDir {
    tempfile::tempdir().expect("create temp dir")
}

/// The finished run of `bodyseg ARGS` in `dir` with extra environment variables.
pub fn bodyseg_env(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_bodyseg"))
        .args(args)
        .current_dir(dir)
        .env_remove("RUST_LOG")
        .envs(env.iter().copied())
        .output();
    match out {
        Ok(out) => out,
        Err(e) => panic!("cannot run bodyseg {args:?}: {e}"),
    }
}

/// Frames of the shared recording.
pub const FRAMES: usize = 8;

/// The shared recording (made once per test binary): 8 frames of two people handing
/// over an object, 3 Kinect v2 cameras, with ground truth and simulated predictions.
pub fn recording() -> &'static Path {
    static REC: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    let (_, rec) = REC.get_or_init(|| {
        let dir = tempdir();
        let line =
            format!("synth --preset handover --frames {FRAMES} --seed 5 --no-preview --out rec");
        let out = bodyseg_line(dir.path(), &line);
        assert_ok(&out, "bodyseg synth");
        let rec = dir.path().join("rec");
        (dir, rec)
    });
    rec
}

/// `bodyseg run` of the shared [`recording`] into `dir/out`, with `extra` arguments.
pub fn run_recording(dir: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "run",
        "--recording",
        recording().to_str().expect("utf-8"),
        "--out",
        "out",
    ];
    args.extend_from_slice(extra);
    bodyseg(dir, &args)
}

/// `bodyseg convert --input data --format recording --out OUT EXTRA...` in `dir` (the
/// recordings in `dir/data`).
pub fn convert_data(dir: &Path, out: &str, extra: &[&str]) -> Output {
    let mut args = vec![
        "convert",
        "--input",
        "data",
        "--format",
        "recording",
        "--out",
        out,
    ];
    args.extend_from_slice(extra);
    bodyseg(dir, &args)
}

/// A temporary folder with a copy of [`recording`] in `rec`, for a test that changes it;
/// returns the folder and the copy's path.
pub fn recording_copy() -> (tempfile::TempDir, PathBuf) {
    let dir = tempdir();
    let rec = dir.path().join("rec");
    copy_tree(recording(), &rec);
    (dir, rec)
}

/// Every file under `dir`, relative, sorted.
pub fn tree(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("list") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(dir).expect("inside");
                out.push(rel.to_string_lossy().replace('\\', "/"));
            }
        }
    }
    out.sort();
    out
}

/// Copies a folder tree.
pub fn copy_tree(from: &Path, to: &Path) {
    for rel in tree(from) {
        let dst = to.join(&rel);
        std::fs::create_dir_all(dst.parent().expect("parent")).expect("mkdir");
        std::fs::copy(from.join(&rel), dst).expect("copy");
    }
}
