//! The ROS 2 messages bodyseg reads, decoded from CDR ([`CdrReader`]) in the field order
//! of their `.msg` definitions (ROS 2 Humble and later; unchanged since Foxy):
//!
//! ```text
//! builtin_interfaces/Time      int32 sec, uint32 nanosec
//! std_msgs/Header              Time stamp, string frame_id
//! sensor_msgs/Image            Header header, uint32 height, uint32 width, string encoding,
//!                              uint8 is_bigendian, uint32 step, uint8[] data
//! sensor_msgs/CompressedImage  Header header, string format, uint8[] data
//! sensor_msgs/CameraInfo       Header header, uint32 height, uint32 width,
//!                              string distortion_model, float64[] d, float64[9] k,
//!                              float64[9] r, float64[12] p, uint32 binning_x,
//!                              uint32 binning_y, RegionOfInterest roi
//! sensor_msgs/RegionOfInterest uint32 x_offset, y_offset, height, width, bool do_rectify
//! tf2_msgs/TFMessage           geometry_msgs/TransformStamped[] transforms
//! geometry_msgs/TransformStamped Header header, string child_frame_id,
//!                              Transform transform (Vector3 translation, Quaternion rotation)
//! ```

use crate::Ros2Error;
use crate::cdr::CdrReader;
use std::fmt;

/// A ROS time (`builtin_interfaces/Time`): seconds and nanoseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Stamp {
    /// Seconds (since the Unix epoch for wall-clock stamps).
    pub sec: i32,
    /// Nanoseconds, `0..1e9`.
    pub nanosec: u32,
}

impl Stamp {
    /// The stamp in nanoseconds.
    pub fn ns(self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }

    /// The stamp of `ns` nanoseconds (the inverse of [`Stamp::ns`] for stamps in range).
    pub fn from_ns(ns: i64) -> Stamp {
        Stamp {
            sec: ns.div_euclid(1_000_000_000) as i32,
            nanosec: ns.rem_euclid(1_000_000_000) as u32,
        }
    }
}

impl fmt::Display for Stamp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{:09}", self.sec, self.nanosec)
    }
}

/// `std_msgs/Header`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Header {
    /// When the data was measured.
    pub stamp: Stamp,
    /// The frame the data is in (an optical frame for images).
    pub frame_id: String,
}

fn header(r: &mut CdrReader<'_>) -> Result<Header, Ros2Error> {
    let sec = r.i32("header.stamp.sec")?;
    let nanosec = r.u32("header.stamp.nanosec")?;
    let frame_id = r.string("header.frame_id")?;
    Ok(Header {
        stamp: Stamp { sec, nanosec },
        frame_id,
    })
}

/// `sensor_msgs/Image`, its pixels borrowed from the message.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageMsg<'a> {
    /// Stamp and optical frame.
    pub header: Header,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// Pixel encoding (`16UC1`, `rgb8`, ...).
    pub encoding: String,
    /// Whether multi-byte samples are big endian.
    pub is_bigendian: bool,
    /// Bytes per row.
    pub step: u32,
    /// The pixels, `step * height` bytes.
    pub data: &'a [u8],
}

/// Decodes a `sensor_msgs/Image`.
///
/// # Errors
/// [`Ros2Error::Cdr`] naming the field that does not fit.
pub fn decode_image(message: &[u8]) -> Result<ImageMsg<'_>, Ros2Error> {
    let mut r = CdrReader::new(message)?;
    Ok(ImageMsg {
        header: header(&mut r)?,
        height: r.u32("height")?,
        width: r.u32("width")?,
        encoding: r.string("encoding")?,
        is_bigendian: r.u8("is_bigendian")? != 0,
        step: r.u32("step")?,
        data: r.bytes("data")?,
    })
}

/// The header of any message that starts with one (every message bodyseg reads but
/// `TFMessage`), without decoding the rest.
///
/// # Errors
/// [`Ros2Error::Cdr`] when the header does not fit.
pub fn decode_header(message: &[u8]) -> Result<Header, Ros2Error> {
    header(&mut CdrReader::new(message)?)
}

/// `sensor_msgs/CompressedImage`, its bytes borrowed from the message.
#[derive(Clone, Debug, PartialEq)]
pub struct CompressedImageMsg<'a> {
    /// Stamp and optical frame.
    pub header: Header,
    /// `jpeg`, `png`, `rgb8; jpeg compressed bgr8`, `16UC1; compressedDepth png`, ...
    pub format: String,
    /// The compressed image (for `compressedDepth`, a 12-byte header first).
    pub data: &'a [u8],
}

