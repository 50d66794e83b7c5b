//! A rosbag2 bag as a stream of messages: the MCAP files read one after the other with
//! `mcap`'s streaming reader (it pulls bytes from a [`Read`] as it goes: memory holds one
//! chunk, whatever the bag's length), and the `metadata.yaml` that lists them.
//!
//! No file is opened here: the caller hands over the readers (bodyseg-pipeline opens the
//! files), so `mcap`'s types stay inside this module.

use crate::Ros2Error;
use crate::msg::MsgKind;
use std::io::Read;
use std::sync::Arc;
use yaml_rust2::{Yaml, YamlLoader};

/// rosbag2's name of the MCAP storage plugin.
pub const STORAGE_MCAP: &str = "mcap";
/// rosbag2's name of the SQLite storage plugin (`.db3` files).
pub const STORAGE_SQLITE: &str = "sqlite3";

/// The message encoding of ROS 2 messages in MCAP.
const ENCODING_CDR: &str = "cdr";

/// What a rosbag2 `metadata.yaml` says about the bag's files.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BagMetadata {
    /// `storage_identifier`: `mcap` or `sqlite3`.
    pub storage: String,
    /// `relative_file_paths`, in recording order.
    pub files: Vec<String>,
}

/// The error for a SQLite (`.db3`) bag, naming the conversion.
pub fn sqlite_error(what: &str) -> Ros2Error {
    Ros2Error::Metadata {
        field: "storage_identifier".into(),
        reason: format!(
            "{what} is a SQLite (.db3) bag, which bodyseg does not read: convert it to MCAP \
             first with `ros2 bag convert -i BAG -o out.yaml` (out.yaml: \
             `output_bags: [{{uri: BAG_mcap, storage_id: mcap}}]`)"
        ),
    }
}

/// Parses a rosbag2 `metadata.yaml`.
///
/// # Errors
/// [`Ros2Error::Metadata`] naming the key: not YAML, no
/// `rosbag2_bagfile_information`, a SQLite bag (naming `ros2 bag convert`), another
/// storage, no files.
pub fn parse_metadata(text: &str) -> Result<BagMetadata, Ros2Error> {
    let bad = |field: &str, reason: String| Ros2Error::Metadata {
        field: field.into(),
        reason,
    };
    let docs = YamlLoader::load_from_str(text.trim_start_matches('\u{feff}'))
        .map_err(|e| bad("", format!("not YAML: {e}")))?;
    let info = docs
        .first()
        .map(|d| &d["rosbag2_bagfile_information"])
        .filter(|v| !v.is_badvalue())
        .ok_or_else(|| bad("rosbag2_bagfile_information", "missing".into()))?;
    const PREFIX: &str = "rosbag2_bagfile_information.";
    let storage = info["storage_identifier"]
        .as_str()
        .ok_or_else(|| bad(&format!("{PREFIX}storage_identifier"), "missing".into()))?
        .to_string();
    if storage == STORAGE_SQLITE {
        return Err(sqlite_error("the bag"));
    }
    if storage != STORAGE_MCAP {
        return Err(bad(
            &format!("{PREFIX}storage_identifier"),
            format!("{storage:?} is not supported (mcap)"),
        ));
    }
    let files: Vec<String> = match &info["relative_file_paths"] {
        Yaml::Array(items) => items
            .iter()
            .map(|i| {
                i.as_str().map(str::to_string).ok_or_else(|| {
                    bad(
                        &format!("{PREFIX}relative_file_paths"),
                        "must be a list of file names".into(),
                    )
                })
            })
            .collect::<Result<_, _>>()?,
        _ => {
            return Err(bad(
                &format!("{PREFIX}relative_file_paths"),
                "missing or not a list".into(),
            ));
        }
    };
    if files.is_empty() {
        return Err(bad(
            &format!("{PREFIX}relative_file_paths"),
            "lists no file".into(),
        ));
    }
    Ok(BagMetadata { storage, files })
}

/// One message of a bag, its data owned.
#[derive(Clone, Debug)]
pub struct BagMessage {
    /// Position in the bag (0, 1, ...), counted over all its files in order: the same
    /// message has the same ordinal on every pass.
    pub ordinal: u64,
    /// The topic.
    pub topic: Arc<str>,
    /// The message type, when bodyseg reads it.
    pub kind: Option<MsgKind>,
    /// When the message was recorded, nanoseconds.
    pub log_time_ns: u64,
    /// The CDR-encoded message.
    pub data: Vec<u8>,
}

