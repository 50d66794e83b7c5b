use super::*;
use bodyseg_pipeline::{AzureColorResolution, AzureDepthMode, ProjectMode, RigFormat, RigInput};
use clap::CommandFactory;

/// `bodyseg BASE EXTRA` as clap parses it (a test's fixed words, then the case's).
fn try_parse(base: &[&str], extra: &[&str]) -> Result<Cli, clap::Error> {
    Cli::try_parse_from(["bodyseg"].iter().chain(base).chain(extra))
}

/// The command `bodyseg BASE EXTRA` parses into; panics when clap refuses the line.
fn parsed(base: &[&str], extra: &[&str]) -> Command {
    try_parse(base, extra).expect("valid command line").command
}

/// The configuration `bodyseg refine --cloud c.ply --boxes b.json --out o.ply EXTRA`
/// resolves to.
fn refine_config(extra: &[&str]) -> Result<PipelineConfig> {
    let files = [
        "refine", "--cloud", "c.ply", "--boxes", "b.json", "--out", "o.ply",
    ];
    let Command::Refine(r) = parsed(&files, extra) else {
        panic!("parsed as refine");
    };
    r.config()
}

#[test]
fn clap_definition_is_consistent() {
    Cli::command().debug_assert();
}

#[test]
fn project_mode_flag_overrides_the_config() {
    let parse = |extra: &[&str]| {
        let Command::Project(p) = parsed(
            &[
                "project",
                "--recording",
                "rec",
                "--frame",
                "000012",
                "--out",
                "o.ply",
            ],
            extra,
        ) else {
            panic!("parsed as project");
        };
        p.options().expect("valid options")
    };
    assert_eq!(parse(&[]).config.project.mode, ProjectMode::Dsa);
    let o = parse(&["--mode", "naive", "--ascii"]);
    assert_eq!(o.config.project.mode, ProjectMode::Naive);
    assert!(o.ascii);
    assert_eq!(o.frame, "000012");
    assert!(
        try_parse(
            &[
                "project",
                "--recording",
                "r",
                "--frame",
                "f",
                "--mode",
                "x",
                "--out",
                "o"
            ],
            &[]
        )
        .is_err()
    );
}

#[test]
fn boxes_takes_a_cloud_or_a_recording_frame() {
    let parse = |args: &[&str]| try_parse(&["boxes", "--out", "b.json"], args);
    let Ok(Cli {
        command: Command::Boxes(b),
        ..
    }) = parse(&["--cloud", "c.pcd", "--mode", "geometry"])
    else {
        panic!("parsed as boxes");
    };
    let o = b.options().expect("valid");
    assert_eq!(o.config.boxes.mode, bodyseg_pipeline::BoxMode::Geometry);
    assert_eq!(o.input, bodyseg_pipeline::BoxesInput::Cloud("c.pcd".into()));
    assert!(parse(&["--recording", "rec", "--frame", "000001"]).is_ok());
    // An input is required; --recording needs --frame; not both inputs.
    assert!(parse(&[]).is_err());
    assert!(parse(&["--recording", "rec"]).is_err());
    assert!(parse(&["--cloud", "c.ply", "--recording", "rec", "--frame", "1"]).is_err());
}

#[test]
fn named_predictions_split_at_the_first_equals_sign() {
    assert_eq!(
        split_named("M-R-N=out/a.ply"),
        (Some("M-R-N".into()), "out/a.ply".into())
    );
    assert_eq!(split_named("out/a.ply"), (None, "out/a.ply".into()));
    assert_eq!(split_named("./a=b.ply"), (None, "./a=b.ply".into()));
    assert_eq!(split_named("=b.ply"), (None, "=b.ply".into()));
}

#[test]
fn flags_override_the_defaults() {
    let flags = ["--steps", "m,n", "--eps-m", "0.03", "--min-points", "5"];
    let c = refine_config(&flags).expect("valid config");
    assert_eq!(c.refine.eps_m, 0.03);
    assert_eq!(c.refine.min_points, 5);
    assert_eq!(c.refine.steps.to_string(), "M-N");
    assert!(!c.refine.keep_outside_boxes);
}

