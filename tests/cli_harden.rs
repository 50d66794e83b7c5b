//! Issue 27 (hardening): names from files that would lead out of a folder, outputs that
//! would replace an input or something not ours, values that hung a command, and the
//! `warning:` lines for valid but implausible inputs. Each failed on the code before.

use crate::common::{SceneDir, bodyseg, bodyseg_env, bodyseg_line, recording_copy, stderr, tree};
use std::path::Path;
use std::process::Output;

/// `bodyseg refine --cloud CLOUD --boxes BOXES --out OUT EXTRA...` in `d`.
fn refine(d: &Path, cloud: &str, boxes: &str, out: &str, extra: &[&str]) -> Output {
    let mut args = vec!["refine", "--cloud", cloud, "--boxes", boxes, "--out", out];
    args.extend_from_slice(extra);
    bodyseg(d, &args)
}

/// `bodyseg eval --pred PRED --gt GT EXTRA...` in `d`.
fn eval(d: &Path, pred: &str, gt: &str, extra: &[&str]) -> Output {
    let mut args = vec!["eval", "--pred", pred, "--gt", gt];
    args.extend_from_slice(extra);
    bodyseg(d, &args)
}

#[test]
fn an_output_that_is_an_input_or_not_ours_is_refused() {
    let s = SceneDir::new();
    let d = s.path();
    let input = std::fs::read(d.join("in.ply")).expect("in.ply");
    let refine_to = |out: &str| format!("refine --cloud in.ply --boxes boxes.json --out {out}");
    let eval_to = |out: &str| format!("eval --pred in.ply --gt gt.ply --out {out}");
    s.fails_line(&refine_to("in.ply"), &["--out in.ply is the input --cloud"]);
    assert_eq!(std::fs::read(d.join("in.ply")).expect("in.ply"), input);
    // The same file through another name.
    std::os::unix::fs::symlink("in.ply", d.join("link.ply")).expect("symlink");
    s.fails_line(&refine_to("link.ply"), &["is the input --cloud"]);
    // A report over a cloud; a device.
    s.fails_line(&eval_to("in.ply"), &["is the input --pred"]);
    s.fails_line(&eval_to("link.ply"), &["is the input --pred"]);
    std::fs::copy(d.join("in.ply"), d.join("other.ply")).expect("copy");
    let not_ours = ["exists and is not a file this command writes"];
    s.fails_line(&eval_to("other.ply"), &not_ours);
    // A socket (not /dev/null: a bodyseg without the guard would replace the device).
    let _socket = std::os::unix::net::UnixListener::bind(d.join("sock.ply")).expect("socket");
    let socket = ["sock.ply: is a socket, not a regular file"];
    s.fails_line(&refine_to("sock.ply"), &socket);
    use std::os::unix::fs::FileTypeExt;
    assert!(
        std::fs::symlink_metadata(d.join("sock.ply"))
            .expect("socket")
            .file_type()
            .is_socket()
    );
}

#[test]
fn run_refuses_to_write_into_its_recording() {
    let (dir, rec) = recording_copy();
    let before = tree(&rec);
    for out in ["rec", "rec/out", "rec/../rec"] {
        let o = bodyseg(
            dir.path(),
            &[
                "run",
                "--recording",
                "rec",
                "--out",
                out,
                "--frame",
                "000000",
            ],
        );
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains("the input REC"), "{err}");
        assert_eq!(tree(&rec), before, "{out}: {err}");
    }
}

