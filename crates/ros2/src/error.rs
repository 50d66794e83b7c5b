//! The crate's error type.

/// Everything that can go wrong while reading a ROS 2 bag into a rig and frames. Messages
/// name the topic, the field and the stamp; the caller adds the bag's path.
#[derive(Debug, thiserror::Error)]
pub enum Ros2Error {
    /// A CDR-encoded message is shorter than its fields say, or malformed.
    #[error("field {field}: {reason}")]
    Cdr {
        /// The field being read (`sensor_msgs/Image.data`).
        field: String,
        /// What is wrong.
        reason: String,
    },
    /// A field holds a value bodyseg does not read (an image encoding, a distortion model).
    #[error("field {field}: {value:?} is not supported ({supported})")]
    Unsupported {
        /// The field (`encoding`, `format`, `distortion_model`).
        field: String,
        /// Its value.
        value: String,
        /// What is supported.
        supported: String,
    },
    /// A message's content is inconsistent (an image whose size disagrees with its data,
    /// a compressed image that does not decode).
    #[error("{reason}")]
    Invalid {
        /// What is wrong, naming the field.
        reason: String,
    },
    /// An error in one message of the bag: its topic and stamp, then the error.
    #[error("{topic} at stamp {stamp}: {source}")]
    AtMessage {
        /// The message's topic.
        topic: String,
        /// Its `header.stamp` (`sec.nanosec`), or its log time when the header could not
        /// be read.
        stamp: String,
        /// The error.
        #[source]
        source: Box<Ros2Error>,
    },
    /// The MCAP container cannot be read (truncated, corrupt, unsupported compression).
    #[error("{reason}")]
    Bag {
        /// What is wrong and where in the bag (after which message).
        reason: String,
    },
    /// A rosbag2 `metadata.yaml` cannot be used.
    #[error("metadata.yaml: {field}: {reason}")]
    Metadata {
        /// The key (`rosbag2_bagfile_information.storage_identifier`).
        field: String,
        /// What is wrong.
        reason: String,
    },
    /// The cameras cannot be found or assembled (no image topics, a camera without
    /// CameraInfo or depth, a `--camera` prefix that matches nothing).
    #[error("{reason}")]
    Camera {
        /// What is missing, naming the camera, the topic and the stamp.
        reason: String,
    },
    /// A transform the rig needs is not in `/tf_static` or `/tf`.
    #[error("{reason}")]
    Transform {
        /// The frames, the topics they come from and the stamp.
        reason: String,
    },
}

impl Ros2Error {
    /// `self` as an error in the message of `topic` at `stamp`.
    pub fn at(self, topic: &str, stamp: impl ToString) -> Ros2Error {
        Ros2Error::AtMessage {
            topic: topic.to_string(),
            stamp: stamp.to_string(),
            source: Box::new(self),
        }
    }

    pub(crate) fn invalid(reason: impl Into<String>) -> Ros2Error {
        Ros2Error::Invalid {
            reason: reason.into(),
        }
    }
}