/// The messages of a bag's MCAP files, in file order, streamed.
pub struct BagReader<R: Read> {
    files: std::vec::IntoIter<(String, R)>,
    current: Option<(String, mcap::io::MessageReader<R>)>,
    ordinal: u64,
    /// The last message read (topic, log time), for error messages.
    last: Option<(Arc<str>, u64)>,
    failed: bool,
}

impl<R: Read> std::fmt::Debug for BagReader<R> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BagReader")
            .field("ordinal", &self.ordinal)
            .finish_non_exhaustive()
    }
}

impl<R: Read> BagReader<R> {
    /// A reader of the MCAP files `files` (a name for error messages, and a reader of the
    /// file's bytes; buffer it), in order.
    pub fn new(files: Vec<(String, R)>) -> BagReader<R> {
        BagReader {
            files: files.into_iter(),
            current: None,
            ordinal: 0,
            last: None,
            failed: false,
        }
    }

    fn error(&self, file: &str, what: &str) -> Ros2Error {
        let after = match &self.last {
            Some((topic, t)) => format!(
                " after {} messages (the last on {topic} at log time {})",
                self.ordinal,
                crate::Stamp::from_ns(*t as i64)
            ),
            None => " before its first message".into(),
        };
        Ros2Error::Bag {
            reason: format!("{file}: {what}{after}"),
        }
    }
}

impl<R: Read> Iterator for BagReader<R> {
    type Item = Result<BagMessage, Ros2Error>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        loop {
            if self.current.is_none() {
                let (name, reader) = self.files.next()?;
                self.current = Some((name, mcap::io::MessageReader::new(reader)));
            }
            let (name, reader) = self.current.as_mut()?;
            match reader.next() {
                None => self.current = None,
                Some(Err(e)) => {
                    let name = name.clone();
                    self.failed = true;
                    let what = match e {
                        mcap::McapError::UnexpectedEof | mcap::McapError::BadMagic => {
                            format!("truncated or not an MCAP file ({e})")
                        }
                        other => format!("corrupt MCAP file ({other})"),
                    };
                    return Some(Err(self.error(&name, &what)));
                }
                Some(Ok(message)) => {
                    let channel = &message.channel;
                    let topic: Arc<str> = Arc::from(channel.topic.as_str());
                    let kind = channel
                        .schema
                        .as_ref()
                        .and_then(|s| MsgKind::of_schema(&s.name));
                    if kind.is_some() && channel.message_encoding != ENCODING_CDR {
                        let name = name.clone();
                        self.failed = true;
                        return Some(Err(self.error(
                            &name,
                            &format!(
                                "topic {topic}: message encoding {:?} is not supported (cdr)",
                                channel.message_encoding
                            ),
                        )));
                    }
                    let out = BagMessage {
                        ordinal: self.ordinal,
                        topic: topic.clone(),
                        kind,
                        log_time_ns: message.log_time,
                        data: message.data.into_owned(),
                    };
                    self.ordinal += 1;
                    self.last = Some((topic, out.log_time_ns));
                    return Some(Ok(out));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metadata_lists_mcap_files_and_refuses_sqlite() {
        let text = "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  \
                    relative_file_paths:\n    - rec_0.mcap\n    - rec_1.mcap\n";
        let m = parse_metadata(text).expect("metadata");
        assert_eq!(m.files, ["rec_0.mcap", "rec_1.mcap"]);
        let db3 = text.replace("storage_identifier: mcap", "storage_identifier: sqlite3");
        let e = parse_metadata(&db3).expect_err("sqlite");
        assert!(e.to_string().contains("ros2 bag convert"), "{e}");
        let e = parse_metadata("a: 1").expect_err("not a bag");
        assert!(e.to_string().contains("rosbag2_bagfile_information"), "{e}");
    }

    #[test]
    fn a_stream_that_is_not_mcap_is_one_error() {
        let mut r = BagReader::new(vec![("x.mcap".to_string(), &b"not an mcap file"[..])]);
        let e = r.next().expect("one item").expect_err("not mcap");
        assert!(
            e.to_string()
                .starts_with("x.mcap: truncated or not an MCAP file"),
            "{e}"
        );
        assert!(r.next().is_none());
    }
}
