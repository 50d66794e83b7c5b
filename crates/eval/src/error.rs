//! The crate's error type.

use std::fmt;

/// Which of the two clouds given to [`match_clouds`](crate::match_clouds) an error is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CloudRole {
    /// The cloud being scored.
    Prediction,
    /// The reference labels.
    GroundTruth,
}

impl fmt::Display for CloudRole {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            CloudRole::Prediction => "predicted",
            CloudRole::GroundTruth => "ground-truth",
        })
    }
}

/// Everything that can go wrong while evaluating or reading and merging reports.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// A cloud's label and origin arrays differ in length, so points cannot be paired up.
    #[error("{cloud} cloud has {labels} labels but {origins} origins")]
    LengthMismatch {
        /// The cloud at fault.
        cloud: CloudRole,
        /// Length of its `labels`.
        labels: usize,
        /// Length of its `origins`.
        origins: usize,
    },
    /// Two labellings of the same points differ in length.
    #[error("prediction has {pred} labels, ground truth {gt}: they must label the same points")]
    AlignedLengths {
        /// Labels in the prediction.
        pred: usize,
        /// Labels in the ground truth.
        gt: usize,
    },
    /// Two points of one cloud come from the same camera pixel, so matching is ambiguous.
    #[error(
        "{cloud} cloud: origin (camera {camera}, pixel {pixel}) appears twice, at points {first} and {second}"
    )]
    DuplicateOrigin {
        /// The cloud at fault.
        cloud: CloudRole,
        /// Camera index of the repeated origin.
        camera: u8,
        /// Pixel index of the repeated origin.
        pixel: u32,
        /// Index of the first point with that origin.
        first: usize,
        /// Index of the second point with that origin.
        second: usize,
    },
    /// A report already has a configuration of that name.
    #[error("report already has a configuration named {name:?}")]
    DuplicateConfiguration {
        /// The repeated name.
        name: String,
    },
    /// [`Report::merge`](crate::Report::merge) was given no report.
    #[error("no reports to merge")]
    NoReports,
    /// Reports to merge do not hold the same set of configurations.
    #[error(
        "cannot merge reports: report {index} has configurations {got:?}, report 0 has {want:?}"
    )]
    ConfigurationMismatch {
        /// Position of the first report that differs from the first one.
        index: usize,
        /// The first report's configuration names, in its order.
        want: Vec<String>,
        /// The differing report's configuration names, in its order.
        got: Vec<String>,
    },
    /// Summing the counts of a configuration across reports exceeds `u64::MAX`.
    #[error("configuration {name:?}: point counts overflow u64 when merged")]
    CountOverflow {
        /// The configuration whose counts overflow.
        name: String,
    },
    /// A report file was written by an incompatible version of this crate.
    #[error("report has format version {got}, this build reads version {want}")]
    UnsupportedVersion {
        /// Version in the file.
        got: u32,
        /// [`REPORT_VERSION`](crate::REPORT_VERSION).
        want: u32,
    },
    /// A report file lists its classes in another order than this build's matrices use.
    #[error("report lists classes {got:?}, expected {want:?}")]
    ClassOrder {
        /// Class names in the file.
        got: Vec<String>,
        /// Class names in matrix order.
        want: Vec<String>,
    },
    /// A report file's evaluated-point count disagrees with its confusion matrix.
    #[error(
        "configuration {name:?}: points.evaluated is {evaluated} but the confusion matrix sums to {matrix_total}"
    )]
    InconsistentCounts {
        /// The configuration at fault.
        name: String,
        /// `points.evaluated` in the file.
        evaluated: u64,
        /// Sum of the file's confusion matrix.
        matrix_total: u64,
    },
    /// A report is not valid JSON or does not have the report's shape.
    #[error("report JSON")]
    Json {
        /// The parser's or serializer's error.
        #[source]
        source: serde_json::Error,
    },
}
