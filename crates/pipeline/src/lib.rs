//! bodyseg-pipeline (in progress).
