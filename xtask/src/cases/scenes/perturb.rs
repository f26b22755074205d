//! Perturbation tests (filled below).
