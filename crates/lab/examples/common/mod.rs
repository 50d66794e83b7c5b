//! What the study examples share (a module of each example, not an example itself).

/// Logs to stderr, filtered by `RUST_LOG` (`RUST_LOG=bodyseg_people=trace` shows the box
/// finder's head candidates and why each was dropped), without times or colours so that a
/// log stays comparable between runs.
pub fn init_logging() {
    tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
        .with_writer(std::io::stderr)
        .without_time()
        .with_ansi(false)
        .init();
}