/// Decodes a `sensor_msgs/CompressedImage`.
///
/// # Errors
/// [`Ros2Error::Cdr`] naming the field that does not fit.
pub fn decode_compressed_image(message: &[u8]) -> Result<CompressedImageMsg<'_>, Ros2Error> {
    let mut r = CdrReader::new(message)?;
    Ok(CompressedImageMsg {
        header: header(&mut r)?,
        format: r.string("format")?,
        data: r.bytes("data")?,
    })
}

/// `sensor_msgs/RegionOfInterest`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Roi {
    /// Left column of the region.
    pub x_offset: u32,
    /// Top row.
    pub y_offset: u32,
    /// Rows (0 = the whole image).
    pub height: u32,
    /// Columns (0 = the whole image).
    pub width: u32,
    /// Whether the region is to be rectified.
    pub do_rectify: bool,
}

/// `sensor_msgs/CameraInfo`.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraInfoMsg {
    /// Stamp and optical frame.
    pub header: Header,
    /// Image rows the calibration is for.
    pub height: u32,
    /// Image columns.
    pub width: u32,
    /// `plumb_bob`, `rational_polynomial`, `equidistant`, ...
    pub distortion_model: String,
    /// Distortion coefficients, OpenCV order.
    pub d: Vec<f64>,
    /// Intrinsic matrix of the raw (distorted) images, row-major 3x3.
    pub k: [f64; 9],
    /// Rectification rotation, row-major 3x3.
    pub r: [f64; 9],
    /// Projection matrix of the rectified images, row-major 3x4.
    pub p: [f64; 12],
    /// Horizontal binning (0 or 1 = none).
    pub binning_x: u32,
    /// Vertical binning.
    pub binning_y: u32,
    /// Region of interest.
    pub roi: Roi,
}

/// Decodes a `sensor_msgs/CameraInfo`.
///
/// # Errors
/// [`Ros2Error::Cdr`] naming the field that does not fit.
pub fn decode_camera_info(message: &[u8]) -> Result<CameraInfoMsg, Ros2Error> {
    let mut r = CdrReader::new(message)?;
    Ok(CameraInfoMsg {
        header: header(&mut r)?,
        height: r.u32("height")?,
        width: r.u32("width")?,
        distortion_model: r.string("distortion_model")?,
        d: r.f64_sequence("d")?,
        k: r.f64_array::<9>("k")?,
        r: r.f64_array::<9>("r")?,
        p: r.f64_array::<12>("p")?,
        binning_x: r.u32("binning_x")?,
        binning_y: r.u32("binning_y")?,
        roi: Roi {
            x_offset: r.u32("roi.x_offset")?,
            y_offset: r.u32("roi.y_offset")?,
            height: r.u32("roi.height")?,
            width: r.u32("roi.width")?,
            do_rectify: r.u8("roi.do_rectify")? != 0,
        },
    })
}

/// One `geometry_msgs/TransformStamped`: `parent_from_child`, i.e. the child frame's pose
/// in the parent frame (`header.frame_id`): `p_parent = R · p_child + t`.
#[derive(Clone, Debug, PartialEq)]
pub struct TransformMsg {
    /// Stamp and the parent frame.
    pub header: Header,
    /// The child frame.
    pub child_frame_id: String,
    /// Translation, metres.
    pub translation_m: [f64; 3],
    /// Rotation as a quaternion `[x, y, z, w]` (ROS order).
    pub rotation_xyzw: [f64; 4],
}

/// Decodes a `tf2_msgs/TFMessage`.
///
/// # Errors
/// [`Ros2Error::Cdr`] naming the field (with the transform's index) that does not fit.
pub fn decode_tf_message(message: &[u8]) -> Result<Vec<TransformMsg>, Ros2Error> {
    let mut r = CdrReader::new(message)?;
    // A transform takes at least 8 (stamp) + 4 + 4 (two empty strings) + 56 bytes.
    let n = r.sequence_len("transforms", 72)?;
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let field = |name: &str| format!("transforms[{i}].{name}");
        let header = header(&mut r).map_err(|e| match e {
            Ros2Error::Cdr { field: f, reason } => Ros2Error::Cdr {
                field: field(&f),
                reason,
            },
            other => other,
        })?;
        let child_frame_id = r.string(&field("child_frame_id"))?;
        let translation_m = r.f64_array::<3>(&field("transform.translation"))?;
        let rotation_xyzw = r.f64_array::<4>(&field("transform.rotation"))?;
        out.push(TransformMsg {
            header,
            child_frame_id,
            translation_m,
            rotation_xyzw,
        });
    }
    Ok(out)
}

