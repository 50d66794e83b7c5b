//! bodyseg-io (in progress).
