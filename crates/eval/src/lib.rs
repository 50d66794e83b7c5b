//! bodyseg-eval (in progress).
