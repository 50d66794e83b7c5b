//! A small reader of CDR, the serialisation ROS 2 messages travel and are stored in
//! (OMG DDS-XTypes "XCDR1", what rmw_fastrtps and rmw_cyclonedds write).
//!
//! A message starts with a 4-byte encapsulation header: `0x00`, the kind (`0x00` CDR big
//! endian, `0x01` CDR little endian; the parameter-list kinds 2 and 3 are not plain
//! messages), and two option bytes. The payload follows. Every primitive is aligned to its
//! own size (1, 2, 4, 8), counted from the start of the payload (after the header).
//! A `string` is a `u32` length that counts the terminating NUL, then the bytes and the NUL;
//! a sequence (`T[]`) is a `u32` element count then the elements; a fixed array (`T[9]`)
//! has no count.

use crate::Ros2Error;

/// Encapsulation header size, bytes.
const HEADER_LEN: usize = 4;

/// Reads the fields of one CDR-encoded message in declaration order.
#[derive(Debug, Clone)]
pub struct CdrReader<'a> {
    /// The payload, after the encapsulation header.
    payload: &'a [u8],
    /// Position in `payload`.
    pos: usize,
    little_endian: bool,
}

impl<'a> CdrReader<'a> {
    /// A reader of `message` (header included).
    ///
    /// # Errors
    /// [`Ros2Error::Cdr`] when the message is shorter than the header or its kind is not
    /// plain CDR (0 or 1).
    pub fn new(message: &'a [u8]) -> Result<CdrReader<'a>, Ros2Error> {
        if message.len() < HEADER_LEN {
            return Err(Ros2Error::Cdr {
                field: "encapsulation header".into(),
                reason: format!("message has {} bytes, fewer than 4", message.len()),
            });
        }
        let little_endian = match message[1] {
            0 => false,
            1 => true,
            kind => {
                return Err(Ros2Error::Cdr {
                    field: "encapsulation header".into(),
                    reason: format!("kind {kind} is not plain CDR (0 big endian, 1 little endian)"),
                });
            }
        };
        Ok(CdrReader {
            payload: &message[HEADER_LEN..],
            pos: 0,
            little_endian,
        })
    }

    /// Whether the payload is little endian.
    pub fn little_endian(&self) -> bool {
        self.little_endian
    }

    /// Bytes of the payload not read yet.
    pub fn remaining(&self) -> usize {
        self.payload.len() - self.pos
    }

    /// `n` bytes after aligning to `align`; `field` names them in the error.
    fn take(&mut self, align: usize, n: usize, field: &str) -> Result<&'a [u8], Ros2Error> {
        let start = self.pos.next_multiple_of(align);
        let end = start.checked_add(n).filter(|&e| e <= self.payload.len());
        let Some(end) = end else {
            return Err(Ros2Error::Cdr {
                field: field.into(),
                reason: format!(
                    "needs {n} bytes at payload offset {start}, the message has {}",
                    self.payload.len()
                ),
            });
        };
        self.pos = end;
        Ok(&self.payload[start..end])
    }

    fn array<const N: usize>(&mut self, field: &str) -> Result<[u8; N], Ros2Error> {
        let bytes = self.take(N, N, field)?;
        let mut out = [0u8; N];
        out.copy_from_slice(bytes);
        Ok(out)
    }

    /// A number of `N` bytes, aligned to `N`, in the payload's byte order.
    fn number<T, const N: usize>(
        &mut self,
        field: &str,
        from_le: fn([u8; N]) -> T,
        from_be: fn([u8; N]) -> T,
    ) -> Result<T, Ros2Error> {
        let b = self.array::<N>(field)?;
        Ok(if self.little_endian {
            from_le(b)
        } else {
            from_be(b)
        })
    }

    /// A `uint8` (also `bool`, `byte`, `char`).
    pub fn u8(&mut self, field: &str) -> Result<u8, Ros2Error> {
        Ok(self.take(1, 1, field)?[0])
    }

    /// A `uint32`.
    pub fn u32(&mut self, field: &str) -> Result<u32, Ros2Error> {
        self.number(field, u32::from_le_bytes, u32::from_be_bytes)
    }

    /// An `int32`.
    pub fn i32(&mut self, field: &str) -> Result<i32, Ros2Error> {
        self.number(field, i32::from_le_bytes, i32::from_be_bytes)
    }