/// The message types bodyseg reads, by schema name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MsgKind {
    /// `sensor_msgs/msg/Image`.
    Image,
    /// `sensor_msgs/msg/CompressedImage`.
    CompressedImage,
    /// `sensor_msgs/msg/CameraInfo`.
    CameraInfo,
    /// `tf2_msgs/msg/TFMessage`.
    Tf,
}

impl MsgKind {
    /// The kind of a schema name: rosbag2 writes `pkg/msg/Type`; `pkg/Type` is accepted
    /// too. `None` for other types (they are skipped).
    pub fn of_schema(name: &str) -> Option<MsgKind> {
        let name = name.replace("/msg/", "/");
        Some(match name.as_str() {
            "sensor_msgs/Image" => MsgKind::Image,
            "sensor_msgs/CompressedImage" => MsgKind::CompressedImage,
            "sensor_msgs/CameraInfo" => MsgKind::CameraInfo,
            "tf2_msgs/TFMessage" => MsgKind::Tf,
            _ => return None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_print_and_convert() {
        let s = Stamp {
            sec: 12,
            nanosec: 3_400,
        };
        assert_eq!(s.to_string(), "12.000003400");
        assert_eq!(Stamp::from_ns(s.ns()), s);
        assert_eq!(Stamp::from_ns(-1).to_string(), "-1.999999999");
    }

    #[test]
    fn schema_names_with_and_without_msg() {
        assert_eq!(
            MsgKind::of_schema("sensor_msgs/msg/Image"),
            Some(MsgKind::Image)
        );
        assert_eq!(MsgKind::of_schema("tf2_msgs/TFMessage"), Some(MsgKind::Tf));
        assert_eq!(MsgKind::of_schema("std_msgs/msg/String"), None);
    }

    // Messages serialised by the ROS 2 Python writer (mcap-ros2-support 0.6, the .msg
    // definitions of scripts/write_ros2_bag.py); regenerate with its `Writer` and
    // `mcap.reader.make_reader(...).iter_messages()`, printing `message.data.hex()`.
    /// `sensor_msgs/msg/Image` as mcap-ros2-support 0.6's writer serialises it.
    const IMAGE: &[&str] = &[
        "0001000000f1536555a0fc011600000063616d305f69725f6f70746963616c5f6672616d6500000002000000",
        "03000000060000003136554331000000060000000c00000001000200030004000500e803",
    ];

    /// `sensor_msgs/msg/CompressedImage` as mcap-ros2-support 0.6's writer serialises it.
    const COMPRESSED: &[&str] = &[
        "00010000050000000700000002000000660000001b000000626772383b206a70656720636f6d707265737365",
        "642062677238000003000000ffd8ff",
    ];

    /// `sensor_msgs/msg/CameraInfo` as mcap-ros2-support 0.6's writer serialises it.
    const CAMERA_INFO: &[&str] = &[
        "0001000001000000020000001700000063616d305f7267625f6f70746963616c5f6672616d6500001c020000",
        "c003000014000000726174696f6e616c5f706f6c796e6f6d69616c00080000009a9999999999b93f9a999999",
        "9999c9bffca9f1d24d62503ffca9f1d24d62603fb81e85eb51b89e3f9a9999999999d93f000000000000e03f",
        "333333333333e33f000000000068804000000000000000000000000000087e40000000000000000000000000",
        "007080400000000000e4704000000000000000000000000000000000000000000000f03f000000000000f03f",
        "000000000000000000000000000000000000000000000000000000000000f03f000000000000000000000000",
        "000000000000000000000000000000000000f03f000000000040804000000000000000000000000000107e40",
        "0000000000000000000000000000000000000000004880400000000000f07040000000000000000000000000",
        "000000000000000000000000000000000000f03f000000000000000000000000000000000000000000000000",
        "000000000000000000",
    ];

    /// `tf2_msgs/msg/TFMessage` as mcap-ros2-support 0.6's writer serialises it.
    const TF_MESSAGE: &[&str] = &[
        "0001000002000000030000000400000006000000776f726c640000000a00000063616d305f6c696e6b000000",
        "000000000000f83f00000000000000c0000000000000d03f0000000000000000000000000000000033333333",
        "3333e33f9a9999999999e93f03000000040000000a00000063616d305f6c696e6b0000001700000063616d30",
        "5f7267625f6f70746963616c5f6672616d650000000000000000000000000000000000000000000000000000",
        "00000000000000000000000000000000000000000000000000000000000000000000f03f",
    ];

    fn bytes_of(hex: &[&str]) -> Vec<u8> {
        let hex: String = hex.concat();
        (0..hex.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).expect("hex"))
            .collect()
    }

    #[test]
    fn messages_written_by_the_python_writer_decode() {
        let image_bytes = bytes_of(IMAGE);
        let image = decode_image(&image_bytes).expect("Image");
        assert_eq!(
            image.header.stamp,
            Stamp {
                sec: 1_700_000_000,
                nanosec: 33_333_333
            }
        );
        assert_eq!(image.header.frame_id, "cam0_ir_optical_frame");
        assert_eq!((image.width, image.height, image.step), (3, 2, 6));
        assert_eq!(image.encoding, "16UC1");
        assert!(!image.is_bigendian);
        assert_eq!(image.data, [1, 0, 2, 0, 3, 0, 4, 0, 5, 0, 0xe8, 0x03]);
        assert_eq!(decode_header(&image_bytes).expect("header"), image.header);

        let compressed_bytes = bytes_of(COMPRESSED);
        let compressed = decode_compressed_image(&compressed_bytes).expect("CompressedImage");
        assert_eq!(compressed.header.stamp, Stamp { sec: 5, nanosec: 7 });
        assert_eq!(compressed.header.frame_id, "f");
        assert_eq!(compressed.format, "bgr8; jpeg compressed bgr8");
        assert_eq!(compressed.data, [0xff, 0xd8, 0xff]);

        let info = decode_camera_info(&bytes_of(CAMERA_INFO)).expect("CameraInfo");
        assert_eq!(info.header.frame_id, "cam0_rgb_optical_frame");
        assert_eq!((info.width, info.height), (960, 540));
        assert_eq!(info.distortion_model, "rational_polynomial");
        assert_eq!(info.d, [0.1, -0.2, 0.001, 0.002, 0.03, 0.4, 0.5, 0.6]);
        assert_eq!(
            info.k,
            [525.0, 0.0, 480.5, 0.0, 526.0, 270.25, 0.0, 0.0, 1.0]
        );
        assert_eq!(info.p[..3], [520.0, 0.0, 481.0]);
        assert_eq!(info.p[5..7], [521.0, 271.0]);
        assert_eq!((info.binning_x, info.binning_y), (0, 0));
        assert!(!info.roi.do_rectify);

        let tf = decode_tf_message(&bytes_of(TF_MESSAGE)).expect("TFMessage");
        assert_eq!(tf.len(), 2);
        assert_eq!(tf[0].header.frame_id, "world");
        assert_eq!(tf[0].header.stamp, Stamp { sec: 3, nanosec: 4 });
        assert_eq!(tf[0].child_frame_id, "cam0_link");
        assert_eq!(tf[0].translation_m, [1.5, -2.0, 0.25]);
        assert_eq!(tf[0].rotation_xyzw, [0.0, 0.0, 0.6, 0.8]);
        assert_eq!(tf[1].child_frame_id, "cam0_rgb_optical_frame");
        assert_eq!(tf[1].rotation_xyzw, [0.0, 0.0, 0.0, 1.0]);

        // Cut anywhere, each message is an error naming a field, never a panic.
        for cut in 0..image_bytes.len() {
            assert!(
                decode_image(&image_bytes[..cut]).is_err(),
                "Image cut at {cut}"
            );
        }
        let tf_bytes = bytes_of(TF_MESSAGE);
        for cut in 0..tf_bytes.len() {
            let e = decode_tf_message(&tf_bytes[..cut]).expect_err("TFMessage cut");
            assert!(
                cut < 4 || e.to_string().contains("field transforms"),
                "cut at {cut}: {e}"
            );
        }
    }
}