#[test]
fn a_camera_name_that_leads_out_of_the_recording_is_refused() {
    let (dir, rec) = recording_copy();
    let rig = std::fs::read_to_string(rec.join("rig.toml")).expect("rig.toml");
    let first = rig
        .lines()
        .find_map(|l| {
            l.trim()
                .strip_prefix("name = \"")
                .and_then(|r| r.strip_suffix('"'))
        })
        .expect("a camera name")
        .to_string();
    for bad in ["../../x", "/tmp/x", "kamera_ä"] {
        let text = rig.replacen(
            &format!("name = \"{first}\""),
            &format!("name = \"{bad}\""),
            1,
        );
        std::fs::write(rec.join("rig.toml"), text).expect("write");
        let o = bodyseg(dir.path(), &["run", "--recording", "rec", "--out", "out"]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{bad}: {err}");
        assert!(err.contains(&format!("camera {bad:?}")), "{bad}: {err}");
        assert!(!dir.path().join("out").exists(), "{bad}");
        assert!(!dir.path().join("x").exists() && !Path::new("/tmp/x/color").exists());
    }
}

#[test]
fn values_that_hung_a_command_are_refused_at_once() {
    let s = SceneDir::new();
    let start = std::time::Instant::now();
    s.fails_line(
        "boxes --cloud in.ply --set boxes.head_separation_m=1000 --out b.json",
        &["boxes.head_separation_m must be in (0, 2] metres, got 1000"],
    );
    assert!(start.elapsed().as_secs() < 10);
}

#[test]
fn implausible_inputs_are_warned_about() {
    let s = SceneDir::new();
    let (d, scene) = (s.path(), &s.scene);
    // A box far from the cloud: refinement would turn every body label into background.
    let mut far = scene.person.person_box.clone();
    far.center_m[0] += 500.0;
    let boxes = bodyseg_core::PersonBoxes {
        frame: "000000".into(),
        boxes: vec![far],
        world_from_cloud: None,
    };
    bodyseg_io::write_boxes(&d.join("far.json"), &boxes).expect("write");
    let out = refine(d, "in.ply", "far.json", "r.ply", &["-q"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        err.lines()
            .any(|l| l.starts_with("warning: in.ply: person box")
                && l.contains("holds no point of the cloud")),
        "{err}"
    );
    // No person at all.
    let none = bodyseg_core::PersonBoxes {
        frame: "000000".into(),
        boxes: vec![],
        world_from_cloud: None,
    };
    bodyseg_io::write_boxes(&d.join("none.json"), &none).expect("write");
    let out = refine(d, "in.ply", "none.json", "r.ply", &[]);
    assert!(
        stderr(&out).contains("warning: in.ply: no person found"),
        "{}",
        stderr(&out)
    );
    // Clouds of other points: refused below half, a warning above.
    let mut moved = scene.person.cloud.clone();
    for p in &mut moved.positions_m {
        p[2] += 0.5;
    }
    let opts = bodyseg_io::PlyWriteOptions::default();
    bodyseg_io::write_ply(&d.join("moved.ply"), &moved, &opts).expect("write");
    let out = eval(d, "moved.ply", "gt.ply", &[]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("clouds of different frames or recordings?"),
        "{err}"
    );
    let n = moved.len() / 4;
    let mut part = scene.person.cloud.clone();
    for p in part.positions_m.iter_mut().take(n) {
        p[2] += 0.5;
    }
    bodyseg_io::write_ply(&d.join("part.ply"), &part, &opts).expect("write");
    let out = eval(d, "part.ply", "gt.ply", &["-q"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(err.starts_with("warning: part.ply: 2"), "{err}");
}

#[test]
fn a_wrong_depth_scale_and_a_frame_a_camera_lacks_are_warned_about() {
    let (dir, rec) = recording_copy();
    let rig = std::fs::read_to_string(rec.join("rig.toml")).expect("rig.toml");
    assert!(rig.contains("depth_scale = 1000.0"), "{rig}");
    std::fs::write(
        rec.join("rig.toml"),
        rig.replace("depth_scale = 1000.0", "depth_scale = 1.0"),
    )
    .expect("write");
    // Frame 000007 without its depth image for one camera.
    let cam = tree(&rec)
        .into_iter()
        .find(|p| p.ends_with("/depth/000007.png"))
        .expect("a depth image of frame 7");
    std::fs::remove_file(rec.join(&cam)).expect("remove");
    let camera = cam.split('/').next().expect("camera");
    // No ground truth for that camera: evaluation is off, with a warning.
    std::fs::remove_dir_all(rec.join(camera).join("depth_labels")).expect("remove truth");
    let out = bodyseg_line(
        dir.path(),
        "run --recording rec --out out --frame 000001 -q",
    );
    let err = stderr(&out);
    assert!(
        err.lines().any(
            |l| l.starts_with("warning: frame 000001: the median point is")
                && l.contains("check the depth unit")
        ),
        "{err}"
    );
    assert!(
        err.lines().any(
            |l| l.starts_with("warning: rec: 1 frame skipped, a camera lacks them")
                && l.contains(&format!("000007 (no {camera})"))
        ),
        "{err}"
    );
    assert!(
        err.lines().any(|l| l
            == format!(
                "warning: rec: no ground truth (depth_labels/) for camera {camera}: evaluation is off"
            )),
        "{err}"
    );
    let log = std::fs::read_to_string(dir.path().join("out/run.json")).expect("run.json");
    assert!(
        log.contains("\"incomplete_frames\"") && log.contains("000007"),
        "{log}"
    );
    let md = std::fs::read_to_string(dir.path().join("out/report.md")).expect("report.md");
    assert!(
        md.contains(&format!("- `000007`: no depth image of {camera}")),
        "{md}"
    );
    let _ = bodyseg_env;
}