#[test]
fn config_files_layer_set_beats_them_and_flags_beat_set() {
    let dir = tempfile::tempdir().expect("temp dir");
    let a = dir.path().join("a.toml");
    let b = dir.path().join("b.toml");
    std::fs::write(&a, "[refine]\neps_m = 0.02\nmin_points = 7\n").expect("write");
    std::fs::write(&b, "[refine]\neps_m = 0.04\n").expect("write");
    let (a, b) = (a.display().to_string(), b.display().to_string());
    let c = refine_config(&["--config", &a, "--config", &b]).expect("valid");
    assert_eq!(
        (c.refine.eps_m, c.refine.min_points),
        (0.04, 7),
        "later file wins"
    );
    let c = refine_config(&["--config", &a, "--config", &b, "--set", "refine.eps_m=0.06"])
        .expect("valid");
    assert_eq!(c.refine.eps_m, 0.06, "--set beats the files");
    let c = refine_config(&[
        "--set",
        "refine.eps_m=0.06",
        "--eps-m",
        "0.03",
        "--set",
        "refine.min_points=5",
    ])
    .expect("valid");
    assert_eq!(
        (c.refine.eps_m, c.refine.min_points),
        (0.03, 5),
        "flags beat --set"
    );
    let e = format!(
        "{:#}",
        refine_config(&["--set", "refine.min_pts=5"]).expect_err("unknown")
    );
    assert!(e.contains("unknown key `refine.min_pts`"), "{e}");

    // Every command that reads the configuration takes them.
    let Command::Run(r) = parsed(
        &[
            "run",
            "--recording",
            "r",
            "--out",
            "o",
            "--config",
            &a,
            "--set",
            "project.mode=naive",
            "--mode",
            "dsa",
            "--set",
            "boxes.mode=geometry",
        ],
        &[],
    ) else {
        panic!("parsed as run");
    };
    let o = r.options().expect("valid");
    assert_eq!(
        o.config.project.mode,
        ProjectMode::Dsa,
        "--mode beats --set"
    );
    assert_eq!(o.config.boxes.mode, bodyseg_pipeline::BoxMode::Geometry);
    assert_eq!(o.config.refine.min_points, 7);
    for command in [
        &["parse", "--recording", "r", "--frame", "f", "--out", "o"][..],
        &["project", "--recording", "r", "--frame", "f", "--out", "o"],
        &["boxes", "--cloud", "c.ply", "--out", "o"],
        &[
            "convert",
            "--input",
            "i",
            "--format",
            "recording",
            "--out",
            "o",
        ],
    ] {
        let settings = ["--config", &a, "--set", "parsing.threads=3"];
        assert!(try_parse(command, &settings).is_ok(), "{command:?}");
    }
}

#[test]
fn negative_radius_parses_and_is_rejected_naming_the_flag() {
    // clap takes the negative number as the flag's value.
    let e = format!(
        "{:#}",
        refine_config(&["--eps-m", "-1"]).expect_err("invalid")
    );
    assert_eq!(e, "--eps-m: refine.eps_m must be in (0, 5] metres, got -1");
}

#[test]
fn rig_import_takes_folders_and_names_in_order() {
    let Command::Rig(RigCommand::Import(r)) = parsed(
        &[
            "rig",
            "import",
            "--from",
            "iai_kinect2",
            "a",
            "b",
            "--name",
            "left",
            "--name",
            "right",
            "--out",
            "rig.toml",
        ],
        &[],
    ) else {
        panic!("parsed as rig import");
    };
    let o = r.options().expect("valid options");
    let formats: Vec<RigFormat> = o.inputs.iter().map(|i| i.format).collect();
    assert_eq!(formats, [RigFormat::IaiKinect2; 2]);
    let paths: Vec<&PathBuf> = o.inputs.iter().map(|i| &i.path).collect();
    assert_eq!(paths, [&PathBuf::from("a"), &PathBuf::from("b")]);
    assert_eq!(o.names, ["left", "right"]);
    assert!(!o.world_from_depth_identity);
    // A folder is required, and so is a known format.
    assert!(
        try_parse(
            &["rig", "import", "--from", "iai_kinect2", "--out", "r"],
            &[]
        )
        .is_err()
    );
    assert!(try_parse(&["rig", "import", "--from", "x", "a", "--out", "r"], &[]).is_err());
}

