//! bodyseg-testkit (in progress).
