//! The bodyseg binary.
fn main() {}
