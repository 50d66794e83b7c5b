//! Per-stage timing and one-line summaries, which the binary prints to stderr.

use std::fmt;
use std::time::{Duration, Instant};

/// One stage of a command: its name, how long it took and what it did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Stage {
    /// Short name (`read`, `refine`, `write`, ...).
    pub name: &'static str,
    /// Wall-clock time.
    pub elapsed: Duration,
    /// What it did, one line (`100000 points`, `out.ply`).
    pub detail: String,
}

impl Stage {
    /// A stage record.
    pub fn new(name: &'static str, elapsed: Duration, detail: String) -> Stage {
        Stage {
            name,
            elapsed,
            detail,
        }
    }
}

impl fmt::Display for Stage {
    /// `read     12 ms  100000 points`: milliseconds, one decimal below 10 ms.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ms = self.elapsed.as_secs_f64() * 1e3;
        let ms = if ms < 10.0 {
            format!("{ms:.1}")
        } else {
            format!("{ms:.0}")
        };
        write!(f, "{:<6} {ms:>6} ms  {}", self.name, self.detail)
    }
}

/// `1 point`, `2 points`.
pub(crate) fn plural(n: usize, one: &str, many: &str) -> String {
    if n == 1 {
        format!("{n} {one}")
    } else {
        format!("{n} {many}")
    }
}

/// Runs `f`, returning its value (or its error) with the time it took.
pub(crate) fn timed<T, E>(f: impl FnOnce() -> Result<T, E>) -> Result<(T, Duration), E> {
    let start = Instant::now();
    let value = f()?;
    Ok((value, start.elapsed()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_pads_name_and_time() {
        let s = Stage::new("read", Duration::from_millis(12), "100 points".into());
        assert_eq!(s.to_string(), "read       12 ms  100 points");
        let s = Stage::new("write", Duration::from_micros(2_340), "o.ply".into());
        assert_eq!(s.to_string(), "write     2.3 ms  o.ply");
    }
}
