//! `--help` of every command exits 0 and names the key flags.

use crate::common::{assert_help as help, words};

#[test]
fn main_help() {
    help(&["--help"], &["refine", "eval", "Examples:", "RUST_LOG"]);
}

#[test]
fn refine_help() {
    help(
        &["refine", "--help"],
        &words(
            "--cloud --boxes --out --config --steps --eps-m --min-points --keep-outside-boxes --ascii metres Examples: configs/default.toml",
        ),
    );
}

#[test]
fn eval_help() {
    help(
        &["eval", "--help"],
        &words("--pred --gt --format --merge --out --name Examples:"),
    );
}

#[test]
fn parse_help() {
    help(
        &["parse", "--help"],
        &words(
            "--recording --frame --model --recorded --threads --out ORT_DYLIB_PATH scripts/setup_onnxruntime.sh bodyseg_parser_small.onnx Examples:",
        ),
    );
}

#[test]
fn calibrate_help() {
    // Present with or without the opencv feature: the commands explain how to build it.
    help(
        &["calibrate", "--help"],
        &["intrinsics", "stereo", "world", "OpenCV", "setup_opencv.sh"],
    );
    help(
        &["calibrate", "intrinsics", "--help"],
        &words("--images --board --square-m --out .yaml Examples:"),
    );
    help(
        &["calibrate", "stereo", "--help"],
        &words("--ir --color --ir-intrinsics --fix-intrinsics --name"),
    );
    help(
        &["calibrate", "world", "--help"],
        &["--rig", "--floor", "points up", "ir.png", "color.png"],
    );
}
