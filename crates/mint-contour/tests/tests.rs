//! mint-contour integration tests, built into one binary (see `suite/`).
mod suite;