#[test]
fn rig_import_pairs_formats_with_inputs() {
    let parse = |args: &[&str]| {
        let Command::Rig(RigCommand::Import(r)) =
            parsed(&["rig", "import", "--out", "rig.toml"], args)
        else {
            panic!("parsed as rig import");
        };
        r.options()
    };
    let o = parse(&[
        "--from",
        "iai_kinect2",
        "--from",
        "ros",
        "--from",
        "azure_kinect",
        "k/0113",
        "d.yaml,c.yaml",
        "k4a.json",
        "--poses",
        "camera_poses.yaml",
        "--depth-mode",
        "nfov_unbinned",
        "--color-resolution",
        "1080P",
    ])
    .expect("valid");
    assert_eq!(
        o.inputs,
        [
            RigInput {
                format: RigFormat::IaiKinect2,
                path: "k/0113".into(),
                color: None
            },
            RigInput {
                format: RigFormat::Ros,
                path: "d.yaml".into(),
                color: Some("c.yaml".into())
            },
            RigInput {
                format: RigFormat::AzureKinect,
                path: "k4a.json".into(),
                color: None
            },
        ]
    );
    assert_eq!(o.poses, Some(PathBuf::from("camera_poses.yaml")));
    assert_eq!(o.azure_mode.depth, Some(AzureDepthMode::NfovUnbinned));
    assert_eq!(o.azure_mode.color, Some(AzureColorResolution::R1080p));
    // One-sensor formats take a single file too; a comma only splits for them.
    let o = parse(&["--from", "opencv", "rgbd.yaml"]).expect("valid");
    assert_eq!(o.inputs[0].color, None);
    let o = parse(&["--from", "iai_kinect2", "a,b"]).expect("valid");
    assert_eq!(o.inputs[0].path, PathBuf::from("a,b"));
    let e = parse(&["--from", "ros", "--from", "ros", "a", "b", "c"]).expect_err("2 for 3");
    assert!(e.to_string().starts_with("2 --from for 3 INPUTs"), "{e}");
    let e = parse(&["--from", "ros", "a", "--depth-mode", "WFOV_UNBINNED"])
        .expect_err("Azure option without Azure input");
    assert!(e.to_string().contains("azure_kinect only"), "{e}");
    let cli = try_parse(
        &[
            "rig",
            "import",
            "--from",
            "azure_kinect",
            "a.json",
            "--depth-mode",
            "NFOV",
            "--out",
            "r",
        ],
        &[],
    );
    let err = cli.expect_err("unknown mode").to_string();
    assert!(err.contains("NFOV_UNBINNED"), "{err}");
}

#[test]
fn eval_names_predictions() {
    let parse = |args: &[&str]| {
        let Command::Eval(e) = parsed(&["eval", "--gt", "g.ply"], args) else {
            panic!("parsed as eval");
        };
        e.options()
    };
    let o = parse(&["--pred", "p.ply"]).expect("valid");
    assert_eq!(o.predictions[0].name, "prediction");
    let o = parse(&["--pred", "p.ply", "--name", "M-R-N"]).expect("valid");
    assert_eq!(o.predictions[0].name, "M-R-N");
    let o = parse(&["--pred", "R=a.ply", "--pred", "M=b.ply"]).expect("valid");
    assert_eq!(o.predictions[1].name, "M");
    assert!(parse(&["--pred", "a.ply", "--pred", "M=b.ply"]).is_err());
    assert!(try_parse(&["eval", "--merge", "a.json", "--gt", "g"], &[]).is_err());
    assert!(try_parse(&["eval", "--merge", "a.json", "b.json"], &[]).is_ok());
    assert!(try_parse(&["eval", "--pred", "a.ply"], &[]).is_err());
}
