//! End-to-end tests: run the real `bodyseg` binary on files in a temporary folder.
//!
//! One test binary (`e2e`) whose modules are the other files of `tests/`.

mod common;

mod cli_bad_input;
mod cli_boxes;
mod cli_calibrate;
mod cli_cloud;
mod cli_convert;
mod cli_eval;
mod cli_harden;
mod cli_help;
mod cli_import_ros2;
mod cli_parse;
mod cli_project;
mod cli_refine;
mod cli_rerun;
mod cli_rig;
mod cli_run;
mod cli_synth;
mod results_regression;