    /// A `float64`.
    pub fn f64(&mut self, field: &str) -> Result<f64, Ros2Error> {
        self.number(field, f64::from_le_bytes, f64::from_be_bytes)
    }

    /// A `float64[N]`.
    pub fn f64_array<const N: usize>(&mut self, field: &str) -> Result<[f64; N], Ros2Error> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.f64(field)?;
        }
        Ok(out)
    }

    /// A sequence length, checked against the bytes left (each element at least
    /// `min_element_bytes`), so a corrupt count cannot ask for gigabytes.
    fn count(&mut self, field: &str, min_element_bytes: usize) -> Result<usize, Ros2Error> {
        let n = self.u32(field)? as usize;
        if n.saturating_mul(min_element_bytes) > self.remaining() {
            return Err(Ros2Error::Cdr {
                field: field.into(),
                reason: format!(
                    "says {n} elements, the message has {} bytes left",
                    self.remaining()
                ),
            });
        }
        Ok(n)
    }

    /// A `float64[]`.
    pub fn f64_sequence(&mut self, field: &str) -> Result<Vec<f64>, Ros2Error> {
        let n = self.count(field, 8)?;
        (0..n).map(|_| self.f64(field)).collect()
    }

    /// A `uint8[]`, borrowed.
    pub fn bytes(&mut self, field: &str) -> Result<&'a [u8], Ros2Error> {
        let n = self.count(field, 1)?;
        self.take(1, n, field)
    }

    /// A sequence's element count (for sequences of structures, read by the caller).
    pub fn sequence_len(
        &mut self,
        field: &str,
        min_element_bytes: usize,
    ) -> Result<usize, Ros2Error> {
        self.count(field, min_element_bytes)
    }

    /// A `string` (UTF-8; the length counts the terminating NUL, which is dropped).
    pub fn string(&mut self, field: &str) -> Result<String, Ros2Error> {
        let n = self.count(field, 1)?;
        let bytes = self.take(1, n, field)?;
        let text = match bytes.split_last() {
            Some((0, text)) => text,
            // Some writers leave the NUL out; an empty string may be length 0.
            _ => bytes,
        };
        String::from_utf8(text.to_vec()).map_err(|_| Ros2Error::Cdr {
            field: field.into(),
            reason: "is not UTF-8".into(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitives_are_aligned_from_the_payload_start() {
        // Little endian: u8 7, pad to 4, u32 5, pad to 8, f64 1.5, string "ab".
        let mut m = vec![0, 1, 0, 0];
        m.extend([7, 0, 0, 0]);
        m.extend(5u32.to_le_bytes());
        m.extend(1.5f64.to_le_bytes());
        m.extend(3u32.to_le_bytes());
        m.extend(b"ab\0");
        let mut r = CdrReader::new(&m).expect("header");
        assert_eq!(r.u8("a").expect("u8"), 7);
        assert_eq!(r.u32("b").expect("u32"), 5);
        assert_eq!(r.f64("c").expect("f64"), 1.5);
        assert_eq!(r.string("d").expect("string"), "ab");
        assert_eq!(r.remaining(), 0);
    }

    #[test]
    fn big_endian_reads_too() {
        let mut m = vec![0, 0, 0, 0];
        m.extend((-3i32).to_be_bytes());
        m.extend([0, 0, 0, 0]); // pad to 8
        m.extend(2.25f64.to_be_bytes());
        let mut r = CdrReader::new(&m).expect("header");
        assert!(!r.little_endian());
        assert_eq!(r.i32("a").expect("i32"), -3);
        assert_eq!(r.f64("b").expect("f64"), 2.25);
    }

    #[test]
    fn short_or_corrupt_messages_are_errors_naming_the_field() {
        assert!(CdrReader::new(&[0, 1]).is_err());
        let e = CdrReader::new(&[0, 2, 0, 0]).expect_err("kind 2");
        assert!(e.to_string().contains("kind 2"), "{e}");
        let mut m = vec![0, 1, 0, 0];
        m.extend(1_000_000u32.to_le_bytes());
        let mut r = CdrReader::new(&m).expect("header");
        let e = r.bytes("data").expect_err("count too large");
        assert!(
            e.to_string().contains("data") && e.to_string().contains("1000000"),
            "{e}"
        );
        let mut r = CdrReader::new(&[0, 1, 0, 0, 1]).expect("header");
        let e = r.u32("height").expect_err("short");
        assert!(e.to_string().contains("height"), "{e}");
    }
}
