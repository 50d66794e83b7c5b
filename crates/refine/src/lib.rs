//! bodyseg-refine (in progress).
